"""numba import, its on-disk cache location, and the thread pool the kernels run on.

Imported only when a kernel is first used (never by ``import emscatter``). Compiled functions
are cached on disk (``cache=True``) in ``EMSCATTER_NUMBA_CACHE_DIR`` (default
``~/.cache/emscatter/numba``) unless the user set ``NUMBA_CACHE_DIR`` themselves; the
override is applied only while *our* functions are decorated, so other numba code keeps its
own cache location.

Threads: the kernels are ``nogil`` and run on contiguous chunks in a
:class:`~concurrent.futures.ThreadPoolExecutor` (thread- and fork-safe, unlike numba's
``parallel=True`` workqueue/OpenMP layers).
"""

from __future__ import annotations

import contextlib
import os
from concurrent.futures import ThreadPoolExecutor, wait
from pathlib import Path

import numba
import numpy as np

from . import default_threads

__all__ = ["jit", "inline", "run_chunked", "run_fused", "run_split", "cache_dir", "NUMBA_VERSION"]

NUMBA_VERSION = numba.__version__
FASTMATH = {"contract"}  # FMA contraction only (see jit)


def _prefer_512_bit_vectors() -> None:
    """LLVM tunes recent Intel cores to 256-bit vectors ("prefer-256-bit"); the kernels are
    compute-bound and run ~1.5× faster with AVX-512. Applied only when the user has not set
    ``NUMBA_CPU_FEATURES`` and the CPU has AVX-512 (it changes numba's target for the whole
    process, and only takes effect if nothing was compiled before)."""
    if os.environ.get("NUMBA_CPU_FEATURES") or numba.config.CPU_FEATURES:
        return
    import llvmlite.binding as llb

    feats = llb.get_host_cpu_features()
    if feats.get("avx512f") and feats.get("prefer-256-bit", True):
        numba.config.CPU_FEATURES = feats.flatten() + ",-prefer-256-bit"


_prefer_512_bit_vectors()
_MIN_CHUNK = 1 << 14
_CPUS = os.cpu_count() or 1


def cache_dir() -> Path:
    """Where compiled kernels are cached (created on demand)."""
    if os.environ.get("NUMBA_CACHE_DIR"):
        return Path(os.environ["NUMBA_CACHE_DIR"])
    base = os.environ.get("EMSCATTER_NUMBA_CACHE_DIR")
    if base:
        return Path(base)
    return Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "emscatter" / "numba"


@contextlib.contextmanager
def _cache_location():
    old = numba.config.CACHE_DIR
    path = cache_dir()
    try:
        path.mkdir(parents=True, exist_ok=True)
        writable = os.access(path, os.W_OK)
    except OSError:
        writable = False
    if writable:
        numba.config.CACHE_DIR = str(path)
    try:
        yield
    finally:
        numba.config.CACHE_DIR = old


def jit(*args, **kwargs):
    """``numba.njit(nogil=True, cache=True, fastmath={"contract"}, error_model="numpy")`` with
    our cache location (decoration is lazy: nothing is compiled until the first call).

    ``contract`` is the only fast-math flag: it lets LLVM fuse ``a*b + c`` into one FMA (one
    rounding instead of two — never less accurate; ×2–3 on these polynomial-heavy loops); no
    reassociation, no ``nnan``/``ninf``, so results stay within the numpy agreement bound."""
    opts = {"nogil": True, "cache": True, "fastmath": FASTMATH, "error_model": "numpy"}
    opts.update(kwargs)

    def deco(fn):
        with _cache_location():
            return numba.njit(**opts)(fn)

    if args and callable(args[0]):
        return deco(args[0])
    return deco


def inline(fn):
    """A helper inlined into its callers (no cache entry of its own)."""
    return numba.njit(inline="always", fastmath=FASTMATH, error_model="numpy")(fn)


def run_chunked(part, n: int, threads: int | None = None) -> None:
    """Call ``part(start, stop)`` over ``[0, n)`` in contiguous chunks, one per thread
    (``threads``: default :func:`emscatter.kernels.default_threads`, the CPU count, at most 8,
    or the cap set for this thread); ``part`` calls a ``nogil`` kernel.
    The chunks run on the persistent pool of :func:`run_split` with the calling thread taking
    the last one: a 1e6-geometry call paid ~5 ms of thread starts per worker (wall, on a
    loaded 2-core machine) when each call made its own pool (issue 22)."""
    if threads is None:
        threads = default_threads()
    run_split(part, n, threads, _MIN_CHUNK)


_POOL: ThreadPoolExecutor | None = None  # persistent workers of run_split (created on demand)


def _forget_pool() -> None:  # a forked child has the pool object but not its threads
    global _POOL
    _POOL = None


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_forget_pool)


def _pool() -> ThreadPoolExecutor:
    global _POOL
    if _POOL is None:
        _POOL = ThreadPoolExecutor(max_workers=min(_CPUS, 8), thread_name_prefix="emscatter")
    return _POOL


def run_split(part, n: int, threads: int, min_chunk: int) -> None:
    """``part(start, stop)`` over ``[0, n)`` in at most ``threads`` contiguous chunks of at
    least ``min_chunk`` items, for kernels whose calls are short (≈ 0.1–1 ms): the workers are
    a persistent pool (no thread start per call) and the calling thread runs the last chunk
    itself. One chunk: a plain call. ``part`` must call a ``nogil`` kernel on disjoint output
    slices; an exception of a chunk is re-raised once every chunk has finished."""
    parts = int(max(1, min(threads, n // max(min_chunk, 1))))
    if parts == 1:
        part(0, n)
        return
    edges = np.linspace(0, n, parts + 1).astype(np.int64)
    pool = _pool()
    futs = [pool.submit(part, int(edges[i]), int(edges[i + 1])) for i in range(parts - 1)]
    try:
        part(int(edges[-2]), int(edges[-1]))
    except BaseException:
        wait(futs)  # the workers write into the caller's arrays: let them finish first
        raise
    for f in futs:
        f.result()


def run_fused(kernel, inputs: tuple, consts: tuple, outputs: tuple, threads: int | None = None):
    """``kernel(*inputs[a:b], *consts, *outputs[a:b])`` over contiguous chunks on threads.

    ``inputs`` and ``outputs``: 1-D C-contiguous arrays of one length n (each output a
    separate array, so the vectorized loop's overlap check passes)."""
    n = inputs[0].size
    if n < 2 * _MIN_CHUNK or threads == 1:  # one chunk: no pool, no closure (µs matter here)
        kernel(*inputs, *consts, *outputs)
        return

    def part(a: int, b: int) -> None:
        kernel(*(x[a:b] for x in inputs), *consts, *(y[a:b] for y in outputs))

    run_chunked(part, n, threads)
