"""Moist soil: relative permittivity from volumetric moisture and texture.

Two published models, each a :class:`~emscatter.materials.Material` (``eps(frequency=...)``,
``Im ε ≥ 0`` under ``exp(−iωt)``; the papers write ``ε′ − iε″`` with ``ε″ ≥ 0``, the same
numbers):

* :class:`DobsonSoil` — the semi-empirical refractive mixing model of Dobson, Ulaby,
  Hallikainen & El-Rayes, "Microwave dielectric behavior of wet soil — Part II: Dielectric
  mixing models", IEEE TGRS 23 (1985) 35–46, with the free-water Debye terms of
  Ulaby, Moore & Fung, *Microwave Remote Sensing* Vol. III (1986), App. E; fitted on
  1.4–18 GHz. Below 1.4 GHz (down to 0.3 GHz) the corrections of Peplinski, Ulaby & Dobson,
  "Dielectric properties of soils in the 0.3–1.3-GHz range", IEEE TGRS 33 (1995) 803–807
  (their effective conductivity and ``ε′ → 1.15 ε′ − 0.68``) are applied; they were fitted on
  0.3–1.3 GHz and are used here up to 1.4 GHz, where Dobson's fit starts (the two fits are
  not continuous there: ε′ steps by ~10 % and ε″ by up to a factor 2 at 1.4 GHz, from the
  two effective-conductivity regressions).
* :class:`MironovSoil` — the generalized refractive mixing dielectric model (GRMDM) of Mironov,
  Kosolapova & Fomin, "Physically and mineralogically based spectroscopic dielectric model
  for moist soils", IEEE TGRS 47 (2009) 2059–2070, eqs. 11–13 with the clay regressions
  (their eqs. 17–25), fitted on the Dobson, Curtis and Hallikainen data sets over
  0.3–26.5 GHz and clay fractions 0–76 % at room temperature (≈ 20 °C).

Units are SI as everywhere in emscatter: moisture as a volume fraction [m³/m³], sand and clay
as mass fractions [-] of the dry soil, bulk density [kg/m³], temperature [K]. Every parameter
is checked against its model's range (physical bounds, and the frequency band of the fit);
outside it the error names the parameter, the value and the range.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..constants import EPSILON_0
from .core import Material
from .media import ZERO_CELSIUS, check_parameter, out_of_band

__all__ = ["DobsonSoil", "MironovSoil", "soil", "SOIL_MODELS"]

_DOBSON = "Dobson et al. 1985 (with Peplinski et al. 1995 below 1.4 GHz)"
_MIRONOV = "Mironov et al. 2009 (GRMDM)"

#: Specific density of the soil solids [kg/m³] (Dobson et al. 1985: ρs = 2.66 g/cm³).
SOLID_DENSITY = 2660.0


def _check_texture(sand: float, clay: float, model: str) -> None:
    if sand + clay > 1.0 + 1e-12:
        raise ValueError(
            f"sand + clay = {sand:g} + {clay:g} = {sand + clay:g} is more than 1 (they are mass "
            f"fractions of the dry soil; silt is the rest) in {model}"
        )


@dataclass(frozen=True, repr=False, eq=True)
class DobsonSoil(Material):
    """Moist soil after Dobson et al. (1985), with Peplinski et al. (1995) below 1.4 GHz.

    moisture : volumetric water content m_v [m³/m³], in [0.01, 0.6] and at most the porosity
        ``1 − ρb/ρs`` (the loss term has ``1/m_v``: a dry soil is outside this model).
    sand, clay : mass fractions [-] of the dry soil, each in [0, 1], sand + clay ≤ 1.
    bulk_density : dry bulk density ρb [kg/m³], in [1000, 2000].
    temperature : [K], in [273.15, 313.15] (0–40 °C, the range of the free-water polynomials).

    Band 0.3–18 GHz. The model (Dobson et al. 1985, α = 0.65, ρs = 2.66 g/cm³,
    εs = (1.01 + 0.44 ρs)² − 0.062)::

        ε′ = [1 + (ρb/ρs)(εs^α − 1) + m_v^β′ ε′fw^α − m_v]^(1/α)
        ε″ = [m_v^β″ ε″fw^α]^(1/α)
        β′ = 1.2748 − 0.519 S − 0.152 C,  β″ = 1.33797 − 0.603 S − 0.166 C

    with free water ``εfw = εw∞ + (εw0 − εw∞)/(1 − i2πfτw) + iσeff(ρs − ρb)/(2πfε₀ρs m_v)``
    (densities in g/cm³). σeff [S/m] is
    ``−1.645 + 1.939ρb − 2.25622S + 1.594C`` (Dobson, 1.4–18 GHz) or
    ``0.0467 + 0.2204ρb − 0.4111S + 0.6614C`` (Peplinski, below 1.4 GHz, where also
    ``ε′ → 1.15ε′ − 0.68``).
    """

    moisture: float = 0.2
    sand: float = 0.4
    clay: float = 0.2
    bulk_density: float = 1400.0
    temperature: float = 293.15
    name: str = "soil (Dobson)"
    source: str = _DOBSON

    def __post_init__(self):
        m = _DOBSON
        sand = check_parameter("sand", self.sand, 0.0, 1.0, unit="(mass fraction)", model=m)
        clay = check_parameter("clay", self.clay, 0.0, 1.0, unit="(mass fraction)", model=m)
        _check_texture(sand, clay, m)
        rho = check_parameter(
            "bulk_density", self.bulk_density, 1000.0, 2000.0, unit="kg/m³", model=m
        )
        mv = check_parameter("moisture", self.moisture, 0.01, 0.6, unit="m³/m³", model=m)
        porosity = 1.0 - rho / SOLID_DENSITY
        if mv > porosity:
            raise ValueError(
                f"moisture = {mv:g} m³/m³ is more than the porosity 1 − ρb/ρs = {porosity:.3g} "
                f"of a soil with bulk_density = {rho:g} kg/m³ (ρs = {SOLID_DENSITY:g} kg/m³): "
                "more water than pore space"
            )
        t = check_parameter(
            "temperature", self.temperature, ZERO_CELSIUS, ZERO_CELSIUS + 40.0, unit="K", model=m
        )
        for attr, v in (("sand", sand), ("clay", clay), ("bulk_density", rho)):
            object.__setattr__(self, attr, v)
        object.__setattr__(self, "moisture", mv)
        object.__setattr__(self, "temperature", t)

    def _check_band(self, f):
        out_of_band(self, f, "MironovSoil (0.3–26.5 GHz)")

    @property
    def band(self):
        return (0.3e9, 18e9)

    def _eps(self, f):
        f = np.asarray(f, dtype=float)
        t = self.temperature - ZERO_CELSIUS  # °C in the polynomials
        rho_b, rho_s = self.bulk_density / 1000.0, SOLID_DENSITY / 1000.0  # g/cm³
        s, c, mv = self.sand, self.clay, self.moisture
        alpha = 0.65
        eps_solid = (1.01 + 0.44 * rho_s) ** 2 - 0.062
        beta_re = 1.2748 - 0.519 * s - 0.152 * c
        beta_im = 1.33797 - 0.603 * s - 0.166 * c
        low = f < 1.4e9  # Peplinski et al. 1995
        sigma_eff = np.where(
            low,
            0.0467 + 0.2204 * rho_b - 0.4111 * s + 0.6614 * c,
            -1.645 + 1.939 * rho_b - 2.25622 * s + 1.594 * c,
        )
        # free water (Ulaby, Moore & Fung 1986, App. E, as used by Dobson et al. 1985)
        two_pi_tau = 1.1109e-10 - 3.824e-12 * t + 6.938e-14 * t**2 - 5.096e-16 * t**3  # [s]
        eps_w0 = 88.045 - 0.4147 * t + 6.295e-4 * t**2 + 1.075e-5 * t**3
        eps_winf = 4.9
        wt = f * two_pi_tau
        relax = (eps_w0 - eps_winf) / (1.0 + wt**2)
        fw_re = eps_winf + relax
        conduction = sigma_eff * (rho_s - rho_b) / (2 * math.pi * f * EPSILON_0 * rho_s * mv)
        fw_im = wt * relax + conduction
        # a negative effective conductivity (coarse, light soils in Dobson's regression) would
        # make ε″ of the water negative: the regression is outside its data there
        if np.any(fw_im <= 0):
            bad = float(f[fw_im <= 0].ravel()[0])
            raise ValueError(
                f"{_DOBSON}: the effective conductivity regression gives a non-physical loss "
                f"at {bad / 1e9:g} GHz for sand = {s:g}, clay = {c:g}, bulk_density = "
                f"{self.bulk_density:g} kg/m³ (σeff = {float(np.ravel(sigma_eff)[0]):.3g} S/m); "
                "use MironovSoil or a denser/finer soil"
            )
        base = 1.0 + (rho_b / rho_s) * (eps_solid**alpha - 1.0) - mv
        re = (base + mv**beta_re * fw_re**alpha) ** (1.0 / alpha)
        im = (mv**beta_im * fw_im**alpha) ** (1.0 / alpha)
        re = np.where(low, 1.15 * re - 0.68, re)
        return re + 1j * im

    def to_dict(self):
        return {
            **super().to_dict(),
            "moisture": self.moisture,
            "sand": self.sand,
            "clay": self.clay,
            "bulk_density": self.bulk_density,
            "temperature": self.temperature,
        }


@dataclass(frozen=True, repr=False, eq=True)
class MironovSoil(Material):
    """Moist soil after Mironov, Kosolapova & Fomin (2009), the GRMDM.

    moisture : volumetric water content m_v [m³/m³], in [0, 0.6].
    clay : clay mass fraction [-], in [0, 0.76] (the range of the fitted soils).

    Band 0.3–26.5 GHz, room temperature (≈ 20 °C; the paper's model has no temperature).
    The refractive mixing (eqs. 11–13): with the complex index ``n + iκ`` of the dry soil (d),
    bound (b) and free (u) water and the maximum bound-water fraction ``m_vt``::

        n = n_d + (n_b − 1) min(m_v, m_vt) + (n_u − 1) max(m_v − m_vt, 0)
        κ = κ_d + κ_b min(m_v, m_vt) + κ_u max(m_v − m_vt, 0)
        ε = (n + iκ)²

    the waters' indices from Debye terms with conduction, ``ε∞ = 4.9``, and the parameters'
    regressions in the clay percentage C (eqs. 17–25): ``n_d = 1.634 − 0.539e−2 C +
    0.2748e−4 C²``, ``κ_d = 0.03952 − 0.04038e−2 C``, ``m_vt = 0.02863 + 0.30673e−2 C``,
    ``ε0b = 79.8 − 85.4e−2 C + 32.7e−4 C²``, ``τb = 1.062e−11 + 3.450e−12·1e−2 C`` s,
    ``σb = 0.3112 + 0.467e−2 C`` S/m, ``ε0u = 100``, ``τu = 8.5e−12`` s,
    ``σu = 0.3631 + 1.217e−2 C`` S/m.
    """

    moisture: float = 0.2
    clay: float = 0.2
    name: str = "soil (Mironov)"
    source: str = _MIRONOV

    def __post_init__(self):
        m = _MIRONOV
        mv = check_parameter("moisture", self.moisture, 0.0, 0.6, unit="m³/m³", model=m)
        clay = check_parameter("clay", self.clay, 0.0, 0.76, unit="(mass fraction)", model=m)
        object.__setattr__(self, "moisture", mv)
        object.__setattr__(self, "clay", clay)

    def _check_band(self, f):
        out_of_band(self, f, "below 0.3 GHz neither soil model holds; above 26.5 GHz neither")

    @property
    def band(self):
        return (0.3e9, 26.5e9)

    def _eps(self, f):
        f = np.asarray(f, dtype=float)
        c = 100.0 * self.clay  # percent in the regressions
        mv = self.moisture
        n_d = 1.634 - 0.539e-2 * c + 0.2748e-4 * c**2
        k_d = 0.03952 - 0.04038e-2 * c
        mvt = 0.02863 + 0.30673e-2 * c
        n_b, k_b = _water_index(
            f,
            79.8 - 85.4e-2 * c + 32.7e-4 * c**2,
            1.062e-11 + 3.450e-12 * 1e-2 * c,
            0.3112 + 0.467e-2 * c,
        )
        n_u, k_u = _water_index(f, 100.0, 8.5e-12, 0.3631 + 1.217e-2 * c)
        bound = min(mv, mvt)
        free = max(mv - mvt, 0.0)
        n = n_d + (n_b - 1.0) * bound + (n_u - 1.0) * free
        k = k_d + k_b * bound + k_u * free
        return (n + 1j * k) ** 2

    def to_dict(self):
        return {**super().to_dict(), "moisture": self.moisture, "clay": self.clay}


def _water_index(f, eps0, tau, sigma):
    """``(n, κ)`` of soil water with the Debye + conduction permittivity (Mironov eqs. 14–16)."""
    w = 2 * math.pi * f
    x = w * tau
    re = 4.9 + (eps0 - 4.9) / (1.0 + x**2)
    im = (eps0 - 4.9) * x / (1.0 + x**2) + sigma / (w * EPSILON_0)
    mod = np.hypot(re, im)
    return np.sqrt((mod + re) / 2.0), np.sqrt((mod - re) / 2.0)


SOIL_MODELS = {"dobson": DobsonSoil, "mironov": MironovSoil}


def soil(model: str = "mironov", **parameters) -> Material:
    """A soil by model name (``"mironov"``, the default, or ``"dobson"``) and its parameters
    (see :class:`MironovSoil`, :class:`DobsonSoil`). ``soil()`` is what the material name
    ``"soil"`` gives: Mironov's model with moisture 0.2 m³/m³ and clay fraction 0.2."""
    key = str(model).strip().lower()
    if key not in SOIL_MODELS:
        raise ValueError(f"unknown soil model {model!r}: use one of {sorted(SOIL_MODELS)}")
    return SOIL_MODELS[key](**parameters)
