"""Sea water (and pure water): relative permittivity from temperature and salinity.

Two published models, each a :class:`~emscatter.materials.Material` (``Im ε ≥ 0`` under
``exp(−iωt)``; both papers write ``ε′ − iε″``, the complex conjugate, with the same numbers):

* :class:`KleinSwiftWater` — Klein & Swift, "An improved model for the dielectric constant of
  sea water at microwave frequencies", IEEE TAP 25 (1977) 104–111: one Debye relaxation with
  ``ε∞ = 4.9`` plus ionic conduction, the static permittivity, relaxation time and
  conductivity as polynomials in temperature and salinity. Measured at
  1.43 and 2.653 GHz; one relaxation holds up to about 10 GHz, the band given here
  (0.1–10 GHz). Temperature 0–40 °C, salinity 0–40 psu (the fit's data: 4–35 psu; 0 is
  the pure-water limit the polynomials reduce to).
* :class:`MeissnerWentzWater` — Meissner & Wentz, "The complex dielectric constant of pure and
  sea water from microwave satellite observations", IEEE TGRS 42 (2004) 1836–1849: two Debye
  relaxations plus conduction, fitted pure-water parameters, their salinity dependence and
  the sea-water conductivity of Stogryn et al. (1995) (coefficients as in the paper's tables).
  Band 1–400 GHz; salinity 0–40 psu; temperature −2…34 °C for sea water and
  −25…40 °C for pure water (S = 0).

Units are SI: temperature [K] (the published polynomials use °C: converted inside), salinity
[psu] (practical salinity, ≈ g/kg), frequency [Hz]. Out-of-range parameters raise
:class:`ValueError` naming the parameter, the value and the range.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .core import Material
from .media import ZERO_CELSIUS, check_parameter, debye, out_of_band

__all__ = ["KleinSwiftWater", "MeissnerWentzWater", "sea_water", "WATER_MODELS"]

_KS = "Klein & Swift 1977"
_MW = "Meissner & Wentz 2004"


def _temperature_salinity(obj, model, t_range_c, s_range):
    s = check_parameter("salinity", obj.salinity, *s_range, unit="psu", model=model)
    lo, hi = t_range_c
    t = check_parameter(
        "temperature",
        obj.temperature,
        lo + ZERO_CELSIUS,
        hi + ZERO_CELSIUS,
        unit="K",
        model=f"{model} ({lo:g} to {hi:g} °C{' at S > 0' if model == _MW and s > 0 else ''})",
    )
    object.__setattr__(obj, "salinity", s)
    object.__setattr__(obj, "temperature", t)


@dataclass(frozen=True, repr=False, eq=True)
class KleinSwiftWater(Material):
    """Sea water after Klein & Swift (1977): ``ε = ε∞ + (εs − ε∞)/(1 − iωτ) + iσ/(ωε₀)``.

    temperature : [K], in [273.15, 313.15] (0–40 °C). salinity : [psu], in [0, 40].
    Band 0.1–10 GHz. :meth:`parameters` gives ``(εs, τ [s], σ [S/m])``.
    """

    temperature: float = 293.15
    salinity: float = 35.0
    name: str = "sea water (Klein-Swift)"
    source: str = _KS

    def __post_init__(self):
        _temperature_salinity(self, _KS, (0.0, 40.0), (0.0, 40.0))

    def _check_band(self, f):
        out_of_band(self, f, "MeissnerWentzWater (1–400 GHz)")

    @property
    def band(self):
        return (0.1e9, 10e9)

    def parameters(self) -> tuple[float, float, float]:
        """Static permittivity εs [-], relaxation time τ [s], ionic conductivity σ [S/m]
        (Klein & Swift 1977; T in °C, S in psu inside)."""
        t, s = self.temperature - ZERO_CELSIUS, self.salinity
        eps_t = 87.134 - 1.949e-1 * t - 1.276e-2 * t**2 + 2.491e-4 * t**3
        a = 1.0 + 1.613e-5 * s * t - 3.656e-3 * s + 3.210e-5 * s**2 - 4.232e-7 * s**3
        tau_t = 1.768e-11 - 6.086e-13 * t + 1.104e-14 * t**2 - 8.111e-17 * t**3
        b = 1.0 + 2.282e-5 * s * t - 7.638e-4 * s - 7.760e-6 * s**2 + 1.105e-8 * s**3
        d = 25.0 - t
        beta = (
            2.033e-2
            + 1.266e-4 * d
            + 2.464e-6 * d**2
            - s * (1.849e-5 - 2.551e-7 * d + 2.551e-8 * d**2)
        )
        sigma25 = s * (0.182521 - 1.46192e-3 * s + 2.09324e-5 * s**2 - 1.28205e-7 * s**3)
        return eps_t * a, tau_t * b, sigma25 * math.exp(-d * beta)

    def _eps(self, f):
        eps_s, tau, sigma = self.parameters()
        return debye(f, eps_s, 4.9, tau, sigma)

    def to_dict(self):
        return {**super().to_dict(), "temperature": self.temperature, "salinity": self.salinity}


# Meissner & Wentz 2004: pure-water coefficients (a) and salinity terms (b) of their fit
_MW_A = (5.7230, 2.2379e-02, -7.1237e-04, 5.0478, -7.0315e-02, 6.0059e-04, 3.6143,
         2.8841e-02, 1.3652e-01, 1.4825e-03, 2.4166e-04)  # fmt: skip
_MW_B = (-3.56417e-03, 4.74868e-06, 1.15574e-05, 2.39357e-03, -3.13530e-05, 2.52477e-07,
         -6.28908e-03, 1.76032e-04, -9.22144e-05, -1.99723e-02, 1.81176e-04, -2.04265e-03,
         1.57883e-04)  # fmt: skip
#: 1/(2π ε₀) in GHz·m/S: the conduction term is iσ·F0/ν with ν in GHz.
_F0_GHZ = 17.97510


@dataclass(frozen=True, repr=False, eq=True)
class MeissnerWentzWater(Material):
    """Sea (or pure) water after Meissner & Wentz (2004), two Debye relaxations::

        ε = (εs − ε1)/(1 − iν/ν1) + (ε1 − ε∞)/(1 − iν/ν2) + ε∞ + iσ/(2πε₀ν)

    temperature : [K]; −2…34 °C for sea water, −25…40 °C when ``salinity == 0``.
    salinity : [psu], in [0, 40]. Band 1–400 GHz. :meth:`parameters` gives
    ``(εs, ε1, ε∞, ν1 [Hz], ν2 [Hz], σ [S/m])``.
    """

    temperature: float = 293.15
    salinity: float = 35.0
    name: str = "sea water (Meissner-Wentz)"
    source: str = _MW

    def __post_init__(self):
        s = check_parameter("salinity", self.salinity, 0.0, 40.0, unit="psu", model=_MW)
        t_range = (-25.0, 40.0) if s == 0 else (-2.0, 34.0)
        _temperature_salinity(self, _MW, t_range, (0.0, 40.0))

    def _check_band(self, f):
        out_of_band(self, f, "KleinSwiftWater (0.1–10 GHz)")

    @property
    def band(self):
        return (1e9, 400e9)

    def parameters(self):
        """``(εs, ε1, ε∞, ν1 [Hz], ν2 [Hz], σ [S/m])`` (Meissner & Wentz 2004)."""
        t, s = self.temperature - ZERO_CELSIUS, self.salinity
        a, b = _MW_A, _MW_B
        eps_s = (3.70886e4 - 8.2168e1 * t) / (4.21854e2 + t)  # Stogryn et al. 1995
        eps_1 = a[0] + a[1] * t + a[2] * t**2
        nu_1 = (45.0 + t) / (a[3] + a[4] * t + a[5] * t**2)  # GHz
        eps_inf = a[6] + a[7] * t
        nu_2 = (45.0 + t) / (a[8] + a[9] * t + a[10] * t**2)  # GHz
        eps_s *= math.exp(b[0] * s + b[1] * s**2 + b[2] * t * s)
        nu_1 *= 1.0 + s * (b[3] + b[4] * t + b[5] * t**2)
        eps_1 *= math.exp(b[6] * s + b[7] * s**2 + b[8] * t * s)
        nu_2 *= 1.0 + s * (b[9] + b[10] * t)
        eps_inf *= 1.0 + s * (b[11] + b[12] * t)
        # conductivity (Stogryn et al. 1995, as used by Meissner & Wentz 2004)
        sigma35 = 2.903602 + 8.607e-2 * t + 4.738817e-4 * t**2 - 2.991e-6 * t**3 + 4.3047e-9 * t**4
        r15 = s * (37.5109 + 5.45216 * s + 1.4409e-2 * s**2) / (1004.75 + 182.283 * s + s**2)
        alpha0 = (6.9431 + 3.2841 * s - 9.9486e-2 * s**2) / (84.850 + 69.024 * s + s**2)
        alpha1 = 49.843 - 0.2276 * s + 0.198e-2 * s**2
        rtr15 = 1.0 + (t - 15.0) * alpha0 / (alpha1 + t)
        sigma = sigma35 * r15 * rtr15
        return eps_s, eps_1, eps_inf, nu_1 * 1e9, nu_2 * 1e9, sigma

    def _eps(self, f):
        eps_s, eps_1, eps_inf, nu_1, nu_2, sigma = self.parameters()
        nu = np.asarray(f, dtype=float)
        return (
            (eps_s - eps_1) / (1.0 - 1j * nu / nu_1)
            + (eps_1 - eps_inf) / (1.0 - 1j * nu / nu_2)
            + eps_inf
            + 1j * sigma * _F0_GHZ / (nu / 1e9)
        )

    def to_dict(self):
        return {**super().to_dict(), "temperature": self.temperature, "salinity": self.salinity}


WATER_MODELS = {"meissner-wentz": MeissnerWentzWater, "klein-swift": KleinSwiftWater}


def sea_water(model: str = "meissner-wentz", **parameters) -> Material:
    """Sea water by model name (``"meissner-wentz"``, the default, or ``"klein-swift"``) and
    its parameters (``temperature`` [K], ``salinity`` [psu]). The material name
    ``"sea_water"`` gives ``sea_water()``: Meissner–Wentz at 20 °C and 35 psu."""
    key = str(model).strip().lower().replace("_", "-")
    if key not in WATER_MODELS:
        raise ValueError(f"unknown sea-water model {model!r}: use one of {sorted(WATER_MODELS)}")
    return WATER_MODELS[key](**parameters)
