"""The compiled linear-space backscatter walk of the IEM (co-pol, hh and vv together):
blocks of :data:`LANES` geometries walk the series orders in lockstep (:func:`walk_lanes`,
:func:`walk_transition`), then :func:`back_kernel` assembles σ⁰; the log-space sums it falls
back on are in :mod:`.series`. Numpy reference: :mod:`emscatter.solvers.iem.terms` and
:mod:`emscatter.solvers.iem.series`."""

from __future__ import annotations

import math

import numpy as np

from emscatter.kernels._runtime import inline, jit
from emscatter.solvers.iem.kernels.mono import back_geometry, cdiv, fast_root, fung92_co, lower_back
from emscatter.solvers.iem.kernels.series import (
    FAST_MAX_ORDER,
    HUGE,
    ISQ,
    TINY,
    back_shadowing,
    cabs,
    isqrt,
    lower_co,
    reduced_i,
    reduced_s,
    root,
    row_series,
    transition_sums,
    w_lin,
)

# ----------------------------------------------------------------------------- lanes
# The exact-backscatter walk runs LANES geometries in lockstep (one order for all of them per
# step), so the per-order arithmetic vectorizes across geometries (SIMD) instead of waiting
# on one geometry's chain of dependent operations. A lane that meets its stopping rule is
# frozen (its sums stop changing: the same sums as a walk of that geometry alone).
LANES = 16
# rows of the lane state, as offsets into the flat state array (row r, lane l: [r + l]; a
# flat array with constant row offsets lets LLVM vectorize the lane loops)
(H0R, H0I, V0R, V0I, H1R, H1I, V1R, V1I, H2R, H2I, V2R, V2I, M0H, M0V, M1H, M1V, M2H, M2V,
 Z0, Z1, Z2, X0, X1, X2, SH, SV, EH, EV, K2F, WPREV, P0H, P0V, P1H, P1V, P2H, P2V,
 XX0, XX1, XX2, KM0, KM1, KM2, E0, E1, INV2, NH, NV, ACT, DROP, ND,
 MSQ) = range(0, 51 * LANES, LANES)  # fmt: skip
N_ROWS = 51


@inline
def _drop_or_walk(S, l, ph, pv, zrow, e, xx, inv2, ks2):
    """Classify component ``zrow`` of lane ``l`` at the start: zero, left out (it starts below
    the precise range; its whole-series bound goes into DROP) or walked (counted in NH/NV)."""
    big = max(ph, pv)
    mj = big * S[zrow + l] * S[zrow + l]
    if mj == 0.0:
        S[zrow + l] = 0.0
    elif mj < 1e-280:
        S[DROP + l] += big * math.exp(2.0 * e + ks2 * xx) / xx * inv2
        S[ND + l] += 1.0
        S[zrow + l] = 0.0
    else:
        if ph > 0.0:
            S[NH + l] += 1.0
        if pv > 0.0:
            S[NV + l] += 1.0


@inline
def lane_start(S, l, a0h, a0v, a1h, a1v, a2h, a2v, x0, x1, x2, att0, att1, e0, e1, dh, dv,
               ks2, K2, w1):  # fmt: skip
    """Set up lane ``l`` for :func:`walk_lanes` (its docstring: the terms, the scaling, the
    range checks) at n = 1 and 2; a PEC passes zero lower-medium amplitudes and ``att1 = 0``;
    ``w1`` = Ŵ₁(K). False (lane inactive): the linear-space walk is not safe."""
    S[ACT + l] = 0.0
    sks = math.sqrt(ks2)
    S[H0R + l], S[H0I + l], S[V0R + l], S[V0I + l] = a0h.real, a0h.imag, a0v.real, a0v.imag
    S[H1R + l], S[H1I + l], S[V1R + l], S[V1I + l] = a1h.real, a1h.imag, a1v.real, a1v.imag
    S[H2R + l], S[H2I + l], S[V2R + l], S[V2I + l] = a2h.real, a2h.imag, a2v.real, a2v.imag
    p0h, p0v = a0h.real**2 + a0h.imag**2, a0v.real**2 + a0v.imag**2
    p1h, p1v = a1h.real**2 + a1h.imag**2, a1v.real**2 + a1v.imag**2
    p2h, p2v = a2h.real**2 + a2h.imag**2, a2v.real**2 + a2v.imag**2
    if e0 < -700.0 and (p0h > 0.0 or p0v > 0.0):  # attenuation not normal
        return False
    if e1 < -700.0 and (p1h > 0.0 or p1v > 0.0 or p2h > 0.0 or p2v > 0.0):
        return False
    S[P0H + l], S[P0V + l], S[P1H + l], S[P1V + l], S[P2H + l], S[P2V + l] = (
        p0h,
        p0v,
        p1h,
        p1v,
        p2h,
        p2v,
    )
    m0h, m0v = math.sqrt(p0h), math.sqrt(p0v)
    m1h, m1v = math.sqrt(p1h), math.sqrt(p1v)
    m2h, m2v = math.sqrt(p2h), math.sqrt(p2v)
    S[M0H + l], S[M0V + l], S[M1H + l], S[M1V + l], S[M2H + l], S[M2V + l] = (
        m0h,
        m0v,
        m1h,
        m1v,
        m2h,
        m2v,
    )
    z0 = att0 * sks * x0 * sks * ISQ[2]  # n = 2
    z1 = att1 * sks * x1 * sks * ISQ[2]
    z2 = att1 * sks * x2 * sks * ISQ[2]
    # n = 1
    f0, f1 = att0 * sks, att1 * sks
    i1h = dh * sks + a0h * f0 + (a1h + a2h) * f1
    i1v = dv * sks + a0v * f0 + (a1v + a2v) * f1
    e1h = (cabs(dh) + m0h * att0) * sks + (m1h + m2h) * f1
    e1v = (cabs(dv) + m0v * att0) * sks + (m1v + m2v) * f1
    s1h = i1h.real * i1h.real + i1h.imag * i1h.imag
    s1v = i1v.real * i1v.real + i1v.imag * i1v.imag
    m2 = max(max(p0h, p0v) * z0 * z0, max(p1h, p1v) * z1 * z1, max(p2h, p2v) * z2 * z2,
             s1h, s1v)  # fmt: skip
    if not (0.0 < m2 < HUGE):
        return False
    inv = 1.0 / math.sqrt(m2)
    inv2 = inv * inv
    S[Z0 + l], S[Z1 + l], S[Z2 + l] = z0 * inv, z1 * inv, z2 * inv
    S[X0 + l], S[X1 + l], S[X2 + l] = x0, x1, x2
    xx0, xx1, xx2 = x0 * x0, x1 * x1, x2 * x2
    S[XX0 + l], S[XX1 + l], S[XX2 + l] = xx0, xx1, xx2
    S[NH + l] = S[NV + l] = S[ND + l] = S[DROP + l] = 0.0
    _drop_or_walk(S, l, p0h, p0v, Z0, e0, xx0, inv2, ks2)
    _drop_or_walk(S, l, p1h, p1v, Z1, e1, xx1, inv2, ks2)
    _drop_or_walk(S, l, p2h, p2v, Z2, e1, xx2, inv2, ks2)
    S[KM0 + l] = S[KM1 + l] = S[KM2 + l] = -1.0  # whole-series bounds, computed when needed
    S[SH + l] = s1h * inv2 * w1
    S[SV + l] = s1v * inv2 * w1
    S[EH + l] = (e1h * inv) ** 2 * w1
    S[EV + l] = (e1v * inv) ** 2 * w1
    S[WPREV + l] = w1
    S[K2F + l] = K2
    S[E0 + l], S[E1 + l], S[INV2 + l], S[MSQ + l] = e0, e1, inv2, m2
    S[ACT + l] = 1.0
    return True


@inline
def _lane_tail(S, l, zrow, xxrow, kmrow, phrow, pvrow, e, rho, w, ks2):
    """(hh, vv) tail bound of one component of lane ``l`` (:func:`walk_lanes`)."""
    z = S[zrow + l]
    if z == 0.0:
        return 0.0, 0.0
    r = S[xxrow + l] * rho
    if r < 1.0:
        g = z * z * w * r / (1.0 - r)
    else:
        if S[kmrow + l] < 0.0:
            xx = S[xxrow + l]
            S[kmrow + l] = math.exp(2.0 * e + ks2 * xx) / xx * S[INV2 + l]
        g = S[kmrow + l]
    return S[phrow + l] * g, S[pvrow + l] * g


@jit
def walk_lanes(S, m, ks2, spec, dim, rtol, max_terms, out_ok, WT, nw):
    """Walk lanes ``0 … m−1`` of ``S`` (set up by :func:`lane_start`, ``ACT`` = 1) in lockstep
    from n = 2 until each meets its stopping rule; ``out_ok[l]`` False where the linear-space
    walk was not safe. Sums end in rows ``SH, SV, EH, EV`` (times ``MSQ``: ``S_hh, S_vv`` and
    the envelopes, without the prefactor ``e^{pref}``).

    Both co-pol series of one backscatter geometry in linear space (the log-space
    :func:`row_series` rewritten as recurrences). Components: the Kirchhoff component 0
    (amplitudes ``a0h, a0v``, base ``x0``, attenuation ``att0 = e^{e0}``) and, for a
    dielectric, the lower-medium components 1, 2 (bases ``x1, x2``, one attenuation
    ``att1 = e^{e1}``); ``dh, dv`` the n = 1 extra amplitudes. Terms
    ``Tₙ = (kσ)^{2n}/n! Ŵₙ |Σ_j a_j att_j x_j^(n−1) + δ_{n1} d|²`` with
    ``z_j(n) = att_j x_j^(n−1) √((kσ)^{2n}/n!)`` by one multiplication per order, scaled by the
    largest start magnitude so every term is ≤ 1-ish. Stopping rule as :func:`row_series`:
    per component the geometric tail ``T r/(1 − r)`` with ``r = x_j² (kσ)²/n Ŵₙ/Ŵₙ₋₁`` (term
    ratios are non-increasing from n = 3 on for the Gaussian and exponential closed forms),
    its whole-series bound ``|a|² e^{2e + Q}/x²`` where it still rises; times the number of
    components (Cauchy–Schwarz); below ``rtol`` of the sum for both polarizations, tested
    every fourth order. Not safe (the caller takes the log-space path): a component that
    starts below 1e-140 of the largest is left out and its whole-series bound must be
    negligible (≤ 1e-3 rtol of the sum) at the end; a walk longer than
    :data:`FAST_MAX_ORDER` or ``max_terms``; sums outside [1e-250, 1e300]. ``WT``: the
    Ŵₙ of orders 1 … ``nw`` of these lanes, as :func:`walk_transition` left them (the same
    numbers: read, not evaluated again)."""
    sks = math.sqrt(ks2)
    w = np.empty(m)
    live = 0
    for l in range(m):
        out_ok[l] = True
        if S[ACT + l] > 0.0:
            live += 1
    n = 2.0
    while live > 0:
        if n <= nw:  # Ŵₙ per lane: the transition walk's, or evaluated
            o = (int(n) - 1) * LANES
            for l in range(m):
                w[l] = WT[o + l]
        else:
            for l in range(m):
                w[l] = w_lin(n, S[K2F + l], spec, dim)
        for l in range(m):  # one order for every lane (frozen lanes add nothing)
            z0, z1, z2 = S[Z0 + l], S[Z1 + l], S[Z2 + l]
            hr = S[H0R + l] * z0 + S[H1R + l] * z1 + S[H2R + l] * z2
            hi = S[H0I + l] * z0 + S[H1I + l] * z1 + S[H2I + l] * z2
            vr = S[V0R + l] * z0 + S[V1R + l] * z1 + S[V2R + l] * z2
            vi = S[V0I + l] * z0 + S[V1I + l] * z1 + S[V2I + l] * z2
            a0, a1, a2 = abs(z0), abs(z1), abs(z2)
            enh = S[M0H + l] * a0 + S[M1H + l] * a1 + S[M2H + l] * a2
            env = S[M0V + l] * a0 + S[M1V + l] * a1 + S[M2V + l] * a2
            act = S[ACT + l] > 0.0
            wl = w[l]
            S[SH + l] += (hr * hr + hi * hi) * wl if act else 0.0
            S[SV + l] += (vr * vr + vi * vi) * wl if act else 0.0
            S[EH + l] += enh * enh * wl if act else 0.0
            S[EV + l] += env * env * wl if act else 0.0
        i = int(n)
        if n >= 3.0 and i & 3 == 3:  # tail test at orders 3, 7, 11, ... (per lane)
            for l in range(m):
                if S[ACT + l] <= 0.0:
                    continue
                wp = S[WPREV + l]
                wl = w[l]
                rho = ks2 / n * wl / wp if wp > 0.0 else np.inf
                e0, e1 = S[E0 + l], S[E1 + l]
                t0h, t0v = _lane_tail(S, l, Z0, XX0, KM0, P0H, P0V, e0, rho, wl, ks2)
                t1h, t1v = _lane_tail(S, l, Z1, XX1, KM1, P1H, P1V, e1, rho, wl, ks2)
                t2h, t2v = _lane_tail(S, l, Z2, XX2, KM2, P2H, P2V, e1, rho, wl, ks2)
                if (S[NH + l] * (t0h + t1h + t2h) <= rtol * S[SH + l]
                        and S[NV + l] * (t0v + t1v + t2v) <= rtol * S[SV + l]):  # fmt: skip
                    S[ACT + l] = 0.0
                    live -= 1
        if live > 0 and (n >= FAST_MAX_ORDER or n > max_terms):
            for l in range(m):
                if S[ACT + l] > 0.0:
                    S[ACT + l] = 0.0
                    out_ok[l] = False
            break
        n += 1.0
        f = sks * isqrt(n)
        for l in range(m):
            S[WPREV + l] = w[l]
            S[Z0 + l] *= S[X0 + l] * f
            S[Z1 + l] *= S[X1 + l] * f
            S[Z2 + l] *= S[X2 + l] * f
    for l in range(m):
        if not out_ok[l]:
            continue
        sh, sv = S[SH + l], S[SV + l]
        if not (TINY <= sh < HUGE and TINY <= sv < HUGE):
            out_ok[l] = False
        else:  # left-out components change √S by at most √(nd·drop) (Minkowski,
            # Cauchy–Schwarz): keep that below 5e-4 rtol of √S (≤ 1e-3 rtol relative)
            nd = S[ND + l]
            if nd > 0.0 and not nd * S[DROP + l] <= (5e-4 * rtol) ** 2 * min(sh, sv):
                out_ok[l] = False


# rows of the transition-sum lane state (offsets, as above)
TK2, TS1, TS2, TS4, TT1, TPREV, TACT = range(0, 7 * LANES, LANES)
T_ROWS = 7
WT_ORDERS = 64  # orders of Ŵₙ the transition walk keeps for the series walk


@jit
def walk_transition(T, m, Q, spec, dim, rtol_t, out_ok, WT):
    """Linear-space :func:`transition_sums` for lanes ``0 … m−1`` of ``T`` in lockstep, one
    ``Q`` for all (rows ``TK2`` = K², ``TACT`` = 1 where wanted): ``S(βQ) = Σ_{n≥1}
    (βQ)ⁿ/n! Ŵₙ`` for β = 1, 2, 4 end in rows ``TS1, TS2, TS4`` (:func:`transition_ratios`
    reads them). ``Qⁿ/n!`` is one number per order for every lane. A lane
    stops when the geometric tail of each of the three series (term ratios non-increasing from
    n = 3 on for these spectra, tested at odd orders) is below ``rtol_t`` of its sum;
    ``out_ok[l]`` False when the sums leave the safe range (the caller then takes the
    log-space path). One lane (m = 1) is the one-geometry form the log-space path uses.
    Returns ``nw``: the Ŵₙ of orders 1 … nw are in ``WT[(n − 1) LANES + l]`` (as many as
    ``WT`` holds; :func:`walk_lanes` reads them)."""
    w = np.empty(m)
    live = 0
    for l in range(m):
        out_ok[l] = True
        T[TS1 + l] = T[TS2 + l] = T[TS4 + l] = 0.0
        T[TPREV + l] = 0.0
        if T[TACT + l] > 0.0:
            live += 1
    n, p2, p4, qn = 1.0, 1.0, 1.0, 1.0
    nw = 0
    cap = WT.shape[0] // LANES
    while live > 0:
        p2 *= 2.0
        p4 *= 4.0
        qn = qn * (Q / n)
        for l in range(m):
            w[l] = w_lin(n, T[TK2 + l], spec, dim)
        if nw < cap:
            o = nw * LANES
            for l in range(m):
                WT[o + l] = w[l]
            nw += 1
        for l in range(m):
            t1 = qn * w[l]
            T[TT1 + l] = t1
            act = T[TACT + l] > 0.0
            T[TS1 + l] += t1 if act else 0.0
            T[TS2 + l] += t1 * p2 if act else 0.0
            T[TS4 + l] += t1 * p4 if act else 0.0
        if n >= 3.0 and int(n) & 1:  # tail test at odd orders
            for l in range(m):
                prev = T[TPREV + l]
                if T[TACT + l] <= 0.0 or not prev > 0.0:
                    continue
                t1 = T[TT1 + l]
                r1 = t1 / prev
                r4 = 4.0 * r1
                if r4 < 1.0:
                    r2 = 2.0 * r1
                    if (t1 * r1 / (1.0 - r1) <= rtol_t * T[TS1 + l]
                            and t1 * p2 * r2 / (1.0 - r2) <= rtol_t * T[TS2 + l]
                            and t1 * p4 * r4 / (1.0 - r4) <= rtol_t * T[TS4 + l]):  # fmt: skip
                        T[TACT + l] = 0.0
                        live -= 1
        for l in range(m):
            T[TPREV + l] = T[TT1 + l]
        n += 1.0
        if live > 0 and n > FAST_MAX_ORDER:
            for l in range(m):
                if T[TACT + l] > 0.0:
                    T[TACT + l] = 0.0
                    out_ok[l] = False
            break
    for l in range(m):
        s1, s4 = T[TS1 + l], T[TS4 + l]
        if not (TINY <= s1 < HUGE and s4 < HUGE):
            out_ok[l] = False
    return nw


@inline
def transition_ratios(T, l, eq):
    """``(S(2Q)/S(Q) e^{−Q}, S(4Q)/S(Q) e^{−2Q})`` of lane ``l`` after :func:`walk_transition`
    (``eq = e^{−Q}``)."""
    s1 = T[TS1 + l]
    return T[TS2 + l] / s1 * eq, T[TS4 + l] / s1 * eq * eq


@inline
def log_transition_ratios(Q, Kr, spec, dim, log_rtol):
    """:func:`transition_ratios` from the log-space :func:`transition_sums` at ``Q`` (any
    size; the sums to ``log_rtol`` − 4.6, i.e. 1e-2 of the series tolerance)."""
    l1, l2, l4 = transition_sums(math.log(Q), Kr, spec, dim, log_rtol - 4.6)
    return math.exp(min(l2 - l1 - Q, 700.0)), math.exp(min(l4 - l1 - 2.0 * Q, 700.0))


@inline
def fresnel_setup(s, c, eps, pec):
    """``(q₂, 1/q₂, R_h, R_v)`` at incidence θ (PEC: ``R_h = −1, R_v = 1``, ``q₂ = 0``)."""
    if pec:
        return 0j, 0j, -1.0 + 0j, 1.0 + 0j
    q2 = fast_root(eps - s * s)
    iq = cdiv(1.0 + 0j, q2)
    rh = cdiv(c - q2, c + q2)
    rv = cdiv(eps * c - q2, eps * c + q2)
    return q2, iq, rh, rv


@inline
def transition_gamma(rh, rv, s2, c, iq, e2, e4, r0, r08, r08sq, a0):
    """``(R_h, R_v, γ_h, γ_v)`` with Wu et al. 2001's transition, from the sum ratios
    ``e₂ = S(2Q)/S(Q) e^{−Q}``, ``e₄ = S(4Q)/S(Q) e^{−2Q}`` at ``Q = (kσ)²``
    (:func:`emscatter.solvers.iem.terms.transition_from_sums`: why not ``(kσ cosθ)²``):
    ``γ_p = 1 − |F + 8R₀|² / (|F|² + 8 Re(F R₀*) e₂ + 16|R₀|² e₄)``,
    ``F_h = −F_v = −8 R₀² sin²θ (cosθ + q₂)/q₂`` (real arithmetic)."""
    ftc = r08sq * s2 * (c * iq + 1.0)
    ff = ftc.real * ftc.real + ftc.imag * ftc.imag
    cr = 8.0 * (ftc.real * r0.real + ftc.imag * r0.imag) * e2
    base = ff + a0 * e4
    dh_ = -ftc + r08
    dv_ = ftc + r08
    den = base - cr
    ratio = (dh_.real * dh_.real + dh_.imag * dh_.imag) / den if den > 0 else 1.0
    gh = min(max(1.0 - ratio, 0.0), 1.0)
    den = base + cr
    ratio = (dv_.real * dv_.real + dv_.imag * dv_.imag) / den if den > 0 else 1.0
    gv = min(max(1.0 - ratio, 0.0), 1.0)
    return rh + (-r0 - rh) * gh, rv + (r0 - rv) * gv, gh, gv


@inline
def lower_setup(s, c, q2, iq, rh, rv, eps, ieps, ks2, lower_q2, fh, fv):
    """Lower-medium terms of exact backscatter: ``(a, e_g, p1, p2, mm)`` (the ``q = −q₂`` "i",
    ``q = +q₂`` "s" and ``q = −q₂`` "s" combinations, co-pol), ``a`` their height phase:
    ``Re q₂`` (``lower_q2``, AIEM) or ``cosθ`` (the upper medium's, ``"aiem-upper"``,
    ``"aiem-faded"``; :func:`.iem_kernels.backscatter_terms`); hh amplitudes times ``fh``,
    vv times ``fv`` (the fade ``1 − γ_v`` of ``"aiem-faded"`` on both, else 1)."""
    a = q2.real if lower_q2 else c
    Ci, _ = reduced_i(s, c, s, c, 0.0, -1.0, -q2, c + a)
    Cs, _ = reduced_s(s, c, s, c, 0.0, -1.0, q2, c + a)
    Cm, _ = reduced_s(s, c, s, c, 0.0, -1.0, -q2, c - a)
    p1 = lower_co(Ci, rh, rv, iq, eps, ieps)
    p2 = lower_co(Cs, rh, rv, iq, eps, ieps)
    mm = lower_co(Cm, rh, rv, iq, eps, ieps)
    p1 = (p1[0] * fh, p1[1], p1[2], p1[3] * fv)
    p2 = (p2[0] * fh, p2[1], p2[2], p2[3] * fv)
    mm = (mm[0] * fh, mm[1], mm[2], mm[3] * fv)
    return a, -ks2 * (a * a + c * c), p1, p2, mm


@inline
def angle_setup(s, c, Kr, eps, pec, ks2, spec, dim, transition, fast, rtol, log_rtol, r0, r08,
                r08sq, a0, ieps, T, tr_ok, lower_q2, fade, fung92):  # fmt: skip
    """Per-geometry coefficients of exact backscatter, one geometry at a time (the
    log-space path): ``(fast, rh, rv, rh_t, rv_t, a, e_k, e_g, p1, p2, mm, J)`` — Fresnel
    coefficients at θ and with the transition, ``a = Re q₂``, the height exponents, the
    lower-medium combinations (zero for a PEC: ``J = 1``; ``fung92``: the 1992 complementary
    amplitude ×4 in ``p1``, base ``cosθ``, ``a = 0``, ``J = 3`` also for a PEC); ``fast``
    False where the linear transition sums left the safe range (the log-space sums were
    used). ``T, tr_ok``: lane state for a one-lane :func:`walk_transition` (lane 0 is
    overwritten)."""
    s2 = s * s
    zero = (0j, 0j, 0j, 0j)
    q2, iq, rh, rv = fresnel_setup(s, c, eps, pec)
    rh_t, rv_t = rh, rv
    gh = gv = 0.0
    if transition and not pec:
        Q = ks2  # the transition's phase variable (kσ)² (terms.transition_q)
        e2, e4 = 2.0, 4.0
        if fast:
            T[TK2], T[TACT] = Kr * Kr, 1.0
            walk_transition(T, 1, Q, spec, dim, rtol * 1e-2, tr_ok, T[:0])
            fast = tr_ok[0]
            if fast:
                e2, e4 = transition_ratios(T, 0, math.exp(-Q))
        if not fast:
            e2, e4 = log_transition_ratios(Q, Kr, spec, dim, log_rtol)
        rh_t, rv_t, gh, gv = transition_gamma(rh, rv, s2, c, iq, e2, e4, r0, r08, r08sq, a0)
    e_k = -2.0 * ks2 * c * c
    if fung92:
        gh92, gv92 = fung92_co(s, c, q2, eps, pec)
        p1 = (4.0 * gh92, 0j, 0j, 4.0 * gv92)
        return fast, rh, rv, rh_t, rv_t, 0.0, e_k, -ks2 * c * c, p1, zero, zero, 3
    if pec:
        return fast, rh, rv, rh_t, rv_t, 0.0, e_k, 0.0, zero, zero, zero, 1
    fh = fv = 1.0 - gv if fade else 1.0
    a, e_g, p1, p2, mm = lower_setup(s, c, q2, iq, rh, rv, eps, ieps, ks2, lower_q2, fh, fv)
    return fast, rh, rv, rh_t, rv_t, a, e_k, e_g, p1, p2, mm, 3


@jit
def back_kernel(si, cs, eps, pec, ks, K, pref, spec, dim, transition, log_rtol,
                max_terms, use_fast, sh_code, sh_slope, psi, out_hh, out_vv, out_e,
                out_fast, lower_q2, fade, fung92, geo):  # fmt: skip
    """Exact-backscatter hh, vv per geometry (``fung92``: the 1992 IEM, Kirchhoff plus one
    complementary component of base ``cosθ``, no n = 1 terms of their own): the linear-space
    walk where it is safe and ``use_fast`` — blocks of :data:`LANES` geometries in lockstep:
    transition sums (:func:`walk_transition`), then both series (:func:`lane_start`,
    :func:`walk_lanes`) — else the log-space :func:`row_series` / :func:`transition_sums`,
    one geometry at a time. Outputs σ⁰_hh, σ⁰_vv, the precision ratio (sum of the envelopes
    over the sum, ≥ 1; :mod:`emscatter.solvers.iem.series`) and ``out_fast[r]``: the fast
    path was taken. ``geo[0]`` ≠ 0: ``cs`` and ``K`` are outputs, the exact-backscatter
    geometry from ``si`` and ``geo`` (:func:`.mono.back_geometry`) first."""
    if geo[0] != 0.0:
        back_geometry(si, geo, dim, cs, K)
    ks2 = ks * ks
    log_ks2 = math.log(ks2)
    rtol = math.exp(log_rtol)
    status = 0
    la = np.empty(3)
    lx = np.empty(3)
    sx = np.ones(3)
    ph = np.ones(3, dtype=np.complex128)
    sq = root(eps)
    r0 = (sq - 1.0) / (sq + 1.0)
    ieps = 1.0 / eps
    r08, r08sq = 8.0 * r0, 8.0 * r0 * r0
    a0 = 16.0 * (r0.real * r0.real + r0.imag * r0.imag)
    wok, wmass, wprev, wcur = np.empty(3, np.bool_), np.empty(3), np.empty(3), np.empty(3)
    sh_den = math.sqrt(2.0 * sh_slope * sh_slope)
    S = np.empty(N_ROWS * LANES)
    T = np.empty(T_ROWS * LANES)
    lane_ok = np.empty(LANES, dtype=np.bool_)
    eq = math.exp(-ks2)  # e^{−Q} of the transition ratios
    tr_ok = np.empty(LANES, dtype=np.bool_)
    started = np.zeros(LANES, dtype=np.bool_)
    lane_shf = np.empty(LANES)
    lq2 = np.empty(LANES, dtype=np.complex128)
    liq = np.empty(LANES, dtype=np.complex128)
    lrh = np.empty(LANES, dtype=np.complex128)
    lrv = np.empty(LANES, dtype=np.complex128)
    with_tr = transition and not pec
    n_all = si.shape[0]
    WT = np.empty(WT_ORDERS * LANES)  # Ŵₙ of the transition walk, for the series walk
    last_pref, last_exp = math.nan, math.nan
    for b in range(0, n_all, LANES):
        m = min(LANES, n_all - b)
        any_tr = False
        nw = 0
        for l in range(m):  # shadowing, Fresnel coefficients, transition lanes
            r = b + l
            s, c = si[r], cs[r]
            lane_shf[l] = 1.0
            if sh_code != 0:
                lane_shf[l] = back_shadowing(s, c, sh_den, sh_code, psi[r] if sh_code == 1 else 0.0)
            started[l] = False
            T[TACT + l] = 0.0
            if not use_fast:
                continue
            lq2[l], liq[l], lrh[l], lrv[l] = fresnel_setup(s, c, eps, pec)
            if with_tr:  # the transition's Q = (kσ)² (terms.transition_q), one for all lanes
                T[TK2 + l] = K[r] * K[r]
                T[TACT + l] = 1.0
                any_tr = True
        if any_tr:
            nw = walk_transition(T, m, ks2, spec, dim, rtol * 1e-2, tr_ok, WT)
        any_started = False
        for l in range(m):  # transition factors, lower-medium terms, series lanes
            if not use_fast:
                continue
            r = b + l
            s, c = si[r], cs[r]
            s2 = s * s
            q2, iq, rh, rv = lq2[l], liq[l], lrh[l], lrv[l]
            rh_t, rv_t = rh, rv
            gh = gv = 0.0
            if with_tr:
                if tr_ok[l]:
                    e2, e4 = transition_ratios(T, l, eq)
                else:  # linear sums out of range (kσ ≳ 9): log-space sums, lane stays fast
                    e2, e4 = log_transition_ratios(ks2, K[r], spec, dim, log_rtol)
                rh_t, rv_t, gh, gv = transition_gamma(rh, rv, s2, c, iq, e2, e4, r0, r08, r08sq,
                                                      a0)  # fmt: skip
            e_k = -2.0 * ks2 * c * c
            ek_lin = math.exp(e_k)
            dh = -4.0 * s2 * rh * rh * ek_lin
            dv = 4.0 * s2 * rv * rv * ek_lin
            if fung92:
                a, e_g = 0.0, -ks2 * c * c
                g1h, g1v = fung92_co(s, c, q2, eps, pec)
                g2h = g2v = 0j
                att1 = math.exp(e_g)
                dh = dv = 0j
            elif pec:
                a, e_g, att1 = 0.0, 0.0, 0.0
                g1h = g1v = g2h = g2v = 0j
            elif lower_q2:  # AIEM's phase Re q₂: the general combination (as before, bit for bit)
                fh = fv = 1.0 - gv if fade else 1.0
                a, e_g, p1, p2, mm = lower_setup(s, c, q2, iq, rh, rv, eps, ieps, ks2, lower_q2,
                                                 fh, fv)  # fmt: skip
                g1h, g1v = 0.25 * (p1[0] + p2[0]), 0.25 * (p1[3] + p2[3])
                g2h, g2v = 0.25 * mm[0], 0.25 * mm[3]
                att1 = math.exp(e_g)
            else:  # the upper-medium phase (the default "aiem-faded"): closed form
                f = 0.25 * (1.0 - gv) if fade else 0.25
                a = c
                e_g, att1 = e_k, ek_lin  # −(kσ)²(a² + cos²θ) with a = cosθ: the Kirchhoff one
                g1h, g1v, g2h, g2v = lower_back(s2, c, q2, iq, rh, rv, eps, ieps, a, f)
            started[l] = lane_start(
                S, l, -4.0 * rh_t, 4.0 * rv_t, g1h, g1v, g2h, g2v, 2.0 * c, c + a, c - a, ek_lin,
                att1, e_k, e_g, dh, dv, ks2, K[r] * K[r],
                WT[l] if nw > 0 else w_lin(1.0, K[r] * K[r], spec, dim),  # the same Ŵ₁
            )  # fmt: skip
            any_started = any_started or started[l]
        if any_started:
            walk_lanes(S, m, ks2, spec, dim, rtol, max_terms, lane_ok, WT, nw)
        for l in range(m):  # results; the log-space path where the fast one was not taken
            r = b + l
            shf = lane_shf[l]
            if started[l] and lane_ok[l]:
                if pref[r] != last_pref:  # e^{pref}: once while it repeats (the monostatic call)
                    last_pref = pref[r]
                    last_exp = math.exp(last_pref)
                ep = last_exp * S[MSQ + l] * shf
                out_hh[r] = S[SH + l] * ep
                out_vv[r] = S[SV + l] * ep
                out_e[r] = max(S[EH + l] / S[SH + l],
                               S[EV + l] / S[SV + l])  # fmt: skip
                out_fast[r] = True
                continue
            out_fast[r] = False
            s, c = si[r], cs[r]
            s2 = s * s
            fast, rh, rv, rh_t, rv_t, a, e_k, e_g, p1, p2, mm, J = angle_setup(
                s, c, K[r], eps, pec, ks2, spec, dim, transition, use_fast, rtol, log_rtol, r0,
                r08, r08sq, a0, ieps, T, tr_ok, lower_q2, fade, fung92,
            )  # fmt: skip
            lx[0] = math.log(2.0 * c) if c > 0 else -np.inf
            if J == 3:
                lx[1] = math.log(abs(c + a)) if c + a != 0 else -np.inf
                lx[2] = math.log(abs(c - a)) if c - a != 0 else -np.inf
                sx[1] = -1.0 if c + a < 0 else 1.0
                sx[2] = -1.0 if c - a < 0 else 1.0
            for p in range(2):
                ak = -4.0 * rh_t if p == 0 else 4.0 * rv_t
                u = (-4.0 * s2 * rh * rh) if p == 0 else (4.0 * s2 * rv * rv)
                if fung92:
                    u = 0j
                amps = (
                    (
                        ak,
                        0.25 * (p1[0] + p2[0]) if p == 0 else 0.25 * (p1[3] + p2[3]),
                        0.25 * mm[0] if p == 0 else 0.25 * mm[3],
                    )
                    if J == 3
                    else (ak, 0j, 0j)
                )
                for j in range(J):
                    mag = abs(amps[j])
                    la[j] = (math.log(mag) if mag > 0 else -np.inf) + (e_k if j == 0 else e_g)
                    ph[j] = amps[j] / mag if mag > 0 else 1.0 + 0j
                d = u * math.exp(e_k)
                sres, eres, st = row_series(
                    la[:J], lx[:J], ph[:J], sx[:J], d, pref[r] + math.log(shf), K[r], log_ks2,
                    spec, dim, log_rtol, max_terms, wok[:J], wmass[:J], wprev[:J], wcur[:J],
                )  # fmt: skip
                status = max(status, st)
                if p == 0:
                    out_hh[r] = math.exp(sres)
                else:
                    out_vv[r] = math.exp(sres)
                out_e[r] = max(out_e[r], math.exp(min(eres - sres, 700.0)))
    return status
