"""Integral-equation model (Fung, Li & Chen 1992; the advanced IEM of Chen et al. 2003):
co-pol single scattering with the transition function, the multiple-scattering cross-pol
term, and their compiled kernels.

======================  ===============================================================
module                  what it holds
======================  ===============================================================
:mod:`.model`           the solver (the registry's ``"iem"``): ``bistatic``, ``check_validity``
:mod:`.terms`           Kirchhoff and complementary field coefficients, the transition
:mod:`.series`          the spectral series Σ (kσ)^{2n}/n! W⁽ⁿ⁾ in log space
:mod:`.crosspol`        multiple-scattering hv (Fung 1994; Chen et al. 2003 app. C)
:mod:`.crosspol_terms`  the slope polynomials shared by numpy and compiled cross-pol
:mod:`.compiled`        when the compiled kernels run; :mod:`.kernels` the numba kernels
                        (series, lanes, crosspol)
======================  ===============================================================
"""

from emscatter.solvers.iem.model import OPTIONS, VALIDITY, bistatic, check_validity

__all__ = ["OPTIONS", "VALIDITY", "bistatic", "check_validity"]
