"""Integral-equation model: backscatter against SMRT 1.7 on the same inputs, bistatic throughput.

    PYTHONPATH=src .venv/bin/python benchmarks/bench_iem.py [--smrt /tmp/smrtvenv/bin/python]
        → benchmarks/results/iem.json (and a table on stdout)

SMRT (a peer, never a dependency) runs in its scratch venv
(``python3 -m venv /tmp/smrtvenv && /tmp/smrtvenv/bin/pip install smrt``) through a subprocess
that times its own calls with the same repeat/median scheme, launched from this script between
our own timings (one run: the ratios share the machine's state). Without that interpreter the
SMRT rows are skipped and said so.

Backscatter case (SMRT's own test case scaled to C band): exponential correlation,
σ = 0.4 cm, ℓ = 3 cm, 5.3 GHz (kσ = 0.44, kℓ = 3.3), ε = 15 + 2i, N incidence angles in
[0.5°, 70°]. Contenders: SMRT ``IEM_Fung92`` (co-pol, its default fixed 10 terms) and
``IIEM_Fung02`` (co-pol + multiple-scattering hv); emscatter ``iem`` co-pol only
(``crosspol=False``; AIEM, series to rtol = 1e-8), with hv, and its 1992 configuration.
Bistatic: random geometries over the hemisphere, all four polarizations, per second — the
single-scattering part (``crosspol=False``) on 20 000 geometries, and with the bistatic
multiple-scattering hv (default ``crosspol=True``, ``crosspol_order=8``) on 1 000, with the
compiled kernels and with ``EMSCATTER_KERNELS=numpy`` (the reference path).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from emscatter.io import write_json
from emscatter.solvers import iem
from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation

HERE = Path(__file__).resolve().parent
C = 299792458.0
FREQ, SIGMA, ELL, EPS = 5.3e9, 0.004, 0.03, 15 + 2j
SIZES = (1, 10, 90, 100, 1000)
FUNG92 = dict(fresnel="incident", complementary="fung92", first_order="model", shadowing=False,
              crosspol=False)  # fmt: skip

SMRT_SCRIPT = r"""
import json, statistics, sys, time, warnings
import numpy as np
from smrt.interface.iem_fung92 import IEM_Fung92
from smrt.interface.iiem_fung02 import IIEM_Fung02
f, s, l, er, ei, reps = (float(a) for a in sys.argv[1:7])
sizes = [int(a) for a in sys.argv[7].split(",")]
out = {}
warnings.simplefilter("ignore")
for name, model, npol, top in (
    ("smrt_iem_fung92", IEM_Fung92(roughness_rms=s, corr_length=l,
        autocorrelation_function="exponential", warning_handling="nothing"), 2, 10**9),
    ("smrt_iiem_fung02", IIEM_Fung02(roughness_rms=s, corr_length=l,
        autocorrelation_function="exponential", warning_handling="nothing"), 3, 100),
):
    for n in sizes:
        if n > top:
            continue
        mu = np.cos(np.radians(np.linspace(0.5, 70.0, n)))
        model.diffuse_reflection_matrix(f, 1, complex(er, ei), mu, mu, np.pi, npol)
        t = []
        for _ in range(int(reps)):
            t0 = time.perf_counter()
            model.diffuse_reflection_matrix(f, 1, complex(er, ei), mu, mu, np.pi, npol)
            t.append(time.perf_counter() - t0)
        out[f"{name}/{n}"] = statistics.median(t)
print(json.dumps(out))
"""


def _median_time(fn, reps: int) -> float:
    fn()
    t = []
    for _ in range(reps):
        t0 = time.perf_counter()
        fn()
        t.append(time.perf_counter() - t0)
    return statistics.median(t)


def _smrt(python: str, reps: int) -> dict:
    if not Path(python).exists():
        return {"skipped": f"no SMRT interpreter at {python}"}
    args = [python, "-c", SMRT_SCRIPT, str(FREQ), str(SIGMA), str(ELL), str(EPS.real),
            str(EPS.imag), str(reps), ",".join(map(str, SIZES))]  # fmt: skip
    res = subprocess.run(args, capture_output=True, text=True, check=True, timeout=1800)
    return json.loads(res.stdout.strip().splitlines()[-1])


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--smrt", default="/tmp/smrtvenv/bin/python")
    ap.add_argument("--reps", type=int, default=7)
    ap.add_argument("--out", type=Path, default=HERE / "results" / "iem.json")
    args = ap.parse_args(argv)
    k = 2 * math.pi * FREQ / C
    rough = ExponentialCorrelation(SIGMA, ELL)
    times: dict[str, float] = {}
    smrt_first = _smrt(args.smrt, args.reps)
    for n in SIZES:
        th = np.radians(np.linspace(0.5, 70.0, n))

        def run(th=th, **kw):
            return lambda: iem.bistatic(rough, EPS, k, th, th, math.pi, coherent=False, **kw)

        times[f"iem_copol/{n}"] = _median_time(run(crosspol=False), args.reps)
        times[f"iem_fung92/{n}"] = _median_time(run(**FUNG92), args.reps)
        if n <= 100:
            times[f"iem_with_hv/{n}"] = _median_time(run(), max(3, args.reps // 2))
    smrt_second = _smrt(args.smrt, args.reps)  # again after ours: the load may drift
    smrt = {key: min(smrt_first[key], smrt_second[key]) for key in smrt_first if key != "skipped"}
    if "skipped" in smrt_first:
        smrt = {"skipped": smrt_first["skipped"]}
    # bistatic throughput
    rng = np.random.default_rng(0)
    m = 20000
    ti, ts = rng.uniform(0, 1.3, m), rng.uniform(0, 1.4, m)
    ps = rng.uniform(0, 2 * math.pi, m)
    throughput = {}
    cases = (
        ("gaussian_ks0.5", GaussianCorrelation(0.5 / (2 * math.pi), 0.6)),
        ("exponential_ks1.1", ExponentialCorrelation(1.1 / (2 * math.pi), 0.9)),
    )
    for label, r in cases:
        for rec in (True, False):
            t = _median_time(
                lambda r=r, rec=rec: iem.bistatic(
                    r,
                    EPS,
                    2 * math.pi,
                    ti,
                    ts,
                    ps,
                    coherent=False,
                    reciprocal=rec,
                    crosspol=False,
                ),  # fmt: skip
                3,
            )
            throughput[f"{label}/reciprocal={rec}"] = m / t
        saved = os.environ.get("EMSCATTER_KERNELS")
        for mode in ("auto", "numpy"):  # with the bistatic multiple-scattering hv
            os.environ["EMSCATTER_KERNELS"] = mode
            n_hv = 1000 if mode == "auto" else 200
            t = _median_time(
                lambda r=r, n=n_hv: iem.bistatic(
                    r, EPS, 2 * math.pi, ti[:n], ts[:n], ps[:n], coherent=False
                ),  # fmt: skip
                3,
            )
            throughput[f"{label}/with_hv/kernels={mode}"] = n_hv / t
        if saved is None:
            os.environ.pop("EMSCATTER_KERNELS")
        else:
            os.environ["EMSCATTER_KERNELS"] = saved
    out = {
        "machine": {
            "nproc": os.cpu_count(),
            "python": sys.version.split()[0],
            "platform": platform.platform(),
            "numpy": np.__version__,
            "load_average": os.getloadavg(),
        },
        "case": {
            "frequency_hz": FREQ,
            "sigma_m": SIGMA,
            "ell_m": ELL,
            "eps": str(EPS),
            "k_sigma": k * SIGMA,
            "k_l": k * ELL,
            "correlation": "exponential",
            "theta_deg": "N angles in [0.5, 70]",
        },  # fmt: skip
        "seconds_median": times,
        "smrt_seconds_median": smrt,
        "bistatic_geometries_per_second": throughput,
    }
    if "skipped" not in smrt:
        out["ratio_smrt_fung92_over_iem_copol"] = {
            n: smrt[f"smrt_iem_fung92/{n}"] / times[f"iem_copol/{n}"] for n in SIZES
        }
        out["ratio_smrt_iiem_over_iem_with_hv"] = {
            n: smrt[f"smrt_iiem_fung02/{n}"] / times[f"iem_with_hv/{n}"]
            for n in SIZES
            if f"smrt_iiem_fung02/{n}" in smrt
        }
    write_json(args.out, out)
    print(json.dumps({k_: v for k_, v in out.items() if k_ != "machine"}, indent=1))
    return out


if __name__ == "__main__":
    main()
