"""The IEM's compiled (numba) kernels: :mod:`.series` (log-space spectral series, Poisson and
transition sums), :mod:`.lanes` (the linear-space backscatter walk, σ⁰ assembly),
:mod:`.crosspol` (the multiple-scattering cross-pol integral). :mod:`..compiled` decides when
they run; compiled on first use and cached on disk (:mod:`emscatter.kernels._runtime`)."""
