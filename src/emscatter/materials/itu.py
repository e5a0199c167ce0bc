"""Building materials of recommendation ITU-R P.2040 (§2.1.4, Table 3): real relative
permittivity ``ε′ = a f^b`` and conductivity ``σ = c f^d`` [S/m] with ``f`` in GHz, each
curve fit valid on its frequency band.

The table (values and bands, including the extra bands of P.2040-3/-4 above 100 GHz) is the
one Sionna RT 2.2 uses (``sionna/rt/radio_materials/itu.py``), in the same order: where bands
overlap, the first listed band that contains the frequency is used, as Sionna does, so that an
emscatter material and Sionna's ``ITURadioMaterial`` agree exactly (tested against the installed
Sionna). Converted to emscatter's ``exp(−iωt)`` convention: ``ε = ε′ + i σ/(ω ε₀)``
(P.2040 and Sionna write ``ε′ − jσ/(ωε₀)`` under ``exp(+jωt)``).

Outside every band :class:`~emscatter.materials.OutOfBandError`; ``extrapolate=True`` uses the
power law of the nearest band beyond its end (an explicit, documented extrapolation: the fits
are smooth power laws, but nothing guarantees them outside the measured range).
"""

from __future__ import annotations

import math

import numpy as np

from .core import (
    Material,
    OutOfBandError,
    _format_band,
    eps_from_conductivity,
    format_frequency,
    unit_hint,
)

__all__ = ["ITU_P2040", "ItuMaterial", "itu", "available_itu"]

#: name → list of ((f_min, f_max) [GHz], (a, b, c, d)), in Sionna RT 2.2's order.
ITU_P2040: dict[str, list[tuple[tuple[float, float], tuple[float, float, float, float]]]] = {
    "vacuum": [((0.001, 100.0), (1.0, 0.0, 0.0, 0.0))],
    "concrete": [
        ((1.0, 100.0), (5.24, 0.0, 0.0462, 0.7822)),
        ((110.0, 330.0), (5.17, 0.0, 0.0145, 1.0900)),
    ],
    "brick": [
        ((1.0, 40.0), (3.91, 0.0, 0.0238, 0.16)),
        ((110.0, 330.0), (4.15, 0.0, 0.0006, 1.5712)),
    ],
    "plasterboard": [
        ((1.0, 100.0), (2.73, 0.0, 0.0085, 0.9395)),
        ((110.0, 330.0), (2.56, 0.0, 0.0001, 1.7799)),
        ((100.0, 400.0), (2.65, 0.0, 0.0002, 1.598)),
    ],
    "wood": [
        ((0.001, 100.0), (1.99, 0.0, 0.0047, 1.0718)),
        ((110.0, 330.0), (1.82, 0.0, 0.0040, 1.0761)),
        ((100.0, 400.0), (2.1183, 0.0, 0.0055, 1.1113)),
    ],
    "glass": [
        ((0.1, 100.0), (6.31, 0.0, 0.0036, 1.3394)),
        ((220.0, 450.0), (5.79, 0.0, 0.0004, 1.658)),
        ((100.0, 400.0), (6.5767, 0.0, 0.0012, 1.4697)),
    ],
    "clear_acrylic": [((110.0, 330.0), (2.58, 0.0, 0.0001, 1.6524))],
    "ceiling_board": [
        ((1.0, 100.0), (1.48, 0.0, 0.0011, 1.0750)),
        ((220.0, 450.0), (1.52, 0.0, 0.0029, 1.029)),
        ((100.0, 400.0), (1.2567, 0.0, 0.00013, 1.454)),
    ],
    "chipboard": [
        ((1.0, 100.0), (2.58, 0.0, 0.0217, 0.7800)),
        ((100.0, 200.0), (2.16, 0.0, 0.0023, 1.359)),
    ],
    "plywood": [
        ((1.0, 40.0), (2.71, 0.0, 0.33, 0.0)),
        ((110.0, 330.0), (1.94, 0.0, 0.0067, 0.9982)),
        ((100.0, 400.0), (2.17, 0.0, 0.0063, 1.045)),
    ],
    "marble": [
        ((1.0, 60.0), (7.074, 0.0, 0.0055, 0.9262)),
        ((110.0, 330.0), (7.94, 0.0, 0.0001, 1.7330)),
        ((100.0, 400.0), (8.62, 0.0, 0.0027, 1.15)),
    ],
    "floorboard": [
        ((50.0, 100.0), (3.66, 0.0, 0.0044, 1.3515)),
        ((220.0, 300.0), (5.27, 0.0, 2.22e-17, 7.3413)),
        ((300.0, 400.0), (5.27, 0.0, 0.0003, 2.0298)),
        ((400.0, 450.0), (5.27, 0.0, 49.8726, 0.0)),
        ((100.0, 400.0), (3.1575, 0.0, 0.001675, 1.32775)),
    ],
    "vinyl_tile": [((1.0, 40.0), (3.62, 0.0, 0.0051, 0.8422))],
    "carpet_tile": [((1.0, 40.0), (2.08, 0.0, 0.0009, 0.8200))],
    "asphalt_concrete": [((1.0, 40.0), (4.83, 0.0, 0.0108, 1.3969))],
    "metal": [((1.0, 100.0), (1.0, 0.0, 1e7, 0.0))],
    "very_dry_ground": [((1.0, 10.0), (3.0, 0.0, 0.00015, 2.52))],
    "medium_dry_ground": [((1.0, 10.0), (15.0, -0.1, 0.035, 1.63))],
    "wet_ground": [((1.0, 10.0), (30.0, -0.4, 0.15, 1.30))],
}

_SOURCE = "ITU-R P.2040-3 Table 3 (+ P.2040-4 bands), as tabulated in Sionna RT 2.2"


def available_itu() -> list[str]:
    """ITU-R P.2040 material names (Sionna's spelling: ``"concrete"``, ``"plasterboard"``, ...)."""
    return list(ITU_P2040)


class ItuMaterial(Material):
    """One ITU-R P.2040 material (module docstring). Build it with :func:`itu`."""

    def __init__(self, name: str, *, extrapolate: bool = False):
        if not isinstance(name, str) or name.lower() not in ITU_P2040:
            raise ValueError(
                f"ITU-R P.2040 material must be one of {available_itu()}, got {name!r}"
            )
        if not isinstance(extrapolate, bool):
            raise TypeError(f"extrapolate must be True or False, got {extrapolate!r}")
        self.name = name.lower()
        self.source = _SOURCE
        self.extrapolate = extrapolate
        self._bands = ITU_P2040[self.name]

    @property
    def bands(self) -> list[tuple[float, float]]:
        """The bands [Hz] where the fits hold, in table order."""
        return [(lo * 1e9, hi * 1e9) for (lo, hi), _ in self._bands]

    @property
    def band(self):
        if self.extrapolate:
            return None
        return (min(b[0] for b in self.bands), max(b[1] for b in self.bands))

    def in_band(self, frequency):
        f = np.asarray(frequency, dtype=float)
        if self.extrapolate:
            return np.ones(f.shape, dtype=bool)
        ok = np.zeros(f.shape, dtype=bool)
        for lo, hi in self.bands:
            ok |= (f >= lo * (1 - 1e-12)) & (f <= hi * (1 + 1e-12))
        return ok

    def _check_band(self, f):
        ok = self.in_band(f)
        if not np.all(ok):
            bad = float(np.asarray(f)[~ok].ravel()[0])
            bands = ", ".join(_format_band(lo, hi) for lo, hi in self.bands)
            raise OutOfBandError(
                f"ITU-R P.2040 material {self.name!r} is defined for {bands}, got "
                f"{format_frequency(bad)}{unit_hint(bad)}. Ways out: give the permittivity "
                "yourself (eps=... or "
                "materials.Constant / eps_from_conductivity(eps_real, sigma, f)), or "
                f"materials.itu({self.name!r}, extrapolate=True) to extend the nearest band's "
                "power law (an extrapolation beyond the measured range)."
            )

    def coefficients(self, frequency) -> tuple[np.ndarray, ...]:
        """``(a, b, c, d)`` arrays chosen per frequency [Hz] (first band that holds it; with
        ``extrapolate=True`` and no band, the nearest band)."""
        f = np.asarray(frequency, dtype=float) / 1e9
        out = [np.full(f.shape, np.nan) for _ in range(4)]
        done = np.zeros(f.shape, dtype=bool)
        for (lo, hi), abcd in self._bands:
            sel = ~done & (f >= lo * (1 - 1e-12)) & (f <= hi * (1 + 1e-12))
            for arr, v in zip(out, abcd, strict=True):
                arr[sel] = v
            done |= sel
        if not np.all(done):  # extrapolation: nearest band in log-frequency
            lf = np.log(f[~done])[..., None]
            ends = np.array([[math.log(lo), math.log(hi)] for (lo, hi), _ in self._bands])
            dist = np.minimum(np.abs(lf - ends[:, 0]), np.abs(lf - ends[:, 1]))
            pick = np.argmin(dist, axis=-1)
            table = np.array([abcd for _, abcd in self._bands])
            for i, arr in enumerate(out):
                arr[~done] = table[pick, i]
        return tuple(out)

    def eps_real_and_conductivity(self, frequency) -> tuple[np.ndarray, np.ndarray]:
        """``(ε′ [-], σ [S/m])`` at ``frequency`` [Hz] (P.2040 eqs. 58–59 form)."""
        f = np.asarray(frequency, dtype=float)
        self._check_band(f)
        a, b, c, d = self.coefficients(f)
        g = f / 1e9
        return a * g**b, c * g**d

    def _eps(self, f):
        er, sig = self.eps_real_and_conductivity(f)
        return eps_from_conductivity(er, sig, f)

    def to_dict(self):
        return {**super().to_dict(), "extrapolate": self.extrapolate}


def itu(name: str, *, extrapolate: bool = False) -> ItuMaterial:
    """An ITU-R P.2040 building material by name (``"concrete"``, ``"plasterboard"``,
    ``"glass"``, ``"metal"``, ...; :func:`available_itu`)."""
    return ItuMaterial(name, extrapolate=extrapolate)
