"""BRDF tables: build time of a 90×90×180 table at 3 wavelengths (GO, SPM), export times,
evaluation throughput.

    .venv/bin/python benchmarks/bench_brdf.py [--repeat 3]   # → benchmarks/results/brdf.json

Targets (issue 8): GO ≤ 2 s, SPM ≤ 5 s for the full table at 3 wavelengths. The breakdown
separates the solver (one ``api.bistatic`` call per wavelength over the reciprocal half grid,
timed alone in the same run) from the table's own work (reciprocity fill, coherent part,
albedo and energy check), and measures what the savings are worth: the half grid against
the full grid, and SPM without its second-order coherent quadrature inside the big call.
Wall-clock medians and the process CPU time (all threads: on a loaded machine the CPU time
of a single-threaded build is close to its quiet wall time; GO's solver uses up to 2 threads
here); the machine, versions and load averages are recorded.
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import statistics
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

from emscatter import api
from emscatter.brdf import build_table, frames
from emscatter.brdf.build import default_phi_d, default_theta, material_eps
from emscatter.brdf.export_merl import write_merl
from emscatter.brdf.export_npz import write_npz
from emscatter.io import write_json
from emscatter.spectra import GaussianCorrelation

HERE = Path(__file__).resolve().parent
WL = [0.45e-6, 0.55e-6, 0.65e-6]
CASES = {
    # gold, Beckmann α = 2σ/T = 0.3 (GO), and a smooth gold surface for SPM (kσ ≈ 0.1)
    "go": (GaussianCorrelation(0.15e-6, 1.0e-6), "go"),
    "spm": (GaussianCorrelation(0.008e-6, 0.3e-6), "spm"),
}


_CPU: list[float] = []  # process CPU time of the last _median_time's runs


def _median_time(fn, repeat: int) -> tuple[float, list[float]]:
    """Median wall time and all wall times; the CPU times (all threads) go to ``_CPU``."""
    times = []
    _CPU.clear()
    for _ in range(repeat):
        c0, t0 = time.process_time(), time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
        _CPU.append(time.process_time() - c0)
    return statistics.median(times), times


def _solver_only(rough, method, half: bool, coherent_flag: bool):
    """The σ⁰ calls alone (one per wavelength) on the half or the full grid."""
    th, pd = default_theta(90), default_phi_d(180)
    if half:
        iu, ou = np.triu_indices(th.size)
        ti, to = th[iu][:, None], th[ou][:, None]
    else:
        ti, to = th[:, None, None], th[None, :, None]
    et, es, ps, ei = frames.to_emscatter(ti, -math.pi, to, pd - math.pi)
    opts = {"coherent": False} if coherent_flag and method == "spm" else {}
    for lam in WL:
        api.bistatic(
            rough,
            material_eps("Au", lam),
            wavelength=lam,
            theta_i=et,
            theta_s=es,
            phi_s=ps,
            phi_i=ei,
            method=method,
            out_of_range="ignore",
            **opts,
        )


def main(repeat: int) -> dict:
    warnings.simplefilter("ignore")
    out = {
        "command": f"benchmarks/bench_brdf.py --repeat {repeat}",
        "machine": {
            "nproc": os.cpu_count(),
            "python": sys.version.split()[0],
            "platform": platform.platform(),
            "numpy": np.__version__,
            "load_average_start": os.getloadavg(),
        },
        "grid": "90 x 90 x 180 (theta_i, theta_o, dphi), 3 wavelengths 450/550/650 nm, Au",
        "cases": {},
    }
    for name, (rough, method) in CASES.items():
        kw = dict(method=method, resolution=(90, 180), out_of_range="ignore")
        build_table(rough, "Au", WL, **kw)  # warm-up (imports, caches)
        total, times = _median_time(lambda r=rough, k=kw: build_table(r, "Au", WL, **k), repeat)
        cpu = statistics.median(_CPU)
        half, _ = _median_time(lambda r=rough, m=method: _solver_only(r, m, True, True), repeat)
        full, _ = _median_time(lambda r=rough, m=method: _solver_only(r, m, False, True), repeat)
        row = {
            "roughness": rough.describe(),
            "build_s_median": total,
            "build_s_all": times,
            "build_cpu_s_median": cpu,
            "solver_half_grid_s": half,
            "solver_full_grid_s": full,
            "table_overhead_s": total - half,
            "target_s": {"go": 2.0, "spm": 5.0}[name],
        }
        if name == "spm":  # what skipping the coherent quadrature in the big call saves
            with_coh, _ = _median_time(lambda r=rough: _solver_only(r, "spm", True, False), 1)
            row["solver_half_grid_with_coherent_s"] = with_coh
        out["cases"][name] = row
        print(
            f"{name:4s} build {total:6.2f} s (CPU {cpu:5.2f} s; target {row['target_s']} s) | "
            "solver half grid "
            f"{half:5.2f} s, full grid {full:5.2f} s | table work {total - half:5.2f} s",
            flush=True,
        )
    table = build_table(*CASES["go"][:1], "Au", WL, method="go", out_of_range="ignore")
    with tempfile.TemporaryDirectory() as tmp:
        t_merl, _ = _median_time(lambda: write_merl(table, Path(tmp) / "t.binary"), repeat)
        t_npz, _ = _median_time(lambda: write_npz(table, Path(tmp) / "t.npz"), repeat)
    rng = np.random.default_rng(0)
    wi = frames.directions(rng.uniform(0, 1.5, 10**6), rng.uniform(0, 6.3, 10**6))
    wo = frames.directions(rng.uniform(0, 1.5, 10**6), rng.uniform(0, 6.3, 10**6))
    t_eval, _ = _median_time(lambda: table.evaluate(wi, wo), repeat)
    out["exports"] = {"merl_write_s": t_merl, "npz_write_s": t_npz}
    out["evaluate"] = {
        "points": 10**6,
        "wavelengths": 3,
        "s": t_eval,
        "points_per_s": 10**6 / t_eval,
    }
    out["machine"]["load_average_end"] = os.getloadavg()
    print(
        f"MERL write {t_merl:.2f} s, npz write {t_npz:.2f} s, evaluate 1e6 pairs × 3 λ "
        f"{t_eval:.2f} s; load {out['machine']['load_average_start']} → "
        f"{out['machine']['load_average_end']}"
    )
    write_json(HERE / "results" / "brdf.json", out)
    return out


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=3)
    main(ap.parse_args().repeat)
