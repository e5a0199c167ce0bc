"""Conventions shared by every module, and the input checks that enforce them.

Settled once, here:

* **Time dependence** ``exp(-iωt)``. A lossy medium therefore has ``Im ε ≥ 0``
  (the seed's ``ε = 17 + 2i``). An input with ``Im ε < 0`` is an error naming the
  convention and the fix (``numpy.conj``); it is never conjugated silently.
  The Sionna RT bridge (``exp(+jωt)``) converts at its own boundary.
* **Units**: SI everywhere (m, Hz, S/m). Angles are radians in the core; a public
  parameter that takes degrees says so in its name (``theta_i_deg``).
* **Polarization**: ``"h"`` (TE, E perpendicular to the plane of incidence) and ``"v"``
  (TM). Results are indexed ``[pol_s, pol_i]`` with index 0 = h and 1 = v, so
  ``"hv"`` is *scattered h from incident v* = ``sigma0[0, 1]``.
* **Geometry**: the mean surface is ``z = 0``, medium 1 (vacuum/air) above, medium 2
  (relative permittivity ε) below. Incident direction
  ``k_i = (sinθi cosφi, sinθi sinφi, −cosθi)``, scattered direction
  ``k_s = (sinθs cosφs, sinθs sinφs, cosθs)``; ``θ ∈ [0, π/2]``. The specular direction is
  ``θs = θi, φs = φi``; backscatter is ``θs = θi, φs = φi + π``.
  For 1-D profiles (2-D problems) the plane of incidence is the x–z plane and
  ``φs ∈ {φi, φi + π}`` only.
* **Randomness** only through a :class:`numpy.random.Generator` or a seed.
"""

from __future__ import annotations

import math
import numbers
from typing import Literal

import numpy as np

from .constants import SPEED_OF_LIGHT

TIME_CONVENTION = "exp(-i omega t)"
POLARIZATIONS: tuple[str, str] = ("h", "v")
POL_INDEX = {"h": 0, "v": 1}
POL_PAIRS: tuple[str, ...] = ("hh", "hv", "vh", "vv")
Pol = Literal["h", "v"]


class ConventionError(ValueError):
    """An input violates one of the library's conventions (e.g. the sign of Im ε)."""


def _describe(value) -> str:
    arr = np.asarray(value)
    if arr.ndim == 0:
        return repr(arr.item())
    return f"array of shape {arr.shape}"


def check_finite(name: str, value, *, allow_nan: bool = False) -> np.ndarray:
    """Return ``value`` as an array, raising if it holds NaN or inf."""
    try:
        arr = np.asarray(value)
    except Exception as exc:  # pragma: no cover - numpy raises for exotic objects only
        raise TypeError(f"{name} must be a number or array of numbers, got {value!r}") from exc
    if arr.dtype == object or not (
        np.issubdtype(arr.dtype, np.number) or np.issubdtype(arr.dtype, np.bool_)
    ):
        raise TypeError(f"{name} must be a number or array of numbers, got {_describe(value)}")
    if not allow_nan and not np.all(np.isfinite(arr)):
        bad = arr[~np.isfinite(arr)].ravel()[0]
        raise ValueError(f"{name} must be finite, got {bad!r} in {_describe(value)}")
    return arr


def check_positive(name: str, value, *, unit: str = "") -> float:
    """A finite real scalar > 0; returns it as ``float``."""
    check_real_scalar(name, value)
    v = float(value)
    if not v > 0:
        raise ValueError(f"{name} must be > 0{(' [' + unit + ']') if unit else ''}, got {value!r}")
    return v


def check_real_scalar(name: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real | np.ndarray):
        raise TypeError(f"{name} must be a real number, got {value!r}")
    arr = np.asarray(value)
    if arr.ndim != 0 or not np.isrealobj(arr):
        raise TypeError(f"{name} must be a real scalar, got {_describe(value)}")
    v = float(arr)
    if not math.isfinite(v):
        raise ValueError(f"{name} must be finite, got {v!r}")
    return v


def check_in_range(
    name: str, value, low: float, high: float, *, low_open=True, high_open=True
) -> float:
    """A finite real scalar in an interval; the message names the interval."""
    v = check_real_scalar(name, value)
    ok_low = v > low if low_open else v >= low
    ok_high = v < high if high_open else v <= high
    if not (ok_low and ok_high):
        lb = "(" if low_open else "["
        hb = ")" if high_open else "]"
        raise ValueError(f"{name} must be in {lb}{low}, {high}{hb}, got {value!r}")
    return v


def check_angle(name: str, value, *, low: float = 0.0, high: float = math.pi / 2) -> np.ndarray:
    """Angles in radians, finite, within ``[low, high]`` (default ``[0, π/2]``)."""
    arr = check_finite(name, value)
    if np.iscomplexobj(arr):
        raise TypeError(f"{name} must be real (radians), got complex {_describe(value)}")
    arr = arr.astype(float)
    if np.any(arr < low) or np.any(arr > high):
        bad = arr[(arr < low) | (arr > high)].ravel()[0]
        raise ValueError(
            f"{name} must be in [{low:g}, {high:g}] rad "
            f"([{math.degrees(low):g}°, {math.degrees(high):g}°]), got {bad!r} rad"
        )
    return arr


def check_permittivity(value, name: str = "eps") -> np.ndarray:
    """Relative permittivity under the ``exp(-iωt)`` convention: finite, ``Im ε ≥ 0``.

    ``value`` may be real or complex, scalar or array, or the string ``"pec"``
    (handled by the callers that accept a perfect conductor).
    """
    arr = check_finite(name, value)
    arr = arr.astype(complex)
    if np.any(arr.imag < 0):
        bad = arr[arr.imag < 0].ravel()[0]
        raise ConventionError(
            f"{name} = {bad!r} has Im(eps) < 0. emscatter uses the exp(-i omega t) time "
            f"convention, where a lossy medium has Im(eps) >= 0; if your value comes from an "
            f"exp(+j omega t) source (engineering convention), pass numpy.conj({name})."
        )
    if np.any(arr == 0):
        raise ValueError(f"{name} must be nonzero, got {arr[arr == 0].ravel()[0]!r}")
    return arr


def wavenumber(frequency: float | None = None, wavelength: float | None = None) -> float:
    """Free-space wavenumber ``k = 2π/λ`` [rad/m] from exactly one of frequency [Hz] or
    wavelength [m]."""
    if (frequency is None) == (wavelength is None):
        raise ValueError(
            "give exactly one of frequency [Hz] or wavelength [m], got "
            f"frequency={frequency!r}, wavelength={wavelength!r}"
        )
    if frequency is not None:
        f = check_positive("frequency", frequency, unit="Hz")
        return 2.0 * math.pi * f / SPEED_OF_LIGHT
    lam = check_positive("wavelength", wavelength, unit="m")
    return 2.0 * math.pi / lam


def check_polarization(pol: str, name: str = "pol") -> str:
    """One of ``"h"``, ``"v"`` (case-insensitive; ``"te"``→h, ``"tm"``→v)."""
    aliases = {"h": "h", "v": "v", "te": "h", "tm": "v"}
    if not isinstance(pol, str) or pol.lower() not in aliases:
        raise ValueError(f"{name} must be one of 'h' (TE) or 'v' (TM), got {pol!r}")
    return aliases[pol.lower()]


def check_pol_pair(pair: str, name: str = "pol") -> tuple[int, int]:
    """``"hv"`` → ``(0, 1)`` = (scattered h, incident v)."""
    if not isinstance(pair, str) or pair.lower() not in POL_PAIRS:
        raise ValueError(f"{name} must be one of {POL_PAIRS}, got {pair!r}")
    p = pair.lower()
    return POL_INDEX[p[0]], POL_INDEX[p[1]]


def broadcast_angles(**angles) -> list[np.ndarray]:
    """Broadcast angle arrays together, naming them if their shapes do not fit."""
    try:
        return list(np.broadcast_arrays(*angles.values()))
    except ValueError:
        shapes = ", ".join(f"{k}{np.shape(v)}" for k, v in angles.items())
        raise ValueError(f"angle arrays do not broadcast together: {shapes}") from None
