"""Benchmark of rough-surface generation (issue 2): speed against peers and memory.

Run:  .venv/bin/python benchmarks/bench_generate.py [--reps 5] [--out FILE.json]
(default output: benchmarks/results/generate.json)

Measures, in one process and interleaved (so that a change of machine load hits every
contender alike), the median wall time over ``--reps`` runs of:

* emscatter periodic FFT synthesis, fBm H = 0.7, 4096² (``generate_surface(periodic=True)``);
* one ``scipy.fft`` filter pass of the same size: ``rfft2 → multiply → irfft2``
  (``workers=-1``), the yardstick of the issue (target: emscatter ≤ 1.2× this);
* SurfaceTopography ``fourier_synthesis`` 4096² (H = 0.7), target: emscatter ≥ 2× faster;
* tamaas ``SurfaceGeneratorFilter2D`` and ``SurfaceGeneratorRandomPhase2D`` 4096²
  (``Isopowerlaw2D``, H = 0.7), if tamaas imports;
* exact 2-D fBm 1024² (Stein 2002) for H ∈ {0.1, 0.3, 0.5, 0.7, 0.9} (target < 1 s each);
* exact Gaussian 1024² (circulant embedding, σ = 1, ℓ = 16 samples).

Memory of the periodic path, as a multiple of the output array (target ≤ ~4×):
``tracemalloc`` peak (numpy allocations are traced; scipy.fft's internal scratch is not) and,
in a fresh subprocess, the growth of the peak resident set size (``VmHWM``), which includes
everything.

Process CPU time (all threads) and the minimum wall time are recorded beside the medians:
on a shared, loaded machine they show the work done when the wall-clock medians are
dominated by other processes (the load average at start and end is recorded).

Writes a table to stdout and the numbers to JSON with the machine description.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import time
import tracemalloc
from pathlib import Path

import numpy as np
import scipy
import scipy.fft as sfft

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import cpu_model  # noqa: E402

from emscatter.spectra import FractionalBrownian, GaussianCorrelation  # noqa: E402
from emscatter.surfaces.generate import generate_surface  # noqa: E402

N_BIG = 4096
N_EXACT = 1024
HURST_BIG = 0.7
HURSTS = (0.1, 0.3, 0.5, 0.7, 0.9)


def _cpu_model() -> str:
    return cpu_model()


def _machine() -> dict:
    info = {
        "nproc": os.cpu_count(),
        "cpu_affinity": len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else None,
        "cpu_model": _cpu_model(),
        "platform": platform.platform(),
        "python": sys.version.split()[0],
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "loadavg_start": os.getloadavg() if hasattr(os, "getloadavg") else None,
    }
    try:
        import SurfaceTopography

        info["SurfaceTopography"] = SurfaceTopography.__version__
    except Exception as exc:  # pragma: no cover - depends on the environment
        info["SurfaceTopography"] = f"unavailable: {exc}"
    try:
        import tamaas

        info["tamaas"] = tamaas.__version__
    except Exception as exc:  # pragma: no cover
        info["tamaas"] = f"unavailable: {exc!r}"
    return info


def _contenders() -> dict:
    """name → zero-argument callable doing one full generation."""
    fbm2 = FractionalBrownian(HURST_BIG, increment_rms=1.0, lag=1.0, dimension=2)
    rng = np.random.default_rng(12345)
    field = rng.standard_normal((N_BIG, N_BIG))
    ky = sfft.fftfreq(N_BIG)[:, None]
    kx = sfft.rfftfreq(N_BIG)[None, :]
    filt = np.hypot(ky, kx)
    filt[0, 0] = 1.0
    np.power(filt, -(HURST_BIG + 1.0), out=filt)

    def filter_pass():
        f = sfft.rfft2(field, workers=-1)
        f *= filt
        return sfft.irfft2(f, s=field.shape, workers=-1, overwrite_x=True)

    seeds = iter(range(10**6))
    out = {
        "emscatter_periodic_4096": lambda: generate_surface(
            fbm2, (N_BIG, N_BIG), 1.0, periodic=True, rng=next(seeds)
        ),
        "scipy_filter_pass_4096": filter_pass,
    }
    try:
        from SurfaceTopography.Generation import fourier_synthesis

        out["surfacetopography_fourier_synthesis_4096"] = lambda: fourier_synthesis(
            (N_BIG, N_BIG),
            (1.0, 1.0),
            hurst=HURST_BIG,
            c0=1.0,
            rng=np.random.default_rng(next(seeds)),
        ).heights()
    except Exception as exc:  # pragma: no cover
        print(f"SurfaceTopography skipped: {exc}")
    try:
        import tamaas as tm

        spec = tm.Isopowerlaw2D()
        spec.q0, spec.q1, spec.q2, spec.hurst = 1, 1, N_BIG // 2, HURST_BIG
        for name, cls in (
            ("tamaas_filter_4096", tm.SurfaceGeneratorFilter2D),
            ("tamaas_random_phase_4096", tm.SurfaceGeneratorRandomPhase2D),
        ):
            gen = cls([N_BIG, N_BIG])
            gen.spectrum = spec

            def run(gen=gen):
                gen.random_seed = next(seeds)
                return np.asarray(gen.buildSurface())

            out[name] = run
    except Exception as exc:  # pragma: no cover
        print(f"tamaas skipped: {exc!r}")
    for h in HURSTS:
        f = FractionalBrownian(h, dimension=2)
        out[f"emscatter_exact_fbm_1024_H{h:.1f}"] = lambda f=f: generate_surface(
            f, (N_EXACT, N_EXACT), 1.0, rng=next(seeds)
        )
    g = GaussianCorrelation(1.0, 16.0)
    out["emscatter_exact_gaussian_1024"] = lambda: generate_surface(
        g, (N_EXACT, N_EXACT), 1.0, rng=next(seeds)
    )
    return out


def _time_all(contenders: dict, reps: int) -> tuple[dict, dict]:
    """Wall and process-CPU seconds (all threads) of each contender, interleaved."""
    wall = {k: [] for k in contenders}
    cpu = {k: [] for k in contenders}
    for fn in contenders.values():  # warm-up (imports, FFT plans, thread pools)
        fn()
    for _ in range(reps):
        for name, fn in contenders.items():
            c0 = time.process_time()
            t0 = time.perf_counter()
            fn()
            wall[name].append(time.perf_counter() - t0)
            cpu[name].append(time.process_time() - c0)
    return wall, cpu


def _memory() -> dict:
    fbm2 = FractionalBrownian(HURST_BIG, dimension=2)
    out_bytes = N_BIG * N_BIG * 8
    tracemalloc.start()
    s = generate_surface(fbm2, (N_BIG, N_BIG), 1.0, periodic=True, rng=1)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    del s
    code = (
        (
            "import re\n"
            "from emscatter.spectra import FractionalBrownian\n"
            "from emscatter.surfaces.generate import generate_surface\n"
            "def vm(key):\n"
            "    t = open('/proc/self/status').read()\n"
            "    return int(re.search(key + r':\\s+(\\d+)', t).group(1)) * 1024\n"
            "f = FractionalBrownian(%r, dimension=2)\n"
            "generate_surface(f, (64, 64), 1.0, periodic=True, rng=0)\n"
            "base = vm('VmRSS')\n"
            "s = generate_surface(f, (%d, %d), 1.0, periodic=True, rng=1)\n"
            "print(vm('VmHWM') - base)\n"
        )
        .replace("%r", repr(HURST_BIG))
        .replace("%d, %d", f"{N_BIG}, {N_BIG}")
    )
    try:
        rss = int(
            subprocess.run(
                [sys.executable, "-c", code], capture_output=True, text=True, check=True
            ).stdout.strip()
        )
    except Exception as exc:  # pragma: no cover
        rss = None
        print(f"RSS measurement failed: {exc}")
    return {
        "output_bytes": out_bytes,
        "tracemalloc_peak_bytes": peak,
        "tracemalloc_peak_over_output": peak / out_bytes,
        "rss_peak_growth_bytes": rss,
        "rss_peak_growth_over_output": (rss / out_bytes) if rss else None,
    }


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--out", default=str(Path(__file__).parent / "results" / "generate.json"))
    args = ap.parse_args(argv)
    machine = _machine()
    contenders = _contenders()
    t0 = time.perf_counter()
    times, cpu = _time_all(contenders, max(args.reps, 1))
    med = {k: statistics.median(v) for k, v in times.items()}
    med_cpu = {k: statistics.median(v) for k, v in cpu.items()}
    best = {k: min(v) for k, v in times.items()}
    mem = _memory()
    machine["loadavg_end"] = os.getloadavg() if hasattr(os, "getloadavg") else None
    ours = med["emscatter_periodic_4096"]
    ratios = {
        "periodic_over_filter_pass": ours / med["scipy_filter_pass_4096"],
        "periodic_over_filter_pass_min_wall": best["emscatter_periodic_4096"]
        / best["scipy_filter_pass_4096"],
        "periodic_over_filter_pass_cpu": med_cpu["emscatter_periodic_4096"]
        / med_cpu["scipy_filter_pass_4096"],
    }
    for peer in (
        "surfacetopography_fourier_synthesis_4096",
        "tamaas_filter_4096",
        "tamaas_random_phase_4096",
    ):
        if peer in med:
            ratios[f"{peer}_over_periodic"] = med[peer] / ours
            ratios[f"{peer}_over_periodic_min_wall"] = best[peer] / best["emscatter_periodic_4096"]
    targets = {
        "periodic_within_1.2x_filter_pass": ratios["periodic_over_filter_pass"] <= 1.2,
        "periodic_2x_faster_than_peers": all(
            v >= 2.0 for k, v in ratios.items() if k.endswith("_over_periodic")
        ),
        "exact_fbm_1024_under_1s": all(
            med[f"emscatter_exact_fbm_1024_H{h:.1f}"] < 1.0 for h in HURSTS
        ),
        "periodic_memory_within_4x": mem["tracemalloc_peak_over_output"] <= 4.0,
    }
    result = {
        "command": f"python benchmarks/bench_generate.py --reps {args.reps}",
        "machine": machine,
        "reps": args.reps,
        "median_seconds": med,
        "min_seconds": best,
        "median_cpu_seconds": med_cpu,
        "all_seconds": times,
        "all_cpu_seconds": cpu,
        "ratios": ratios,
        "memory": mem,
        "targets_met": targets,
        "wall_seconds": time.perf_counter() - t0,
    }
    width = max(map(len, med))
    print(f"{'case':<{width}}  median [s]   min [s]   max [s]  median CPU [s]")
    for k, v in med.items():
        print(f"{k:<{width}}  {v:10.3f}  {best[k]:8.3f}  {max(times[k]):8.3f}  {med_cpu[k]:14.3f}")
    for k, v in ratios.items():
        print(f"{k}: {v:.2f}")
    print(
        f"periodic peak memory / output: tracemalloc {mem['tracemalloc_peak_over_output']:.2f}, "
        f"RSS growth {mem['rss_peak_growth_over_output'] or float('nan'):.2f}"
    )
    print("targets met:", targets)
    print("load average start/end:", machine["loadavg_start"], machine["loadavg_end"])
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(result, indent=2))
    print(f"wrote {args.out}")
    return result


if __name__ == "__main__":
    main()
