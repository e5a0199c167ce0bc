"""First-order small-perturbation transmission through a slightly rough dielectric interface.

The transmitted counterpart of the reflection SPM (:mod:`.first_order`, :mod:`.second_order`):
the small-roughness end of the BTDF (fine polish on glass, plastic coats, calm water), where
GO and PO (:mod:`emscatter.solvers.kirchhoff.transmission`) do not hold.

Fields. Surface ``z = f(x, y)`` between vacuum (``z > 0``, wavenumber ``k``) and a dielectric
of relative permittivity ``ε`` (``z < 0``, ``k₂ = ηk``, ``η = √ε``), lossless or absorbing
(``Im ε > 0``; ``exp(−iωt)``, a negative ``Im ε`` is a ConventionError).
Expanding the fields in powers of ``f`` (Rice 1951) and the tangential boundary conditions
``n̂ × [E] = n̂ × [H] = 0`` at ``z = f`` about ``z = 0``, the first-order fields are one
up-going plane wave (amplitudes ``a_h, a_v``) and one down-going plane wave in the dielectric
(``b_h, b_v``) per transverse wavenumber ``k⊥ = k_i⊥ + κ``, both proportional to the height
spectrum ``F(κ)``, driven by the source ``−f ∂z[E⁽⁰⁾]_t + ∇f [E⁽⁰⁾_z]`` (and the same for ``H``).
The 4 × 4 system per ``k⊥`` is that of :func:`.second_order._solve_up` (mirrored here,
broadcast over ``θi``); its closed forms are the first-order transmitted amplitudes of
Johnson, JOSA A 16 (1999) 2720 (its first-order solution: the fields in both media; the TE
one, ``|b_hh| = 2k₁zi k²|ε − 1||cos Δφ| / |(k₁z + k₂z)(k₁zi + k₂zi)|``, is tested), Tsang,
Kong & Ding, *Scattering of Electromagnetic Waves* vol. III (2001) ch. 4 (second-order SPM,
energy conservation) and Ulaby, Moore & Fung 1982 vol. II §12-5 (the reflected first order).
Amplitudes are E-field amplitudes on emscatter's h/v bases of the transmitted direction
(``ĥ = ẑ × k̂/|ẑ × k̂|``, ``v̂ = ĥ × k̂``: :mod:`emscatter.conventions`).

Transmitted quantity and directions (lossless and absorbing alike). The transmitted power is
the time-averaged flux through the mean plane ``z = 0⁻`` per unit area, per real, conserved
transverse wavenumber ``k⊥``; each wave has ``k₂z = √(k₂² − k⊥²)``, ``Im k₂z ≥ 0`` (Tsang,
Kong & Ding vol. III ch. 4 and Johnson 1999 for the lossless balance; the flux of an
inhomogeneous plane wave as Born & Wolf §14.2, Chew 1990 §2.1). In an absorbing medium a
wave has no real unit direction (its phase and amplitude planes differ), so the direction is
*defined* by ``k⊥``: ``sinθt = |k⊥| / Re k₂`` (``k_t⊥ = Re η k sinθt (cosφt, sinφt)``) — the
refraction law with the real index ``Re η`` that renderers and ray tracers use, continuous in
``Im ε → 0`` (where it is the usual direction), and ``d²k⊥ = (Re k₂)² cosθt dΩ_t`` exactly.
Waves with ``|k⊥| > Re k₂`` (evanescent when lossless) then carry flux too (``Re k₂z > 0``):
:func:`diffuse_transmissivity` returns that part (``T_beyond``) beside the hemisphere's. The
flux of a unit h wave is ``Re k₂z``, of a unit v wave ``|ε| Re(k₂z/ε)`` (:func:`flux_factors`;
TM differs from TE), against ``k₁zi`` incident; with ``⟨|F|²⟩ = σ² w(κ) d²κ``::

    σ⁰_t,pq = 4π σ² |b_pq|² w(k_t⊥ − k_i⊥) (Re k₂)² cosθt f_p / k,
    f_h = Re k₂z,  f_v = |ε| Re(k₂z/ε)        (lossless: 4π η³ k² cos²θt σ² |b_pq|² w)

so that ``T = ∫ σ⁰_t / (4π cosθi) dΩ_t`` as for PO and GO.

(``b`` per unit ``F(κ)``, ``w`` the normalized spectrum of :mod:`emscatter.spectra`). The
coherent transmissivity to second order (mean field ``T⁽⁰⁾ + T⁽²⁾``, :func:`.second_order.
_second_order_R` with ``transmitted=True``; the evanescent part of the ``k⊥`` integral
included)::

    T_coh,p = (|T⁽⁰⁾_p|² + 2 σ² Re(T⁽⁰⁾*_p T⁽²⁾_p/σ²)) f_p(k_i⊥) / k₁zi

so that ``R_coh + R_diff + T_coh + T_diff = 1`` for a lossless dielectric to ``O((kσ)²)``,
the remainder ``O((kσ)⁴)`` (tested: ``tests/test_btdf_spm.py``). Absorbing: the flux through
the mean plane differs from the flux through the rough interface (``1 − R``) by the power
absorbed between the two, ``O((kσ)² Im ε)`` and of either sign (:func:`layer_absorption`):
``R_coh + R_diff + T_coh + T_diff + T_beyond + A = 1`` (tested to ≤ 5e-8 at kσ = 0.1, the
lossless test's quadrature precision, ``tests/test_spm_transmission_lossy.py``; without
``A`` it misses by up to 1.2e-2 at ε = 4 + 4i). What is absorbed below ``z = 0`` (all of
``T`` for a half space, a slab's share otherwise) is the caller's.

Reciprocity: ``σ⁰_t,pq(ε, k; k̂_i → k̂_t) = ε σ⁰_t,qp(1/ε, ηk; −k̂_t → −k̂_i)`` (as PO's; the
radiance BTDF's η² factor of Walter et al. 2007 eq. 21). ``ε < 1`` is light from the denser
side (total internal reflection of the coherent part beyond the critical angle).

Validity: that of the reflection SPM (:func:`emscatter.solvers.spm.validity.check_validity`:
``kσ ≤ 0.3``, rms slope ≤ 0.3, the per-angle scattered fraction); ``out_of_range`` applies it.
"""

from __future__ import annotations

import math

import numpy as np

from emscatter.conventions import check_positive
from emscatter.scattering import Scattering
from emscatter.solvers.kirchhoff.transmission.go import (
    OUT_OF_RANGE,
    check_lossy_transmission_eps,
    transmission_angles,
    transmission_policy,
)
from emscatter.solvers.spm.second_order import _second_order_R
from emscatter.solvers.spm.validity import check_validity
from emscatter.spectra import Roughness

__all__ = [
    "bistatic_transmission",
    "coherent_transmissivity",
    "transmission_amplitudes",
    "flux_factors",
    "diffuse_transmissivity",
    "OUT_OF_RANGE",
    "SPMWarning",
]


class SPMWarning(UserWarning):
    """SPM transmission used outside the small-perturbation method's validity."""


def _kz(k2, kperp2):
    """√(k² − k⊥²) with Im ≥ 0 (decaying branch)."""
    r = np.sqrt(np.asarray(k2 - kperp2, dtype=complex))
    return np.where(r.imag < 0, -r, r)


def flux_factors(eps, k: float, kperp) -> np.ndarray:
    """Downward power flux through the plane ``z = 0⁻`` of a unit-amplitude h and v wave of
    real transverse wavenumber ``kperp`` [rad/m] in the lower medium, in units of the flux
    ``k₁z`` of a unit wave in vacuum per unit ``k₁z``: ``(2, ...)`` = ``(Re k₂z,
    |ε| Re(k₂z/ε))`` [rad/m], ``k₂z = √(εk² − k⊥²)`` (Im ≥ 0).

    The time-averaged Poynting vector ``½ Re(E × H*)·(−ẑ)`` of an inhomogeneous plane wave
    with ``E = b ĥ`` (TE) is ``|b|² Re k₂z / (2ωμ₀)``; with ``H̃ = ωμ₀H = k₂ b ĥ`` (TM, the
    amplitude convention of :func:`transmission_amplitudes`) it is ``|b|² |ε| Re(k₂z/ε) /
    (2ωμ₀)`` (Born & Wolf §1.5.3 and §14.2 for absorbing media; Chew, *Waves and Fields in
    Inhomogeneous Media*, 1990, §2.1). TE and TM fields of one ``k⊥`` carry no cross flux
    (``(k × ĥ) × (k* × ĥ) ∥ ĥ`` is horizontal). Lossless: both ``k₂z`` (0 for evanescent
    waves)."""
    e = np.asarray(eps, dtype=complex)
    kz2 = _kz(e * k * k, np.asarray(kperp, dtype=float) ** 2)
    return np.stack(np.broadcast_arrays(kz2.real, (np.abs(e) * (kz2 / e)).real))


def _plane_wave(km, cx, cy, K, amp_h, amp_v, qz):
    """E and H̃ = q × E (Cartesian, each a 3-tuple) of a plane wave of transverse direction
    (cx, cy), |k⊥| = K, vertical wavenumber qz, medium wavenumber km, h/v amplitudes."""
    hx, hy = -cy, cx
    vx, vy, vz = cx * qz / km, cy * qz / km, -K / km
    e = (amp_h * hx + amp_v * vx, amp_h * hy + amp_v * vy, amp_v * vz)
    h = (km * (amp_v * hx - amp_h * vx), km * (amp_v * hy - amp_h * vy), -km * amp_h * vz)
    return e, h


def transmission_amplitudes(eps, k: float, theta_i, kx, ky) -> np.ndarray:
    """First-order transmitted E amplitudes ``b[pol_t, pol_i]`` ``(2, 2, ...)`` (complex,
    per unit height spectrum ``F(κ)`` [1/m]) of the down-going wave of transverse wavenumber
    ``(kx, ky)`` [rad/m] for unit incident h/v waves at ``theta_i`` [rad] (``φi = 0``),
    emscatter's h/v bases (module docstring; for a complex ``k₂`` the v amplitude is that of
    ``H̃ = ωμ₀H = k₂ b ĥ``); arguments broadcast, ``eps`` complex, ``Im ε ≥ 0``.

    The source ``S = ∂z[J⁽⁰⁾]_t + iκ [J⁽⁰⁾_z]`` is linear in ``κ``: its two coefficients
    depend on the incidence only and are computed once per distinct (θi, ε)."""
    eps = np.asarray(eps, dtype=complex)
    ti = np.asarray(theta_i, dtype=float)
    kx, ky = np.asarray(kx, dtype=float), np.asarray(ky, dtype=float)
    shape = np.broadcast_shapes(eps.shape, ti.shape, kx.shape, ky.shape)
    e_f = np.broadcast_to(eps, shape).reshape(-1)
    t_f = np.broadcast_to(ti, shape).reshape(-1)
    if e_f.size and np.all(e_f == e_f[0]):  # one medium: the distinct incidence angles
        t_u, inv = np.unique(t_f, return_inverse=True)
        e_u, e_big = e_f[:1], e_f[0]
    else:
        t_u, inv, e_u, e_big = t_f, slice(None), e_f, e_f.reshape(shape)
    src = _incidence_source(e_u, k, t_u)  # (2 pols, 6 coefficients, n_u)
    src = src[:, :, inv].reshape(2, 6, *shape)
    kx, ky = np.broadcast_to(kx, shape), np.broadcast_to(ky, shape)
    kix = k * np.broadcast_to(np.sin(ti), shape)
    k2 = e_big * k * k
    k2m = np.sqrt(e_big) * k
    Kn = np.hypot(kx, ky)
    safe = np.where(Kn == 0, 1.0, Kn)
    cxn, cyn = np.where(Kn == 0, 1.0, kx / safe), np.where(Kn == 0, 0.0, ky / safe)
    kap_x, kap_y = kx - kix, ky
    k1zn, k2zn = _kz(k * k, Kn * Kn), _kz(k2, Kn * Kn)
    out = np.empty((2, 2, *shape), dtype=complex)
    for p in (0, 1):  # incident polarization (h, v), not an angle loop
        ax, ay, bz, hx, hy, hz = src[p]
        se = (ax + 1j * kap_x * bz, ay + 1j * kap_y * bz)
        sh = (hx + 1j * kap_x * hz, hy + 1j * kap_y * hz)
        se_c = se[0] * cxn + se[1] * cyn
        se_h = -se[0] * cyn + se[1] * cxn
        sh_c = sh[0] * cxn + sh[1] * cyn
        sh_h = -sh[0] * cyn + sh[1] * cxn
        # the system of second_order._solve_up: up-going a, down-going b
        a_h = (sh_c - k2zn * se_h) / (k1zn + k2zn)
        a_v = -(e_big * k * se_c + k2zn * sh_h / k) / (e_big * k1zn + k2zn)
        out[0, p] = a_h + se_h
        out[1, p] = (k * a_v + sh_h) / k2m
    return out


def _incidence_source(eps, k, ti) -> np.ndarray:
    """Coefficients ``(2, 6, n)`` of the first-order source per incident polarization:
    ``S_E,x = A_x + iκ_x B``, ``S_E,y = A_y + iκ_y B`` (``A = Σ ±i q_z E_t``, ``B = Σ ± E_z``
    over the incident, reflected and transmitted zeroth-order waves at ``z = 0``), the same
    three for ``H̃``; ``eps``, ``ti`` 1-D (n,)."""
    si, ci = np.sin(ti), np.cos(ti)
    kix, k1zi = k * si, k * ci
    k2m = np.sqrt(eps) * k
    k2zi = _kz(eps * k * k, kix * kix)
    rh0 = (k1zi - k2zi) / (k1zi + k2zi)
    rv0 = (eps * k1zi - k2zi) / (eps * k1zi + k2zi)
    one, zero = np.ones_like(ci), np.zeros_like(ci)
    out = np.zeros((2, 6, ci.size), dtype=complex)
    for p in (0, 1):
        inc = (one, zero) if p == 0 else (zero, one)
        ref = (rh0, zero) if p == 0 else (zero, rv0)
        tra = (1.0 + rh0, zero) if p == 0 else (zero, (1.0 + rv0) / np.sqrt(eps))
        waves = (
            (*_plane_wave(k, one, zero, kix, *inc, -k1zi), -k1zi, 1.0),
            (*_plane_wave(k, one, zero, kix, *ref, k1zi), k1zi, 1.0),
            (*_plane_wave(k2m, one, zero, kix, *tra, -k2zi), -k2zi, -1.0),
        )
        for E, H, qz, sg in waves:
            out[p] += sg * np.stack(
                [1j * qz * E[0], 1j * qz * E[1], E[2], 1j * qz * H[0], 1j * qz * H[1], H[2]]
            )
    return out


def _rotated(rough: Roughness, eps, k, ti, tt, pt, pi_):
    """Transverse wavenumbers of the transmitted directions in the ``φi = 0`` frame and the
    spectrum ``w`` at ``κ`` in the surface's axes."""
    eta = np.sqrt(eps).real  # the transmitted direction: sinθt = k⊥ / (Re k₂)
    d = pt - pi_
    kt = eta * k * np.sin(tt)
    kx, ky = kt * np.cos(d), kt * np.sin(d)
    dx, dy = kx - k * np.sin(ti), ky
    if not rough.is_isotropic:  # the φi = 0 frame → surface axes
        c, s = np.cos(pi_), np.sin(pi_)
        dx, dy = c * dx - s * dy, s * dx + c * dy
    return kx, ky, rough.spectrum(dx, dy)


def _check(roughness, eps, k, theta_i, theta_t, phi_t, phi_i):
    if not isinstance(roughness, Roughness):
        raise TypeError(f"roughness must be an emscatter.spectra.Roughness, got {roughness!r}")
    if roughness.dimension != 2:
        raise ValueError("SPM transmission needs a 2-D surface (dimension=2), got a 1-D profile")
    k = check_positive("k", k, unit="rad/m")
    e = check_lossy_transmission_eps(eps, "SPM")
    arrs = transmission_angles(e, eps, theta_i, theta_t, phi_t, phi_i)
    return k, arrs


def jones(roughness, eps, k, theta_i, theta_t, phi_t, phi_i=0.0) -> np.ndarray:
    """Transmission Jones matrices ``J[pol_t, pol_i]`` ``(2, 2, ...)`` (complex, emscatter's
    h/v bases) with ``|J_pq|² = σ⁰_t,pq`` (the amplitude products of the Mueller BTDF:
    ``b_pq √(4π η³ k² cos²θt σ² w)``); angles [rad], ``k`` [rad/m], as
    :func:`bistatic_transmission`."""
    k, (ti, tt, pt, pi_, e) = _check(roughness, eps, k, theta_i, theta_t, phi_t, phi_i)
    kx, ky, w = _rotated(roughness, e, k, ti, tt, pt, pi_)
    b = transmission_amplitudes(e, k, ti, kx, ky)
    re_k2 = np.sqrt(e).real * k
    flux = flux_factors(e, k, np.hypot(kx, ky))[:, None]  # per transmitted polarization
    scale = 4 * math.pi * roughness.sigma**2 * w * re_k2**2 * np.cos(tt) * flux / k
    # the h/v bases (ẑ × k̂) turn with the frame: the φi = 0 amplitudes hold in any frame
    return b * np.sqrt(np.maximum(scale, 0.0))


def coherent_transmissivity(roughness, eps, k: float, theta_i, phi_i=0.0) -> np.ndarray:
    """Coherent transmissivity ``(2, ...)`` [-] (h, v) to second order in ``kσ`` at
    incidence ``theta_i`` [rad] (module docstring; 0 beyond the critical angle for
    ``ε < 1``). ``k``: the incident medium's wavenumber [rad/m]; ``phi_i`` [rad] matters for
    an anisotropic surface only."""
    k, (ti, _, _, pi_, e) = _check(roughness, eps, k, theta_i, 0.0, 0.0, phi_i)
    if roughness.is_isotropic:
        pi_ = np.zeros_like(pi_)
    out = np.zeros((2, *ti.shape))
    keys = np.stack([ti.ravel(), pi_.ravel(), e.real.ravel(), e.imag.ravel()])
    uniq, inv = np.unique(keys, axis=1, return_inverse=True)
    vals = np.empty((2, uniq.shape[1]))
    e_u = uniq[2] + 1j * uniq[3]
    s2 = roughness.sigma**2
    for ev in np.unique(e_u):  # one medium per call (the second-order nodes depend on it)
        m = e_u == ev
        t_u, p_u = uniq[0, m], uniq[1, m]
        _, _, T0, T2 = _second_order_R(
            roughness, np.complex128(ev), k, t_u, 16, 16, transmitted=True, phi_i=p_u
        )
        k1zi = k * np.cos(t_u)
        flux = flux_factors(ev, k, k * np.sin(t_u))  # (Re k₂zi, |ε| Re(k₂zi/ε))
        t = (np.abs(T0) ** 2 + 2 * s2 * (np.conj(T0) * T2).real) * flux / k1zi
        vals[:, m] = np.clip(t, 0.0, 1.0)
    out[:] = vals[:, inv.reshape(-1)].reshape(2, *ti.shape)
    return out


def _gl(n, a, b, cluster=False):
    """Gauss–Legendre nodes and weights on [a, b]; ``cluster``: through ``x = a + (b − a)
    (1 − cos u)/2`` (dense at both ends: removes the square-root kinks of ``k_z`` there)."""
    x, w = np.polynomial.legendre.leggauss(n)
    if not cluster:
        return 0.5 * (b - a) * x + 0.5 * (b + a), 0.5 * (b - a) * w
    u, wu = 0.5 * math.pi * (x + 1), 0.5 * math.pi * w
    return a + 0.5 * (b - a) * (1 - np.cos(u)), wu * 0.5 * (b - a) * np.sin(u)


def _check_quadrature(roughness, eps, k, theta_i, phi_i, n, kappa_max):
    """The checked ``(k, theta_i, phi_i, eps, kappa_max)`` of the flux quadratures
    (:func:`diffuse_transmissivity`, :func:`layer_absorption`; ``n`` an integer ≥ 4, the
    default ``kappa_max = 16/ℓ_min`` [rad/m])."""
    if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 4:
        raise ValueError(f"n must be an integer >= 4 (quadrature nodes), got {n!r}")
    k, (ti, _, _, pi_, e) = _check(roughness, eps, k, theta_i, 0.0, 0.0, phi_i)
    if kappa_max is None:
        kappa_max = 16.0 / min(roughness.length, roughness.length_y or roughness.length)
    kappa_max = check_positive("kappa_max", kappa_max, unit="rad/m")
    return k, ti, pi_, e, kappa_max


def diffuse_transmissivity(
    roughness, eps, k: float, theta_i, phi_i=0.0, *, n: int = 48, kappa_max=None
) -> tuple[np.ndarray, np.ndarray]:
    """Diffuse (first-order) transmitted flux through ``z = 0⁻`` per incident polarization
    ``(2, ...)`` [-] (summed over the transmitted ones) at ``theta_i`` [rad]:
    ``(T_diff, T_beyond)``.

    ``T_diff = ∫ σ⁰_t dΩ_t / (4π cosθi)`` over the directions of :func:`bistatic_transmission`
    (``sinθt = k⊥/Re k₂`` ≤ 1); ``T_beyond`` the flux of the waves with ``k⊥ > Re k₂``, which
    an absorbing medium carries too (``Re k₂z > 0``; 0 for a lossless one, where they are
    evanescent): ``∫ d²k⊥ σ² w(κ) Σ_p |b_pq|² f_p / k₁zi`` (:func:`flux_factors`) up to
    ``|κ| ≤ kappa_max`` (default ``16/ℓ_min``: the Gaussian spectrum is ``e⁻⁶⁴`` there; pass a
    larger value for slowly decaying spectra). ``R_coh + R_diff + T_coh + T_diff + T_beyond``
    is the energy budget (module docstring). Gauss–Legendre, ``2n × n`` and ``n × n`` nodes
    (split at the branch circles ``|k⊥| = k``, ``Re k₂``)."""
    k, ti, pi_, e, kappa_max = _check_quadrature(roughness, eps, k, theta_i, phi_i, n, kappa_max)
    shape = ti.shape
    ti, pi_, e = (a.reshape(-1, 1, 1) for a in (ti, pi_, e))
    re_eta = np.sqrt(e).real
    out = np.zeros((2, 2, ti.shape[0]))
    p, wp = _gl(n, 0.0, 2 * math.pi)
    for j in range(ti.shape[0]):  # per medium and incidence (the kinks move); vectorized inside
        eta, sl = float(re_eta[j, 0, 0]), slice(j, j + 1)
        if eta > 1:  # the vacuum branch circle |k⊥| = k inside the transmitted cone
            (a, wa), (b, wb) = (
                _gl(n, 0.0, math.asin(1 / eta)),
                _gl(n, math.asin(1 / eta), 0.5 * math.pi),
            )
            t, wt = np.r_[a, b], np.r_[wa, wb]
        else:
            t, wt = _gl(2 * n, 0.0, 0.5 * math.pi)
        tt, pt = np.meshgrid(t, p, indexing="ij")
        jj = jones(roughness, e[sl], k, ti[sl], tt, pt + pi_[sl], pi_[sl])
        dom = np.outer(wt * np.sin(t), wp)
        out[0, :, j] = (np.abs(jj[:, :, 0]) ** 2 * dom).sum(axis=(0, -1, -2))
        out[0, :, j] /= 4 * math.pi * math.cos(float(ti[j, 0, 0]))
        if abs(e[j, 0, 0].imag) == 0:
            continue  # lossless: the waves beyond are evanescent
        kix = k * math.sin(float(ti[j, 0, 0]))
        kk, _, kx, ky, wgt = _plane_nodes(k, eta, kix, kappa_max, n, eta * k)
        w = _spectrum_frame(roughness, kx, ky, kix, float(pi_[j, 0, 0]))
        b = transmission_amplitudes(e[j, 0, 0], k, float(ti[j, 0, 0]), kx, ky)
        f = flux_factors(e[j, 0, 0], k, kk)[:, None]
        dens = roughness.sigma**2 * w * np.abs(b) ** 2 * f / (k * math.cos(float(ti[j, 0, 0])))
        out[1, :, j] = (dens * wgt).sum(axis=(0, -1, -2))
    return out[0].reshape(2, *shape), out[1].reshape(2, *shape)


def _plane_nodes(k, eta, kix, kappa_max, n, start):
    """Polar nodes ``(|k⊥|, φ, kx, ky, d²k⊥ weights)`` from ``|k⊥| = start`` to
    ``max(k, Re k₂) + k_i⊥ + kappa_max``, split and clustered at the branch circles."""
    top = max(k, eta * k) + kix + kappa_max
    cuts = sorted({c for c in (start, k, eta * k, top) if c >= start})
    nodes = [_gl(n, a, b, cluster=True) for a, b in zip(cuts[:-1], cuts[1:], strict=False)]
    kr, wk = np.concatenate([q[0] for q in nodes]), np.concatenate([q[1] for q in nodes])
    p, wp = _gl(n, 0.0, 2 * math.pi)
    kk, pp = np.meshgrid(kr, p, indexing="ij")
    return kk, pp, kk * np.cos(pp), kk * np.sin(pp), np.outer(wk * kr, wp)


def _spectrum_frame(roughness, kx, ky, kix, phi_i):
    """The spectrum ``w`` at ``κ = k⊥ − k_i⊥`` (``φi = 0`` frame → surface axes)."""
    dx, dy = kx - kix, ky
    if not roughness.is_isotropic:
        c, s_ = math.cos(phi_i), math.sin(phi_i)
        dx, dy = c * dx - s_ * dy, s_ * dx + c * dy
    return roughness.spectrum(dx, dy)


def layer_absorption(
    roughness, eps, k: float, theta_i, phi_i=0.0, *, n: int = 48, kappa_max=None
) -> np.ndarray:
    """Power absorbed between the rough interface and the mean plane ``z = 0`` (signed:
    the dielectric above ``z = 0`` where ``f > 0`` adds, the continued field in ``f < z < 0``
    subtracts), per incident polarization ``(2, ...)`` [-] to ``O((kσ)²)``, at ``theta_i``
    [rad]. It is what separates the flux through the mean plane (``T_coh``, σ⁰_t) from the
    flux through the interface (``1 − R``) in an absorbing medium; 0 when lossless.

    Poynting's theorem between the two surfaces, the absorbed density ``½ωε₀ Im ε |E|²``
    over the incident flux ``k₁zi |E_i|² / (2ωμ₀)``::

        A = k² Im ε / k₁zi · ⟨∫₀^f |E₀ + E₁|² dz⟩
          = k² Im ε / k₁zi · σ² [Im k₂zi |E₀(0)|² + 2 Re(E₀(0)* · ∫ w(κ) E₁(κ) d²κ)]

    (``⟨f⟩ = 0``, ``⟨f²⟩ = σ²``, ``|E₀(z)|² ∝ e^{2 Im k₂zi z}``, ``⟨f E₁⟩ = σ² ∫ w b ê d²κ``
    with ``b`` of :func:`transmission_amplitudes` and ``ê`` its h/v field vectors), the
    ``k⊥`` integral over the whole plane (propagating, inhomogeneous and evanescent waves;
    ``kappa_max`` and ``n`` as :func:`diffuse_transmissivity`). Tested: ``R_coh + R_diff +
    T_coh + T_diff + T_beyond + A = 1`` to the quadrature's precision
    (``tests/test_spm_transmission_lossy.py``)."""
    k, ti, pi_, e, kappa_max = _check_quadrature(roughness, eps, k, theta_i, phi_i, n, kappa_max)
    shape = ti.shape
    out = np.zeros((2, ti.size))
    for j, (th, ph, ev) in enumerate(zip(ti.ravel(), pi_.ravel(), e.ravel(), strict=True)):
        if ev.imag == 0:  # per medium and incidence (the kinks move); vectorized inside
            continue
        kix, k1zi, km = k * math.sin(th), k * math.cos(th), np.sqrt(ev) * k
        kk, pp, kx, ky, wgt = _plane_nodes(k, km.real / k, kix, kappa_max, n, 0.0)
        w = _spectrum_frame(roughness, kx, ky, kix, ph)
        b = transmission_amplitudes(ev, k, th, kx, ky)  # (pol_t, pol_i, ...)
        cx, cy, k2z = np.cos(pp), np.sin(pp), _kz(ev * k * k, kk * kk)
        eh = (-cy, cx, np.zeros_like(cx))
        ev_ = (-cx * k2z / km, -cy * k2z / km, -kk / km)
        k2zi = complex(_kz(ev * k * k, kix * kix))
        rh0 = (k1zi - k2zi) / (k1zi + k2zi)
        rv0 = (ev * k1zi - k2zi) / (ev * k1zi + k2zi)
        tv = (1 + rv0) / np.sqrt(ev)
        e0 = ((0.0, 1 + rh0, 0.0), (-tv * k2zi / km, 0.0, -tv * kix / km))
        for p in (0, 1):  # incident polarization
            cross = sum(
                np.conj(e0[p][c]) * ((b[0, p] * eh[c] + b[1, p] * ev_[c]) * w * wgt).sum()
                for c in range(3)
            )
            mean = k2zi.imag * sum(abs(x) ** 2 for x in e0[p])
            out[p, j] = roughness.sigma**2 * (mean + 2 * cross.real)
        out[:, j] *= k * k * ev.imag / k1zi
    return out.reshape(2, *shape)


def bistatic_transmission(
    roughness, eps, k: float, theta_i, theta_t, phi_t, phi_i=0.0, *, out_of_range: str = "warn"
) -> Scattering:
    """First-order SPM bistatic transmission coefficients σ⁰_t ``[pol_t, pol_i]`` [-] and the
    second-order coherent transmissivity (module docstring).

    Parameters
    ----------
    roughness : a 2-D :class:`~emscatter.spectra.Roughness` (lengths [m]).
    eps : relative permittivity of the lower medium to the upper: complex with ``Im ε ≥ 0``
        (absorbing) or real (> 0, ≠ 1).
    k : wavenumber of the upper (incident) medium [rad/m].
    theta_i, theta_t, phi_t, phi_i : emscatter angles [rad], numpy-broadcast (``θt`` from the
        downward normal, ``sinθt = |k⊥|/Re k₂`` (module docstring), as
        :func:`emscatter.solvers.kirchhoff.transmission.go.bistatic_transmission`).
    out_of_range : ``"warn"`` (default), ``"raise"``, ``"nan"`` (σ⁰_t and the coherent part
        NaN at the failing incidence angles, everywhere when the roughness fails) or
        ``"ignore"``; ``info["out_of_range"]`` is the mask of failing angles in every case.

    Returns
    -------
    :class:`~emscatter.scattering.Scattering`: ``sigma0`` (2, 2, *shape), ``coherent``
    (2, *shape) the coherent transmissivity (a delta lobe at the refracted direction),
    ``theta_s``/``phi_s`` holding ``θt``/``φt``, ``info["direction"] = "transmission"``;
    ``coherent`` is computed on first read (the second-order quadrature per distinct θi).
    """
    if out_of_range not in OUT_OF_RANGE:
        raise ValueError(f"out_of_range must be one of {OUT_OF_RANGE}, got {out_of_range!r}")
    k, (ti, tt, pt, pi_, e) = _check(roughness, eps, k, theta_i, theta_t, phi_t, phi_i)
    j = jones(roughness, e, k, ti, tt, pt, pi_)
    sigma0 = np.abs(j) ** 2
    validity = check_validity(
        roughness, k, eps=complex(e.ravel()[np.argmax(np.abs(e))]), theta_i=ti
    )
    failing, bad = transmission_policy(
        validity, ti.shape, out_of_range, warning=SPMWarning,
        label="SPM transmission used outside the small-perturbation method's validity",
    )  # fmt: skip
    if np.any(bad):
        sigma0 = np.where(bad, np.nan, sigma0)
    elif not np.all(np.isfinite(sigma0)):
        raise ValueError("SPM transmission produced NaN/inf (please report the inputs)")

    def coh():  # on first read (Scattering.coherent): ~3 ms per distinct (θi, φi, ε)
        c = coherent_transmissivity(roughness, e, k, ti, pi_)
        return np.where(bad, np.nan, c)

    info = {
        "direction": "transmission",
        "directions": "sin(theta_t) = |k_perp| / Re k2 (flux through the mean plane z = 0-)",
        "absorbing": bool(np.any(e.imag != 0)),  # then T_beyond, A: diffuse_transmissivity,
        # layer_absorption close R + T + A = 1
        "validity": validity,
        "out_of_range": failing,
        "source": "first-order SPM (Rice 1951; transmitted amplitudes as Johnson, JOSA A 16, "
        "1999, 2720); coherent part to second order (Tsang, Kong & Ding 2001 vol. III ch. 4)",
    }
    return Scattering(
        sigma0=sigma0, coherent=coh, method="spm-transmission", theta_i=ti, theta_s=tt,
        phi_s=pt, phi_i=pi_, k=k, dimension=2, info=info,
    )  # fmt: skip
