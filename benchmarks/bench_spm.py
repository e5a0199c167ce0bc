"""Throughput of first-order SPM σ⁰ (all four polarizations) and cost of the second-order
coherent reflectivity.

Run: ``.venv/bin/python benchmarks/bench_spm.py`` — prints and writes
``benchmarks/results/spm.json``.
"""

from __future__ import annotations

import json
import os
import pathlib
import platform
import time

import numpy as np

from emscatter.solvers.spm import model as spm
from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation

N = 1_000_000
K = 2 * np.pi / 0.03  # 10 GHz-ish [rad/m]


def best_of(fn, repeat=3):
    """Best wall time and best CPU (process) time of ``repeat`` runs [s]. On a shared
    machine the CPU time is the fairer single-core figure."""
    wall, cpu = [], []
    for _ in range(repeat):
        t, c = time.perf_counter(), time.process_time()
        fn()
        wall.append(time.perf_counter() - t)
        cpu.append(time.process_time() - c)
    return min(wall), min(cpu)


def main():
    rng = np.random.default_rng(0)
    ti = rng.uniform(0, np.radians(89.9), N)
    ts = rng.uniform(0, np.radians(89.9), N)
    ps = rng.uniform(0, 2 * np.pi, N)
    results = {
        "n_geometries": N,
        "machine": platform.processor() or platform.machine(),
        "cpus": os.cpu_count(),
        "sigma0": {},
        "coherent_order2_ms_per_theta": {},
    }
    for name, rough in (
        ("gaussian", GaussianCorrelation(0.1 / K, 2.0 / K)),
        ("exponential", ExponentialCorrelation(0.1 / K, 2.0 / K)),
    ):
        for eps in (17 + 2j, "pec"):
            dt, dc = best_of(lambda r=rough, e=eps: spm.bistatic(r, e, K, ti, ts, ps, order=0))
            key = f"{name}/{eps}"
            results["sigma0"][key] = {
                "wall_seconds": dt,
                "cpu_seconds": dc,
                "evals_per_second_wall": N / dt,
                "evals_per_second_cpu": N / dc,
            }
            print(
                f"sigma0 full-pol {key:>22}: {N / dt:.3e} /s wall ({dt:.3f} s), {N / dc:.3e} /s CPU"
            )
    thetas = np.radians(np.linspace(0, 85, 18))
    for name, rough in (
        ("gaussian-2d", GaussianCorrelation(0.1 / K, 2.0 / K)),
        ("exponential-2d", ExponentialCorrelation(0.1 / K, 2.0 / K)),
        ("gaussian-1d", GaussianCorrelation(0.1 / K, 2.0 / K, dimension=1)),
    ):
        for eps in (17 + 2j, "pec"):
            dt, _ = best_of(lambda r=rough, e=eps: spm.coherent_reflectivity(r, e, K, thetas))
            ms = 1e3 * dt / thetas.size
            results["coherent_order2_ms_per_theta"][f"{name}/{eps}"] = ms
            print(f"coherent order 2 {name:>15}/{eps}: {ms:.2f} ms per theta_i")
    results["load_average"] = os.getloadavg()
    results["command"] = ".venv/bin/python benchmarks/bench_spm.py"
    out = pathlib.Path(__file__).parent / "results" / "spm.json"
    out.parent.mkdir(exist_ok=True)
    out.write_text(json.dumps(results, indent=2))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
