"""Compiled (numba) kernels of the integral-equation model: the series of
:mod:`emscatter.solvers.iem.series`
per geometry, exact backscatter end to end, and the spectral sums of the cross-pol integral.

Optional: used when numba imports and ``EMSCATTER_KERNELS`` (``auto`` default | ``numba`` |
``numpy``, the switch of :mod:`emscatter.kernels`) allows it, for Gaussian and exponential
correlations (the power-law table stays on the numpy path). The numpy code is the reference:
the same formulas and the same stopping rule (log-space summands; per-component geometric
tail where a component decreases, its whole-series bound otherwise; stop below ``rtol`` of the
sum or below the smallest double), checked against it in ``tests/test_iem_kernels.py``.
Walks go order by order (the tail test every fourth order), from the peak of the dominant
component (golden-section search on log n, skipped when the terms already fall from n = 2).

Exact backscatter (:func:`backscatter`) first tries a linear-space walk
(``kernels.lanes.lane_start``, ``walk_lanes``, ``walk_transition``): hh and vv in one walk from
n = 2 (they share the bases and the order weights), each order by multiplications
(``x_j √((kσ)²/n)``) and one ``Ŵₙ`` (one ``exp`` for the Gaussian, a square root for the
exponential), the same rigorous geometric tail bound at ``rtol`` (term ratios are
non-increasing from n = 3 for both closed forms), tested every fourth order (the transition
sums: every odd order). Blocks of ``kernels.lanes.LANES`` geometries walk in lockstep, so each
order's arithmetic is vectorized across geometries (a geometry that has met its stopping
rule is frozen: the same sums as walking it alone). It is used only where every term stays in
the range of doubles — checked per geometry from the start magnitudes, the components'
whole-series bounds and the final sums — and falls back to the log-space walk otherwise
(kσ ≳ 5, very lossy high-ε media at kσ ≳ 2.5): same σ⁰ to ~1e-11 at rtol = 1e-12
(``tests/test_iem_fast.py``), ≈ 15× faster. Large calls split into contiguous chunks on
threads (``threads``; :func:`emscatter.kernels._runtime.run_split`).

The bistatic series (:func:`series_rows`) likewise walks in linear space
(``kernels.linseries.series_kernel_lin``: from n = 1, one multiplication per component and
order, the same geometric tail bounds at ``rtol``, tested at orders 3, 7, 11, …) where it is
safe — components within e^300 of the largest, Poisson arguments ``(kσ)² x_j² ≤ 600``, at most
``kernels.series.FAST_MAX_ORDER`` orders, final sums in [1e-250, 1e300] — and takes the
log-space ``row_series`` for the other rows: same σ⁰ and precision ratio to ≤ ``rtol``
(``tests/test_iem_linseries.py``), ≈ 3.5× faster on the rows of an emissivity call.

Kernels compile on first use (tens of seconds on a loaded 2-core machine) and are cached on
disk by the package runtime (:mod:`emscatter.kernels._runtime`: ``EMSCATTER_NUMBA_CACHE_DIR``,
default ``~/.cache/emscatter/numba``); nothing here is imported by ``import emscatter``.
"""

from __future__ import annotations

import functools
import math
import time

import numpy as np

__all__ = ["enabled", "spectrum_code", "series_rows", "backscatter", "poisson_sums"]

GAUSSIAN, EXPONENTIAL = 0, 1


def enabled() -> bool:
    """Whether the compiled kernels are to be used now (``EMSCATTER_KERNELS``, read at each
    call: :func:`emscatter.kernels.backend`)."""
    from emscatter.kernels import backend

    return backend() == "numba"


def spectrum_code(rough) -> int | None:
    """Kernel code of the correlation (None: not covered, use numpy)."""
    from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation

    if isinstance(rough, GaussianCorrelation):
        return GAUSSIAN
    if isinstance(rough, ExponentialCorrelation):
        return EXPONENTIAL
    return None


@functools.cache
def _build():
    from emscatter.kernels._runtime import run_split
    from emscatter.solvers.iem.kernels import lanes, linseries, series

    return series.series_kernel, series.poisson_kernel, lanes.back_kernel, run_split, \
        linseries.series_kernel_lin  # fmt: skip


def series_rows(la, lx, ph, sx, d, log_ks2, spec, dim, K, pref, *, rtol, max_terms, fast=True,
                report=False):  # fmt: skip
    """Compiled :func:`emscatter.solvers.iem.series.iem_series` (same arguments, ``spec``,
    ``dim`` the spectrum code and dimension): ``(log σ⁰, log precision ratio, status)``.

    ``fast``: the linear-space walk (``kernels.linseries.series_kernel_lin``: the same terms and
    stopping rule by recurrences, ≈ 3.5× faster on an emissivity call's rows) where it is safe,
    the log-space ``kernels.series.row_series`` per row otherwise (and for every row with
    ``fast=False``); ``report=True`` appends a boolean array: the linear path was taken."""
    series_kernel, _, _, _, series_kernel_lin = _build()
    n = la.shape[0]
    out_s, out_e = np.empty(n), np.empty(n)
    args = (
        np.ascontiguousarray(la, float), np.ascontiguousarray(lx, float),
        np.ascontiguousarray(ph, complex), np.ascontiguousarray(sx, float),
        np.ascontiguousarray(d, complex), np.ascontiguousarray(np.broadcast_to(pref, (n,)), float),
        np.ascontiguousarray(np.broadcast_to(K, (n,)), float), float(log_ks2), int(spec),
        int(dim), math.log(rtol), int(max_terms), out_s, out_e,
    )  # fmt: skip
    out_fast = np.zeros(n, dtype=np.bool_)
    st = series_kernel_lin(*args, out_fast) if fast else series_kernel(*args)
    with np.errstate(invalid="ignore"):
        lp = np.where(np.isfinite(out_s), out_e - out_s, 0.0)
    if report:
        return out_s, lp, st, out_fast
    return out_s, lp, st


#: Target duration [s] of one compiled call of :func:`poisson_sums`: between calls Python runs
#: signal handlers (Ctrl-C, SIGALRM), which cannot interrupt compiled code.
CHUNK_SECONDS = 0.2


def poisson_sums(logq, K, spec, dim, *, rtol):
    """``log Σ_{n≥1} qⁿ/n! Ŵₙ(K)`` per element (``logq = log q``). Elements are independent:
    they are summed in contiguous chunks of about :data:`CHUNK_SECONDS` each (sized from the
    previous chunk's time; at kσ ~ 1e3 one element costs ~1e-3 s), so the call can be
    interrupted."""
    _, poisson_kernel, _, _, _ = _build()
    logq = np.ascontiguousarray(logq, float).ravel()
    Kf = np.ascontiguousarray(np.broadcast_to(K, logq.shape), float).ravel()
    out = np.empty(logq.size)
    start, size, lr = 0, 16, math.log(rtol)
    while start < logq.size:
        stop = min(logq.size, start + size)
        t = time.perf_counter()
        poisson_kernel(logq[start:stop], Kf[start:stop], int(spec), int(dim), lr, out[start:stop])
        per = (time.perf_counter() - t) / (stop - start)
        size = int(min(8 * (stop - start), max(1.0, CHUNK_SECONDS / max(per, 1e-9))))
        start = stop
    return out


def flat_n(v, n: int, dtype=float) -> np.ndarray:
    """``v`` as a C-contiguous, writeable array of length n and ``dtype`` (no copy when it
    already is one; a number is spread with ``np.full``). Writeable always: numba compiles a
    kernel once per argument type, and a read-only array (a ``np.broadcast_to`` view of a
    full-length array, e.g. the specular geometry of an emissivity's coherent part) is
    another type — a signature ``python -m emscatter.warm`` had not compiled (issue 22)."""
    a = np.asarray(v, dtype=dtype)
    if a.shape == (n,) and a.flags.c_contiguous and a.flags.writeable:
        return a
    if a.ndim == 0:
        return np.full(n, a[()], dtype=dtype)
    return np.array(np.broadcast_to(a, (n,)), dtype=dtype, order="C")  # a copy: writeable


NO_PSI = np.zeros(1)  # the kernel's ψ argument when the shadowing is not direction-correlated
NO_GEO = np.zeros(8)  # the kernel's ``geo`` argument when cosθ and K are given


def back_kernel():
    """The compiled exact-backscatter kernel itself (``kernels.lanes.back_kernel``; its
    arguments are those :func:`backscatter` passes)."""
    return _build()[2]


#: Fewest geometries per thread of the exact-backscatter kernel. One geometry costs
#: ~0.1–0.5 µs (kσ 0.1–2.5, the 1992 and default models), and handing a chunk to a worker
#: thread costs tens of µs on an idle machine and up to milliseconds on a loaded one (the
#: worker waits for a core: measured ×0.1–0.7 at 1000 angles with 2 threads under load 8 on
#: 2 cores): a call splits only from 2 × 2048 angles on, ≳ 0.4 ms of work per thread.
BACK_MIN_CHUNK = 2048


def backscatter(
    si,
    cs,
    eps,
    ks,
    K,
    pref,
    spec,
    dim,
    *,
    transition,
    rtol,
    max_terms,
    fast=True,
    report=False,
    shadow=(0, 0.0, None),
    threads=1,
    lower_q2=True,
    fade=False,
    fung92=False,
):
    """Exact-backscatter ``(σ⁰_hh, σ⁰_vv, log precision ratio, status)`` (the closed forms of
    :func:`emscatter.solvers.iem.terms.backscatter_terms`, end to end).

    ``fast``: the linear-space walk where it is safe (else, and with ``fast=False``, the
    log-space walk); ``report=True`` appends a boolean array: the fast path was taken.
    ``shadow = (code, s, ψ)``: the monostatic shadowing evaluated in the kernel (code 1
    direction-correlated with azimuths ψ (n,), 2 height-correlated, isotropic rms slope s;
    0: none, or already in ``pref``). ``threads``: at most this many threads over contiguous
    chunks of at least :data:`BACK_MIN_CHUNK` geometries (each geometry is independent: the
    result does not depend on the split). ``lower_q2``: the lower-medium terms with the
    height phase ``Re q₂`` (AIEM, default) or, False, the upper medium's
    (``complementary="aiem-upper"``, ``"aiem-faded"``). ``fade``: those terms times
    ``1 − γ_v``, one minus the vv transition factor (``"aiem-faded"``). ``fung92``: the 1992
    IEM (``complementary="fung92"``: one complementary component of base ``cosθ``, no height
    phase; ``lower_q2`` and ``fade`` are then ignored)."""
    _, _, back_kernel, run_split, _ = _build()
    n = si.size
    pec = isinstance(eps, str)
    si, cs, K, pref = flat_n(si, n), flat_n(cs, n), flat_n(K, n), flat_n(pref, n)
    psi = flat_n(shadow[2], n) if shadow[0] == 1 else NO_PSI
    out_hh, out_vv, out_e = np.empty(n), np.empty(n), np.ones(n)
    out_fast = np.empty(n, dtype=np.bool_)
    e = complex(1.0 if pec else eps)
    code, slope, log_rtol = int(shadow[0]), float(shadow[1]), math.log(rtol)
    flags = (bool(transition), log_rtol, int(max_terms), bool(fast), code, slope)
    tail = (bool(lower_q2), bool(fade), bool(fung92))
    if threads <= 1 or n < 2 * BACK_MIN_CHUNK:  # one chunk: a plain call (µs matter here)
        status = [back_kernel(si, cs, e, pec, float(ks), K, pref, int(spec), int(dim), *flags,
                              psi, out_hh, out_vv, out_e, out_fast, *tail, NO_GEO)]  # fmt: skip
    else:
        status = [0]

        def part(a: int, b: int) -> None:
            st = back_kernel(
                si[a:b], cs[a:b], e, pec, float(ks), K[a:b], pref[a:b], int(spec), int(dim),
                *flags, psi[a:b] if code == 1 else psi, out_hh[a:b], out_vv[a:b], out_e[a:b],
                out_fast[a:b], *tail, NO_GEO,
            )  # fmt: skip
            status.append(st)

        run_split(part, n, threads, BACK_MIN_CHUNK)
    log_e = np.log(out_e)  # out_e ≥ 1
    if report:
        return out_hh, out_vv, log_e, max(status), out_fast
    return out_hh, out_vv, log_e, max(status)
