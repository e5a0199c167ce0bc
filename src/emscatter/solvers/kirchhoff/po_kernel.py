"""Compiled physical-optics series ``log T``, ``T = e^{−Q} Σ_{n≥1} Q^{n−1}/n! · w_n(K)``.

The numpy reference is :func:`emscatter.solvers.kirchhoff.po.series_sum` (the series and its
sources are documented there: Ulaby, Moore & Fung 1982 vol. II §12-4; Tsang, Kong & Ding 2001
vol. III ch. 2). Here one geometry at a time, term by term, in compiled code:

* the terms are the reference's own expression, ``(n−1) log Q − lgamma(n+1) − Q + log w_n``,
  with ``lgamma(n+1)`` and ``log n`` read from tables built with scipy/numpy (the same values
  the reference computes), for the closed-form n-fold spectra of the Gaussian and exponential
  correlations (1-D and 2-D);
* the peak term is found by integer ternary search (the log-terms are concave in n), then the
  sum walks outward and stops on each side with the reference's geometric tail bound
  (remaining terms ≤ ``rtol`` × sum);
* geometries whose peak is at ``n ≥ 400`` (the reference sums those as a continuum integral)
  or whose walk would leave the tables are returned as NaN, and the caller computes them with
  the reference.
Agreement with the reference: the kernel stops at the tail bound ``rtol × RTOL_MARGIN``
(1e-4): the reference checks its bound only after blocks of ≥ 16 terms and so sums past it
(far past at small ``Q``: there the two agree to ~1e-12 even at the default ``rtol = 1e-8``;
at large ``Q`` within ``rtol``); at ``rtol = 1e-13`` they agree to 1e-12 everywhere
(tests/test_kernels.py).
"""

from __future__ import annotations

import math

import numpy as np

from emscatter.kernels._runtime import jit, run_fused

GAUSSIAN_2D, GAUSSIAN_1D, EXPONENTIAL_2D, EXPONENTIAL_1D = 0, 1, 2, 3
N_PEAK_MAX = 400  # the reference's continuum threshold (kirchhoff_po._N_CONTINUUM)
N_TABLE = 1 << 14  # terms available to the walk
#: The kernel stops at ``rtol × RTOL_MARGIN``: the reference walks in blocks of ≥ 16 terms, so
#: it over-sums far past its own bound; this keeps the two within ~1e-12 at the default rtol.
RTOL_MARGIN = 1e-4


def _tables():
    from scipy import special

    n = np.arange(N_TABLE + 2, dtype=float)
    lgam = special.gammaln(n + 1.0)  # lgamma(n + 1), as the reference
    with np.errstate(divide="ignore"):
        logn = np.log(n)
    return lgam, logn


_LGAM, _LOGN = _tables()
_C_G2 = -math.log(4 * math.pi)  # log w_n constants, as kirchhoff_po.log_nfold
_C_G1 = -math.log(2 * math.sqrt(math.pi))
_C_E2 = -math.log(2 * math.pi)
_C_E1 = -math.log(math.pi)


@jit
def _log_term(n, logq, q, kk, kind, lgam, logn):
    """``(n−1) log Q − lgamma(n+1) − Q + log w_n(K)`` for integer ``n ≥ 1``."""
    if kind == GAUSSIAN_2D:
        lw = _C_G2 - logn[n] - kk * kk / (4 * n)
    elif kind == GAUSSIAN_1D:
        lw = _C_G1 - 0.5 * logn[n] - kk * kk / (4 * n)
    elif kind == EXPONENTIAL_2D:
        lw = _C_E2 - 2 * logn[n] - 1.5 * math.log1p((kk / n) ** 2)
    else:
        lw = _C_E1 - logn[n] - math.log1p((kk / n) ** 2)
    return (n - 1) * logq - lgam[n] - q + lw


@jit
def _tail_ok(last, prev, log_rtol, acc):
    lr = last - prev
    if not lr < 0:
        return False
    return last + lr - math.log(-math.expm1(lr)) <= log_rtol + math.log(acc)


@jit
def _series_kernel(qv, kv, kind, log_rtol, max_terms, lgam, logn, out):
    top = lgam.size - 2
    for j in range(qv.size):
        q = qv[j]
        kk = kv[j]
        logq = math.log(max(q, 1e-300))
        # peak: ternary search of the concave log-term on [1, hi]
        lo, hi = 1, int(min(2.0 * q + 2.0 * kk + 20.0, top))
        while hi - lo > 2:
            m1 = lo + (hi - lo) // 3
            m2 = hi - (hi - lo) // 3
            if _log_term(m1, logq, q, kk, kind, lgam, logn) < _log_term(
                m2, logq, q, kk, kind, lgam, logn
            ):
                lo = m1 + 1
            else:
                hi = m2 - 1
        n0 = lo
        l0 = _log_term(lo, logq, q, kk, kind, lgam, logn)
        for m in range(lo + 1, hi + 1):
            v = _log_term(m, logq, q, kk, kind, lgam, logn)
            if v > l0:
                n0, l0 = m, v
        if n0 >= N_PEAK_MAX:
            out[j] = math.nan
            continue
        acc = 1.0
        count = 1
        ok = True
        prev = 0.0
        n = n0 + 1  # upward
        while True:
            if n > top or count > max_terms:
                ok = False
                break
            r = _log_term(n, logq, q, kk, kind, lgam, logn) - l0
            acc += math.exp(r)
            count += 1
            if _tail_ok(r, prev, log_rtol, acc):
                break
            prev = r
            n += 1
        prev = 0.0
        n = n0 - 1  # downward
        while ok and n >= 1:
            r = _log_term(n, logq, q, kk, kind, lgam, logn) - l0
            acc += math.exp(r)
            count += 1
            if n > 8 and _tail_ok(r, prev, log_rtol, acc):
                break
            prev = r
            n -= 1
        out[j] = l0 + math.log(acc) if ok else math.nan


def log_series(q: np.ndarray, k: np.ndarray, kind: int, *, rtol: float, max_terms: int,
               threads: int | None = None) -> np.ndarray:  # fmt: skip
    """``log T`` per geometry (NaN where the reference must compute it); ``q`` = ``Q``,
    ``k`` = the scaled wavenumber ``K`` (see kirchhoff_po.log_nfold), flat float64."""
    out = np.empty(q.size)
    consts = (int(kind), math.log(rtol * RTOL_MARGIN), int(max_terms), _LGAM, _LOGN)
    run_fused(_series_kernel, (q, k), consts, (out,), threads)
    return out
