"""Roughness descriptions: correlation functions and their roughness spectra.

A *roughness* is the second-order statistics of a zero-mean Gaussian random surface
``z = h(x, y)`` (``dimension=2``) or profile ``z = h(x)`` (``dimension=1``):
its rms height ``sigma`` [m] and its correlation coefficient ``ρ(x, y)`` with
``ρ(0) = 1``. Fractional Brownian surfaces (non-stationary) are described by their
structure function instead (:class:`FractionalBrownian`).

Spectrum normalization (written down once, used everywhere)
-----------------------------------------------------------
``spectrum(kx, ky)`` returns the *normalized* spectrum ``w`` of ``ρ``, the Fourier
transform with the ``1/(2π)^d`` factor, so that it integrates to one:

* 2-D: ``w(K) = (1/(2π)²) ∫ ρ(r) exp(−i K·r) d²r``  [m²],  ``∫ w d²K = 1``;
* 1-D: ``w(k) = (1/2π) ∫ ρ(x) exp(−i k x) dx``       [m],   ``∫ w dk = 1``.

The height power spectral density is ``σ² w``. Ulaby's ``W(K)`` (Ulaby, Moore & Fung
1982, vol. II ch. 12; used in the SPM form ``σ⁰ = 8 k⁴σ² cos⁴θ |α|² W(2k sinθ)``) is
``W = 2π w`` in 2-D (:meth:`Roughness.spectrum_ulaby`): Gaussian ``(ℓ²/2) exp(−K²ℓ²/4)``,
exponential ``ℓ² (1 + K²ℓ²)^(−3/2)``. Tsang et al. (2000, vol. I) write
``W(K) = σ² w(K)``.

Closed forms (isotropic; ℓ is the correlation length):

* Gaussian ``ρ = exp(−r²/ℓ²)``: ``w₂ = ℓ²/(4π) exp(−K²ℓ²/4)``, ``w₁ = ℓ/(2√π) exp(−k²ℓ²/4)``
* exponential ``ρ = exp(−r/ℓ)``: ``w₂ = ℓ²/(2π) (1+K²ℓ²)^(−3/2)``, ``w₁ = ℓ/π (1+k²ℓ²)^(−1)``
* power law (von Kármán / Matérn ν = H): ``w₂ = Hℓ²/π (1+K²ℓ²)^(−(H+1))``,
  ``w₁ = Γ(H+½)/(√π Γ(H)) ℓ (1+k²ℓ²)^(−(H+½))``

Anisotropic forms (seed eqs. 2.4–2.5) replace ``r/ℓ`` by ``√((x/ℓx)² + (y/ℓy)²)`` and
``Kℓ`` by ``√((kx ℓx)² + (ky ℓy)²)``, with the prefactor ``ℓ²`` becoming ``ℓx ℓy``.

Slopes
------
``mean_square_slope()`` returns the **per-direction** mean-square slopes
``(⟨h_x²⟩, ⟨h_y²⟩)``; the **total** mean-square slope (Beckmann's ``m²``, the seed's
``m = tan β0 = 2σ/T``, eq. 3.1) is their sum. For the Gaussian correlation
``⟨h_x²⟩ = 2σ²/ℓx²``, so isotropic ``m² = 4σ²/ℓ²``. The exponential correlation (and the
power law with H ≤ 1) is not differentiable at the origin: its slope variance is
infinite and needs a short-wavelength cutoff ``k_max``; a finite-difference slope measured
with spacing ``dx`` grows as ``dx^(−1/2)`` for the exponential case.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass, field

import numpy as np

from .conventions import check_in_range, check_positive

__all__ = [
    "Roughness",
    "GaussianCorrelation",
    "ExponentialCorrelation",
    "PowerLawCorrelation",
    "FractionalBrownian",
    "roughness",
    "check_roughness",
]


def _check_dimension(dimension) -> int:
    if dimension not in (1, 2) or isinstance(dimension, bool):
        raise ValueError(f"dimension must be 1 (profile) or 2 (surface), got {dimension!r}")
    return int(dimension)


@dataclass(frozen=True)
class Roughness(ABC):
    """Stationary Gaussian roughness: rms height and a correlation coefficient.

    Parameters
    ----------
    sigma : rms height [m], > 0.
    length : correlation length along x [m], > 0.
    length_y : correlation length along y [m]; defaults to ``length`` (isotropic).
        Only for ``dimension=2``.
    dimension : 2 for a surface ``h(x, y)`` (3-D scattering problem), 1 for a profile
        ``h(x)`` (2-D scattering problem).
    """

    sigma: float
    length: float
    length_y: float | None = None
    dimension: int = 2
    name: str = field(default="", init=False, repr=False)

    def __post_init__(self):
        object.__setattr__(self, "sigma", check_positive("sigma", self.sigma, unit="m"))
        object.__setattr__(self, "length", check_positive("length", self.length, unit="m"))
        dim = _check_dimension(self.dimension)
        object.__setattr__(self, "dimension", dim)
        if self.length_y is None:
            object.__setattr__(self, "length_y", self.length)
        else:
            ly = check_positive("length_y", self.length_y, unit="m")
            if dim == 1 and ly != self.length:
                raise ValueError(
                    f"length_y={ly!r} given for a 1-D profile (dimension=1); anisotropy "
                    "needs dimension=2"
                )
            object.__setattr__(self, "length_y", ly)

    # -- shape functions of the unit-length isotropic correlation (subclasses) --
    @abstractmethod
    def _rho_unit(self, u: np.ndarray) -> np.ndarray:
        """ρ at normalized lag u = r/ℓ ≥ 0."""

    @abstractmethod
    def _w2_unit(self, q: np.ndarray) -> np.ndarray:
        """2-D normalized spectrum of the unit-length correlation at q = Kℓ."""

    @abstractmethod
    def _w1_unit(self, q: np.ndarray) -> np.ndarray:
        """1-D normalized spectrum of the unit-length correlation at q = kℓ."""

    # -- public API --
    @property
    def is_isotropic(self) -> bool:
        return self.length_y == self.length

    def profile(self) -> Roughness:
        """The 1-D profile along x with the same statistics."""
        return type(self)(**{**self._params(), "length_y": None, "dimension": 1})

    def surface(self) -> Roughness:
        """The 2-D surface with the same statistics (isotropic if built from a profile)."""
        return type(self)(**{**self._params(), "dimension": 2})

    def _params(self) -> dict:
        return {
            "sigma": self.sigma,
            "length": self.length,
            "length_y": self.length_y,
            "dimension": self.dimension,
        }

    def correlation(self, x, y=0.0) -> np.ndarray:
        """Correlation coefficient ρ(x, y) [-], ``ρ(0, 0) = 1``. ``x, y`` in [m]."""
        x = np.asarray(x, dtype=float)
        y = np.asarray(y, dtype=float)
        u = np.sqrt((x / self.length) ** 2 + (y / self.length_y) ** 2)
        return self._rho_unit(u)

    def spectrum(self, kx, ky=0.0) -> np.ndarray:
        """Normalized spectrum ``w`` of ρ (module docstring) [m^dimension].

        For ``dimension=1`` ``ky`` is ignored and the 1-D spectrum is returned.
        """
        kx = np.asarray(kx, dtype=float)
        if self.dimension == 1:
            return self.length * self._w1_unit(np.abs(kx) * self.length)
        ky = np.asarray(ky, dtype=float)
        # sqrt(x² + y²) rather than np.hypot: ~20× faster, and no overflow at these scales
        q = np.sqrt((kx * self.length) ** 2 + (ky * self.length_y) ** 2)
        return self.length * self.length_y * self._w2_unit(q)

    def spectrum_ulaby(self, kx, ky=0.0) -> np.ndarray:
        """Ulaby's ``W(K) = 2π w(K)`` (2-D) [m²]; ``W = 2π w`` likewise in 1-D [m]."""
        return 2.0 * math.pi * self.spectrum(kx, ky)

    def height_spectrum(self, kx, ky=0.0) -> np.ndarray:
        """Height power spectral density ``σ² w`` [m^(2+dimension)]."""
        return self.sigma**2 * self.spectrum(kx, ky)

    def nfold_spectrum(self, n, kx, ky=0.0) -> np.ndarray:
        """Normalized transform of ``ρⁿ`` (same ``1/(2π)^d`` factor as :meth:`spectrum`),
        used by the physical-optics series. ``n`` ≥ 1 (int or int array, broadcasts).

        Default: numerical Hankel/cosine transform; subclasses with closed forms override.
        """
        return _numeric_nfold(self, n, kx, ky)

    def mean_square_slope(self, k_max: float | None = None) -> tuple[float, float]:
        """Per-direction mean-square slopes ``(⟨h_x²⟩, ⟨h_y²⟩)`` [-].

        ``k_max`` [rad/m]: short-wavelength cutoff of the spectrum; needed (and only then
        used) when the slope variance is infinite (exponential, power law). Without it such
        a roughness raises ``ValueError``.
        """
        closed = self._mss_closed()
        if closed is not None and k_max is None:
            return closed
        from scipy import integrate  # lazy: keep `import emscatter` (and closed forms) fast

        if k_max is None:
            raise ValueError(
                f"{type(self).__name__} has an infinite slope variance (its correlation is "
                "not differentiable at the origin); give k_max [rad/m], the short-wavelength "
                "cutoff, e.g. pi/dx for a grid of spacing dx"
            )
        k_max = check_positive("k_max", k_max, unit="rad/m")
        s2 = self.sigma**2
        if self.dimension == 1:
            val = 2 * integrate.quad(lambda k: k**2 * self.spectrum(k), 0, k_max, limit=200)[0]
            return s2 * val, 0.0

        # ∫∫_{|K|<k_max} kx² w d²K over the disk, in polar coordinates.
        def radial(kr, c2):
            return integrate.quad(
                lambda p: (kr * np.cos(p)) ** 2 * c2(kr, p) * kr, 0, 2 * math.pi, limit=100
            )[0]

        def wxx(kr, p):
            return self.spectrum(kr * np.cos(p), kr * np.sin(p))

        gx = integrate.quad(lambda kr: radial(kr, wxx), 0, k_max, limit=200)[0]
        if self.is_isotropic:
            return s2 * gx, s2 * gx
        swapped = type(self)(**{**self._params(), "length": self.length_y, "length_y": self.length})
        gy = integrate.quad(
            lambda kr: radial(kr, lambda k, p: swapped.spectrum(k * np.cos(p), k * np.sin(p))),
            0,
            k_max,
            limit=200,
        )[0]
        return s2 * gx, s2 * gy

    def total_mean_square_slope(self, k_max: float | None = None) -> float:
        """Total mean-square slope ``m² = ⟨h_x²⟩ + ⟨h_y²⟩`` (Beckmann's m²) [-]."""
        sx, sy = self.mean_square_slope(k_max)
        return sx + sy

    def _mss_closed(self) -> tuple[float, float] | None:
        return None

    def describe(self) -> str:
        aniso = "" if self.is_isotropic else f", ℓy={self.length_y:g} m"
        return (
            f"{self.name} {('profile' if self.dimension == 1 else 'surface')}: "
            f"σ={self.sigma:g} m, ℓ={self.length:g} m{aniso}"
        )


@dataclass(frozen=True)
class GaussianCorrelation(Roughness):
    """Gaussian correlation ``ρ = exp(−r²/ℓ²)`` (seed eqs. 2.3, 2.4)."""

    name: str = field(default="gaussian", init=False, repr=False)

    def _rho_unit(self, u):
        return np.exp(-(u**2))

    def _w2_unit(self, q):
        return np.exp(-(q**2) / 4.0) / (4.0 * math.pi)

    def _w1_unit(self, q):
        return np.exp(-(q**2) / 4.0) / (2.0 * math.sqrt(math.pi))

    def nfold_spectrum(self, n, kx, ky=0.0):
        # ρⁿ = exp(−n r²/ℓ²): a Gaussian of length ℓ/√n.
        n = np.asarray(n, dtype=float)
        kx = np.asarray(kx, dtype=float)
        if self.dimension == 1:
            lx = self.length / np.sqrt(n)
            return lx * self._w1_unit(np.abs(kx) * lx)
        ky = np.asarray(ky, dtype=float)
        lx, ly = self.length / np.sqrt(n), self.length_y / np.sqrt(n)
        return lx * ly * self._w2_unit(np.hypot(kx * lx, ky * ly))

    def _mss_closed(self):
        # ⟨h_x²⟩ = −σ² ∂²ρ/∂x²(0) = 2σ²/ℓx²
        sx = 2 * self.sigma**2 / self.length**2
        sy = 2 * self.sigma**2 / self.length_y**2 if self.dimension == 2 else 0.0
        return sx, sy


@dataclass(frozen=True)
class ExponentialCorrelation(Roughness):
    """Exponential correlation ``ρ = exp(−r/ℓ)`` (seed eq. 2.5). Infinite slope variance."""

    name: str = field(default="exponential", init=False, repr=False)

    def _rho_unit(self, u):
        return np.exp(-u)

    def _w2_unit(self, q):
        return (1.0 + q**2) ** -1.5 / (2.0 * math.pi)

    def _w1_unit(self, q):
        return 1.0 / (math.pi * (1.0 + q**2))

    def nfold_spectrum(self, n, kx, ky=0.0):
        # ρⁿ = exp(−n r/ℓ): an exponential of length ℓ/n.
        n = np.asarray(n, dtype=float)
        kx = np.asarray(kx, dtype=float)
        if self.dimension == 1:
            lx = self.length / n
            return lx * self._w1_unit(np.abs(kx) * lx)
        ky = np.asarray(ky, dtype=float)
        lx, ly = self.length / n, self.length_y / n
        return lx * ly * self._w2_unit(np.hypot(kx * lx, ky * ly))


@dataclass(frozen=True)
class PowerLawCorrelation(Roughness):
    """Von Kármán (Matérn, ν = H) correlation: power-law spectrum ``∝ K^(−2(H+1))`` beyond
    ``1/ℓ`` in 2-D, self-affine with Hurst exponent ``H`` at scales below ``ℓ``.

    ``ρ(r) = 2^(1−H)/Γ(H) (r/ℓ)^H K_H(r/ℓ)``; ``H = 1/2`` is the exponential correlation.
    Infinite slope variance for ``H ≤ 1`` (always here): give a cutoff.
    """

    hurst: float = 0.5
    name: str = field(default="power-law", init=False, repr=False)

    def __post_init__(self):
        super().__post_init__()
        object.__setattr__(self, "hurst", check_in_range("hurst", self.hurst, 0.0, 1.0))

    def _params(self):
        return {**super()._params(), "hurst": self.hurst}

    def _rho_unit(self, u):
        from scipy import special

        h = self.hurst
        u = np.asarray(u, dtype=float)
        with np.errstate(invalid="ignore", divide="ignore"):
            val = 2 ** (1 - h) / special.gamma(h) * u**h * special.kv(h, u)
        return np.where(u == 0, 1.0, np.nan_to_num(val, nan=0.0))

    def _w2_unit(self, q):
        h = self.hurst
        return h / math.pi * (1.0 + q**2) ** -(h + 1.0)

    def _w1_unit(self, q):
        h = self.hurst
        c = math.gamma(h + 0.5) / (math.sqrt(math.pi) * math.gamma(h))
        return c * (1.0 + q**2) ** -(h + 0.5)

    def describe(self):
        return super().describe() + f", H={self.hurst:g}"


@dataclass(frozen=True)
class FractionalBrownian:
    """Fractional Brownian (self-affine) roughness (seed eq. 5.11), set by its Hurst exponent.

    Structure function ``D(r) = ⟨(h(x + r) − h(x))²⟩ = increment_rms² (r / lag)^(2H)``.
    Fractal dimension ``D_f = 2 − H`` for a profile (seed eq. 5.12), ``3 − H`` for a surface.

    Parameters
    ----------
    hurst : Hurst exponent H ∈ (0, 1).
    increment_rms : rms height difference [m] between points ``lag`` apart.
    lag : the reference lag [m] (the physical scale).
    dimension : 2 (surface) or 1 (profile).
    """

    hurst: float
    increment_rms: float = 1.0
    lag: float = 1.0
    dimension: int = 2
    name: str = field(default="fbm", init=False, repr=False)

    def __post_init__(self):
        object.__setattr__(self, "hurst", check_in_range("hurst", self.hurst, 0.0, 1.0))
        object.__setattr__(
            self, "increment_rms", check_positive("increment_rms", self.increment_rms, unit="m")
        )
        object.__setattr__(self, "lag", check_positive("lag", self.lag, unit="m"))
        object.__setattr__(self, "dimension", _check_dimension(self.dimension))

    @property
    def fractal_dimension(self) -> float:
        """``2 − H`` for a profile, ``3 − H`` for a surface."""
        return self.dimension + 1 - self.hurst

    def structure_function(self, r) -> np.ndarray:
        """``D(r)`` [m²] at lag ``r`` [m]."""
        r = np.abs(np.asarray(r, dtype=float))
        return self.increment_rms**2 * (r / self.lag) ** (2 * self.hurst)

    def describe(self) -> str:
        kind = "profile" if self.dimension == 1 else "surface"
        return (
            f"fBm {kind}: H={self.hurst:g}, rms increment {self.increment_rms:g} m at lag "
            f"{self.lag:g} m (D={self.fractal_dimension:g})"
        )


_NAMES = {
    "gaussian": GaussianCorrelation,
    "exponential": ExponentialCorrelation,
    "power-law": PowerLawCorrelation,
    "powerlaw": PowerLawCorrelation,
    "fbm": FractionalBrownian,
}


def roughness(kind: str, **params):
    """Build a roughness by name: ``"gaussian"``, ``"exponential"``, ``"power-law"``, ``"fbm"``."""
    if not isinstance(kind, str) or kind.lower() not in _NAMES:
        raise ValueError(f"kind must be one of {sorted(set(_NAMES))}, got {kind!r}")
    return _NAMES[kind.lower()](**params)


def check_roughness(value, name: str = "roughness") -> Roughness:
    """``value`` if it is a stationary :class:`Roughness`, else a TypeError naming ``name``."""
    if not isinstance(value, Roughness):
        raise TypeError(
            f"{name} must be a roughness description from emscatter.spectra "
            "(GaussianCorrelation, ExponentialCorrelation, PowerLawCorrelation), got "
            f"{type(value).__name__}; fractional Brownian statistics are for surface generation "
            "and measurement, and a generated Surface carries its statistics in .target"
        )
    return value


def _numeric_nfold(rough: Roughness, n, kx, ky=0.0) -> np.ndarray:
    """Transform of ρⁿ by quadrature (1-D cosine transform, 2-D Hankel transform of order 0,
    anisotropy folded into the scaled wavenumber). Slow; for spectra without closed forms."""
    from scipy import integrate, special

    n_arr, kx, ky = np.broadcast_arrays(
        np.asarray(n, dtype=float), np.asarray(kx, dtype=float), np.asarray(ky, dtype=float)
    )
    out = np.empty(n_arr.shape)
    if rough.dimension == 1:
        q = np.abs(kx) * rough.length
        for idx in np.ndindex(out.shape):
            nn, qq = n_arr[idx], q[idx]
            val = (
                integrate.quad(
                    lambda u, nn=nn: rough._rho_unit(u) ** nn, 0, np.inf, weight="cos", wvar=qq
                )[0]
                if qq > 0
                else integrate.quad(lambda u, nn=nn: rough._rho_unit(u) ** nn, 0, np.inf)[0]
            )
            out[idx] = rough.length * val / math.pi
        return out
    q = np.hypot(kx * rough.length, ky * rough.length_y)
    for idx in np.ndindex(out.shape):
        nn, qq = n_arr[idx], q[idx]
        upper = 60.0 / max(nn, 1.0) ** 0.5 + 60.0
        val = integrate.quad(
            lambda u, nn=nn, qq=qq: rough._rho_unit(u) ** nn * special.j0(qq * u) * u,
            0,
            upper,
            limit=400,
        )[0]
        out[idx] = rough.length * rough.length_y * val / (2 * math.pi)
    return out
