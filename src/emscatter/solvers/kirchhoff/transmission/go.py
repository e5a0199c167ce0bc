"""Geometric-optics (microfacet) transmission through a rough dielectric interface: the BTDF.

The transmitted counterpart of :mod:`emscatter.solvers.kirchhoff.go`, after Walter, Marschner,
Li & Torrance, "Microfacet models for refraction through rough surfaces", EGSR 2007 (below
"W07"), with the Beckmann distribution of GO's slope variances.

Geometry
--------
The incident wave propagates along ``k̂_i = (sinθi cosφi, sinθi sinφi, −cosθi)`` in the upper
medium (index 1); the transmitted wave along ``k̂_t = (sinθt cosφt, sinθt sinφt, −cosθt)``
in the lower one, of relative permittivity ``ε`` and index ``η = √ε`` (real: a lossless
dielectric). ``θt ∈ [0, π/2]`` is measured from the *downward* normal, so the refracted
direction of a flat interface is ``sinθt = sinθi/η``, ``φt = φi``. ``ε < 1`` is incidence from
the denser side (e.g. under water looking up: ``ε = 1/ε_water``), total internal reflection
included. With W07's directions pointing away from the surface, ``i = −k̂_i``, ``o = k̂_t``,
the generalized half vector (W07 eq. 16) is ``ĥ ∝ ±(i + η o)``, the sign giving ``ĥ_z > 0``;
the facet refracts ``i`` into ``o`` only where ``i·ĥ > 0`` and ``o·ĥ < 0`` (W07 eq. 18's χ⁺).

Transmission coefficient (power, per unit area, like σ⁰ of reflection)::

    σ⁰_t,pq = 4π cosθi cosθt f_t,pq
            = 4π |i·ĥ| |o·ĥ| η² |J_pq|² D(ĥ) G(i, o) / |i + η o|²          (W07 eq. 21)

so that the transmitted fraction is ``T = ∫ σ⁰_t / (4π cosθi) dΩ_t`` over the lower
hemisphere, as ``R = ∫ σ⁰ / (4π cosθi) dΩ_s`` for the reflection. ``f_t`` is the radiance
BTDF for light arriving along ``i`` (W07's ``η_o²`` numerator: the radiance compression;
Mitsuba 3's ``roughdielectric`` in radiance mode with ``wo`` the light direction).
``(i·ĥ + η o·ĥ)² = |i + η o|²`` since ``ĥ ∥ i + η o``.

* ``D(ĥ) = p(−h_x/h_z, −h_y/h_z) / h_z⁴`` is the Beckmann distribution (W07 eq. 25) of the
  Gaussian slope density ``p`` of :mod:`.go` (per-direction variances ``sx, sy``; Mitsuba's
  ``α² = 2 s``).
* ``G`` is Smith's shadowing with the Gaussian ``Λ`` of
  :func:`emscatter.solvers.kirchhoff.common.smith_lambda` (W07 eqs. 23, 27):
  ``"separable"``: ``G1(i) G1(o)`` (W07 eq. 23; Mitsuba 3); ``"correlated"`` (default, also
  ``True``): height-correlated, ``B(1 + Λ(i), 1 + Λ(o))`` (the Beta function; Heitz 2014,
  JCGT 3(2), §6.3 eq. 102: a point at height ``h`` is lit with probability ``C(h)^Λi`` and
  seen from below with ``(1 − C(h))^Λo``); ``False``: none. The reflection forms
  ``"direction-correlated"``/``"smith"`` are for reflection only and are refused here.
* ``J_pq`` is the facet's power-normalized Fresnel transmission, rotated into emscatter's h/v
  bases (``ĥ = ẑ × k̂/|ẑ × k̂|``, ``v̂ = ĥ × k̂``, :mod:`emscatter.conventions`): with the
  facet's TE vector ``t̂ ∝ k̂_i × k̂_t`` and TM vectors ``d̂ = t̂ × k̂``,
  ``J_pq = τ_h (p̂_t·t̂)(q̂_i·t̂) + τ_v (p̂_t·d̂_t)(q̂_i·d̂_i)``, ``τ_p = √(1 − |R_p(θl)|²)`` at
  the local incidence cosine ``cosθl = i·ĥ`` (real, ≥ 0 for a lossless interface; Born &
  Wolf §1.5.3). Rotations keep ``Σ_pq |J_pq|² = T_h + T_v``, so the unpolarized value carries
  ``1 − F`` with ``F = (|R_h|² + |R_v|²)/2``, W07's Fresnel term.

Energy. With the reflection of :mod:`.go` (same ``ε``, same slope variances), ``R + T = 1``
would hold exactly for a flat lossless interface. Rough, single scattering: the shadowed
fraction of the light is lost (no multiple scattering between facets), so ``R + T < 1`` by
a deficit that grows towards grazing incidence (up to 75°); the same deficit is in
Mitsuba's ``roughdielectric`` (W07's model; its albedo integrated from its own ``eval`` on
the same grid equals ours to 3.2e-4 at α = 0.4, θi ≤ 70°). Measured deficit
``1 − (R + T)`` for ``ε = 2.25``, separable Smith (``tests/test_go_transmission.py``;
height-correlated, and GO's default direction-correlated reflection, within 1e-3 of it),
quadrature error < 1e-4::

    α, θi:    0°        30°       60°       75°
    0.1        0         0         4e-5      1.24e-2
    0.3        1e-5      7.1e-4    2.17e-2   4.84e-2
    0.5        2.8e-3    9.0e-3    3.68e-2   4.71e-2

Part of it is light sent by a single facet into the wrong hemisphere (reflected below the
horizon or refracted above it), which single scattering drops too; without shadowing the
slope-space total is Smith's ``1 + Λ(θi)`` exactly (tested).

Validity: that of GO (:func:`emscatter.solvers.kirchhoff.go.check_validity`).
"""

from __future__ import annotations

import math
import warnings

import numpy as np
from scipy import special

from emscatter.conventions import check_angle, check_finite, check_positive
from emscatter.fresnel import check_eps, is_pec
from emscatter.scattering import Scattering
from emscatter.solvers.kirchhoff import go
from emscatter.solvers.kirchhoff.common import (
    _a,
    check_roughness,
    fast_fresnel,
    slope_variances,
    smith_lambda,
)

__all__ = [
    "bistatic_transmission",
    "transmission_jones",
    "transmission_intensity",
    "check_transmission_eps",
    "check_lossy_transmission_eps",
    "check_transmission_shadowing",
]

#: Relative tolerance on ``Im ε`` (against ``|ε|``) below which ``ε`` counts as lossless.
LOSSLESS_RTOL = 1e-12

_TAU_EPS = 1e-28

#: The ``out_of_range`` policies of the PO, SPM and IEM transmissions (:func:`transmission_policy`):
#: warn, raise, blank with NaN, ignore.
OUT_OF_RANGE = ("warn", "raise", "nan", "ignore")


def transmission_angles(e, eps, theta_i, theta_t, phi_t, phi_i) -> tuple:
    """The transmission solvers' angles checked (θ in [0, π/2], φ finite and real) and broadcast
    with the checked permittivity ``e`` (``eps``: the caller's argument, for the message):
    ``(theta_i, theta_t, phi_t, phi_i, e)`` [rad], or a ValueError naming the shapes."""
    ti = check_angle("theta_i", theta_i)
    tt = check_angle("theta_t", theta_t)
    pt = check_finite("phi_t", phi_t)
    pi_ = check_finite("phi_i", phi_i)
    for name, arr in (("phi_t", pt), ("phi_i", pi_)):
        if np.iscomplexobj(arr):
            raise TypeError(f"{name} must be real (radians), got a complex array")
    try:
        return tuple(np.broadcast_arrays(ti, tt, pt.astype(float), pi_.astype(float), e))
    except ValueError:
        raise ValueError(
            "angle arrays (and eps) do not broadcast together: theta_i"
            f"{np.shape(theta_i)}, theta_t{np.shape(theta_t)}, phi_t{np.shape(phi_t)}, "
            f"phi_i{np.shape(phi_i)}, eps{np.shape(eps)}"
        ) from None


def transmission_policy(
    validity: dict, shape, out_of_range: str, *, label: str, warning: type[Warning]
) -> tuple[np.ndarray, np.ndarray]:
    """The transmission solvers' ``out_of_range`` policy from a validity report
    (:func:`emscatter.solvers.validity.build_report`, checked at ``theta_i`` of ``shape``):
    ``(failing, blank)``, boolean masks of ``shape``.

    ``failing`` marks the geometries outside the validity (all of them when a roughness check,
    a name in ``validity["details"]``, fails; else those with ``angle_valid`` false): what
    ``info["out_of_range"]`` holds whatever the policy. ``blank`` is what to set NaN: ``failing``
    for ``"nan"``, none otherwise; ``"raise"`` raises a ValueError and ``"warn"`` warns with
    the class ``warning`` (at the caller of the solver), both with the message
    ``f"{label}: {reasons}"`` (``label`` e.g. "PO transmission used outside the Kirchhoff
    approximation's validity"); ``"ignore"`` and a valid report: neither."""
    if not all(validity["checks"].get(n, True) for n in validity.get("details", {})):
        failing = np.ones(shape, dtype=bool)
    else:
        angle_ok = np.asarray(validity.get("angle_valid", True), dtype=bool)
        failing = ~np.broadcast_to(angle_ok, shape)
    if validity.get("valid", True) or out_of_range == "ignore":
        return failing, np.zeros(shape, dtype=bool)
    why = "; ".join(validity.get("reasons", [])) or "outside its validity range"
    msg = f"{label}: {why}"
    if out_of_range == "raise":
        raise ValueError(msg + " (out_of_range='warn' computes anyway, 'nan' blanks those angles)")
    if out_of_range == "warn":
        warnings.warn(msg + " (out_of_range='nan' blanks them, 'raise' stops)", warning, 3)
        return failing, np.zeros(shape, dtype=bool)
    return failing, failing


def check_transmission_eps(eps) -> np.ndarray:
    """``ε`` as a real float array, or a ValueError: the BTDF needs a real index ``η = √ε``
    (a lossless dielectric, ``ε > 0``, ``ε ≠ 1``); PEC and absorbing media are refused
    (GO's facets refract rays: an absorbing medium's inhomogeneous wave has no real ray, and
    the microfacet BTDF has no depth to attenuate it over; the PO and SPM solvers take a
    lossy ε through :func:`check_lossy_transmission_eps`)."""
    if is_pec(eps):
        raise ValueError(
            "eps='pec': a perfect conductor transmits nothing; GO transmission needs a "
            "lossless dielectric (real eps > 0, eps != 1)"
        )
    e = check_eps(eps)
    im = np.imag(e)
    re = np.real(e)
    if np.any(np.abs(im) > LOSSLESS_RTOL * np.abs(e)):
        bad = np.broadcast_to(e, im.shape)[np.abs(im) > LOSSLESS_RTOL * np.abs(e)].ravel()[0]
        raise ValueError(
            f"eps must be real for GO transmission (a lossless dielectric: the microfacet BTDF "
            f"of Walter et al. 2007 needs a real index η = √ε; an absorbing medium attenuates "
            f"the transmitted wave, which this model has no depth for), got eps = {bad!r}"
        )
    if np.any(re <= 0) or np.any(re == 1.0):
        bad = np.broadcast_to(re, np.shape(re))[(re <= 0) | (re == 1.0)].ravel()[0]
        raise ValueError(
            f"eps must be > 0 and != 1 for GO transmission (eps = 1 is no interface: the "
            f"transmitted field is the undisturbed incident one), got eps = {bad!r}"
        )
    return np.asarray(re, dtype=float)


def check_lossy_transmission_eps(eps, method: str) -> np.ndarray:
    """``ε`` as a complex array for the solvers that accept an absorbing lower medium (SPM,
    PO): finite, ``Im ε ≥ 0`` (emscatter's ``exp(−iωt)`` convention; a negative imaginary part
    is a ConventionError naming the value), not "pec", and for a real ``ε``: ``ε > 0``,
    ``ε ≠ 1``. ``method`` names the solver in the messages ("SPM", "PO")."""
    if is_pec(eps):
        raise ValueError(
            f"eps='pec': a perfect conductor transmits nothing; {method} transmission needs a "
            "dielectric (complex eps with Im eps >= 0, or real eps > 0, eps != 1)"
        )
    e = check_eps(eps)
    lossless = np.abs(np.imag(e)) <= LOSSLESS_RTOL * np.abs(e)
    re = np.real(e)
    wrong = lossless & ((re <= 0) | (re == 1.0))
    if np.any(wrong):
        bad = np.broadcast_to(e, wrong.shape)[wrong].ravel()[0]
        raise ValueError(
            f"eps must be > 0 and != 1 for {method} transmission when real (eps = 1 is no "
            f"interface; a real eps <= 0 has no propagating or absorbing transmitted wave), "
            f"got eps = {bad!r}; an absorbing medium has Im eps > 0 (exp(-i omega t))"
        )
    return np.where(lossless, re + 0j, e).astype(complex)


def check_transmission_shadowing(shadowing) -> str | None:
    """The transmission shadowing mode: True/"correlated" → ``"correlated"`` (height-correlated
    Beta form), ``"separable"``, False/None → no shadowing; anything else a ValueError."""
    if shadowing is True or shadowing == "correlated":
        return "correlated"
    if shadowing is False or shadowing is None:
        return None
    if shadowing == "separable":
        return "separable"
    raise ValueError(
        "shadowing must be True/'correlated' (height-correlated Smith, Heitz 2014 eq. 102), "
        "'separable' (G1(i) G1(o), Walter et al. 2007 eq. 23; Mitsuba's roughdielectric) or "
        f"False/None for GO transmission, got {shadowing!r} ('direction-correlated' and "
        "'smith' are reflection forms)"
    )


def _dirs(ti, pi_, tt, pt):
    """Unit vectors (3, ...) ``i = −k̂_i``, ``o = k̂_t`` and emscatter's h/v bases."""
    sti, cti = np.sin(ti), np.cos(ti)
    stt, ctt = np.sin(tt), np.cos(tt)
    cpi, spi, cpt, spt = np.cos(pi_), np.sin(pi_), np.cos(pt), np.sin(pt)
    ki = np.stack([sti * cpi, sti * spi, -cti])
    kt = np.stack([stt * cpt, stt * spt, -ctt])
    zero = np.zeros_like(cpi)
    hi = np.stack([-spi, cpi, zero])
    ht = np.stack([-spt, cpt, np.zeros_like(cpt)])
    vi = np.cross(hi, ki, axis=0)
    vt = np.cross(ht, kt, axis=0)
    return ki, kt, hi, vi, ht, vt


def _dot(a, b):
    return np.einsum("i...,i...->...", a, b)


def _half(ki, kt, eta):
    """Generalized half vector ``ĥ`` (h_z ≥ 0), ``i·ĥ``, ``o·ĥ``, ``|i + η o|²`` (W07 eq. 16)."""
    w = -ki + eta * kt
    w2 = _dot(w, w)
    norm = np.sqrt(np.maximum(w2, 1e-300))
    sign = np.where(w[2] < 0, -1.0, 1.0)
    h = w * (sign / norm)
    return h, _dot(-ki, h), _dot(kt, h), w2


def transmission_jones(eps, theta_i, theta_t, phi_t, phi_i=0.0) -> np.ndarray:
    """The facet transmission Jones matrix ``J[pol_t, pol_i]`` ``(2, 2, ...)`` (real, power
    normalized ``τ_p = √(1 − |R_p|²)``, emscatter's h/v bases; module docstring) at
    emscatter angles [rad]; zero where no facet refracts ``k̂_i`` into ``k̂_t``."""
    eta_e = check_transmission_eps(eps)
    ti, tt = check_angle("theta_i", theta_i), check_angle("theta_t", theta_t)
    pt, pi_ = check_finite("phi_t", phi_t), check_finite("phi_i", phi_i)
    ti, tt, pt, pi_, e = np.broadcast_arrays(ti, tt, pt, pi_, eta_e)
    return _jones(e, ti, tt, pt.astype(float), pi_.astype(float))


def _jones(e, ti, tt, pt, pi_, eta=None):
    """(the facet geometry uses the real index ``eta``, default ``√e``; PO passes ``Re √ε``
    with a complex ``e`` for an absorbing medium, whose facet Fresnel is then lossy)"""
    eta = np.sqrt(e) if eta is None else eta
    ki, kt, hi, vi, ht, vt = _dirs(ti, pi_, tt, pt)
    _, ci, co, _ = _half(ki, kt, eta)
    ok = (ci > 0) & (co < 0)
    cl = np.clip(ci, 0.0, 1.0)
    rh2, rv2, _ = fast_fresnel(e, cl, cross=False)
    tau_h = np.sqrt(np.clip(1.0 - rh2, 0.0, 1.0))
    tau_v = np.sqrt(np.clip(1.0 - rv2, 0.0, 1.0))
    tau = np.cross(ki, kt, axis=0)
    t2 = _dot(tau, tau)
    degenerate = t2 < _TAU_EPS  # straight through (k̂_t ∥ k̂_i): any t̂ ⊥ k̂_i, take ĥ_i
    t = np.where(degenerate, hi, tau / np.sqrt(np.where(degenerate, 1.0, t2)))
    di, dt = np.cross(t, ki, axis=0), np.cross(t, kt, axis=0)
    out_b, in_b = (ht, vt), (hi, vi)
    j = np.empty((2, 2, *ci.shape))
    for s in range(2):  # the four polarization pairs (not angles)
        ps, pt_ = _dot(out_b[s], t), _dot(out_b[s], dt)
        for i in range(2):
            j[s, i] = tau_h * ps * _dot(in_b[i], t) + tau_v * pt_ * _dot(in_b[i], di)
    return np.where(ok, j, 0.0)


def _lambda_dir(cos_t, sin_t, phi, sx, sy):
    s2 = sx * np.cos(phi) ** 2 + sy * np.sin(phi) ** 2 if sx != sy else sx
    return smith_lambda(_a(cos_t, sin_t, s2))


def transmission_intensity(
    e, ti, tt, pt, pi_, sx: float, sy: float, mode: str | None
) -> np.ndarray:
    """The polarization-free factor ``4π |i·ĥ||o·ĥ| η² D(ĥ) G / |i + η o|²`` [-] of σ⁰_t
    (module docstring) at checked, broadcast emscatter angles [rad]; ``e`` real ε."""
    eta = np.sqrt(e)
    ki, kt, _, _, _, _ = _dirs(ti, pi_, tt, pt)
    h, ci, co, w2 = _half(ki, kt, eta)
    ok = (ci > 0) & (co < 0) & (h[2] > 0)
    hz = np.where(ok, h[2], 1.0)
    zx, zy = -h[0] / hz, -h[1] / hz
    expo = -0.5 * (zx * zx / sx + zy * zy / sy)
    d = np.exp(np.where(ok, expo, -np.inf)) / (2 * math.pi * math.sqrt(sx * sy) * hz**4)
    val = 4 * math.pi * np.abs(ci * co) * e * d / np.maximum(w2, 1e-300)
    if mode is not None:
        lam_i = _lambda_dir(np.cos(ti), np.sin(ti), pi_, sx, sy)
        lam_o = _lambda_dir(np.cos(tt), np.sin(tt), pt, sx, sy)
        if mode == "separable":
            val = val / ((1.0 + lam_i) * (1.0 + lam_o))
        else:  # height-correlated: B(1 + Λi, 1 + Λo)
            val = val * np.exp(
                special.gammaln(1 + lam_i) + special.gammaln(1 + lam_o)
                - special.gammaln(2 + lam_i + lam_o)
            )  # fmt: skip
    return np.where(ok, val, 0.0)


def bistatic_transmission(
    roughness,
    eps,
    k: float,
    theta_i,
    theta_t,
    phi_t,
    phi_i=0.0,
    *,
    shadowing: bool | str = True,
    k_max: float | None = None,
    slope_variance=None,
) -> Scattering:
    """GO bistatic *transmission* coefficients σ⁰_t ``[pol_t, pol_i]`` (module docstring).

    Parameters
    ----------
    roughness : :class:`emscatter.spectra.Roughness` (``dimension=2``).
    eps : real relative permittivity ``ε > 0``, ``ε ≠ 1`` of the lower medium to the upper
        (broadcasts with the angles); complex ``ε`` with ``Im ε > 0`` and "pec" are refused.
    k : free-space wavenumber [rad/m] (enters the slope variance of non-Gaussian correlations
        and the validity report).
    theta_i, theta_t, phi_t, phi_i : angles [rad], numpy-broadcast; ``θt`` from the downward
        normal (the refracted direction of a flat interface: ``sinθt = sinθi/√ε``, ``φt = φi``).
    shadowing : True/"correlated" (height-correlated Smith, default), "separable" (Mitsuba's
        ``roughdielectric``) or False.
    k_max, slope_variance : as :func:`emscatter.solvers.kirchhoff.go.bistatic`.

    Returns
    -------
    :class:`~emscatter.scattering.Scattering` with ``sigma0`` (2, 2, *shape) the transmission
    coefficient [-] (``theta_s``/``phi_s`` hold ``θt``/``φt``); ``coherent`` is the zero
    coherent transmissivity of GO's range (the Kirchhoff mean field is ``< e⁻⁴⁰`` where GO
    holds, as for reflection), ``info["direction"] = "transmission"``.
    """
    rough = check_roughness(roughness)
    if rough.dimension != 2:
        raise ValueError("GO transmission needs a 2-D surface (dimension=2), got a 1-D profile")
    k = check_positive("k", k, unit="rad/m")
    mode = check_transmission_shadowing(shadowing)
    e = check_transmission_eps(eps)
    ti, tt, pt, pi_, e = transmission_angles(e, eps, theta_i, theta_t, phi_t, phi_i)
    sx, sy = slope_variances(rough, k_max, slope_variance, k=k)
    inten = transmission_intensity(e, ti, tt, pt, pi_, sx, sy, mode)
    j = _jones(e, ti, tt, pt, pi_)
    sigma0 = j * j * inten
    if not np.all(np.isfinite(sigma0)):
        raise ValueError("GO transmission produced NaN/inf (please report the inputs)")
    info = {
        "direction": "transmission",
        "slope_variance": (sx, sy),
        "total_mean_square_slope": sx + sy,
        "shadowing": mode,
        "validity": go.check_validity(rough, k, slope_variance=(sx, sy)),
        "source": "Walter, Marschner, Li & Torrance 2007 (EGSR), eqs. 16, 21, 23, 25, 27",
    }
    return Scattering(
        sigma0=sigma0,
        coherent=np.zeros((2, *ti.shape)),
        method="kirchhoff-go-transmission",
        theta_i=ti,
        theta_s=tt,
        phi_s=pt,
        phi_i=pi_,
        k=k,
        dimension=2,
        info=info,
    )
