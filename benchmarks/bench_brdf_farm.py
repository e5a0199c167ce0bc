"""BRDF table farms (``emscatter.brdf.build_tables``) serially and on a 2-worker dask
LocalCluster, per workload: the tables a farm user builds — materials × wavelengths ×
roughness — with GO (whose kernel is the fastest: small tables, the farm's per-task cost
shows), PO, IEM and SPM (numpy/compiled builds that run on one core: what a farm is for).

Same work on both sides: the same specs, ``threads=1`` per table (serial: one core; farm: one
per worker), result cache off (``EMSCATTER_CACHE=off``), warm on both sides (this process and
the workers first build a few tables of the workload: numba cache loaded, material data read),
serial and farm alternated ``--repeat`` times in one process; the farm's tables checked
bit-identical to the serial ones. Each row records the per-table serial time, the serial run's
CPU utilisation (process CPU time / wall: 1.0 = one core busy; near 2 the serial build already
uses both cores and no 2-worker farm can reach 2×), the farm's speed-up (median serial /
median farm) with the default batching (about four tasks per worker) and, for GO, with one
table per task (``batch=1``, the previous behaviour) and with ``out_dir`` (the workers write
the ``.npz`` files, the serial side writes the same files).

    EMSCATTER_CACHE=off PYTHONPATH=src python benchmarks/bench_brdf_farm.py [--repeat 3]
        [--workloads go po iem spm] [--workers 2] [--scale 1.0] [--resolution 90 180]
        [--out brdf_farm] [--cli]

``--cli`` adds a row for the command line (``emscatter farm brdf`` serially and with
``--scheduler local``, each a fresh process: the interpreter's and the cluster's start are in
the time, as a user waits for them).

The default tables are small (GO 5 ms, IEM 20 ms of CPU each on the reference machine): the
farm's fixed costs show. Full-size tables (``--resolution 90 180``: 17.5 MB each in float32)
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

#: workload → (method, tables, (n_theta, n_phi), roughness σ [µm], ℓ [µm])
WORKLOADS = {
    "go": ("go", 64, (30, 60), (0.2, 0.3, 0.4, 0.5), 1.0),
    "po": ("po", 64, (24, 48), (0.03, 0.04, 0.05, 0.06), 0.6),
    "iem": ("iem", 64, (6, 12), (0.02, 0.03, 0.04, 0.05), 0.3),
    "spm": ("spm", 16, (8, 16), (0.01, 0.015, 0.02, 0.025), 0.5),
}
MATERIALS = ["Au", "Ag", "Cu", "Al"]
WAVELENGTHS = (450e-9, 550e-9, 650e-9, 750e-9)


def specs(workload: str, scale: float = 1.0, resolution=None) -> list[dict]:
    """The workload's specs: roughness × materials × wavelengths (one wavelength each), the
    first ``tables × scale`` of them (``resolution``: ``(n_theta, n_phi)`` instead)."""
    from emscatter.brdf import table_specs
    from emscatter.spectra import GaussianCorrelation

    method, n, res, sigmas, ell = WORKLOADS[workload]
    res = tuple(resolution) if resolution else res
    rough = [GaussianCorrelation(sigma=s * 1e-6, length=ell * 1e-6, dimension=2) for s in sigmas]
    wls = [[w] for w in WAVELENGTHS]
    sp = table_specs(rough, MATERIALS, wls, method=method, resolution=res, out_of_range="ignore")
    n = max(4, round(n * scale))
    return (sp * (1 + n // len(sp)))[:n] if n > len(sp) else sp[:n]


def _identical(a, b) -> bool:
    return all(x.values.tobytes() == y.values.tobytes() for x, y in zip(a, b, strict=True))


def _timed(fn) -> tuple[float, float, object]:
    t, c = time.perf_counter(), time.process_time()
    out = fn()
    return time.perf_counter() - t, time.process_time() - c, out


def run_workload(name, client, repeat, scale, resolution=None) -> dict:
    from emscatter.brdf import build_tables

    sp = specs(name, scale, resolution)
    variants = {"farm": {}}
    if name == "go":
        variants["farm_batch1"] = {"batch": 1}
        variants["farm_out_dir"] = {"out_dir": True}
    build_tables(sp[:4], progress=False)  # warm this process
    build_tables(sp[:8], client=client, progress=False)  # warm the workers
    serial_t, serial_cpu = [], []
    times = {v: [] for v in variants}
    identical = True
    with tempfile.TemporaryDirectory(prefix="emscatter-farm-") as tmp:
        for r in range(repeat):  # alternated in one process
            wall, cpu, serial = _timed(lambda: build_tables(sp, progress=False))
            serial_t.append(wall)
            serial_cpu.append(cpu / wall)
            for v, kw in variants.items():
                kw = dict(kw)
                if kw.get("out_dir"):
                    folder = Path(tmp) / f"{v}-{r}"
                    folder.mkdir()
                    kw["out_dir"] = folder
                wall, _, farm = _timed(
                    lambda kw=kw: build_tables(sp, client=client, progress=False, **kw)
                )
                times[v].append(wall)
                if "out_dir" in kw:
                    from emscatter.brdf.export_npz import read_npz

                    farm = [read_npz(p) for p in farm]
                identical = identical and _identical(serial, farm)
        if "farm_out_dir" in variants:  # the serial side writing the same files
            times["serial_out_dir"] = []
            for r in range(repeat):
                folder = Path(tmp) / f"serial-{r}"
                folder.mkdir()
                wall, _, _ = _timed(lambda f=folder: build_tables(sp, out_dir=f, progress=False))
                times["serial_out_dir"].append(wall)
    method, _, res, _, _ = WORKLOADS[name]
    res = tuple(resolution) if resolution else res
    med = statistics.median(serial_t)
    row = {
        "what": f"{len(sp)} {method.upper()} tables {res[0]}×{res[1]}, 1 wavelength each, "
        "threads=1 per table, warm, cache off",
        "tables": len(sp),
        "serial_s": serial_t,
        "per_table_serial_ms": 1e3 * med / len(sp),
        "serial_cpu_utilisation": statistics.median(serial_cpu),
        "identical": identical,
    }
    for v, ts in times.items():
        row[f"{v}_s"] = ts
    for v in variants:
        base = times["serial_out_dir"] if v == "farm_out_dir" else serial_t
        row[f"{v}_speedup"] = statistics.median(base) / statistics.median(times[v])
    print(f"{name:4s} {len(sp):3d} tables  serial {med:.2f} s ({row['per_table_serial_ms']:.0f} "
          f"ms/table, CPU ×{row['serial_cpu_utilisation']:.2f})  " + "  ".join(
              f"{v} ×{row[f'{v}_speedup']:.2f}" for v in variants) + f"  identical {identical}",
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
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[1] / "src")}
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
        "--cli",
        action="store_true",
        help="also time the command line: 'emscatter farm brdf' serially and with "
        "--scheduler local (process and cluster start included)",
    )
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    from emscatter.parallel import open_executor

    # the cluster build_tables(client="local") starts (emscatter.parallel): thread caps in the
    # workers' environment, their statistical profiler off, the dashboard on a free port;
    # EMSCATTER_CACHE=off reaches them through this process's environment
    data = {"machine": machine(), "command": command(), "workers": args.workers, "rows": {}}
    client, close = open_executor("local", args.workers, 1)
    try:
        for name in args.workloads:
            data["rows"][name] = run_workload(
                name, client, args.repeat, args.scale, args.resolution
            )
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
