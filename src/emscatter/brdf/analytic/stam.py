"""Stam 1999's diffraction shader for a Gaussian random surface ("Diffraction shaders",
SIGGRAPH '99, 101–110, §5.2 "anisotropic noise"; the seed's §2.3.3), on the footing of
:mod:`emscatter.brdf.analytic` (renderer frame, ``wi``/``wo`` unit vectors ``(..., 3)``
pointing away, normal ``+z``, tangent ``+x``; ``f_r`` [1/sr]; vectorized).

Stam writes the Kirchhoff BRDF of a height field as
``f = k² F² G ⟨|P(ku, kv)|²⟩ / (4π² A w²)`` with ``(u, v, w) = wi + wo`` (``−k₁ − k₂`` in his
notation), ``G = (1 + wi·wo)²/(cosθi cosθo)`` and, for a Gaussian surface of rms height ``σ``
[m] with the anisotropic Gaussian correlation ``exp(−x²/τ_x² − y²/τ_y²)`` (seed eq. 2.4),
per unit area ``A``::

    ⟨|P|²⟩/A = (2π)² e^{−g} δ(ku) δ(kv) + π τ_x τ_y e^{−g} Σ_{n≥1} gⁿ/(n! n)
               · exp(−k²(τ_x² u² + τ_y² v²)/(4n)),      g = (kσw)²

(Stam's eqs. for "anisotropic noise"; ``τ_x = τ_y = τ`` is the isotropic form). The first term
is the specular (coherent) reflectance ``|F(θi)|² e^{−(2kσ cosθi)²}``
(:func:`stam_specular`); the second is :func:`stam`. ``F²`` is the unpolarized Fresnel
reflectance at the bisector ``wi·h`` from the complex index ``n`` (``ε = n²``, ``Im n ≥ 0``) or
``"pec"``.

Relation to HTSG and PO: since ``|wi + wo|² = 2(1 + wi·wo)``, Stam's ``k² G/(4π² w²) · πτ²``
equals HTSG's ``G D/π`` term by term — Stam's Gaussian shader is HTSG without the shadowing
and the effective roughness (:func:`~.htsg.htsg` with both off, tested), i.e. emscatter's
physical optics (:mod:`emscatter.solvers.kirchhoff.po`, ``ℓ = τ_x``, ``ℓ_y = τ_y``) converted
with ``f = σ⁰/(4π cosθi cosθo)`` — the anisotropic case too (tested to 1e-6). It is
reciprocal (every factor is symmetric in ``wi``, ``wo``). Without shadowing its albedo
exceeds 1 toward grazing (PO's known excess; ``validation/brdf/catalogue.md``).

First order (``kσ ≪ 1``): the ``n = 1`` term alone, ``g π τ_xτ_y exp(−k²(τ_x²u² + τ_y²v²)/4)``
= ``g (2π)² w(ku, kv)`` with ``w`` the height spectrum — the first-order Kirchhoff
(tangent-plane) result, which differs from first-order SPM (``16πk⁴σ²|α_pq|² w``) by the
polarization factors only (SPM's ``α_pq`` against the bisector Fresnel ``F`` and ``G``); the
catalogue gives the difference in dB.

Beckmann equivalent: ``(m_x, m_y) = (2σ/τ_x, 2σ/τ_y)`` (seed eq. 3.1 per axis), the
``kσ → ∞`` limit of the lobe.
"""

from __future__ import annotations

import math

import numpy as np

from emscatter.brdf.analytic import fresnel_unpolarized
from emscatter.brdf.analytic.htsg import _check_surface, _directional_diffuse, _eps
from emscatter.conventions import check_in_range, check_positive

__all__ = ["stam", "stam_specular", "stam_equivalent_beckmann"]


def stam(
    wi,
    wo,
    wavelength: float,
    sigma: float,
    tau_x: float,
    tau_y: float | None = None,
    n=1.5,
    *,
    rtol: float = 1e-8,
    max_terms: int = 100_000,
) -> np.ndarray:
    """Stam 1999's Gaussian-surface diffraction BRDF (incoherent part) [1/sr] (module
    docstring): ``wavelength``, rms height ``sigma``, correlation lengths ``tau_x`` (along the
    tangent ``+x``) and ``tau_y`` (default ``tau_x``: isotropic) [m]; ``n`` a complex index
    (``Im n ≥ 0``), a callable ``n(λ)`` or ``"pec"``; ``rtol`` the series' tail tolerance."""
    s, tx, lam = _check_surface(sigma, tau_x, wavelength)
    ty = tx if tau_y is None else check_positive("tau_y", tau_y, unit="m")
    eps = _eps(n, lam)
    rtol = check_in_range("rtol", rtol, 0.0, 1.0)
    if isinstance(max_terms, bool) or not isinstance(max_terms, int) or max_terms < 1:
        raise ValueError(f"max_terms must be a positive integer, got {max_terms!r}")
    # Stam's k²F²G⟨|P|²⟩/(4π²A w²) is HTSG's |F|² G D/(π cosθi cosθo) term by term (module
    # docstring): HTSG's series without its shadowing and effective roughness
    return _directional_diffuse(
        wi,
        wo,
        lam,
        s,
        tx,
        ty,
        eps,
        shadowing=False,
        effective_roughness=False,
        rtol=rtol,
        max_terms=max_terms,
    )


def stam_specular(theta_i, wavelength: float, sigma: float, n=1.5) -> np.ndarray:
    """The coherent (delta) reflectance ``|F(θi)|² e^{−(2kσ cosθi)²}`` [-] of Stam's Gaussian
    surface at incidence angles ``theta_i`` [rad] (the ``δ`` term of the module docstring)."""
    s = check_positive("sigma", sigma, unit="m")
    lam = check_positive("wavelength", wavelength, unit="m")
    eps = _eps(n, lam)
    th = np.asarray(theta_i, dtype=float)
    if not np.all(np.isfinite(th)) or np.any(th < 0) or np.any(th > 0.5 * math.pi):
        raise ValueError(f"theta_i must be in [0, π/2] rad, got {theta_i!r}")
    c = np.cos(th)
    k = 2.0 * math.pi / lam
    return fresnel_unpolarized(eps, c) * np.exp(-((2.0 * k * s * c) ** 2))


def stam_equivalent_beckmann(sigma: float, tau_x: float, tau_y: float | None = None):
    """``(m_x, m_y) = (2σ/τ_x, 2σ/τ_y)`` (seed eq. 3.1 per axis; exact as ``kσ → ∞``) as an
    :class:`~.equivalence.Equivalence`."""
    from emscatter.brdf.analytic.equivalence import Equivalence

    s = check_positive("sigma", sigma)
    tx = check_positive("tau_x", tau_x)
    ty = tx if tau_y is None else check_positive("tau_y", tau_y)
    return Equivalence((2 * s / tx, 2 * s / ty), 0.0, "m = 2 sigma / tau per axis (seed eq. 3.1)")
