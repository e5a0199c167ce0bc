"""Run time against error for the accuracy knobs (Pareto plots).

    python benchmarks/bench_pareto.py [--quick] [--repeat 5]
    → benchmarks/results/pareto.json, pareto.png

Knobs (each error is measured against the same computation at a much finer setting):
* physical-optics series tolerance ``rtol`` (10⁴ bistatic geometries, Gaussian kσ = 2, kℓ = 12);
* method-of-moments points per wavelength (1-D PEC Gaussian profile, 100 λ, kσ = 0.5, kℓ = 6, 8
  realizations, fixed seed: the error is the σ⁰ change against 40 points/λ on the SAME
  surfaces, i.e. the discretization error alone);
* Hurst-exponent estimator vs surface size (fBm H = 0.7, periodogram; error = |Ĥ − H| rms over
  16 seeds; time per estimate);
* BRDF table resolution vs interpolation error — when ``emscatter.brdf`` is present (branch
  brdf): tables of n × n × 2n nodes against direct σ⁰ at random directions.
The emissivity quadrature tolerance has its own script (bench_emissivity.py →
results/emissivity.png).
"""

from __future__ import annotations

import argparse
import math
import sys
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import numpy as np  # noqa: E402
from common import command, machine, save, stamp, timeit, write  # noqa: E402


def po_rtol(repeat):
    from emscatter.solvers.kirchhoff import po
    from emscatter.spectra import GaussianCorrelation

    k = 2 * math.pi
    rough = GaussianCorrelation(2.0 / k, 12.0 / k)
    rng = np.random.default_rng(0)
    n = 10_000
    geo = (rng.uniform(0, 1.4, n), rng.uniform(0, 1.4, n), rng.uniform(0, 2 * math.pi, n))
    ref = po.bistatic(rough, 17 + 2j, k, *geo, rtol=1e-14).sigma0
    rows = []
    for rtol in (1e-2, 1e-3, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12):
        t = timeit(lambda r=rtol: po.bistatic(rough, 17 + 2j, k, *geo, rtol=r), repeat=repeat)
        s = po.bistatic(rough, 17 + 2j, k, *geo, rtol=rtol).sigma0
        err = float(np.max(np.abs(s - ref) / np.maximum(np.abs(ref), 1e-300 + 1e-12 * ref.max())))
        rows.append({"knob": rtol, "error": err, "seconds": t["median_s"]})
    return {
        "label": "PO series rtol (10⁴ geometries)",
        "knob": "rtol",
        "error": "max relative σ⁰ error vs rtol=1e-14",
        "rows": rows,
    }


def mom_ppw(repeat, quick):
    from emscatter.solvers.mom import model as mom
    from emscatter.spectra import GaussianCorrelation

    k = 2 * math.pi
    rough = GaussianCorrelation(0.5 / k, 6.0 / k, dimension=1)  # ≥ 5 points per ℓ from 5.3/λ
    ts = np.radians(np.linspace(-80, 80, 81))
    opts = dict(
        realizations=4 if quick else 8, seed=1, length=100 * 2 * math.pi / k, progress=False
    )

    def run(ppw):
        r = mom.bistatic(
            rough,
            "pec",
            k,
            math.radians(20),
            np.abs(ts),
            np.where(ts < 0, math.pi, 0.0),
            points_per_wavelength=ppw,
            **opts,
        )
        return r.sigma0[0, 0]

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ref = run(40.0)
        rows = []
        for ppw in (6.0, 8.0, 10.0, 15.0, 20.0):
            t = timeit(lambda p=ppw: run(p), repeat=max(1, repeat // 2), warmup=0)
            s = run(ppw)
            m = ref > 1e-3 * ref.max()
            err = float(np.max(np.abs(10 * np.log10(s[m] / ref[m]))))
            rows.append({"knob": ppw, "error": err, "seconds": t["median_s"]})
    return {
        "label": "MoM points per wavelength (1-D PEC, 100 λ)",
        "knob": "points/λ",
        "error": "max |Δσ⁰_hh| [dB] vs 40 points/λ, same surfaces",
        "rows": rows,
    }


def hurst_size(repeat, quick):
    from emscatter.spectra import FractionalBrownian
    from emscatter.surfaces.generate import generate_surface
    from emscatter.surfaces.measure import hurst_exponent

    h = 0.7
    rough = FractionalBrownian(h, increment_rms=1.0, lag=1.0)
    rows = []
    for n in (32, 64, 128, 256, 512) if quick else (32, 64, 128, 256, 512, 1024):
        est, times = [], []
        for seed in range(16):
            z = generate_surface(rough, (n, n), 1.0, rng=seed).heights
            t = timeit(lambda z=z: hurst_exponent(z, 1.0), repeat=1, warmup=0)
            times.append(t["median_s"])
            est.append(hurst_exponent(z, 1.0).hurst)
        err = float(np.sqrt(np.mean((np.array(est) - h) ** 2)))
        rows.append({"knob": n, "error": err, "seconds": float(np.median(times))})
    return {
        "label": "Hurst estimator vs surface size (fBm H = 0.7, n × n)",
        "knob": "n",
        "error": "rms |Ĥ − H| over 16 seeds",
        "rows": rows,
    }


def brdf_resolution(repeat):
    try:
        from emscatter.brdf import build_table  # noqa: F401 — branch brdf
    except ImportError:
        return None
    import emscatter as em
    from emscatter.brdf import build_table

    rough = em.GaussianCorrelation(0.3, 1.0)  # GO-like lobe at λ = 1 m: rms slope 0.42
    rng = np.random.default_rng(0)
    m = 4000
    ti, to = rng.uniform(0, 1.4, m), rng.uniform(0, 1.4, m)
    pi_, po_ = rng.uniform(0, 2 * math.pi, m), rng.uniform(0, 2 * math.pi, m)
    from emscatter.brdf import frames

    th_i, th_s, ph_s, ph_i = frames.to_emscatter(ti, pi_, to, po_)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        s = em.bistatic(
            rough,
            17 + 2j,
            wavelength=1.0,
            theta_i=th_i,
            theta_s=th_s,
            phi_s=ph_s,
            phi_i=ph_i,
            method="go",
            out_of_range="ignore",
        )
        direct = s.sigma0.sum(axis=0).mean(axis=0) / (4 * math.pi * np.cos(ti) * np.cos(to))
        rows = []
        for n in (10, 20, 45, 90):

            def build(n=n):
                return build_table(
                    rough, 17 + 2j, [1.0], method="go", resolution=(n, 2 * n), energy="off"
                )

            t = timeit(build, repeat=1, warmup=0)
            tab = build()
            got = tab.evaluate_angles(ti, pi_, to, po_, 1.0)
            err = float(np.sqrt(np.mean((got - direct) ** 2)) / np.sqrt(np.mean(direct**2)))
            rows.append({"knob": n, "error": err, "seconds": t["median_s"]})
    return {
        "label": "BRDF table resolution (GO, n θ nodes × 2n Δφ)",
        "knob": "n",
        "error": "rms relative f_r interpolation error at 4000 random directions",
        "rows": rows,
    }


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--repeat", type=int, default=5)
    a = ap.parse_args(argv)
    studies = {}
    for name, fn in (
        ("po_rtol", lambda: po_rtol(a.repeat)),
        ("mom_points_per_wavelength", lambda: mom_ppw(a.repeat, a.quick)),
        ("hurst_vs_size", lambda: hurst_size(a.repeat, a.quick)),
        ("brdf_resolution", lambda: brdf_resolution(a.repeat)),
    ):
        res = fn()
        if res is None:
            print(f"{name}: skipped (module not present on this branch)")
            continue
        studies[name] = res
        for r in res["rows"]:
            print(
                f"{name:28s} {res['knob']}={r['knob']:<8g} error={r['error']:.3g}  "
                f"{r['seconds'] * 1e3:9.2f} ms",
                flush=True,
            )
    info, cmd = machine(), command()
    data = {
        "benchmark": "run time against error",
        "command": cmd,
        "machine": info,
        "repeat": a.repeat,
        "studies": studies,
    }
    write("pareto", data)
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(studies), figsize=(4.2 * len(studies), 4.2))
    for ax, st in zip(np.atleast_1d(axes), studies.values(), strict=True):
        xs = [r["seconds"] for r in st["rows"]]
        ys = [max(r["error"], 1e-16) for r in st["rows"]]
        ax.loglog(xs, ys, "o-")
        for r, x, y in zip(st["rows"], xs, ys, strict=True):
            ax.annotate(
                f"{r['knob']:g}", (x, y), fontsize=7, xytext=(3, 3), textcoords="offset points"
            )
        ax.set_title(st["label"], fontsize=8)
        ax.set_xlabel("run time [s] (median)")
        ax.set_ylabel(st["error"], fontsize=7)
        ax.grid(True, which="both", alpha=0.3)
    fig.suptitle(
        f"Run time against error (labels: {', '.join(s['knob'] for s in studies.values())})",
        fontsize=9,
    )
    fig.tight_layout()
    stamp(fig, info, cmd, a.repeat)
    save(fig, "pareto")
    return data


if __name__ == "__main__":
    main()
