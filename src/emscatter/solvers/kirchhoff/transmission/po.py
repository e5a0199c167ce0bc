"""Physical-optics (Kirchhoff) transmission through a rough dielectric interface.

The transmitted counterpart of :mod:`emscatter.solvers.kirchhoff.po`: tangent-plane fields with
the local Fresnel *transmission* coefficients at the stationary-phase facet, the scalar
Kirchhoff integral over the surface heights (Tsang, Kong & Ding, *Scattering of
Electromagnetic Waves: Theories and Applications*, 2000, §9.4 on the Kirchhoff approximation;
Tsang & Kong, *Advanced Topics*, 2001, ch. 2; Ulaby, Moore & Fung 1982 vol. II §12-4 for the
series form of the reflection, eqs. 12.52–12.55, whose structure the transmission shares).

Geometry and phase. Upper medium of wavenumber ``k₁ = k``, lower of ``k₂ = η k``, ``η = √ε``
(real: lossless). Incident ``k̂_i``, transmitted ``k̂_t`` (``θt`` from the downward normal),
as in :mod:`.go`. The Kirchhoff integral carries ``exp(i q·r)`` with ``q = k₁ k̂_i − k₂ k̂_t =
−k (i + η o)`` (``i = −k̂_i``, ``o = k̂_t``): the stationary-phase facet normal is ``ĥ ∥ q``,
Walter et al.'s generalized half vector (EGSR 2007 eq. 16), and
``q_z = −k (cosθi − η cosθt)``.

Transmission coefficient (power per unit area, ``T = ∫ σ⁰_t / (4π cosθi) dΩ_t``)::

    σ⁰_t,pq = η² k² |i·ĥ||o·ĥ| |q|² / (π q_z²) · |J_pq|² ∫ d²r e^{i q⊥·r}
                  [e^{−q_z²σ²(1−ρ(r))} − e^{−q_z²σ²}]
            = 4π η² (kσ)² (kℓx)(kℓy) |i·ĥ||o·ĥ| |w|² |J_pq|² · e^{−Q} Σ_{n≥1} Q^{n−1}/n! w_n

with ``w = i + η o`` (``|q| = k|w|``), ``Q = q_z²σ²`` and ``w_n`` the normalized spectrum of
``ρⁿ`` (:func:`emscatter.solvers.kirchhoff.po.log_nfold`, scaled wavenumber
``√((q_x ℓx)² + (q_y ℓy)²)``), summed in log space by :func:`~..po.series_sum` (no overflow at
any ``Q``; ``q_z`` cancels, so the forward direction stays finite). ``J_pq`` is the facet's
power-normalized transmission Jones matrix of :func:`.go.transmission_jones` at the
stationary-phase facet (local cosine ``i·ĥ``), rotated into emscatter's h/v bases. The
geometric prefactor is the one that makes the two limits of the Kirchhoff integral exact:

* **Flat / coherent limit.** The ``e^{−Q}`` part of the integral is ``(2π)² δ(q⊥) e^{−Q}``;
  with ``∫ δ²(q⊥) dΩ_t = 1/(k₂² cosθt)`` it gives the coherent transmissivity
  ``T_coh,p = T_F,p · exp(−σ²(k₁ cosθi − k₂ cosθt)²)`` (:func:`coherent_transmissivity`;
  ``T_F,p = 1 − |R_p|²`` Fresnel, ``sinθt = sinθi/η``), so σ → 0 gives Fresnel ``T``.
* **Stationary-phase (large kσ) limit.** ``σ²(1 − ρ) ≈ s r²/2`` (``s`` the slope variance per
  direction) turns the integral into
  ``(2π)² p(ζ)/q_z²`` with the Gaussian slope density ``p`` at the facet slope
  ``ζ = −q⊥/q_z``; then σ⁰_t is Walter et al.'s eq. 21 without shadowing
  (``4π |i·ĥ||o·ĥ| η² |J|² D(ĥ) / |i + η o|²``, ``D = p/h_z⁴``) — tested against
  :func:`.go.bistatic_transmission` (``shadowing=False``).

Absorbing lower medium (``Im ε > 0``; ``exp(−iωt)``). The transmitted quantity and the
directions are SPM's (:mod:`emscatter.solvers.spm.transmission`): flux through the mean plane
per real ``k⊥``, ``sinθt = |k⊥|/Re k₂``. The stationary-phase facet is that of the real index
``Re η`` (``w = i + Re η o``; a complex ``k₂`` has no real facet), its Fresnel transmission
lossy (``τ_p² = 1 − |R_p(ε, i·ĥ)|²``, the flux into the facet), and each transmitted
polarization carries the flux factor ``f_p / (Re k₂ cosθt)`` of SPM (``f_h = Re k₂z``,
``f_v = |ε| Re(k₂z/ε)``; 1 when lossless). The coherent transmissivity uses the complex
``q_z = k₁ cosθi − k₂z``: ``|⟨e^{i q_z f}⟩|² = exp(−σ² Re q_z²)`` for Gaussian heights, exact
Fresnel flux ``1 − |R_p|²`` when flat (tested to 1e-12 |ε|). A low-loss model: the diffuse
lobe ignores the attenuation of the tangent-plane field inside the roughness layer
(``Im q_z``); measured against the lossy SPM where both hold (kσ = 0.3, kℓ = 12–20,
ε = 4 + 0.4i) it agrees as well as lossless at ε = 4 (0.52 against 0.57 dB,
``tests/test_po_transmission_lossy.py``).

Reciprocity: ``σ⁰_t,pq(ε, k; k̂_i → k̂_t) = ε · σ⁰_t,qp(1/ε, ηk; −k̂_t → −k̂_i)`` (the
radiance BTDF's ``f(1→2)/η₂² = f(2→1)/η₁²``, Walter et al. eq. 21's η² factor); ``k`` is the
wavenumber of the medium the light comes from (free space for the usual ``ε > 1``).

Shadowing and multiple scattering are not in the Kirchhoff approximation: where they matter
(grazing incidence against the facet tilts) the transmitted σ⁰ is too large and ``R + T``
can exceed 1. Validity: that of the reflection PO (:func:`~..po.check_validity` with the
dielectric's grazing limit, per incidence angle); ``out_of_range`` applies it.
"""

from __future__ import annotations

import math

import numpy as np

from emscatter.conventions import check_angle, check_positive
from emscatter.scattering import Scattering
from emscatter.solvers.kirchhoff import compiled as kirchhoff_compiled
from emscatter.solvers.kirchhoff import po
from emscatter.solvers.kirchhoff.common import check_roughness, fast_fresnel
from emscatter.solvers.kirchhoff.transmission.go import (
    OUT_OF_RANGE,
    _dirs,
    _half,
    _jones,
    check_lossy_transmission_eps,
    transmission_angles,
    transmission_policy,
)

__all__ = ["bistatic_transmission", "coherent_transmissivity", "OUT_OF_RANGE", "POWarning"]

_BLOCK = 1 << 16


class POWarning(UserWarning):
    """PO transmission used outside the validity of the Kirchhoff approximation."""


def coherent_transmissivity(roughness, eps, k: float, theta_i) -> np.ndarray:
    """Coherent transmissivity ``(2, ...)`` [-] (h, v) at incidence ``theta_i`` [rad]:
    ``T_F,p · exp(−(kσ)² (cosθi − η cosθt)²)`` with ``sinθt = sinθi/η`` (module docstring;
    0 beyond the critical angle for a lossless ``ε < 1``; complex ``ε``: ``exp(−(kσ)² Re(cosθi −
    √(ε − sin²θi))²)``, module docstring). ``k``: the incident medium's wavenumber."""
    rough = check_roughness(roughness)
    k = check_positive("k", k, unit="rad/m")
    e = check_lossy_transmission_eps(eps, "PO")
    ti = check_angle("theta_i", theta_i)
    ti, e = np.broadcast_arrays(ti, e)
    ci = np.cos(ti)
    # q_z / k = cosθi − k₂z/k, k₂z = √(ε − sin²θi) k (Im ≥ 0; imaginary beyond the critical
    # angle of a lossless ε < 1, where T_F = 0): |⟨e^{i q_z f}⟩|² = exp(−σ² Re q_z²)
    kz2 = np.sqrt(e - (1.0 - ci * ci) + 0j)
    kz2 = np.where(kz2.imag < 0, -kz2, kz2)
    rh2, rv2, _ = fast_fresnel(e, ci, cross=False)
    att = np.exp(-((k * rough.sigma) ** 2) * ((ci - kz2) ** 2).real)
    t = np.stack([1.0 - rh2, 1.0 - rv2]) * att
    tir = (np.abs(e.imag) == 0) & ((1.0 - ci * ci) >= e.real)
    return np.where(tir, 0.0, np.clip(t, 0.0, 1.0))


def series_geometry(rough, k: float, eta, ti, tt, pt, pi_) -> tuple:
    """The Kirchhoff series' geometry at broadcast emscatter angles [rad] (module docstring):
    ``(Q, K, geo)`` with ``Q = (kσ w_z)²``, ``K = √((w_x kℓx)² + (w_y kℓy)²)`` the scaled
    spectrum wavenumber and ``geo = 4π η² (kσ)² (kℓx)(kℓy) |i·ĥ||o·ĥ| |w|²`` [-] the prefactor
    of ``e^{−Q} Σ Q^{n−1}/n! w_n`` (``w = i + η o``, ``η`` the real index; ``k`` [rad/m])."""
    ki, kt, _, _, _, _ = _dirs(ti, pi_, tt, pt)
    _, ci, co, w2 = _half(ki, kt, eta)
    w = -ki + eta * kt
    ks = k * rough.sigma
    Q = (ks * w[2]) ** 2
    K = np.hypot(w[0] * (k * rough.length), w[1] * (k * rough.length_y))
    pref = 4 * math.pi * ks**2 * (k * rough.length) * (k * rough.length_y)
    return Q, K, pref * eta**2 * np.abs(ci * co) * w2


def bistatic_transmission(
    roughness,
    eps,
    k: float,
    theta_i,
    theta_t,
    phi_t,
    phi_i=0.0,
    *,
    out_of_range: str = "warn",
    rtol: float = 1e-8,
    max_terms: int = 10**6,
) -> Scattering:
    """PO (Kirchhoff) bistatic transmission coefficients σ⁰_t ``[pol_t, pol_i]`` [-] and the
    coherent transmissivity (module docstring).

    Parameters
    ----------
    roughness : Gaussian, exponential or power-law :class:`~emscatter.spectra.Roughness` (or a
        measured map's), ``dimension=2``; lengths [m].
    eps : relative permittivity of the lower medium to the upper, complex with ``Im ε ≥ 0``
        (absorbing: module docstring) or real (> 0, ≠ 1); ``Re ε < 1``: light from the denser
        side.
    k : wavenumber of the upper (incident) medium [rad/m].
    theta_i, theta_t, phi_t, phi_i : emscatter angles [rad], numpy-broadcast (as
        :func:`.go.bistatic_transmission`: ``θt`` from the downward normal).
    out_of_range : ``"warn"`` (default), ``"raise"`` (a ValueError naming the failed checks),
        ``"nan"`` (σ⁰_t and the coherent part NaN at the failing incidence angles, or
        everywhere when the roughness fails) or ``"ignore"``; ``info["out_of_range"]`` is the
        mask of failing angles in every case.
    rtol, max_terms : the series' relative tolerance and term cap (:func:`~..po.series_sum`).

    Returns
    -------
    :class:`~emscatter.scattering.Scattering`: ``sigma0`` (2, 2, *shape), ``coherent``
    (2, *shape) the coherent transmissivity (a delta lobe at the refracted direction, not in
    ``sigma0``), ``theta_s``/``phi_s`` holding ``θt``/``φt``, ``info["direction"] =
    "transmission"`` and ``info["validity"]`` (the PO report at ``theta_i``).
    """
    rough = check_roughness(roughness)
    if rough.dimension != 2:
        raise ValueError("PO transmission needs a 2-D surface (dimension=2), got a 1-D profile")
    k = check_positive("k", k, unit="rad/m")
    if out_of_range not in OUT_OF_RANGE:
        raise ValueError(f"out_of_range must be one of {OUT_OF_RANGE}, got {out_of_range!r}")
    rtol = check_positive("rtol", rtol)
    if not rtol < 1:
        raise ValueError(f"rtol must be in (0, 1), got {rtol!r}")
    if isinstance(max_terms, bool) or not isinstance(max_terms, int | np.integer) or max_terms < 1:
        raise ValueError(f"max_terms must be a positive integer, got {max_terms!r}")
    e = check_lossy_transmission_eps(eps, "PO")
    ti, tt, pt, pi_, e = transmission_angles(e, eps, theta_i, theta_t, phi_t, phi_i)
    e_big = complex(e.ravel()[np.argmax(np.abs(e))])
    validity = po.check_validity(rough, k, eps=e_big if e_big.imag else e_big.real, theta_i=ti)
    shape = ti.shape
    failing, bad = transmission_policy(
        validity, shape, out_of_range, warning=POWarning,
        label="PO transmission used outside the Kirchhoff approximation's validity",
    )  # fmt: skip
    eta = np.sqrt(e).real  # the direction of a wave of the lower medium: sinθt = k⊥/Re k₂
    Q, K, geo = series_geometry(rough, k, eta, ti, tt, pt, pi_)
    Q, K = Q.reshape(-1), K.reshape(-1)
    log_w = po.log_nfold(rough)
    logt = np.empty(Q.size)
    opts = {"rtol": rtol, "max_terms": int(max_terms)}
    for st in range(0, Q.size, _BLOCK):  # blocks of geometries (memory), vectorized inside
        sl = slice(st, st + _BLOCK)
        comp = kirchhoff_compiled.po_log_series(
            rough, log_w, Q[sl], K[sl], series_sum=po.series_sum, **opts
        )
        logt[sl] = comp if comp is not None else po.series_sum(log_w, Q[sl], K[sl], **opts)
    geo = geo * np.exp(logt.reshape(shape))
    j = _jones(e, ti, tt, pt, pi_, eta=eta)
    sigma0 = j * j * geo
    if np.any(e.imag != 0):  # the mean-plane flux of the transmitted wave (lossless: 1)
        kperp = eta * np.sin(tt)
        kz2 = np.sqrt(e - kperp**2 + 0j)
        kz2 = np.where(kz2.imag < 0, -kz2, kz2)
        ref = np.maximum(eta * np.cos(tt), 1e-300)
        flux = np.stack([kz2.real, (np.abs(e) * kz2 / e).real]) / ref
        sigma0 = sigma0 * flux[:, None]
    coh = coherent_transmissivity(rough, e, k, ti)
    if np.any(bad):
        sigma0 = np.where(bad, np.nan, sigma0)
        coh = np.where(bad, np.nan, coh)
    elif not np.all(np.isfinite(sigma0)):
        raise ValueError("PO transmission produced NaN/inf (please report the inputs)")
    info = {
        "direction": "transmission",
        "directions": "sin(theta_t) = |k_perp| / Re k2 (flux through the mean plane z = 0-)",
        "absorbing": bool(np.any(e.imag != 0)),
        "rtol": rtol,
        "polarization_factors": "local Fresnel transmission at the stationary-phase facet",
        "validity": validity,
        "out_of_range": failing,
        "source": "Kirchhoff approximation (Tsang, Kong & Ding 2000 §9.4; Ulaby, Moore & Fung "
        "1982 §12-4); limits: Fresnel T (flat), Walter et al. 2007 eq. 21 (large k sigma)",
    }
    return Scattering(
        sigma0=sigma0,
        coherent=coh,
        method="kirchhoff-po-transmission",
        theta_i=ti,
        theta_s=tt,
        phi_s=pt,
        phi_i=pi_,
        k=k,
        dimension=2,
        info=info,
    )
