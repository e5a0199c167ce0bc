"""Bias and spread of every Hurst estimator and of box counting, H = 0.1 … 0.9.

    .venv/bin/python validation/hurst_estimators.py
    # → validation/hurst_estimators.csv, .png, .md   (about 2 min on one core)

Records: exact fBm from emscatter's generator — 2-D 512² (Stein 2002 embedding) and 1-D
2¹⁴ (Davies–Harte) — plus, as a cross-check, SurfaceTopography's periodic self-affine maps
256² (Fourier synthesis with a radial cutoff at π/dx). For each record every estimator of
:func:`emscatter.surfaces.measure.hurst_exponent` is run with its defaults (and the
periodogram with ``window=None`` on the periodic maps), and box counting
(:func:`~emscatter.surfaces.measure.box_counting_dimension`) is converted to
``H = d + 1 − D``. The table holds, per (record kind, H, estimator): the mean and standard
deviation of the recovered H over realizations, the bias, the mean reported standard
error, and the fractal dimension (D true, D from the mean H).
"""

from __future__ import annotations

import csv
import re
import sys
import time
from pathlib import Path

import numpy as np

from emscatter.spectra import FractionalBrownian
from emscatter.surfaces import measure as M
from emscatter.surfaces.generate import generate_batch

HERE = Path(__file__).resolve().parent
HURSTS = [round(0.1 * i, 1) for i in range(1, 10)]
KINDS = {
    # name: (dimension, shape, realizations)
    "fbm-1d-16384": (1, 2**14, 48),
    "fbm-2d-512": (2, (512, 512), 24),
    "surfacetopography-2d-256": (2, (256, 256), 16),
}
SEED = 20261122


def _records(kind: str, hurst: float, seed: int):
    dim, shape, count = KINDS[kind]
    if kind.startswith("fbm"):
        rough = FractionalBrownian(hurst, 1.0, 1.0, dim)
        return [s.heights for s in generate_batch(rough, count, shape, 1.0, seed=seed)]
    from SurfaceTopography.Generation import fourier_synthesis

    rng = np.random.default_rng(seed)
    return [
        fourier_synthesis(shape, (1.0, 1.0), hurst=hurst, rms_height=1.0, rng=rng).heights()
        for _ in range(count)
    ]


def _estimators(kind: str):
    est = {m: (lambda h, m=m: M.hurst_exponent(h, 1.0, m)) for m in M.HURST_METHODS}
    if kind.startswith("surfacetopography"):
        est["periodogram-raw"] = lambda h: M.hurst_exponent(h, 1.0, "periodogram", window=None)
    est["box-counting"] = lambda h: M.box_counting_dimension(h, 1.0)
    return est


def run() -> list[dict]:
    rows = []
    for ik, kind in enumerate(KINDS):
        dim, shape, count = KINDS[kind]
        for ih, hurst in enumerate(HURSTS):
            t0 = time.perf_counter()
            recs = _records(kind, hurst, SEED + 100 * ik + ih)
            for name, fn in _estimators(kind).items():
                res = [fn(h) for h in recs]
                hs = np.array([r.hurst for r in res])
                se = np.array([r.stderr for r in res])
                rows.append(
                    {
                        "record": kind,
                        "dimension": dim,
                        "shape": "x".join(map(str, np.atleast_1d(shape))),
                        "realizations": count,
                        "hurst_true": hurst,
                        "estimator": name,
                        "hurst_mean": float(hs.mean()),
                        "hurst_bias": float(hs.mean() - hurst),
                        "hurst_std": float(hs.std(ddof=1)),
                        "stderr_of_mean": float(hs.std(ddof=1) / np.sqrt(count)),
                        # box counting: stderr of the D fit (regression residuals)
                        "reported_stderr_mean": float(se.mean()),
                        "D_true": dim + 1 - hurst,
                        "D_mean": float(dim + 1 - hs.mean()),
                    }
                )
            print(f"{kind:26s} H={hurst:.1f}  {time.perf_counter() - t0:5.1f} s", flush=True)
    return rows


def write_csv(rows, path: Path) -> None:
    with path.open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.4f}" if isinstance(v, float) else v) for k, v in r.items()})


def plot(rows, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(KINDS), figsize=(5.2 * len(KINDS), 4.8), sharey=True)
    styles = {
        "variogram": ("C0", "o"),
        "madogram": ("C1", "s"),
        "periodogram": ("C2", "^"),
        "periodogram-raw": ("C4", "v"),
        "box-counting": ("C3", "D"),
    }
    for ax, kind in zip(axes, KINDS, strict=True):
        sub = [r for r in rows if r["record"] == kind]
        names = list(dict.fromkeys(r["estimator"] for r in sub))
        for i, name in enumerate(names):
            rr = [r for r in sub if r["estimator"] == name]
            x = np.array([r["hurst_true"] for r in rr]) + 0.012 * (i - (len(names) - 1) / 2)
            c, mk = styles[name]
            label = name if name != "box-counting" else "box counting (H = d+1−D)"
            ax.errorbar(
                x,
                [r["hurst_mean"] for r in rr],
                yerr=[r["hurst_std"] for r in rr],
                fmt=mk,
                color=c,
                ms=4,
                capsize=2,
                label=label,
            )
        ax.plot([0, 1], [0, 1], "k--", lw=0.8, label="truth")
        dim, shape, count = KINDS[kind]
        ax.set_title(f"{kind} ({count} realizations)", fontsize=10)
        ax.set_xlabel("true H")
        ax.set_xlim(0, 1)
        ax.set_ylim(0, 1.05)
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("recovered H (mean ± std over realizations)")
    axes[-1].legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def write_md(rows, path: Path, seconds: float) -> None:
    lines = [
        "# Hurst-exponent estimators and box counting: bias and spread",
        "",
        f"Made by (about {seconds:.0f} s on one core of the build machine):",
        "",
        "    .venv/bin/python validation/hurst_estimators.py",
        "",
        "Records: exact fBm from `emscatter.surfaces.generate` (1-D 2^14 Davies–Harte, 2-D 512²",
        "Stein 2002), and SurfaceTopography's periodic self-affine maps 256² (`fourier_synthesis`,",
        "PSD ∝ q^(−2−2H) cut off at π/dx). Estimators with their defaults:",
        "`hurst_exponent(h, dx, m)` (default m = periodogram) for m in variogram (lags 1–16",
        "samples), madogram, periodogram",
        "(Hann-tapered increments, aliasing of the sampled power law in the model, band",
        "(0, 0.5)·K_Nyquist), `periodogram-raw` = periodogram with `window=None` (plain power law",
        "on the raw periodogram, same band; periodic maps only), and `box_counting_dimension`",
        "converted with H = d + 1 − D. `bias` = mean − true; `std` = scatter over",
        "realizations; `se` = mean reported standard error (box counting: error of the D fit).",
        "",
        "![recovered vs true H](hurst_estimators.png)",
        "",
    ]
    lines += ["## What it shows", ""]

    def worst(kind, est):
        rr = [r for r in rows if r["record"] == kind and r["estimator"] == est]
        return max(abs(r["hurst_bias"]) for r in rr) if rr else float("nan")

    def box_range(kind):
        rr = [
            r["D_mean"] - r["D_true"]
            for r in rows
            if r["record"] == kind and r["estimator"] == "box-counting"
        ]
        return min(rr), max(rr)

    b1, b2 = box_range("fbm-1d-16384"), box_range("fbm-2d-512")
    lines += [
        f"* **Box counting is strongly biased**: on exact fBm its D is too low by "
        f"{-b1[1]:.2f}–{-b1[0]:.2f} on profiles and {-b2[1]:.2f}–{-b2[0]:.2f} on 512² maps, "
        "worst for rough (low-H) records — the dimension is pulled toward the topological "
        "one, d. Read D from the Hurst estimators (D = d + 1 − H) instead.",
        f"* The default periodogram (aliasing in the model) is unbiased on exact fBm: max "
        f"|bias| {worst('fbm-1d-16384', 'periodogram'):.3f} (1-D), "
        f"{worst('fbm-2d-512', 'periodogram'):.3f} (2-D), with a calibrated standard error.",
        f"* Variogram / madogram: max |bias| {worst('fbm-1d-16384', 'variogram'):.3f} (1-D), "
        f"{worst('fbm-2d-512', 'variogram'):.3f} (2-D, at high H where its scatter grows and "
        "its jackknife error is too small).",
        "* On band-limited periodic surfaces (SurfaceTopography) the variogram and the aliased "
        f"periodogram are biased (up to {worst('surfacetopography-2d-256', 'variogram'):.2f} and "
        f"{worst('surfacetopography-2d-256', 'periodogram'):.2f}); the raw periodogram "
        f"(`window=None`) recovers their H within "
        f"{worst('surfacetopography-2d-256', 'periodogram-raw'):.3f}.",
        "",
    ]
    lines += [
        "## Summary per estimator (over H = 0.1 … 0.9)",
        "",
        "| record | estimator | max abs bias | at H | mean std | se/std (min–max) |",
        "|---|---|---|---|---|---|",
    ]
    for kind in KINDS:
        names = list(dict.fromkeys(r["estimator"] for r in rows if r["record"] == kind))
        for n in names:
            rr = [r for r in rows if r["record"] == kind and r["estimator"] == n]
            worst = max(rr, key=lambda r: abs(r["hurst_bias"]))
            ratio = [r["reported_stderr_mean"] / r["hurst_std"] for r in rr]
            lines += [
                f"| {kind} | {n} | {abs(worst['hurst_bias']):.3f} | {worst['hurst_true']} | "
                f"{np.mean([r['hurst_std'] for r in rr]):.3f} | "
                f"{min(ratio):.2f}–{max(ratio):.2f} |"
            ]
    lines += [""]
    # summary of the box-counting bias
    lines += ["## Box-counting bias (D from box counting − true D)", ""]
    lines += ["| record | " + " | ".join(f"H={h}" for h in HURSTS) + " |"]
    lines += ["|---|" + "---|" * len(HURSTS)]
    for kind in KINDS:
        rr = [r for r in rows if r["record"] == kind and r["estimator"] == "box-counting"]
        lines += [
            f"| {kind} | " + " | ".join(f"{r['D_mean'] - r['D_true']:+.3f}" for r in rr) + " |"
        ]
    lines += ["", "## Bias of every estimator (mean H − true H)", ""]
    for kind in KINDS:
        lines += [f"### {kind}", ""]
        names = list(dict.fromkeys(r["estimator"] for r in rows if r["record"] == kind))
        lines += ["| H | " + " | ".join(f"{n} bias ± std (se)" for n in names) + " |"]
        lines += ["|---|" + "---|" * len(names)]
        for h in HURSTS:
            cells = []
            for n in names:
                (r,) = [
                    q
                    for q in rows
                    if q["record"] == kind and q["estimator"] == n and q["hurst_true"] == h
                ]
                b, sd, se = r["hurst_bias"], r["hurst_std"], r["reported_stderr_mean"]
                cells.append(f"{b:+.3f} ± {sd:.3f} ({se:.3f})")
            lines += [f"| {h} | " + " | ".join(cells) + " |"]
        lines += [""]
    lines += ["Full numbers: [hurst_estimators.csv](hurst_estimators.csv).", ""]
    path.write_text("\n".join(lines))


def read_csv(path: Path) -> list[dict]:
    rows = []
    with path.open() as f:
        for r in csv.DictReader(f):
            for k, v in r.items():
                try:
                    r[k] = int(v) if k in ("dimension", "realizations") else float(v)
                except ValueError:
                    pass
            rows.append(r)
    return rows


def main() -> list[dict]:
    """``--from-csv``: redraw the figure and the markdown from the saved CSV."""
    if "--from-csv" in sys.argv:
        rows = read_csv(HERE / "hurst_estimators.csv")
        old = (
            (HERE / "hurst_estimators.md").read_text()
            if (HERE / "hurst_estimators.md").exists()
            else ""
        )
        m = re.search(r"about (\d+) s", old)
        plot(rows, HERE / "hurst_estimators.png")
        write_md(rows, HERE / "hurst_estimators.md", float(m.group(1)) if m else float("nan"))
        return rows
    t0 = time.perf_counter()
    rows = run()
    seconds = time.perf_counter() - t0
    write_csv(rows, HERE / "hurst_estimators.csv")
    plot(rows, HERE / "hurst_estimators.png")
    write_md(rows, HERE / "hurst_estimators.md", seconds)
    print(f"wrote validation/hurst_estimators.{{csv,png,md}} in {seconds:.0f} s")
    return rows


if __name__ == "__main__":
    sys.exit(0 if main() else 1)
