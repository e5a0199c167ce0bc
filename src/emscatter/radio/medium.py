"""What a radio material is made of: a :class:`~emscatter.materials.Material` from an ITU-R
P.2040 name, a permittivity, or a real permittivity and a conductivity [S/m]."""

from __future__ import annotations

import math
import numbers

import numpy as np

from .. import materials
from ..constants import EPSILON_0
from ..conventions import check_real_scalar

__all__ = ["ConductiveMedium", "resolve_medium"]


class ConductiveMedium(materials.Material):
    """``ε(f) = ε′ + iσ/(2πf ε₀)`` (``exp(−iωt)``) for a real relative permittivity ``ε′`` [-]
    and a conductivity ``σ`` [S/m] that do not depend on frequency — the form Sionna's
    ``RadioMaterial(relative_permittivity, conductivity)`` takes."""

    def __init__(self, eps_real: float, conductivity: float, name: str | None = None):
        er = check_real_scalar("eps_real", eps_real)
        sig = check_real_scalar("conductivity", conductivity)
        if sig < 0:
            raise ValueError(
                f"conductivity must be >= 0 [S/m], got {sig:g} S/m (a negative conductivity "
                "would be a medium that creates energy); a loss-free medium has conductivity=0"
            )
        if er <= 0:
            raise ValueError(
                f"eps_real must be > 0 for a dielectric, got {er:g}; for a metal give a large "
                "conductivity instead (e.g. medium='metal': ITU-R P.2040, 1e7 S/m)"
            )
        self.eps_real = er
        self.conductivity_s_per_m = sig
        self.name = name or f"eps'={er:g}, sigma={sig:g} S/m"
        self.source = "user-given (eps', conductivity)"

    def _eps(self, f):
        return self.eps_real + 1j * self.conductivity_s_per_m / (2 * math.pi * f * EPSILON_0)

    def to_dict(self):
        return {
            **super().to_dict(),
            "eps_real": self.eps_real,
            "conductivity": self.conductivity_s_per_m,
        }


def resolve_medium(medium=None, *, eps_real=None, conductivity=None) -> materials.Material:
    """A :class:`~emscatter.materials.Material` from exactly one of

    * ``medium``: a Material, an ITU-R P.2040 name (``"concrete"``, ``"itu:glass"``), or a
      complex permittivity (``exp(−iωt)``, ``Im ε ≥ 0``; constant over frequency);
    * ``eps_real`` [-] and ``conductivity`` [S/m] together (:class:`ConductiveMedium`).

    A perfect conductor has no finite permittivity for Sionna's slab formulas: use
    ``"metal"`` (ITU, 1e7 S/m) or a large conductivity.
    """
    pair = (eps_real is not None, conductivity is not None)
    if medium is not None and any(pair):
        raise ValueError(
            "give either medium=... or eps_real=... with conductivity=..., not both "
            f"(got medium={medium!r}, eps_real={eps_real!r}, conductivity={conductivity!r})"
        )
    if medium is None:
        if not all(pair):
            raise ValueError(
                "a radio material needs a medium: medium='concrete' (an ITU-R P.2040 name, one "
                f"of {materials.available_itu()}), medium=<complex eps>, or eps_real=... "
                f"together with conductivity=... [S/m]; got eps_real={eps_real!r}, "
                f"conductivity={conductivity!r}"
            )
        return ConductiveMedium(eps_real, conductivity)
    if isinstance(medium, str) and medium.strip().lower() in ("pec", "itu:pec"):
        raise ValueError(
            "medium='pec': Sionna's slab formulas need a finite permittivity; use "
            "medium='metal' (ITU-R P.2040, 1e7 S/m) or eps_real=1, conductivity=1e7"
        )
    if isinstance(medium, numbers.Number) or (
        isinstance(medium, np.ndarray | np.generic) and np.ndim(medium) == 0
    ):
        return materials.Constant(complex(medium))
    mat = materials.as_material(medium)
    if isinstance(mat, materials.PerfectConductor):
        raise ValueError("a perfect conductor cannot be a radio medium; use medium='metal'")
    return mat
