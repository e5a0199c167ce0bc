"""Validity-map files: CSV (every number), JSON (configuration, selector failures, run time),
one PNG per polarization (a heat map per method) and a Markdown table."""

from __future__ import annotations

import math
import warnings
from dataclasses import asdict
from pathlib import Path

import numpy as np

from ..io import atomic_path, save_figure, write_csv, write_json
from .maps import CAP_DB, TOL_DB, MapConfig, map_methods, selector_failures, tag_of

__all__ = [
    "CSV_HEADER",
    "write_map",
    "read_map",
    "plot_map",
    "plot_method",
    "markdown_table",
    "TITLES",
]

CSV_HEADER = (
    "k_sigma",
    "k_l",
    "rms_slope",
    "method",
    "pol",
    "error_dB",
    "max_error_dB",
    "n_bins",
    "mom_se_dB",
    "valid",
    "auto",
    "status",
    "realizations",
    "unknowns",
    "seconds",
)
_NUMERIC = ("k_sigma", "k_l", "rms_slope", "error_dB", "max_error_dB", "mom_se_dB", "seconds")
LETTERS = {"spm1": "S", "go": "G", "po": "P", "iem": "I"}
TITLES = {
    "spm1": "SPM1 σ⁰",
    "spm2": "SPM2 coherent reflectivity",
    "po": "Kirchhoff PO σ⁰",
    "go": "Kirchhoff GO σ⁰ (shadowed)",
    "go_surface": "GO σ⁰, full slope of the (tapered) surface",
    "iem": "IEM σ⁰ (AIEM)",
    "iem92": "IEM σ⁰, 1992 configuration (fung92, incident Fresnel)",
}


def _edges(v: np.ndarray) -> np.ndarray:
    lv = np.log(v)
    if v.size == 1:
        return np.exp([lv[0] - 0.3, lv[0] + 0.3])
    mid = 0.5 * (lv[1:] + lv[:-1])
    return np.exp(np.concatenate([[2 * lv[0] - mid[0]], mid, [2 * lv[-1] - mid[-1]]]))


def _cell(ks, kl, r):
    return int(np.argmin(np.abs(ks - r["k_sigma"]))), int(np.argmin(np.abs(kl - r["k_l"])))


def _matrix(rows, method, pol, ks, kl, key="error_dB"):
    z = np.full((ks.size, kl.size), np.nan)
    for r in rows:
        if r["method"] == method and r["pol"] == pol:
            z[_cell(ks, kl, r)] = r[key]
    return z


def _log_axes(ax, x: np.ndarray, y: np.ndarray) -> None:
    """Log axes ticked at the grid values, plain number labels."""
    from matplotlib.ticker import FuncFormatter

    ax.set_xscale("log")
    ax.set_yscale("log")
    for axis in (ax.xaxis, ax.yaxis):
        axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        axis.set_minor_formatter(FuncFormatter(lambda v, _: ""))
    ax.set_xticks(x)
    ax.set_yticks(y)


def _title(cfg: MapConfig) -> str:
    eps = cfg.eps if isinstance(cfg.eps, str) else f"ε = {complex(cfg.eps)}"
    return f"{eps}, θi = {cfg.theta_i_deg:g}°, {cfg.correlation} 1-D"


def plot_map(rows: list[dict], cfg: MapConfig, pol: str, path, methods=None) -> Path:
    """Heat maps (one per method) of the error [dB] for ``pol``, values printed, the 1 dB
    contour, and the ``auto`` choice (letter) in every cell."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm

    methods = tuple(methods or map_methods(cfg))
    present = {r["method"] for r in rows}
    methods = tuple(m for m in methods if m in present)
    ks = np.asarray(cfg.k_sigma, dtype=float)
    kl = np.asarray(cfg.k_l, dtype=float)
    auto = {(r["k_sigma"], r["k_l"]): r["auto"] for r in rows}
    ncol = 2 if len(methods) <= 4 else 3
    nrow = math.ceil(len(methods) / ncol)
    fig, axes = plt.subplots(
        nrow, ncol, figsize=(6 * ncol, 5 * nrow), constrained_layout=True, squeeze=False
    )
    norm = LogNorm(vmin=0.05, vmax=CAP_DB)
    xe, ye = _edges(kl), _edges(ks)
    mesh = None
    for ax in axes.ravel()[len(methods) :]:
        ax.set_visible(False)
    for ax, m in zip(axes.ravel(), methods, strict=False):
        z = _matrix(rows, m, pol, ks, kl)
        mesh = ax.pcolormesh(
            xe, ye, np.clip(np.ma.masked_invalid(z), 0.05, CAP_DB), norm=norm, cmap="viridis_r"
        )
        nc = np.zeros_like(z)
        for r in rows:
            if r["method"] == m and r["pol"] == pol and r["status"].startswith("not computed"):
                nc[_cell(ks, kl, r)] = 1
        ax.pcolormesh(xe, ye, np.ma.masked_equal(nc, 0), cmap="Greys", vmin=0, vmax=4)
        _log_axes(ax, kl, ks)
        finite = np.isfinite(z)
        if finite.sum() >= 4 and ks.size > 1 and kl.size > 1:
            zc = np.where(finite, z, CAP_DB)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                ax.contour(kl, ks, zc, levels=[TOL_DB], colors="red", linewidths=2)
        for i in range(ks.size):
            for j in range(kl.size):
                txt = "—" if not np.isfinite(z[i, j]) else f"{z[i, j]:.2g}"
                a = LETTERS.get(auto.get((float(ks[i]), float(kl[j])), ""), "")
                color = "white" if np.isfinite(z[i, j]) and z[i, j] > 3 else "black"
                ax.text(kl[j], ks[i], txt, ha="center", va="center", fontsize=8, color=color)
                if m in LETTERS:
                    ax.text(
                        kl[j] * 1.12,
                        ks[i] * 1.12,
                        a,
                        ha="left",
                        va="bottom",
                        fontsize=7,
                        color="red" if LETTERS.get(m) == a else "grey",
                    )
        ax.set_xlabel("kℓ")
        ax.set_ylabel("kσ")
        ax.set_title(TITLES.get(m, m))
    fig.suptitle(
        f"Error vs method of moments [dB], pol {pol} ({'TE' if pol == 'h' else 'TM'}), "
        f"{_title(cfg)}; red line: 1 dB; letters: auto choice "
        f"({'/'.join(LETTERS[m] for m in LETTERS if m in methods)})\n"
        "grey: not computed (rms slope too steep); "
        "'—' in SPM2: MoM coherent reflectivity below its noise"
    )
    fig.colorbar(mesh, ax=axes, shrink=0.6, label="error [dB]")
    return save_figure(fig, path)


def markdown_table(rows: list[dict], methods=None) -> str:
    """The map as a Markdown table: one line per cell, errors h/v per method."""
    methods = tuple(methods or dict.fromkeys(r["method"] for r in rows))
    cells: dict = {}
    for r in rows:
        c = cells.setdefault((r["k_sigma"], r["k_l"]), {"auto": r["auto"], "m": r["rms_slope"]})
        c[(r["method"], r["pol"])] = r["error_dB"]
    head = "| kσ | kℓ | slope | auto | " + " | ".join(f"{m} h/v" for m in methods) + " |"
    lines = [head, "|" + "---|" * (4 + len(methods))]

    def f(v):
        return "—" if v is None or not np.isfinite(v) else f"{v:.2f}"

    for (ks, kl), c in sorted(cells.items()):
        vals = " | ".join(f"{f(c.get((m, 'h')))} / {f(c.get((m, 'v')))}" for m in methods)
        lines.append(f"| {ks:g} | {kl:g} | {c['m']:.2f} | {c['auto']} | {vals} |")
    return "\n".join(lines) + "\n"


def write_map(
    rows: list[dict], cfg: MapConfig, out: Path, *, seconds: float = 0.0, plots: bool = True
) -> list:
    """CSV, JSON, one PNG per pol (unless ``plots=False``) and the Markdown table, named
    ``validity_<tag>.*``."""
    out = Path(out)
    tag = tag_of(cfg)
    cols = [np.array([r[h] for r in rows], dtype=object) for h in CSV_HEADER]
    paths = [write_csv(out / f"validity_{tag}.csv", CSV_HEADER, cols)]
    meta = {
        "config": {**asdict(cfg), "eps": str(cfg.eps)},
        "wavelength_m": 1.0,
        "mom_seconds": seconds,
        "selector_failures": selector_failures(rows),
        "methods": list(dict.fromkeys(r["method"] for r in rows)),
    }
    paths.append(write_json(out / f"validity_{tag}.json", meta))
    for p in "hv" if plots else "":
        paths.append(plot_map(rows, cfg, p, out / f"validity_{tag}_{p}.png"))
    md = out / f"validity_{tag}.md"
    with atomic_path(md) as tmp:
        tmp.write_text(markdown_table(rows))
    paths.append(md)
    return paths


def read_map(path) -> list[dict]:
    """Rows of a map CSV written by :func:`write_map` (numbers parsed)."""
    import csv

    with open(path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    for r in rows:
        for key in _NUMERIC:
            r[key] = float(r[key])
        for key in ("n_bins", "realizations", "unknowns"):
            r[key] = int(r[key])
        r["valid"] = r["valid"] == "True"
    return rows


def plot_method(rows_by_cfg: list[tuple[MapConfig, list[dict]]], method: str, path) -> Path:
    """One method's error [dB] on every map (columns) and polarization (rows): the map a
    model's own README figure shows (e.g. the IEM's)."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm

    ncol = len(rows_by_cfg)
    fig, axes = plt.subplots(
        2, ncol, figsize=(4.6 * ncol, 8.4), constrained_layout=True, squeeze=False
    )
    norm = LogNorm(vmin=0.05, vmax=CAP_DB)
    mesh = None
    for j, (cfg, rows) in enumerate(rows_by_cfg):
        ks = np.asarray(cfg.k_sigma, dtype=float)
        kl = np.asarray(cfg.k_l, dtype=float)
        for i, pol in enumerate("hv"):
            ax = axes[i, j]
            z = _matrix(rows, method, pol, ks, kl)
            mesh = ax.pcolormesh(
                _edges(kl),
                _edges(ks),
                np.clip(np.ma.masked_invalid(z), 0.05, CAP_DB),
                norm=norm,
                cmap="viridis_r",
            )
            _log_axes(ax, kl, ks)
            ax.tick_params(labelsize=7)
            finite = np.isfinite(z)
            if finite.sum() >= 4:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    ax.contour(kl, ks, np.where(finite, z, CAP_DB), levels=[TOL_DB],
                               colors="red", linewidths=2)  # fmt: skip
            for a in range(ks.size):
                for b in range(kl.size):
                    if np.isfinite(z[a, b]):
                        ax.text(kl[b], ks[a], f"{z[a, b]:.2g}", ha="center", va="center",
                                fontsize=7, color="white" if z[a, b] > 3 else "black")  # fmt: skip
            ax.set_title(f"{_title(cfg)}, {pol}", fontsize=9)
            ax.set_xlabel("kℓ")
            ax.set_ylabel("kσ")
    fig.suptitle(
        f"{TITLES.get(method, method)}: error against the method of moments [dB] "
        "(θi = 20°, 1-D profiles; red line: 1 dB; blank: not computed or MoM below its noise)"
    )
    fig.colorbar(mesh, ax=axes, shrink=0.6, label="error [dB]")
    return save_figure(fig, path)
