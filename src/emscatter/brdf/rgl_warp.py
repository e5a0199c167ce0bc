"""The pieces of the RGL ``.bsdf`` format that are arithmetic, in numpy.

* the unit square of directions ``u = (√(2θ/π), (φ + π)/2π)`` used by Mitsuba's ``measured``;
* the proxy microfacet distribution (Beckmann, Smith projected area, visible normals);
* :func:`estimate_alpha`, the Beckmann width of a BRDF's lobe (to size the proxy);
* :func:`marginal2d_sample`, the continuous marginal/conditional warp of Mitsuba's
  ``Marginal2D`` (``include/mitsuba/core/distr_2d.h``), checked against Mitsuba's own in
  ``tests/test_export_rgl.py``; :func:`bilinear`, its ``eval``;
* :func:`fill_from_neighbours` for nodes whose direction falls below the horizon.
"""

from __future__ import annotations

import math

import numpy as np

from .source import BrdfFunction

__all__ = [
    "beckmann_d",
    "beckmann_sigma",
    "bilinear",
    "direction",
    "estimate_alpha",
    "fill_from_neighbours",
    "marginal2d_sample",
    "phi2u",
    "theta2u",
    "u2phi",
    "u2theta",
]

_F32_EPS = float(np.finfo(np.float32).eps) / 2  # Dr.Jit's Epsilon<float> = 2^-24


def u2theta(u):
    return np.square(u) * (math.pi / 2)


def theta2u(theta):
    return np.sqrt(theta * (2 / math.pi))


def u2phi(u):
    return (2 * u - 1) * math.pi


def phi2u(phi):
    return (phi + math.pi) / (2 * math.pi)


def beckmann_d(m: np.ndarray, au: float, av: float) -> np.ndarray:
    """Beckmann D(m) [1/sr], normalized so that ∫ D cosθm dω = 1."""
    cz2 = np.clip(m[..., 2], 0, 1) ** 2
    t2 = (m[..., 0] / au) ** 2 + (m[..., 1] / av) ** 2  # tan²θ · (cos²φ/αu² + sin²φ/αv²) · cos²θ
    with np.errstate(divide="ignore", invalid="ignore"):
        val = np.exp(-t2 / cz2) / (math.pi * au * av * cz2 * cz2)
    return np.where(cz2 > 0, val, 0.0)


def beckmann_sigma(w: np.ndarray, au: float, av: float) -> np.ndarray:
    """Projected area σ(w) = cosθ (1 + Λ(w)) of the Beckmann surface, Smith's Λ."""
    from scipy.special import erfc

    ct = np.clip(w[..., 2], 0, 1)
    st = np.hypot(w[..., 0], w[..., 1])
    aw = np.sqrt((w[..., 0] * au) ** 2 + (w[..., 1] * av) ** 2) / np.maximum(st, 1e-300)
    aw = np.where(st > 0, aw, au)
    with np.errstate(divide="ignore"):
        a = np.where(st > 0, ct / (aw * st), np.inf)  # cotθ / α_w
    return ct * (1 - 0.5 * erfc(a)) + aw * st * np.exp(-np.square(a)) / (2 * math.sqrt(math.pi))


def direction(theta, phi) -> np.ndarray:
    st = np.sin(theta)
    return np.stack(np.broadcast_arrays(st * np.cos(phi), st * np.sin(phi), np.cos(theta)), -1)


def _weighted_median(x: np.ndarray, w: np.ndarray) -> float:
    order = np.argsort(x)
    cdf = np.cumsum(w[order])
    return float(x[order][np.searchsorted(cdf, 0.5 * cdf[-1])])


def _truncated_exponential_scale(median: float, top: float) -> float:
    """The scale a of an exponential law cut at ``top`` whose median is ``median``:
    ``1 − exp(−median/a) = ½ (1 − exp(−top/a))`` (bisection on ln a)."""
    lo, hi = math.log(median / 50), math.log(50 * top)
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        a = math.exp(mid)
        if -math.expm1(-median / a) > -0.5 * math.expm1(-top / a):
            lo = mid
        else:
            hi = mid
    return math.exp(0.5 * (lo + hi))


def estimate_alpha(source: BrdfFunction) -> tuple[float, float]:
    """Beckmann-equivalent roughness ``(α_x, α_y)`` of a BRDF's lobe, from normal incidence.

    For a Beckmann surface ``tan²θh/α²`` follows the unit exponential law under the reflected
    power ``f_r cosθo dωo``; at normal incidence only ``θh < 45°`` reflects above the horizon,
    so α² solves ``1 − exp(−M/α²) = ½ (1 − exp(−T/α²))`` with M the power-weighted median of
    ``tan²θh`` and T its largest visible value (the median of a truncated exponential law;
    a median keeps heavy-tailed lobes finite). The anisotropy comes from the ratio of the
    weighted medians of ``ζ_x² = tan²θh cos²φh`` and ``ζ_y²``.
    """
    n = 128
    u = (np.arange(n) + 0.5) / n
    th_m = u2theta(u)[:, None]
    ph_m = u2phi(u)[None, :]
    m = direction(th_m, ph_m)
    wi = np.array([0.0, 0.0, 1.0])
    wo = 2 * m[..., 2:3] * m - wi
    ok = wo[..., 2] > 1e-9
    f = np.zeros(ok.shape)
    f[ok] = source.evaluate(np.broadcast_to(wi, wo.shape)[ok], wo[ok]).mean(-1)
    # power per cell: f cosθo dωo, dωo = 4 cosθm sinθm dθm dφm and dθm ∝ u du
    w = np.where(ok, f * wo[..., 2] * m[..., 2] * np.sin(th_m) * u[:, None], 0.0)
    if not np.any(w > 0):
        raise ValueError("the BRDF reflects no power at normal incidence; give alpha=")
    tan2 = np.broadcast_to(np.tan(th_m) ** 2, w.shape)
    top = float(tan2[ok].max())
    a2 = 0.0
    weights = w[ok]
    for _ in range(4):  # undo the shadowing of the outgoing direction, Smith G1 at the estimate
        if a2 > 0:
            a = math.sqrt(a2)
            weights = w[ok] * beckmann_sigma(wo[ok], a, a) / wo[ok][:, 2]
        a2 = _truncated_exponential_scale(_weighted_median(tan2[ok], weights), top)
    zx2 = tan2 * np.cos(ph_m) ** 2
    zy2 = tan2 * np.sin(ph_m) ** 2
    ratio = _weighted_median(zx2[ok], weights) / max(_weighted_median(zy2[ok], weights), 1e-300)
    return math.sqrt(2 * a2 * ratio / (1 + ratio)), math.sqrt(2 * a2 / (1 + ratio))


# --------------------------------------------------------------------------- Marginal2D warp


def _segment(sample, inv_width, v0, v1):
    """Invert the CDF of a linear density on one interval (Mitsuba's ``sample_segment``)."""
    non_const = np.abs(v0 - v1) > 1e-4 * (v0 + v1)
    divisor = np.where(non_const, v0 - v1, v0 + v1)
    s = sample * (2 * inv_width)
    s = np.where(non_const, v0 - np.sqrt(np.maximum(v0 * v0 + s * (v1 - v0), 0.0)), s)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(divisor != 0, s / divisor, s)


def _take(a, idx):
    return np.take_along_axis(a, idx, axis=-1)


def marginal2d_sample(data: np.ndarray, sx: np.ndarray, sy: np.ndarray):
    """The continuous marginal/conditional warp of Mitsuba's ``Marginal2D`` (distr_2d.h).

    ``data`` (S, H, W): S densities on a bilinear W×H grid over [0,1]²; ``sx``, ``sy`` (S, P)
    uniform variates. Returns the warped points ``(x, y)`` (S, P) each in [0, 1].
    """
    s_, h, w = data.shape
    d = np.asarray(data, dtype=float)
    cond = np.cumsum((0.5 / (w - 1)) * (d[..., :-1] + d[..., 1:]), axis=-1)  # (S, H, W-1)
    rows = cond[..., -1]
    marg = np.cumsum((0.5 / (h - 1)) * (rows[:, :-1] + rows[:, 1:]), axis=-1)  # (S, H-1)
    norm = 1.0 / marg[:, -1]
    cond, rows, marg, d = cond * norm[:, None, None], rows * norm[:, None], marg * norm[:, None], d
    d = d * norm[:, None, None]
    sx = np.clip(sx, _F32_EPS, 1 - _F32_EPS)
    sy = np.clip(sy, _F32_EPS, 1 - _F32_EPS)
    # row: first marginal CDF entry >= sy (offset each slice to search them all at once)
    off = np.arange(s_)[:, None] * 4.0
    row = np.searchsorted((marg + off).ravel(), (sy + off).ravel()).reshape(sy.shape)
    row = np.clip(row - np.arange(s_)[:, None] * (h - 1), 0, h - 2)
    prev = np.where(row > 0, _take(marg, np.maximum(row - 1, 0)), 0.0)
    r0, r1 = _take(rows, row), _take(rows, row + 1)
    t = _segment(sy - prev, h - 1, r0, r1)
    sx = sx * (r0 + (r1 - r0) * t)
    # column: first interpolated conditional CDF entry >= sx (vectorized binary search)
    cflat = cond.reshape(s_, h * (w - 1))
    lo_row, hi_row = row * (w - 1), (row + 1) * (w - 1)

    def cdf_at(idx):
        a, b = _take(cflat, lo_row + idx), _take(cflat, hi_row + idx)
        return a + (b - a) * t

    lo = np.zeros_like(row)
    hi = np.full_like(row, w - 2)
    for _ in range(int(math.ceil(math.log2(max(w - 1, 2)))) + 1):
        mid = (lo + hi) // 2
        below = cdf_at(mid) < sx
        lo = np.where(below, np.minimum(mid + 1, hi), lo)
        hi = np.where(below, hi, mid)
    col = lo
    prev = np.where(col > 0, cdf_at(np.maximum(col - 1, 0)), 0.0)
    dflat = d.reshape(s_, h * w)
    v00 = _take(dflat, row * w + col)
    v10 = _take(dflat, row * w + col + 1)
    v01 = _take(dflat, (row + 1) * w + col)
    v11 = _take(dflat, (row + 1) * w + col + 1)
    c0, c1 = v00 + (v01 - v00) * t, v10 + (v11 - v10) * t
    x = _segment(sx - prev, w - 1, c0, c1)
    return (col + x) / (w - 1), (row + t) / (h - 1)


def bilinear(table: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Bilinear interpolation of ``table`` (H, W) at ``x`` ∈ [0,1] (along W), ``y`` (along H),
    as Mitsuba's ``Marginal2D::eval`` does it."""
    h, w = table.shape
    px, py = np.clip(x, 0, 1) * (w - 1), np.clip(y, 0, 1) * (h - 1)
    ix, iy = np.minimum(px.astype(int), w - 2), np.minimum(py.astype(int), h - 2)
    fx, fy = px - ix, py - iy
    t = table.astype(float)
    a = t[iy, ix] * (1 - fx) + t[iy, ix + 1] * fx
    b = t[iy + 1, ix] * (1 - fx) + t[iy + 1, ix + 1] * fx
    return a * (1 - fy) + b * fy


def fill_from_neighbours(values: np.ndarray, valid: np.ndarray) -> np.ndarray:
    """Give each invalid node of ``values`` (S, C, H, W) the value of its nearest valid node in
    the same (H, W) slice; ``valid`` is (S, H, W)."""
    from scipy.ndimage import distance_transform_edt

    if not valid.any(axis=(-2, -1)).all():
        raise ValueError("an incident direction has no valid node (is the BRDF zero there?)")
    if valid.all():
        return values
    # a huge spacing along the slice axis keeps every nearest node inside its own slice
    _, (i_s, i_y, i_x) = distance_transform_edt(
        ~valid, sampling=(1e6, 1.0, 1.0), return_indices=True
    )
    return np.moveaxis(np.moveaxis(values, 1, -1)[i_s, i_y, i_x], -1, 1)
