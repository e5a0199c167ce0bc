"""The Monte Carlo realizations of :func:`~emscatter.solvers.mom3d.bistatic`, serially, on a
:class:`concurrent.futures.Executor` or on a dask.distributed cluster (:mod:`emscatter.parallel`).

Realization ``j`` is a pure function of its own seed, ``SeedSequence(seed).spawn(n)[j]``
(fixed by its index, drawn in the caller so that ``seed=None`` too gives one set of
surfaces), of the surface statistics and of the solver options: the surface is generated in
the worker, solved there, and only its far-field amplitudes (``(2, 2, D)`` plus the hemisphere
quadrature's, a few hundred kB) come back, never the matrix or the currents. The Monte Carlo
sums are taken in the caller in index order, so σ⁰, the coherent part and every ``info``
entry are bit-identical to the serial run whatever the executor (tested).

Memory: each worker holds one realization's matrix at a time — the dense ``(2N)²`` (PEC) or
``(4N)²`` (dielectric) matrix of :func:`~.model.matrix_bytes`, or the SMCG strong part of
:func:`~.model.smcg_bytes` — plus ≈ 30 % for GMRES's Krylov basis and temporaries;
``bistatic`` reports it as ``info["bytes_per_worker"]`` and ``client="local"`` starts no
more workers than the free memory holds. Threads: ``threads`` per worker (default 1) for
BLAS (dense GMRES), scipy.fft (SMCG, the far-field sums) and numba; mom3d uses no compiled
kernel of :mod:`emscatter.kernels`, so no compiled runtime is loaded in the workers.
"""

from __future__ import annotations

import math
import os

import numpy as np

from emscatter.parallel import open_executor, run_ordered

__all__ = ["run_realizations", "local_workers", "stack_results"]

#: Working memory of one realization over its matrix (GMRES basis, temporaries).
MEMORY_OVERHEAD = 1.3


def local_workers(bytes_per_worker: int, threads: int | None) -> int:
    """Workers of ``client="local"``: the CPU count ÷ ``threads``, no more than the available
    memory holds at ``bytes_per_worker`` each (at least one)."""
    n = max(1, (os.cpu_count() or 1) // (threads or 1))
    try:
        import psutil

        free = psutil.virtual_memory().available
    except ImportError:  # pragma: no cover - psutil comes with dask.distributed
        return n
    return max(1, min(n, int(0.8 * free // max(1, bytes_per_worker))))


def run_realizations(fn, job: dict, seeds, *, client=None, threads=1, n_workers=None, bar=None,
                     bytes_per_worker: int = 0) -> list[dict]:  # fmt: skip
    """``fn(job, ss)`` (module-level: it pickles) for each seed ``ss`` of ``seeds``, in order;
    ``client``,
    ``threads``, ``n_workers`` as in :func:`~emscatter.solvers.mom3d.bistatic`, ``bar`` a
    progress bar advanced per finished realization (seconds and energy of the last beside it)."""
    if client == "local" and n_workers is None:
        n_workers = local_workers(bytes_per_worker * MEMORY_OVERHEAD, threads)
    executor, close = open_executor(client, n_workers, threads)

    def shown(j, res):
        if bar is not None:
            e = np.round(res["energy"], 4)
            bar.set_postfix_str(f"{res['seconds']:.1f} s, energy {e}")

    names = [f"mom3d realization {j}" for j in range(len(seeds))]
    try:
        return run_ordered(executor, fn, [(job, ss) for ss in seeds], names,
                           threads=threads, bar=bar, on_result=shown, stacklevel=4)  # fmt: skip
    finally:
        close()


def stack_results(results: list[dict]) -> dict:
    """The per-realization entries stacked in realization order (``amplitude`` ``(n, 2, 2,
    D)``, ``energy`` ``(n, 2)``, …) and the shared ones of the first (``power``, ``weights``,
    ``unknowns``, ``matrix_bytes``, ``taper_g``), in fresh arrays."""
    first = results[0]
    out = {key: first[key] for key in ("power", "unknowns", "matrix_bytes", "taper_g")}
    # fresh C-ordered arrays: a solve's amplitudes are strided views, pickling makes them
    # contiguous, and numpy's reductions sum another layout in another order (last bits)
    out["weights"] = np.array(first["weights"], order="C", copy=True)
    for key in ("amplitude", "hemisphere", "energy", "reflectivity"):
        out[key] = np.ascontiguousarray(np.stack([r[key] for r in results]))
    out["iterations"] = np.array([r["iterations"] for r in results])
    out["seconds"] = float(math.fsum(r["seconds"] for r in results) / len(results))
    return out
