"""Interpolation and quadrature on the table axes (shared by :class:`~.table.BrdfTable`,
the energy remedy and the builders).

Every axis is a strictly increasing array of nodes [rad]. Two kinds:

* **clamped** (θ axes, the isotropic ``Δφ ∈ [0, π]`` axis): piecewise-linear between nodes,
  constant beyond the first and the last node;
* **periodic** (anisotropic ``φ ∈ [0, 2π)`` axes): piecewise-linear with the last interval
  wrapping from the last node to ``2π + first``.

The quadrature weights integrate that piecewise-linear interpolant *exactly* (against
``cosθ sinθ dθ`` on θ axes, ``dφ`` on azimuth axes), so a table's albedo is the albedo of
what a renderer interpolating the same nodes sees.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

TWO_PI = 2.0 * math.pi


@lru_cache(maxsize=32)
def _leggauss(n: int) -> tuple[np.ndarray, np.ndarray]:
    x, w = np.polynomial.legendre.leggauss(n)
    x.setflags(write=False)
    w.setflags(write=False)
    return x, w


def gauss_legendre(n: int, a: float = -1.0, b: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """``n`` Gauss–Legendre nodes and weights on ``[a, b]`` (the reference nodes cached: numpy
    computes them by an eigenvalue problem, ~1 s for n = 400)."""
    x, w = _leggauss(int(n))
    return 0.5 * (b - a) * x + 0.5 * (b + a), 0.5 * (b - a) * w


def check_table_wavelengths(wavelengths) -> np.ndarray:
    """A table's wavelength axis [m]: 1-D, positive, finite, strictly increasing; read-only copy."""
    wl = np.array(wavelengths, dtype=float).reshape(-1)
    if wl.size == 0 or not np.all(np.isfinite(wl)) or np.any(wl <= 0):
        raise ValueError(f"wavelengths must be positive finite [m], got {wl!r}")
    if np.any(np.diff(wl) <= 0):
        raise ValueError(f"wavelengths must be strictly increasing [m], got {wl!r}")
    wl.setflags(write=False)
    return wl


def check_axis(name: str, axis, low: float, high: float, *, high_open: bool = False) -> np.ndarray:
    """A 1-D strictly increasing float array within ``[low, high]`` (``high`` excluded when
    ``high_open``), read-only copy."""
    a = np.array(axis, dtype=float).reshape(-1) if np.ndim(axis) <= 1 else None
    if a is None:
        raise ValueError(f"{name} must be a 1-D array of angles [rad], got shape {np.shape(axis)}")
    if a.size == 0 or not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be a non-empty array of finite angles [rad], got {a!r}")
    if a.size > 1 and np.any(np.diff(a) <= 0):
        raise ValueError(f"{name} must be strictly increasing, got {a!r}")
    bad_high = a[-1] >= high if high_open else a[-1] > high
    if a[0] < low or bad_high:
        hb = ")" if high_open else "]"
        raise ValueError(
            f"{name} must lie in [{low:.6g}, {high:.6g}{hb} rad, got [{a[0]:.6g}, {a[-1]:.6g}]"
        )
    a.setflags(write=False)
    return a


def locate_clamped(axis: np.ndarray, x: np.ndarray):
    """``(i0, i1, t)``: ``f(x) ≈ (1−t) f[i0] + t f[i1]``, constant outside the axis."""
    n = axis.size
    if n == 1:
        z = np.zeros(x.shape, dtype=np.intp)
        return z, z, np.zeros(x.shape)
    xc = np.clip(x, axis[0], axis[-1])
    i0 = np.clip(np.searchsorted(axis, xc, side="right") - 1, 0, n - 2)
    t = (xc - axis[i0]) / (axis[i0 + 1] - axis[i0])
    return i0, i0 + 1, t


def locate_periodic(axis: np.ndarray, x: np.ndarray):
    """``(i0, i1, t)`` on a 2π-periodic axis whose nodes lie in ``[0, 2π)``."""
    n = axis.size
    xm = np.remainder(x, TWO_PI)
    i0 = np.searchsorted(axis, xm, side="right") - 1  # −1: before the first node (wraps)
    i0 = np.where(i0 < 0, n - 1, i0)
    i1 = (i0 + 1) % n
    lo = axis[i0]
    hi = np.where(i1 > i0, axis[i1], axis[i1] + TWO_PI)
    xw = np.where(xm < lo, xm + TWO_PI, xm)
    width = hi - lo
    t = np.where(width > 0, (xw - lo) / np.where(width > 0, width, 1.0), 0.0)
    return i0, i1, t


def multilinear(values: np.ndarray, locs: list[tuple]) -> np.ndarray:
    """Interpolate ``values`` (shape ``(m, n_1, …, n_d)``) at points located by ``locs``
    (one ``(i0, i1, t)`` per grid axis, each array of shape ``(N,)``) → ``(m, N)``."""
    m = values.shape[0]
    grid = values.shape[1:]
    flat = values.reshape(m, -1)
    strides = np.cumprod((1,) + grid[::-1])[:-1][::-1]
    npts = locs[0][0].size
    out = np.zeros((m, npts))
    for corner in range(1 << len(locs)):
        idx = np.zeros(npts, dtype=np.intp)
        w = np.ones(npts)
        for d, (i0, i1, t) in enumerate(locs):
            if corner >> d & 1:
                idx += i1 * strides[d]
                w = w * t
            else:
                idx += i0 * strides[d]
                w = w * (1.0 - t)
        if np.any(w):
            out += w * flat[:, idx]
    return out


def theta_weights(axis: np.ndarray) -> np.ndarray:
    """``w`` with ``Σ_k w_k f_k = ∫_0^{π/2} f(θ) cosθ sinθ dθ`` for the clamped
    piecewise-linear interpolant ``f`` of the nodes ``f_k`` (exact)."""
    a = axis
    w = np.zeros(a.size)
    w[0] += 0.5 * math.sin(a[0]) ** 2  # [0, θ_first]: constant f_0
    w[-1] += 0.5 * math.cos(a[-1]) ** 2  # [θ_last, π/2]: constant f_last
    if a.size > 1:
        lo, hi = a[:-1], a[1:]
        h = hi - lo
        i0 = 0.25 * (np.cos(2 * lo) - np.cos(2 * hi))  # ∫ sin2θ/2 dθ

        def prim(x):  # ∫ θ sin(2θ)/2 dθ
            return -0.25 * x * np.cos(2 * x) + 0.125 * np.sin(2 * x)

        i1 = prim(hi) - prim(lo) - lo * i0  # ∫ (θ − lo) sin2θ/2 dθ
        upper = i1 / h
        np.add.at(w, np.arange(a.size - 1), i0 - upper)
        np.add.at(w, np.arange(1, a.size), upper)
    return w


def phi_d_weights(axis: np.ndarray) -> np.ndarray:
    """Weights for ``∫_{−π}^{π} f(|Δφ|) dΔφ`` of the clamped interpolant on ``[0, π]``."""
    a = axis
    w = np.zeros(a.size)
    w[0] += a[0]
    w[-1] += math.pi - a[-1]
    if a.size > 1:
        h = np.diff(a)
        w[:-1] += 0.5 * h
        w[1:] += 0.5 * h
    return 2.0 * w


def periodic_weights(axis: np.ndarray) -> np.ndarray:
    """Weights for ``∫_0^{2π} f(φ) dφ`` of the periodic interpolant (trapezoid with wrap)."""
    ext = np.append(axis, axis[0] + TWO_PI)
    h = np.diff(ext)
    return 0.5 * (h + np.roll(h, 1))
