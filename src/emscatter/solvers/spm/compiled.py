"""The compiled path of first-order SPM σ⁰ (:mod:`.kernel`), behind the shared gate
(:mod:`emscatter.kernels.gate`): :func:`spm1_sigma0` returns ``True`` after filling ``out`` or
``False`` (nothing touched) so that :mod:`.model` runs its numpy reference."""

from __future__ import annotations

import functools

import numpy as np

from emscatter.kernels import SPM_EXPONENTIAL, SPM_GAUSSIAN, backend
from emscatter.kernels.gate import azimuth_ok, flat, scalar_eps, worth_it

__all__ = ["spm1_sigma0", "covered_spm1"]


@functools.cache
def _spm1_spectra() -> dict:
    from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation

    return {GaussianCorrelation: SPM_GAUSSIAN, ExponentialCorrelation: SPM_EXPONENTIAL}


def covered_spm1(rough, eps) -> bool:
    """Whether :func:`spm1_sigma0` has a kernel for this roughness and permittivity."""
    return (
        rough.dimension == 2
        and type(rough) in _spm1_spectra()
        and rough.is_isotropic
        and scalar_eps(eps) is not None
    )


def spm1_sigma0(rough, eps, k: float, ti, ts, dphi, out: np.ndarray) -> bool:
    """First-order SPM σ⁰ into ``out`` (2, 2, n) for flat angle arrays [rad] (as
    ``emscatter.solvers.spm.model._sigma0_first``)."""
    n = out.shape[-1]
    if backend() != "numba" or not worth_it(n) or not covered_spm1(rough, eps):
        return False
    dphi = flat(dphi, n)
    if not azimuth_ok(dphi) or not out.flags.c_contiguous:
        return False
    from emscatter.solvers.spm.kernel import spm1_sigma0 as kernel

    code = _spm1_spectra()[type(rough)]
    kernel(
        flat(ti, n), flat(ts, n), dphi, scalar_eps(eps),
        k=k, sigma=rough.sigma, length=rough.length, spectrum=code, out=out,
    )  # fmt: skip
    return True
