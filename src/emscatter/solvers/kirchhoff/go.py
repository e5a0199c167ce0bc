"""Kirchhoff approximation, geometric-optics limit (stationary phase), with optional shadowing.

Surface (``dimension=2``, per unit area; Tsang, Kong & Ding 2001, vol. III ch. 2;
Ulaby, Moore & Fung 1982, vol. II §12-4, eq. 12.59 for backscatter)::

    σ⁰_pq = π |q|⁴/q_z⁴ · |F_pq|² · p(−q_x/q_z, −q_y/q_z) · S(θi, θs)

with ``q = k_s − k_i``, ``F_pq`` the Fresnel/polarization factor at the local specular angle
``cosθl = |q|/(2k)`` (:mod:`emscatter.solvers.kirchhoff.common`), ``p`` the Gaussian slope density
with the
per-direction variances ``sx = ⟨ζx²⟩``, ``sy = ⟨ζy²⟩`` (anisotropic allowed)::

    p(ζx, ζy) = exp(−ζx²/(2 sx) − ζy²/(2 sy)) / (2π √(sx sy))

and ``S`` an optional shadowing factor (default: the direction-and-height-correlated Smith
form ``1/(1 + max(Λi, Λs) + λ(ψ) min(Λi, Λs))``, Ginneken et al. 1998 / Heitz 2014 §6 —
continuous in every direction and the monostatic ``1/(1+Λ(θi))`` at backscatter, one event
not two; ``"separable"`` is Mitsuba's ``G1(θi) G1(θs)``;
:func:`emscatter.solvers.kirchhoff.common.shadowing_factor`).
Written with the half vector ``ĥ = q/|q|``,
``p / cos⁴θh = D(ĥ)`` is the Beckmann distribution of total mean-square slope
``m² = sx + sy`` (``α = m`` in Mitsuba 3; the seed's eq. 2.14 with ``m = 2σ/T``, eq. 3.1), so
``σ⁰ = π F D S`` and the BRDF ``f_r = σ⁰/(4π cosθi cosθs) = F D G / (4 cosθi cosθs)`` is exactly
Cook–Torrance with Beckmann (seed eq. 2.13). Backscatter (Ulaby, Moore & Fung 1982 eq. 12.59;
the monostatic shadowing as SMRT's ``geometrical_optics_backscatter``)::

    σ⁰_pp = |R(0)|² exp(−tan²θ/m²) / (m² cos⁴θ) / (1 + Λ(cotθ/m))

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

from emscatter.conventions import check_angle, check_positive
from emscatter.scattering import Scattering
from emscatter.solvers.kirchhoff import compiled as kirchhoff_compiled
from emscatter.solvers.kirchhoff import go_backscatter as go_monostatic
from emscatter.solvers.kirchhoff.common import (
    check_flag,
    check_roughness,
    check_shadowing,
    coherent_local,
    fresnel_factors,
    geometry,
    shadowing_angle_check,
    shadowing_factor,
    slope_variances,
    tangent_plane_checks,
    workers_for,
)
from emscatter.solvers.validity import (
    SLOPE_CUTOFF_FACTOR,
    angle_lower,
    build_report,
    check_solver_options,
    lower,
    upper,
)

__all__ = [
    "bistatic", "check_validity", "angle_entries", "VALIDITY", "slope_pdf_factor",
    "measured_pdf_factor",
]  # fmt: skip

#: Validity of the geometric-optics (stationary-phase) Kirchhoff solution (Ulaby, Moore &
#: Fung 1982 vol. II §12-4 / Table 12.2): ``kℓ ≥ 6``, ``ℓ² ≥ 2.76 σλ`` (tangent plane),
#: stationary phase ``Q = (2kσ cosθi)² ≥ 10`` — ``Q = (q_z σ)²`` is the exponent of the
#: Kirchhoff coherent attenuation ``e^{−Q}`` that GO, the whole-intensity limit, double counts
#: (``e^{−10} = 4.5e-5``); checked at normal incidence for the roughness and per angle with
#: ``theta_i`` — and rms slope ``m ≤ 1``. Per angle also Smith's illuminated fraction
#: ``G1(θi) ≥ 0.5`` (with shadowing: GO has no multiple scattering, which becomes comparable
#: to single scattering once half the surface is in shadow, Thorsos 1988 JASA 83, 78;
#: Bourlier, Berginc & Saillard 2002) or ``≥ 0.9`` without shadowing (Kirchhoff without
#: shadowing, as physical optics).
VALIDITY = {
    "k_l_min": 6.0,
    "curvature_factor": 2.76,
    "phase_q_min": 10.0,
    "rms_slope_max": 1.0,
    "illuminated_min": 0.5,
    "illuminated_min_unshadowed": 0.9,
}

#: GO's σ⁰ is the whole Kirchhoff intensity (stationary phase), coherent part included: a
#: hemispherical integral (emissivity, BRDF albedo) must not add ``coherent`` to it (issue 21:
#: adding it gave 1 − e = 1.17 at 85°). :func:`emscatter.api.emissivity` reads this flag.
COHERENT_IN_SIGMA0 = True

#: Options of :func:`bistatic` (what ``check_validity`` accepts).
OPTIONS = ("shadowing", "k_max", "slope_variance", "threads", "coherent")

_SRC_Q = "Ulaby, Moore & Fung 1982 vol. II §12-4, Table 12.2 (stationary phase)"
_SRC_SH = "Smith 1967; Thorsos 1988 JASA 83 78; Bourlier, Berginc & Saillard 2002"

_CHUNK = 1 << 15
_MEASURED_PDF = (
    "measured (kernel density, slope tail {}); shadowing: Smith Λ of the Gaussian, measured "
    "variances"
)


def check_validity(
    roughness,
    k: float,
    *,
    eps=None,
    theta_i=None,
    k_max=None,
    slope_variance=None,
    shadowing=True,
    **solver_options,
) -> dict:
    """Validity report (BOARD interface 1, :mod:`.validity`) for ``k`` [rad/m]; criteria in
    :data:`VALIDITY`. ``theta_i`` [rad] adds the per-angle stationary-phase and shadowing
    checks; ``eps`` is accepted for the common signature (GO's limits do not depend on it)."""
    check_solver_options("go", solver_options, OPTIONS)
    rough = check_roughness(roughness)
    k = check_positive("k", k, unit="rad/m")
    mode = check_shadowing(shadowing)
    v = VALIDITY
    q0 = (2 * k * rough.sigma) ** 2
    sx, sy = slope_variances(rough, k_max, slope_variance, k=k)
    m = math.sqrt(sx + sy)
    checks = [
        *tangent_plane_checks(rough, k, v),
        lower("stationary_phase", q0, v["phase_q_min"], "(2kσ)² at normal incidence", _SRC_Q),
        upper("rms_slope", m, v["rms_slope_max"], "total rms slope m", _SRC_Q),
    ]
    angle_checks = []
    ti = None
    if theta_i is not None:
        ti = check_angle("theta_i", theta_i)
        ci = np.cos(ti)
        angle_checks.append(
            angle_lower("stationary_phase_angle", q0 * ci * ci, v["phase_q_min"],
                        "Q = (2kσ cosθi)²", _SRC_Q, increasing=True)
        )  # fmt: skip
        limit = v["illuminated_min"] if mode else v["illuminated_min_unshadowed"]
        angle_checks.append(
            shadowing_angle_check("illuminated", ti, sx, sy, limit,
                                  "Smith's illuminated fraction G1(θi)", _SRC_SH)
        )  # fmt: skip
    return build_report(
        rough,
        k,
        checks,
        theta_i=ti,
        angle_checks=angle_checks,
        rms_slope=m,
        slope_cutoff=slope_cutoff(rough, k, k_max, slope_variance),
    )


def angle_entries(roughness, k: float, theta_i: np.ndarray) -> dict | None:
    """The per-angle entries (``angle_valid``, ``angle_excess``, ``angle_reasons``) of
    :func:`check_validity` with its defaults at flat float64 ``theta_i`` [rad] (checked), in
    one compiled pass (:mod:`.go_validity`); None where the compiled kernels do not run (the
    numpy backend, few angles): the caller builds them from :func:`check_validity` then
    (:func:`emscatter.method_resolution.angle_report`)."""
    from emscatter.kernels import backend
    from emscatter.solvers.kirchhoff import go_validity

    if theta_i.size < go_validity.MIN_ANGLES or backend() != "numba":
        return None
    rough = check_roughness(roughness)
    sx, sy = slope_variances(rough, None, None, k=float(k))
    q0 = (2 * float(k) * rough.sigma) ** 2
    v = VALIDITY
    return go_validity.angle_entries(q0, max(sx, sy), v["phase_q_min"], v["illuminated_min"],
                                     theta_i)  # fmt: skip


def slope_cutoff(rough, k: float, k_max=None, slope_variance=None) -> float | None:
    """The spectral cutoff [rad/m] GO's slope variance is computed with (None: none used)."""
    if slope_variance is not None or (k_max is None and rough._mss_closed() is not None):
        return None
    return float(k_max) if k_max is not None else SLOPE_CUTOFF_FACTOR * k


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


def measured_pdf_factor(g, pdf, dimension: int) -> np.ndarray:
    """:func:`slope_pdf_factor` with a measured slope density ``pdf(ζx[, ζy])`` (the
    histogram of a height map, :meth:`emscatter.surfaces.measured.MeasuredRoughness.slope_pdf`)
    in place of the Gaussian, at the specular slopes ``ζ = (−q_x/q_z, −q_y/q_z)``."""
    qz = g.qz
    ok = qz > 0
    inv = 1.0 / np.where(ok, qz, 1.0)
    if dimension == 2:
        p = pdf(-g.qx * inv, -g.qy * inv)
        r = g.q2 * inv * inv
        val = math.pi * r * r * p
    else:
        p = pdf(-g.qx * inv)
        val = 0.5 * math.pi * g.q2 * g.q2 * inv * inv * inv * p
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
    coherent: bool = True,
) -> Scattering:
    """Geometric-optics bistatic scattering coefficients σ⁰ (all four polarizations).

    Parameters
    ----------
    roughness : :class:`emscatter.spectra.Roughness` (``dimension`` 2 or 1).
    eps : relative permittivity (complex, ``Im ε ≥ 0``, broadcasts with the angles) or "pec".
    k : free-space wavenumber [rad/m] (enters only the coherent part and validity).
    theta_i, theta_s, phi_s, phi_i : angles [rad], numpy-broadcast.
    shadowing : True/"direction-correlated" (default: continuous, ``1/(1+Λ)`` at
        backscatter), "separable" (``G1(θi) G1(θs)``, Mitsuba 3's roughconductor),
        "correlated" (height-correlated), "smith" (separable, monostatic only at the exact
        backscatter point; the previous default) or False
        (:func:`emscatter.solvers.kirchhoff.common.shadowing_factor`).
    k_max : spectral cutoff [rad/m] of the slope variance for correlations whose slope
        variance is infinite (exponential, power law); default ``2k``, the spectrum the wave
        sees (:mod:`emscatter.solvers.validity`). Ignored for a Gaussian unless given.
    slope_variance : override the per-direction slope variance(s) ``⟨ζx²⟩[, ⟨ζy²⟩]`` [-].
        A measured roughness (:mod:`emscatter.surfaces.measured`) without it uses its
        measured slope density (histogram, non-Gaussian); shadowing then uses Smith's
        Gaussian Λ with the measured slope variances (an approximation, stated in
        ``info["slope_pdf"]``).
    threads : worker threads for large inputs (default: the CPU count, at most 8).
    coherent : False skips the coherent part (``coherent`` is then a read-only NaN array and
        ``info["coherent"]`` says so; BOARD interface 3).

    Returns
    -------
    :class:`~emscatter.scattering.Scattering` with ``sigma0`` (2, 2, *shape) and the Kirchhoff
    coherent reflectivity ``|R_p(θi)|² exp(−(2kσ cosθi)²)``.
    """
    return _bistatic(
        roughness, eps, k, theta_i, theta_s, phi_s, phi_i, shadowing=shadowing, k_max=k_max,
        slope_variance=slope_variance, threads=threads, coherent=coherent, validity=True,
    )  # fmt: skip


def _bistatic(
    roughness, eps, k, theta_i, theta_s, phi_s, phi_i=0.0, *, shadowing=True, k_max=None,
    slope_variance=None, threads=None, coherent=True, validity=False, checked=False,
    monostatic=False,
) -> Scattering:  # fmt: skip
    """:func:`bistatic`; ``info["validity"]`` is None unless ``validity``; ``checked``: the
    roughness, ``k``, angles and ``eps`` are checked already
    (:func:`emscatter.solvers.kirchhoff.common.geometry`);
    ``monostatic``: the caller guarantees ``θs = θi``, ``φs = φi + π`` (closed form then)."""
    rough = roughness if checked else check_roughness(roughness)
    k = float(k) if checked else check_positive("k", k, unit="rad/m")
    mode = check_shadowing(shadowing)
    sx, sy = slope_variances(rough, k_max, slope_variance, k=k)
    want_coh = check_flag("coherent", coherent)
    dim = rough.dimension
    g = geometry(theta_i, theta_s, phi_s, phi_i, eps, dim, checked=checked)
    shape = g.shape
    n = g.size
    flat = np.empty((2, 2, n))
    # coherent=False: a read-only NaN placeholder (no 2n-element fill the caller throws away)
    coh = np.empty((2, n)) if want_coh else np.broadcast_to(np.nan, (2, n))
    # a measured roughness (emscatter.surfaces.measured) brings its own slope density
    pdf = getattr(rough, "slope_pdf", None) if slope_variance is None else None
    signed = (sx != sy or pdf is not None) and dim == 2

    def work(start: int) -> None:
        loc = g.chunk(slice(start, min(start + _CHUNK, n)), signed_azimuth=signed)
        val = (
            slope_pdf_factor(loc, sx, sy, dim)
            if pdf is None
            else measured_pdf_factor(loc, pdf, dim)
        )
        if mode is not None:
            val = val * shadowing_factor(loc, sx, sy, mode)
        fresnel_factors(loc, dim, val, out=flat[:, :, start : start + loc.n])
        if want_coh:
            coh[:, start : start + loc.n] = coherent_local(loc, rough.sigma, k)

    starts = range(0, n, _CHUNK)
    workers = workers_for(threads, len(starts))
    ti_c, ts_c, dphi_c, _, _, eps_c = g.compact  # unbroadcast: the kernel reads grids as such
    if pdf is not None:  # the numpy path: the compiled kernels know the Gaussian only
        for st in starts:
            work(st)
    elif monostatic and not want_coh and go_monostatic.covers(g, dim, sx, sy, mode):
        flat = go_monostatic.backscatter_sigma0(g.ti_flat, eps_c, sx, mode)
    elif kirchhoff_compiled.go_sigma0(
        ti_c, ts_c, dphi_c, eps_c, dimension=dim, sx=sx, sy=sy, shadowing=mode, out=flat,
        coherent_out=coh if want_coh else None, k=k, sigma=rough.sigma, threads=workers,
        shape=shape,
    ):  # fmt: skip
        pass  # compiled kernel (emscatter.kernels); the numpy path below is the reference
    elif workers > 1:
        with ThreadPoolExecutor(max_workers=workers) as pool:
            list(pool.map(work, starts))  # numpy releases the GIL in its kernels
    else:
        for st in starts:
            work(st)
    sigma0 = flat.reshape(2, 2, *shape)
    info = {
        "slope_variance": (sx, sy),
        "total_mean_square_slope": sx + sy,
        "slope_cutoff": slope_cutoff(rough, k, k_max, slope_variance),
        "shadowing": mode,
        "slope_pdf": "gaussian"
        if pdf is None
        else _MEASURED_PDF.format(
            ((getattr(rough, "info", None) or {}).get("slope_tail") or {}).get("shape", "none")
        ),
        "validity": check_validity(rough, k, slope_variance=(sx, sy) if dim == 2 else sx)
        if validity
        else None,
    }
    if not want_coh:
        info["coherent"] = "not computed (coherent=False)"
    return Scattering.from_geometry(
        g, sigma0=sigma0, coherent=coh.reshape(2, *shape), method="kirchhoff-go", k=k, info=info
    )


def _bistatic_checked(*args, monostatic: bool = False, **options) -> Scattering:
    """The public API's entry (``bistatic.checked``): inputs checked as :func:`bistatic`
    checks them; no validity report of its own (the API supplies one); ``monostatic``: the
    exact backscatter geometry (``θs = θi``, ``φs = φi + π``)."""
    return _bistatic(*args, **options, validity=False, checked=True, monostatic=monostatic)


bistatic.checked = _bistatic_checked
