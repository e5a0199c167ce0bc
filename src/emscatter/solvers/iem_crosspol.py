"""Cross-polarized backscatter of the integral-equation model: the multiple-scattering term.

Fung, Li & Chen (IEEE TGRS 30, 356, 1992, appendix) and Fung (1994, *Microwave Scattering
and Emission Models*, ch. 4), in the form of Ulaby & Long (2014, *Microwave Radar and
Radiometric Remote Sensing*, §10-3.9, code 10.1 ``IEMX``) and SMRT's ``iiem_fung02``::

    σ⁰_hv = σ⁰_vh = S(θ) · (1/8π) e^{−2Q} ∫∫_{|r|<1} |F_hv(r)|² Σₙ Σₘ Qⁿ⁺ᵐ/(n! m!)
                     Ŵₙ(k|r − ŝ|) Ŵₘ(k|r + ŝ|) S_m(r) d²r

with ``Q = (kσ cosθ)²``, ``ŝ = (sinθ, 0)``, ``r = (u, v)/k`` the transverse wavevector of the
intermediate (propagating, ``|r| < 1``) wave, ``Ŵₙ = k² Wₙ`` as in :mod:`.iem`, and

    F_hv = (u v / cosθ) [(b − c)(1 − 3R) − (b − c/ε)(1 + R) + (a − d)(1 + 3R) − (a − dε)(1 − R)],
    a = (1 + R)/q, b = (1 − R)/q, c = (1 + R)/q_t, d = (1 − R)/q_t,
    q = √(1 − r²), q_t = √(ε − r²), R = (R_v(θ) − R_h(θ))/2.

``S(θ) = 1/(1 + Λ(θ))`` is the monostatic Smith shadowing of the single bounce and
``S_m(r) = 1/(1 + Λ(q/r))`` the shadowing of the intermediate wave (both with the model's
nominal slope, :func:`emscatter.solvers.iem.nominal_rms_slope`). ``|F|² ∝ 1/q²`` near the
horizon ``|r| → 1`` is made integrable by ``S_m ∝ q``: without it the integral diverges
(logarithmically), so the shadowing is part of the model here, not an option.

The double sum factorizes: ``Σₙ Qⁿ/n! Ŵₙ(K) = Ŵ-normalization · Q e^Q T(Q, K)`` with the
physical-optics series ``T`` (:func:`emscatter.solvers.kirchhoff_po.series_sum`), summed to a
tolerance in log space. The integral uses ``r = sin t`` (smooth at the horizon) and
Gauss–Legendre panels graded geometrically toward the spectral peak ``r = ŝ`` (width
``1/kℓ``) in ``t`` and in azimuth, over one quadrant (the integrand is even in ``u`` and ``v``).
Per-roughness parts (nodes, spectra, shadowing) are cached for repeated calls.

PEC limit (``R = 1``, ``q_t → ∞``): ``F_hv = 8 u v/(q cosθ)``, and at small kσ the whole term
is ``(8/π) k⁴σ⁴cos²θ ∫∫ u²v²/q² W W S_m d²(u,v)/k⁴`` (the small-roughness form quoted by
Chen et al. 2003 for AIEM, without the shadowing), tested.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from ..fresnel import fresnel_cos, is_pec
from .kirchhoff_common import smith_lambda
from .kirchhoff_po import log_nfold, series_sum

__all__ = ["backscatter_hv"]


@lru_cache(maxsize=32)
def _gl(m: int):
    x, w = np.polynomial.legendre.leggauss(m)
    return 0.5 * (x + 1.0), 0.5 * w


def _graded(a: float, b: float, centers, finest: float, m: int):
    """Gauss–Legendre nodes on [a, b], panels growing ×4 away from each of ``centers``."""
    edges = {a, b}
    for center in centers:
        edges.add(center)
        for side in (-1, 1):
            d = finest
            while True:
                p = center + side * d
                if not a < p < b:
                    break
                edges.add(p)
                d *= 4.0
    e = np.array(sorted(edges))
    e = e[np.concatenate([[True], np.diff(e) > 1e-12 * (b - a)])]
    t, w = _gl(m)
    x = (e[:-1, None] + np.diff(e)[:, None] * t[None, :]).ravel()
    wx = (np.diff(e)[:, None] * w[None, :]).ravel()
    return x, wx


def _log_T(rough, log_w, Q, K):
    """log of the physical-optics series ``T(Q, K) = e^{−Q} Σ Q^{n−1}/n! wₙ(K)`` (compiled
    sums where :mod:`.iem_jit` covers the correlation)."""
    from . import iem_jit

    spec = iem_jit.spectrum_code(rough) if iem_jit.enabled() else None
    if spec is None or np.any(Q <= 0):
        return series_sum(log_w, Q, K, rtol=1e-10)
    lq = np.log(Q)
    return iem_jit.poisson_sums(lq, K, spec, rough.dimension, rtol=1e-10) - lq - Q


@lru_cache(maxsize=64)
def _spectral_part(rough, k: float, theta: float, phi_i: float, slope: tuple, order: int):
    """Nodes (u, v as r·(cos, sin) in the incidence frame), and the weights
    ``w · r dr/dt · Q² T(K−) T(K+) S_m`` · normalization, for one incidence angle."""
    ks = k * rough.sigma
    s = math.sin(theta)
    Q = (ks * math.cos(theta)) ** 2
    ell = min(rough.length, rough.length_y)
    width = min(0.25, 1.0 / (k * ell))
    t_c = math.asin(min(s, 1.0 - 1e-12))
    t, wt = _graded(0.0, 0.5 * math.pi, (t_c,), width, order)
    fine_phi = min(0.25, width / max(s, width))
    if rough.is_isotropic:  # integrand even in u and in v: one quadrant, ×4
        phi, wp = _graded(0.0, 0.5 * math.pi, (0.0,), fine_phi, order)
        quadrants = 4.0
    else:  # only (u, v) → (−u, −v) is a symmetry: a half plane, ×2
        phi, wp = _graded(0.0, math.pi, (0.0, math.pi), fine_phi, order)
        quadrants = 2.0
    r = np.sin(t)[:, None]
    q = np.cos(t)[:, None]
    cp, sp = np.cos(phi)[None, :], np.sin(phi)[None, :]
    u, v = r * cp, r * sp
    log_w = log_nfold(rough)
    c, sn = math.cos(phi_i), math.sin(phi_i)

    def scaled_K(du, dv):  # spectral argument in the surface frame, scaled by ℓ
        kx, ky = c * du - sn * dv, sn * du + c * dv
        if rough.dimension == 1:  # pragma: no cover - cross-pol is 2-D only
            return np.abs(kx) * k * rough.length
        return np.sqrt((kx * k * rough.length) ** 2 + (ky * k * rough.length_y) ** 2)

    Km = np.broadcast_to(scaled_K(u - s, v), u.shape).ravel()
    Kp = np.broadcast_to(scaled_K(u + s, v), u.shape).ravel()
    Qa = np.full(Km.size, Q)
    lt = _log_T(rough, log_w, np.concatenate([Qa, Qa]), np.concatenate([Km, Kp]))
    lt_m, lt_p = lt[: Km.size], lt[Km.size :]
    # intermediate-wave shadowing: a = cotθ_r/(√2 s) with cotθ_r = q/r, slope along its azimuth
    sx, sy = slope
    s2 = (sx * (c * cp - sn * sp)) ** 2 + (sy * (sn * cp + c * sp)) ** 2
    with np.errstate(divide="ignore"):
        a = np.where(r > 0, q / (np.maximum(r, 1e-300) * np.sqrt(2.0 * s2)), np.inf)
    sha = 1.0 / (1.0 + smith_lambda(np.minimum(a, 1e300)))
    # each sum is Σ Qⁿ/n! Ŵₙ = 2π (kℓx)(kℓy) Q e^Q T(Q, K); with e^{−2Q}/(8π) and the
    # quadrants: (2π kℓx kℓy)² Q² T− T+ · quadrants/(8π)
    norm = (2.0 * math.pi * k * rough.length * k * rough.length_y * Q) ** 2 * quadrants
    norm /= 8.0 * math.pi
    jac = (wt[:, None] * r * q) * wp[None, :]  # r dr = sin t cos t dt
    weight = norm * jac * sha * np.exp(lt_m + lt_p).reshape(u.shape)
    return r, q, u * v, weight


def backscatter_hv(rough, eps, k: float, theta_i, phi_i=0.0, *, slope, order: int = 8):
    """Multiple-scattering ``σ⁰_hv = σ⁰_vh`` in backscatter [-], shape of ``theta_i``.

    ``eps`` scalar (complex, ``Im ≥ 0``) or ``"pec"``; ``slope = (s_x, s_y)`` the nominal
    per-direction rms slopes; ``order`` Gauss–Legendre nodes per panel."""
    th = np.asarray(theta_i, dtype=float)
    ph = np.broadcast_to(np.asarray(phi_i, dtype=float), th.shape)
    out = np.zeros(th.shape)
    pec = is_pec(eps)
    flat_t, flat_p = th.ravel(), ph.ravel()
    pairs, inv = np.unique(np.stack([flat_t, np.mod(flat_p, 2 * math.pi)], 1), axis=0,
                           return_inverse=True)  # fmt: skip
    vals = np.zeros(len(pairs))
    slope = (float(slope[0]), float(slope[1]))
    for i, (t, p) in enumerate(pairs):
        if t <= 0.0 or t >= 0.5 * math.pi:
            continue  # sinθ = 0: u v-symmetry gives 0; grazing: cosθ → 0 kills Q
        pk = 0.0 if rough.is_isotropic else float(p)
        r, q, uv, weight = _spectral_part(rough, float(k), float(t), pk, slope, int(order))
        cs = math.cos(t)
        rh, rv = fresnel_cos(eps, cs)
        R = 0.5 * (rv - rh)
        a = (1.0 + R) / q
        b = (1.0 - R) / q
        if pec:
            f = 4.0 * a
        else:
            qt = np.sqrt((eps - r * r).astype(complex))
            qt = np.where(qt.imag < 0, -qt, qt)
            c = (1.0 + R) / qt
            d = (1.0 - R) / qt
            f = (b - c) * (1 - 3 * R) - (b - c / eps) * (1 + R)
            f = f + (a - d) * (1 + 3 * R) - (a - d * eps) * (1 - R)
        F2 = np.abs(f * uv / cs) ** 2
        a_s = cs / (math.sin(t) * math.sqrt(2.0 * _slope2(slope, p)))
        shadow = 1.0 / (1.0 + float(smith_lambda(np.array(a_s))))
        vals[i] = shadow * float(np.sum(F2 * weight))
    out.ravel()[:] = vals[inv.ravel()]
    return out


def _slope2(slope, phi):
    sx, sy = slope
    return (sx * math.cos(phi)) ** 2 + (sy * math.sin(phi)) ** 2
