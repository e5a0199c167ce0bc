"""The single-scattering amplitudes of the IEM (:mod:`emscatter.solvers.iem.model`): the
Kirchhoff and complementary field coefficients combined per series component with the
transition function (Wu et al. 2001) and the first-order defect that makes the small-kσ limit
exact SPM; the spectral series and its arguments. The equations and the choices made are in
the model's docstring."""

from __future__ import annotations

import math

import numpy as np

from emscatter.fresnel import PEC, _sqrt_branch, fresnel_cos, is_pec
from emscatter.solvers.iem import compiled as iem_jit
from emscatter.solvers.iem import terms as kern
from emscatter.solvers.iem.series import _too_many, iem_series

_SPM_SIGN = (-1.0, 1.0, -1.0, 1.0)  # I₁(AIEM) ≈ s · 4 f_SPM (hh, hv, vh, vv): basis signs


class _Options:
    __slots__ = ("fresnel", "complementary", "first_order", "rtol", "max_terms", "threads")


def _amplitudes(rough, si, cs, ss, css, sf, cf, eps, ks: float, log_w, K, opt: _Options):
    """Series components for flat geometries (k = 1, φi = 0): ``la, ph`` (4, N, J), ``lx, sx``
    (N, J) and the first-order amplitude ``d`` (4, N), pols ordered (hh, hv, vh, vv).
    Compiled (:mod:`emscatter.solvers.iem.kernels.amplitudes`) where numba is enabled, else
    :func:`_amplitudes_numpy` (the reference; same values to ≤ 1e-12 relative)."""
    if not iem_jit.enabled():
        return _amplitudes_numpy(rough, si, cs, ss, css, sf, cf, eps, ks, log_w, K, opt)
    from emscatter.solvers.iem.kernels import amplitudes as amp_jit

    pec = is_pec(eps)
    n = si.shape[0]
    flat = lambda v: iem_jit.flat_n(v, n)  # noqa: E731
    si, cs, ss, css, sf, cf = flat(si), flat(cs), flat(ss), flat(css), flat(sf), flat(cf)
    if opt.fresnel == "transition" and not pec:
        g_h, g_v = _transition(rough, eps, cs, ks, log_w, K, opt.rtol)
        g_h, g_v = flat(g_h), flat(g_v)
    else:
        g_h = g_v = np.zeros(n)
    e = np.ones(n, complex) if pec else iem_jit.flat_n(eps, n, complex)  # writeable (flat_n)
    # components: Kirchhoff (with dn_i, up_s merged unless "fung92"), the other upper-medium
    # terms, the four lower-medium terms (none for a PEC)
    J = 1 + (4 if opt.complementary == "fung92" else 2) + (0 if pec else 4)
    roots = np.zeros((5, n), complex)  # cos θ_l and the complex square roots, numpy's
    if not pec:
        cos_l = np.sqrt(np.clip(0.5 * (1.0 + cs * css - si * ss * cf), 0.0, 1.0))
        roots[0] = cos_l
        for row, c in ((1, cs), (2, cos_l)):  # as fresnel_cos
            c = np.clip(c, 0.0, 1.0)
            roots[row] = _sqrt_branch(e - (1.0 - c * c))
        roots[3], roots[4] = kern.branch_root(e - si * si), kern.branch_root(e - ss * ss)
    la, ph = np.empty((4, n, J)), np.empty((4, n, J), complex)
    lx, sx, d = np.empty((n, J)), np.empty((n, J)), np.empty((4, n), complex)
    amp_jit.amplitudes_kernel(
        si, cs, ss, css, sf, cf, e, pec, g_h, g_v, float(ks * ks),
        amp_jit.PHASES[opt.complementary], opt.first_order == "spm", roots, la, lx, ph, sx, d,
    )  # fmt: skip
    return la, lx, ph, sx, d


def _amplitudes_numpy(rough, si, cs, ss, css, sf, cf, eps, ks: float, log_w, K, opt: _Options):
    """:func:`_amplitudes` in numpy (the reference of the compiled kernel)."""
    pec = is_pec(eps)
    n = si.shape[0]
    rh_i, rv_i = fresnel_cos(eps, cs)
    cos_l = np.sqrt(np.clip(0.5 * (1.0 + cs * css - si * ss * cf), 0.0, 1.0))
    rh_l, rv_l = fresnel_cos(eps, cos_l)
    if opt.fresnel == "transition" and not pec:
        g_h, g_v = _transition(rough, eps, cs, ks, log_w, K, opt.rtol)
        rh_t, rv_t = rh_i + (rh_l - rh_i) * g_h, rv_i + (rv_l - rv_i) * g_v
    else:
        g_h = g_v = np.zeros(n)
        rh_t, rv_t = rh_i, rv_i
    kv = kern.kirchhoff_vector(si, cs, ss, css, sf, cf, rh_l, rv_l)
    sh, sv = kern.kirchhoff_scalar(si, cs, ss, css, cf, rh_t - rh_l, rv_t - rv_l)
    xf = (kv[0] + sh, kv[1], kv[2], kv[3] + sv)
    terms = kern.complementary_terms(
        si, cs, ss, css, sf, cf, 1.0 if pec else eps, rh_i, rv_i, lower=not pec,
        phase=opt.complementary,
    )  # fmt: skip
    # "aiem-faded": the lower-medium ("G") terms × (1 − γ_v); the first-order defect below
    # is taken with the unfaded terms (the fade, like the transition, is not undone at n = 1)
    fade = 1.0 - g_v if opt.complementary == "aiem-faded" and not pec else None
    ks2 = ks * ks
    base = -0.5 * ks2 * (cs * cs + css * css)
    # component 0: Kirchhoff (x = kz + ksz, E = −σ² kz ksz), with the complementary terms of
    # the same base and exponent merged in (AIEM's q = −kz "i" and q = +ksz "s" terms)
    x0 = cs + css
    amps = [list(xf)]
    xs = [x0]
    es = [-ks2 * cs * css]
    merged = ("dn_i", "up_s") if opt.complementary != "fung92" else ()
    comp_sum = [0.0, 0.0, 0.0, 0.0]
    for name, F, qph, side in terms:
        comp_sum = [c + 0.25 * f for c, f in zip(comp_sum, F, strict=True)]
        if name in merged:
            amps[0] = [a + 0.25 * f for a, f in zip(amps[0], F, strict=True)]
            continue
        w = 0.25 * fade if (fade is not None and name[0] == "G") else 0.25
        amps.append([w * f for f in F])
        xs.append((css - qph) if side == "i" else (cs + qph))
        es.append(-ks2 * (qph * qph - qph * (css - cs)))
    J = len(xs)
    a = np.empty((4, n, J), dtype=complex)
    for j in range(J):
        for p in range(4):
            a[p, :, j] = amps[j][p]
    E = np.stack([np.broadcast_to(e, (n,)) for e in es], axis=1) + base[:, None]
    x = np.stack([np.broadcast_to(v, (n,)) for v in xs], axis=1)
    mag = np.abs(a)
    with np.errstate(divide="ignore"):
        la = np.log(mag) + E[None]
        lx = np.log(np.abs(x))
    ph = np.where(mag > 0, a / np.where(mag > 0, mag, 1.0), 1.0)
    sx = np.where(x < 0, -1.0, 1.0)
    # first-order defect to SPM1 (γ = 0 Kirchhoff coefficient, all exponentials → 1)
    if opt.first_order == "spm":
        from emscatter.solvers.spm.model import _f_factors  # the closed-form first-order amplitudes

        sh0, sv0 = kern.kirchhoff_scalar(si, cs, ss, css, cf, rh_i - rh_l, rv_i - rv_l)
        xf0 = (kv[0] + sh0, kv[1], kv[2], kv[3] + sv0)
        f_spm = _f_factors(PEC if pec else eps, cs, si, css, ss, cf, sf)
        d = np.empty((4, n), dtype=complex)
        for p in range(4):
            d[p] = (4.0 * _SPM_SIGN[p] * f_spm[p] - (xf0[p] + comp_sum[p])) * np.exp(base)
    else:
        d = np.zeros((4, n), dtype=complex)
    return la, lx, ph, sx, d


def _spectral_args(rough, k, loc, n):
    """Scaled spectral argument K and log normalization of the series (module docstring)."""
    qx, qy = iem_jit.flat_n(loc.qx, n), iem_jit.flat_n(loc.qy, n)
    if rough.dimension == 2:
        K = np.sqrt((qx * (k * rough.length)) ** 2 + (qy * (k * rough.length_y)) ** 2)
        return K, math.log(math.pi * (k * rough.length) * (k * rough.length_y))
    return np.abs(qx) * (k * rough.length), math.log(0.5 * math.pi * k * rough.length)


def _transition(rough, eps, cs, ks, log_w, K, rtol):
    """Fresnel transition factors (γ_h, γ_v), compiled sums where covered."""
    spec = iem_jit.spectrum_code(rough) if iem_jit.enabled() else None
    if spec is None:
        return kern.transition_factor(eps, cs, ks, log_w, K)
    lq = np.full(np.shape(cs), math.log(kern.transition_q(ks)))  # S(βQ), Q = (kσ)²
    # the three sums S(βQ), β = 1, 2, 4, in one call (independent elements: the same values)
    n = lq.size
    lqs = np.concatenate([lq + math.log(b) for b in (1.0, 2.0, 4.0)])
    Ks = np.tile(np.broadcast_to(K, (n,)), 3)
    s = iem_jit.poisson_sums(lqs, Ks, spec, rough.dimension, rtol=rtol * 1e-2)
    return kern.transition_from_sums(eps, cs, ks, s[:n], s[n : 2 * n], s[2 * n :])


def _series(rough, la, lx, ph, sx, d, log_ks2, log_w, K, pref, opt):
    """The series (:func:`emscatter.solvers.iem.series.iem_series`), compiled where
    :mod:`emscatter.solvers.iem.compiled` covers it."""
    spec = iem_jit.spectrum_code(rough) if iem_jit.enabled() else None
    if spec is not None:
        ls, lp, status = iem_jit.series_rows(
            la, lx, ph, sx, d, log_ks2, spec, rough.dimension, K, pref,
            rtol=opt.rtol, max_terms=opt.max_terms,
        )  # fmt: skip
        if status:
            raise RuntimeError(_too_many(opt.rtol, opt.max_terms, opt.max_terms, log_ks2))
        return ls, lp
    return iem_series(la, lx, ph, sx, d, log_ks2, log_w, K, pref, rtol=opt.rtol,
                      max_terms=opt.max_terms)  # fmt: skip
