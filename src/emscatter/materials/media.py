"""Shared pieces of the natural-media models (soil, sea water): range checks that name the
parameter, the value and the range, and the Debye relaxation under ``exp(−iωt)``."""

from __future__ import annotations

import math

import numpy as np

from ..constants import EPSILON_0

#: 0 °C in kelvin: temperatures are given in K (SI) and converted to °C where the published
#: polynomials use °C.
ZERO_CELSIUS = 273.15


def check_parameter(
    name: str, value, low: float, high: float, *, unit: str, model: str, low_open=False
) -> float:
    """``value`` as a float, inside ``[low, high]`` (``(low, high]`` with ``low_open``), else a
    :class:`ValueError` naming the parameter, the value, the range and the model's source."""
    if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
        raise TypeError(f"{name} must be a real number [{unit}], got {value!r}")
    v = float(value)
    if not math.isfinite(v):
        raise ValueError(f"{name} must be finite [{unit}], got {v!r}")
    below = v <= low if low_open else v < low
    if below or v > high:
        bracket = "(" if low_open else "["
        raise ValueError(
            f"{name} = {v:g} {unit} is outside the range of {model}: "
            f"{bracket}{low:g}, {high:g}] {unit}"
        )
    return v


def debye(f: np.ndarray, eps_static, eps_inf, tau, conductivity=0.0) -> np.ndarray:
    """Single Debye relaxation plus ionic conduction under ``exp(−iωt)`` (``Im ε ≥ 0``):
    ``ε = ε∞ + (εs − ε∞)/(1 − iωτ) + iσ/(ωε₀)``; ``f`` [Hz], ``tau`` [s], ``conductivity``
    [S/m] (Debye 1929; the form of Klein & Swift 1977, conjugated to this convention)."""
    w = 2.0 * math.pi * np.asarray(f, dtype=float)
    return (
        eps_inf
        + (eps_static - eps_inf) / (1.0 - 1j * w * tau)
        + 1j * conductivity / (w * EPSILON_0)
    )


def out_of_band(material, f: np.ndarray, alternative: str):
    """:class:`~emscatter.materials.OutOfBandError` for a natural medium asked outside its
    fitted band: names the band, the frequency, and the ways out (no extrapolation switch:
    an empirical fit outside its data is not a documented model)."""
    from .core import OutOfBandError, _format_band, _format_point

    ok = material.in_band(f)
    if np.all(ok):
        return
    bad = float(np.asarray(f)[~ok].ravel()[0])
    lo, hi = material.band
    raise OutOfBandError(
        f"material {material.name!r} ({material.source}) is defined for {_format_band(lo, hi)}, "
        f"got frequency = {_format_point(bad)}. Ways out: {alternative}, or give the "
        "permittivity at that frequency yourself (a number or materials.Constant)."
    )
