"""The exact 3-D reference (issue 19), first form: method of moments for a perfectly conducting
2-D rough surface ``z = f(x, y)`` — MFIE, pulse bases, point matching, a tapered incident wave
(Tsang, Kong, Ding & Ao 2001 vol. II ch. 10), dense GMRES, Monte Carlo over realizations.

==================  ====================================================================
module              what it holds
==================  ====================================================================
:mod:`.model`       ``bistatic`` (Monte Carlo σ⁰, coherent reflectivity), ``solve_realization``
:mod:`.operator`    the MFIE matrix (pulse basis, point matching, J/2 self term), GMRES
:mod:`.incident`    the tapered wave as a Gaussian plane-wave spectrum, its exact power
:mod:`.farfield`    far-field amplitudes, polarization vectors, hemisphere quadrature
==================  ====================================================================

Not registered as a solver yet (perfect conductors only); call
``emscatter.solvers.mom3d.bistatic``.
"""

from emscatter.solvers.mom3d.model import bistatic, matrix_bytes, solve_realization

__all__ = ["bistatic", "matrix_bytes", "solve_realization"]
