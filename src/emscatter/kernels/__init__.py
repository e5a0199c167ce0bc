"""Compiled kernels for the hottest loops (first-order SPM σ⁰, geometric-optics σ⁰ with
Smith shadowing, the physical-optics series), selected automatically; the numpy code in
:mod:`emscatter.solvers` stays the reference and can be forced.

Selection (``EMSCATTER_KERNELS``, read at each call):

* ``auto`` (default) — the compiled kernel where one covers the case and numba imports, for
  calls of ≥ 4096 geometries or once the kernels are loaded in the process (a small one-off
  call is not worth importing numba for);
* ``numpy`` — always the numpy reference path;
* ``numba`` — the compiled kernel wherever one covers the case, any size; a missing numba is an
  error instead of a fallback.

Cases covered (others run the numpy path, identical results): 2-D surfaces, one permittivity
(or ``"pec"``) per call, ``|φs − φi| ≤ 1e6`` rad; SPM1 with isotropic Gaussian or exponential
correlation; GO with isotropic slopes, shadowing off / smith / separable / correlated; the PO
series for Gaussian and exponential correlations, 1-D and 2-D (peaks at n ≥ 400 stay with the
reference's continuum integral).

Agreement with numpy (tests/test_kernels.py): ``|Δσ⁰| ≤ 1e-12 |σ⁰| + 1e-14 max σ⁰_pq`` per
polarization — relative 1e-12 except where the numpy formula itself loses digits to
cancellation (``sin²Δφ = 1 − cos²Δφ`` near the plane of incidence, ``cos θ = √(1 − sin²θ)``
at grazing, zeros of ``F_pq``): there the values differ by a few units of the last place of
the polarization's largest value, as two numpy builds with different ``libm`` would.

Threads: a compiled call that is not told how many threads to use takes the CPU count (at
most 8), capped by ``EMSCATTER_THREADS`` (read at each call) and by :func:`thread_cap` (this
thread only: what a farm's worker sets for its tasks, :mod:`emscatter.brdf.farm`) —
:func:`default_threads`.

Nothing here imports numba or compiles at ``import emscatter``: kernels compile on first use
and are cached on disk (see :mod:`._runtime`). This package is light to import.
"""

from __future__ import annotations

import contextlib
import functools
import importlib.util
import os
import threading

__all__ = [
    "backend", "selection", "BACKENDS", "numba_available", "default_threads", "thread_cap",
]  # fmt: skip

BACKENDS = ("auto", "numba", "numpy")
#: spectrum codes of the SPM1 kernel (here, so that choosing a path imports nothing heavy)
SPM_GAUSSIAN, SPM_EXPONENTIAL = 0, 1


@functools.cache
def numba_available() -> bool:
    """Whether numba can be imported (checked once, without importing it)."""
    return importlib.util.find_spec("numba") is not None


def selection() -> str:
    """``EMSCATTER_KERNELS`` checked: ``"auto"``, ``"numba"`` or ``"numpy"``."""
    choice = os.environ.get("EMSCATTER_KERNELS", "auto").strip().lower() or "auto"
    if choice not in BACKENDS:
        raise ValueError(f"EMSCATTER_KERNELS must be one of {', '.join(BACKENDS)}, got {choice!r}")
    return choice


def backend() -> str:
    """``"numba"`` or ``"numpy"``: the path the solvers take now (``EMSCATTER_KERNELS``)."""
    choice = selection()
    if choice == "numpy":
        return "numpy"
    if numba_available():
        return "numba"
    if choice == "numba":
        raise ImportError(
            "EMSCATTER_KERNELS=numba but numba is not installed; "
            "pip install 'emscatter[fast]' or set EMSCATTER_KERNELS=auto"
        )
    return "numpy"


_CPUS = os.cpu_count() or 1
_LOCAL = threading.local()  # .cap: this thread's cap (thread_cap)


def default_threads() -> int:
    """Threads for a compiled call that does not say: ``min(CPU count, 8)``, at most
    ``EMSCATTER_THREADS`` (a positive integer) and this thread's :func:`thread_cap`."""
    n = min(_CPUS, 8)
    env = os.environ.get("EMSCATTER_THREADS", "").strip()
    if env:
        try:
            cap = int(env)
        except ValueError:
            cap = 0
        if cap < 1:
            raise ValueError(f"EMSCATTER_THREADS must be a positive integer, got {env!r}")
        n = min(n, cap)
    cap = getattr(_LOCAL, "cap", None)
    return n if cap is None else min(n, cap)


@contextlib.contextmanager
def thread_cap(threads: int):
    """Within the block, :func:`default_threads` in this thread is at most ``threads``."""
    if isinstance(threads, bool) or not isinstance(threads, int) or threads < 1:
        raise ValueError(f"threads must be a positive integer, got {threads!r}")
    old = getattr(_LOCAL, "cap", None)
    _LOCAL.cap = threads if old is None else min(old, threads)
    try:
        yield
    finally:
        _LOCAL.cap = old
