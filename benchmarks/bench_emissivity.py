"""Emissivity quadrature: run time against error, for SPM and geometric optics.

    .venv/bin/python benchmarks/bench_emissivity.py   # → benchmarks/results/emissivity.json + .png

Error is measured against a reference at tol = 1e-10 (the same graded rule refined until two
successive estimates agree to 1e-10). Time per incidence angle and polarization: one call
evaluates both polarizations at once, so the per-(θi, pol) time is the call time / (n_θ · 2).
Target (issue 3): 1e-4 absolute in ≤ 20 ms per θi and polarization.
"""

from __future__ import annotations

import math
import os
import platform
import statistics
import sys
import time
import warnings
from pathlib import Path

import numpy as np

import emscatter as em
from emscatter.io import save_figure, write_json

HERE = Path(__file__).resolve().parent
CASES = {
    "spm": em.GaussianCorrelation(0.02, 0.5),  # kσ = 0.13, kℓ = 3.1 at λ = 1 m
    "go": em.GaussianCorrelation(0.5, 3.0),  # kσ = 3.1, rms slope 0.24
}
EPS = 17 + 2j
THETA = np.radians([0.0, 20.0, 40.0, 60.0, 75.0])
TOLS = [1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7]


def main() -> dict:
    out = {
        "machine": {
            "nproc": os.cpu_count(),
            "python": sys.version.split()[0],
            "platform": platform.platform(),
            "numpy": np.__version__,
        },
        "eps": str(EPS),
        "theta_i_deg": np.degrees(THETA).tolist(),
        "cases": {},
    }
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4.2))
    for method, rough in CASES.items():
        kw = dict(wavelength=1.0, theta_i=THETA, method=method, out_of_range="ignore")
        ref = em.emissivity(rough, EPS, tol=1e-10, **kw).emissivity
        rows = []
        for tol in TOLS:
            times = []
            for _ in range(7):
                t0 = time.perf_counter()
                e = em.emissivity(rough, EPS, tol=tol, **kw)
                times.append(time.perf_counter() - t0)
            per = statistics.median(times) / (THETA.size * 2)
            err = float(np.max(np.abs(e.emissivity - ref)))
            rows.append(
                {
                    "tol": tol,
                    "max_abs_error": err,
                    "ms_per_theta_pol": per * 1e3,
                    "evaluations": e.evaluations,
                    "estimated_error": float(e.error.max()),
                }
            )
            print(
                f"{method:4s} tol={tol:7.0e}  error={err:9.2e}  "
                f"{per * 1e3:7.3f} ms/(θi·pol)  evals={e.evaluations}"
            )
        out["cases"][method] = {"roughness": rough.describe(), "rows": rows}
        ax.loglog(
            [r["ms_per_theta_pol"] for r in rows],
            [max(r["max_abs_error"], 1e-16) for r in rows],
            "o-",
            label=f"{method}: {rough.describe()}",
        )
    ax.axhline(1e-4, color="0.5", ls=":")
    ax.axvline(20, color="0.5", ls=":")
    ax.set_xlabel("run time per θi and polarization [ms] (median of 7)")
    ax.set_ylabel("max |emissivity error| vs tol=1e-10 reference")
    ax.set_title("Emissivity quadrature: error against time", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    sys.path.insert(0, str(HERE))
    from common import command, machine, stamp

    out["machine_info"] = machine()
    out["command"] = command()
    stamp(fig, out["machine_info"], out["command"], 7)
    save_figure(fig, HERE / "results" / "emissivity.png")
    write_json(HERE / "results" / "emissivity.json", out)
    return out


if __name__ == "__main__":
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", category=UserWarning)
        main()
    _ = math
