"""Independent tasks serially, on any :class:`concurrent.futures.Executor` or on a
dask.distributed cluster: the plumbing shared by the package's farms (the Monte Carlo of
:func:`emscatter.solvers.mom3d.bistatic`; the same rules as :mod:`emscatter.brdf.farm`).

* :func:`open_executor` turns ``client`` (None, ``"local"``, ``"tcp://host:port"``, a dask
  ``Client`` or an ``Executor``) into an executor and a ``close`` for what it started; a bad
  one is refused before any work, with the accepted forms named.
* :func:`limited_threads` caps the compiled threads of one task (numba's, scipy.fft's
  workers and, where ``threadpoolctl`` is installed, BLAS's), so ``n_workers × threads``
  stays within the cores; a ``"local"`` cluster also starts its workers with
  ``OMP/OPENBLAS/MKL/NUMBA_NUM_THREADS = threads``.
* :func:`run_ordered` submits the tasks, advances a progress bar as they finish, returns the
  results in submission order, cancels the rest on the first failure (re-raised as a
  ``RuntimeError`` naming the task) and passes on the warnings each task recorded
  (:func:`call_recording`), once each, prefixed with the task's name — Python's warnings
  state is per process, so a worker's would otherwise be lost in its log (and the recording
  is not thread-safe: on a thread pool some may be lost; use processes or dask).

A task that is a pure function of its arguments gives the same result, bit for bit, serially,
on a process pool or on a cluster.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import numbers
import os
import warnings

__all__ = [
    "check_threads",
    "check_n_workers",
    "limited_threads",
    "open_executor",
    "dask_client",
    "dashboard_link",
    "call_recording",
    "run_ordered",
]

_ADDRESS = ("tcp://", "tls://", "inproc://", "ucx://")
_FORMS = (
    "None (serial), 'local', a scheduler address 'tcp://host:port', a dask.distributed "
    "Client or a concurrent.futures Executor"
)


def check_threads(threads) -> int | None:
    """``threads`` as a positive int, or None (no cap)."""
    if threads is None:
        return None
    if isinstance(threads, bool) or not isinstance(threads, numbers.Integral) or threads < 1:
        raise ValueError(f"threads must be a positive integer or None, got {threads!r}")
    return int(threads)


def check_n_workers(n_workers) -> int | None:
    """``n_workers`` as a positive int, or None (the default of ``client="local"``)."""
    if n_workers is None:
        return None
    if isinstance(n_workers, bool) or not isinstance(n_workers, numbers.Integral) or n_workers < 1:
        raise ValueError(f"n_workers must be a positive integer or None, got {n_workers!r}")
    return int(n_workers)


def check_client(client) -> None:
    """Refuse a ``client`` that :func:`open_executor` cannot use, without starting anything."""
    if client is None or client == "local" or isinstance(client, cf.Executor):
        return
    if isinstance(client, str) and client.startswith(_ADDRESS):
        return
    if not isinstance(client, str) and callable(getattr(client, "get_executor", None)):
        return
    raise ValueError(f"client must be {_FORMS}, got {client!r:.80}")


@contextlib.contextmanager
def limited_threads(threads: int | None, wheel_blas: bool = False):
    """Within the block, at most ``threads`` compiled threads: numba's (this thread's),
    scipy.fft's default ``workers`` and BLAS's (through ``threadpoolctl`` when installed;
    otherwise, with ``wheel_blas``, the OpenBLAS that numpy's and scipy's wheels ship,
    :func:`_openblas_controls`). ``None``: no cap. BLAS's count is process-wide: the cap
    holds for the whole process during the block."""
    if threads is None:
        yield
        return
    with contextlib.ExitStack() as stack:
        try:
            import numba

            before = numba.get_num_threads()
            numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
            stack.callback(numba.set_num_threads, before)
        except ImportError:
            pass
        from scipy import fft as sfft

        stack.enter_context(sfft.set_workers(threads))
        try:
            from threadpoolctl import threadpool_limits

            stack.enter_context(threadpool_limits(limits=threads))
        except ImportError:
            for get, put in _openblas_controls() if wheel_blas else ():
                before = int(get())
                put(min(threads, before))
                stack.callback(put, before)
        yield


_OPENBLAS_CALLS = (
    ("scipy_openblas_get_num_threads64_", "scipy_openblas_set_num_threads64_"),
    ("scipy_openblas_get_num_threads", "scipy_openblas_set_num_threads"),
    ("openblas_get_num_threads64_", "openblas_set_num_threads64_"),
    ("openblas_get_num_threads", "openblas_set_num_threads"),
)
_OPENBLAS: list | None = None


def _openblas_controls() -> list:
    """``[(get_num_threads, set_num_threads), ...]`` of the OpenBLAS builds numpy and scipy
    ship in their wheels (``numpy.libs``, ``scipy.libs``), found without ``threadpoolctl``:
    the serial run caps BLAS as a ``"local"`` worker's ``OPENBLAS_NUM_THREADS`` does, since a
    threaded BLAS reduction may differ from the single-threaded one in the last bit. Empty
    where none is found (a system BLAS: install ``threadpoolctl``)."""
    global _OPENBLAS
    if _OPENBLAS is not None:
        return _OPENBLAS
    import ctypes
    import glob

    found = []
    for mod in ("numpy", "scipy"):
        try:
            top = os.path.dirname(__import__(mod).__file__)
        except (ImportError, TypeError):
            continue
        for path in sorted(glob.glob(os.path.join(top + ".libs", "*openblas*.so*"))):
            try:
                lib = ctypes.CDLL(path)  # already loaded by the module: the same handle
            except OSError:
                continue
            for get, put in _OPENBLAS_CALLS:
                if hasattr(lib, get) and hasattr(lib, put):
                    found.append((getattr(lib, get), getattr(lib, put)))
                    break
    _OPENBLAS = found
    return found


#: glibc malloc settings of a ``"local"`` cluster's workers (set before they start: dask's
#: own ``MALLOC_TRIM_THRESHOLD_=65536`` freezes glibc's mmap threshold at 128 kB, so every
#: numpy temporary over it is a fresh zeroed mapping, page-faulted in on each use: a PO
#: 90×180 BRDF table took 610–740 ms of CPU in such a worker against 390–415 ms in a plain
#: process). These are the limits glibc's dynamic threshold reaches by itself (32 MiB and
#: twice that); a worker keeps up to 64 MiB of freed heap instead of returning it at once.
WORKER_MALLOC = {"MALLOC_MMAP_THRESHOLD_": 1 << 25, "MALLOC_TRIM_THRESHOLD_": 1 << 26}


def _thread_env(threads: int | None) -> dict:
    t = str(threads or 1)
    return {name: t for name in ("NUMBA_NUM_THREADS", "EMSCATTER_THREADS", "OMP_NUM_THREADS",
                                 "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")}  # fmt: skip


def open_executor(client, n_workers: int | None = None, threads: int | None = 1,
                  memory_limit=None, timeout: float | None = None):  # fmt: skip
    """``(executor or None, close)`` for ``client``; ``close()`` shuts down what was started
    here (a ``"local"`` LocalCluster of ``n_workers`` single-threaded processes, default the
    CPU count ÷ ``threads``, its dashboard on a free port and its workers' statistical
    profiler off; a Client to a scheduler address) and leaves a caller's own Client or
    Executor open. ``memory_limit``: the LocalCluster's per-worker limit (dask's default: the
    machine's memory ÷ workers); ``timeout`` [s]: how long to try to reach a scheduler
    address (dask's default, 30 s, when None) before an ``OSError``."""
    check_client(client)
    if client is None:
        return None, lambda: None
    if isinstance(client, cf.Executor):
        return client, lambda: None
    if isinstance(client, str):
        try:
            from dask.distributed import Client, LocalCluster
        except ImportError:
            raise ValueError(
                f"client={client!r} needs dask.distributed (pip install 'emscatter[distributed]'); "
                "or pass a concurrent.futures Executor, or None (serial)"
            ) from None
        if client == "local":
            n = n_workers or max(1, (os.cpu_count() or 1) // (threads or 1))
            extra = {} if memory_limit is None else {"memory_limit": memory_limit}
            import dask

            # the workers' statistical profiler samples every thread each 10 ms: CPU a farm of
            # small tasks on few cores does not have (the dashboard's task stream stays); and
            # glibc's heap as a plain process has it (:data:`WORKER_MALLOC`)
            with dask.config.set({"distributed.worker.profile.enabled": False, **{
                f"distributed.nanny.pre-spawn-environ.{k}": v for k, v in WORKER_MALLOC.items()
            }}):  # fmt: skip
                cluster = LocalCluster(
                    n_workers=n,
                    threads_per_worker=1,
                    processes=True,
                    dashboard_address=":0",
                    env=_thread_env(threads),
                    **extra,
                )
            dc = Client(cluster)

            def close():
                dc.close()
                cluster.close()

            return dc.get_executor(), close
        dc = Client(client) if timeout is None else Client(client, timeout=timeout)
        return dc.get_executor(), dc.close
    return client.get_executor(), lambda: None  # a dask.distributed Client


def dask_client(executor):
    """The dask.distributed ``Client`` behind ``executor`` (its ``get_executor()``), or None."""
    if executor is None:
        return None
    if callable(getattr(executor, "scheduler_info", None)):
        return executor
    return getattr(executor, "_client", None)


def dashboard_link(executor) -> str | None:
    """The dask dashboard's address of ``executor``'s cluster (None: not dask, or none)."""
    dc = dask_client(executor)
    try:
        return None if dc is None else dc.dashboard_link
    except Exception:  # noqa: BLE001 - a cluster without a dashboard
        return None


def call_recording(fn, *args, threads: int | None = None, wheel_blas: bool = False, **kwargs):
    """``(fn(*args, **kwargs), [(category, message), ...])`` with ``threads`` capped
    (:func:`limited_threads`) and every warning recorded instead of shown: the task function
    of :func:`run_ordered` in a worker (module-level, so it pickles)."""
    with limited_threads(threads, wheel_blas), warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = fn(*args, **kwargs)
    return out, [(w.category, str(w.message)) for w in caught]


def run_ordered(executor, fn, arg_list, names, *, threads=None, bar=None, on_result=None,
                stacklevel: int = 3, cap_serial: bool = False):  # fmt: skip
    """``[fn(*args) for args in arg_list]`` on ``executor`` (None: serially here, warnings
    shown as they come, no thread cap unless ``cap_serial``), in the order of ``arg_list``.

    ``cap_serial``: the serial tasks are capped at ``threads`` like a worker's, BLAS included
    (also without ``threadpoolctl``: the wheels' OpenBLAS, ``wheel_blas``), in the workers
    too — a threaded BLAS or numba reduction may differ from a single-threaded one in the
    last bit, so equal counts are what make the serial and the farmed results identical.

    ``names[j]`` labels task ``j`` in errors and in its warnings; ``bar`` (a tqdm-like object
    or None) is advanced once per finished task; ``on_result(j, result)`` is called as each
    finishes (in completion order). A failing task cancels the others and raises
    ``RuntimeError("<name> failed: …")`` chained to the worker's exception."""
    arg_list = list(arg_list)
    results: list = [None] * len(arg_list)

    def done(j, res):
        results[j] = res
        if on_result is not None:
            on_result(j, res)
        if bar is not None:
            bar.update(1)

    if executor is None:
        cap = limited_threads(threads, True) if cap_serial else contextlib.nullcontext()
        with cap:
            for j, args in enumerate(arg_list):
                done(j, fn(*args))
        return results
    futures = {
        executor.submit(call_recording, fn, *args, threads=threads, wheel_blas=cap_serial): j
        for j, args in enumerate(arg_list)
    }
    caught: list = [[] for _ in arg_list]
    try:
        for fut in cf.as_completed(futures):
            j = futures[fut]
            try:
                res, caught[j] = fut.result()
            except Exception as exc:
                raise RuntimeError(f"{names[j]} failed: {exc}") from exc
            done(j, res)
    except BaseException:
        for fut in futures:
            fut.cancel()
        raise
    seen = set()
    for name, items in zip(names, caught, strict=True):
        for category, message in items:
            if (category, message) not in seen:
                seen.add((category, message))
                warnings.warn(f"{name}: {message}", category, stacklevel=stacklevel)
    return results
