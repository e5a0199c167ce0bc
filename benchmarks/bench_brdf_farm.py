"""64 BRDF tables (4 roughness × 4 materials × 4 wavelengths, GO 30 × 60) serially and on a
2-worker dask LocalCluster (``emscatter.brdf.build_tables``), warm on both sides (the workers
load the numba cache on a warm-up farm first), result cache off, the two alternated ``--repeat``
times in one process; tables checked bit-identical.

    EMSCATTER_CACHE=off PYTHONPATH=src python benchmarks/bench_brdf_farm.py [--repeat 3]

Writes ``benchmarks/results/brdf_farm.json``. The issue's target is ≥ 1.7× on 2 cores.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

import numpy as np


def specs(n_theta=30, n_phi=60):
    from emscatter.brdf import table_specs
    from emscatter.spectra import GaussianCorrelation

    rough = [
        GaussianCorrelation(sigma=s * 1e-6, length=1e-6, dimension=2) for s in (0.2, 0.3, 0.4, 0.5)
    ]
    mats = ["Au", "Ag", "Cu", "Al"]
    wls = [[w] for w in (450e-9, 550e-9, 650e-9, 750e-9)]
    return table_specs(
        rough, mats, wls, method="go", resolution=(n_theta, n_phi), out_of_range="ignore"
    )


def main() -> None:
    os.environ.setdefault("EMSCATTER_CACHE", "off")
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--n-theta", type=int, default=30)
    ap.add_argument("--n-phi", type=int, default=60)
    args = ap.parse_args()
    from dask.distributed import Client, LocalCluster

    from emscatter.brdf import build_tables
    from emscatter.io import write_json

    sp = specs(args.n_theta, args.n_phi)
    assert len(sp) == 64
    build_tables(sp[:4], progress=False)  # warm this process
    env = {"NUMBA_NUM_THREADS": "1", "EMSCATTER_CACHE": "off"}
    with (
        LocalCluster(
            n_workers=args.workers,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
            env=env,
        ) as cluster,
        Client(cluster) as client,
    ):
        build_tables(sp[: 2 * args.workers], client=client, progress=False)  # warm the workers
        serial_t, farm_t = [], []
        for _ in range(args.repeat):  # alternated in one process
            t = time.perf_counter()
            serial = build_tables(sp, progress=False)
            serial_t.append(time.perf_counter() - t)
            t = time.perf_counter()
            farm = build_tables(sp, client=client, progress=False)
            farm_t.append(time.perf_counter() - t)
        identical = all(
            a.values.tobytes() == b.values.tobytes() for a, b in zip(serial, farm, strict=True)
        )
    out = {
        "what": f"64 GO tables {args.n_theta}x{args.n_phi}, 1 wavelength each, warm, cache off",
        "command": "EMSCATTER_CACHE=off PYTHONPATH=src python benchmarks/bench_brdf_farm.py "
        f"--repeat {args.repeat} --workers {args.workers} "
        f"--n-theta {args.n_theta} --n-phi {args.n_phi}",
        "cpus": os.cpu_count(),
        "workers": args.workers,
        "serial_s": serial_t,
        "farm_s": farm_t,
        "speedup_median": float(np.median(serial_t) / np.median(farm_t)),
        "identical": identical,
        "per_table_serial_ms": 1e3 * float(np.median(serial_t)) / 64,
    }
    print(json.dumps(out, indent=1))
    name = (
        "brdf_farm.json"
        if (args.n_theta, args.n_phi) == (30, 60)
        else f"brdf_farm_{args.n_theta}x{args.n_phi}.json"
    )
    write_json(Path(__file__).parent / "results" / name, out)


if __name__ == "__main__":
    main()
