"""Figures (matplotlib, headless): surfaces and spectra, bistatic and emissivity curves."""

from __future__ import annotations

import math

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

__all__ = ["surface_figure", "curves_figure", "emissivity_figure"]


def surface_figure(heights, spacing, *, title: str = "", psd=None, stats: dict | None = None):
    """Height map (or profile) beside its radially averaged PSD (log–log).

    ``psd``: optional ``(k, P)`` [rad/m, m^(2+d)] from :func:`emscatter.surfaces.measure.psd`.
    """
    h = np.asarray(heights)
    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(10, 4.2))
    if h.ndim == 2:
        dy, dx = spacing
        ny, nx = h.shape
        im = ax0.imshow(
            h, extent=(0, nx * dx, 0, ny * dy), origin="lower", cmap="terrain", aspect="equal"
        )
        fig.colorbar(im, ax=ax0, label="height [m]")
        ax0.set_xlabel("x [m]")
        ax0.set_ylabel("y [m]")
    else:
        (dx,) = spacing
        ax0.plot(np.arange(h.size) * dx, h, lw=0.6)
        ax0.set_xlabel("x [m]")
        ax0.set_ylabel("height [m]")
    ax0.set_title(title or "surface")
    if psd is not None:
        k, p = psd
        good = (k > 0) & (p > 0)
        ax1.loglog(k[good], p[good], lw=1)
        ax1.set_xlabel("wavenumber K [rad/m]")
        ax1.set_ylabel(f"PSD [m$^{{{2 + h.ndim}}}$]")
        ax1.set_title("radially averaged power spectrum")
        ax1.grid(True, which="both", alpha=0.3)
    if stats:
        text = "\n".join(
            f"{k}: {v:.4g}" if isinstance(v, float) else f"{k}: {v}" for k, v in stats.items()
        )
        ax1.text(
            0.98,
            0.98,
            text,
            transform=ax1.transAxes,
            fontsize=7,
            va="top",
            ha="right",
            family="monospace",
            bbox={"facecolor": "white", "alpha": 0.8, "lw": 0},
        )
    fig.tight_layout()
    return fig


def curves_figure(
    x_deg,
    curves: dict[str, np.ndarray],
    *,
    xlabel: str,
    ylabel: str,
    title: str,
    db: bool = True,
    floor_db: float = -80.0,
):
    """Several curves over an angle axis; ``db=True`` plots ``10 log10`` with a floor."""
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    for label, y in curves.items():
        y = np.asarray(y, dtype=float)
        if db:
            y = np.maximum(10 * np.log10(np.maximum(y, 1e-300)), floor_db)
        ax.plot(x_deg, y, label=label)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def emissivity_figure(theta_deg, series: dict[str, tuple[np.ndarray, np.ndarray]], *, title: str):
    """``series[label] = (e_h, e_v)``; h solid, v dashed."""
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for i, (label, (eh, ev)) in enumerate(series.items()):
        c = colors[i % len(colors)]
        ax.plot(theta_deg, eh, color=c, label=f"{label}  h")
        ax.plot(theta_deg, ev, color=c, ls="--", label=f"{label}  v")
    ax.set_xlabel("incidence / observation angle θ [deg]")
    ax.set_ylabel("emissivity [-]")
    ax.set_ylim(0, 1)
    ax.set_xlim(0, math.ceil(max(theta_deg)))
    ax.set_title(title, fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    return fig
