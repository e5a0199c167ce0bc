"""Compiled geometric-optics (Kirchhoff, stationary phase) σ⁰ with Smith shadowing.

The arithmetic of the numpy reference — :class:`emscatter.solvers.kirchhoff.common.Geometry`
``.chunk``, :func:`~emscatter.solvers.kirchhoff.go.slope_pdf_factor`,
:func:`~emscatter.solvers.kirchhoff.common.shadowing_factor` and
:func:`~emscatter.solvers.kirchhoff.common.fresnel_factors` (equations and sources there:
Tsang, Kong & Ding 2001 vol. III ch. 2; Ulaby, Moore & Fung 1982 vol. II §12-4; Smith 1967)
— fused into one loop per geometry. Covered: 2-D surfaces with isotropic slopes
(``⟨ζx²⟩ = ⟨ζy²⟩``), one permittivity or PEC, shadowing off / ``"smith"`` (monostatic at
exact backscatter) / ``"separable"`` / ``"correlated"``.
With isotropic slopes σ⁰ depends on ``φs − φi`` only, so the rotation by ``φi`` that the
numpy path applies to ``q`` is skipped (rounding-level difference).

What makes it fast (each a rounding-level change, checked against numpy in
tests/test_kernels.py):

* **One loop per case.** PEC / dielectric and shadowed / unshadowed are separate compiled
  loops (an inlined core with the case as a constant), so a PEC loop carries no Fresnel code
  and an unshadowed one no Smith function; the coherent part is its own loop over ``θi``, run
  only when asked for. (A loop-invariant ``if`` inside one loop is not unswitched by LLVM at
  this body size: both sides were computed.)
* **Only ``sin²Δφ``.** The polarization factors and the slope density use ``sin Δφ`` only
  squared (``x y = p m`` below), so no square root is taken for it.
* **Smith's Λ as a fraction.** ``Λ(a) = [e^{−a²}/(a√π) − erfc(a)]/2 = N/D`` with
  ``N = e^{−a²}(d Qⁿ − a√π H)``, ``D = 2a√π d Qⁿ``, ``d = 1 + 2a``, where
  ``(1 + 2a) erfcx(a) ≈ H/Qⁿ``: a degree-13 polynomial in ``t = (a − 3)/(a + 3)`` evaluated
  in homogeneous form, ``H = Σ c_k (a−3)^k (a+3)^{13−k}``, ``Q = a + 3`` (Estrin's scheme:
  short dependency chains, no division for ``t``). The shadowing factor of both directions —
  separable ``D_i D_s/((D_i+N_i)(D_s+N_s))``, correlated ``D_i D_s/(D_i D_s + N_i D_s +
  N_s D_i)``, monostatic ``D_i/(D_i + N_i)`` — then costs one division, where the reference
  divides five times. The polynomial is fitted (:data:`SMITH_COEF`, weighted least squares
  on ``a ∈ [0, 6]``) to the accuracy the shadowing factor needs, not to ``erfcx``'s own:
  ``|ΔΛ| ≤ 2e-14 (1 + Λ)`` — ``erfcx``'s relative error enters ``Λ`` multiplied by
  ``erfc(a)``, so the bound is tight where ``a`` is small and loose where ``erfc`` is tiny
  (a 20-term series for ``erfcx`` alone before). ``Λ = 0`` for ``a ≥ 6`` (as the reference).
"""

from __future__ import annotations

import math

import numpy as np

from emscatter.kernels._runtime import _MIN_CHUNK, inline, jit, run_chunked, run_fused
from emscatter.kernels._vmath import INV_LN2, LN2_HI, LN2_LO, vcos, vexp, vsin_q1

NO_SHADOWING, SEPARABLE, CORRELATED, SMITH, DIRECTIONAL = 0, 1, 2, 3, 4
#: kirchhoff_common.check_shadowing's modes: "smith" is the separable product except in the
#: exact backscatter direction (|q|² > 4(1 − 1e-12)), where the monostatic 1/(1 + Λi) applies;
#: "direction-correlated" (accuracy's default, Ginneken et al. 1998 / Heitz 2014 §6) is
#: 1/(1 + max Λ + λ(ψ) min Λ), λ(ψ) = 4.41ψ/(4.41ψ + 1), ψ = arccos(−cos Δφ) — λ from numpy
#: (:func:`directional_weight`, as the numpy reference computes it) and passed in per geometry
SHADOWING_CODES = {
    None: NO_SHADOWING,
    "separable": SEPARABLE,
    "correlated": CORRELATED,
    "smith": SMITH,
    "direction-correlated": DIRECTIONAL,
}
_SQRT_PI = math.sqrt(math.pi)
_TAU_EPS = 1e-28  # as kirchhoff_common._TAU_EPS

#: ``(1 + 2a) erfcx(a) ≈ Σ_k SMITH_COEF[k] t^k``, ``t = (a − SMITH_K)/(a + SMITH_K)``, on
#: ``0 ≤ a ≤ SMITH_A_MAX``; fitted by iteratively reweighted Chebyshev least squares (4000
#: Chebyshev nodes, weight 1/tolerance, tolerance the relative error of ``erfcx`` that keeps
#: ``|ΔΛ| ≤ 2e-14 (1 + Λ)``, i.e. ``2e-14 (1 + Λ)/erfc(a)``), then expanded in powers of t
#: (well conditioned: Σ|c_k| = 1.78). Reached: 0.07 of that tolerance (tests/test_kernels.py
#: checks the bound against scipy on a fine grid).
SMITH_K = 3.0
SMITH_A_MAX = 6.0
SMITH_COEF = (
    1.2530080582500078, -0.13562110685515139, -0.04756230438630461, 0.12964509291713613,
    -0.11927383544821415, 0.06830851010831562, -0.023764500749538696, 0.002555528986079152,
    0.0019589413829854633, -0.0006499881073466499, 6.468321519334276e-05,
    0.0002808909002765413, 9.983914240071576e-05, 1.1953457245548298e-05,
)  # fmt: skip
_C0, _C1, _C2, _C3, _C4, _C5, _C6, _C7, _C8, _C9, _C10, _C11, _C12, _C13 = SMITH_COEF


_E = [1.0 / math.factorial(j) for j in range(12)]
_E0, _E1, _E2, _E3, _E4, _E5, _E6, _E7, _E8, _E9, _E10, _E11 = _E
_LN2_HI, _LN2_LO, _INV_LN2 = LN2_HI, LN2_LO, INV_LN2


@inline
def _exp_neg(x):
    """``e^x`` for ``−40 ≤ x ≤ 0`` (the ``e^{−a²}`` of :func:`_lambda_parts`, ``a ≤ 6``):
    :func:`._vmath.vexp`'s reduction with the Taylor series to ``r¹¹`` (relative error
    < 7e-15, inside Λ's budget) and no range clamps; Estrin's scheme."""
    n = math.floor(x * _INV_LN2 + 0.5)
    r = (x - n * _LN2_HI) - n * _LN2_LO
    r2 = r * r
    r4 = r2 * r2
    p01 = _E0 + _E1 * r
    p23 = _E2 + _E3 * r
    p45 = _E4 + _E5 * r
    p67 = _E6 + _E7 * r
    p89 = _E8 + _E9 * r
    pab = _E10 + _E11 * r
    lo = (p01 + p23 * r2) + r4 * (p45 + p67 * r2)
    hi = p89 + pab * r2
    p = lo + (r4 * r4) * hi
    return p * np.int64((int(n) + 1023) << 52).view(np.float64)


@inline
def _lambda_parts(a):
    """``(N, D)`` with Smith's ``Λ(a) = N/D`` (module docstring), ``D > 0``; ``N = 0`` for
    ``a ≥ 6`` (the reference's ``Λ = 0`` there)."""
    an = min(max(a, 1e-300), SMITH_A_MAX)
    e = _exp_neg(-an * an)
    p = an - SMITH_K
    q = an + SMITH_K
    # H = Σ_k c_k p^k q^(13−k) (Estrin: pairs, then pairs of pairs)
    b0 = _C0 * q + _C1 * p
    b1 = _C2 * q + _C3 * p
    b2 = _C4 * q + _C5 * p
    b3 = _C6 * q + _C7 * p
    b4 = _C8 * q + _C9 * p
    b5 = _C10 * q + _C11 * p
    b6 = _C12 * q + _C13 * p
    p2 = p * p
    q2 = q * q
    c0 = b0 * q2 + b1 * p2
    c1 = b2 * q2 + b3 * p2
    c2 = b4 * q2 + b5 * p2
    p4 = p2 * p2
    q4 = q2 * q2
    d0 = c0 * q4 + c1 * p4
    p8 = p4 * p4
    h = q2 * (d0 * q4 + c2 * p8) + b6 * (p4 * p8)
    qn = q * q4 * (q4 * q4)  # q^13
    w = an * _SQRT_PI
    d = 1.0 + 2.0 * an
    num = max(e * (d * qn - w * h), 0.0)
    if a >= SMITH_A_MAX:
        num = 0.0
    return num, 2.0 * w * d * qn


@inline
def _smith_lambda(a):
    """Λ(a) (as kirchhoff_common.smith_lambda, 0 for a ≥ 6)."""
    num, den = _lambda_parts(a)
    return num / den


@inline
def _shadow_a(c, s, kappa):
    """``a = cotθ/(√2 s)`` with ``kappa = √(2 s²)`` (as kirchhoff_common._a)."""
    den = s * kappa
    return c / (den if den > 0 else 1.0) if den > c * 1e-300 else 1e300


@inline
def _shadow_pair(ci, si, cs, ss, kappa):
    """``(a_i, a_s)`` of :func:`_shadow_a` with one division: ``sinθ`` is floored at 1e-100
    (``a`` is then ≥ 1e99: ``Λ = 0``, as the reference's ``a = 1e300`` for ``sinθ → 0``)."""
    sic = max(si, 1e-100) * kappa
    ssc = max(ss, 1e-100) * kappa
    r = 1.0 / (sic * ssc)
    return ci * (ssc * r), cs * (sic * r)


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


@inline
def _go_point(si, ci, ss, cs, cd, sd2, ni, di, ns, ds, corr, er, ei, pref, inv_s2, shadowing,
              pec, shadowed):  # fmt: skip
    """σ⁰ ``(hh, hv, vh, vv)`` [-] of one geometry from its trigonometry (``sd2 = sin²Δφ``),
    the Smith parts ``Λ = N/D`` of both directions (unused unless ``shadowed``) and the
    direction-correlation weight ``corr = λ(ψ)`` (used by ``DIRECTIONAL`` only)."""
    qx = ss * cd - si
    qz = cs + ci
    q2 = max(2.0 * (1.0 + ci * cs - si * ss * cd), 0.0)
    # slope_pdf_factor (2-D)
    ok = qz > 0
    inv = 1.0 / (qz if ok else 1.0)
    zx = qx * inv
    zy2 = ss * ss * sd2 * (inv * inv)
    expo = -0.5 * (zx * zx * inv_s2 + zy2 * inv_s2)
    r = q2 * inv * inv
    val = pref * r * r * vexp(expo) if ok else 0.0
    num = 1.0
    den = 1.0
    if shadowed:  # shadowing_factor num/den: folded into the one division below
        num = di * ds
        den = (di + ni) * (ds + ns)
        if shadowing == CORRELATED:
            den = num + ni * ds + ns * di
        elif shadowing == DIRECTIONAL:  # Λi·D = ni·ds, Λs·D = ns·di with D = di·ds
            li = ni * ds
            ls = ns * di
            den = num + max(li, ls) + corr * min(li, ls)
        elif shadowing == SMITH and q2 > 4.0 * (1.0 - 1e-12):
            num = di * (ds + ns)  # monostatic 1/(1 + Λi)
    # fresnel_factors (2-D)
    if pec:
        rh2, rv2, cross = 1.0, 1.0, -1.0
    else:
        rh2, rv2, cross = _fast_fresnel(False, er, ei, min(0.5 * math.sqrt(q2), 1.0))
    hi = ci * ss * cd + si * cs
    hs = si * cs * cd + ci * ss
    vi2 = ss * ss * sd2  # (v̂_i·τ)² = sin²θs sin²Δφ
    d = hi * hi + vi2
    if d < _TAU_EPS:  # exact backscatter: t̂ = ĥ_i
        hi, hs, vi2, sd2, d = 1.0, -1.0, 0.0, 0.0, 1.0
    inv4 = (val * num) / (den * (d * d))
    ah = rh2 * inv4
    av = rv2 * inv4
    cr = 2.0 * cross * inv4
    p = hs * hi
    m = si * ss * sd2  # (v̂_s·τ)(v̂_i·τ)
    x2 = hs * hs * vi2  # ((ĥ_s·τ)(v̂_i·τ))²
    y2 = si * si * sd2 * (hi * hi)  # ((v̂_s·τ)(ĥ_i·τ))²
    pm = cr * p * m  # x·y = p·m
    hh = max(ah * p * p + av * m * m + pm, 0.0)
    vv = max(ah * m * m + av * p * p + pm, 0.0)
    hv = max(ah * x2 + av * y2 - pm, 0.0)
    vh = max(ah * y2 + av * x2 - pm, 0.0)
    return hh, hv, vh, vv


_TWO_PI = 2.0 * math.pi
_INV_TWO_PI = 1.0 / _TWO_PI


@inline
def _direction_weight(dphi):
    """``λ(ψ) = 4.41ψ/(4.41ψ + 1)`` [-] with ``ψ = arccos(−cos Δφ) = π − |Δφ mod± 2π|`` (as
    :func:`directional_weight`, without the transcendental calls: the wrap is exact to
    ``|Δφ|·2⁻⁵²``, and better conditioned than ``arccos`` near ``ψ = 0``)."""
    n = math.floor(dphi * _INV_TWO_PI + 0.5)
    psi = max(math.pi - abs(dphi - n * _TWO_PI), 0.0)
    return 4.41 * psi / (4.41 * psi + 1.0)


@inline
def _go_loop(ti, ts, dphi, er, ei, s2, shadowing, hh, hv, vh, vv, pec, shadowed):
    """σ⁰ [-] into the four 1-D outputs; ``pec`` and ``shadowed`` are constants of the
    compiled loop (see the ``_go_*`` kernels); the direction-correlation weight λ(ψ) of
    ``DIRECTIONAL`` is computed per geometry from ``dphi`` (:func:`_direction_weight`)."""
    pref = 0.5 / math.sqrt(s2 * s2)  # π · 1/(2π√(sx sy))
    inv_s2 = 1.0 / s2
    kappa = math.sqrt(2.0 * s2)
    for j in range(ti.size):
        si = vsin_q1(ti[j])
        ci = math.sqrt((1.0 - si) * (1.0 + si))
        ss = vsin_q1(ts[j])
        cs = math.sqrt((1.0 - ss) * (1.0 + ss))
        cd = vcos(dphi[j])
        sd2 = max((1.0 - cd) * (1.0 + cd), 0.0)  # sin²Δφ: sin Δφ enters squared only
        ni = di = ns = ds = 1.0
        if shadowed:
            ai, as_ = _shadow_pair(ci, si, cs, ss, kappa)
            ni, di = _lambda_parts(ai)
            ns, ds = _lambda_parts(as_)
        corr = _direction_weight(dphi[j]) if shadowing == DIRECTIONAL else 0.0
        hh[j], hv[j], vh[j], vv[j] = _go_point(
            si, ci, ss, cs, cd, sd2, ni, di, ns, ds, corr, er, ei, pref, inv_s2, shadowing,
            pec, shadowed,
        )  # fmt: skip


@jit
def _go_pec(ti, ts, dphi, er, ei, s2, shadowing, hh, hv, vh, vv):
    _go_loop(ti, ts, dphi, er, ei, s2, shadowing, hh, hv, vh, vv, True, False)


@jit
def _go_pec_shadowed(ti, ts, dphi, er, ei, s2, shadowing, hh, hv, vh, vv):
    _go_loop(ti, ts, dphi, er, ei, s2, shadowing, hh, hv, vh, vv, True, True)


@jit
def _go_dielectric(ti, ts, dphi, er, ei, s2, shadowing, hh, hv, vh, vv):
    _go_loop(ti, ts, dphi, er, ei, s2, shadowing, hh, hv, vh, vv, False, False)


@jit
def _go_dielectric_shadowed(ti, ts, dphi, er, ei, s2, shadowing, hh, hv, vh, vv):
    _go_loop(ti, ts, dphi, er, ei, s2, shadowing, hh, hv, vh, vv, False, True)


_KERNELS = {
    (True, False): _go_pec,
    (True, True): _go_pec_shadowed,
    (False, False): _go_dielectric,
    (False, True): _go_dielectric_shadowed,
}


# ----------------------------------------------------------------------------- grids
@inline
def _direction_table(theta, s2, tab):
    """Per distinct direction: ``sinθ``, ``cosθ`` and Smith's ``Λ = N/D`` into the rows of
    ``tab`` (as the fused loop, ``a = cosθ/(max(sinθ, 1e-100) √(2s²))``)."""
    kappa = math.sqrt(2.0 * s2)
    for j in range(theta.size):
        si = vsin_q1(theta[j])
        ci = math.sqrt((1.0 - si) * (1.0 + si))
        tab[0, j] = si
        tab[1, j] = ci
        sic = max(si, 1e-100) * kappa
        tab[2, j], tab[3, j] = _lambda_parts(ci * (1.0 / sic))


@jit
def _grid_tables(ti, ts, dphi, s2, ti_tab, ts_tab, d_tab):
    """The per-direction tables of :func:`go_sigma0_grid` (``d_tab``: cos Δφ, sin²Δφ; its
    third row, λ(ψ), is filled by the caller)."""
    _direction_table(ti, s2, ti_tab)
    _direction_table(ts, s2, ts_tab)
    for j in range(dphi.size):
        cd = vcos(dphi[j])
        d_tab[0, j] = cd
        d_tab[1, j] = max((1.0 - cd) * (1.0 + cd), 0.0)


_BLOCK = 256  # geometries gathered per block (the scratch rows stay in L1)


@inline
def _go_grid_loop(j0, shape, st, ti_tab, ts_tab, d_tab, er, ei, s2, shadowing, hh, hv, vh, vv,
                  pec, shadowed):  # fmt: skip
    """The fused loop over a broadcast grid (up to 3-D, C order) in blocks: each block first
    gathers its geometries' rows of the per-direction tables into contiguous scratch rows
    (position ``(a, b, c)`` counted up, table index from the element strides ``st`` (3, 3)
    of the unbroadcast θi, θs, Δφ, 0 along broadcast axes), then runs the point formula over them (a
    loop that vectorizes); ``hh``… hold the flat geometries ``j0, j0 + 1, …``."""
    pref = 0.5 / math.sqrt(s2 * s2)
    inv_s2 = 1.0 / s2
    n1 = shape[1]
    n2 = shape[2]
    a = j0 // (n1 * n2)
    rest = j0 - a * (n1 * n2)
    b = rest // n2
    c = rest - b * n2
    buf = np.empty((11, _BLOCK))
    g_si, g_ci, g_ni, g_di = buf[0], buf[1], buf[2], buf[3]
    g_ss, g_cs, g_ns, g_ds = buf[4], buf[5], buf[6], buf[7]
    g_cd, g_sd, g_w = buf[8], buf[9], buf[10]
    si_t, ci_t, ni_t, di_t = ti_tab[0], ti_tab[1], ti_tab[2], ti_tab[3]
    ss_t, cs_t, ns_t, ds_t = ts_tab[0], ts_tab[1], ts_tab[2], ts_tab[3]
    cd_t, sd_t, w_t = d_tab[0], d_tab[1], d_tab[2]
    i0, i1, i2 = st[0, 0], st[0, 1], st[0, 2]
    s0, s1, s2_ = st[1, 0], st[1, 1], st[1, 2]
    d0, d1, d2 = st[2, 0], st[2, 1], st[2, 2]
    ki = a * i0 + b * i1 + c * i2
    ks = a * s0 + b * s1 + c * s2_
    kd = a * d0 + b * d1 + c * d2
    n = hh.size
    for start in range(0, n, _BLOCK):
        m = min(_BLOCK, n - start)
        for t in range(m):  # gather (scalar: loads, and the position counted up)
            g_si[t] = si_t[ki]
            g_ci[t] = ci_t[ki]
            g_ni[t] = ni_t[ki]
            g_di[t] = di_t[ki]
            g_ss[t] = ss_t[ks]
            g_cs[t] = cs_t[ks]
            g_ns[t] = ns_t[ks]
            g_ds[t] = ds_t[ks]
            g_cd[t] = cd_t[kd]
            g_sd[t] = sd_t[kd]
            g_w[t] = w_t[kd]
            c += 1
            ki += i2
            ks += s2_
            kd += d2
            if c == n2:
                c = 0
                b += 1
                if b == n1:
                    b = 0
                    a += 1
                ki = a * i0 + b * i1
                ks = a * s0 + b * s1
                kd = a * d0 + b * d1
        o_hh = hh[start : start + m]
        o_hv = hv[start : start + m]
        o_vh = vh[start : start + m]
        o_vv = vv[start : start + m]
        for t in range(m):  # the point formula (vectorized)
            o_hh[t], o_hv[t], o_vh[t], o_vv[t] = _go_point(
                g_si[t], g_ci[t], g_ss[t], g_cs[t], g_cd[t], g_sd[t], g_ni[t], g_di[t],
                g_ns[t], g_ds[t], g_w[t], er, ei, pref, inv_s2, shadowing, pec, shadowed,
            )  # fmt: skip


@jit
def _grid_pec(j0, shape, st, ti_tab, ts_tab, d_tab, er, ei, s2, shadowing, hh, hv, vh, vv):
    _go_grid_loop(j0, shape, st, ti_tab, ts_tab, d_tab, er, ei, s2, shadowing, hh, hv, vh, vv,
                  True, False)  # fmt: skip


@jit
def _grid_pec_shadowed(j0, shape, st, ti_tab, ts_tab, d_tab, er, ei, s2, shadowing, hh, hv, vh, vv):
    _go_grid_loop(j0, shape, st, ti_tab, ts_tab, d_tab, er, ei, s2, shadowing, hh, hv, vh, vv,
                  True, True)  # fmt: skip


@jit
def _grid_dielectric(j0, shape, st, ti_tab, ts_tab, d_tab, er, ei, s2, shadowing, hh, hv, vh, vv):
    _go_grid_loop(j0, shape, st, ti_tab, ts_tab, d_tab, er, ei, s2, shadowing, hh, hv, vh, vv,
                  False, False)  # fmt: skip


@jit
def _grid_dielectric_shadowed(j0, shape, st, ti_tab, ts_tab, d_tab, er, ei, s2, shadowing,
                              hh, hv, vh, vv):  # fmt: skip
    _go_grid_loop(j0, shape, st, ti_tab, ts_tab, d_tab, er, ei, s2, shadowing, hh, hv, vh, vv,
                  False, True)  # fmt: skip


_GRID_KERNELS = {
    (True, False): _grid_pec,
    (True, True): _grid_pec_shadowed,
    (False, False): _grid_dielectric,
    (False, True): _grid_dielectric_shadowed,
}


@jit
def _coherent_kernel(ti, pec, er, ei, two_k_sigma, ch, cv):
    """Kirchhoff coherent ``|R_p(θi)|² e^{−(2kσ cosθi)²}`` (as kirchhoff_common.coherent_local)."""
    for j in range(ti.size):
        si = vsin_q1(ti[j])
        ci = math.sqrt((1.0 - si) * (1.0 + si))
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
    kernel = _KERNELS[(pec, code != NO_SHADOWING)]
    consts = (e.real, e.imag, float(slope_variance), code)
    outs = (out[0, 0], out[0, 1], out[1, 0], out[1, 1])
    run_fused(kernel, (ti, ts, dphi), consts, outs, threads)
    if coherent_out is not None:
        consts = (pec, e.real, e.imag, 2.0 * k * sigma)
        run_fused(_coherent_kernel, (ti,), consts, (coherent_out[0], coherent_out[1]), threads)
    return out


def directional_weight(dphi: np.ndarray) -> np.ndarray:
    """``λ(ψ) = 4.41ψ/(4.41ψ + 1)``, ``ψ = arccos(−cos Δφ)`` [-] for ``dphi`` = φs − φi [rad]
    (Ginneken, Stavridi & Koenderink 1998, Appl. Opt. 37, 130; in numpy, as the numpy
    reference's "direction-correlated" shadowing computes it)."""
    psi = np.arccos(np.clip(-np.cos(dphi), -1.0, 1.0))
    return 4.41 * psi / (4.41 * psi + 1.0)


def coherent_reflectivity(ti: np.ndarray, eps, *, k: float, sigma: float) -> np.ndarray:
    """Kirchhoff coherent ``|R_p(θi)|² e^{−(2kσ cosθi)²}`` (2, n) [-] for flat ``ti`` [rad]."""
    pec = isinstance(eps, str)
    e = 0j if pec else complex(eps)
    out = np.empty((2, ti.size))
    _coherent_kernel(np.ascontiguousarray(ti), pec, e.real, e.imag, 2.0 * k * sigma, out[0], out[1])
    return out


def _element_strides(shape: tuple[int, ...], grid: tuple[int, ...]) -> list[int]:
    """C-order element strides of a contiguous array of ``shape`` on the 3-D ``grid`` it
    broadcasts to (padded in front; 0 along the axes it is broadcast over)."""
    shape = (1,) * (3 - len(shape)) + shape
    out, step = [0, 0, 0], 1
    for d in (2, 1, 0):
        if shape[d] != 1:
            out[d] = step
            step *= shape[d]
    return out


def go_sigma0_grid(
    ti: np.ndarray,
    ts: np.ndarray,
    dphi: np.ndarray,
    shape: tuple[int, ...],
    eps,
    *,
    slope_variance: float,
    shadowing: str | None,
    out: np.ndarray,
    threads: int | None = None,
) -> np.ndarray:
    """:func:`go_sigma0` for angles given unbroadcast — ``ti``, ``ts``, ``dphi`` [rad]
    broadcast together to ``shape`` (at most 3-D; ``θ ∈ [0, π/2]``, ``|dphi| ≤ 1e6``) — into
    ``out`` (2, 2, prod(shape)), C order. The trigonometry and Smith's ``Λ`` are computed once
    per distinct direction (per element of ``ti``, ``ts``, ``dphi``) and each geometry reads
    them: a grid of m θi × m θs × m φ pays for 2m + m of them, not 3m³."""
    pec = isinstance(eps, str)
    e = 0j if pec else complex(eps)
    code = SHADOWING_CODES[shadowing]
    s2 = float(slope_variance)
    grid = (1,) * (3 - len(shape)) + tuple(shape)
    shape3 = np.array(grid, np.int64)
    flats = [np.ascontiguousarray(a, dtype=np.float64) for a in (ti, ts, dphi)]
    st = np.array([_element_strides(a.shape, grid) for a in flats], np.int64)
    flats = [a.reshape(-1) for a in flats]
    ti_tab, ts_tab = np.empty((4, flats[0].size)), np.empty((4, flats[1].size))
    d_tab = np.empty((3, flats[2].size))
    _grid_tables(*flats, s2, ti_tab, ts_tab, d_tab)
    d_tab[2] = directional_weight(flats[2]) if code == DIRECTIONAL else 0.0
    kernel = _GRID_KERNELS[(pec, code != NO_SHADOWING)]
    outs = (out[0, 0], out[0, 1], out[1, 0], out[1, 1])
    consts = (ti_tab, ts_tab, d_tab, e.real, e.imag, s2, code)

    def part(a: int, b: int) -> None:
        kernel(a, shape3, st, *consts, *(y[a:b] for y in outs))

    n = out.shape[-1]
    if n < 2 * _MIN_CHUNK or threads == 1:
        part(0, n)
    else:
        run_chunked(part, n, threads)
    return out
