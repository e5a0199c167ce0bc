"""BRDF table farms (``emscatter.brdf.build_tables``) serially and on a 2-worker dask
LocalCluster, per workload: the tables a farm user builds — materials × wavelengths ×
roughness — with GO (whose kernel is the fastest: small tables, the farm's per-task cost
shows), PO, IEM and SPM (numpy/compiled builds that run on one core: what a farm is for).

The serial side is the plain loop a user writes: ``build_table(**spec)`` per spec, the spec's
options, the solvers' default threads, in this process (``serial``: tables in memory;
``serial_out_dir`` / ``serial_out_dir_stored``: each also written with ``write_npz``,
deflated / stored), plus ``build_tables(specs)`` (``serial_threads1``: one thread a table, the
farm's per-task setting). The farm: ``build_tables(specs, client=<LocalCluster>)``, one
single-threaded worker per core, the tables pickled back (``farm``) or written by the workers
(``farm_out_dir``: deflated, ``farm_out_dir_stored``: ``compress=False``). Result cache off
(``EMSCATTER_CACHE=off``), warm on both sides (this process and the workers first build a few
tables of the workload: numba cache loaded, material data read), every side alternated
``--repeat`` times in one process; every farm's and every serial side's tables checked
bit-identical to the plain loop's. Each row records the per-table serial time, the plain
loop's CPU utilisation (process CPU / wall: 1.0 = one core busy), the load average at its start
and end, and each farm's speed-up over the serial side writing the same files (median /
median); ``farm_out_dir_stored_vs_memory`` is the in-memory plain loop over the farm that also
writes the files (the farm does more). On a loaded machine wall times mostly measure the other
load: ``cpu_per_table_ms`` (this process's CPU; for a farm the workers' plus this process's)
and ``cpu_projected_speedup`` (serial CPU ÷ (farm CPU ÷ workers): the idle machine's speed-up
if the serial side keeps one core busy and the farm's cores are all busy) are the
load-independent view. The JSON's ``threads`` says what each dask worker runs
with (thread caps, numba's thread count and layer, OpenBLAS threads, glibc heap settings) and
the same for this process; ``--profile`` adds a cProfile of one plain ``build_table`` call
(own-time shares: the compiled kernels show as their Python entry, the rest is numpy).

    EMSCATTER_CACHE=off PYTHONPATH=src python benchmarks/bench_brdf_farm.py [--repeat 3]
        [--workloads go po iem spm] [--workers 2] [--scale 1.0] [--resolution 90 180]
        [--out brdf_farm] [--cli] [--profile] [--dtype float32]

``--cli`` adds a row for the command line (``emscatter farm brdf`` serially and with
``--scheduler local``, each a fresh process: the interpreter's and the cluster's start are in
the time, as a user waits for them; run with this script's starting environment, not the
thread caps dask's nanny leaves in it).

The default tables are small (GO 5 ms, IEM 20 ms of CPU each on the reference machine): the
farm's fixed costs show. Full-size tables (``--resolution 90 180``: 11.7 MB each in float64)
are where ``out_dir`` matters — the workers write them instead of pickling them back.

Writes ``benchmarks/results/brdf_farm.json``. The issue's target is ≥ 1.7× for 64 tables on 2
cores; ``--scale`` multiplies the table counts (small runs to check the script).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import tempfile
import time
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import command, machine, write  # noqa: E402

#: This process's environment at the start (dask's nanny writes its workers' thread caps and
#: malloc settings into it when a LocalCluster starts; the CLI rows run without them).
START_ENV = dict(os.environ)

#: workload → (method, tables, (n_theta, n_phi), roughness σ [µm], ℓ [µm])
WORKLOADS = {
    "go": ("go", 64, (30, 60), (0.2, 0.3, 0.4, 0.5), 1.0),
    "po": ("po", 64, (24, 48), (0.03, 0.04, 0.05, 0.06), 0.6),
    "iem": ("iem", 64, (6, 12), (0.02, 0.03, 0.04, 0.05), 0.3),
    "spm": ("spm", 16, (8, 16), (0.01, 0.015, 0.02, 0.025), 0.5),
}
MATERIALS = ["Au", "Ag", "Cu", "Al"]
WAVELENGTHS = (450e-9, 550e-9, 650e-9, 750e-9)


def specs(workload: str, scale: float = 1.0, resolution=None, dtype="float64") -> list[dict]:
    """The workload's specs: roughness × materials × wavelengths (one wavelength each), the
    first ``tables × scale`` of them (``resolution``: ``(n_theta, n_phi)`` instead)."""
    from emscatter.brdf import table_specs
    from emscatter.spectra import GaussianCorrelation

    method, n, res, sigmas, ell = WORKLOADS[workload]
    res = tuple(resolution) if resolution else res
    rough = [GaussianCorrelation(sigma=s * 1e-6, length=ell * 1e-6, dimension=2) for s in sigmas]
    wls = [[w] for w in WAVELENGTHS]
    sp = table_specs(
        rough, MATERIALS, wls, method=method, resolution=res, out_of_range="ignore", dtype=dtype
    )
    n = max(4, round(n * scale))
    return (sp * (1 + n // len(sp)))[:n] if n > len(sp) else sp[:n]


def _identical(a, b) -> bool:
    return all(x.values.tobytes() == y.values.tobytes() for x, y in zip(a, b, strict=True))


def _timed(fn) -> tuple[float, float, object]:
    t, c = time.perf_counter(), time.process_time()
    out = fn()
    return time.perf_counter() - t, time.process_time() - c, out


def thread_report() -> dict:
    """The thread settings of this process (run in each dask worker with ``client.run``):
    the cap variables, numba's thread count and layer, the wheels' OpenBLAS thread count,
    emscatter's default compiled-call threads."""
    import numba

    from emscatter.kernels import default_threads
    from emscatter.parallel import _openblas_controls

    names = ("NUMBA_NUM_THREADS", "EMSCATTER_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS",
             "MKL_NUM_THREADS", "MALLOC_TRIM_THRESHOLD_", "MALLOC_MMAP_THRESHOLD_")  # fmt: skip
    try:
        layer = numba.threading_layer()
    except ValueError:  # no parallel numba function has run in this process
        layer = "not initialised"
    return {
        "env": {n: os.environ.get(n) for n in names},
        "numba_threads": numba.get_num_threads(),
        "numba_threading_layer": layer,
        "openblas_threads": [int(get()) for get, _ in _openblas_controls()],
        "emscatter_default_threads": default_threads(),
    }


def profile_one(sp: list[dict], top: int = 8) -> dict:
    """cProfile of one plain ``build_table`` call of the workload (the plain loop's options):
    wall and CPU time and the functions with the most own time (the compiled kernels show as
    their Python entry, e.g. ``po_kernel._series_kernel``; the rest is numpy on one core)."""
    import cProfile
    import pstats

    from emscatter.brdf import build_table

    kw = {k: v for k, v in sp[min(5, len(sp) - 1)].items() if k != "name"}
    build_table(**kw)
    prof = cProfile.Profile()
    wall, cpu, _ = _timed(lambda: prof.runcall(build_table, **kw))
    st = pstats.Stats(prof)
    total = sum(v[2] for v in st.stats.values()) or 1.0
    rows = sorted(st.stats.items(), key=lambda kv: -kv[1][2])[:top]
    return {
        "wall_s_profiled": wall,
        "cpu_s_profiled": cpu,
        "own_time_share": {
            f"{Path(f).parent.name}/{Path(f).name}:{name}": round(v[2] / total, 3)
            for (f, _, name), v in rows
        },
    }


def _plain_loop(sp, out_dir=None, compress=True):
    """The serial loop a user writes: ``build_table`` per spec with the spec's options (the
    solvers' default threads), optionally each table written with ``write_npz``."""
    from emscatter.brdf import build_table
    from emscatter.brdf.export_npz import write_npz

    out = []
    for spec in sp:
        table = build_table(**{k: v for k, v in spec.items() if k != "name"})
        if out_dir is not None:
            table = write_npz(table, Path(out_dir) / f"{spec['name']}.npz", compress=compress)
        out.append(table)
    return out


#: farm variant → (build_tables keywords, the serial side it is compared with)
VARIANTS = {
    "farm": ({}, "serial"),
    "farm_out_dir": ({"out_dir": True}, "serial_out_dir"),
    "farm_out_dir_stored": ({"out_dir": True, "compress": False}, "serial_out_dir_stored"),
}
#: serial side → (out_dir?, compress): the plain loop, in memory or writing the same files
SERIAL = {
    "serial": (False, True),
    "serial_out_dir": (True, True),
    "serial_out_dir_stored": (True, False),
}


def run_workload(name, client, repeat, scale, resolution=None, profile=False,
                 dtype="float64") -> dict:  # fmt: skip
    from emscatter.brdf import build_tables
    from emscatter.brdf.export_npz import read_npz
    from emscatter.parallel import dask_client

    dc = dask_client(client)

    def workers_cpu() -> float:  # the dask workers' process CPU time, summed [s]
        return sum(dc.run(time.process_time).values())

    load0 = list(os.getloadavg())
    sp = specs(name, scale, resolution, dtype)
    variants = dict(VARIANTS)
    if name == "go":
        variants["farm_batch1"] = ({"batch": 1}, "serial")
    _plain_loop(sp[:4])  # warm this process
    build_tables(sp[:8], client=client, progress=False)  # warm the workers
    times = {v: [] for v in (*SERIAL, "serial_threads1", *variants)}
    cpus = {v: [] for v in times}  # CPU seconds of each run (farm: workers + this process)
    serial_cpu = []
    identical = True
    with tempfile.TemporaryDirectory(prefix="emscatter-farm-") as tmp:

        def folder(label, r):
            f = Path(tmp) / f"{label}-{r}"
            f.mkdir()
            return f

        for r in range(repeat):  # alternated in one process
            reference = None
            for side, (to_dir, compress) in SERIAL.items():
                where = folder(side, r) if to_dir else None
                wall, cpu, out = _timed(lambda w=where, c=compress: _plain_loop(sp, w, c))
                times[side].append(wall)
                cpus[side].append(cpu)
                if side == "serial":
                    serial_cpu.append(cpu / wall)
                    reference = out
                else:
                    identical = identical and _identical(reference, [read_npz(p) for p in out])
            wall, cpu, out = _timed(lambda: build_tables(sp, progress=False))  # threads=1
            times["serial_threads1"].append(wall)
            cpus["serial_threads1"].append(cpu)
            identical = identical and _identical(reference, out)
            for v, (kw, _) in variants.items():
                kw = {**kw, "out_dir": folder(v, r)} if kw.get("out_dir") else dict(kw)
                w0 = workers_cpu()
                wall, cpu, farm = _timed(
                    lambda kw=kw: build_tables(sp, client=client, progress=False, **kw)
                )
                times[v].append(wall)
                cpus[v].append(workers_cpu() - w0 + cpu)
                if "out_dir" in kw:
                    farm = [read_npz(p) for p in farm]
                identical = identical and _identical(reference, farm)
    method, _, res, _, _ = WORKLOADS[name]
    res = tuple(resolution) if resolution else res
    med = statistics.median(times["serial"])
    row = {
        "what": f"{len(sp)} {method.upper()} tables {res[0]}×{res[1]} {dtype}, 1 wavelength each, "
        "warm, cache off. Serial: the plain loop a user writes (build_table per spec, the "
        "solvers' default threads, in this process), in memory or writing each table with "
        "write_npz (deflated / stored); serial_threads1: build_tables(specs) (threads=1). "
        "Farm: build_tables(specs, client=<2-worker LocalCluster>, threads=1 per worker), "
        "tables pickled back or written by the workers (out_dir, compress=True/False). "
        "Each speed-up: median serial side / median farm; farm_out_dir_stored_vs_memory: "
        "the in-memory plain loop over the farm that also writes the files.",
        "tables": len(sp),
        "per_table_serial_ms": 1e3 * med / len(sp),
        "serial_cpu_utilisation": statistics.median(serial_cpu),
        "identical": identical,
        "load_average_start": load0,
    }
    for v, ts in times.items():
        row[f"{v}_s"] = ts
    for v, (_, base) in variants.items():
        row[f"{v}_speedup"] = statistics.median(times[base]) / statistics.median(times[v])
    row["farm_out_dir_stored_vs_memory_speedup"] = med / statistics.median(
        times["farm_out_dir_stored"]
    )
    row["serial_threads1_over_plain"] = statistics.median(times["serial_threads1"]) / med
    # CPU per table and what it predicts for an idle machine (wall = CPU ÷ workers for the
    # farm, = CPU for the serial side): the load-independent view of a loaded machine's run
    cpu_ms = {v: 1e3 * statistics.median(c) / len(sp) for v, c in cpus.items()}
    row["cpu_per_table_ms"] = cpu_ms
    workers = len(dc.scheduler_info().get("workers", {})) if dc is not None else 1
    row["cpu_projected_speedup"] = {
        v: cpu_ms[base] / (cpu_ms[v] / workers) for v, (_, base) in variants.items()
    }
    row["load_average_end"] = list(os.getloadavg())
    if profile:
        row["profile_one_table"] = profile_one(sp)
    shown = [*variants, "farm_out_dir_stored_vs_memory"]
    print(f"{name:4s} {len(sp):3d} tables  serial {med:.2f} s ({row['per_table_serial_ms']:.0f} "
          f"ms/table, CPU ×{row['serial_cpu_utilisation']:.2f})  " + "  ".join(
              f"{v} ×{row[f'{v}_speedup']:.2f}" for v in shown) + f"  identical {identical}"
          + "\n     CPU ms/table " + "  ".join(f"{v} {c:.0f}" for v, c in cpu_ms.items())
          + "\n     CPU-projected " + "  ".join(
              f"{v} ×{x:.2f}" for v, x in row["cpu_projected_speedup"].items()),
          flush=True)  # fmt: skip
    return row


def run_cli(workers: int, repeat: int, scale: float, resolution=None) -> dict:
    """``emscatter farm brdf`` of the GO workload's tables (σ × material × wavelength, one
    ``.npz`` each), serially and with ``--scheduler local --workers N``, alternated: what a
    command-line user waits for, the interpreter's and the cluster's start included; the
    two folders' files compared byte for byte."""
    import subprocess

    method, n, res, sigmas, ell = WORKLOADS["go"]
    res = tuple(resolution) if resolution else res
    n_mat = max(1, min(len(MATERIALS), round(len(MATERIALS) * scale)))
    argv = [sys.executable, "-m", "emscatter", "farm", "brdf", "--quiet", "--method", method,
            "--n-theta", str(res[0]), "--n-phi", str(res[1]), "--out-of-range", "ignore",
            "--length", f"{ell * 1e-6:g}"]  # fmt: skip
    for s in sigmas:
        argv += ["--sigma", f"{s * 1e-6:g}"]
    for m in MATERIALS[:n_mat]:
        argv += ["--material", m]
    for w in WAVELENGTHS:
        argv += ["--wavelengths-nm", f"{w * 1e9:g}"]
    tables = len(sigmas) * n_mat * len(WAVELENGTHS)
    env = {**START_ENV, "PYTHONPATH": str(Path(__file__).resolve().parents[1] / "src")}
    env.setdefault("EMSCATTER_CACHE", "off")
    times = {"serial": [], "local": []}
    identical = True
    with tempfile.TemporaryDirectory(prefix="emscatter-farm-cli-") as tmp:
        for r in range(repeat):
            out = {}
            for side, extra in (("serial", []), ("local", ["--scheduler", "local", "--workers",
                                                          str(workers)])):  # fmt: skip
                out[side] = Path(tmp) / f"{side}-{r}"
                t = time.perf_counter()
                subprocess.run([*argv, "--out-dir", str(out[side]), *extra], check=True, env=env,
                               capture_output=True)  # fmt: skip
                times[side].append(time.perf_counter() - t)
            a = {p.name: p.read_bytes() for p in out["serial"].glob("*.npz")}
            b = {p.name: p.read_bytes() for p in out["local"].glob("*.npz")}
            identical = identical and len(a) == tables and a == b
    row = {
        "what": f"emscatter farm brdf: {tables} {method.upper()} tables {res[0]}×{res[1]}, "
        f"serial vs --scheduler local --workers {workers} (interpreter and cluster start "
        "included)",
        "tables": tables,
        "serial_s": times["serial"],
        "local_s": times["local"],
        "speedup": statistics.median(times["serial"]) / statistics.median(times["local"]),
        "identical_files": identical,
    }
    print(f"cli  {tables:3d} tables  serial {statistics.median(times['serial']):.2f} s  "
          f"local ×{row['speedup']:.2f}  identical files {identical}", flush=True)  # fmt: skip
    return row


def main() -> None:
    os.environ.setdefault("EMSCATTER_CACHE", "off")
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--workloads", nargs="+", default=list(WORKLOADS), choices=list(WORKLOADS))
    ap.add_argument("--scale", type=float, default=1.0, help="× the table counts")
    ap.add_argument(
        "--resolution",
        type=int,
        nargs=2,
        metavar=("N_THETA", "N_PHI"),
        help="every workload's table resolution instead of its own (e.g. 90 180)",
    )
    ap.add_argument("--out", default="brdf_farm", help="results file name (results/NAME.json)")
    ap.add_argument(
        "--dtype",
        default="float64",
        choices=["float64", "float32"],
        help="the tables' storage (build_table's dtype=; float32 halves what is written)",
    )
    ap.add_argument(
        "--profile",
        action="store_true",
        help="add each row a cProfile of one plain build_table call (own-time shares)",
    )
    ap.add_argument(
        "--cli",
        action="store_true",
        help="also time the command line: 'emscatter farm brdf' serially and with "
        "--scheduler local (process and cluster start included)",
    )
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    from emscatter.parallel import dask_client, open_executor

    # the cluster build_tables(client="local") starts (emscatter.parallel): thread caps in the
    # workers' environment, their statistical profiler off, the dashboard on a free port;
    # EMSCATTER_CACHE=off reaches them through this process's environment
    data = {"machine": machine(), "command": command(), "workers": args.workers, "rows": {}}
    serial_threads = thread_report()  # before the cluster: as the user's process starts
    client, close = open_executor("local", args.workers, 1)
    try:
        dc = dask_client(client)
        info = dc.scheduler_info().get("workers", {})
        data["threads"] = {
            "serial_process": serial_threads,
            "dask_workers": dc.run(thread_report),
            "dask_worker_nthreads": [int(w.get("nthreads", 0)) for w in info.values()],
        }
        for name in args.workloads:
            data["rows"][name] = run_workload(
                name, client, args.repeat, args.scale, args.resolution, args.profile, args.dtype
            )
        data["threads"]["dask_workers_end"] = dc.run(thread_report)
        data["threads"]["serial_process_end"] = thread_report()
    finally:
        close()
    if args.cli:
        data["rows"]["cli"] = run_cli(args.workers, args.repeat, args.scale, args.resolution)
    data["machine"]["load_average_end"] = list(os.getloadavg())
    print(json.dumps({k: {m: v[m] for m in v if m.endswith("speedup")}
                      for k, v in data["rows"].items()}, indent=1))  # fmt: skip
    print(write(args.out, data))


if __name__ == "__main__":
    main()
