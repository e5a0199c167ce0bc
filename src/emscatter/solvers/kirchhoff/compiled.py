"""The compiled paths of the Kirchhoff solvers — GO σ⁰ with shadowing (:mod:`.go_kernel`) and
the physical-optics series (:mod:`.po_kernel`) — behind the shared gate
(:mod:`emscatter.kernels.gate`): each returns its answer, or ``False``/``None`` (nothing touched)
so that the solver runs its numpy reference."""

from __future__ import annotations

import numpy as np

from emscatter.kernels import backend
from emscatter.kernels.gate import azimuth_ok, flat, scalar_eps, worth_it

__all__ = ["go_sigma0", "po_log_series", "covered_go"]


def covered_go(dimension: int, sx: float, sy: float, eps, shadowing) -> bool:
    """Whether :func:`go_sigma0` has a kernel for this case."""
    return (
        dimension == 2
        and sx == sy
        and shadowing in (None, "smith", "separable", "correlated", "direction-correlated")
        and scalar_eps(eps) is not None
    )


def go_sigma0(
    ti, ts, dphi, eps, *, dimension: int, sx: float, sy: float, shadowing,
    out: np.ndarray, coherent_out: np.ndarray | None = None, k: float = 1.0, sigma: float = 0.0,
    threads: int | None = None, shape: tuple[int, ...] | None = None,
) -> bool:  # fmt: skip
    """GO σ⁰ into ``out`` (2, 2, n) and, when given, the Kirchhoff coherent reflectivity into
    ``coherent_out`` (2, n) (as ``emscatter.solvers.kirchhoff.go.bistatic``).

    The angles [rad] are flat arrays of length n, or (``shape`` given) unbroadcast arrays that
    broadcast to ``shape`` (C order, n = prod(shape)): a grid of directions then takes the
    kernel that computes each direction's trigonometry and shadowing once
    (:func:`emscatter.solvers.kirchhoff.go_kernel.go_sigma0_grid`)."""
    n = out.shape[-1]
    if backend() != "numba" or not worth_it(n) or not covered_go(dimension, sx, sy, eps, shadowing):
        return False
    if not out.flags.c_contiguous or (
        coherent_out is not None and not coherent_out.flags.c_contiguous
    ):
        return False
    arrays = [np.asarray(a, dtype=np.float64) for a in (ti, ts, dphi)]
    if not azimuth_ok(arrays[2]):
        return False
    e = scalar_eps(eps)
    if shape is not None and len(shape) <= 3 and sum(a.size for a in arrays) < n:
        from emscatter.solvers.kirchhoff.go_kernel import coherent_reflectivity, go_sigma0_grid

        go_sigma0_grid(
            *arrays, shape, e, slope_variance=sx, shadowing=shadowing, out=out, threads=threads
        )
        if coherent_out is not None:  # a function of θi alone: once per θi, then spread
            small = coherent_reflectivity(arrays[0].reshape(-1), e, k=k, sigma=sigma)
            lead = (1,) * (len(shape) - arrays[0].ndim)
            coherent_out.reshape(2, *shape)[...] = small.reshape(2, *lead, *arrays[0].shape)
        return True
    from emscatter.solvers.kirchhoff.go_kernel import go_sigma0 as kernel

    ti, ts, dphi = (flat(a, n, shape) for a in arrays)
    kernel(
        ti, ts, dphi, e, slope_variance=sx, shadowing=shadowing, out=out,
        coherent_out=coherent_out, k=k, sigma=sigma, threads=threads,
    )  # fmt: skip
    return True


def po_log_series(rough, log_w, Q, K, *, rtol: float, max_terms: int, series_sum):
    """The physical-optics ``log T`` (as ``kirchhoff_po.series_sum``) or None when not
    covered; geometries the kernel leaves (peak at n ≥ 400, long walks) are computed by the
    reference ``series_sum(log_w, Q, K, ...)`` passed in."""
    if backend() != "numba" or not worth_it(np.size(Q)):
        return None
    from emscatter.solvers.kirchhoff import po_kernel as po
    from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation

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
    q, kk = flat(Q, n), flat(K, n)
    out = po.log_series(q, kk, kind, rtol=rtol, max_terms=max_terms)
    rest = np.isnan(out)
    if rest.any():
        out[rest] = series_sum(log_w, q[rest], kk[rest], rtol=rtol, max_terms=max_terms)
    return out
