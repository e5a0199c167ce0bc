"""How cost grows: σ⁰ evaluations, method-of-moments unknowns, BRDF tables, from small to large.

    python benchmarks/bench_scaling.py [--quick]
    → benchmarks/results/scaling.json, scaling.png

Each series: wall time (median of 3, 1 for the largest) and the peak of numpy allocations
(``tracemalloc``) against problem size, log-log, with the exponent of a least-squares fit over
the upper half of the sizes (where fixed overheads no longer dominate).
* σ⁰: ``spm.bistatic`` (first order, coherent=False) and ``kirchhoff_go.bistatic`` on n random
  geometries, numpy path and compiled kernels;
* MoM: two realizations of a 1-D PEC profile, N unknowns (10 points/λ), forward–backward solve;
* BRDF tables (when ``emscatter.brdf`` is present): GO table with n θ nodes × 2n Δφ nodes.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import tracemalloc
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import numpy as np  # noqa: E402
from common import command, machine, save, stamp, timeit, write  # noqa: E402


def measure(fn, repeat):
    tracemalloc.start()
    fn()
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    t = timeit(fn, repeat=repeat, warmup=0)
    return t["median_s"], peak


def fit(sizes, times):
    x, y = np.log(sizes), np.log(times)
    h = len(x) // 2
    return float(np.polyfit(x[h:], y[h:], 1)[0])


def sigma0_series(kernels: str, quick: bool):
    from emscatter.solvers.kirchhoff import go
    from emscatter.solvers.spm import model as spm
    from emscatter.spectra import GaussianCorrelation

    os.environ["EMSCATTER_KERNELS"] = kernels
    sizes = [10**2, 10**3, 10**4, 10**5, 10**6] + ([] if quick else [3 * 10**6])
    rng = np.random.default_rng(0)
    out = {}
    for name, fn in (
        (
            "spm1",
            lambda g: spm.bistatic(
                GaussianCorrelation(0.005, 0.05), 17 + 2j, 60.0, *g, coherent=False
            ),
        ),
        ("go", lambda g: go.bistatic(GaussianCorrelation(0.1, 1.0), 17 + 2j, 6.3, *g)),
    ):
        rows = []
        for n in sizes:
            g = (rng.uniform(0, 1.5, n), rng.uniform(0, 1.5, n), rng.uniform(0, 6.28, n))
            fn(g)  # warm-up (compile / cache load)
            t, mem = measure(lambda g=g, fn=fn: fn(g), 3 if n < 10**6 else 1)
            rows.append({"size": n, "seconds": t, "peak_bytes": mem})
        out[f"{name} ({kernels})"] = rows
    os.environ.pop("EMSCATTER_KERNELS", None)
    return out


def mom_series(quick: bool):
    from emscatter.solvers.mom import model as mom
    from emscatter.spectra import GaussianCorrelation

    k = 2 * math.pi
    rough = GaussianCorrelation(0.3 / k, 6.0 / k, dimension=1)
    rows = []
    for n in (250, 500, 1000, 2000, 4000) + (() if quick else (8000,)):
        length = n / 10.0  # λ = 1 m, 10 points/λ
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")

            def run(length=length):
                mom.bistatic(
                    rough,
                    "pec",
                    k,
                    0.3,
                    0.3,
                    0.0,
                    realizations=2,
                    seed=0,
                    length=length,
                    progress=False,
                    polarizations=("h",),
                )

            t, mem = measure(run, 1)
        rows.append({"size": n, "seconds": t, "peak_bytes": mem})
    return {"MoM unknowns (2 realizations, PEC h)": rows}


def brdf_series(quick: bool):
    try:
        from emscatter.brdf import build_table
    except ImportError:
        return {}
    import emscatter as em

    rough = em.GaussianCorrelation(0.3, 1.0)
    rows = []
    for n in (8, 16, 32, 64) + (() if quick else (90,)):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            t, mem = measure(
                lambda n=n: build_table(
                    rough, 17 + 2j, [1.0], method="go", resolution=(n, 2 * n), energy="off"
                ),
                1,
            )
        rows.append({"size": 2 * n**3, "seconds": t, "peak_bytes": mem})
    return {"BRDF table nodes (GO, n × n × 2n)": rows}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    a = ap.parse_args(argv)
    series = {}
    series.update(sigma0_series("numpy", a.quick))
    series.update(sigma0_series("auto", a.quick))
    series.update(mom_series(a.quick))
    series.update(brdf_series(a.quick))
    for name, rows in series.items():
        e = fit([r["size"] for r in rows], [r["seconds"] for r in rows])
        em_ = fit([r["size"] for r in rows], [max(r["peak_bytes"], 1) for r in rows])
        series[name] = {"rows": rows, "time_exponent": e, "memory_exponent": em_}
        print(
            f"{name:40s} time ∝ n^{e:.2f}  memory ∝ n^{em_:.2f}  largest: "
            f"{rows[-1]['seconds']:.3g} s, {rows[-1]['peak_bytes'] / 2**20:.1f} MiB",
            flush=True,
        )
    info, cmd = machine(), command()
    data = {"benchmark": "cost growth", "command": cmd, "machine": info, "series": series}
    write("scaling", data)
    import matplotlib.pyplot as plt

    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(11, 4.4))
    for j, (name, s) in enumerate(series.items()):
        xs = [r["size"] for r in s["rows"]]
        ax0.loglog(
            xs,
            [r["seconds"] for r in s["rows"]],
            "o-",
            color=f"C{j}",
            label=f"{name}: n^{s['time_exponent']:.2f}",
        )
        ax1.loglog(
            xs,
            [max(r["peak_bytes"], 1) / 2**20 for r in s["rows"]],
            "s-",
            color=f"C{j}",
            label=f"{name}: n^{s['memory_exponent']:.2f}",
        )
    ax0.set_ylabel("wall time [s]")
    ax1.set_ylabel("peak numpy allocations [MiB] (tracemalloc)")
    for ax in (ax0, ax1):
        ax.set_xlabel("problem size n (geometries / unknowns / table nodes)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=6.5)
    fig.suptitle("How cost grows (fitted exponent over the upper half of the sizes)", fontsize=9)
    fig.tight_layout()
    stamp(fig, info, cmd, 3)
    save(fig, "scaling")
    return data


if __name__ == "__main__":
    main()
