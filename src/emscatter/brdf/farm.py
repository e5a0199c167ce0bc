"""Many BRDF tables at once (materials × wavelength sets × roughness), serially, on any
:class:`concurrent.futures.Executor` or on a dask.distributed cluster.

Each table is one task: :func:`~emscatter.brdf.build_table` with the spec's arguments, in a
worker whose compiled-kernel threads are capped (``threads`` per task: the solvers' own
``threads=`` option where they take one — GO, PO, IEM — and ``NUMBA_NUM_THREADS`` /
``numba.set_num_threads`` for numba's own layer), so ``n_workers × threads`` stays within the
cores instead of every worker starting a thread per core. A task is a pure function of its
spec, so the tables are the same, bit for bit, serially, on a process pool or on a cluster
(tested); they come back in the order of ``specs``::

    from emscatter.brdf import build_tables, table_specs
    specs = table_specs([rough_a, rough_b], ["Au", "Ag", "Cu"], [[450e-9, 550e-9, 650e-9]],
                        method="go", resolution=(30, 60))
    tables = build_tables(specs, client="local")           # a 2-worker-per-core LocalCluster
    tables = build_tables(specs, client="tcp://host:8786")  # a running scheduler
    tables = build_tables(specs, client=my_dask_client)     # or a ProcessPoolExecutor

Tasks are batches of specs (``batch`` tables each; by default about four batches per worker,
so that a cluster's per-task cost — scheduling, pickling, a round trip — is paid per batch, not
per small table), and with ``out_dir`` each worker writes its tables to
``out_dir/<name>.npz`` itself (atomically, :func:`~emscatter.brdf.export_npz.write_npz`) and
sends back only the path: thousands of 17.5 MB tables neither cross the network nor sit in
this process's memory (the folder must be one the workers and this process share);
``compress=False`` stores the files' arrays instead of deflating them (a 90×180 float64
table: 11.7 MB stored, 10.9 MB deflated, the deflating ~0.3 s of CPU a table).

A ``"local"`` cluster's workers start with glibc's heap thresholds of a plain process
(:data:`emscatter.parallel.WORKER_MALLOC`): under dask's default
``MALLOC_TRIM_THRESHOLD_=65536`` every numpy temporary over 128 kB is a fresh mapping and a
PO table costs ×1.6 its CPU. Workers you start yourself (``dask worker tcp://…``) should get
the same: ``MALLOC_MMAP_THRESHOLD_=33554432 MALLOC_TRIM_THRESHOLD_=67108864`` in their
environment before they start (``distributed.nanny.pre-spawn-environ`` in dask's config).

The executor plumbing (a ``"local"`` LocalCluster with its dashboard on a free port, a
scheduler address, thread caps per task, results in order, failed tasks named, worker
warnings passed on) is :mod:`emscatter.parallel`'s, shared with the MoM Monte Carlo and the
radio farm (:mod:`emscatter.radio.farm`).

Every spec is checked before any work (surface, material at every wavelength, method, the
keyword names): a bad one raises a ``ValueError`` naming the spec, the field, the value and
what is allowed. Warnings raised in the workers are passed on once each in this process,
prefixed with the spec (use process pools or dask: Python's warnings state is per
process, so a thread pool's tables may lose theirs). Progress: a tqdm bar over the tables
(stderr; quiet when stderr is
not a terminal unless ``progress=True``); on a dask cluster the tasks also show on its
dashboard.
"""

from __future__ import annotations

import contextlib
import inspect
import itertools
import numbers
import os
import warnings
from collections.abc import Iterable, Mapping

from ..parallel import (
    check_client,
    check_n_workers,
    check_threads,
    dask_client,
    open_executor,
    run_ordered,
)
from ..spectra import check_roughness
from . import build as _build_mod
from .progress import bar

__all__ = ["build_tables", "table_specs", "check_spec", "SPEC_FIELDS"]

#: The keywords of :func:`build_table` a spec may set (besides ``surface``, ``material``,
#: ``wavelengths``); solver options go in ``options`` (a dict).
BUILD_KEYWORDS = tuple(
    name
    for name, p in inspect.signature(_build_mod.build_table).parameters.items()
    if p.kind is p.KEYWORD_ONLY and name != "progress"
)
#: Every field a spec (a mapping) may have.
SPEC_FIELDS = ("surface", "material", "wavelengths", "name", "options", *BUILD_KEYWORDS)
_REQUIRED = ("surface", "material", "wavelengths")


def table_specs(surfaces, materials, wavelength_sets, **common) -> list[dict]:
    """Specs for every (surface, material, wavelength set), surfaces outermost, with the
    :func:`build_table` keywords ``common`` shared by all (``name``: ``"s{i}-{material}-w{k}"``)."""
    surfaces, materials, wavelength_sets = list(surfaces), list(materials), list(wavelength_sets)
    out = []
    for (i, s), m, (k, w) in itertools.product(
        enumerate(surfaces), materials, enumerate(wavelength_sets)
    ):
        label = m if isinstance(m, str) else type(m).__name__
        out.append(
            {"surface": s, "material": m, "wavelengths": w, "name": f"s{i}-{label}-w{k}", **common}
        )
    return out


def check_spec(spec, index: int = 0) -> dict:
    """``spec`` (a mapping with :data:`SPEC_FIELDS`) checked without computing: the keyword
    arguments of its :func:`build_table` call. ValueError naming the spec and the field."""
    where = f"specs[{index}]"
    if not isinstance(spec, Mapping):
        raise ValueError(
            f"{where} must be a dict with the fields {list(_REQUIRED)} (and optionally "
            f"{list(SPEC_FIELDS[3:])}), got {type(spec).__name__} {spec!r:.80}"
        )
    where = f"{where} ({spec['name']!r})" if isinstance(spec.get("name"), str) else where
    missing = [f for f in _REQUIRED if f not in spec]
    if missing:
        raise ValueError(f"{where} lacks the field(s) {missing}; a spec needs {list(_REQUIRED)}")
    unknown = [f for f in spec if f not in SPEC_FIELDS]
    if unknown:
        raise ValueError(
            f"{where} has unknown field(s) {unknown}; allowed: {list(SPEC_FIELDS)} (solver "
            "options go in 'options', a dict)"
        )
    kw = {k: v for k, v in spec.items() if k != "name"}
    try:
        rough = check_roughness(kw["surface"], "surface")
        if rough.dimension != 2:
            raise ValueError(f"must be 2-D (dimension=2), got dimension {rough.dimension}")
    except (ValueError, TypeError) as exc:
        raise ValueError(f"{where} field 'surface': {exc}") from None
    try:
        wl = _build_mod._check_wavelengths(kw["wavelengths"])
    except (ValueError, TypeError) as exc:
        raise ValueError(f"{where} field 'wavelengths': {exc}") from None
    for lam in wl:
        try:
            _build_mod.material_eps(kw["material"], float(lam))
        except (ValueError, TypeError, KeyError) as exc:
            raise ValueError(
                f"{where} field 'material' = {kw['material']!r} at λ = {lam:.6g} m: {exc}"
            ) from None
    method = kw.get("method", "auto")
    from ..solvers import available

    allowed = ["auto", *available()]
    if not isinstance(method, str) or method not in allowed:
        raise ValueError(f"{where} field 'method' must be one of {allowed}, got {method!r}")
    options = kw.pop("options", None) or {}
    if not isinstance(options, Mapping):
        raise ValueError(
            f"{where} field 'options' must be a dict of solver options, got {options!r:.80}"
        )
    clash = sorted(set(options) & set(SPEC_FIELDS))
    if clash:
        raise ValueError(f"{where} field 'options' repeats spec field(s) {clash}")
    return {**kw, "wavelengths": wl, **options}


def _cap_threads(kwargs: dict, threads: int | None, in_worker: bool) -> dict:
    """The solver's ``threads=`` set to the cap where it takes one and the caller did not;
    in a worker also numba's own thread count (this thread's, never the caller's process)."""
    if threads is None:
        return kwargs
    if in_worker:
        try:
            import numba

            numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
        except ImportError:
            pass
    method = kwargs.get("method", "auto")
    if method != "auto" and "threads" not in kwargs:
        from .. import solvers

        if "threads" in inspect.signature(solvers.get(method).bistatic).parameters:
            return {**kwargs, "threads": threads}
    return kwargs


def _load_compiled() -> bool:
    """Load the compiled-kernel runtime when the numba backend is selected (returns whether).

    The solvers take the compiled path for a small call only once the runtime is loaded in the
    process (:mod:`emscatter.kernels.gate`), and the compiled and numpy paths agree to ~1e-12,
    not bit for bit: loading it in the caller and in every worker makes each table take the
    same path wherever it is built, so a farm's tables are identical to the serial run's."""
    from .. import kernels

    if kernels.backend() != "numba":
        return False
    import emscatter.kernels._runtime  # noqa: F401

    return True


def _build_one(kwargs: dict, threads: int | None, in_worker: bool = True, compiled=False):
    """One table in a worker: ``(table, [(category, message), ...])`` — its warnings come back
    with it instead of being lost in the worker's log."""
    if compiled:
        _load_compiled()
    kwargs = _cap_threads(kwargs, threads, in_worker)
    from ..kernels import thread_cap

    cap = thread_cap(threads) if threads is not None else contextlib.nullcontext()
    with cap, warnings.catch_warnings(record=True) as caught:  # every compiled call capped
        warnings.simplefilter("always")
        table = _build_mod.build_table(progress=False, **kwargs)
    return table, [(w.category, str(w.message)) for w in caught]


def _build_batch(calls: list, names: list, threads, compiled: bool, out_dir,
                 in_worker: bool = True, compress: bool = True) -> list:  # fmt: skip
    """The tables of one task: ``[(table or its path, warnings), ...]`` in the order given;
    with ``out_dir`` each is written to ``out_dir/<name>.npz`` here, in the worker (``compress``:
    deflated or stored members; serially: ``in_worker=False``, this process's numba thread
    count left alone)."""
    out = []
    for kw, name in zip(calls, names, strict=True):
        try:
            table, caught = _build_one(kw, threads, in_worker, compiled)
        except Exception as exc:
            if len(calls) == 1:
                raise
            raise RuntimeError(f"{name}: {type(exc).__name__}: {exc}") from exc
        if out_dir is not None:
            from .export_npz import write_npz

            path = os.path.join(out_dir, f"{name}.npz")
            table = str(write_npz(table, path, compress=compress))
        out.append((table, caught))
    return out


def _workers_of(executor, client, n_workers, threads) -> int | None:
    """How many tasks ``executor`` runs at once, where it says (None: unknown)."""
    if client == "local":
        return n_workers or max(1, (os.cpu_count() or 1) // (threads or 1))
    dc = dask_client(client if hasattr(client, "scheduler_info") else executor)
    if dc is not None:
        try:
            workers = dc.scheduler_info().get("workers", {})
            return max(1, sum(int(w.get("nthreads", 1)) for w in workers.values()))
        except Exception:  # noqa: BLE001 - a client that cannot tell: unknown
            return None
    n = getattr(executor, "_max_workers", None)
    return int(n) if isinstance(n, int) and n > 0 else None


def _batches(n: int, batch: int | None, workers: int | None) -> list[range]:
    """Contiguous index ranges of the tasks: ``batch`` specs each, or (None) about
    :data:`BATCHES_PER_WORKER` tasks per worker (one spec per task when that is unknown)."""
    if batch is None:
        batch = 1 if workers is None else max(1, -(-n // (BATCHES_PER_WORKER * workers)))
    return [range(a, min(a + batch, n)) for a in range(0, n, batch)]


#: Tasks per worker when ``batch`` is None: few enough that the per-task cost is amortized,
#: enough that a slow table does not leave the other workers idle at the end.
BATCHES_PER_WORKER = 4


def _check_out_dir(out_dir, names: list[str]):
    if out_dir is None:
        return None
    if not isinstance(out_dir, str | os.PathLike):
        raise ValueError(f"out_dir must be a folder path or None, got {out_dir!r}")
    path = os.fspath(out_dir)
    if not os.path.isdir(path):
        raise ValueError(f"out_dir {path!r} is not an existing folder (create it first)")
    seen = {}
    for i, name in enumerate(names):
        if not isinstance(name, str) or not name or os.sep in name or name in (".", ".."):
            raise ValueError(
                f"specs[{i}] field 'name' = {name!r}: with out_dir the name is the file name "
                f"(<name>.npz): a non-empty string without {os.sep!r}"
            )
        if name in seen:
            raise ValueError(
                f"specs[{i}] field 'name' = {name!r} repeats specs[{seen[name]}]'s: with "
                "out_dir every table needs its own name (its file)"
            )
        seen[name] = i
    return path


def build_tables(
    specs: Iterable[Mapping],
    *,
    client=None,
    threads: int | None = 1,
    n_workers: int | None = None,
    progress: bool | None = None,
    batch: int | None = None,
    out_dir=None,
    compress: bool = True,
) -> list:
    """One :class:`~emscatter.brdf.BrdfTable` per spec, in the order of ``specs``.

    Parameters
    ----------
    specs : mappings with ``surface``, ``material``, ``wavelengths`` [m] and optionally ``name``,
        ``options`` (solver options, a dict) and any :func:`build_table` keyword (``method``,
        ``resolution``, ``dtype``, …); :func:`table_specs` makes the product of several.
    client : None (serial, in this process), ``"local"`` (a LocalCluster of ``n_workers``
        single-threaded worker processes, closed at the end), a scheduler address
        ``"tcp://host:port"``, a dask.distributed ``Client`` or any
        :class:`concurrent.futures.Executor` (the task function is module-level, picklable).
    threads : compiled-kernel threads per task (default 1: one task per core); None leaves
        the solvers' default (the CPU count, at most 8) — oversubscribes a cluster's workers.
    n_workers : workers of ``client="local"`` (default: the CPU count ÷ ``threads``).
    progress : tqdm bar over the tables: None → only when stderr is a terminal.
    batch : specs per task on an executor or cluster (None: about
        :data:`BATCHES_PER_WORKER` tasks per worker where the executor tells its workers,
        else 1); the tables are the same whatever the batching.
    out_dir : None (the tables come back) or an existing folder, shared with the workers:
        each table is written there by its worker as ``<name>.npz`` (atomically; the spec
        names must then be unique file names) and its :class:`~pathlib.Path` comes back
        (read it with :func:`emscatter.brdf.export_npz.read_npz`).
    compress : with ``out_dir``, deflate the files' arrays (True, the default:
        ``np.savez_compressed``; a PO or GO 90×180 float64 table's 11.7 MB become 10.9 MB for
        ~0.3 s of CPU a table, more than a GO table's build and half a PO one's) or store them
        (False: ``np.savez``, 11.7 MB for ~20 ms); the values read back are the same bit for
        bit either way. Only with ``out_dir`` (False without it is a ValueError).
    """
    threads = check_threads(threads)
    if batch is not None and (
        isinstance(batch, bool) or not isinstance(batch, numbers.Integral) or batch < 1
    ):
        raise ValueError(f"batch must be a positive integer or None, got {batch!r}")
    n_workers = check_n_workers(n_workers)
    check_client(client)
    if isinstance(specs, Mapping):
        raise ValueError("specs must be a list of spec dicts, got a single dict (wrap it: [spec])")
    specs = list(specs)
    if not specs:
        raise ValueError("specs is empty: give at least one spec (see table_specs)")
    calls = [check_spec(s, i) for i, s in enumerate(specs)]  # every spec before any work
    names = [s.get("name") or f"specs[{i}]" for i, s in enumerate(specs)]
    out_dir = _check_out_dir(out_dir, names)
    if not isinstance(compress, bool):
        raise ValueError(f"compress must be True or False, got {compress!r}")
    if not compress and out_dir is None:
        raise ValueError(
            "compress=False applies to the files out_dir receives; without out_dir no file is "
            "written (give out_dir, or leave compress at True)"
        )
    compiled = _load_compiled()  # the same kernel path in this process and every worker
    with bar(len(calls), "BRDF tables", progress, unit="table") as b:
        executor, close = open_executor(client, n_workers, threads)
        try:
            if executor is None:
                tasks = [range(j, j + 1) for j in range(len(calls))]
            else:
                workers = _workers_of(executor, client, n_workers, threads)
                tasks = _batches(len(calls), batch, workers)
            arg_list = [
                ([calls[j] for j in r], [names[j] for j in r], threads, compiled, out_dir,
                 executor is not None, compress)
                for r in tasks
            ]  # fmt: skip
            labels = [
                f"build_tables: {names[r[0]]}" if len(r) == 1
                else f"build_tables: a table of {names[r[0]]} … {names[r[-1]]}"
                for r in tasks
            ]  # fmt: skip
            done = run_ordered(
                executor, _build_batch, arg_list, labels, threads=threads,
                on_result=lambda k, _res: b.update(len(tasks[k])), cap_serial=True,
            )  # fmt: skip
        finally:
            close()
    results = [item for batch_out in done for item in batch_out]
    seen = set()
    for name, (_, caught) in zip(names, results, strict=True):
        for category, message in caught:
            if (category, message) not in seen:
                seen.add((category, message))
                warnings.warn(f"{name}: {message}", category, stacklevel=2)
    if out_dir is not None:
        from pathlib import Path

        return [Path(table) for table, _ in results]
    return [table for table, _ in results]
