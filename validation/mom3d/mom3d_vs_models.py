"""The 3-D method of moments (PEC) beside SPM, IEM, PO and GO in the plane of incidence (issue 19).

One Gaussian perfectly conducting surface, kσ = 1, kℓ = 7 (rms slope per axis √2 σ/ℓ = 0.20),
θi = 40°, a 6λ × 6λ patch at 8 points/λ (taper g = 1.5λ), Monte Carlo over ``--realizations``
surfaces (default 24). Error bars: ± one standard error of the Monte Carlo σ⁰ per direction
(``info["sigma0_std"]``). The backward half of the plane is drawn at negative θs (φs = π).

Run: PYTHONPATH=src python validation/mom3d/mom3d_vs_models.py [--realizations 24]
     [--plot-only]   (≈ 3 min on 2 cores; ``--plot-only`` redraws from the CSV)
Writes mom3d_vs_models.csv here and docs/figures/mom3d_vs_models.png.
"""

from __future__ import annotations

import argparse
import math
import platform
import time
import warnings
from pathlib import Path

import numpy as np

import emscatter as em
from emscatter.io import read_csv, save_figure, write_csv
from emscatter.solvers import mom3d
from emscatter.spectra import GaussianCorrelation

HERE = Path(__file__).resolve().parent
CSV = HERE / "mom3d_vs_models.csv"
PNG = HERE.parents[1] / "docs" / "figures" / "mom3d_vs_models.png"
K = 2 * math.pi  # λ = 1 m
KS, KL, THETA_I, LENGTH, PPW = 1.0, 7.0, 40.0, 6.0, 8.0
MODELS = ("spm", "iem", "po", "go")


def compute(realizations: int, seed: int = 11) -> None:
    rough = GaussianCorrelation(KS / K, KL / K)
    deg = np.arange(-70.0, 71.0, 5.0)  # signed θs: < 0 is the backward half (φs = π)
    ts, ps = np.radians(np.abs(deg)), np.where(deg < 0, math.pi, 0.0)
    ti = math.radians(THETA_I)
    t0 = time.perf_counter()
    res = mom3d.bistatic(
        rough,
        "pec",
        K,
        ti,
        ts,
        ps,
        realizations=realizations,
        seed=seed,
        length=LENGTH,
        points_per_wavelength=PPW,
    )
    seconds = time.perf_counter() - t0
    cols, header = [deg], ["theta_s_deg"]
    for p, (a, b) in (("hh", (0, 0)), ("vv", (1, 1))):
        cols += [res.sigma0[a, b], res.info["sigma0_std"][a, b]]
        header += [f"mom3d_{p}", f"mom3d_{p}_se"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # SPM/GO are out of range here on purpose
        for m in MODELS:
            s = em.bistatic(
                rough,
                "pec",
                wavelength=1.0,
                theta_i=ti,
                theta_s=ts,
                phi_s=ps,
                method=m,
                out_of_range="ignore",
            )
            cols += [s.pol("hh"), s.pol("vv")]
            header += [f"{m}_hh", f"{m}_vv"]
    meta = {
        "k_sigma": KS,
        "k_ell": KL,
        "theta_i_deg": THETA_I,
        "length_wavelengths": LENGTH,
        "points_per_wavelength": PPW,
        "realizations": realizations,
        "seed": seed,
        "seconds": round(seconds, 1),
        "energy_min": float(res.info["energy"].min()),
        "energy_mean": res.info["energy"].mean(axis=0),
        "coherent": res.coherent[:, 0],
        "python": platform.python_version(),
        "emscatter": em.__version__,
    }
    write_csv(CSV, header, cols, metadata=meta, schema="mom3d_vs_models/1")
    print(
        f"mom3d: {realizations} realizations in {seconds:.0f} s, energy ≥ {meta['energy_min']:.4f}"
    )


def plot() -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    _, c, meta = read_csv(CSV)
    deg = c["theta_s_deg"]
    fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
    style = {"spm": ("C0", ":"), "iem": ("C1", "-."), "po": ("C2", "-"), "go": ("C3", "--")}
    for ax, p in zip(axes, ("hh", "vv"), strict=True):
        mean, se = c[f"mom3d_{p}"], c[f"mom3d_{p}_se"]
        lo = 10 * np.log10(np.maximum(mean - se, 1e-6 * mean.max()))
        hi = 10 * np.log10(mean + se)
        db = 10 * np.log10(mean)
        ax.errorbar(
            deg,
            db,
            yerr=[db - lo, hi - db],
            fmt="ko",
            ms=3.5,
            capsize=2,
            label=f"mom3d (MFIE, {meta['realizations']} realizations)",
        )
        for m in MODELS:
            col, ls = style[m]
            ax.plot(
                deg,
                10 * np.log10(np.maximum(c[f"{m}_{p}"], 1e-30)),
                color=col,
                ls=ls,
                label=m.upper(),
            )
        ax.axvline(meta["theta_i_deg"], color="0.7", lw=0.8)
        ax.set_title(
            f"{p}, PEC, kσ = {meta['k_sigma']:g}, kℓ = {meta['k_ell']:g}, "
            f"θi = {meta['theta_i_deg']:g}°"
        )
        ax.set_xlabel("θs [deg] (< 0: backward, φs = π)")
        ax.set_ylim(-25, 20)
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("σ⁰ [dB]")
    axes[1].legend(fontsize=8, loc="lower center")
    fig.tight_layout()
    save_figure(fig, PNG)
    print(f"wrote {PNG.name}")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--realizations", type=int, default=24)
    ap.add_argument("--plot-only", action="store_true")
    args = ap.parse_args(argv)
    if not args.plot_only:
        compute(args.realizations)
    plot()


if __name__ == "__main__":
    main()
