"""Scattering solvers: one module per formulation, all with the same contract.

Every solver module exposes

* ``bistatic(roughness, eps, k, theta_i, theta_s, phi_s, phi_i=0.0, **options) -> Scattering``
* ``check_validity(roughness, k) -> dict`` with at least ``{"valid": bool, "reasons": [...]}``

so that tests can compare them where their validity ranges overlap (the style of
``miepython``'s sibling modules). The registry below maps short names to modules; modules
are imported lazily so ``import emscatter`` stays fast.

========  ===============================================  =====================
name      formulation                                      module
========  ===============================================  =====================
``spm``   small-perturbation method (1st-order σ⁰,         :mod:`.spm`
          2nd-order coherent reflectivity)
``go``    Kirchhoff, geometric optics (stationary phase)   :mod:`.kirchhoff_go`
``po``    Kirchhoff, physical optics (scalar, series)      :mod:`.kirchhoff_po`
``mom``   method of moments, 1-D profiles (reference)      :mod:`.mom`
``iem``   integral-equation model (AIEM), all pols, hv     :mod:`.iem`
========  ===============================================  =====================
"""

from __future__ import annotations

import importlib
import sys
from types import ModuleType

_REGISTRY: dict[str, str] = {
    "spm": "emscatter.solvers.spm",
    "go": "emscatter.solvers.kirchhoff_go",
    "po": "emscatter.solvers.kirchhoff_po",
    "mom": "emscatter.solvers.mom",
    "iem": "emscatter.solvers.iem",
}

#: Methods that ``method="auto"`` may choose, cheapest first.
AUTO_ORDER: tuple[str, ...] = ("spm", "go", "po", "iem")


def register(name: str, module: str) -> None:
    """Register a solver module (dotted path) under ``name``."""
    if not isinstance(name, str) or not name:
        raise ValueError(f"solver name must be a non-empty string, got {name!r}")
    _REGISTRY[name.lower()] = module


def available() -> list[str]:
    """Registered solver names."""
    return sorted(_REGISTRY)


def get(name: str) -> ModuleType:
    """The solver module registered as ``name``."""
    if not isinstance(name, str) or name.lower() not in _REGISTRY:
        raise ValueError(f"method must be one of {['auto', *available()]}, got {name!r}")
    target = _REGISTRY[name.lower()]
    return sys.modules.get(target) or importlib.import_module(target)  # (the import, once)
