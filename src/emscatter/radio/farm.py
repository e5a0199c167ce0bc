"""The radio tables of many materials at many frequencies at once — serially, on any
:class:`concurrent.futures.Executor` or on a dask.distributed cluster.

One task per (material, frequency): :meth:`emscatter.radio.MaterialSpec.tables`, the same
builder a Sionna scene calls (:func:`emscatter.radio.tables.build_tables`, or the textured one
for anisotropic roughness), in a worker whose compiled threads are capped (``threads`` per
task, :func:`emscatter.parallel.limited_threads`). A task is a pure function of its spec and
frequency, so the tables are the same, bit for bit, serially and on a cluster (tested); the
executor plumbing — ``client=None | "local" | "tcp://host:port" | Client | Executor``,
results in order, a failed task named, worker warnings passed on once each prefixed with
the task — is :mod:`emscatter.parallel`'s, as for BRDF tables (:mod:`emscatter.brdf.farm`)
and the MoM Monte Carlo::

    from emscatter import radio
    from emscatter.radio.farm import farm_tables
    walls = {"concrete": radio.MaterialSpec(surface=rough, medium="concrete"),
             "brick": radio.MaterialSpec(surface=rough, medium="brick", thickness=0.1)}
    tables = farm_tables(walls, [3.5e9, 28e9], client="local")
    tables["brick", 28e9].incoherent

Every (material, frequency) is checked before any work: the spec's medium (and its band at
each frequency), its surface, method and ``out_of_range`` policy; an error names the
material and the frequency. Progress: a tqdm bar over the tables (stderr; quiet off a
terminal unless ``progress=True``); on a dask cluster the tasks also show on its dashboard.
The tables built in workers are not in this process's reuse cache nor in
:func:`~emscatter.radio.tables.build_log` (that log is per process).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping

import numpy as np

from ..parallel import (
    check_client,
    check_n_workers,
    check_threads,
    open_executor,
    run_ordered,
)
from ..progress import task

__all__ = ["farm_tables", "check_jobs"]


def _materials(materials) -> list[tuple[str, object]]:
    from . import MaterialSpec

    if isinstance(materials, MaterialSpec):
        raise ValueError("materials must be a dict {label: MaterialSpec} or a list, got one spec "
                         "(wrap it: {'wall': spec})")  # fmt: skip
    if isinstance(materials, Mapping):
        items = list(materials.items())
    elif isinstance(materials, Iterable) and not isinstance(materials, str | bytes):
        items = [(f"material{i}", m) for i, m in enumerate(materials)]
    else:
        raise ValueError(
            f"materials must be a dict {{label: MaterialSpec}} or a list of MaterialSpec, got "
            f"{type(materials).__name__}"
        )
    if not items:
        raise ValueError("materials is empty: give at least one radio.MaterialSpec")
    for label, spec in items:
        if not isinstance(label, str) or not label:
            raise ValueError(f"materials: every label must be a non-empty string, got {label!r}")
        if not isinstance(spec, MaterialSpec):
            raise ValueError(
                f"materials[{label!r}] must be an emscatter.radio.MaterialSpec, got "
                f"{type(spec).__name__} {spec!r:.60}"
            )
    return items


def _frequencies(frequencies) -> list[float]:
    f = np.atleast_1d(np.asarray(frequencies, dtype=object))
    out = []
    for v in f.ravel():
        try:
            x = float(v)
        except (TypeError, ValueError):
            x = math.nan
        if isinstance(v, bool) or not (math.isfinite(x) and x > 0):
            raise ValueError(f"frequencies must be finite numbers > 0 [Hz], got {v!r}")
        out.append(x)
    if not out:
        raise ValueError("frequencies is empty: give at least one frequency [Hz]")
    if len(set(out)) != len(out):
        twice = sorted({x for x in out if out.count(x) > 1})
        raise ValueError(f"frequencies repeat {twice} Hz: each frequency is one table per material")
    return out


def check_jobs(materials, frequencies) -> list[tuple[str, object, float]]:
    """``[(label, spec, frequency), ...]``, materials outermost, every one checked without
    computing (medium and its band, surface, method, policy); ValueError naming the material
    and the frequency."""
    from ..solvers import available
    from .tables import check_policy, check_surface
    from .texture import check_textured_surface

    items, freqs = _materials(materials), _frequencies(frequencies)
    jobs = []
    for label, spec in items:
        where = f"materials[{label!r}]"
        try:
            medium = spec.material()
            check_policy(spec.out_of_range)
            allowed = ["auto", *available()]
            if not isinstance(spec.method, str) or spec.method not in allowed:
                raise ValueError(f"method must be one of {allowed}, got {spec.method!r}")
            if spec.surface is not None:
                textured = spec.texture_direction is not None or not getattr(
                    spec.surface, "is_isotropic", True
                )
                (check_textured_surface if textured else check_surface)(spec.surface)
        except (ValueError, TypeError) as exc:
            raise ValueError(f"{where}: {exc}") from None
        for f in freqs:
            try:
                complex(np.asarray(medium.eps(frequency=f)))
            except (ValueError, TypeError) as exc:
                raise ValueError(f"{where} at {f / 1e9:g} GHz: {exc}") from None
            jobs.append((label, spec, f))
    return jobs


def _load_compiled() -> bool:
    """The compiled-kernel runtime loaded when the numba backend is selected: the solvers take
    the compiled path for small calls only once it is loaded (:mod:`emscatter.kernels.gate`),
    so loading it here and in every worker gives each table the same path (as
    :func:`emscatter.brdf.farm._load_compiled`)."""
    from .. import kernels

    if kernels.backend() != "numba":
        return False
    import emscatter.kernels._runtime  # noqa: F401

    return True


def _build_one(spec, frequency: float, label: str, compiled: bool, threads: int | None):
    """One table (the task function, module-level so it pickles), its compiled threads
    capped the same way serially and in a worker — the kernels' own (``kernels.thread_cap``)
    here, numba's, scipy.fft's and BLAS's by :func:`emscatter.parallel.run_ordered`
    (``cap_serial``; a parallel reduction's order depends on its thread count, so the cap is
    what makes the serial and the farmed tables the same bit for bit)."""
    import contextlib

    from ..kernels import thread_cap

    if compiled:
        _load_compiled()
    cap = thread_cap(threads) if threads is not None else contextlib.nullcontext()
    with cap:  # numba's, scipy.fft's, BLAS's: run_ordered(cap_serial=True)
        return spec.tables(frequency, label=label)


def farm_tables(
    materials,
    frequencies,
    *,
    client=None,
    threads: int | None = 1,
    n_workers: int | None = None,
    progress: bool | None = None,
) -> dict:
    """The radio tables of every material at every frequency:
    ``{(label, frequency): RadioTables}``, materials outermost, frequencies in the given order.

    Parameters
    ----------
    materials : ``{label: radio.MaterialSpec}`` (the label names the tables, as
        ``label=`` of :func:`~emscatter.radio.tables.build_tables`), or a list of specs
        (labels ``material0``, ``material1``, …).
    frequencies : one frequency or several [Hz], distinct, each inside every medium's band.
    client : None (serial, here), ``"local"`` (a LocalCluster of ``n_workers`` single-threaded
        processes, closed at the end), ``"tcp://host:port"``, a dask.distributed ``Client`` or
        any :class:`concurrent.futures.Executor` (:func:`emscatter.parallel.open_executor`).
    threads : compiled threads per task (default 1: one task per core).
    n_workers : workers of ``client="local"`` (default: the CPU count ÷ ``threads``).
    progress : tqdm bar over the tables: None → only when stderr is a terminal.
    """
    threads = check_threads(threads)
    n_workers = check_n_workers(n_workers)
    check_client(client)
    jobs = check_jobs(materials, frequencies)  # every one before any work
    names = [f"radio tables {label!r} at {f / 1e9:g} GHz" for label, _, f in jobs]
    compiled = _load_compiled()
    args = [(spec, f, label, compiled, threads) for label, spec, f in jobs]
    with task("radio tables", len(jobs), progress, unit="table") as bar:
        executor, close = open_executor(client, n_workers, threads)
        try:
            out = run_ordered(
                executor, _build_one, args, names, threads=threads, bar=bar, cap_serial=True
            )
        finally:
            close()
    return {(label, f): t for (label, _, f), t in zip(jobs, out, strict=True)}
