"""The rough-dielectric BTDF at renderer direction pairs: unpolarized and Mueller.

The transmission side of the BRDF bridge, from the GO microfacet transmission of
:mod:`emscatter.solvers.kirchhoff.transmission.go` (Walter, Marschner, Li & Torrance, EGSR 2007,
eq. 21 with GO's Beckmann slopes and Smith shadowing)::

    f_t(wi → wo) = σ⁰_t / (4π cosθi |cosθo|)      [1/sr]

Renderer frame (:mod:`.frames`): ``wi`` towards the light, *above* the surface (``z > 0``),
``wo`` towards the viewer, *below* it (``z < 0``), both pointing away from the surface; the
lower medium has ``ε`` (the material) relative to the upper one. ``f_t`` is the radiance BTDF
for light arriving along ``wi`` (Mitsuba 3's ``roughdielectric`` ``eval`` in radiance mode,
``si.wi`` = our ``wo``, its ``wo`` = our ``wi``, returns ``f_t · cosθi``); ``∫ f_t |cosθo| dωo``
is the transmitted fraction ``T``. In emscatter's angles ``k̂_i = −wi`` and ``k̂_t = wo``:
``θt = π − θ(wo)``, ``φt = φ(wo)``, ``φi = φ(wi) + π``.

Mueller matrices: the facet's real, power-normalized Jones matrix
(:func:`~emscatter.solvers.kirchhoff.transmission.go.transmission_jones`) through
:func:`.mueller.jones_to_mueller`, in emscatter's h/v bases or in Mitsuba's Stokes frames
(``mi.mueller.stokes_basis`` of each propagation direction, right-handed), converted exactly as
:func:`.mueller.to_frames` does for reflection. ``M₀₀`` is the unpolarized ``f_t``.
"""

from __future__ import annotations

import math

import numpy as np

from ..solvers.kirchhoff.common import check_roughness, slope_variances
from ..solvers.kirchhoff.transmission import go as gt
from . import frames
from .build import material_eps
from .mueller import D_MITSUBA, _hv, _rotate_stokes_basis, jones_to_mueller, stokes_basis

__all__ = ["btdf_at", "mueller_btdf_at", "emscatter_to_mitsuba"]

_OPTIONS = ("shadowing", "slope_variance", "k_max")


def checked_surface(surface, options, what: str = "a BTDF"):
    """The roughness of a GO BTDF (a 2-D surface) with ``options`` among :data:`_OPTIONS`
    (clear errors naming what is wrong)."""
    unknown = set(options) - set(_OPTIONS)
    if unknown:
        raise ValueError(
            f"unknown option(s) {sorted(unknown)} for the GO BTDF; allowed: {list(_OPTIONS)}"
        )
    rough = check_roughness(surface, "surface")
    if rough.dimension != 2:
        raise ValueError(f"{what} needs a 2-D surface (dimension=2), got a 1-D profile")
    return rough


def _setup(surface, material, wavelength, wi, wo, options):
    rough = checked_surface(surface, options)
    lam = float(wavelength)
    if not (math.isfinite(lam) and lam > 0):
        raise ValueError(f"wavelength must be a positive finite number [m], got {wavelength!r}")
    eps = material_eps(material, lam)
    try:
        e = gt.check_transmission_eps(eps)
    except ValueError as err:
        raise ValueError(f"material {material!r} at λ = {lam:.6g} m: {err}") from None
    th_i, ph_i = frames.angles(wi, "wi")
    th_o, ph_o = frames.angles(wo, "wo")
    if np.any(th_i >= math.pi / 2):
        raise ValueError("wi must point above the surface (z > 0, towards the light)")
    if np.any(th_o <= math.pi / 2):
        raise ValueError("wo must point below the surface (z < 0, towards a viewer inside)")
    ti, pi_, tt, pt = np.broadcast_arrays(th_i, ph_i + math.pi, math.pi - th_o, ph_o)
    return rough, e, 2 * math.pi / lam, ti, pi_, tt, pt


def btdf_at(surface, material, wavelength, wi, wo, **options) -> np.ndarray:
    """Unpolarized GO BTDF ``f_t`` [1/sr] at renderer directions ``wi`` (``(..., 3)``, above,
    towards the light) and ``wo`` (``(..., 3)``, below, towards the viewer), broadcast.

    ``surface``: a 2-D :class:`emscatter.spectra.Roughness`; ``material``: a lossless
    dielectric (real ``ε > 0``, ``ε ≠ 1``: a number or anything
    :func:`emscatter.materials.eps_at` takes); ``wavelength`` [m]; options ``shadowing``
    (True/"correlated", "separable" = Mitsuba's, False), ``slope_variance``, ``k_max`` as
    :func:`emscatter.solvers.kirchhoff.transmission.go.bistatic_transmission`."""
    rough, e, k, ti, pi_, tt, pt = _setup(surface, material, wavelength, wi, wo, options)
    res = gt.bistatic_transmission(rough, e, k, ti, tt, pt, pi_, **options)
    return res.unpolarized() / (4 * math.pi * np.cos(ti) * np.cos(tt))


def mueller_btdf_at(
    surface, material, wavelength, wi, wo, *, frame: str = "mitsuba", **options
) -> np.ndarray:
    """Mueller BTDF ``(4, 4, ...)`` [1/sr] at renderer directions (as :func:`btdf_at`).

    ``frame="mitsuba"``: Mitsuba's Stokes frames (what a ``*_polarized`` ``roughdielectric``
    ``eval`` returns divided by ``cosθi``); ``"emscatter"``: emscatter's h/v bases (incident
    ``(ĥ_i, v̂_i)``, transmitted ``(ĥ_t, v̂_t)``). ``M[0, 0]`` equals :func:`btdf_at`."""
    if frame not in ("mitsuba", "emscatter"):
        raise ValueError(f"frame must be 'mitsuba' or 'emscatter', got {frame!r}")
    rough, e, k, ti, pi_, tt, pt = _setup(surface, material, wavelength, wi, wo, options)
    mode = gt.check_transmission_shadowing(options.get("shadowing", True))
    sx, sy = slope_variances(rough, options.get("k_max"), options.get("slope_variance"), k=k)
    inten = gt.transmission_intensity(e, ti, tt, pt, pi_, sx, sy, mode)
    jones = gt.transmission_jones(e, ti, tt, pt, pi_)
    m = jones_to_mueller(jones) * (inten / (4 * math.pi * np.cos(ti) * np.cos(tt)))
    if frame == "emscatter":
        return m
    return emscatter_to_mitsuba(m, ti, pi_, tt, pt)


def emscatter_to_mitsuba(m, ti, pi_, tt, pt) -> np.ndarray:
    """A transmission Mueller matrix ``(4, 4, ...)`` from emscatter's h/v bases into
    Mitsuba's Stokes frames, at emscatter angles ``θi, φi`` (incident ``k̂_i``) and ``θt, φt``
    (transmitted ``k̂_t``) [rad], broadcast (as :func:`mueller_btdf_at`)."""
    ti, pi_, tt, pt = np.broadcast_arrays(ti, pi_, tt, pt)
    ki, hi, _ = _hv(ti, pi_, -1.0)
    kt, ht, _ = _hv(tt, pt, -1.0)
    r_in = _rotate_stokes_basis(ki, hi, stokes_basis(ki))
    r_out = _rotate_stokes_basis(kt, ht, stokes_basis(kt))
    m = np.einsum("ij,jk...,kl->il...", D_MITSUBA, m, D_MITSUBA)
    return np.einsum("ij...,jk...,lk...->il...", r_out, m, r_in)
