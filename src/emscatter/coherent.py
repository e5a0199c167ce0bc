"""The complex coherent (mean) reflected amplitude of a rough interface, and the classical
roughness factors it is compared with.

Solvers report the coherent *power* reflectivity ``r_coh,p(θi)`` (``Scattering.coherent``).
A ray tracer multiplies complex amplitudes along a path and needs the mean field itself:

``R_coh,p = √r_coh,p · exp(i arg R̄_p)``

* its power is exactly the solver's coherent reflectivity (so a path built from it and
  emscatter's own prediction agree by construction), and
* its phase is the method's mean-field phase: for ``"spm"`` the second-order mean field
  ``R̄ = R⁽⁰⁾ + σ² R⁽²⁾`` (the same quadrature :mod:`emscatter.solvers.spm` uses for its coherent
  reflectivity;
  SPM's consistent reflectivity is ``|R⁽⁰⁾|² + 2 Re(R⁽⁰⁾* σ²R⁽²⁾)``, which differs from
  ``|R̄|²`` at ``O((kσ)⁴)``); for the Kirchhoff methods (``"go"``, ``"po"``) and any solver
  without its own mean field the Kirchhoff mean field ``R̄ = R_Fresnel exp(−2k²σ²cos²θi)``
  (Tsang, Kong & Ding 2001 vol. III ch. 2; Ulaby, Moore & Fung 1982 vol. II ch. 12), whose
  factor is real and positive, so the phase is Fresnel's.

Time convention ``exp(−iωt)`` like the rest of the library (the Sionna bridge conjugates at its
boundary, :func:`emscatter.radio.convention.to_sionna_amplitude`).

Roughness factors (on the *field*; square them for power), with ``g = (2kσ cosθ)²``:

* Ament (1953), the Rayleigh / Kirchhoff factor: ``exp(−g/2) = exp(−2(kσ cosθ)²)``
  (:func:`ament_factor`);
* Boithias (1987) after Miller, Brown & Vegh (1984): ``exp(−g/2) I₀(g/2)``
  (:func:`boithias_factor`), derived for a sea surface of sinusoidal swell, not a Gaussian
  height distribution;
* Kirchhoff mean field through an interface (transmission): ``exp(−σ²(k₁z − k₂z)²/2)``
  (:func:`kirchhoff_transmission_factor`) — the same Gaussian average ``⟨e^{iqh}⟩ =
  e^{−q²σ²/2}`` with the vertical wavenumber change ``q`` across the interface.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .conventions import check_angle, check_finite, check_positive
from .fresnel import check_eps, fresnel_cos, is_pec
from .spectra import Roughness, check_roughness

__all__ = [
    "CoherentAmplitude",
    "coherent_amplitude",
    "kirchhoff_mean_field",
    "ament_factor",
    "boithias_factor",
    "kirchhoff_reflection_factor",
    "kirchhoff_transmission_factor",
    "rayleigh_parameter",
]


@dataclass(frozen=True)
class CoherentAmplitude:
    """Mean reflected field of a rough interface, per incident polarization (axis 0: h, v).

    ``amplitude`` complex (``exp(−iωt)``), ``power = |amplitude|²`` = the solver's coherent
    reflectivity [-]; ``method`` the solver that produced it; ``validity`` its report;
    ``info`` extra details (``"phase"``: where the phase comes from, ``"evaluations"``)."""

    amplitude: np.ndarray
    power: np.ndarray
    method: str
    validity: dict
    info: dict = field(default_factory=dict)

    h = property(lambda self: self.amplitude[0])
    v = property(lambda self: self.amplitude[1])


def kirchhoff_reflection_factor(k_z, sigma: float):
    """Kirchhoff mean-field reflection factor ``exp(−2 k_z² σ²)`` [-] for a Gaussian height
    distribution of rms ``sigma`` [m] and vertical wavenumber ``k_z`` [rad/m] of the medium the
    wave travels in (complex ``k_z`` allowed: lossy media, either time convention)."""
    kz = np.asarray(k_z)
    return np.exp(-2.0 * kz * kz * sigma * sigma)


def kirchhoff_transmission_factor(k1z, k2z, sigma: float):
    """Kirchhoff mean-field transmission factor ``exp(−σ²(k₁z − k₂z)²/2)`` [-] across a rough
    interface of rms height ``sigma`` [m] (``k₁z``, ``k₂z`` [rad/m] on either side)."""
    q = np.asarray(k1z) - np.asarray(k2z)
    return np.exp(-0.5 * q * q * sigma * sigma)


def ament_factor(k: float, sigma: float, theta) -> np.ndarray:
    """Ament (1953) / Rayleigh coherent factor on the field, ``exp(−2(kσ cosθ)²)`` [-];
    ``k`` [rad/m], ``sigma`` rms height [m], ``theta`` incidence [rad]."""
    kc = k * sigma * np.cos(np.asarray(theta, dtype=float))
    return np.exp(-2.0 * kc * kc)


def boithias_factor(k: float, sigma: float, theta) -> np.ndarray:
    """Boithias (1987) / Miller–Brown–Vegh (1984) coherent factor on the field,
    ``exp(−g/2) I₀(g/2)`` with ``g = (2kσ cosθ)²`` [-] (computed as ``i0e(g/2)``, stable for
    large ``g``)."""
    from scipy.special import i0e

    g = (2.0 * k * sigma * np.cos(np.asarray(theta, dtype=float))) ** 2
    return i0e(0.5 * g)


def kirchhoff_mean_field(roughness: Roughness, eps, k: float, theta_i) -> np.ndarray:
    """``R_Fresnel,p(θi) exp(−2k²σ²cos²θi)``, complex, shape ``(2, *shape)`` (h, v)."""
    rough = check_roughness(roughness)
    ti = check_angle("theta_i", theta_i)
    c = np.cos(ti)
    rh, rv = fresnel_cos(eps, c)
    att = kirchhoff_reflection_factor(k * c, rough.sigma)
    return np.stack([rh * att, rv * att])


def _spm_mean_field(rough, eps, k, ti_flat):
    """SPM's second-order mean field and consistent reflectivity at unique angles."""
    from emscatter.solvers.spm import model as spm

    uniq, inv = np.unique(ti_flat, return_inverse=True)
    # One quadrature per distinct angle; spm.coherent_reflectivity uses the same kernel.
    r0, r2 = spm._second_order_R(rough, eps, k, uniq, 16, 16)
    r2 = r2 * rough.sigma**2
    power = np.clip(np.abs(r0) ** 2 + 2.0 * (np.conj(r0) * r2).real, 0.0, 1.0)
    return (r0 + r2)[:, inv], power[:, inv], uniq.size


def coherent_amplitude(
    roughness: Roughness,
    eps,
    k: float,
    theta_i,
    *,
    method: str = "auto",
    out_of_range: str = "warn",
    **options,
) -> CoherentAmplitude:
    """Complex coherent reflection coefficient (module docstring) at incidence ``theta_i``
    [rad] (any shape) for a 2-D isotropic or anisotropic surface (φi = 0 frame).

    Parameters
    ----------
    roughness : :class:`~emscatter.spectra.Roughness`.
    eps : relative permittivity (``Im ε ≥ 0``, a scalar) or ``"pec"``.
    k : free-space wavenumber [rad/m].
    method : ``"auto"`` or a solver name (``"spm"``, ``"po"``, ``"go"``, ...).
    out_of_range : validity policy, as in :func:`emscatter.bistatic`.
    options : passed to the solver when the power comes from its ``bistatic``.
    """
    from . import api
    from .solvers import get

    rough = check_roughness(roughness)
    k = check_positive("k", k, unit="rad/m")
    eps = check_eps(eps)
    if not is_pec(eps) and np.ndim(eps) != 0:
        raise ValueError(f"eps must be a single permittivity here, got shape {np.shape(eps)}")
    ti = check_angle("theta_i", theta_i)
    shape = ti.shape
    flat = ti.ravel()
    name, module, report, make_nan = api.resolve_method(rough, k, method, out_of_range, eps)
    info: dict = {}
    if name == "spm":
        mean, power, n_eval = _spm_mean_field(rough, eps, k, flat)
        info["phase"] = "SPM second-order mean field R0 + sigma^2 R2"
        info["evaluations"] = n_eval
    else:
        mean = kirchhoff_mean_field(rough, eps, k, flat)
        res = get(name).bistatic(rough, eps, k, flat, flat, 0.0, 0.0, **options)
        power = np.asarray(res.coherent, dtype=float)
        info["phase"] = "Kirchhoff mean field R_Fresnel exp(-2 k^2 sigma^2 cos^2)"
        info["evaluations"] = flat.size
    mag = np.abs(mean)
    with np.errstate(invalid="ignore", divide="ignore"):
        unit = np.where(mag > 0, mean / np.where(mag > 0, mag, 1.0), 1.0 + 0j)
    amp = np.sqrt(np.clip(power, 0.0, None)) * unit
    if make_nan:
        amp = np.full_like(amp, np.nan)
        power = np.full_like(power, np.nan)
        info["out_of_range"] = True
    return CoherentAmplitude(
        amplitude=amp.reshape(2, *shape),
        power=np.asarray(power, dtype=float).reshape(2, *shape),
        method=name,
        validity=report,
        info=info,
    )


def rayleigh_parameter(k: float, sigma: float, theta) -> np.ndarray:
    """``g = (2kσ cosθ)²`` [-], the Rayleigh roughness parameter of both factors."""
    k = check_positive("k", k, unit="rad/m")
    th = check_finite("theta", theta).astype(float)
    return (2.0 * k * sigma * np.cos(th)) ** 2
