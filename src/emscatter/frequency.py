"""Frequencies that vary across a call, and permittivities that depend on frequency.

``frequency=`` / ``wavelength=`` in the public API may be arrays that broadcast with the
angles (a band, a spectrum) and ``eps`` may be a material (any object with
``.eps(frequency=...)`` [Hz] returning the complex relative permittivity, ``exp(-iωt)``; e.g.
:class:`emscatter.materials.Material`). The API then runs the solver once per distinct
frequency on the elements that have it (:func:`frequency_groups`) and puts the results back in
place; a material is evaluated once, at all distinct frequencies together.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .constants import SPEED_OF_LIGHT
from .conventions import broadcast_angles
from .fresnel import check_eps, is_pec

__all__ = [
    "Group",
    "is_material",
    "as_eps_or_material",
    "eps_at",
    "frequency_groups",
    "frequency_of",
]


def is_material(eps) -> bool:
    """Whether ``eps`` is a material (has a callable ``.eps``) rather than a value."""
    return not isinstance(eps, str) and callable(getattr(eps, "eps", None))


def frequency_of(k):
    """Frequency [Hz] of free-space wavenumber ``k`` [rad/m]."""
    return np.asarray(k) * SPEED_OF_LIGHT / (2 * math.pi)


def as_eps_or_material(eps):
    """``eps`` checked: ``"pec"``, a complex array (``Im ε ≥ 0``), or a material — an object
    with ``.eps(frequency=...)`` or a material name (``"Au"``, ``"concrete"``, ``"itu:glass"``;
    :func:`emscatter.materials.as_material`)."""
    if is_material(eps):
        return eps
    if isinstance(eps, str) and not is_pec(eps):
        from .materials import as_material

        return as_material(eps)
    return check_eps(eps)


def _material_eps(material, frequency):
    name = getattr(material, "name", type(material).__name__)
    from .materials import Material, eps_at

    if isinstance(material, Material):
        value = eps_at(material, frequency=frequency)  # "pec" for a perfect conductor
    else:
        value = material.eps(frequency=frequency)
    if isinstance(value, str):  # a perfect conductor
        return check_eps(value, f"eps of material {name!r}")
    return check_eps(np.asarray(value), f"eps of material {name!r}")


def eps_at(eps, k: float):
    """The permittivity at wavenumber ``k`` [rad/m]: ``eps`` itself, or a material's value."""
    if not is_material(eps):
        return eps
    return _material_eps(eps, float(frequency_of(k)))


@dataclass(frozen=True)
class Group:
    """The elements of a broadcast call that share one frequency."""

    k: float
    eps: object
    mask: np.ndarray

    @property
    def frequency(self) -> float:
        return float(frequency_of(self.k))

    def take(self, arrays) -> tuple[np.ndarray, ...]:
        """Each array broadcast to the call's shape, restricted to this group (1-D)."""
        return tuple(np.broadcast_to(a, self.mask.shape)[self.mask] for a in arrays)


def frequency_groups(k, eps, **arrays):
    """``None`` for a scalar ``k``; else ``(shape, k_broadcast, [Group, ...])`` with one group
    per distinct wavenumber, ``arrays`` (named, for error messages) and an array ``eps``
    broadcast together with ``k``."""
    if np.ndim(k) == 0:
        return None
    named = dict(arrays)
    named["frequency"] = np.asarray(k, dtype=float)
    eps_is_array = not is_material(eps) and not is_pec(eps) and np.ndim(eps) > 0
    if eps_is_array:
        named["eps"] = eps
    b = dict(zip(named, broadcast_angles(**named), strict=True))
    k_b = np.array(b["frequency"], dtype=float)
    shape = k_b.shape
    uniq, inverse = np.unique(k_b, return_inverse=True)
    inverse = inverse.reshape(shape)
    eps_u = _material_eps(eps, frequency_of(uniq)) if is_material(eps) else None
    groups = []
    for i, kv in enumerate(uniq):
        mask = inverse == i
        if eps_u is not None:
            e = eps_u if is_pec(eps_u) else np.broadcast_to(eps_u, uniq.shape)[i]
        elif eps_is_array:
            e = np.asarray(b["eps"])[mask]
        else:
            e = eps
        groups.append(Group(k=float(kv), eps=e, mask=mask))
    return shape, k_b, groups
