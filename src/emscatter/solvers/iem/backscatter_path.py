"""The IEM's exact-backscatter fast path: σ⁰ (2, 2, n) from the closed-form backscatter terms
(:func:`emscatter.solvers.iem.terms.backscatter_terms`, the 1992 ones for
``complementary="fung92"``), compiled where covered. Called by
:func:`emscatter.solvers.iem.model.bistatic` when every geometry is exact backscatter; the model
and its choices are documented there."""

from __future__ import annotations

import math

import numpy as np

from emscatter.fresnel import fresnel_cos, is_pec
from emscatter.solvers.iem import compiled as iem_jit
from emscatter.solvers.iem import terms as kern
from emscatter.solvers.iem.amplitudes import (
    _spectral_args,
)
from emscatter.solvers.iem.series import _orders_needed as iem_series_orders
from emscatter.solvers.iem.series import _too_many, direct_sum, iem_series, orders_table
from emscatter.solvers.iem.shadowing import _back_shadow_args, _shadowing
from emscatter.solvers.iem.validity import (  # noqa: F401 (re-exported: the solver's contract)
    OPTIONS,
    VALIDITY,
    _conductor,
    check_validity,
    nominal_rms_slope,
)
from emscatter.solvers.kirchhoff.common import Local
from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation

__all__: list[str] = []

_SPEC_CODES = {  # iem_jit.spectrum_code by exact type (a subclass takes the general path)
    ExponentialCorrelation: iem_jit.EXPONENTIAL,
    GaussianCorrelation: iem_jit.GAUSSIAN,
}


def monostatic(rough, eps, k, ti, ps, pi_, opt, slope, shadow_mode):
    """Exact backscatter for the public API's checked inputs — ``ti`` a float array of θi
    [rad] in [0, π/2] (θs = θi), ``ps, pi_`` the azimuths φs = φi + π and φi [rad] (0-d),
    ``eps`` "pec" or one complex permittivity (0-d) — without the general geometry:
    ``(σ⁰ (2, 2, n) flat, 0, log precision)``, the values of :func:`_backscatter` on
    :meth:`~emscatter.solvers.kirchhoff.common.Geometry.backscatter_chunk` bit for bit (the
    same formulas on the same numbers: ``sinθ, cosθ`` by ``_trig``,
    ``Δφ = φs − φi``, the lateral ``q`` of ``_lateral_q``), compiled end to end: after
    ``sinθ`` the kernel computes ``cosθ`` and ``K`` itself (``geo``,
    :func:`emscatter.solvers.iem.kernels.mono.back_geometry`), one pass over the angles. ``None``
    where this path does not cover the call (numpy kernels, a power-law or measured
    spectrum, an array ε or φi, anisotropic shadowing slopes): the caller takes the general
    one."""
    pec = isinstance(eps, str)
    if np.ndim(pi_) or np.ndim(ps) or not (pec or np.ndim(eps) == 0):
        return None
    spec = _SPEC_CODES.get(type(rough)) if iem_jit.enabled() else None
    if spec is None or (shadow_mode is not None and slope[0] != slope[1]):
        return None
    ti_f = ti.reshape(-1)
    n = ti_f.size
    si = np.sin(ti_f)
    zero = float(pi_) == 0.0
    dphi = ps if (zero and math.copysign(1.0, float(pi_)) > 0) else ps - pi_
    cd, sd = np.cos(dphi), np.sin(dphi)
    rotate = not (zero or rough.dimension == 1)
    cpi, spi = (np.cos(pi_), np.sin(pi_)) if rotate else (1.0, 0.0)
    if opt.threads > 1 and n >= 2 * iem_jit.BACK_MIN_CHUNK:  # threads: the general wrapper
        ci = np.sqrt((1.0 - si) * (1.0 + si))  # kirchhoff.common._trig
        qxp = si * cd - si  # Geometry._lateral_q with θs = θi
        qyp = si * sd
        qx, qy = (qxp * cpi - qyp * spi, qxp * spi + qyp * cpi) if rotate else (qxp, qyp)
        loc = Local()
        loc.n, loc.si, loc.ci, loc.ss, loc.cs = n, si, ci, si, ci
        loc.cd, loc.sd, loc.qx, loc.qy, loc.eps, loc.phi_i, loc.phi_s = cd, sd, qx, qy, eps, pi_, ps
        return _compiled(rough, eps, k, loc, opt, slope, shadow_mode, spec)
    if not n:
        return np.zeros((2, 2, 0)), 0.0, -np.inf
    kl = k * rough.length  # amplitudes._spectral_args
    if rough.dimension == 2:
        kly = k * rough.length_y
        pref = math.log(math.pi * kl * kly)
    else:
        kly = kl
        pref = math.log(0.5 * math.pi * k * rough.length)
    code, s_slope, psi = 0, 0.0, 0.0  # shadowing._back_shadow_args, θs = θi
    if shadow_mode == "height-correlated":
        code, s_slope = 2, float(slope[0])
    elif shadow_mode is not None:
        psi = float(np.abs(np.mod(ps - pi_ - math.pi + math.pi, 2 * math.pi) - math.pi))
        code, s_slope = 1, float(slope[0])
    sig = np.zeros((2, 2, n))
    out_e = np.ones(n)
    ks = k * rough.sigma
    # cosθ and K in the kernel (kernels.mono.back_geometry: the numpy numbers bit for bit)
    geo = np.array((1.0, cd, sd, cpi, spi, float(rotate), kl, kly))
    st = iem_jit.back_kernel()(
        si, np.empty(n), complex(1.0 if pec else eps), pec, ks, np.empty(n), np.full(n, pref),
        spec, rough.dimension, opt.fresnel == "transition", math.log(opt.rtol), opt.max_terms,
        True, code, s_slope, np.full(n, psi) if code == 1 else iem_jit.NO_PSI, sig[0, 0],
        sig[1, 1], out_e, np.empty(n, dtype=np.bool_), opt.complementary == "aiem",
        opt.complementary == "aiem-faded", opt.complementary == "fung92", geo,
    )  # fmt: skip
    if st:
        raise RuntimeError(_too_many(opt.rtol, opt.max_terms, opt.max_terms, 2 * math.log(ks)))
    # the log of the max: the max of the logs (np.log is monotone; the general path takes the
    # max of its log array) at one logarithm instead of n
    return sig, 0.0, float(np.log(out_e.max()))


def _backscatter(rough, eps, k, loc, opt, slope, shadow_mode, log_w):
    """Exact-backscatter σ⁰ (2, 2, n): the closed-form terms of
    :func:`emscatter.solvers.iem.terms.backscatter_terms`, two components (Kirchhoff, lower medium)
    plus the
    n = 1 terms; hh and vv only (single-scattering cross-pol vanishes in the plane). The 1992
    model (``"fung92"``): Kirchhoff plus one complementary component of base ``cosθ``
    (:func:`emscatter.solvers.iem.terms.fung92_backscatter_terms`), no n = 1 terms."""
    f92 = opt.complementary == "fung92"
    n = loc.n
    ks = k * rough.sigma
    ks2 = ks * ks
    pec = is_pec(eps)
    spec = iem_jit.spectrum_code(rough) if iem_jit.enabled() else None
    if spec is not None and (pec or np.ndim(eps) == 0):  # compiled, end to end
        return _compiled(rough, eps, k, loc, opt, slope, shadow_mode, spec)
    K, pref = _spectral_args(rough, k, loc, n)
    shadow = _shadowing(shadow_mode, loc, slope)
    with np.errstate(divide="ignore"):
        pref = pref + np.log(np.broadcast_to(shadow, (n,)))
    si, cs = np.broadcast_to(loc.si, (n,)), np.broadcast_to(loc.ci, (n,))
    eps_f = eps if (pec or np.ndim(eps) == 0) else np.broadcast_to(eps, (n,))
    rh, rv = fresnel_cos(eps_f, cs)
    if f92:  # one component of base cosθ and exponent −σ²cos²θ: a_p = cosθ (a = 0), no α⁻
        u_h = u_v = 0j
        g_h92, g_v92 = kern.fung92_backscatter_terms(si, cs, eps_f)
        lower = (g_h92, g_v92, cs, 0.0 * cs, 0.0 * cs, cs)
    else:
        (u_h, u_v), lower = kern.backscatter_terms(si, cs, eps_f, rh, rv, phase=opt.complementary)
    # components: Kirchhoff (base 2 kz), the lower-medium α⁺, α⁻ terms, (and d at n = 1)
    e_k = -2.0 * ks2 * cs * cs
    bases = [2.0 * cs]
    e_list = [e_k]
    if lower is not None:
        gp_h, gp_v, a_p, gm_h, gm_v, a_m = lower
        e_g = -ks2 * ((a_p - cs) ** 2 + cs * cs)  # a_p − cs: the lower-medium phase
        bases += [a_p, a_m]
        e_list += [e_g, e_g]
    J = len(bases)
    lx = np.empty((n, J))
    sx = np.empty((n, J))
    for j, x in enumerate(bases):
        x = np.broadcast_to(x, (n,))
        with np.errstate(divide="ignore"):
            lx[:, j] = np.log(np.abs(x))
        sx[:, j] = np.where(x < 0, -1.0, 1.0)
    log_ks2 = 2.0 * math.log(ks)
    log_rtol = math.log(opt.rtol)
    # orders: enough for every component whose mass bound is relevant (as in iem_series)
    mass = [np.log(4.0 * np.maximum(np.abs(rh), np.abs(rv)) + 1e-300) * 2 + 2 * e_k]
    if lower is not None:
        for gh, gv in ((gp_h, gp_v), (gm_h, gm_v)):
            mass.append(2 * (np.log(np.maximum(np.abs(gh), np.abs(gv)) + 1e-300) + e_g))
    q_all = np.exp(log_ks2 + 2.0 * lx)
    mass = np.stack(mass, axis=1) + q_all
    relevant = mass >= np.max(mass, axis=1, keepdims=True) + log_rtol - 10.0
    q_size = np.max(np.where(relevant & np.isfinite(lx), q_all, 0.0), axis=1)
    N = int(np.max(iem_series_orders(q_size, log_rtol))) + 2 if n else 2
    if N > opt.max_terms:
        raise RuntimeError(_too_many(opt.rtol, opt.max_terms, N, log_ks2))
    table = orders_table(log_ks2, log_w, K, N)
    # transition (Wu et al. 2001, Q = (kσ)²: terms.py): its own sums S(βQ), β = 1, 2, 4
    if opt.fresnel == "transition" and not pec:
        g_h, g_v = kern.transition_factor(eps_f, cs, ks, log_w, K, rtol=opt.rtol * 1e-2)
        rh0, rv0 = fresnel_cos(eps_f, np.ones(1))
        rh_t, rv_t = rh + (rh0 - rh) * g_h, rv + (rv0 - rv) * g_v
    else:
        g_h = g_v = 0.0
        rh_t, rv_t = rh, rv
    amps = [(-4.0 * rh_t, 4.0 * rv_t)]
    if lower is not None:
        f = 1.0 - g_v if opt.complementary == "aiem-faded" else 1.0
        amps += [(gp_h * f, gp_v * f), (gm_h * f, gm_v * f)]
    la = np.empty((2, n, J))
    ph = np.empty((2, n, J), dtype=complex)
    for j, amp in enumerate(amps):
        for p in (0, 1):
            a = np.broadcast_to(amp[p], (n,))
            m = np.abs(a)
            with np.errstate(divide="ignore"):
                la[p, :, j] = np.log(m) + e_list[j]
            ph[p, :, j] = np.where(m > 0, a / np.where(m > 0, m, 1.0), 1.0)
    d = np.stack([u_h * np.exp(e_k), u_v * np.exp(e_k)])
    prefs = np.broadcast_to(pref, (n,))
    log_s = np.empty((2, n))
    log_prec = np.empty((2, n))
    for p in (0, 1):
        ls, ok, lp = direct_sum(table, la[p], lx, ph[p], sx, d[p], prefs, log_rtol, log_ks2,
                                float(np.max(log_w(np.ones(1), np.zeros(1)))))  # fmt: skip
        if not np.all(ok):
            bad = np.nonzero(~ok)[0]
            ls[bad], lp[bad] = iem_series(
                la[p][bad], lx[bad], ph[p][bad], sx[bad], d[p][bad], log_ks2, log_w, K[bad],
                prefs[bad], rtol=opt.rtol, max_terms=opt.max_terms,
            )  # fmt: skip
        log_s[p], log_prec[p] = ls, lp
    s = np.exp(log_s)
    sig = np.zeros((2, 2, n))
    sig[0, 0], sig[1, 1] = s
    return sig, 0.0, float(np.max(log_prec)) if n else -np.inf


def _compiled(rough, eps, k, loc, opt, slope, shadow_mode, spec):
    """:func:`_backscatter`'s compiled branch (one ε, a covered spectrum ``spec``):
    ``(σ⁰ (2, 2, n), 0, log precision)``."""
    n = loc.n
    ks = k * rough.sigma
    K, pref = _spectral_args(rough, k, loc, n)
    shadow = _back_shadow_args(shadow_mode, loc, slope)
    if shadow[0] < 0:
        pref = pref + np.log(iem_jit.flat_n(_shadowing(shadow_mode, loc, slope), n))  # > 0
        shadow = (0, 0.0, shadow[2])
    s_hh, s_vv, lp, status = iem_jit.backscatter(
        iem_jit.flat_n(loc.si, n), iem_jit.flat_n(loc.ci, n), eps, ks, K, pref, spec,
        rough.dimension,
        transition=opt.fresnel == "transition", rtol=opt.rtol, max_terms=opt.max_terms,
        shadow=shadow, threads=opt.threads, lower_q2=opt.complementary == "aiem",
        fade=opt.complementary == "aiem-faded", fung92=opt.complementary == "fung92",
    )  # fmt: skip
    if status:
        raise RuntimeError(_too_many(opt.rtol, opt.max_terms, opt.max_terms, 2 * math.log(ks)))
    sig = np.zeros((2, 2, n))
    sig[0, 0], sig[1, 1] = s_hh, s_vv
    return sig, 0.0, float(np.max(lp)) if n else -np.inf


def _table_sum(table, log_c2):
    """``log Σₙ exp(table[:, n] + n log_c2)`` (row-wise, n from 1)."""
    n = np.arange(1.0, table.shape[1] + 1.0)
    with np.errstate(invalid="ignore"):
        t = table + n[None, :] * np.asarray(log_c2)[:, None]
    t = np.where(np.isnan(t), -np.inf, t)
    top = np.max(t, axis=1)
    top = np.where(np.isfinite(top), top, 0.0)
    return top + np.log(np.exp(t - top[:, None]).sum(axis=1))
