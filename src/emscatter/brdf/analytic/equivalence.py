"""The seed's roughness equivalences (chapter 3, section 3.2): one "general roughness" across
the analytic models.

* :func:`rms_slope_from_surface` — ``m = tan β0 = 2σ/T`` (eq. 3.1) for a Gaussian correlation
  ``exp(−τ²/T²)``: the *total* rms slope (Beckmann's ``m``, Mitsuba's Beckmann ``α``).
* Beckmann ``m`` ↔ Phong ``n`` (:func:`phong_from_beckmann`, :func:`beckmann_from_phong`),
  ↔ Blinn ``n_B`` (:func:`blinn_from_beckmann`, :func:`beckmann_from_blinn`), Ward
  ``(m_x, m_y)`` ↔ Ashikhmin–Shirley ``(n_u, n_v)`` (:func:`ashikhmin_from_ward`).

Fit criterion (:data:`FIT_CRITERION`, the seed's section 3.2.2 made precise). The seed matches
the *distributions* (its Table 3.1 "general roughness") after equalizing their levels with the
correction ``1/(4m²)`` ("les niveaux ont été ajustés"), finding the parameter that "minimizes
the error between the two distributions". Here both curves are taken at level 1 for ``γ = 0``
— Beckmann/Ward ``exp(−tan²γ/m²)/cos⁴γ`` (Table 3.1 times ``4m²``), Phong ``cosⁿ(2γ)`` (eq. 3.3
with ``ν = 2γ``, zero beyond ``γ = π/4``), Blinn ``cos^{n_B} γ``, Ashikhmin
``cos^(n_u cos²φ + n_v sin²φ) γ`` — and the parameter minimizes the least-squares difference
on a uniform grid of the half angle ``γ ∈ [0, π/2)`` (× ``φ ∈ [0, 2π)`` for the anisotropic
pair). The returned ``error`` is the rms difference on that grid (peak = 1). This reproduces
the seed's values: ``m = 0.32 → n = 3.9 ≈ 4``, ``n_B = 17.0``; ``n = 1 → m_max = 0.505 ≈ 0.51``;
``n_B = 4 → m = 0.56`` (seed 0.54, "clearly not a good approximation": the error valley is
flat there) — see ``validation/brdf/equivalences.md``.

Ward ↔ Ashikhmin is not unique (the seed's Figs. 3.8–3.9 show two fits); the seed fixes the
ratio of the exponents "with a criterion using ``m_x/m_y``". ``ratio="seed"`` is that criterion
as the seed states and draws it: its Figs. 3.3–3.9 are curves of ``γ`` alone, and the one
section of the anisotropic pair on which both printed pairs (10, 187) and (100, 100) fit
equally well — the non-uniqueness the seed reports — is the diagonal ``φ = π/4``, where the
Ashikhmin exponent is ``(n_u + n_v)/2`` and Ward is a Beckmann lobe of
``1/m² = (1/m_x² + 1/m_y²)/2`` (:func:`ward_section_exponent`; (0.1, 0.8): ``n_u + n_v =
197.7``, the seed's pairs sum to 197 and 200). The section fixes the sum only; the seed's
ratio then splits it, ``n_u/n_v = m_x/m_y`` in the seed's axes (its Fig. 3.8 pairs ``n_u``
with ``m_y``), i.e. ``n_u/n_v = m_y/m_x`` here. ``ratio="slope"`` (default) fixes
``n_u/n_v = (m_y/m_x)²``, the ratio of the exponents that match the two lobes' curvatures at
``γ = 0`` (``n ≈ 2/m²``), fitted on the full ``(γ, φ)`` grid; ``ratio=None`` a free
two-parameter fit on that grid. ``n_u`` is the exponent along the tangent ``x`` (``φ = 0``),
paired with ``m_x``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize, minimize_scalar

from emscatter.conventions import check_positive

__all__ = [
    "FIT_CRITERION",
    "Equivalence",
    "rms_slope_from_surface",
    "beckmann_shape",
    "phong_shape",
    "blinn_shape",
    "ward_shape",
    "ashikhmin_shape",
    "phong_from_beckmann",
    "beckmann_from_phong",
    "blinn_from_beckmann",
    "beckmann_from_blinn",
    "ashikhmin_from_ward",
    "ward_section_exponent",
    "ward_ashikhmin_grid_error",
    "SEED_CRITERION",
    "SEED_SECTION_PHI",
    "fit_error",
]

FIT_CRITERION = (
    "least squares between the two distributions, both at level 1 for gamma = 0 (the seed's "
    "1/(4 m^2) level correction), on a uniform grid of the half angle gamma in [0, pi/2) "
    "(x phi in [0, 2 pi) for Ward-Ashikhmin); error = rms difference on that grid"
)

SEED_CRITERION = (
    "the seed's section 3.2.2 for Ward-Ashikhmin: least squares on the section phi = pi/4 "
    "(both at level 1 for gamma = 0, uniform gamma grid in [0, pi/2)), which fixes "
    "n_u + n_v; split n_u/n_v = m_y/m_x (n_u along x); error = rms on that section"
)

SEED_SECTION_PHI = 0.25 * math.pi
"""Azimuth [rad] of the section on which the seed compares Ward and Ashikhmin (Figs. 3.8–3.9)."""

_GAMMA = np.linspace(0.0, 0.5 * math.pi, 2001)[:-1]
_PHI = np.linspace(0.0, 2 * math.pi, 181)[:-1]


@dataclass(frozen=True)
class Equivalence:
    """A fitted equivalent parameter and the rms difference of the two distributions."""

    value: float | tuple[float, float]
    error: float
    criterion: str = FIT_CRITERION


def rms_slope_from_surface(sigma: float, correlation_length: float) -> float:
    """``m = tan β0 = 2σ/T`` (seed eq. 3.1; Beckmann & Spizzichino 1963) for rms height ``σ``
    and Gaussian correlation length ``T`` (``exp(−τ²/T²)``), same units."""
    s = check_positive("sigma", sigma)
    t = check_positive("correlation_length", correlation_length)
    return 2.0 * s / t


def beckmann_shape(gamma, m: float) -> np.ndarray:
    """``exp(−tan²γ/m²)/cos⁴γ`` — Table 3.1's Cook–Torrance/Ward general roughness × 4m²."""
    g = np.asarray(gamma, dtype=float)
    c = np.cos(g)
    with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
        return np.where(c > 0, np.exp(-(np.tan(g) ** 2) / (m * m)) / c**4, 0.0)


def phong_shape(gamma, n: float) -> np.ndarray:
    """``cosⁿ(2γ)`` for ``γ ≤ π/4``, else 0 (eq. 3.3 with ``ν = 2γ``)."""
    return np.clip(np.cos(2 * np.asarray(gamma, dtype=float)), 0.0, None) ** n


def blinn_shape(gamma, n: float) -> np.ndarray:
    """``cos^{n_B} γ`` (``(N·H)^{n_B}``, eq. 2.19)."""
    return np.clip(np.cos(np.asarray(gamma, dtype=float)), 0.0, None) ** n


def ward_shape(gamma, phi, mx: float, my: float) -> np.ndarray:
    """``exp(−tan²γ (cos²φ/m_x² + sin²φ/m_y²))/cos⁴γ`` (Table 3.1's anisotropic Ward × 4m²)."""
    g, p = np.broadcast_arrays(np.asarray(gamma, float), np.asarray(phi, float))
    c = np.cos(g)
    e = np.tan(g) ** 2 * (np.cos(p) ** 2 / mx**2 + np.sin(p) ** 2 / my**2)
    with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
        return np.where(c > 0, np.exp(-e) / c**4, 0.0)


def ashikhmin_shape(gamma, phi, nu: float, nv: float) -> np.ndarray:
    """``cos^(n_u cos²φ + n_v sin²φ) γ`` (eq. 2.24)."""
    g, p = np.broadcast_arrays(np.asarray(gamma, float), np.asarray(phi, float))
    return np.clip(np.cos(g), 0.0, None) ** (nu * np.cos(p) ** 2 + nv * np.sin(p) ** 2)


def fit_error(a: np.ndarray, b: np.ndarray) -> float:
    """rms difference of two distributions sampled on the criterion's grid."""
    return float(np.sqrt(np.mean((np.asarray(a) - np.asarray(b)) ** 2)))


def _fit_scalar(err, lo: float, hi: float) -> float:
    """Minimize ``err(x)`` over ``x ∈ [lo, hi]`` (bounded, in log x), then polish."""
    res = minimize_scalar(
        lambda t: err(math.exp(t)),
        bounds=(math.log(lo), math.log(hi)),
        method="bounded",
        options={"xatol": 1e-10},
    )
    return math.exp(res.x)


def _equivalent(reference, model, lo: float, hi: float) -> Equivalence:
    """The parameter ``x ∈ [lo, hi]`` of ``model(γ, x)`` closest to ``reference(γ)``."""
    ref = reference(_GAMMA)
    x = _fit_scalar(lambda x: fit_error(ref, model(_GAMMA, x)), lo, hi)
    return Equivalence(x, fit_error(ref, model(_GAMMA, x)))


def phong_from_beckmann(m: float) -> Equivalence:
    """Phong exponent ``n`` equivalent to Beckmann rms slope ``m`` (seed: 0.32 → 4)."""
    m = check_positive("m", m)
    return _equivalent(lambda g: beckmann_shape(g, m), phong_shape, 1e-3, 1e5)


def beckmann_from_phong(n: float) -> Equivalence:
    """Beckmann ``m`` equivalent to Phong ``n`` (seed: n = 1 → m_max ≈ 0.51, the roughest
    surface a Phong lobe can stand for)."""
    n = check_positive("n", n)
    return _equivalent(lambda g: phong_shape(g, n), beckmann_shape, 1e-3, 10.0)


def blinn_from_beckmann(m: float) -> Equivalence:
    """Blinn exponent ``n_B`` equivalent to Beckmann ``m`` (seed: 0.32 → 17)."""
    m = check_positive("m", m)
    return _equivalent(lambda g: beckmann_shape(g, m), blinn_shape, 1e-3, 1e5)


def beckmann_from_blinn(n: float) -> Equivalence:
    """Beckmann ``m`` equivalent to Blinn ``n_B`` (seed: n_B = 4 → m ≈ 0.54)."""
    n = check_positive("n", n)
    return _equivalent(lambda g: blinn_shape(g, n), beckmann_shape, 1e-3, 10.0)


def ward_section_exponent(mx: float, my: float, phi: float = SEED_SECTION_PHI) -> Equivalence:
    """The single Ashikhmin/Blinn exponent ``N = n_u cos²φ + n_v sin²φ`` that best fits the
    section ``φ`` [rad] of Ward ``(m_x, m_y)`` (Table 3.1 × 4m², level 1 at ``γ = 0``), by the
    module's criterion on the ``γ`` grid. Every pair on the line ``n_u cos²φ + n_v sin²φ = N``
    fits that section equally well (the seed's §3.2.2 non-uniqueness)."""
    mx = check_positive("mx", mx)
    my = check_positive("my", my)
    phi = float(phi)
    if not math.isfinite(phi):
        raise ValueError(f"phi must be a finite angle in radians, got {phi!r}")
    return _equivalent(lambda g: ward_shape(g, phi, mx, my), blinn_shape, 1e-3, 1e6)


def ashikhmin_from_ward(mx: float, my: float, *, ratio: str | float | None = "slope"):
    """Ashikhmin–Shirley ``(n_u, n_v)`` equivalent to Ward ``(m_x, m_y)``.

    ``ratio="seed"``: the seed's §3.2.2 criterion as it states it (module docstring) — fit on
    the section ``φ = π/4`` (:func:`ward_section_exponent`, which fixes ``n_u + n_v = 2N``),
    the exponents split in the ratio of the slopes, ``n_u/n_v = m_y/m_x`` in our axes (the
    seed's ``m_x/m_y`` with its ``n_u`` along ``y``); ``error`` is the rms on that section.
    Seed example ``(0.1, 0.8)`` → ``(175.7, 22.0)``; the seed prints (10, 187), same sum,
    other split. ``ratio="slope"`` fixes ``n_u/n_v = (m_y/m_x)²`` and a number fixes
    ``n_u/n_v`` to it, both fitted on the ``(γ, φ)`` grid; ``None`` fits both freely there.
    """
    mx = check_positive("mx", mx)
    my = check_positive("my", my)
    if isinstance(ratio, str) and ratio not in ("slope", "seed"):
        raise ValueError(f"ratio must be 'slope', 'seed', a number > 0 or None, got {ratio!r}")
    if ratio == "seed":
        sec = ward_section_exponent(mx, my)
        r = my / mx
        c2, s2 = math.cos(SEED_SECTION_PHI) ** 2, math.sin(SEED_SECTION_PHI) ** 2
        nv = sec.value / (r * c2 + s2)
        return Equivalence((r * nv, nv), sec.error, SEED_CRITERION)
    g, p = np.meshgrid(_GAMMA[::4], _PHI, indexing="ij")
    ref = ward_shape(g, p, mx, my)

    def err(nu, nv):
        return fit_error(ref, ashikhmin_shape(g, p, nu, nv))

    if ratio is None:
        start = np.log([max(2 / mx**2, 1.0), max(2 / my**2, 1.0)])
        res = minimize(
            lambda x: err(*np.exp(x)),
            start,
            method="Nelder-Mead",
            options={"xatol": 1e-8, "fatol": 1e-12, "maxiter": 4000},
        )
        nu, nv = (float(v) for v in np.exp(res.x))
        return Equivalence((nu, nv), err(nu, nv))
    r = (my / mx) ** 2 if ratio == "slope" else check_positive("ratio", ratio)
    nv = _fit_scalar(lambda nv: err(r * nv, nv), 1e-4, 1e5)
    return Equivalence((r * nv, nv), err(r * nv, nv))


def ward_ashikhmin_grid_error(mx: float, my: float, nu: float, nv: float) -> float:
    """rms difference of Ward ``(m_x, m_y)`` and Ashikhmin ``(n_u, n_v)`` (level 1 at ``γ = 0``)
    on the full ``(γ, φ)`` grid of the module's criterion (peak = 1)."""
    g, p = np.meshgrid(_GAMMA[::4], _PHI, indexing="ij")
    return fit_error(ward_shape(g, p, mx, my), ashikhmin_shape(g, p, nu, nv))
