"""The compiled single-scattering amplitudes of the IEM (:func:`emscatter.solvers.iem.amplitudes.
_amplitudes`, the numpy reference): per geometry, the Fresnel coefficients at θi and at the
local specular angle, the vector and scalar Kirchhoff coefficients, the eight complementary
terms (Chen et al., IEEE TGRS 41, 90, 2003, appendix B–C; :mod:`emscatter.solvers.iem.terms`),
their merge into the series components and the first-order defect to SPM1 — one loop over
geometries in scalar arithmetic instead of ~300 numpy operations on the chunk (the fixed cost
of a call, ~1 ms, and most of the per-direction cost beyond the series).

Same formulas in the same order of operations, numpy's complex division, numpy's complex square
roots (computed by the caller), no fused multiply-add: the amplitudes agree with the numpy
path to ≤ 1e-13 of each geometry's largest (``tests/test_iem_bistatic_speed.py``). Where
complementary coefficients cancel (specular, in-plane geometries) numpy's vectorized complex
products leave a residue ~1e-17 of the operands where scalar arithmetic (numpy's own scalars
too) gives an exact 0; the series counts the non-zero components in its tail bound, so there
its stop can move by one tail test: σ⁰ then differs within the series' ``rtol`` (measured
≤ 3.6e-9 at rtol 1e-8, in ≲ 1 % of random geometries), ≤ 1e-12 relative elsewhere. The
transition factors γ are inputs (:func:`emscatter.solvers.iem.amplitudes._transition`).
Only :mod:`emscatter.solvers.iem.amplitudes` imports this module, on first use."""

from __future__ import annotations

import math

import numba
import numpy as np

from emscatter.kernels._runtime import jit
from emscatter.solvers.iem import terms as kern

# no fused multiply-add (``fastmath`` off): products rounded one by one, as numpy rounds them
reduced_i = jit(kern._reduced_i, fastmath=False)
reduced_s = jit(kern._reduced_s, fastmath=False)


def inline(fn):
    """A helper inlined into its callers, without fused multiply-add."""
    return numba.njit(inline="always", error_model="numpy")(fn)


@inline
def cdiv(a, b):
    """``a / b`` for complex ``a``, ``b`` as numpy divides (Smith's method with the reciprocal
    of the scaled denominator; ``b = 0`` gives inf/nan, no exception)."""
    ar, ai, br, bi = a.real, a.imag, b.real, b.imag
    abr, abi = abs(br), abs(bi)
    if abr >= abi:
        if abr == 0.0 and abi == 0.0:
            return complex(ar / abr, ai / abi)
        rat = bi / br
        scl = 1.0 / (br + bi * rat)
        return complex((ar + ai * rat) * scl, (ai - ar * rat) * scl)
    rat = br / bi
    scl = 1.0 / (bi + br * rat)
    return complex((ar * rat + ai) * scl, (ai * rat - ar) * scl)


@inline
def combine(C, B, R, Rx, qfix, eps, lower):
    """:func:`emscatter.solvers.iem.terms._combine` (co- and cross-pol) for one geometry, with
    numpy's complex division."""
    c1, c2, c3, c4, c5 = C
    b1, b2, b3, b4, b5, b6 = B
    rh, rv = R
    qf = qfix + 0j
    rp, rm = 1 + rh, 1 - rh
    a, b = cdiv(rp, qf), cdiv(rm, qf)
    if lower:
        hh = a * (-rp * c1 * eps + rm * c2 + rp * c3) + b * (rm * c4 + rp * c5)
    else:
        hh = -(b * (-rp * c1 + rm * c2 + rp * c3) + a * (rm * c4 + rp * c5))
    rp, rm = 1 + Rx, 1 - Rx
    a, b = cdiv(rp, qf), cdiv(rm, qf)
    if lower:
        hv = a * (-rp * b1 + rm * b2 + rp * cdiv(b3 + 0j, eps)) - b * (
            rm * b4 * eps + rp * b5 + rm * b6
        )
        vh = -a * (rp * b4 + rm * b5 + rp * cdiv(b6 + 0j, eps)) + b * (
            -rm * b1 * eps + rp * b2 + rm * b3
        )
    else:
        hv = b * (rp * b1 - rm * b2 - rp * b3) + a * (rm * b4 + rp * b5 + rm * b6)
        vh = b * (rp * b4 + rm * b5 + rp * b6) - a * (-rm * b1 + rp * b2 + rm * b3)
    rp, rm = 1 + rv, 1 - rv
    a, b = cdiv(rp, qf), cdiv(rm, qf)
    if lower:
        vv = a * (rp * c1 - rm * c2 - rp * cdiv(c3 + 0j, eps)) - b * (rm * c4 * eps + rp * c5)
    else:
        vv = b * (-rp * c1 + rm * c2 + rp * c3) + a * (rm * c4 + rp * c5)
    return hh, hv, vh, vv


#: complementary-phase codes (``opt.complementary``)
PHASES = {"aiem": 0, "aiem-upper": 1, "aiem-faded": 2, "fung92": 3}
_SPM_SIGN = (-1.0, 1.0, -1.0, 1.0)


@inline
def _fresnel(eps, c, root, pec):
    """:func:`emscatter.fresnel.fresnel_cos` for one geometry, ``root = √(ε − sin²θ)`` given
    (numpy's complex square root, computed by the caller: the square roots decide which
    cancelling coefficients are exact zeros, and with them the series' stopping point)."""
    if pec:
        return -1.0 + 0j, 1.0 + 0j
    c = min(max(c, 0.0), 1.0)
    den_h, den_v = c + root, eps * c + root
    rh = 0j if den_h == 0 else cdiv(c - root, den_h)
    rv = 0j if den_v == 0 else cdiv(eps * c - root, den_v)
    return rh, rv


@inline
def _kirchhoff_vector(si, cs, ss, css, sf, cf, rh, rv):
    """:func:`emscatter.solvers.iem.terms.kirchhoff_vector` for one geometry."""
    den = css + cs
    zx = si - ss * cf
    zy = -ss * sf
    a = cs * den + si * zx
    hsnv = -(cs * cf * den + si * (zx * cf + zy * sf))
    vsnh = css * cf * den - zx * ss
    hsnh = -sf * den
    vsnv = zy * cs * ss + css * (zy * cf * si - a * sf)
    t = cs * zx - si * den
    d2 = t * t + zy * zy
    n_t = -sf * t * den + cf * a * zy + si * sf * zy * zy
    n_d = -a * (si * ss * zy - css * (si * sf * den - cs * sf * zx + cs * cf * zy))
    n_hd = -a * (-cf * si * den + cs * cf * zx + cs * sf * zy)
    n_vt = t * (cf * css * den - ss * zx) + css * sf * a * zy - (cf * css * si + cs * ss) * zy * zy
    g = zy / d2 if d2 > 1e-300 else 0.0
    mix = rh + rv
    co = (n_t + n_d) * g * mix
    cr = (n_hd - n_vt) * g * mix
    fhh = (1 - rh) * hsnv + (1 + rh) * vsnh - co
    fvv = -((1 - rv) * hsnv + (1 + rv) * vsnh) + co
    fhv = -(1 + rv) * hsnh + (1 - rv) * vsnv + cr
    fvh = -(1 + rh) * hsnh + (1 - rh) * vsnv + cr
    return fhh, fhv, fvh, fvv


@inline
def _f_spm(eps, pec, ci, si, cs, ss, cphi, sphi, ri, rs):
    """:func:`emscatter.solvers.spm.first_order._f_factors` for one geometry (``ri, rs`` the
    roots ``√(ε − sin²θ)``)."""
    if pec:
        return (ci * cs * cphi + 0j, cs * sphi + 0j, ci * sphi + 0j, si * ss - cphi + 0j)
    em1 = eps - 1.0
    dhi, dhs = ci + ri, cs + rs
    dvi, dvs = eps * ci + ri, eps * cs + rs
    cc = ci * cs
    fhh = cdiv(em1 * cc * cphi, dhi * dhs)
    fvv = cdiv(em1 * cc * (eps * si * ss - ri * rs * cphi), dvi * dvs)
    fhv = cdiv(em1 * cc * ri * sphi, dvi * dhs)
    fvh = cdiv(em1 * cc * rs * sphi, dhi * dvs)
    return fhh, fhv, fvh, fvv


@inline
def _put(la, ph, lx, sx, r, j, amp, x, e):
    """Component j of row r: ``log|a| + E``, the unit phase, ``log|x|`` and its sign."""
    for p in range(4):
        a = amp[p]
        mag = abs(a)
        la[p, r, j] = (math.log(mag) if mag > 0 else -np.inf) + e
        ph[p, r, j] = cdiv(a, mag + 0j) if mag > 0 else 1.0 + 0j
    ax = abs(x)
    lx[r, j] = math.log(ax) if ax > 0 else -np.inf
    sx[r, j] = -1.0 if x < 0 else 1.0


@jit(fastmath=False)
def amplitudes_kernel(si, cs, ss, css, sf, cf, eps, pec, g_h, g_v, ks2, phase, spm, roots, la,
                      lx, ph, sx, d):  # fmt: skip
    """Fill ``la, ph`` (4, n, J), ``lx, sx`` (n, J), ``d`` (4, n) (see the module docstring;
    ``phase`` a :data:`PHASES` code, ``spm`` the first-order defect, ``g_h, g_v`` the
    transition factors, zeros for ``R(θi)``; ``roots`` (5, n): cos θ_l and the roots
    ``√(ε − sin²θ)`` at θi, θ_l (Fresnel: ``1 − cos²θ``), θi and θs (``sin²θ``), from numpy)."""
    n = si.shape[0]
    fade_on = phase == 2 and not pec
    for r in range(n):
        s_i, c_i, s_s, c_s, s_f, c_f = si[r], cs[r], ss[r], css[r], sf[r], cf[r]
        e = eps[r]
        cos_l = roots[0, r].real
        rh_i, rv_i = _fresnel(e, c_i, roots[1, r], pec)
        rh_l, rv_l = _fresnel(e, cos_l, roots[2, r], pec)
        gh, gv = g_h[r], g_v[r]
        rh_t, rv_t = rh_i + (rh_l - rh_i) * gh, rv_i + (rv_l - rv_i) * gv
        kv = _kirchhoff_vector(s_i, c_i, s_s, c_s, s_f, c_f, rh_l, rv_l)
        g2 = 2.0 * (s_i * s_s - (1.0 + c_i * c_s) * c_f)
        a0 = [kv[0] + (-(rh_t - rh_l) * g2), kv[1], kv[2], kv[3] + (rv_t - rv_l) * g2]
        comp = [0j, 0j, 0j, 0j]
        ee = 1.0 if pec else e
        R = (rh_i, rv_i)
        Rx = 0.5 * (rv_i - rh_i)
        fade = 1.0 - gv
        base = -0.5 * ks2 * (c_i * c_i + c_s * c_s)
        j = 1
        # upper-medium terms: up_i, dn_i, up_s, dn_s
        for t in range(4):
            side_i = t < 2
            q = (c_i if t == 0 else -c_i) if side_i else (c_s if t == 2 else -c_s)
            qph = 0.0 * q if phase == 3 else q
            alpha = c_s - qph if side_i else c_i + qph
            if side_i:
                C, B = reduced_i(s_i, c_i, s_s, c_s, s_f, c_f, q, alpha)
                F = combine(C, B, R, Rx, c_i, ee, False)
            else:
                C, B = reduced_s(s_i, c_i, s_s, c_s, s_f, c_f, q, alpha)
                F = combine(C, B, R, Rx, c_s, ee, False)
            for p in range(4):
                comp[p] = comp[p] + 0.25 * F[p]
            if phase != 3 and (t == 1 or t == 2):  # dn_i, up_s: merged into component 0
                for p in range(4):
                    a0[p] = a0[p] + 0.25 * F[p]
                continue
            amp = (0.25 * F[0], 0.25 * F[1], 0.25 * F[2], 0.25 * F[3])
            x = (c_s - qph) if side_i else (c_i + qph)
            _put(la, ph, lx, sx, r, j, amp, x, -ks2 * (qph * qph - qph * (c_s - c_i)) + base)
            j += 1
        if not pec:
            q2i, q2s = roots[3, r], roots[4, r]
            for t in range(4):
                side_i = t < 2
                q = (q2i if t == 0 else -q2i) if side_i else (q2s if t == 2 else -q2s)
                qup = (c_i if t == 0 else -c_i) if side_i else (c_s if t == 2 else -c_s)
                if phase == 0:
                    qph = q.real
                elif phase == 1 or phase == 2:
                    qph = qup + 0.0 * q.real
                else:
                    qph = 0.0 * q.real
                alpha = c_s - qph if side_i else c_i + qph
                if side_i:
                    C, B = reduced_i(s_i, c_i, s_s, c_s, s_f, c_f, q, alpha)
                    F = combine(C, B, R, Rx, q2i, ee, True)
                else:
                    C, B = reduced_s(s_i, c_i, s_s, c_s, s_f, c_f, q, alpha)
                    F = combine(C, B, R, Rx, q2s, ee, True)
                for p in range(4):
                    comp[p] = comp[p] + 0.25 * F[p]
                w = 0.25 * fade if fade_on else 0.25
                amp = (w * F[0], w * F[1], w * F[2], w * F[3])
                x = (c_s - qph) if side_i else (c_i + qph)
                _put(la, ph, lx, sx, r, j, amp, x, -ks2 * (qph * qph - qph * (c_s - c_i)) + base)
                j += 1
        _put(la, ph, lx, sx, r, 0, (a0[0], a0[1], a0[2], a0[3]), c_i + c_s,
             -ks2 * c_i * c_s + base)  # fmt: skip
        if spm:
            f = _f_spm(e, pec, c_i, s_i, c_s, s_s, c_f, s_f, roots[3, r], roots[4, r])
            x0 = (kv[0] + (-(rh_i - rh_l) * g2), kv[1], kv[2], kv[3] + (rv_i - rv_l) * g2)
            eb = math.exp(base)
            for p in range(4):
                d[p, r] = (4.0 * _SPM_SIGN[p] * f[p] - (x0[p] + comp[p])) * eb
        else:
            for p in range(4):
                d[p, r] = 0j
