"""Shared pieces of the Kirchhoff (tangent-plane) solvers: geometry, local-specular
polarization factors, slope statistics, Smith shadowing and the coherent reflectivity.

Geometry (see :mod:`emscatter.conventions`): ``k_i = k (sinθi cosφi, sinθi sinφi, −cosθi)``,
``k_s = k (sinθs cosφs, sinθs sinφs, cosθs)`` and the scattering vector ``q = k_s − k_i``.
Lengths below are in units of ``k`` (``q̃ = q / k``, dimensionless).

Local specular facet (stationary phase)
---------------------------------------
The facets that reflect ``k_i`` into ``k_s`` have the normal ``n̂ = q/|q|``, the slopes
``(ζx, ζy) = (−qx/qz, −qy/qz)`` and the local incidence cosine ``cosθl = −k̂_i·n̂ = |q|/(2k)``
(Tsang, Kong & Ding 2001, vol. III, ch. 2; Ulaby, Moore & Fung 1982, vol. II, §12-4).

Polarization factors. With the facet's TE unit vector ``t̂ ∝ k̂_i × k̂_s`` and TM vectors
``d̂_i = t̂ × k̂_i``, ``d̂_s = t̂ × k̂_s``, the reflected field is
``E_r = R_h(θl) (E_i·t̂) t̂ + R_v(θl) (E_i·d̂_i) d̂_s`` (``R_v`` the ratio of magnetic fields,
as in :mod:`emscatter.fresnel`), so the amplitude for scattered ``p̂_s`` from incident ``q̂_i`` is

    F_pq = R_h (p̂_s·t̂)(q̂_i·t̂) + R_v (p̂_s·d̂_s)(q̂_i·d̂_i).

With ``ĥ = ẑ × k̂/|ẑ × k̂|`` and ``v̂ = ĥ × k̂`` (Tsang's basis) the four projections on
``τ = k̂_i × k̂_s`` are, with ``Δ = φs − φi`` (common sign dropped, it cancels in products),

    h_i·τ = cosθi sinθs cosΔ + sinθi cosθs      v_i·τ = sinθs sinΔ
    h_s·τ = sinθi cosθs cosΔ + cosθi sinθs      v_s·τ = sinθi sinΔ

and ``(p̂_s·d̂_s)``, ``(q̂_i·d̂_i)`` follow from ``ĥ·d̂ = −v̂·t̂``, ``v̂·d̂ = ĥ·t̂``. In the plane of
incidence ``F_hh = R_h(θl)``, ``F_vv = R_v(θl)`` and the cross terms vanish; out of the plane
they do not. Since the basis changes are rotations, ``Σ_pq |F_pq|² = |R_h|² + |R_v|²`` — the
unpolarized Fresnel factor of the Cook–Torrance model. At exact backscatter ``τ = 0``; there
``R_v(0) = −R_h(0)`` and ``E_r = R_h(0) E_i`` for any ``t̂`` (``t̂ = ĥ_i`` is used).
"""

from __future__ import annotations

import math

import numpy as np
from scipy import special

from ..conventions import broadcast_angles, check_angle, check_finite, check_positive
from ..fresnel import check_eps, fresnel_cos, is_pec
from ..spectra import Roughness

__all__ = [
    "Geometry",
    "geometry",
    "coherent_reflectivity",
    "fresnel_factors",
    "slope_variances",
    "smith_lambda",
    "shadowing",
    "check_roughness",
    "validity_report",
]

_TAU_EPS = 1e-28  # |k̂_i × k̂_s|² below this is treated as exact backscatter


def check_roughness(roughness) -> Roughness:
    if not isinstance(roughness, Roughness):
        raise TypeError(
            "roughness must be an emscatter.spectra Roughness (GaussianCorrelation, "
            f"ExponentialCorrelation, PowerLawCorrelation), got {type(roughness).__name__}"
        )
    return roughness


class Geometry:
    """Broadcast angles and the derived dimensionless vectors (units of ``k``)."""

    __slots__ = (
        "theta_i", "theta_s", "phi_s", "phi_i", "eps", "shape", "ci", "si", "cs", "ss",
        "cd", "sd", "qx", "qy", "qz", "q2", "cos_l",
    )  # fmt: skip


def geometry(theta_i, theta_s, phi_s, phi_i, eps, dimension: int) -> Geometry:
    """Check and broadcast the angles [rad] and ``eps``; compute ``q/k`` and ``cosθl``.

    For ``dimension=1`` (profile along x) the scattering is in the x–z plane: ``sin φi`` and
    ``sin φs`` must vanish (``φ ∈ {0, π}`` modulo 2π).
    """
    ti = check_angle("theta_i", theta_i)
    ts = check_angle("theta_s", theta_s)
    ps = check_finite("phi_s", phi_s)
    pi_ = check_finite("phi_i", phi_i)
    for name, arr in (("phi_s", ps), ("phi_i", pi_)):
        if np.iscomplexobj(arr):
            raise TypeError(f"{name} must be real (radians), got a complex array")
    ps = ps.astype(float)
    pi_ = pi_.astype(float)
    eps = check_eps(eps)
    arrays = {"theta_i": ti, "theta_s": ts, "phi_s": ps, "phi_i": pi_}
    if not is_pec(eps):
        arrays["eps"] = eps
    b = broadcast_angles(**arrays)
    g = Geometry()
    g.theta_i, g.theta_s, g.phi_s, g.phi_i = b[:4]
    g.eps = b[4] if len(b) > 4 else eps
    g.shape = g.theta_i.shape
    if dimension == 1:
        for name, arr in (("phi_i", g.phi_i), ("phi_s", g.phi_s)):
            if np.any(np.abs(np.sin(arr)) > 1e-9):
                bad = arr[np.abs(np.sin(arr)) > 1e-9].ravel()[0]
                raise ValueError(
                    f"{name} must be 0 or π (mod 2π) for a 1-D profile (scattering in the "
                    f"x–z plane), got {bad!r} rad"
                )
    g.ci, g.si = np.cos(g.theta_i), np.sin(g.theta_i)
    g.cs, g.ss = np.cos(g.theta_s), np.sin(g.theta_s)
    dphi = g.phi_s - g.phi_i
    g.cd, g.sd = np.cos(dphi), np.sin(dphi)
    cpi, spi = np.cos(g.phi_i), np.sin(g.phi_i)
    # q/k in the frame rotated by φi (x' along the incident azimuth), then rotated back.
    qxp = g.ss * g.cd - g.si
    qyp = g.ss * g.sd
    g.qx = qxp * cpi - qyp * spi
    g.qy = qxp * spi + qyp * cpi
    g.qz = g.cs + g.ci
    # |q|²/k² = 2 (1 − k̂i·k̂s) = 2 (1 + cosθi cosθs − sinθi sinθs cosΔ)
    g.q2 = np.maximum(2.0 * (1.0 + g.ci * g.cs - g.si * g.ss * g.cd), 0.0)
    g.cos_l = np.minimum(0.5 * np.sqrt(g.q2), 1.0)  # cosθl = |q|/(2k)
    return g


def fresnel_factors(g: Geometry, dimension: int) -> np.ndarray:
    """``|F_pq|²`` (module docstring), shape ``(2, 2, *shape)`` indexed ``[pol_s, pol_i]``."""
    rh, rv = fresnel_cos(g.eps, g.cos_l)
    rh = np.broadcast_to(rh, g.shape)
    rv = np.broadcast_to(rv, g.shape)
    a_h = rh.real**2 + rh.imag**2
    a_v = rv.real**2 + rv.imag**2
    out = np.zeros((2, 2, *g.shape))
    if dimension == 1:
        out[0, 0] = a_h
        out[1, 1] = a_v
        return out
    cross = rh.real * rv.real + rh.imag * rv.imag  # Re(R_h R_v*)
    hi = g.ci * g.ss * g.cd + g.si * g.cs
    vi = g.ss * g.sd
    hs = g.si * g.cs * g.cd + g.ci * g.ss
    vs = g.si * g.sd
    d = hi * hi + vi * vi
    degenerate = d < _TAU_EPS
    if np.any(degenerate):  # exact backscatter (or q = 0): t̂ = ĥ_i, see module docstring
        hi = np.where(degenerate, 1.0, hi)
        vi = np.where(degenerate, 0.0, vi)
        hs = np.where(degenerate, -1.0, hs)
        vs = np.where(degenerate, 0.0, vs)
        d = np.where(degenerate, 1.0, d)
    inv = 1.0 / (d * d)
    # (a, b) products: F_pq = (R_h a_pq + R_v b_pq) / |τ|²
    pairs = (
        ((0, 0), hs * hi, vs * vi),
        ((0, 1), hs * vi, -vs * hi),
        ((1, 0), vs * hi, -hs * vi),
        ((1, 1), vs * vi, hs * hi),
    )
    for (p, q), a, b in pairs:
        out[p, q] = (a_h * a * a + a_v * b * b + 2.0 * cross * a * b) * inv
    return out


def coherent_reflectivity(roughness, eps, k: float, theta_i) -> np.ndarray:
    """Kirchhoff coherent reflectivity ``|R_p(θi)|² exp(−(2kσ cosθi)²)`` [-], shape
    ``(2, *shape)`` (h, v) — Ulaby, Moore & Fung (1982) vol. II eq. 12.x; Tsang et al. (2001)
    vol. III ch. 2 (the Kirchhoff mean field is ``R exp(−2k²σ²cos²θi)``).

    ``theta_i`` [rad] broadcasts with ``eps``; ``k`` [rad/m]."""
    rough = check_roughness(roughness)
    k = check_positive("k", k, unit="rad/m")
    ti = check_angle("theta_i", theta_i)
    eps = check_eps(eps)
    ci = np.cos(ti)
    if not is_pec(eps):
        ci, eps = np.broadcast_arrays(ci, eps)
    rh, rv = fresnel_cos(eps, ci)
    att = np.exp(-((2.0 * k * rough.sigma * ci) ** 2))
    return np.stack(
        [np.broadcast_to(np.abs(rh) ** 2 * att, ci.shape), np.abs(rv) ** 2 * att]
    )


def slope_variances(roughness: Roughness, k_max=None, slope_variance=None) -> tuple[float, float]:
    """Per-direction slope variances ``(⟨ζx²⟩, ⟨ζy²⟩)`` [-] (``⟨ζy²⟩ = 0`` for a profile).

    ``slope_variance`` overrides: a float (the per-direction variance, isotropic) or a pair.
    Otherwise ``roughness.mean_square_slope(k_max)``; exponential and power-law correlations
    need ``k_max`` [rad/m] (or ``slope_variance``) since their slope variance is infinite.
    """
    if slope_variance is not None:
        sv = np.atleast_1d(check_finite("slope_variance", slope_variance)).astype(float)
        if sv.ndim != 1 or sv.size not in (1, 2) or np.any(sv <= 0) or np.iscomplexobj(sv):
            raise ValueError(
                "slope_variance must be a positive float (per-direction ⟨ζx²⟩ = ⟨ζy²⟩) or a "
                f"pair (⟨ζx²⟩, ⟨ζy²⟩), got {slope_variance!r}"
            )
        sx = float(sv[0])
        sy = float(sv[-1])
    else:
        try:
            sx, sy = roughness.mean_square_slope(k_max)
        except ValueError as exc:
            raise ValueError(
                f"{exc}; or pass slope_variance=(⟨ζx²⟩, ⟨ζy²⟩) to the Kirchhoff solver"
            ) from None
    if roughness.dimension == 1:
        sy = 0.0
    return sx, sy


def smith_lambda(a: np.ndarray) -> np.ndarray:
    """Smith's ``Λ(a) = [exp(−a²)/(a√π) − erfc(a)] / 2`` for Gaussian slopes (Smith 1967,
    IEEE TAP 15; Walter et al. 2007 eq. 27 form ``G1 = 1/(1+Λ)``), ``a = cotθ/(√2 s)``."""
    a = np.maximum(a, 1e-300)
    lam = 0.5 * (np.exp(-a * a) / (a * math.sqrt(math.pi)) - special.erfc(a))
    return np.where(a > 26.0, 0.0, np.maximum(lam, 0.0))


def _g1(cos_t, sin_t, s2_dir):
    # a = cotθ / (√2 s) ; s2_dir = slope variance along the azimuth of the direction
    with np.errstate(divide="ignore"):
        a = np.where(sin_t > 0, cos_t / np.maximum(sin_t * np.sqrt(2.0 * s2_dir), 1e-300), np.inf)
    a = np.minimum(a, 1e300)
    return 1.0 / (1.0 + smith_lambda(a))


def shadowing(g: Geometry, sx: float, sy: float, mode="smith") -> np.ndarray:
    """Bistatic shadowing/masking factor [-].

    ``"smith"``: separable ``G1(θi) G1(θs)`` with Smith's ``G1 = 1/(1+Λ(a))`` (Smith 1967;
    the form used by Mitsuba 3's microfacet models, Walter et al. 2007 eqs. 23–27);
    ``"correlated"``: height-correlated ``1/(1+Λ(a_i)+Λ(a_s))`` (Sancer 1969 for the
    forward half-space; Heitz 2014). The slope variance along each direction's azimuth is
    ``sx cos²φ + sy sin²φ`` (anisotropic Gaussian slopes).
    """
    cpi, spi = np.cos(g.phi_i), np.sin(g.phi_i)
    cps, sps = np.cos(g.phi_s), np.sin(g.phi_s)
    s2i = sx * cpi**2 + sy * spi**2 if sy > 0 else np.full(g.shape, sx)
    s2s = sx * cps**2 + sy * sps**2 if sy > 0 else np.full(g.shape, sx)
    if mode == "smith":
        return _g1(g.ci, g.si, s2i) * _g1(g.cs, g.ss, s2s)

    def lam(c, s, s2):
        with np.errstate(divide="ignore"):
            a = np.where(s > 0, c / np.maximum(s * np.sqrt(2.0 * s2), 1e-300), np.inf)
        return smith_lambda(np.minimum(a, 1e300))

    return 1.0 / (1.0 + lam(g.ci, g.si, s2i) + lam(g.cs, g.ss, s2s))


def check_shadowing(shadowing_opt) -> str | None:
    if shadowing_opt is True or shadowing_opt == "smith":
        return "smith"
    if shadowing_opt is False or shadowing_opt is None:
        return None
    if shadowing_opt == "correlated":
        return "correlated"
    raise ValueError(
        f"shadowing must be True/'smith', 'correlated', or False/None, got {shadowing_opt!r}"
    )


def validity_report(roughness: Roughness, k: float, checks: list[tuple[str, bool, str]]) -> dict:
    """``{"valid", "reasons", "checks", "k_sigma", "k_l"}`` from (name, ok, text) triples."""
    reasons = [text for _, ok, text in checks if not ok]
    return {
        "valid": not reasons,
        "reasons": reasons,
        "checks": {name: ok for name, ok, _ in checks},
        "k_sigma": k * roughness.sigma,
        "k_l": k * roughness.length,
    }
