"""Small-perturbation method (Rice 1951): first-order bistatic σ⁰, second-order coherent
reflectivity, second-order cross-pol, their validity and compiled kernel.

==================  =====================================================================
module              what it holds
==================  =====================================================================
:mod:`.model`       the solver: ``bistatic``, ``check_validity`` (the registry's ``"spm"``)
:mod:`.first_order` the first-order amplitudes ``f_pq`` and σ⁰, the coherent reflectivity
:mod:`.second_order` the second-order coherent kernel (derived from the boundary conditions)
:mod:`.crosspol`    second-order (2,2) backscatter cross-pol ``σ⁰_hv``
:mod:`.validity`    ``kσ``, rms-slope and per-angle scattered-fraction limits
:mod:`.compiled`    when the compiled σ⁰ kernel runs; :mod:`.kernel` the numba kernel itself
==================  =====================================================================
"""

from emscatter.solvers.spm.model import (
    OPTIONS,
    VALIDITY,
    bistatic,
    check_validity,
    coherent_cutoff,
    coherent_reflectivity,
)

__all__ = [
    "OPTIONS",
    "VALIDITY",
    "bistatic",
    "check_validity",
    "coherent_cutoff",
    "coherent_reflectivity",
]
