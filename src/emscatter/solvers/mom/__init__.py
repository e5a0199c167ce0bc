"""The exact 1-D reference: method of moments for rough profiles (the 2-D problem), with a
tapered incident wave (Thorsos 1988) and Monte Carlo over realizations.

==================  ====================================================================
module              what it holds
==================  ====================================================================
:mod:`.model`       the solver (the registry's ``"mom"``): ``bistatic``, ``reflectivity``
:mod:`.fields`      the tapered incident wave and its power, far-field quadrature
:mod:`.solve`       one realization: discretization, operators assembled, solution
:mod:`.operators`   the Green's-function matrix entries and the dense / forward-backward solves
==================  ====================================================================
"""

from emscatter.solvers.mom.model import (
    MomResult,
    MomWarning,
    bistatic,
    check_validity,
    reflectivity,
    solve_realization,
    tapered_wave,
)

__all__ = [
    "MomResult",
    "MomWarning",
    "bistatic",
    "check_validity",
    "reflectivity",
    "solve_realization",
    "tapered_wave",
]
