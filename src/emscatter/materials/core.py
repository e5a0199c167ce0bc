"""Permittivity models that depend on frequency, and the conversions between the ways people
write a medium.

Convention (see :mod:`emscatter.conventions`): time dependence ``exp(−iωt)``, so a lossy medium
has ``Im ε ≥ 0`` and a complex index ``n + ik`` with ``k ≥ 0``:

* ``ε = (n + ik)²``                                   (complex index ↔ permittivity)
* ``ε = ε′ + i σ / (ω ε₀)``,  ``ω = 2π f``           (real permittivity + conductivity [S/m])

Radio engineering codes (Sionna RT, ITU-R P.2040) use ``exp(+jωt)`` and write
``ε = ε′ − j σ/(ω ε₀)``: the same medium is the complex conjugate. :func:`to_engineering` and
:func:`from_engineering` are the one place that flips it.

A :class:`Material` returns ``ε`` at any array of frequencies [Hz] or wavelengths [m]
(``eps(frequency=...)`` or ``eps(wavelength=...)``, exactly one), says where its data comes
from (``source``) and over which band it is defined (``band`` [Hz]); outside it raises
:class:`OutOfBandError`, which names the band and the ways out.
"""

from __future__ import annotations

import math
import numbers
from abc import ABC, abstractmethod
from dataclasses import dataclass

import numpy as np

from ..constants import EPSILON_0, SPEED_OF_LIGHT
from ..conventions import ConventionError, check_finite, check_permittivity

__all__ = [
    "Material",
    "Constant",
    "ComplexIndex",
    "Drude",
    "Tabulated",
    "PerfectConductor",
    "OutOfBandError",
    "frequency_array",
    "format_frequency",
    "eps_from_nk",
    "nk_from_eps",
    "eps_from_conductivity",
    "conductivity_from_eps",
    "to_engineering",
    "from_engineering",
]


class OutOfBandError(ValueError):
    """A material was asked for outside the frequency band where its data is defined."""


# ----------------------------------------------------------------------------- helpers
def frequency_array(frequency=None, wavelength=None) -> np.ndarray:
    """Frequencies [Hz] as a float array from exactly one of ``frequency`` [Hz] or
    ``wavelength`` [m] (scalars or arrays; positive and finite)."""
    if (frequency is None) == (wavelength is None):
        raise ValueError(
            "give exactly one of frequency [Hz] or wavelength [m], got "
            f"frequency={_plain(frequency)}, wavelength={_plain(wavelength)}"
        )
    name, value = ("frequency", frequency) if frequency is not None else ("wavelength", wavelength)
    arr = check_finite(name, value)
    if np.iscomplexobj(arr) or arr.dtype == bool:
        raise TypeError(f"{name} must be real and positive, got {_plain(value)}")
    arr = arr.astype(float)
    if np.any(arr <= 0):
        bad = arr[arr <= 0].ravel()[0]
        unit = "Hz" if name == "frequency" else "m"
        raise ValueError(f"{name} must be > 0 [{unit}], got {bad:g} {unit}")
    return arr if name == "frequency" else SPEED_OF_LIGHT / arr


def _plain(value) -> str:
    """A value for a message: plain numbers, never numpy reprs."""
    if value is None:
        return "None"
    arr = np.asarray(value)
    if arr.ndim == 0:
        v = arr.item()
        return f"{v:g}" if isinstance(v, float) else repr(v)
    return f"an array of shape {arr.shape}"


def format_frequency(f: float) -> str:
    """``3.5e9`` → ``"3.5 GHz"`` (Hz, kHz, MHz, GHz, THz)."""
    for scale, unit in ((1e12, "THz"), (1e9, "GHz"), (1e6, "MHz"), (1e3, "kHz")):
        if abs(f) >= scale:
            return f"{f / scale:g} {unit}"
    return f"{f:g} Hz"


def _format_band(lo: float, hi: float) -> str:
    """A band [Hz] in the unit people use for it: nm for light, GHz/MHz for radio."""
    if lo > 1e13:  # infrared and above: wavelengths read better
        return f"{SPEED_OF_LIGHT / hi * 1e9:.4g}–{SPEED_OF_LIGHT / lo * 1e9:.4g} nm"
    return f"{format_frequency(lo)}–{format_frequency(hi)}"


def _format_point(f: float) -> str:
    """One frequency [Hz] as people say it: a wavelength for light, a frequency for radio."""
    if f > 1e13:
        return f"λ = {SPEED_OF_LIGHT / f * 1e9:.4g} nm ({format_frequency(f)})"
    return f"{format_frequency(f)} (λ = {SPEED_OF_LIGHT / f:.4g} m)"


def unit_hint(f: float) -> str:
    """``" — did you mean 28 GHz (28e9 Hz)?"`` for a frequency below 1 MHz (a GHz value given
    in Hz, as in ``frequency=28``); ``""`` otherwise. Frequencies are in Hz."""
    if 0 < f < 1e6:
        return f" — did you mean {f:g} GHz ({f * 1e9:g} Hz)? frequency is in Hz"
    return ""


def _omega(frequency) -> np.ndarray:
    return 2.0 * math.pi * np.asarray(frequency, dtype=float)


# ----------------------------------------------------------------------------- conversions
def eps_from_nk(n, k):
    """``ε = (n + ik)²`` [-] for the complex index ``n + ik`` (``exp(−iωt)``: ``k ≥ 0`` is loss)."""
    n = check_finite("n", n).astype(float)
    k = check_finite("k", k).astype(float)
    if np.any(k < 0):
        raise ConventionError(
            f"k = {float(k[k < 0].ravel()[0]):g} < 0: under emscatter's exp(-i omega t) "
            "convention an absorbing medium has k >= 0 "
            "(pass -k if your source uses exp(+j omega t))"
        )
    return (n + 1j * k) ** 2


def nk_from_eps(eps) -> tuple[np.ndarray, np.ndarray]:
    """Complex index ``(n, k)`` with ``(n + ik)² = ε``, ``k ≥ 0`` and ``n ≥ 0`` (principal root;
    ``Im ε ≥ 0`` is required)."""
    e = check_permittivity(eps)
    root = np.sqrt(e)  # principal branch: Re ≥ 0; Im ≥ 0 because Im ε ≥ 0
    return root.real, np.abs(root.imag)


def eps_from_conductivity(eps_real, conductivity, frequency):
    """``ε = ε′ + i σ/(ω ε₀)`` [-] from the real relative permittivity ``ε′`` [-], the
    conductivity ``σ`` [S/m] (≥ 0) and the frequency [Hz] (``exp(−iωt)``; Sionna RT and ITU-R
    P.2040 write the conjugate ``ε′ − jσ/(ωε₀)``, see :func:`to_engineering`)."""
    er = check_finite("eps_real", eps_real)
    if np.iscomplexobj(er):
        raise TypeError("eps_real must be real (the real part of the relative permittivity)")
    sig = check_finite("conductivity", conductivity)
    if np.iscomplexobj(sig):
        raise TypeError("conductivity must be real [S/m]")
    if np.any(sig < 0):
        raise ValueError(
            f"conductivity must be >= 0 [S/m], got {float(sig[sig < 0].ravel()[0]):g} S/m "
            "(a negative conductivity would be a medium that creates energy)"
        )
    f = frequency_array(frequency=frequency)
    return er.astype(float) + 1j * sig.astype(float) / (_omega(f) * EPSILON_0)


def conductivity_from_eps(eps, frequency) -> tuple[np.ndarray, np.ndarray]:
    """``(ε′, σ [S/m])`` of a relative permittivity at ``frequency`` [Hz]:
    ``ε′ = Re ε``, ``σ = ω ε₀ Im ε`` (inverse of :func:`eps_from_conductivity`)."""
    e = check_permittivity(eps)
    f = frequency_array(frequency=frequency)
    return e.real, _omega(f) * EPSILON_0 * e.imag


def to_engineering(eps):
    """emscatter's ``ε`` (``exp(−iωt)``, ``Im ε ≥ 0``) → the engineering convention
    ``exp(+jωt)`` (``ε′ − jσ/(ωε₀)``, ``Im ≤ 0``) used by Sionna RT: the complex conjugate."""
    return np.conj(check_permittivity(eps))


def from_engineering(eps_engineering):
    """Engineering ``ε′ − jσ/(ωε₀)`` (``exp(+jωt)``, ``Im ≤ 0``) → emscatter's ``exp(−iωt)``
    permittivity (``Im ≥ 0``): the complex conjugate. ``Im > 0`` here is a sign error in the
    source and raises :class:`~emscatter.ConventionError`."""
    e = check_finite("eps_engineering", eps_engineering).astype(complex)
    if np.any(e.imag > 0):
        raise ConventionError(
            f"eps_engineering = {complex(e[e.imag > 0].ravel()[0])} has Im > 0, which is not a "
            "lossy medium under exp(+j omega t); if it is already in emscatter's exp(-i omega t) "
            "convention, use it as it is"
        )
    return np.conj(e)


# ----------------------------------------------------------------------------- materials
class Material(ABC):
    """A medium whose relative permittivity depends on frequency.

    Subclasses implement :meth:`_eps` on frequencies [Hz] already checked (and in band).
    ``band`` is ``(f_min, f_max)`` [Hz] or ``None`` (defined everywhere).
    """

    name: str = "material"
    source: str = ""

    @property
    def band(self) -> tuple[float, float] | None:
        return None

    @abstractmethod
    def _eps(self, f: np.ndarray) -> np.ndarray:
        """ε at frequencies ``f`` [Hz] (float array), complex, same shape."""

    def eps(self, frequency=None, wavelength=None) -> np.ndarray:
        """Relative permittivity ε [-] (``exp(−iωt)``, ``Im ε ≥ 0``) at ``frequency`` [Hz] or
        ``wavelength`` [m] (exactly one; scalars or arrays — the result has their shape)."""
        f = frequency_array(frequency, wavelength)
        self._check_band(f)
        return np.asarray(self._eps(f), dtype=complex)

    def nk(self, frequency=None, wavelength=None) -> tuple[np.ndarray, np.ndarray]:
        """Complex index ``(n, k)`` [-] (see :func:`nk_from_eps`)."""
        return nk_from_eps(self.eps(frequency, wavelength))

    def conductivity(self, frequency) -> tuple[np.ndarray, np.ndarray]:
        """``(ε′ [-], σ [S/m])`` at ``frequency`` [Hz] (see :func:`conductivity_from_eps`)."""
        return conductivity_from_eps(self.eps(frequency=frequency), frequency)

    def in_band(self, frequency) -> np.ndarray:
        """Boolean array: where ``frequency`` [Hz] lies inside the band."""
        f = np.asarray(frequency, dtype=float)
        b = self.band
        if b is None:
            return np.ones(f.shape, dtype=bool)
        return (f >= b[0] * (1 - 1e-12)) & (f <= b[1] * (1 + 1e-12))

    def _check_band(self, f: np.ndarray) -> None:
        ok = self.in_band(f)
        if not np.all(ok):
            bad = float(np.asarray(f)[~ok].ravel()[0])
            lo, hi = self.band
            raise OutOfBandError(
                f"material {self.name!r} ({self.source or 'no source given'}) is defined for "
                f"{_format_band(lo, hi)}, got {_format_point(bad)}{unit_hint(bad)}. Ways out: "
                "give the "
                "permittivity at that frequency yourself (a number or materials.Constant), "
                "or build the material with extrapolate=True (documented extrapolation)."
            )

    def describe(self) -> str:
        band = "" if self.band is None else f", {_format_band(*self.band)}"
        return f"{self.name} ({type(self).__name__}{band}; {self.source or 'user-given'})"

    def to_dict(self) -> dict:
        """JSON-able description (type, parameters, source) for metadata and cache keys."""
        return {"type": type(self).__name__, "name": self.name, "source": self.source}

    def __repr__(self) -> str:
        return f"<{self.describe()}>"


@dataclass(frozen=True, repr=False, eq=True)
class Constant(Material):
    """A frequency-independent relative permittivity ``value`` (``Im ≥ 0``)."""

    value: complex = 1.0
    name: str = "constant"
    source: str = "user-given"

    def __post_init__(self):
        v = check_permittivity(self.value, "value")
        if v.ndim != 0:
            raise TypeError("Constant(value) takes one permittivity; use Tabulated for spectra")
        object.__setattr__(self, "value", complex(v))

    def _eps(self, f):
        return np.full(np.shape(f), self.value, dtype=complex)

    def to_dict(self):
        return {**super().to_dict(), "eps": {"re": self.value.real, "im": self.value.imag}}


@dataclass(frozen=True, repr=False, eq=True)
class ComplexIndex(Material):
    """A frequency-independent complex index ``n + ik`` (``k ≥ 0``): ``ε = (n + ik)²``."""

    n: float = 1.0
    k: float = 0.0
    name: str = "complex index"
    source: str = "user-given"

    def __post_init__(self):
        e = eps_from_nk(self.n, self.k)
        if np.ndim(e) != 0:
            raise TypeError("ComplexIndex takes scalars n, k; use Tabulated for spectra")
        object.__setattr__(self, "n", float(self.n))
        object.__setattr__(self, "k", float(self.k))

    def _eps(self, f):
        return np.full(np.shape(f), (self.n + 1j * self.k) ** 2, dtype=complex)

    def to_dict(self):
        return {**super().to_dict(), "n": self.n, "k": self.k}


@dataclass(frozen=True, repr=False, eq=True)
class Drude(Material):
    """Free-electron (Drude) metal: ``ε(ω) = ε∞ − ωp² / (ω (ω + iγ))`` (``exp(−iωt)``, so
    ``Im ε = ωp² γ / (ω (ω² + γ²)) ≥ 0``; e.g. Ashcroft & Mermin 1976, ch. 1).

    plasma_angular_frequency : ωp [rad/s]; collision_rate : γ = 1/τ [rad/s]; eps_inf : ε∞ [-].
    At ``ω ≪ γ`` it tends to ``ε∞ + i σ₀/(ω ε₀)`` with the DC conductivity
    ``σ₀ = ε₀ ωp²/γ`` [S/m] (:meth:`from_conductivity`).
    """

    plasma_angular_frequency: float = 1.37e16
    collision_rate: float = 1.0e14
    eps_inf: float = 1.0
    name: str = "drude"
    source: str = "Drude model"

    def __post_init__(self):
        for attr in ("plasma_angular_frequency", "collision_rate"):
            v = getattr(self, attr)
            if isinstance(v, bool) or not (isinstance(v, int | float) and math.isfinite(v)):
                raise TypeError(f"{attr} must be a finite number [rad/s], got {v!r}")
            if v <= 0:
                raise ValueError(f"{attr} must be > 0 [rad/s], got {v:g}")
        if not (isinstance(self.eps_inf, int | float) and math.isfinite(self.eps_inf)):
            raise TypeError(f"eps_inf must be a finite real number, got {self.eps_inf!r}")

    @classmethod
    def from_conductivity(cls, conductivity: float, collision_rate: float, eps_inf=1.0, **kw):
        """From the DC conductivity σ₀ [S/m] and the collision rate γ [rad/s]:
        ``ωp² = σ₀ γ / ε₀``."""
        for name, v, unit in (
            ("conductivity", conductivity, "S/m"),
            ("collision_rate", collision_rate, "rad/s"),
        ):
            if isinstance(v, bool) or not isinstance(v, numbers.Real) or not math.isfinite(v):
                raise TypeError(f"{name} must be a finite number > 0 [{unit}], got {v!r}")
            if v <= 0:
                raise ValueError(f"{name} must be > 0 [{unit}], got {float(v):g}")
        wp = math.sqrt(float(conductivity) * float(collision_rate) / EPSILON_0)
        return cls(wp, float(collision_rate), eps_inf, **kw)

    def _eps(self, f):
        w = _omega(f)
        wp2 = self.plasma_angular_frequency**2
        return self.eps_inf - wp2 / (w * (w + 1j * self.collision_rate))

    def to_dict(self):
        return {
            **super().to_dict(),
            "plasma_angular_frequency": self.plasma_angular_frequency,
            "collision_rate": self.collision_rate,
            "eps_inf": self.eps_inf,
        }


class Tabulated(Material):
    """A measured spectrum, interpolated linearly in wavelength — of ``n`` and ``k`` when given
    as a complex index (as Mitsuba 3 interpolates its η/k spectra), else of ``Re ε``, ``Im ε``.

    wavelength : strictly increasing or decreasing sample wavelengths [m] (≥ 2 samples).
    eps : complex ε at those samples, or n, k : the index.
    extrapolate : ``False`` (default) → :class:`OutOfBandError` outside the samples;
        ``True`` → the end values held constant beyond them (documented, explicit choice).
    """

    def __init__(
        self,
        wavelength,
        eps=None,
        *,
        n=None,
        k=None,
        name: str = "tabulated",
        source: str = "user-given",
        extrapolate: bool = False,
    ):
        lam = check_finite("wavelength", wavelength).astype(float)
        if lam.ndim != 1 or lam.size < 2:
            raise ValueError(
                f"wavelength must be a 1-D array of ≥ 2 samples, got shape {lam.shape}"
            )
        if np.any(lam <= 0):
            raise ValueError("wavelength samples must be > 0 [m]")
        order = np.argsort(lam)
        lam = lam[order]
        if np.any(np.diff(lam) <= 0):
            raise ValueError("wavelength samples must be distinct")
        if (eps is None) == (n is None and k is None):
            raise ValueError("give either eps=... or n=... and k=... (not both, not neither)")
        if eps is not None:
            e = check_permittivity(eps)
            if e.shape != lam.shape:
                raise ValueError(f"eps has shape {e.shape}, wavelength {lam.shape}")
            self._a, self._b, self._kind = e.real[order], e.imag[order], "eps"
        else:
            if n is None or k is None:
                raise ValueError("give both n and k")
            nn = check_finite("n", n).astype(float)
            kk = check_finite("k", k).astype(float)
            if nn.shape != lam.shape or kk.shape != lam.shape:
                raise ValueError(f"n {nn.shape} and k {kk.shape} must match wavelength {lam.shape}")
            eps_from_nk(nn, kk)  # checks k ≥ 0
            self._a, self._b, self._kind = nn[order], kk[order], "nk"
        if not isinstance(extrapolate, bool):
            raise TypeError(f"extrapolate must be True or False, got {extrapolate!r}")
        self._lam = lam
        self.name = name
        self.source = source
        self.extrapolate = extrapolate

    @property
    def wavelengths(self) -> np.ndarray:
        """Sample wavelengths [m], increasing."""
        return self._lam.copy()

    @property
    def band(self):
        if self.extrapolate:
            return None
        return (SPEED_OF_LIGHT / self._lam[-1], SPEED_OF_LIGHT / self._lam[0])

    def _eps(self, f):
        lam = SPEED_OF_LIGHT / np.asarray(f, dtype=float)
        a = np.interp(lam, self._lam, self._a)
        b = np.interp(lam, self._lam, self._b)
        if self._kind == "nk":
            return (a + 1j * b) ** 2
        return a + 1j * b

    def to_dict(self):
        key = ("n", "k") if self._kind == "nk" else ("eps_re", "eps_im")
        return {
            **super().to_dict(),
            "wavelength": self._lam.tolist(),
            key[0]: self._a.tolist(),
            key[1]: self._b.tolist(),
            "extrapolate": self.extrapolate,
        }

    def __eq__(self, other):
        return isinstance(other, Tabulated) and self.to_dict() == other.to_dict()

    def __hash__(self):
        return hash((self.name, self.source, self._kind, self._lam.tobytes(), self._a.tobytes()))


@dataclass(frozen=True, repr=False, eq=True)
class PerfectConductor(Material):
    """A perfect electric conductor (``|ε| → ∞``). :meth:`eps` raises: solvers take the string
    ``"pec"`` for it (:func:`emscatter.materials.eps_at` returns that)."""

    name: str = "pec"
    source: str = "perfect electric conductor"

    def _eps(self, f):
        raise TypeError(
            "a perfect conductor has no finite permittivity; solvers take eps='pec' "
            "(use emscatter.materials.eps_at, which returns 'pec' for it)"
        )
