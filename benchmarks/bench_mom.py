"""Benchmark of the 1-D method of moments: solve time against unknowns (dense LU and the
block forward–backward method), and Monte Carlo throughput serial vs a dask LocalCluster.

Writes ``benchmarks/results/mom.json`` and ``benchmarks/mom_solve_time.png``.

    python benchmarks/bench_mom.py            # full run (≈ 2–4 min on 2 cores)
    python benchmarks/bench_mom.py --quick    # small sizes only

Case: perfect conductor, TE (EFIE, the slower-converging polarization for FB) and TM,
Gaussian profile σ = 0.1 λ, ℓ = λ, θi = 30°, 10 points per wavelength, taper g = L/4.
Times are wall-clock minima over ``--repeat`` runs; the machine load is recorded with them.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

from emscatter.solvers.mom import model as mom
from emscatter.solvers.mom.operators import solve_fb, solve_lu
from emscatter.solvers.mom.solve import _assemble, _derivatives
from emscatter.spectra import GaussianCorrelation
from emscatter.surfaces.generate import generate_surface

HERE = Path(__file__).resolve().parent
K = 2 * math.pi  # λ = 1 m
THETA_I = math.radians(30)
ROUGH = GaussianCorrelation(0.1, 1.0, dimension=1)


def case(n: int, seed: int = 0):
    dx = 0.1
    x = (np.arange(n) - (n - 1) / 2) * dx
    h = generate_surface(ROUGH, n, dx, rng=seed).heights
    return x, h, dx


def time_solve(n: int, pol: str, method: str, repeat: int) -> dict:
    x, h, dx = case(n)
    fp, fpp = _derivatives(h, dx)
    g = n * dx / 4
    b = mom.tapered_wave(x, h, K, THETA_I, g)
    best = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        a = _assemble(x, h, fp, fpp, dx, K, "pec", pol)
        t1 = time.perf_counter()
        if method == "lu":
            sol = solve_lu(a.copy(), b)
            it, ok = 0, True
        else:
            sol, ok, it, _, _ = solve_fb(a, b, tol=1e-6)
        t2 = time.perf_counter()
        res = float(np.linalg.norm(a @ sol - b) / np.linalg.norm(b))
        rec = {
            "unknowns": n,
            "polarization": pol,
            "method": method,
            "fill_s": t1 - t0,
            "solve_s": t2 - t1,
            "total_s": t2 - t0,
            "iterations": int(it),
            "converged": bool(ok),
            "relative_residual": res,
        }
        del a
        if best is None or rec["total_s"] < best["total_s"]:
            best = rec
    b_ = best
    print(
        f"  {method:2s} {pol} N={n:6d}: fill {b_['fill_s']:.3f} s, solve {b_['solve_s']:.3f} s, "
        f"total {b_['total_s']:.3f} s, it={b_['iterations']}, res={b_['relative_residual']:.1e}",
        flush=True,
    )
    return best


def mc_throughput(n_real: int) -> dict:
    ts = np.radians(np.arange(0.0, 86.0, 5.0))
    kw = dict(realizations=n_real, seed=1, length=100.0, progress=False)
    t0 = time.perf_counter()
    serial = mom.bistatic(ROUGH, "pec", K, THETA_I, ts, **kw)
    t_serial = time.perf_counter() - t0
    out = {"realizations": n_real, "serial_s": t_serial, "serial_per_s": n_real / t_serial}
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError:  # pragma: no cover
        out["dask"] = "not installed"
        return out
    t0 = time.perf_counter()
    with (
        LocalCluster(
            n_workers=2,
            threads_per_worker=1,
            host="127.0.0.1",
            dashboard_address=None,
            silence_logs=40,
        ) as cluster,
        Client(cluster) as client,
    ):
        t_start = time.perf_counter() - t0
        ex = client.get_executor()
        t1 = time.perf_counter()
        par = mom.bistatic(ROUGH, "pec", K, THETA_I, ts, executor=ex, **kw)
        t_dask = time.perf_counter() - t1
    out.update(
        dask_cluster_start_s=t_start,
        dask_s=t_dask,
        dask_per_s=n_real / t_dask,
        dask_workers=2,
        # workers run BLAS single-threaded, so LU rounding may differ in the last bits
        max_relative_difference=float(
            np.max(np.abs(par.sigma0 - serial.sigma0) / serial.sigma0.max())
        ),
    )
    print(
        f"  Monte Carlo {n_real} realizations (h and v, 1000 unknowns): serial {t_serial:.2f} s, "
        f"dask 2 workers {t_dask:.2f} s (+{t_start:.1f} s cluster start), "
        f"max relative difference {out['max_relative_difference']:.1e}",
        flush=True,
    )
    return out


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--mc-only", action="store_true", help="redo the Monte Carlo part only")
    args = ap.parse_args(argv)
    out_json = HERE / "results" / "mom.json"
    if args.mc_only:
        result = json.loads(out_json.read_text())
        result["montecarlo"] = mc_throughput(32)
        out_json.write_text(json.dumps(result, indent=2))
        return
    sizes = [250, 500, 1000] if args.quick else [250, 500, 1000, 2000, 4000]
    fast_only = [] if args.quick else [10000]
    runs = []
    print(f"load average before: {os.getloadavg()}", flush=True)
    for pol in ("h", "v"):
        for n in sizes:
            for method in ("lu", "fb"):
                runs.append(time_solve(n, pol, method, args.repeat if n < 4000 else 1))
        for n in fast_only:
            runs.append(time_solve(n, pol, "fb", 1))
    mc = mc_throughput(8 if args.quick else 32)
    result = {
        "case": "PEC, Gaussian sigma=0.1 lambda, ell=1 lambda, theta_i=30 deg, 10 points/lambda",
        "machine": {
            "platform": platform.platform(),
            "cpus": os.cpu_count(),
            "load_average_after": os.getloadavg(),
            "numpy": np.__version__,
        },
        "solve": runs,
        "montecarlo": mc,
    }
    out_dir = HERE / "results"
    out_dir.mkdir(exist_ok=True)
    (out_dir / "mom.json").write_text(json.dumps(result, indent=2))

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    styles = {("lu", "h"): "o-", ("fb", "h"): "s-", ("lu", "v"): "o--", ("fb", "v"): "s--"}
    for (method, pol), st in styles.items():
        rr = [r for r in runs if r["method"] == method and r["polarization"] == pol]
        ax.loglog(
            [r["unknowns"] for r in rr],
            [r["total_s"] for r in rr],
            st,
            label=f"{'dense LU' if method == 'lu' else 'forward–backward'}, "
            f"{'TE' if pol == 'h' else 'TM'} (fill + solve)",
        )
    fills = [r for r in runs if r["method"] == "fb" and r["polarization"] == "h"]
    ax.loglog([r["unknowns"] for r in fills], [r["fill_s"] for r in fills], "k:", label="fill only")
    ax.axhline(1.0, color="0.6", lw=0.8)
    ax.axhline(10.0, color="0.6", lw=0.8)
    ax.set_xlabel("unknowns")
    ax.set_ylabel("wall time [s]")
    ax.set_title("1-D MoM, PEC, 10 pts/λ (2-core machine)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    sys.path.insert(0, str(HERE))
    from common import command, machine, stamp

    stamp(fig, machine(), command(), None)
    fig.savefig(HERE / "mom_solve_time.png", dpi=120)
    print(f"wrote {out_dir / 'mom.json'} and {HERE / 'mom_solve_time.png'}")


if __name__ == "__main__":
    main()
