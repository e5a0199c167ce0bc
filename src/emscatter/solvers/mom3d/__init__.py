"""The exact 3-D reference (issue 19): method of moments for a perfectly conducting or
dielectric 2-D rough surface ``z = f(x, y)`` — MFIE (PEC) or Müller's equations (dielectric),
pulse bases, point matching, a tapered incident wave
(Tsang, Kong, Ding & Ao 2001 vol. II ch. 10), GMRES on the dense matrix or (large
patches, PEC and dielectric) the sparse-matrix/canonical-grid product, Monte Carlo over
realizations (serially, on a process pool or on a dask cluster: ``client=``).

=========================  ===============================================================
module                     what it holds
=========================  ===============================================================
:mod:`.model`              ``bistatic`` (Monte Carlo σ⁰, coherent part), ``solve_realization``
:mod:`.montecarlo`         the realizations serially, on an Executor or on dask (bit-identical)
:mod:`.operator`           the MFIE matrix (pulse basis, point matching, J/2 self term), GMRES
:mod:`.smcg`               the SMCG product of the MFIE: near pairs sparse, far pairs by FFT
:mod:`.dielectric`         Müller's equations (J and M, both media's Green functions), self cells
:mod:`.dielectric_smcg`    the SMCG product of Müller's equations (both media's far kernels)
:mod:`.dielectric_model`   one dielectric realization: reflected/transmitted power, Fresnel beam
:mod:`.incident`           the tapered wave as a Gaussian plane-wave spectrum, its exact power
:mod:`.farfield`           far-field amplitudes, polarization vectors, hemisphere quadrature
:mod:`.gridsum`            fast far-field sums on the grid (Taylor in height, gridding NUFFT)
:mod:`.truncated`          band-limited surfaces (``spectral_cutoff``): spectrum zeroed > K_c
=========================  ===============================================================

Not registered as a solver yet; call
``emscatter.solvers.mom3d.bistatic``.
"""

from emscatter.solvers.mom3d.model import bistatic, matrix_bytes, solve_realization

__all__ = ["bistatic", "matrix_bytes", "solve_realization"]
