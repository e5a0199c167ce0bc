"""Throughput of the Kirchhoff solvers: full-polarization σ⁰ evaluations per second.

Run:  .venv/bin/python benchmarks/bench_kirchhoff.py [--n 1000000] [--repeat 3]
Writes benchmarks/results/kirchhoff.json and prints a summary.

One "evaluation" is one geometry (θi, θs, φs, φi) giving all four σ⁰_pq and the coherent
reflectivity. Geometries are random over the upper hemisphere (θ ∈ [0, 89°], φs ∈ [0, 2π));
ε = 17 + 2i; Gaussian roughness. GO is timed with Smith shadowing (the default) and without;
PO at kσ = 0.5 and kσ = 3 (the series needs more terms as kσ grows) and for the
exponential correlation. Wall time is the best of ``--repeat`` runs; CPU time (all threads)
is reported too, since the 2-core machine is shared.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import time
from pathlib import Path

import numpy as np

from emscatter.solvers.kirchhoff import go, po
from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation

K0 = 2 * math.pi


def _time(fn, repeat: int) -> tuple[float, float]:
    best_wall, best_cpu = math.inf, math.inf
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        fn()
        best_wall = min(best_wall, time.perf_counter() - t0)
        best_cpu = min(best_cpu, time.process_time() - c0)
    return best_wall, best_cpu


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=1_000_000, help="geometries per call")
    ap.add_argument("--n-po", type=int, default=None, help="geometries for PO (default: --n)")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--out", default=str(Path(__file__).parent / "results" / "kirchhoff.json"))
    args = ap.parse_args(argv)
    n, n_po = args.n, args.n_po or args.n
    rng = np.random.default_rng(0)
    hi = math.radians(89.0)
    geo = (rng.uniform(0, hi, n), rng.uniform(0, hi, n), rng.uniform(0, 2 * math.pi, n))
    geo_po = tuple(a[:n_po] for a in geo)
    eps = 17 + 2j
    cases = {
        "go_smith_shadowing": (
            lambda: go.bistatic(GaussianCorrelation(0.1, 1.0), eps, K0, *geo),
            n,
        ),
        "go_no_shadowing": (
            lambda: go.bistatic(GaussianCorrelation(0.1, 1.0), eps, K0, *geo, shadowing=False),
            n,
        ),
        "go_smith_1thread": (
            lambda: go.bistatic(GaussianCorrelation(0.1, 1.0), eps, K0, *geo, threads=1),
            n,
        ),
        "po_gaussian_ks0.5": (
            lambda: po.bistatic(GaussianCorrelation(0.5 / K0, 5 / K0), eps, K0, *geo_po),
            n_po,
        ),
        "po_gaussian_ks3": (
            lambda: po.bistatic(GaussianCorrelation(3 / K0, 20 / K0), eps, K0, *geo_po),
            n_po,
        ),
        "po_exponential_ks0.5": (
            lambda: po.bistatic(ExponentialCorrelation(0.5 / K0, 5 / K0), eps, K0, *geo_po),
            n_po,
        ),
    }
    results = {}
    for name, (fn, count) in cases.items():
        wall, cpu = _time(fn, args.repeat if name.startswith("go") else 1)
        results[name] = {
            "geometries": count,
            "wall_s": wall,
            "cpu_s": cpu,
            "evals_per_s": count / wall,
            "evals_per_cpu_s": count / cpu if cpu > 0 else None,
        }
        print(
            f"{name:24s} {count:>9d} geometries  {wall:7.3f} s wall  "
            f"{count / wall:10.3g} /s  ({count / cpu:10.3g} per CPU-s)"
        )
    load = os.getloadavg() if hasattr(os, "getloadavg") else None
    out = {
        "benchmark": "kirchhoff full-polarization sigma0 throughput",
        "command": "python benchmarks/bench_kirchhoff.py " + " ".join(argv or []),
        "machine": {
            "cpu_count": os.cpu_count(),
            "platform": platform.platform(),
            "python": platform.python_version(),
            "numpy": np.__version__,
            "load_average_at_end": load,
        },
        "target_go_evals_per_s": 3e6,
        "results": results,
    }
    path = Path(args.out)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(out, indent=2))
    print(f"wrote {path}  (load average {load})")
    return out


if __name__ == "__main__":
    main()
