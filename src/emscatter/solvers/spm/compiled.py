"""The compiled paths of SPM, behind the shared gate (:mod:`emscatter.kernels.gate`):
first-order σ⁰ (:mod:`.kernel`; :func:`spm1_sigma0` returns ``True`` after filling ``out`` or
``False``, nothing touched, so that :mod:`.model` runs its numpy reference) and the
second-order backscatter cross-pol (:mod:`.kernel_crosspol`; :func:`spm2_backscatter_hv`
returns the values or None, so that :mod:`.crosspol` runs its numpy reference)."""

from __future__ import annotations

import functools
import os

import numpy as np

from emscatter.kernels import SPM_EXPONENTIAL, SPM_GAUSSIAN, backend
from emscatter.kernels.gate import azimuth_ok, flat, scalar_eps, worth_it

__all__ = ["spm1_sigma0", "covered_spm1", "spm2_backscatter_hv", "SPM2_ANGLE_WEIGHT"]

#: One SPM2 backscatter angle counted as this many geometries by :func:`worth_it`: ~5000
#: kernel nodes, 1.5–5 ms in numpy, so ≥ 64 angles (≈ 0.1–0.3 s) pay for loading numba.
SPM2_ANGLE_WEIGHT = 64


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


def spm2_backscatter_hv(rough, eps: complex, k: float, theta, phi_i: float, n_radial: int,
                        n_azimuth: int):  # fmt: skip
    """Second-order SPM backscatter hv [-] at the flat angles ``theta`` [rad] (checked by
    :func:`emscatter.solvers.spm.crosspol.backscatter_hv`, whose arguments these are), or None
    where the numpy reference runs: backend numpy, a correlation other than Gaussian or
    exponential, a small call before the kernels are loaded. Angles whose azimuth rule lacks
    the point symmetry come back as NaN (the caller computes them in numpy)."""
    from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation

    n = int(np.size(theta))
    codes = {GaussianCorrelation: SPM_GAUSSIAN, ExponentialCorrelation: SPM_EXPONENTIAL}
    if (
        n == 0
        or backend() != "numba"
        or type(rough) not in codes
        or rough.dimension != 2
        or not worth_it(n * SPM2_ANGLE_WEIGHT)
    ):
        return None
    from emscatter.solvers.spm.kernel_crosspol import backscatter_hv as kernel

    vals, done = kernel(
        np.asarray(theta, dtype=float).ravel(), complex(eps), float(k), rough.sigma,
        rough.length, rough.length_y, float(phi_i), codes[type(rough)], int(n_radial),
        int(n_azimuth), threads=min(os.cpu_count() or 1, 8),
    )  # fmt: skip
    vals[~done] = np.nan
    return vals
