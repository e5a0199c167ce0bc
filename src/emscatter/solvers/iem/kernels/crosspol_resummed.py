"""Compiled (numba) resummed backscatter cross-pol, ``σ⁰_hv = σ⁰_vh`` [-]
(:func:`emscatter.solvers.iem.crosspol_resummed.backscatter_resummed`): every angle of a call in
one jitted loop.

The equation and its sources are in :mod:`emscatter.solvers.iem.crosspol_resummed`::

    σ⁰_hv = 4π k² cos²θ σ⁴ ∫ T̂(Q, k_s⊥ − p) T̂(Q, p − k_i⊥) g₂(p)[g₂*(p) + g₂*(−p)] d²p,
    T̂(Q, κ) = ℓₓℓᵧ e^{−Q} Σ_{n≥1} Qⁿ⁻¹/n! wₙ(κ),   Q = (kσ cosθ)².

Per angle, the node rule, its azimuth partners and the kernel ``g₂`` are those of the compiled
second-order SPM (:mod:`emscatter.solvers.spm.kernel_crosspol`, whose inline helpers run here):
the σ⁰⁽²²⁾ rule of ``spm.crosspol._polar_nodes``, the incident-v kernel ``g_hv`` only (the
backscatter symmetries: ``g₂*(−p)`` is the kernel at the point partner, and on the upper half
plane where the surface's quadratic form is even under ``y → −y``). What differs is the weight:
``T̂`` in place of the spectrum ``w``, summed at each node

* in linear space: ``T̂ = ℓₓℓᵧ Σ cₙ fₙ(K)``, ``cₙ = e^{−Q} Qⁿ⁻¹/n! · (4πn)⁻¹`` with
  ``fₙ = e^{−K²/4n}`` (Gaussian) or ``cₙ = e^{−Q} Qⁿ⁻¹/n! · (2πn²)⁻¹`` with
  ``fₙ = (1 + K²/n²)^{−3/2}`` (exponential) — the closed forms of
  ``kirchhoff.po.log_nfold`` — the ``cₙ`` once per angle by recurrence;
* until the geometric bound of the rest is below 1e-13 of the sum (the terms are log-concave
  in n from n = 2, as ``iem.kernels.series._peak`` uses: past the peak the term ratio only
  falls; the bound is first tried on ``t₃/t₂``: at K = 0 the exponential's ``t₂/t₁ = Q/8`` is
  below ``t₃/t₂ = 4Q/27``);
  leading terms that underflow (Gaussian, ``K ≳ 55``) are negligible against the peak;
* ``T̂(k_s⊥ − p) = T̂(−(p + k_i⊥))`` is the second factor at the point partner ``−p``: one
  series per node (half of them on the upper half plane);
* exponential: not node by node but every node of the angle at once, terms outer (the node
  loop vectorizes), with one term count ``N`` whose tail is bounded at every node
  (``fₙ/f₁ ≤ n³``: ``Σ_{n>N} cₙ n³ ≤ 1e-13 c₁``, :func:`_exp_terms`); four terms share one
  division (``Σ cⱼ/tⱼ`` over a common denominator, ``tₙ = uₙ√uₙ``: the loop is bound by
  the divider and the square root; issue 20's second speed pass, values to ≤ 1e-14).

The kernel ``g₂`` per node circle (``|p| = ρ`` fixed) from its Fourier series: every factor of
``spm.kernel_crosspol._g_hv`` is a polynomial in ``(cos ψ, sin ψ)`` of degree ≤ 3 (the
first-order sources of degree 1, their amplitudes of degree 2 — ``ĉ`` times a degree-1 source —,
the second-order source at ``k_s`` of degree 3: the fields of degree 3, ``(k_s − p) E_z`` of
1 + 2), so ``g₂(ρ, ψ) = Σ_{|m|≤3} c_m(ρ) e^{imψ}`` exactly; 8 equispaced samples per circle give
the ``c_m`` (discrete Fourier transform, no aliasing), and each node costs, in the real form
``g₂ = c₀ + Σ_{m=1}^{3} [(c_m + c₋m) cos mψ + i(c_m − c₋m) sin mψ]`` (cos mψ, sin mψ by angle
addition, once per azimuth), 12 real products in place of the kernel's ~40 complex ones
(``_fill_g_fourier``; issue 20's speed target: 0.34 → 0.14 ms per angle on its 162-case grid,
loaded machine; → 0.12 ms with the real form and the grouped series divisions).

Per angle in two parts: :func:`_prepare` (node rule, partners, the kernel products times the
weights, the nodes' ``(Kℓ)²``: independent of σ) and :func:`_evaluate` (the height series at
``Q`` and the weighted sum); :func:`prepare_one` / :func:`evaluate_one` expose them for one
angle, so that the caller may remember the first (``iem.crosspol_resummed._PREP``) — the same
arithmetic as :func:`_kernel`, the same double.

Agreement with the numpy reference (``kirchhoff.po.series_sum`` at ``rtol = 1e-10``, whose
16-term blocks sum far past that bound; the whole-plane rule without the symmetries):
``tests/test_iem_crosspol_resummed_kernel.py``, ≤ 1e-10 relative. Angles whose rule lacks the
point symmetry are flagged 0 and computed by the caller's numpy reference.
"""

from __future__ import annotations

import math
import threading

import numpy as np

from emscatter.kernels._runtime import inline, jit, run_split
from emscatter.solvers.spm.kernel_crosspol import (
    _MAX_AZIMUTH_SEGMENTS,
    _MAX_RADIAL_SEGMENTS,
    GAUSSIAN,
    _g_hv,
    _node_rules,
    _partner,
    _q2,
    _radial,
    _root,
    _rule_constants,
    _rule_scratch,
    _zeroth,
    unit_rule,
)

__all__ = [
    "backscatter_resummed",
    "prepare_one",
    "value_one",
    "evaluate_one",
    "GAUSSIAN",
    "EXPONENTIAL",
    "N_COEF",
]

EXPONENTIAL = 1
#: Series coefficients kept per angle (``Q ≤ 9``: ``cₙ`` < 1e-300 of the first by n ≈ 200).
N_COEF = 1024
_SERIES_RTOL = 1e-13


@inline
def _coefficients(Q, spec, c, inv):
    """``c[n − 1] = e^{−Q} Qⁿ⁻¹/n! / (4πn)`` (Gaussian) or ``/ (2πn²)`` (exponential), by
    recurrence, until they fall below 1e-300; count returned. ``inv[n − 1]`` the argument
    scale of ``fₙ``: ``1/(4n)`` (Gaussian) or ``1/n²`` (exponential), so that the node loop
    multiplies instead of dividing."""
    a = math.exp(-Q)
    m = 0
    for n in range(1, c.size + 1):
        if n > 1:
            a *= Q / n
        if a < 1e-300:
            break
        c[n - 1] = a / (4.0 * math.pi * n) if spec == GAUSSIAN else a / (2.0 * math.pi * n * n)
        inv[n - 1] = 0.25 / n if spec == GAUSSIAN else 1.0 / (n * n)
        m = n
    return m


@inline
def _t_hat(K2, c, inv, nc, spec, area):
    """``ℓₓℓᵧ T(Q, K)`` at ``K² = K2`` from the angle's coefficients ``c[:nc]``, ``inv[:nc]``
    (module docstring: linear-space sum, geometric tail bound ``t r/(1 − r) ≤ rtol·sum`` with
    ``r = t/t_prev``, written ``t² ≤ rtol (t_prev − t) sum``: no division)."""
    acc, prev = 0.0, 0.0
    for i in range(nc):
        if spec == GAUSSIAN:
            f = math.exp(-K2 * inv[i])
        else:
            u = 1.0 + K2 * inv[i]
            f = 1.0 / (u * math.sqrt(u))
        t = c[i] * f
        acc += t
        if i >= 2 and t < prev:  # past the peak: the ratio only falls (log-concave from n = 2)
            if t * t <= _SERIES_RTOL * (prev - t) * acc:
                break
        prev = t
    return area * acc


#: Azimuth samples per node circle for the kernel's Fourier coefficients: ``g₂`` is a
#: trigonometric polynomial of degree 3 in the node azimuth ψ at fixed ``|p|`` (module
#: docstring), so 8 equispaced samples give its 7 coefficients exactly (no aliasing).
_FOURIER_SAMPLES = 8
_DEGREE = 3


@inline
def _exp_terms(c, nc, rtol):
    """Terms ``N`` of the exponential height series that bound its tail at every ``K``:
    ``fₙ(K)/f₁(K) ≤ n³`` (``fₙ = (1 + K²/n²)^{−3/2}`` increases with n), so
    ``Σ_{n>N} cₙ fₙ ≤ f₁ Σ_{n>N} cₙ n³ ≤ rtol · c₁ f₁ ≤ rtol · T̂/(ℓₓℓᵧ)``."""
    tail = 0.0
    m = nc
    while m > 1:
        t = c[m - 1] * float(m) ** 3
        if tail + t > rtol * c[0]:
            break
        tail += t
        m -= 1
    return m


@inline
def _fill_g_fourier(g, eps, k, si, ci, sq_eps, inv_k2, cphi, sphi, ksv0, ksv1, zc, kr, nr,
                    cpsi, spsi, first, na, gs, cf, ep, cs, sn):  # fmt: skip
    """``g_hv`` at the nodes ``(ir < nr, first ≤ ia < na)`` into ``g``, as
    ``spm.kernel_crosspol._fill_g`` but per radius from its Fourier coefficients: at fixed
    ``ρ = |p|`` every factor of ``_g_hv`` is a polynomial in ``(cos ψ, sin ψ)`` — the first-order
    amplitudes of degree 2, the second-order source of degree 3 — so
    ``g(ρ, ψ) = Σ_{|m|≤3} c_m(ρ) e^{imψ}``; ``c_m`` from 8 samples (``cs``, ``sn``: their
    cos, sin) by the discrete Fourier transform — as ``c₀`` and the real-weighted
    ``c_m + c₋m``, ``i(c_m − c₋m)`` (module docstring) —, then 12 real products per node
    (``ep[ia] = (cos ψ, sin ψ, …, cos 3ψ, sin 3ψ)``) in place of the kernel's ~40."""
    K_i, k1z = k * si, k * ci
    k2z = _root(eps * k * k - K_i * K_i)
    rv = (eps * k1z - k2z) / (eps * k1z + k2z)
    zc[:] = 0j
    _zeroth(zc, 1.0 + 0j, -k1z + 0j, 1.0, k + 0j, K_i)  # incident
    _zeroth(zc, rv, k1z + 0j, 1.0, k + 0j, K_i)  # reflected
    _zeroth(zc, (1.0 + rv) / sq_eps, -k2z, -1.0, sq_eps * k, K_i)  # transmitted
    k2zs = _root(eps * k * k - (k * si) ** 2)
    inv_den = 1.0 / (k * ci + k2zs)
    ns = cs.size
    for ia in range(first, na):  # cos mψ, sin mψ (m = 1 … 3) by angle addition
        c1, s1 = cpsi[ia], spsi[ia]
        cm, sm = c1, s1
        for m in range(_DEGREE):
            ep[ia, 2 * m], ep[ia, 2 * m + 1] = cm, sm
            cm, sm = cm * c1 - sm * s1, sm * c1 + cm * s1
    for ir in range(nr):
        rho = kr[ir]
        rad = _radial(eps, k, rho)
        for j in range(ns):
            gs[j] = _g_hv(eps, k, inv_k2, k2zs, inv_den, cphi, sphi, ksv0, ksv1, K_i, zc, rho,
                          rad, cs[j], sn[j], rho * cs[j], rho * sn[j])  # fmt: skip
        # c₀ = (1/ns) Σ_j g_j; c_m + c₋m = (2/ns) Σ_j g_j cos mψ_j; i(c_m − c₋m) = (2/ns)
        # Σ_j g_j sin mψ_j: g = c₀ + Σ_{m=1}^{3} [(c_m + c₋m) cos mψ + i(c_m − c₋m) sin mψ]
        acc = 0j
        for j in range(ns):
            acc += gs[j]
        c0 = acc / ns
        for m in range(1, _DEGREE + 1):
            a, b = 0j, 0j
            for j in range(ns):
                jm = (m * j) % ns
                a += gs[j] * cs[jm]
                b += gs[j] * sn[jm]
            cf[2 * m - 2], cf[2 * m - 1] = a * (2.0 / ns), b * (2.0 / ns)
        c0r, c0i = c0.real, c0.imag
        a1r, a1i, b1r, b1i = cf[0].real, cf[0].imag, cf[1].real, cf[1].imag
        a2r, a2i, b2r, b2i = cf[2].real, cf[2].imag, cf[3].real, cf[3].imag
        a3r, a3i, b3r, b3i = cf[4].real, cf[4].imag, cf[5].real, cf[5].imag
        for ia in range(first, na):
            e = ep[ia]
            vr = c0r + a1r * e[0] + b1r * e[1] + a2r * e[2] + b2r * e[3] + a3r * e[4] + b3r * e[5]
            vi = c0i + a1i * e[0] + b1i * e[1] + a2i * e[2] + b2i * e[3] + a3i * e[4] + b3i * e[5]
            g[ir, ia] = complex(vr, vi)


@inline
def _t_hat_exp_block(qv, cnt, c, inv, nterms, area, out):
    """``out[i] = ℓₓℓᵧ Σ_{n≤nterms} cₙ (1 + qv[i]/n²)^{−3/2}`` for ``i < cnt``: the exponential
    series at a fixed term count (:func:`_exp_terms`), terms outer so that the node loop
    vectorizes (``sqrt`` and the division are IEEE-exact in SIMD: no fastmath needed); four
    (then two) terms over one common denominator, ``Σ cⱼ/tⱼ`` with ``tⱼ = uⱼ√uⱼ``: one
    division per four terms (``1 ≤ tⱼ``, and the product of four, ``≤ u_max⁶``, overflows
    only beyond ``Kℓ ~ 1e25``: far outside any rule)."""
    for i in range(cnt):
        out[i] = 0.0
    n = 0
    while n + 3 < nterms:  # four terms per division
        ca, sa, cb, sb = c[n], inv[n], c[n + 1], inv[n + 1]
        cc, sc, cd, sd = c[n + 2], inv[n + 2], c[n + 3], inv[n + 3]
        for i in range(cnt):
            ua, ub = 1.0 + qv[i] * sa, 1.0 + qv[i] * sb
            uc, ud = 1.0 + qv[i] * sc, 1.0 + qv[i] * sd
            ta, tb = ua * math.sqrt(ua), ub * math.sqrt(ub)
            tc, td = uc * math.sqrt(uc), ud * math.sqrt(ud)
            tab, tcd = ta * tb, tc * td
            out[i] += ((ca * tb + cb * ta) * tcd + (cc * td + cd * tc) * tab) / (tab * tcd)
        n += 4
    while n + 1 < nterms:  # two terms per division: cₐ/tₐ + c_b/t_b = (cₐ t_b + c_b tₐ)/(tₐ t_b)
        ca, sa, cb, sb = c[n], inv[n], c[n + 1], inv[n + 1]
        for i in range(cnt):
            ua, ub = 1.0 + qv[i] * sa, 1.0 + qv[i] * sb
            ta, tb = ua * math.sqrt(ua), ub * math.sqrt(ub)
            out[i] += (ca * tb + cb * ta) / (ta * tb)
        n += 2
    if n < nterms:
        cn, sn = c[n], inv[n]
        for i in range(cnt):
            u = 1.0 + qv[i] * sn
            out[i] += cn / (u * math.sqrt(u))
    for i in range(cnt):
        out[i] *= area


@jit
def _prepare(a, eps, k, lx, ly, cr, sr, spec, s_r, ds_r, s_a, ds_a, W, qv, pidx, g, qa):
    """The σ-independent part of one backscatter angle ``a`` [rad]: for every node ``c`` of
    the rule (the upper half plane where the surface allows), ``W[c]`` the quadrature weight
    times ``Re g₂(p)[g₂*(p) + g₂*(−p)]`` (× 2 on the upper half), ``qv[c] = (|p − k_i⊥|ℓ)²``
    and ``pidx[c]`` the node where ``T̂(k_s⊥ − p)`` is ``T̂`` (the point partner, or its
    mirror); ``g`` complex and ``qa`` real scratch (``(_MAX_RADIAL_SEGMENTS·s_r.size,
    _MAX_AZIMUTH_SEGMENTS·s_a.size)``: the kernel and q at the nodes), the caller's, reused, so that
    a call neither allocates nor first touches its ~0.3 MB; the node count returned, −1 where
    the azimuth rule lacks the point symmetry (the caller's numpy). Depends on ε, k, θ, ℓₓ,
    ℓᵧ, φ and the spectrum's kind, not on σ: the node rule's breaks are ``k``, ``Re√ε k``
    and ``1/ℓ`` distances (module docstring)."""
    log, inv_len, extent, sq_eps, cphi, sphi = _rule_constants(spec, lx, ly, eps)
    pts, br, kr, wr, psi, wpsi, neg, mir, cpsi, spsi = _rule_scratch(s_r.size, s_a.size)
    zc = np.empty(6, dtype=np.complex128)
    gs = np.empty(_FOURIER_SAMPLES, dtype=np.complex128)
    cf = np.empty(2 * _DEGREE, dtype=np.complex128)
    ep = np.empty((psi.size, 2 * _DEGREE))
    cs = np.empty(_FOURIER_SAMPLES)
    sn = np.empty(_FOURIER_SAMPLES)
    for j in range(_FOURIER_SAMPLES):
        cs[j] = math.cos(2.0 * math.pi * j / _FOURIER_SAMPLES)
        sn[j] = math.sin(2.0 * math.pi * j / _FOURIER_SAMPLES)
    inv_k2 = 1.0 / (sq_eps * k)
    si, ci = math.sin(a), math.cos(a)
    kis0, kis1 = k * si, 0.0
    ksv0, ksv1 = k * si * cphi, k * si * sphi
    nr, na = _node_rules(k, kis0, kis1, ksv0, ksv1, sq_eps, inv_len, extent, log, s_r, ds_r,
                         s_a, ds_a, pts, br, kr, wr, psi, wpsi)  # fmt: skip
    if not _partner(psi, na, math.pi, False, neg):
        return -1  # (no point symmetry: the numpy reference)
    half = _partner(psi, na, 0.0, True, mir)
    for ia in range(na):
        cpsi[ia], spsi[ia] = math.cos(psi[ia]), math.sin(psi[ia])
    first = 0
    if half:  # the surface's quadratic form even under y → −y (to 1e-12)
        for ir in range(nr):  # q at every node once (the mirror's is its node's: qa[ir, pm])
            for ia in range(na):
                px, py = kr[ir] * cpsi[ia], kr[ir] * spsi[ia]
                qa[ir, ia] = _q2(px - kis0, py - kis1, cr, sr, lx, ly)
        for ir in range(nr):
            for ia in range(na):
                q_a, q_b = qa[ir, ia], qa[ir, mir[ia]]
                if not abs(q_a - q_b) <= 1e-12 * abs(q_b):
                    half = False
        if half:
            while first < na and not psi[first] > 0.0:
                first += 1
    _fill_g_fourier(g, eps, k, si, ci, sq_eps, inv_k2, cphi, sphi, ksv0, ksv1, zc, kr, nr,
                    cpsi, spsi, first, na, gs, cf, ep, cs, sn)  # fmt: skip
    m = na - first
    fac = 2.0 if half else 1.0
    for ir in range(nr):
        base = fac * wr[ir] * kr[ir]
        for ia in range(first, na):
            ga = g[ir, ia]
            if half:  # −p's mirror, on the upper half: g(−p) = −g there, T̂ the same
                pos = max(mir[neg[ia]] - first, 0) + first
                d = ga - g[ir, pos]
            else:
                pos = neg[ia]
                d = ga + g[ir, pos]
            c = ir * m + (ia - first)
            W[c] = base * wpsi[ia] * (ga.real * d.real + ga.imag * d.imag)
            if half:  # (its q from the check: the same expression, the same double)
                qv[c] = qa[ir, ia]
            else:
                px, py = kr[ir] * cpsi[ia], kr[ir] * spsi[ia]
                qv[c] = _q2(px - kis0, py - kis1, cr, sr, lx, ly)
            pidx[c] = ir * m + (pos - first)
    return nr * m


@jit
def _evaluate(W, qv, pidx, n, a, k, sigma, spec, area, coef, cinv, tv):
    """σ⁰_hv = 4π k² cos²θ σ⁴ ``Σ_c W[c] T̂(qv[c]) T̂(qv[pidx[c]])`` over the ``n`` nodes of
    :func:`_prepare` at the angle ``a`` [rad]: the height series at every node at
    ``Q = (kσ cosθ)²`` (exponential: every node at once, terms outer, the term count bounding
    the tail everywhere), then the weighted sum."""
    ci = math.cos(a)
    Q = (k * sigma * ci) ** 2
    nc = _coefficients(Q, spec, coef, cinv)
    if spec == GAUSSIAN:
        for c in range(n):
            tv[c] = _t_hat(qv[c], coef, cinv, nc, spec, area)
    else:
        _t_hat_exp_block(qv, n, coef, cinv, _exp_terms(coef, nc, _SERIES_RTOL), area, tv)
    val = 0.0
    for c in range(n):
        val += W[c] * tv[c] * tv[pidx[c]]
    return 4.0 * math.pi * k * k * ci * ci * sigma**4 * val


@jit
def _kernel(theta, eps, k, sigma, lx, ly, cr, sr, spec, s_r, ds_r, s_a, ds_a, start, stop, out,
            flag):  # fmt: skip
    """Resummed σ⁰_hv into ``out[j]`` for ``theta[start:stop]`` [rad] (:func:`_prepare`, then
    :func:`_evaluate`); ``flag[j]`` 1 where computed, 0 where the azimuth rule lacks the point
    symmetry (the caller's numpy)."""
    size = _MAX_RADIAL_SEGMENTS * s_r.size * _MAX_AZIMUTH_SEGMENTS * s_a.size
    W, qv, tv = np.empty(size), np.empty(size), np.empty(size)
    g = np.empty((_MAX_RADIAL_SEGMENTS * s_r.size, _MAX_AZIMUTH_SEGMENTS * s_a.size),
                 dtype=np.complex128)  # fmt: skip
    qa = np.empty(g.shape)
    pidx = np.empty(size, dtype=np.int64)
    coef, cinv = np.empty(N_COEF), np.empty(N_COEF)
    for j in range(start, stop):
        flag[j] = 0
        out[j] = 0.0
        n = _prepare(theta[j], eps, k, lx, ly, cr, sr, spec, s_r, ds_r, s_a, ds_a, W, qv, pidx,
                     g, qa)  # fmt: skip
        if n < 0:
            continue
        out[j] = _evaluate(W, qv, pidx, n, theta[j], k, sigma, spec, lx * ly, coef, cinv, tv)
        flag[j] = 1


def backscatter_resummed(theta, eps: complex, k: float, sigma: float, length: float,
                         length_y: float, phi_i: float, spectrum: int, n_nodes: int,
                         threads: int = 1, n_azimuth: int | None = None):  # fmt: skip
    """``(σ⁰_hv, computed)`` at the flat angles ``theta`` [rad] (checked by the caller):
    values [-] and a bool mask (False: the caller's numpy reference runs that angle).
    ``n_nodes`` Gauss–Legendre nodes per radial segment, ``n_azimuth`` per azimuth segment
    (default ``n_nodes``)."""
    theta = np.ascontiguousarray(theta, dtype=np.float64)
    n = theta.size
    out, flag = np.zeros(n), np.zeros(n, dtype=np.int64)
    s, ds = unit_rule(int(n_nodes))
    sa, dsa = unit_rule(int(n_nodes if n_azimuth is None else n_azimuth))
    args = (complex(eps), float(k), float(sigma), float(length), float(length_y),
            math.cos(phi_i), math.sin(phi_i), int(spectrum), s, ds, sa, dsa)  # fmt: skip

    def part(a: int, b: int) -> None:
        _kernel(theta, *args, a, b, out, flag)

    run_split(part, n, threads, 2)
    return out, flag.astype(bool)


#: Per-thread scratch of the one-angle path (:func:`_buffers`): reused, as :func:`_kernel`
#: reuses its own across angles (a fresh ~0.8 MB per call, first touched, cost as much as the
#: node rule; issue 20's second speed pass).
_LOCAL = threading.local()


def _buffers(n_nodes: int, n_azimuth: int):
    """This thread's ``(s, ds, sa, dsa, W, qv, pidx, g, qa, coef, cinv, tv)`` for the rule
    ``n_nodes × n_azimuth``: the unit rules and :func:`_one`'s scratch (made once)."""
    key = (n_nodes, n_azimuth)
    buf = getattr(_LOCAL, "buf", None)
    if buf is None or buf[0] != key:
        s, ds = unit_rule(n_nodes)
        sa, dsa = unit_rule(n_azimuth)
        nr, na = _MAX_RADIAL_SEGMENTS * s.size, _MAX_AZIMUTH_SEGMENTS * sa.size
        size = nr * na
        buf = (key, (s, ds, sa, dsa, np.empty(size), np.empty(size),
                     np.empty(size, dtype=np.int64), np.empty((nr, na), dtype=np.complex128),
                     np.empty((nr, na)), np.empty(N_COEF), np.empty(N_COEF),
                     np.empty(size)))  # fmt: skip
        _LOCAL.buf = buf
    return buf[1]


def _series_scratch(n: int):
    """This thread's ``(coef, cinv, tv)`` for :func:`_evaluate` on ``n`` nodes (``tv`` grown
    as needed; reused)."""
    buf = getattr(_LOCAL, "series", None)
    if buf is None or buf[2].size < n:
        buf = (np.empty(N_COEF), np.empty(N_COEF), np.empty(max(n, 4096)))
        _LOCAL.series = buf
    return buf


@jit
def _one(a, eps, k, sigma, lx, ly, cr, sr, spec, s_r, ds_r, s_a, ds_a, W, qv, pidx, g, qa,
         coef, cinv, tv):  # fmt: skip
    """:func:`_prepare` then :func:`_evaluate` for one angle ``a`` [rad] in one call (as
    :func:`_kernel` runs them: the same value to the bit): ``(n, σ⁰_hv)``, ``n`` the node count
    of ``W, qv, pidx`` (−1, value 0, where the rule lacks the point symmetry)."""
    n = _prepare(a, eps, k, lx, ly, cr, sr, spec, s_r, ds_r, s_a, ds_a, W, qv, pidx, g, qa)
    if n < 0:
        return n, 0.0
    return n, _evaluate(W, qv, pidx, n, a, k, sigma, spec, lx * ly, coef, cinv, tv)


def _trimmed(W, qv, pidx, n):
    prep = (W[:n].copy(), qv[:n].copy(), pidx[:n].copy())
    for a in prep:
        a.flags.writeable = False
    return prep


def value_one(theta: float, eps: complex, k: float, sigma: float, length: float,
              length_y: float, phi_i: float, spectrum: int, n_nodes: int,
              n_azimuth: int):  # fmt: skip
    """``(σ⁰_hv, prep)`` at one flat backscatter angle ``theta`` [rad] (checked by the
    caller): :func:`prepare_one` and :func:`evaluate_one` in one compiled call on reused
    scratch — the same value to the bit —, ``prep`` the σ-independent part to remember (as
    :func:`prepare_one` returns it), or ``(None, None)`` where the rule lacks the point
    symmetry (the caller's numpy reference)."""
    s, ds, sa, dsa, W, qv, pidx, g, qa, coef, cinv, tv = _buffers(n_nodes, n_azimuth)
    n, v = _one(theta, eps, k, sigma, length, length_y, math.cos(phi_i), math.sin(phi_i),
                spectrum, s, ds, sa, dsa, W, qv, pidx, g, qa, coef, cinv, tv)  # fmt: skip
    if n < 0:
        return None, None
    return v, _trimmed(W, qv, pidx, n)


def prepare_one(theta: float, eps: complex, k: float, length: float, length_y: float,
                phi_i: float, spectrum: int, n_nodes: int, n_azimuth: int):  # fmt: skip
    """The σ-independent part of one flat backscatter angle ``theta`` [rad] (:func:`_prepare`):
    ``(W, qv, pidx)`` trimmed to the rule's nodes (fresh arrays, read-only), or None where the
    rule lacks the point symmetry (the caller's numpy reference)."""
    s, ds, sa, dsa, W, qv, pidx, g, qa, _, _, _ = _buffers(n_nodes, n_azimuth)
    n = _prepare(theta, eps, k, length, length_y, math.cos(phi_i), math.sin(phi_i), spectrum,
                 s, ds, sa, dsa, W, qv, pidx, g, qa)  # fmt: skip
    if n < 0:
        return None
    return _trimmed(W, qv, pidx, n)


def evaluate_one(
    prep, theta: float, k: float, sigma: float, length: float, length_y: float, spectrum: int
) -> float:
    """σ⁰_hv [-] at one flat angle ``theta`` [rad] from its :func:`prepare_one` part and the
    surface's ``sigma`` [m]: the same arithmetic as :func:`_kernel` (the same value to the bit)."""
    W, qv, pidx = prep
    coef, cinv, tv = _series_scratch(W.size)
    return _evaluate(W, qv, pidx, W.size, theta, k, sigma, spectrum, length * length_y,
                     coef, cinv, tv)  # fmt: skip
