"""The public entry points: bistatic and backscatter coefficients, emissivity.

All take a roughness description (:mod:`emscatter.spectra`), a relative permittivity
(``exp(-iωt)``: ``Im ε ≥ 0``; or ``"pec"``), exactly one of ``frequency`` [Hz] or
``wavelength`` [m], and angles in radians that broadcast together (numpy rules).
``method="auto"`` picks the cheapest method valid for the regime (see
:mod:`emscatter.solvers.select`) and records it in the result.
"""

from __future__ import annotations

import inspect
import math

import numpy as np

from . import solvers
from .conventions import broadcast_angles, check_angle, check_finite, wavenumber
from .emissivity import Emissivity, hemispherical_reflectivity, lobe_width
from .fresnel import check_eps
from .scattering import Scattering
from .solvers import select
from .spectra import Roughness, check_roughness

__all__ = ["bistatic", "backscatter", "emissivity", "resolve_method"]


def _check_roughness(surface) -> Roughness:
    return check_roughness(surface, "surface")


def resolve_method(roughness: Roughness, k: float, method: str, out_of_range: str, eps=None):
    """``(name, module, report, make_nan)`` for a method name or ``"auto"``."""
    select.check_out_of_range(out_of_range)
    if not isinstance(method, str):
        raise ValueError(f"method must be 'auto' or one of {solvers.available()}, got {method!r}")
    if method.lower() == "auto":
        name, reports = select.select_method(roughness, k)
        report = reports[name]
    else:
        name = method.lower()
        module = solvers.get(name)  # raises for unknown names
        params = inspect.signature(module.check_validity).parameters
        extra = {"eps": eps} if eps is not None and "eps" in params else {}
        report = module.check_validity(roughness, k, **extra)
    make_nan = select.enforce(name, report, out_of_range, stacklevel=4)
    return name, solvers.get(name), report, make_nan


def bistatic(
    surface: Roughness,
    eps,
    *,
    frequency: float | None = None,
    wavelength: float | None = None,
    theta_i,
    theta_s,
    phi_s,
    phi_i=0.0,
    method: str = "auto",
    out_of_range: str = "warn",
    **options,
) -> Scattering:
    """Bistatic scattering coefficients σ⁰ (all four polarizations) and coherent reflectivity.

    Parameters
    ----------
    surface : roughness statistics (``dimension=2`` surface, or ``dimension=1`` profile).
    eps : relative permittivity of the lower medium (complex, ``Im ε ≥ 0``) or ``"pec"``.
    frequency : [Hz], or ``wavelength`` [m] — exactly one.
    theta_i, theta_s : incidence and scattering angles from the normal [rad], in [0, π/2].
    phi_s, phi_i : azimuths [rad]; ``phi_s = phi_i`` is the forward (specular) half-plane.
    method : ``"auto"``, ``"spm"``, ``"go"``, ``"po"`` or ``"mom"`` (1-D only).
    out_of_range : ``"warn"`` | ``"raise"`` | ``"nan"`` | ``"ignore"`` when the method is
        outside its validity range.
    options : passed to the solver (e.g. ``shadowing=False`` for ``"go"``).

    Returns
    -------
    :class:`emscatter.scattering.Scattering` — ``sigma0[pol_s, pol_i]`` linear,
    ``coherent[pol_i]``, ``method``.
    """
    rough = _check_roughness(surface)
    eps = check_eps(eps)
    k = wavenumber(frequency, wavelength)
    ti = check_angle("theta_i", theta_i)
    ts = check_angle("theta_s", theta_s)
    ps = check_finite("phi_s", phi_s).astype(float)
    pi_ = check_finite("phi_i", phi_i).astype(float)
    ti, ts, ps, pi_ = broadcast_angles(theta_i=ti, theta_s=ts, phi_s=ps, phi_i=pi_)
    name, module, report, make_nan = resolve_method(rough, k, method, out_of_range, eps)
    result = module.bistatic(rough, eps, k, ti, ts, ps, pi_, **options)
    info = {**result.info, "validity": report}
    sigma0, coherent = result.sigma0, result.coherent
    if make_nan:
        sigma0 = np.full_like(sigma0, np.nan)
        coherent = np.full_like(coherent, np.nan)
        info["out_of_range"] = True
    return Scattering(
        sigma0=sigma0,
        coherent=coherent,
        method=name,
        theta_i=result.theta_i,
        theta_s=result.theta_s,
        phi_s=result.phi_s,
        phi_i=result.phi_i,
        k=k,
        dimension=rough.dimension,
        info=info,
    )


def backscatter(
    surface: Roughness,
    eps,
    *,
    frequency: float | None = None,
    wavelength: float | None = None,
    theta_i,
    phi_i=0.0,
    method: str = "auto",
    out_of_range: str = "warn",
    **options,
) -> Scattering:
    """Monostatic (backscatter) coefficients: ``θs = θi``, ``φs = φi + π``."""
    ti = check_angle("theta_i", theta_i)
    pi_ = check_finite("phi_i", phi_i).astype(float)
    return bistatic(
        surface,
        eps,
        frequency=frequency,
        wavelength=wavelength,
        theta_i=ti,
        theta_s=ti,
        phi_s=pi_ + math.pi,
        phi_i=pi_,
        method=method,
        out_of_range=out_of_range,
        **options,
    )


def _integrate(module, rough, eps, k, ti, pi_, tol, options):
    """(r_coh, r_incoh, error, evaluations) by the shared hemispherical quadrature."""
    dims = (Ellipsis,) + (None,) * (1 if rough.dimension == 1 else 2)
    # σ⁰ only inside the integral: skip a solver's coherent part when it offers to.
    takes_flag = "coherent" in inspect.signature(module.bistatic).parameters
    skip = {"coherent": False} if takes_flag else {}

    def sigma0_fn(theta_s, phi_s):
        res = module.bistatic(rough, eps, k, ti[dims], theta_s, phi_s, pi_[dims], **skip, **options)
        return res.sigma0

    r_inc, err, evals = hemispherical_reflectivity(
        sigma0_fn,
        ti,
        pi_,
        dimension=rough.dimension,
        finest=lobe_width(rough, k),
        tol=tol,
    )
    r_coh = module.bistatic(rough, eps, k, ti, ti, pi_, pi_, **options).coherent
    return r_coh, r_inc, err, evals


def emissivity(
    surface: Roughness,
    eps,
    *,
    frequency: float | None = None,
    wavelength: float | None = None,
    theta_i,
    phi_i=0.0,
    method: str = "auto",
    tol: float = 1e-4,
    out_of_range: str = "warn",
    **options,
) -> Emissivity:
    """h and v emissivity ``e_p = 1 − r_coh,p − r_incoh,p`` (Kirchhoff's law) by hemispherical
    integration of the incoherent σ⁰ plus the coherent reflectivity, with an error estimate.

    ``tol`` [-]: absolute tolerance of the quadrature (the reported ``error`` is the difference
    of the last two refinements). Other parameters as :func:`bistatic`.
    """
    rough = _check_roughness(surface)
    eps = check_eps(eps)
    k = wavenumber(frequency, wavelength)
    ti = check_angle("theta_i", theta_i)
    pi_ = np.broadcast_to(check_finite("phi_i", phi_i).astype(float), ti.shape)
    if not (isinstance(tol, int | float) and math.isfinite(tol) and tol > 0):
        raise ValueError(f"tol must be a positive finite number, got {tol!r}")
    name, module, report, make_nan = resolve_method(rough, k, method, out_of_range, eps)
    if hasattr(module, "reflectivity"):  # e.g. the method of moments: its own far-field sums
        r_coh, r_inc, err = module.reflectivity(rough, eps, k, ti, pi_, **options)
        evals = 0
    else:
        r_coh, r_inc, err, evals = _integrate(module, rough, eps, k, ti, pi_, tol, options)
    e = 1.0 - r_coh - r_inc
    info = {"validity": report}
    if make_nan:
        e = np.full_like(e, np.nan)
        info["out_of_range"] = True
    return Emissivity(
        emissivity=e,
        coherent=r_coh,
        incoherent=r_inc,
        error=err,
        method=name,
        theta_i=ti,
        evaluations=evals,
        info=info,
    )
