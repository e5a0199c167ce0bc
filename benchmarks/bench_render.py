"""Rendering bridge: RGL ``.bsdf`` export time, and the plugin's render time against Mitsuba's
``roughconductor`` at equal samples.

    .venv/bin/python benchmarks/bench_render.py [--repeat 7]   # → benchmarks/results/render.json

Targets (issue 8): ``.bsdf`` export ≤ 10 s (32 θi × 64² sample nodes, an isotropic geometric-
optics table of gold, 90 × 90 × 180 nodes, 3 and 16 wavelengths; the table's build is not
timed); plugin render time ≤ 1.5 × ``roughconductor`` (same scene — a row of three spheres, and
one sphere filling most of the frame, under a procedural sky and a directional light, path
tracer depth 4 —, same resolution and samples, kernels compiled
before timing, renders of the two BSDFs interleaved, medians of ``--repeat``), in
``llvm_ad_rgb`` and ``llvm_ad_spectral`` (tables with 4 and 16 wavelengths).
Machine, versions and load averages are recorded; the ratio is the number to compare (both
renders share the machine's state), the seconds are not.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

from emscatter.brdf import build_table
from emscatter.brdf.export_rgl import write_rgl
from emscatter.io import write_json
from emscatter.materials import metal
from emscatter.spectra import GaussianCorrelation

HERE = Path(__file__).resolve().parent
ALPHA = 0.2
SURFACE = GaussianCorrelation(0.1e-6, 1e-6)  # α = 2σ/ℓ = 0.2


def _table(n_wl: int, resolution=(90, 180)):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return build_table(
            SURFACE,
            metal("Au"),
            np.linspace(360e-9, 830e-9, n_wl),
            method="go",
            resolution=resolution,
        )


def bench_export(repeat: int) -> dict:
    out = {}
    for n_wl in (3, 16):
        table = _table(n_wl)
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "gold.bsdf"
            times = []
            for _ in range(repeat):
                t0 = time.perf_counter()
                write_rgl(path, table, channels="spectral", n_theta_i=32, n_samples=64)
                times.append(time.perf_counter() - t0)
            size = path.stat().st_size
        out[f"{n_wl}_wavelengths"] = {
            "median_s": statistics.median(times),
            "times_s": times,
            "file_MiB": size / 2**20,
            "target_s": 10.0,
        }
        print(
            f"export, {n_wl} wavelengths: {statistics.median(times):.2f} s ({size / 2**20:.1f} MiB)"
        )
    return out


def bench_render(variant: str, n_wl: int, repeat: int, width: int, spp: int, spheres: int) -> dict:
    import drjit as dr
    import mitsuba as mi

    mi.set_variant(variant)
    from emscatter.render import mitsuba as em_mi
    from emscatter.render import scenes

    table = _table(n_wl)
    rc = {"type": "roughconductor", "distribution": "beckmann", "alpha": ALPHA, "material": "Au"}
    loaded = {
        name: mi.load_dict(scenes.sphere_row([b] * spheres, width=width, spp=spp))
        for name, b in (("roughconductor", rc), ("emscatter", em_mi.bsdf_dict(table)))
    }
    times = {name: [] for name in loaded}
    for rep in range(repeat + 1):  # the first round compiles the kernels
        for name, scene in loaded.items():
            t0 = time.perf_counter()
            img = mi.render(scene, seed=rep)
            dr.eval(img)
            dr.sync_thread()
            if rep:
                times[name].append(time.perf_counter() - t0)
    med = {k: statistics.median(v) for k, v in times.items()}
    ratio = med["emscatter"] / med["roughconductor"]
    print(f"render {variant}, {n_wl} wavelengths, {spheres} sphere(s): ratio {ratio:.2f} ({med})")
    return {
        "variant": variant,
        "spheres": spheres,
        "table_wavelengths": n_wl,
        "image": [width, spp],
        "median_s": med,
        "times_s": times,
        "ratio": ratio,
        "target_ratio": 1.5,
    }


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--repeat", type=int, default=7)
    p.add_argument("--width", type=int, default=320)
    p.add_argument("--spp", type=int, default=64)
    p.add_argument("--out", type=Path, default=HERE / "results" / "render.json")
    a = p.parse_args(argv)
    import mitsuba

    load_before = os.getloadavg()
    result = {
        "command": "benchmarks/bench_render.py "
        + f"--repeat {a.repeat} --width {a.width} --spp {a.spp}",
        "machine": {
            "platform": platform.platform(),
            "cpus": os.cpu_count(),
            "python": platform.python_version(),
        },
        "versions": {"mitsuba": mitsuba.__version__, "numpy": np.__version__},
        "export": bench_export(max(3, a.repeat // 2)),
        "render": [
            bench_render(variant, n_wl, a.repeat, a.width, a.spp, spheres)
            for spheres in (3, 1)  # a row, and one sphere filling most of the frame
            for variant, n_wl in (
                ("llvm_ad_rgb", 16),
                ("llvm_ad_spectral", 4),
                ("llvm_ad_spectral", 16),
            )
        ],
        "load_average": {"before": load_before, "after": os.getloadavg()},
    }
    write_json(a.out, result)
    print(f"wrote {a.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
