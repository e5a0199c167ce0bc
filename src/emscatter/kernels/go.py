"""Compiled geometric-optics (Kirchhoff, stationary phase) σ⁰ with Smith shadowing.

The arithmetic of the numpy reference — :class:`emscatter.solvers.kirchhoff_common.Geometry`
``.chunk``, :func:`~emscatter.solvers.kirchhoff_go.slope_pdf_factor`,
:func:`~emscatter.solvers.kirchhoff_common.shadowing_factor` and
:func:`~emscatter.solvers.kirchhoff_common.fresnel_factors` (equations and sources there:
Tsang, Kong & Ding 2001 vol. III ch. 2; Ulaby, Moore & Fung 1982 vol. II §12-4; Smith 1967)
— fused into one loop per geometry. Covered: 2-D surfaces with isotropic slopes
(``⟨ζx²⟩ = ⟨ζy²⟩``), one permittivity or PEC, shadowing off / ``"smith"`` (monostatic at
exact backscatter) / ``"separable"`` / ``"correlated"``.
With isotropic slopes σ⁰ depends on ``φs − φi`` only, so the rotation by ``φi`` that the
numpy path applies to ``q`` is skipped (rounding-level difference).

Smith's ``Λ(a) = [e^{−a²}/(a√π) − erfc(a)]/2`` is evaluated as
``e^{−a²} [1/(a√π) − erfcx(a)]/2`` with :func:`._vmath.verfcx`.
"""

from __future__ import annotations

import math

import numpy as np

from ._runtime import inline, jit, run_fused
from ._vmath import vcos, verfcx_parts, vexp, vsin

NO_SHADOWING, SEPARABLE, CORRELATED, SMITH, DIRECTIONAL = 0, 1, 2, 3, 4
#: kirchhoff_common.check_shadowing's modes: "smith" is the separable product except in the
#: exact backscatter direction (|q|² > 4(1 − 1e-12)), where the monostatic 1/(1 + Λi) applies;
#: "direction-correlated" is 1/(1 + max Λ + λ(ψ) min Λ), ψ = arccos(−cos Δφ)
SHADOWING_CODES = {
    None: NO_SHADOWING,
    "separable": SEPARABLE,
    "correlated": CORRELATED,
    "smith": SMITH,
    "direction-correlated": DIRECTIONAL,
}
_SQRT_PI = math.sqrt(math.pi)
_TAU_EPS = 1e-28  # as kirchhoff_common._TAU_EPS


@inline
def _smith_lambda(a):
    """Λ(a), 0 for a ≥ 6 (as kirchhoff_common.smith_lambda); branch-free, one division:
    ``Λ = e^{−a²} [1/(a√π) − p/d] / 2 = e^{−a²} (d − a√π p) / (2 a√π d)``."""
    an = min(max(a, 1e-300), 6.0)
    e = vexp(-an * an)
    p, d = verfcx_parts(an)
    w = an * _SQRT_PI
    lam = max(0.5 * e * (d - w * p) / (w * d), 0.0)
    return lam if a < 6.0 else 0.0


@inline
def _shadow_a(c, s, s2):
    den = s * math.sqrt(2.0 * s2)
    return c / (den if den > 0 else 1.0) if den > c * 1e-300 else 1e300


@inline
def _fast_fresnel(pec, er, ei, c):
    """(|R_h|², |R_v|², Re(R_h R_v*)) as kirchhoff_common.fast_fresnel."""
    if pec:
        return 1.0, 1.0, -1.0
    a = er - (1.0 - c * c)
    b = ei + 0.0 * c
    big = math.sqrt(0.5 * (math.sqrt(a * a + b * b) + abs(a)))
    small = 0.5 * b / max(big, 1e-300)
    u = big if a >= 0 else small
    v = small if a >= 0 else big
    hn_r = c - u
    hd_r = c + u
    ec_r = er * c
    ec_i = ei * c
    vn_r = ec_r - u
    vn_i = ec_i - v
    vd_r = ec_r + u
    vd_i = ec_i + v
    v2 = v * v
    hd2 = max(hd_r * hd_r + v2, 1e-300)
    vd2 = max(vd_r * vd_r + vd_i * vd_i, 1e-300)
    inv = 1.0 / (hd2 * vd2)  # one division for the three ratios (the reference divides 3×)
    rh2 = (hn_r * hn_r + v2) * vd2 * inv
    rv2 = (vn_r * vn_r + vn_i * vn_i) * hd2 * inv
    h_r = hn_r * hd_r - v2
    h_i = -v * (hd_r + hn_r)
    w_r = vn_r * vd_r + vn_i * vd_i
    w_i = vn_i * vd_r - vn_r * vd_i
    return rh2, rv2, (h_r * w_r + h_i * w_i) * inv


@jit
def _go_kernel(ti, ts, dphi, pec, er, ei, s2, shadowing, two_k_sigma, hh, hv, vh, vv, ch, cv):
    """σ⁰ [-] into the four 1-D outputs; coherent ``|R_p|² e^{−(2kσ cosθi)²}`` into ch, cv
    when ``two_k_sigma`` (= 2kσ) ≥ 0."""
    pref = 0.5 / math.sqrt(s2 * s2)  # π · 1/(2π√(sx sy))
    inv_s2 = 1.0 / s2
    for j in range(ti.size):
        si = vsin(ti[j])
        ci = math.sqrt((1.0 - si) * (1.0 + si))
        ss = vsin(ts[j])
        cs = math.sqrt((1.0 - ss) * (1.0 + ss))
        cd = vcos(dphi[j])
        sd = math.sqrt(max((1.0 - cd) * (1.0 + cd), 0.0))
        qx = ss * cd - si
        qy = ss * sd
        qz = cs + ci
        q2 = max(2.0 * (1.0 + ci * cs - si * ss * cd), 0.0)
        cos_l = min(0.5 * math.sqrt(q2), 1.0)
        # slope_pdf_factor (2-D)
        ok = qz > 0
        inv = 1.0 / (qz if ok else 1.0)
        zx = qx * inv
        zy = qy * inv
        expo = -0.5 * (zx * zx * inv_s2 + zy * zy * inv_s2)
        r = q2 * inv * inv
        val = pref * r * r * vexp(expo) if ok else 0.0
        if shadowing != 0:
            lam_i = _smith_lambda(_shadow_a(ci, si, s2))
            lam_s = _smith_lambda(_shadow_a(cs, ss, s2))
            if shadowing == DIRECTIONAL:
                psi = math.acos(min(max(-cd, -1.0), 1.0))
                corr = 4.41 * psi / (4.41 * psi + 1.0)
                val = val / (1.0 + max(lam_i, lam_s) + corr * min(lam_i, lam_s))
            elif shadowing == CORRELATED:
                val = val * (1.0 / (1.0 + lam_i + lam_s))
            elif shadowing == SMITH and q2 > 4.0 * (1.0 - 1e-12):
                val = val * (1.0 / (1.0 + lam_i))
            else:
                val = val * (1.0 / ((1.0 + lam_i) * (1.0 + lam_s)))
        # fresnel_factors (2-D)
        rh2, rv2, cross = _fast_fresnel(pec, er, ei, cos_l)
        a_h = rh2 * val
        a_v = rv2 * val
        a_x = cross * val
        hi = ci * ss * cd + si * cs
        vi = ss * sd
        hs = si * cs * cd + ci * ss
        vs = si * sd
        d = hi * hi + vi * vi
        if d < _TAU_EPS:  # exact backscatter: t̂ = ĥ_i
            hi, vi, hs, vs, d = 1.0, 0.0, -1.0, 0.0, 1.0
        inv4 = 1.0 / (d * d)
        ah = a_h * inv4
        av = a_v * inv4
        cr = 2.0 * a_x * inv4
        p = hs * hi
        m = vs * vi
        x = hs * vi
        y = vs * hi
        hh[j] = max(ah * p * p + av * m * m + cr * p * m, 0.0)
        vv[j] = max(ah * m * m + av * p * p + cr * p * m, 0.0)
        hv[j] = max(ah * x * x + av * y * y - cr * x * y, 0.0)
        vh[j] = max(ah * y * y + av * x * x - cr * x * y, 0.0)
        if two_k_sigma >= 0:
            ch2, cv2, _ = _fast_fresnel(pec, er, ei, ci)
            t = two_k_sigma * ci
            att = vexp(-(t * t))
            ch[j] = ch2 * att
            cv[j] = cv2 * att


def go_sigma0(
    ti: np.ndarray,
    ts: np.ndarray,
    dphi: np.ndarray,
    eps,
    *,
    slope_variance: float,
    shadowing: str | None,
    out: np.ndarray,
    coherent_out: np.ndarray | None = None,
    k: float = 1.0,
    sigma: float = 0.0,
    threads: int | None = None,
) -> np.ndarray:
    """GO σ⁰ (2-D surface, isotropic per-direction slope variance ``slope_variance`` [-]) into
    ``out`` (2, 2, n) [-]; the Kirchhoff coherent reflectivity into ``coherent_out`` (2, n)
    when given (``k`` [rad/m], ``sigma`` [m]). Angles [rad]: flat float64 arrays,
    ``|dphi| ≤ 1e6``."""
    pec = isinstance(eps, str)
    e = 0j if pec else complex(eps)
    code = SHADOWING_CODES[shadowing]
    two_ks = 2.0 * k * sigma if coherent_out is not None else -1.0

    n = ti.size
    if coherent_out is not None:
        coh = (coherent_out[0], coherent_out[1])
    else:  # not written; full-length scratch so the vectorized loop's overlap check passes
        coh = (np.empty(n), np.empty(n))
    consts = (pec, e.real, e.imag, float(slope_variance), code, two_ks)
    outs = (out[0, 0], out[0, 1], out[1, 0], out[1, 1], *coh)
    run_fused(_go_kernel, (ti, ts, dphi), consts, outs, threads)
    return out
