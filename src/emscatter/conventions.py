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
import warnings
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


class PlausibilityWarning(UserWarning):
    """An input is allowed but probably not meant (e.g. ``frequency=5.4`` with GHz in mind)."""


#: Frequencies [Hz] below this, or wavelengths [m] above :data:`WAVELENGTH_WARN`, warn with
#: "did you mean GHz?" (:class:`PlausibilityWarning`).
FREQUENCY_WARN = 1e6
WAVELENGTH_WARN = 1e3


def fmt(x, digits: int = 6) -> str:
    """A number as a person writes it: ``0.5``, ``1e+09``, ``(17+2j)`` — never a numpy repr."""
    if isinstance(x, complex | np.complexfloating):
        z = complex(x)
        if z.imag == 0:
            return f"{z.real:.{digits}g}"
        sign = "+" if z.imag >= 0 or math.isnan(z.imag) else "-"
        return f"({z.real:.{digits}g}{sign}{abs(z.imag):.{digits}g}j)"
    if isinstance(x, bool | np.bool_):
        return str(bool(x))
    try:
        return f"{float(x):.{digits}g}"
    except (TypeError, ValueError):
        return repr(x)


def _describe(value) -> str:
    arr = np.asarray(value)
    if arr.ndim == 0:
        return fmt(arr.item()) if arr.dtype != object else repr(arr.item())
    return f"array of shape {arr.shape}"


def _deg(rad: float) -> str:
    return f"{math.degrees(rad):.4g}°"


#: dtype kinds that :func:`check_finite` accepts: numbers (timedelta is a signed integer to
#: numpy) and booleans — ``np.issubdtype(dtype, np.number) or np.issubdtype(dtype, np.bool_)``
_NUMERIC_KINDS = frozenset("biufcm")


def check_finite(name: str, value, *, allow_nan: bool = False) -> np.ndarray:
    """Return ``value`` as an array, raising if it holds NaN or inf."""
    if type(value) is float and math.isfinite(value):  # the common scalar
        return np.array(value)
    try:
        arr = np.asarray(value)
    except Exception as exc:  # pragma: no cover - numpy raises for exotic objects only
        raise TypeError(f"{name} must be a number or array of numbers, got {value!r}") from exc
    kind = arr.dtype.kind
    if kind not in _NUMERIC_KINDS:
        raise TypeError(f"{name} must be a number or array of numbers, got {_describe(value)}")
    # integers and booleans are always finite (no element-wise test needed)
    if not allow_nan and kind in "fcm" and not np.isfinite(arr).all():
        bad = arr[~np.isfinite(arr)].ravel()[0]
        where = "" if arr.ndim == 0 else f" in {_describe(value)}"
        raise ValueError(f"{name} must be finite, got {fmt(bad)}{where}")
    return arr


def check_positive(name: str, value, *, unit: str = "") -> float:
    """A finite real scalar > 0; returns it as ``float``."""
    v = check_real_scalar(name, value)
    if not v > 0:
        raise ValueError(f"{name} must be > 0{(' [' + unit + ']') if unit else ''}, got {fmt(v)}")
    return v


def check_real_scalar(name: str, value) -> float:
    if type(value) in _FLOATS and math.isfinite(value):  # the common scalar: no array round trip
        return float(value)
    if isinstance(value, bool | np.bool_) or not isinstance(value, numbers.Real | np.ndarray):
        raise TypeError(f"{name} must be a real number, got {value!r}")
    arr = np.asarray(value)
    if arr.ndim != 0 or not np.isrealobj(arr) or arr.dtype == bool:
        raise TypeError(f"{name} must be a real scalar, got {_describe(value)}")
    v = float(arr)
    if not math.isfinite(v):
        raise ValueError(f"{name} must be finite, got {fmt(v)}")
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
        raise ValueError(f"{name} must be in {lb}{low}, {high}{hb}, got {fmt(v)}")
    return v


_FLOATS = (float, np.float64)


def check_angle(
    name: str, value, *, low: float = 0.0, high: float = math.pi / 2, copy: bool = True
) -> np.ndarray:
    """Angles in radians, finite, within ``[low, high]`` (default ``[0, π/2]``).

    Messages give the allowed range and the offending value in radians and in degrees.
    ``copy=False``: a float64 array that passes is returned itself, not copied (for a caller
    that holds its own copy already, e.g. the public API's checked angles; issue 22)."""
    if type(value) in _FLOATS:  # the common scalar: one comparison (NaN and inf fail it)
        if low <= value <= high:
            return np.array(value, dtype=float)
    elif type(value) is np.ndarray and value.dtype.char == "d" and value.size:
        if value.size == 1:  # one angle: a scalar comparison, no reductions
            if low <= value.item() <= high:
                return value.copy()
        # real floats: min and max in range ⇒ finite and in range (NaN fails the comparison)
        elif low <= value.min() and value.max() <= high:
            return value.astype(float) if copy else value
    return _check_angle_slow(name, value, low, high)


def _check_angle_slow(name: str, value, low: float, high: float) -> np.ndarray:
    arr = check_finite(name, value)
    if np.iscomplexobj(arr):
        raise TypeError(f"{name} must be real (radians), got complex {_describe(value)}")
    if arr.dtype == bool:
        raise TypeError(f"{name} must be angles in radians, got booleans {_describe(value)}")
    arr = arr.astype(float)
    if np.any(arr < low) or np.any(arr > high):
        bad = float(arr[(arr < low) | (arr > high)].ravel()[0])
        raise ValueError(
            f"{name} must be in [{fmt(low, 5)}, {fmt(high, 5)}] rad "
            f"([{_deg(low)}, {_deg(high)}]), got {fmt(bad, 5)} rad ({_deg(bad)})"
        )
    return arr


def check_permittivity(value, name: str = "eps") -> np.ndarray:
    """Relative permittivity under the ``exp(-iωt)`` convention: finite, ``Im ε ≥ 0``.

    ``value`` may be real or complex, scalar or array, or the string ``"pec"``
    (handled by the callers that accept a perfect conductor). Booleans are refused.
    """
    if type(value) is complex:  # the common scalar: checked without arrays
        re, im = value.real, value.imag
        if math.isfinite(re) and math.isfinite(im) and im >= 0 and value != 0:
            return np.array(value)
    elif type(value) is np.ndarray and value.dtype.kind == "c" and value.size:
        # a checked permittivity passed on: finite, Im ≥ 0, nonzero (else the messages below)
        if value.ndim == 0:
            z = complex(value)
            if math.isfinite(z.real) and math.isfinite(z.imag) and z.imag >= 0 and z != 0:
                return value.astype(complex)
        elif value.imag.min() >= 0 and np.isfinite(value).all() and value.all():
            return value.astype(complex)
    if isinstance(value, bool | np.bool_) or np.asarray(value).dtype == bool:
        raise TypeError(
            f"{name} must be a complex permittivity (a number, e.g. 17+2j) or 'pec', got {value!r}"
        )
    arr = check_finite(name, value)
    arr = arr.astype(complex)
    if np.any(arr.imag < 0):
        bad = arr[arr.imag < 0].ravel()[0]
        raise ConventionError(
            f"{name} = {fmt(bad)} has Im(eps) < 0. emscatter uses the exp(-i omega t) time "
            f"convention, where a lossy medium has Im(eps) >= 0; if your value comes from an "
            f"exp(+j omega t) source (engineering convention), pass numpy.conj({name})."
        )
    if np.any(arr == 0):
        raise ValueError(f"{name} must be nonzero, got {fmt(arr[arr == 0].ravel()[0])}")
    return arr


def _positive_array(name: str, value, unit: str) -> np.ndarray:
    if isinstance(value, bool | np.bool_) or np.asarray(value).dtype == bool:
        raise TypeError(f"{name} must be a number [{unit}] or an array of numbers, got {value!r}")
    arr = check_finite(name, value)
    if np.iscomplexobj(arr):
        raise TypeError(f"{name} must be real [{unit}], got complex {_describe(value)}")
    arr = arr.astype(float)
    if np.any(arr <= 0):
        bad = arr[arr <= 0].ravel()[0]
        raise ValueError(f"{name} must be > 0 [{unit}], got {fmt(bad)}")
    return arr


_REALS = (float, np.float64)  # (ints, bools and arrays take the checks below)


def wavenumber(frequency=None, wavelength=None, *, warn: bool = True):
    """Free-space wavenumber ``k = 2π/λ`` [rad/m] from exactly one of frequency [Hz] or
    wavelength [m]: a ``float`` for a scalar, an ndarray of the same shape for an array.

    A frequency below 1 MHz or a wavelength above 1 km is allowed but warns
    (:class:`PlausibilityWarning`, "did you mean GHz?") unless ``warn=False``."""
    if wavelength is None and type(frequency) in _REALS:  # a plain number: no arrays
        if FREQUENCY_WARN <= frequency < math.inf:
            return 2.0 * math.pi * float(frequency) / SPEED_OF_LIGHT
    elif frequency is None and type(wavelength) in _REALS:
        if 0 < wavelength <= WAVELENGTH_WARN:
            return 2.0 * math.pi / float(wavelength)
    if (frequency is None) == (wavelength is None):
        raise ValueError(
            "give exactly one of frequency [Hz] or wavelength [m], got "
            f"frequency={_describe(frequency) if frequency is not None else None}, "
            f"wavelength={_describe(wavelength) if wavelength is not None else None}"
        )
    if frequency is not None:
        f = _positive_array("frequency", frequency, "Hz")
        if warn and np.any(f < FREQUENCY_WARN):
            low = float(f.min())
            warnings.warn(
                f"frequency = {fmt(low)} Hz is below 1 MHz (wavelength "
                f"{fmt(SPEED_OF_LIGHT / low, 3)} m); did you mean {fmt(low)} GHz = "
                f"{fmt(low * 1e9)} Hz? frequency is in Hz",
                PlausibilityWarning,
                stacklevel=3,
            )
        k = 2.0 * math.pi * f / SPEED_OF_LIGHT
    else:
        lam = _positive_array("wavelength", wavelength, "m")
        if warn and np.any(lam > WAVELENGTH_WARN):
            high = float(lam.max())
            warnings.warn(
                f"wavelength = {fmt(high)} m is above 1 km; did you mean GHz? wavelength is in "
                f"metres (give frequency= in Hz for a frequency)",
                PlausibilityWarning,
                stacklevel=3,
            )
        k = 2.0 * math.pi / lam
    return float(k) if k.ndim == 0 else k


_POL_ALIASES = {"h": "h", "v": "v", "te": "h", "tm": "v"}


def check_polarization(pol: str, name: str = "pol") -> str:
    """One of ``"h"``, ``"v"`` (case-insensitive; ``"te"``→h, ``"tm"``→v)."""
    key = pol.strip().lower() if isinstance(pol, str) else None
    if key not in _POL_ALIASES:
        raise ValueError(
            f"{name} must be 'h' (or 'TE') or 'v' (or 'TM'), case-insensitive, got {pol!r}"
        )
    return _POL_ALIASES[key]


def pol_index(pol: str, name: str = "pol") -> int:
    """0 for h/TE, 1 for v/TM (:func:`check_polarization`)."""
    return POL_INDEX[check_polarization(pol, name)]


def check_pol_pair(pair: str, name: str = "pol") -> tuple[int, int]:
    """``"hv"`` → ``(0, 1)`` = (scattered h, incident v); case-insensitive."""
    key = pair.strip().lower() if isinstance(pair, str) else None
    if key not in POL_PAIRS:
        raise ValueError(
            f"{name} must be one of {', '.join(POL_PAIRS)} (scattered, incident; "
            f"case-insensitive), got {pair!r}"
        )
    return POL_INDEX[key[0]], POL_INDEX[key[1]]


def broadcast_angles(**angles) -> list[np.ndarray]:
    """Broadcast angle arrays together, naming them if their shapes do not fit."""
    try:
        return list(np.broadcast_arrays(*angles.values()))
    except ValueError:
        shapes = ", ".join(f"{k}{np.shape(v)}" for k, v in angles.items())
        raise ValueError(f"angle arrays do not broadcast together: {shapes}") from None


def broadcast_shape(*shapes: tuple[int, ...]) -> tuple[int, ...]:
    """``np.broadcast_shapes(*shapes)``, without its cost in the common case of one shape
    (the others ``()`` or equal to it); ValueError as numpy's when they do not fit."""
    shape = ()
    for s in shapes:
        if s and s != shape:
            if shape:
                return np.broadcast_shapes(*shapes)
            shape = s
    return shape


def broadcast_view(a: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    """``np.broadcast_to(a, shape)`` (a read-only view) for an array known to broadcast to
    ``shape``, built directly from strides (a few µs less per call: these are per-call costs
    of every solver call)."""
    if not isinstance(a, np.ndarray) or a.ndim > len(shape):
        return np.broadcast_to(a, shape)
    lead = len(shape) - a.ndim
    strides = (0,) * lead
    for n_a, n, st in zip(a.shape, shape[lead:], a.strides, strict=True):
        if n_a != n and n_a != 1:
            return np.broadcast_to(a, shape)  # numpy's error message
        strides += (0 if n_a == 1 else st,)
    try:
        view = np.ndarray(shape, a.dtype, a, 0, strides)
    except (TypeError, ValueError):  # not a buffer (e.g. a non-contiguous view): numpy's way
        return np.broadcast_to(a, shape)
    view.flags.writeable = False
    return view


def check_broadcast(**angles) -> tuple[int, ...]:
    """The broadcast shape of the named arrays (as :func:`broadcast_angles`, same message
    when their shapes do not fit, without building the broadcast views)."""
    try:
        return broadcast_shape(*(np.shape(v) for v in angles.values()))
    except ValueError:
        shapes = ", ".join(f"{k}{np.shape(v)}" for k, v in angles.items())
        raise ValueError(f"angle arrays do not broadcast together: {shapes}") from None
