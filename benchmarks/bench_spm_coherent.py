"""The SPM second-order coherent reflectivity, before and after its compiled kernel (issue 22:
77 % of an SPM ``emscatter.emissivity`` call was this quadrature).

    python benchmarks/bench_spm_coherent.py [--repeat 7] [--out spm_coherent]
    → benchmarks/results/spm_coherent.json

Rows, 9 θi (0–80°), λ = 0.1 m, kσ = 0.1, kℓ = 2, Gaussian and exponential, ε = 17 + 2i and PEC:
``_second_order_R`` by the numpy reference (``_second_order_R_numpy``, the path before), the
compiled kernel with the per-angle nodes memoized (a repeated call) and with the memo cleared
(a first call's node building); and ``emscatter.emissivity(..., method="spm")`` at the same
9 θi with the coherent part on the reference path (before) and on the kernel (after). The
contenders are alternated round by round in one process, result cache off
(``EMSCATTER_CACHE=0``), ``EMSCATTER_KERNELS=numba`` (so the 9-angle call takes the kernel even
before numba is loaded); medians of ``--repeat`` rounds after one warm-up round (compilation
excluded: that is bench_api's ``cold``). The largest relative difference of R⁽²⁾ between the
paths is recorded per row.
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import sys
import time
import warnings
from pathlib import Path

os.environ["EMSCATTER_CACHE"] = "0"
os.environ["EMSCATTER_KERNELS"] = "numba"
sys.path.insert(0, str(Path(__file__).resolve().parent))
import numpy as np  # noqa: E402
from common import command, machine, write  # noqa: E402

LAM = 0.1
K = 2 * math.pi / LAM
THETA = np.radians(np.linspace(0.0, 80.0, 9))


def _rounds(contenders: dict, repeat: int) -> dict:
    """Alternate the contenders round by round; median wall time [s] of each."""
    times = {name: [] for name in contenders}
    for r in range(repeat + 1):
        for name, fn in contenders.items():
            t0 = time.perf_counter()
            fn()
            if r:  # round 0 is the warm-up
                times[name].append(time.perf_counter() - t0)
    return {name: statistics.median(v) for name, v in times.items()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--out", default="spm_coherent", help="results file name (results/NAME.json)")
    args = ap.parse_args()
    import emscatter as em
    from emscatter.solvers.spm import second_order as so
    from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation

    rows = {}
    for rough in (GaussianCorrelation(0.1 / K, 2.0 / K), ExponentialCorrelation(0.1 / K, 2.0 / K)):
        for eps in (17 + 2j, "pec"):
            e = eps if eps == "pec" else complex(eps)

            def fresh(r=rough, e=e):
                so._angle_nodes.cache_clear()
                return so._second_order_R(r, e, K, THETA, 16, 16)

            contenders = {
                "numpy_reference": lambda r=rough, e=e: so._second_order_R_numpy(
                    r, e, K, THETA, 16, 16
                ),
                "compiled": lambda r=rough, e=e: so._second_order_R(r, e, K, THETA, 16, 16),
                "compiled_nodes_rebuilt": fresh,
            }
            med = _rounds(contenders, args.repeat)
            ref = so._second_order_R_numpy(rough, e, K, THETA, 16, 16)[1]
            got = so._second_order_R(rough, e, K, THETA, 16, 16)[1]
            row = {f"{n}_ms": 1e3 * t for n, t in med.items()}
            row["speedup"] = med["numpy_reference"] / med["compiled"]
            row["speedup_nodes_rebuilt"] = med["numpy_reference"] / med["compiled_nodes_rebuilt"]
            row["max_rel_diff_R2"] = float(np.max(np.abs(got - ref) / np.abs(ref)))
            name = f"{type(rough).__name__}/{eps}"
            rows[name] = row
            print(f"{name:32s} numpy {row['numpy_reference_ms']:.1f} ms, compiled "
                  f"{row['compiled_ms']:.1f} ms (nodes rebuilt "
                  f"{row['compiled_nodes_rebuilt_ms']:.1f} ms), ×{row['speedup']:.1f}, "
                  f"max rel diff {row['max_rel_diff_R2']:.1e}", flush=True)  # fmt: skip
    rough = GaussianCorrelation(0.1 / K, 2.0 / K)
    kernel_path = so._compiled_R

    def emis(before: bool):
        so._compiled_R = (lambda *a, **k: None) if before else kernel_path  # before: reference
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                return em.emissivity(rough, 17 + 2j, wavelength=LAM, theta_i=THETA, method="spm")
        finally:
            so._compiled_R = kernel_path

    med = _rounds({"before": lambda: emis(True), "after": lambda: emis(False)}, args.repeat)
    a, b = emis(True).emissivity, emis(False).emissivity
    rows["emissivity_spm_9_angles"] = {
        "before_ms": 1e3 * med["before"],
        "after_ms": 1e3 * med["after"],
        "speedup": med["before"] / med["after"],
        "max_abs_diff_emissivity": float(np.max(np.abs(a - b))),
    }
    r = rows["emissivity_spm_9_angles"]
    print(f"emissivity(method='spm'), 9 θi: before {r['before_ms']:.1f} ms, after "
          f"{r['after_ms']:.1f} ms (×{r['speedup']:.1f}), "
          f"|Δe| ≤ {r['max_abs_diff_emissivity']:.1e}", flush=True)  # fmt: skip
    data = {"machine": machine(), "command": command(), "rows": rows, "repeat": args.repeat}
    data["machine"]["load_average_end"] = list(os.getloadavg())
    print(write(args.out, data))


if __name__ == "__main__":
    main()
