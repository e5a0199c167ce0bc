"""Integral-equation model: backscatter against SMRT 1.7 on the same inputs, bistatic throughput.

    PYTHONPATH=src .venv/bin/python benchmarks/bench_iem.py [--smrt /tmp/smrtvenv/bin/python]
        [--reps 15 --rounds 27 --round-seconds 0.2]
        → benchmarks/results/iem.json (and a table on stdout)

SMRT (a peer, never a dependency) runs in its scratch venv
(``python3 -m venv /tmp/smrtvenv && /tmp/smrtvenv/bin/pip install smrt``) as a timing server
kept running beside this script: per size, ``--rounds`` alternations of our calls and SMRT's
(each timed in its own process: at least ``--reps`` calls and ``--round-seconds`` of them, so
both run warm; median per round); the ratio is
the median over rounds of SMRT's time over ours, each round's two timings taken back to back
(the same machine state: this shared 2-core machine's speed drifts ×1.5–2 within minutes),
with its range over rounds. Without that interpreter the SMRT rows are skipped and said so.

Backscatter case (SMRT's own test case scaled to C band): exponential correlation,
σ = 0.4 cm, ℓ = 3 cm, 5.3 GHz (kσ = 0.44, kℓ = 3.3), ε = 15 + 2i, N incidence angles in
[0.5°, 70°]. Contenders: SMRT ``IEM_Fung92`` (co-pol, its default fixed 10 terms) and
``IIEM_Fung02`` (co-pol + multiple-scattering hv); emscatter ``iem`` co-pol only
(``crosspol=False``; AIEM, series to rtol = 1e-8), with hv, and its 1992 configuration.
Bistatic: random geometries over the hemisphere, all four polarizations, per second — the
single-scattering part (``crosspol=False``) on 20 000 geometries, and with the bistatic
multiple-scattering hv (default ``crosspol=True``, ``crosspol_order=8``) on 1 000, with the
compiled kernels and with ``EMSCATTER_KERNELS=numpy`` (the reference path).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from emscatter.io import write_json
from emscatter.solvers.iem import compiled as iem_jit
from emscatter.solvers.iem import model as iem
from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation

HERE = Path(__file__).resolve().parent
C = 299792458.0
FREQ, SIGMA, ELL, EPS = 5.3e9, 0.004, 0.03, 15 + 2j
SIZES = (1, 10, 90, 100, 1000)
FUNG92 = dict(fresnel="incident", complementary="fung92", first_order="model", shadowing=False,
              crosspol=False)  # fmt: skip

SMRT_SERVER = r"""
import json, sys, time, warnings
import numpy as np
from smrt.interface.iem_fung92 import IEM_Fung92
from smrt.interface.iiem_fung02 import IIEM_Fung02
f, s, l, er, ei = (float(a) for a in sys.argv[1:6])
warnings.simplefilter("ignore")
models = {
    "smrt_iem_fung92": (IEM_Fung92(roughness_rms=s, corr_length=l,
        autocorrelation_function="exponential", warning_handling="nothing"), 2),
    "smrt_iiem_fung02": (IIEM_Fung02(roughness_rms=s, corr_length=l,
        autocorrelation_function="exponential", warning_handling="nothing"), 3),
}
print("ready", flush=True)
for line in sys.stdin:  # "<model> <n angles> <reps> <seconds>" -> wall times [s], as JSON
    name, n, reps, seconds = line.split()
    model, npol = models[name]
    mu = np.cos(np.radians(np.linspace(0.5, 70.0, int(n))))
    t0 = time.perf_counter()
    model.diffuse_reflection_matrix(f, 1, complex(er, ei), mu, mu, np.pi, npol)
    reps = max(int(reps), int(float(seconds) / max(time.perf_counter() - t0, 1e-6)))
    t = []
    for _ in range(reps):
        t0 = time.perf_counter()
        model.diffuse_reflection_matrix(f, 1, complex(er, ei), mu, mu, np.pi, npol)
        t.append(time.perf_counter() - t0)
    print(json.dumps(t), flush=True)
"""


def _times(fn, reps: int, seconds: float = 0.0) -> list[float]:
    """Wall times of ``max(reps, seconds / one call)`` calls after a warm-up call."""
    t0 = time.perf_counter()
    fn()
    reps = max(reps, int(seconds / max(time.perf_counter() - t0, 1e-6)))
    t = []
    for _ in range(reps):
        t0 = time.perf_counter()
        fn()
        t.append(time.perf_counter() - t0)
    return t


def _median_time(fn, reps: int) -> float:
    return statistics.median(_times(fn, reps))


class _Smrt:
    """SMRT in its own interpreter, kept running: each request times one model at one size
    there, so our timings and SMRT's alternate within seconds (the same machine state)."""

    def __init__(self, python: str):
        args = [python, "-c", SMRT_SERVER, str(FREQ), str(SIGMA), str(ELL), str(EPS.real),
                str(EPS.imag)]  # fmt: skip
        # one BLAS thread: SMRT's work is elementwise numpy, and idle OpenBLAS workers would
        # spin on the cores our timings share between rounds
        env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
        self.proc = subprocess.Popen(args, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     text=True, env=env)  # fmt: skip
        if self.proc.stdout.readline().strip() != "ready":
            raise RuntimeError("the SMRT timing server did not start")

    def times(self, model: str, n: int, reps: int, seconds: float = 0.0) -> list[float]:
        self.proc.stdin.write(f"{model} {n} {reps} {seconds}\n")
        self.proc.stdin.flush()
        return json.loads(self.proc.stdout.readline())

    def close(self) -> None:
        self.proc.stdin.close()
        self.proc.wait(timeout=60)


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--smrt", default="/tmp/smrtvenv/bin/python")
    ap.add_argument("--reps", type=int, default=7, help="fewest calls per timing (median)")
    ap.add_argument(
        "--round-seconds",
        type=float,
        default=0.2,
        help="each contender's share of a round: as many calls as fit (warm caches)",
    )
    ap.add_argument(
        "--rounds",
        type=int,
        default=27,
        help="alternations of our timing and SMRT's per size (ratio: their median)",
    )
    ap.add_argument("--out", type=Path, default=HERE / "results" / "iem.json")
    args = ap.parse_args(argv)
    k = 2 * math.pi * FREQ / C
    rough = ExponentialCorrelation(SIGMA, ELL)
    times: dict[str, float] = {}
    smrt: dict = {}
    rounds: dict[str, list[float]] = {}
    server = _Smrt(args.smrt) if Path(args.smrt).exists() else None
    if server is None:
        smrt = {"skipped": f"no SMRT interpreter at {args.smrt}"}
    for n in SIZES:
        th = np.radians(np.linspace(0.5, 70.0, n))

        def run(th=th, **kw):
            return lambda: iem.bistatic(rough, EPS, k, th, th, math.pi, coherent=False, **kw)

        # co-pol against SMRT iem_fung92: `--rounds` alternations of `--reps` calls each
        # (and, where the kernel splits over threads, ours on one thread too)
        ours_r, one_r, theirs_r = [], [], []
        chunk = getattr(iem_jit, "BACK_MIN_CHUNK", None)  # None: a version without threads
        split = chunk is not None and n >= 2 * chunk
        for _ in range(args.rounds):
            sec = args.round_seconds
            ours_r.append(statistics.median(_times(run(crosspol=False), args.reps, sec)))
            if split:
                one_r.append(
                    statistics.median(_times(run(crosspol=False, threads=1), args.reps, sec))
                )
            if server is not None:
                theirs_r.append(
                    statistics.median(server.times("smrt_iem_fung92", n, args.reps, sec))
                )
        times[f"iem_copol/{n}"] = statistics.median(ours_r)
        if split:
            times[f"iem_copol_one_thread/{n}"] = statistics.median(one_r)
        if server is not None:
            smrt[f"smrt_iem_fung92/{n}"] = statistics.median(theirs_r)
            rounds[str(n)] = [b / a for a, b in zip(ours_r, theirs_r, strict=True)]
            if split:
                rounds[f"{n}/one_thread"] = [b / a for a, b in zip(one_r, theirs_r, strict=True)]
        times[f"iem_fung92/{n}"] = _median_time(run(**FUNG92), args.reps)
        if n <= 100:
            times[f"iem_with_hv/{n}"] = _median_time(run(), max(3, args.reps // 2))
            if server is not None:
                smrt[f"smrt_iiem_fung02/{n}"] = statistics.median(
                    server.times("smrt_iiem_fung02", n, max(3, args.reps // 2))
                )
    if server is not None:
        server.close()
    # bistatic throughput
    rng = np.random.default_rng(0)
    m = 20000
    ti, ts = rng.uniform(0, 1.3, m), rng.uniform(0, 1.4, m)
    ps = rng.uniform(0, 2 * math.pi, m)
    throughput = {}
    cases = (
        ("gaussian_ks0.5", GaussianCorrelation(0.5 / (2 * math.pi), 0.6)),
        ("exponential_ks1.1", ExponentialCorrelation(1.1 / (2 * math.pi), 0.9)),
    )
    for label, r in cases:
        for rec in (True, False):
            t = _median_time(
                lambda r=r, rec=rec: iem.bistatic(
                    r,
                    EPS,
                    2 * math.pi,
                    ti,
                    ts,
                    ps,
                    coherent=False,
                    reciprocal=rec,
                    crosspol=False,
                ),  # fmt: skip
                3,
            )
            throughput[f"{label}/reciprocal={rec}"] = m / t
        saved = os.environ.get("EMSCATTER_KERNELS")
        for mode in ("auto", "numpy"):  # with the bistatic multiple-scattering hv
            os.environ["EMSCATTER_KERNELS"] = mode
            n_hv = 1000 if mode == "auto" else 200
            t = _median_time(
                lambda r=r, n=n_hv: iem.bistatic(
                    r, EPS, 2 * math.pi, ti[:n], ts[:n], ps[:n], coherent=False
                ),  # fmt: skip
                3,
            )
            throughput[f"{label}/with_hv/kernels={mode}"] = n_hv / t
        if saved is None:
            os.environ.pop("EMSCATTER_KERNELS")
        else:
            os.environ["EMSCATTER_KERNELS"] = saved
    out = {
        "machine": {
            "nproc": os.cpu_count(),
            "python": sys.version.split()[0],
            "platform": platform.platform(),
            "numpy": np.__version__,
            "load_average": os.getloadavg(),
        },
        "case": {
            "frequency_hz": FREQ,
            "sigma_m": SIGMA,
            "ell_m": ELL,
            "eps": str(EPS),
            "k_sigma": k * SIGMA,
            "k_l": k * ELL,
            "correlation": "exponential",
            "theta_deg": "N angles in [0.5, 70]",
        },  # fmt: skip
        "seconds_median": times,
        "smrt_seconds_median": smrt,
        "bistatic_geometries_per_second": throughput,
    }
    if "skipped" not in smrt:
        # per size: the median over rounds of (SMRT median / our median), each round's two
        # timings taken back to back; and the range over rounds
        out["ratio_smrt_fung92_over_iem_copol"] = {
            n: statistics.median(rounds[str(n)]) for n in SIZES
        }
        out["ratio_smrt_fung92_over_iem_copol_range"] = {
            n: [min(rounds[str(n)]), max(rounds[str(n)])] for n in SIZES
        }
        out["ratio_smrt_fung92_over_iem_copol_one_thread"] = {
            key.split("/")[0]: [statistics.median(v), min(v), max(v)]
            for key, v in rounds.items()
            if key.endswith("/one_thread")
        }
        out["ratio_smrt_iiem_over_iem_with_hv"] = {
            n: smrt[f"smrt_iiem_fung02/{n}"] / times[f"iem_with_hv/{n}"]
            for n in SIZES
            if f"smrt_iiem_fung02/{n}" in smrt
        }
    out["command"] = (
        f"PYTHONPATH=src python benchmarks/bench_iem.py --reps {args.reps} --rounds {args.rounds}"
        f" --round-seconds {args.round_seconds}"
    )
    write_json(args.out, out)
    print(json.dumps({k_: v for k_, v in out.items() if k_ != "machine"}, indent=1))
    return out


if __name__ == "__main__":
    main()
