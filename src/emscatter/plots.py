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
    floor_db: float | None = None,
):
    """Several curves over an angle axis; ``db=True`` plots ``10 log10``.

    Values are drawn as computed: zeros (−∞ dB) and NaN leave gaps rather than a fake floor;
    ``floor_db`` (default none) clips only if asked."""
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    for label, y in curves.items():
        y = np.asarray(y, dtype=float)
        if db:
            with np.errstate(divide="ignore", invalid="ignore"):
                y = np.where(y > 0, 10 * np.log10(np.where(y > 0, y, 1.0)), np.nan)
            if floor_db is not None:
                y = np.maximum(y, floor_db)
        ax.plot(x_deg, y, label=label)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def _spans(x, mask):
    """Contiguous runs of ``mask`` over the sorted axis ``x`` as ``(start, stop)`` pairs,
    widened by half a step so a single flagged point shows."""
    x = np.asarray(x, dtype=float)
    mask = np.asarray(mask, dtype=bool)
    if x.size == 0 or not mask.any():
        return []
    order = np.argsort(x)
    x, mask = x[order], mask[order]
    half = 0.5 * (np.min(np.diff(x)) if x.size > 1 else 1.0)
    spans, start = [], None
    for i, m in enumerate(mask):
        if m and start is None:
            start = x[i]
        if start is not None and (not m or i == x.size - 1):
            stop = x[i] if m else x[i - 1]
            spans.append((start - half, stop + half))
            start = None
    return spans


def emissivity_figure(
    theta_deg,
    series: dict[str, tuple[np.ndarray, np.ndarray]],
    *,
    title: str,
    flagged=None,
    flag_label: str = "energy not conserved / outside validity",
):
    """``series[label] = (e_h, e_v)``; h solid, v dashed.

    The axis always shows all the data — never clipped to [0, 1]: the physical bounds
    e = 0 and e = 1 are drawn as lines, and the angles in ``flagged`` (a bool array over
    ``theta_deg``, e.g. ``~result.energy_ok``) are shaded and labelled."""
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    theta_deg = np.atleast_1d(np.asarray(theta_deg, dtype=float))
    marker = "o" if theta_deg.size < 4 else None
    values = []
    for i, (label, (eh, ev)) in enumerate(series.items()):
        c = colors[i % len(colors)]
        ax.plot(theta_deg, np.atleast_1d(eh), color=c, marker=marker, label=f"{label}  h")
        ax.plot(theta_deg, np.atleast_1d(ev), color=c, ls="--", marker=marker, label=f"{label}  v")
        values += [np.atleast_1d(eh), np.atleast_1d(ev)]
    for bound in (0.0, 1.0):
        ax.axhline(bound, color="0.3", lw=0.8, ls=":")
    if flagged is not None:
        for j, (a, b) in enumerate(_spans(theta_deg, flagged)):
            ax.axvspan(
                a, b, color="tab:red", alpha=0.15, lw=0, label=flag_label if j == 0 else None
            )
    finite = np.concatenate([v[np.isfinite(v)] for v in values]) if values else np.array([])
    lo = min(0.0, float(finite.min())) if finite.size else 0.0
    hi = max(1.0, float(finite.max())) if finite.size else 1.0
    pad = 0.04 * (hi - lo)
    ax.set_ylim(lo - pad, hi + pad)
    ax.set_xlabel("incidence / observation angle θ [deg]")
    ax.set_ylabel("emissivity [-]")
    right = math.ceil(float(theta_deg.max())) if theta_deg.size else 90
    left = min(0.0, float(theta_deg.min())) if theta_deg.size else 0.0
    ax.set_xlim(left, right if right > left else left + 1)
    ax.set_title(title, fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    return fig
