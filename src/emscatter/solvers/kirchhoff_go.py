"""Kirchhoff approximation, geometric-optics limit (stationary phase), with optional shadowing.

Surface (``dimension=2``, per unit area; Tsang, Kong & Ding 2001, vol. III ch. 2;
Ulaby, Moore & Fung 1982, vol. II §12-4, eq. 12.59 for backscatter)::

    σ⁰_pq = π |q|⁴/q_z⁴ · |F_pq|² · p(−q_x/q_z, −q_y/q_z) · S(θi, θs)

with ``q = k_s − k_i``, ``F_pq`` the Fresnel/polarization factor at the local specular angle
``cosθl = |q|/(2k)`` (:mod:`.kirchhoff_common`), ``p`` the Gaussian slope density with the
per-direction variances ``sx = ⟨ζx²⟩``, ``sy = ⟨ζy²⟩`` (anisotropic allowed)::

    p(ζx, ζy) = exp(−ζx²/(2 sx) − ζy²/(2 sy)) / (2π √(sx sy))

and ``S`` an optional shadowing factor. Written with the half vector ``ĥ = q/|q|``,
``p / cos⁴θh = D(ĥ)`` is the Beckmann distribution of total mean-square slope
``m² = sx + sy`` (``α = m`` in Mitsuba 3; the seed's eq. 2.14 with ``m = 2σ/T``, eq. 3.1), so
``σ⁰ = π F D S`` and the BRDF ``f_r = σ⁰/(4π cosθi cosθs) = F D G / (4 cosθi cosθs)`` is exactly
Cook–Torrance with Beckmann (seed eq. 2.13). Backscatter: ``|R(0)|² exp(−tan²θ/m²)/(m² cos⁴θ)``.

Profile (``dimension=1``, per unit length, 2-D problem, only hh and vv): the facet picture with
the 1-D slope density ``p₁(ζ) = exp(−ζ²/(2 sx))/√(2π sx)`` and ``dθs = 2 dθh`` gives::

    σ⁰_pp = π |F_pp|² |q|⁴ / (2 k q_z³) · p₁(−q_x/q_z) · S

(the large-``kσ`` limit of the 1-D Kirchhoff integral, cf. Thorsos 1988, JASA 83, 78), so
that ``r = 1/(2π cosθi) ∫ σ⁰ dθs → 1`` for a perfect conductor at small slopes.

Energy: without shadowing a perfect conductor reflects ``∫ D (ĥ·k̂_i)/cosθi dΩh ≈ 1`` at
small slopes (tested, 2-D and 1-D); at large slopes GO without shadowing exceeds 1 at grazing
angles, shadowing only removes energy.

Coherent part: ``coherent`` holds the Kirchhoff ``|R_p(θi)|² exp(−(2kσ cosθi)²)`` like the
other solvers. GO's σ⁰ is the stationary-phase limit of the *whole* Kirchhoff intensity, so
where GO is valid (``kσ cosθ > √10``) the coherent term is < e⁻⁴⁰ and negligible; outside
that range adding it to GO's σ⁰ double counts the specular energy (use PO there).
"""

from __future__ import annotations

import math
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from ..conventions import check_positive
from ..scattering import Scattering
from .kirchhoff_common import (
    check_roughness,
    check_shadowing,
    coherent_local,
    fresnel_factors,
    geometry,
    shadowing_factor,
    slope_variances,
    tangent_plane_checks,
    validity_report,
    workers_for,
)

__all__ = ["bistatic", "check_validity", "VALIDITY", "slope_pdf_factor"]

#: Validity of the geometric-optics (stationary-phase) Kirchhoff solution: Ulaby, Moore &
#: Fung (1982) vol. II §12-4 / Table 12.2: ``kℓ > 6``, ``ℓ² > 2.76 σ λ`` (tangent plane) and
#: ``(kσ cosθ)² > 10`` (stationary phase; checked at θ = 0, i.e. ``kσ > √10``); shadowing
#: matters beyond ``m ≈ 0.5``.
VALIDITY = {
    "k_l_min": 6.0,
    "curvature_factor": 2.76,
    "k_sigma_min": math.sqrt(10.0),
    "rms_slope_max": 1.0,
}

_CHUNK = 1 << 15


def check_validity(roughness, k: float, *, k_max=None, slope_variance=None) -> dict:
    """Validity report ``{"valid", "reasons", "checks", ...}`` for ``k`` [rad/m]."""
    rough = check_roughness(roughness)
    k = check_positive("k", k, unit="rad/m")
    ks = k * rough.sigma
    v = VALIDITY
    checks = [
        *tangent_plane_checks(rough, k, v),
        (
            "k_sigma",
            ks > v["k_sigma_min"],
            f"kσ = {ks:.3g} ≤ √10 (stationary phase)",
            v["k_sigma_min"] / ks,
        ),
    ]
    try:
        sx, sy = slope_variances(rough, k_max, slope_variance)
        m = math.sqrt(sx + sy)
        checks.append(
            (
                "rms_slope",
                m < v["rms_slope_max"],
                f"rms slope m = {m:.3g} ≥ 1",
                m / v["rms_slope_max"],
            )
        )
    except ValueError as exc:
        checks.append(("rms_slope", False, str(exc)))
    return validity_report(rough, k, checks)


def slope_pdf_factor(g, sx: float, sy: float, dimension: int) -> np.ndarray:
    """The geometric part of σ⁰ (all but ``|F_pq|²`` and shadowing) [-]:
    ``π |q|⁴/q_z⁴ p(ζ)`` (2-D) or ``π |q|⁴/(2 q_z³) p₁(ζ)`` (1-D, ``q`` in units of k)."""
    qz = g.qz
    ok = qz > 0
    qzs = np.where(ok, qz, 1.0)
    inv = 1.0 / qzs
    zx = g.qx * inv
    if dimension == 2:
        zy = g.qy * inv
        expo = -0.5 * (zx * zx / sx + zy * zy / sy)
        r = g.q2 * inv * inv
        pref = 0.5 / math.sqrt(sx * sy)  # π · 1/(2π√(sx sy))
        val = pref * r * r * np.exp(np.where(ok, expo, -np.inf))
    else:
        expo = -0.5 * zx * zx / sx
        pref = math.pi / math.sqrt(2 * math.pi * sx) * 0.5
        val = pref * g.q2 * g.q2 * inv * inv * inv * np.exp(np.where(ok, expo, -np.inf))
    return np.broadcast_to(np.where(ok, val, 0.0), (g.n,))


def bistatic(
    roughness,
    eps,
    k: float,
    theta_i,
    theta_s,
    phi_s,
    phi_i=0.0,
    *,
    shadowing: bool | str = True,
    k_max: float | None = None,
    slope_variance=None,
    threads: int | None = None,
) -> Scattering:
    """Geometric-optics bistatic scattering coefficients σ⁰ (all four polarizations).

    Parameters
    ----------
    roughness : :class:`emscatter.spectra.Roughness` (``dimension`` 2 or 1).
    eps : relative permittivity (complex, ``Im ε ≥ 0``, broadcasts with the angles) or "pec".
    k : free-space wavenumber [rad/m] (enters only the coherent part and validity).
    theta_i, theta_s, phi_s, phi_i : angles [rad], numpy-broadcast.
    shadowing : True/"smith" (separable Smith, as Mitsuba 3), "correlated", or False.
    k_max : spectral cutoff [rad/m] for correlations with infinite slope variance.
    slope_variance : override the per-direction slope variance(s) ``⟨ζx²⟩[, ⟨ζy²⟩]`` [-].
    threads : worker threads for large inputs (default: the CPU count, at most 8).

    Returns
    -------
    :class:`~emscatter.scattering.Scattering` with ``sigma0`` (2, 2, *shape) and the Kirchhoff
    coherent reflectivity ``|R_p(θi)|² exp(−(2kσ cosθi)²)``.
    """
    rough = check_roughness(roughness)
    k = check_positive("k", k, unit="rad/m")
    mode = check_shadowing(shadowing)
    sx, sy = slope_variances(rough, k_max, slope_variance)
    dim = rough.dimension
    g = geometry(theta_i, theta_s, phi_s, phi_i, eps, dim)
    shape = g.shape
    n = g.size
    flat = np.empty((2, 2, n))
    coh = np.empty((2, n))
    signed = sx != sy and dim == 2

    def work(start: int) -> None:
        loc = g.chunk(slice(start, min(start + _CHUNK, n)), signed_azimuth=signed)
        val = slope_pdf_factor(loc, sx, sy, dim)
        if mode is not None:
            val = val * shadowing_factor(loc, sx, sy, mode)
        fresnel_factors(loc, dim, val, out=flat[:, :, start : start + loc.n])
        coh[:, start : start + loc.n] = coherent_local(loc, rough.sigma, k)

    starts = range(0, n, _CHUNK)
    workers = workers_for(threads, len(starts))
    if workers > 1:
        with ThreadPoolExecutor(max_workers=workers) as pool:
            list(pool.map(work, starts))  # numpy releases the GIL in its kernels
    else:
        for st in starts:
            work(st)
    sigma0 = flat.reshape(2, 2, *shape)
    return Scattering(
        sigma0=sigma0,
        coherent=coh.reshape(2, *shape),
        method="kirchhoff-go",
        theta_i=g.theta_i,
        theta_s=g.theta_s,
        phi_s=g.phi_s,
        phi_i=g.phi_i,
        k=k,
        dimension=dim,
        info={
            "slope_variance": (sx, sy),
            "total_mean_square_slope": sx + sy,
            "shadowing": mode,
            "validity": check_validity(rough, k, slope_variance=(sx, sy) if dim == 2 else sx),
        },
    )
