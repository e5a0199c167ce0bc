"""Scattering solvers: one subpackage per formulation, all with the same contract.

Every solver module exposes

* ``bistatic(roughness, eps, k, theta_i, theta_s, phi_s, phi_i=0.0, **options) -> Scattering``
* ``check_validity(roughness, k) -> dict`` with at least ``{"valid": bool, "reasons": [...]}``

so that tests can compare them where their validity ranges overlap (the style of
``miepython``'s sibling modules). The registry below maps short names to modules; modules
are imported lazily so ``import emscatter`` stays fast. Beside the formulations:
:mod:`.select` (``auto``'s ranking), :mod:`.validity` (the shared validity machinery),
:mod:`.measured` (the measured errors of the validity maps), :mod:`.coherent` (the coherent
reflectivity dispatcher). ``docs/architecture.md`` says where each equation lives.

The flat module names of 0.1 (``emscatter.solvers.kirchhoff_go``,
``emscatter.solvers.iem.crosspol``, …) still
resolve as attributes of this package, with a ``DeprecationWarning``; they go in 0.3.

========  ===============================================  =====================
name      formulation                                      module
========  ===============================================  =====================
``spm``   small-perturbation method (1st-order σ⁰,         :mod:`.spm.model`
          2nd-order coherent reflectivity)
``go``    Kirchhoff, geometric optics (stationary phase)   :mod:`.kirchhoff.go`
``po``    Kirchhoff, physical optics (scalar, series)      :mod:`.kirchhoff.po`
``mom``   method of moments, 1-D profiles (reference)      :mod:`.mom.model`
``iem``   integral-equation model (AIEM), all pols, hv     :mod:`.iem.model`
========  ===============================================  =====================
"""

from __future__ import annotations

import importlib
import sys
from types import ModuleType

_REGISTRY: dict[str, str] = {
    "spm": "emscatter.solvers.spm.model",
    "go": "emscatter.solvers.kirchhoff.go",
    "po": "emscatter.solvers.kirchhoff.po",
    "mom": "emscatter.solvers.mom.model",
    "iem": "emscatter.solvers.iem.model",
}

#: The 0.1 flat module names → their homes since 0.2 (deprecated; removed in 0.3).
_MOVED: dict[str, str] = {
    "spm_validity": "emscatter.solvers.spm.validity",
    "spm_second_order": "emscatter.solvers.spm.second_order",
    "spm2_crosspol": "emscatter.solvers.spm.crosspol",
    "kirchhoff_common": "emscatter.solvers.kirchhoff.common",
    "kirchhoff_go": "emscatter.solvers.kirchhoff.go",
    "kirchhoff_po": "emscatter.solvers.kirchhoff.po",
    "go_monostatic": "emscatter.solvers.kirchhoff.go_backscatter",
    "iem_series": "emscatter.solvers.iem.series",
    "iem_kernels": "emscatter.solvers.iem.terms",
    "iem_crosspol": "emscatter.solvers.iem.crosspol",
    "iem_crosspol_numba": "emscatter.solvers.iem.kernels.crosspol",
    "iem_jit": "emscatter.solvers.iem.compiled",
    "iem_numba": "emscatter.solvers.iem.kernels.series",
    "mom_fields": "emscatter.solvers.mom.fields",
    "mom_kernels": "emscatter.solvers.mom.operators",
    "mom_solve": "emscatter.solvers.mom.solve",
}


def __getattr__(name: str):
    """The deprecated flat module names (:data:`_MOVED`): the moved module, with a warning."""
    if name in _MOVED:
        import warnings

        warnings.warn(
            f"emscatter.solvers.{name} moved to {_MOVED[name]} in 0.2 and will be removed in "
            "0.3; import it from there",
            DeprecationWarning,
            stacklevel=2,
        )
        return importlib.import_module(_MOVED[name])
    raise AttributeError(f"module 'emscatter.solvers' has no attribute {name!r}")


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
