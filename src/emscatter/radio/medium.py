"""What a radio material is made of: a :class:`~emscatter.materials.Material` from an ITU-R
P.2040 name, a permittivity, or a real permittivity and a conductivity [S/m]."""

from __future__ import annotations

import math
import numbers

import numpy as np

from .. import materials
from ..constants import EPSILON_0
from ..conventions import check_real_scalar

__all__ = ["ConductiveMedium", "resolve_medium", "real_number", "check_thickness"]


def _unwrap_drjit(value):
    """A Dr.Jit scalar (``mi.Float(0.1)``, the type of Sionna's ``radio_material.thickness``:
    one lane of a JIT array) → its Python value; anything else unchanged. Detected by module
    name, so Dr.Jit is never imported here."""
    if not type(value).__module__.startswith("drjit"):
        return value
    import drjit as dr

    if (
        dr.is_array_v(value)
        and dr.depth_v(value) == 1
        and not dr.is_mask_v(value)
        and not dr.is_complex_v(value)
        and dr.width(value) == 1
    ):
        return value[0]
    return value


def real_number(name: str, value) -> float:
    """A finite real number from a Python or NumPy number (``np.float32``, ``np.int64``, a 0-d
    array) or a one-lane Dr.Jit scalar (``mi.Float``); a clear error naming ``name`` otherwise."""
    return check_real_scalar(name, _unwrap_drjit(value))


def check_thickness(thickness) -> float | None:
    """A slab thickness [m] > 0 as a float, or ``None`` (a half-space)."""
    if thickness is None:
        return None
    try:
        d = real_number("thickness", thickness)
    except (TypeError, ValueError):
        d = math.nan
    if not (math.isfinite(d) and d > 0):
        raise ValueError(
            "thickness must be a positive number of metres (a finite real > 0), or None for a "
            f"half-space; got {thickness!r}"
        )
    return d


class ConductiveMedium(materials.Material):
    """``ε(f) = ε′ + iσ/(2πf ε₀)`` (``exp(−iωt)``) for a real relative permittivity ``ε′`` [-]
    and a conductivity ``σ`` [S/m] that do not depend on frequency — the form Sionna's
    ``RadioMaterial(relative_permittivity, conductivity)`` takes."""

    def __init__(self, eps_real: float, conductivity: float, name: str | None = None):
        er = real_number("eps_real", eps_real)
        sig = real_number("conductivity", conductivity)
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
    medium = _unwrap_drjit(medium)
    if isinstance(medium, bool | np.bool_):
        raise TypeError(
            f"medium must be an ITU-R P.2040 name, a Material or a permittivity, got {medium!r}"
        )
    if isinstance(medium, numbers.Number) or (
        isinstance(medium, np.ndarray | np.generic) and np.ndim(medium) == 0
    ):
        if complex(medium).real <= 0:
            raise ValueError(
                f"medium: a permittivity must have Re ε > 0 for a radio medium (as eps_real > 0), "
                f"got {medium!r}; for a metal use medium='metal' (ITU-R P.2040, 1e7 S/m) or "
                "eps_real=1 with a large conductivity [S/m]"
            )
        return materials.Constant(complex(medium))
    mat = materials.as_material(medium)
    if isinstance(mat, materials.PerfectConductor):
        raise ValueError("a perfect conductor cannot be a radio medium; use medium='metal'")
    return mat
