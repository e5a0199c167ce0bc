"""The one place the solvers ask "is there a compiled kernel for this call?".

Each function returns ``True`` after filling the caller's output arrays with the compiled
kernel, or ``False`` (nothing touched) when the case is not covered or the numpy path is
selected (:func:`emscatter.kernels.backend`); the solver then runs its numpy code.
Light to import: numba is imported only when a kernel runs.
"""

from __future__ import annotations

import functools
import sys

import numpy as np

from . import SPM_EXPONENTIAL, SPM_GAUSSIAN, backend, selection

__all__ = ["spm1_sigma0", "go_sigma0", "po_log_series", "covered_spm1", "covered_go"]

MAX_AZIMUTH = 1.0e6  # |φs − φi| [rad] up to which the kernels' cos reduction is exact
#: Below this many geometries a call takes the numpy path unless the kernels are already
#: loaded in this process: a 90-angle curve costs ~0.2 ms in numpy, while the first kernel call
#: imports numba and loads the compiled code (~0.5 s; 3–4 s if it must compile).
MIN_GEOMETRIES = 4096


def _worth_it(n: int) -> bool:
    if n >= MIN_GEOMETRIES or "emscatter.kernels._runtime" in sys.modules:
        return True
    return selection() == "numba"


def _scalar_eps(eps):
    """``"pec"``, a Python complex, or None when ``eps`` is an array with more than one value."""
    if isinstance(eps, str):
        return "pec" if eps.lower() == "pec" else None
    arr = np.asarray(eps)
    if arr.ndim == 0:
        return complex(arr)
    return None


def _flat(a, n: int) -> np.ndarray:
    a = np.asarray(a, dtype=np.float64)
    if a.size == n and a.ndim == 1 and a.flags.c_contiguous:
        return a
    return np.ascontiguousarray(np.broadcast_to(a, (n,)).reshape(n))


def _azimuth_ok(dphi: np.ndarray) -> bool:
    return dphi.size == 0 or -MAX_AZIMUTH <= dphi.min() and dphi.max() <= MAX_AZIMUTH


@functools.cache
def _spm1_spectra() -> dict:
    from ..spectra import ExponentialCorrelation, GaussianCorrelation

    return {GaussianCorrelation: SPM_GAUSSIAN, ExponentialCorrelation: SPM_EXPONENTIAL}


def covered_spm1(rough, eps) -> bool:
    """Whether :func:`spm1_sigma0` has a kernel for this roughness and permittivity."""
    return (
        rough.dimension == 2
        and type(rough) in _spm1_spectra()
        and rough.is_isotropic
        and _scalar_eps(eps) is not None
    )


def spm1_sigma0(rough, eps, k: float, ti, ts, dphi, out: np.ndarray) -> bool:
    """First-order SPM σ⁰ into ``out`` (2, 2, n) for flat angle arrays [rad] (as
    ``emscatter.solvers.spm._sigma0_first``)."""
    n = out.shape[-1]
    if backend() != "numba" or not _worth_it(n) or not covered_spm1(rough, eps):
        return False
    dphi = _flat(dphi, n)
    if not _azimuth_ok(dphi) or not out.flags.c_contiguous:
        return False
    from .spm import spm1_sigma0 as kernel

    code = _spm1_spectra()[type(rough)]
    kernel(
        _flat(ti, n), _flat(ts, n), dphi, _scalar_eps(eps),
        k=k, sigma=rough.sigma, length=rough.length, spectrum=code, out=out,
    )  # fmt: skip
    return True


def covered_go(dimension: int, sx: float, sy: float, eps, shadowing) -> bool:
    """Whether :func:`go_sigma0` has a kernel for this case."""
    return (
        dimension == 2
        and sx == sy
        and shadowing in (None, "smith", "separable", "correlated", "direction-correlated")
        and _scalar_eps(eps) is not None
    )


def go_sigma0(
    ti, ts, dphi, eps, *, dimension: int, sx: float, sy: float, shadowing,
    out: np.ndarray, coherent_out: np.ndarray | None = None, k: float = 1.0, sigma: float = 0.0,
    threads: int | None = None,
) -> bool:  # fmt: skip
    """GO σ⁰ into ``out`` (2, 2, n) and, when given, the Kirchhoff coherent reflectivity into
    ``coherent_out`` (2, n) (as ``emscatter.solvers.kirchhoff_go.bistatic``)."""
    n = out.shape[-1]
    if (
        backend() != "numba"
        or not _worth_it(n)
        or not covered_go(dimension, sx, sy, eps, shadowing)
    ):
        return False
    dphi = _flat(dphi, n)
    if not _azimuth_ok(dphi) or not out.flags.c_contiguous:
        return False
    if coherent_out is not None and not coherent_out.flags.c_contiguous:
        return False
    from .go import go_sigma0 as kernel

    kernel(
        _flat(ti, n), _flat(ts, n), dphi, _scalar_eps(eps), slope_variance=sx,
        shadowing=shadowing, out=out, coherent_out=coherent_out, k=k, sigma=sigma, threads=threads,
    )  # fmt: skip
    return True


def po_log_series(rough, log_w, Q, K, *, rtol: float, max_terms: int, series_sum):
    """The physical-optics ``log T`` (as ``kirchhoff_po.series_sum``) or None when not
    covered; geometries the kernel leaves (peak at n ≥ 400, long walks) are computed by the
    reference ``series_sum(log_w, Q, K, ...)`` passed in."""
    if backend() != "numba" or not _worth_it(np.size(Q)):
        return None
    from ..spectra import ExponentialCorrelation, GaussianCorrelation
    from . import po

    kinds = {
        (GaussianCorrelation, 2): po.GAUSSIAN_2D,
        (GaussianCorrelation, 1): po.GAUSSIAN_1D,
        (ExponentialCorrelation, 2): po.EXPONENTIAL_2D,
        (ExponentialCorrelation, 1): po.EXPONENTIAL_1D,
    }
    kind = kinds.get((type(rough), rough.dimension))
    if kind is None:
        return None
    n = np.size(Q)
    q, kk = _flat(Q, n), _flat(K, n)
    out = po.log_series(q, kk, kind, rtol=rtol, max_terms=max_terms)
    rest = np.isnan(out)
    if rest.any():
        out[rest] = series_sum(log_w, q[rest], kk[rest], rtol=rtol, max_terms=max_terms)
    return out
