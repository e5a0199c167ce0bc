"""Sionna RT solver time with textured (anisotropic) emscatter materials.

The furnished room of ``emscatter.radio.scenes`` at 28 GHz, every rough medium of
``emscatter.radio.indoor.ROUGHNESS`` three ways: Sionna's built-in ``RadioMaterial`` (S = 0.3
Lambertian), the isotropic emscatter material (σ, ℓ) and the textured one (σ, ℓx = ℓ,
ℓy = ℓ/2, vertical texture direction: every wall's ℓx axis vertical, floor and ceiling by the
degenerate rule). Same rays and depth; timed alternately after one warm-up call each (kernels
and tables; the tables' one-off cost is reported apart); medians of ``--repeat`` calls, with
the process CPU time beside the wall time (the steadier ratio on a loaded machine).

The per-ray cost does not depend on which emscatter solver filled the tables, so both emscatter
kinds use ``method="spm"`` tables (fast to build with the ψ axis; ``out_of_range="ignore"``).

Run: ``.venv/bin/python benchmarks/bench_radio_texture.py`` — prints and writes
``benchmarks/results/radio_texture.json``; ``--quick`` for a smoke run.
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import statistics
import time


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--repeat", type=int, default=5)
    p.add_argument("--samples", type=int, default=1_000_000)
    p.add_argument("--map-samples", type=int, default=1_000_000)
    p.add_argument("--quick", action="store_true")
    a = p.parse_args(argv)
    if a.quick:
        a.repeat, a.samples, a.map_samples = 3, 100_000, 100_000

    import mitsuba as mi
    import sionna.rt as rt

    from emscatter.radio import build_log, indoor, scenes
    from emscatter.radio.material import EmscatterRadioMaterial
    from emscatter.radio.tables import TableOptions
    from emscatter.spectra import GaussianCorrelation

    f = 28e9
    setup = indoor.SETUPS["room"]
    opts = TableOptions(n_theta=24, n_alpha=19, n_s=48, n_psi=5)

    def factory(kind):
        if kind == "builtin":
            return indoor.material_factory("sionna", f)

        def make(obj, medium, thickness):
            s = indoor.ROUGHNESS.get(medium)
            kw = {}
            if s is not None and kind == "textured":
                s = GaussianCorrelation(sigma=s.sigma, length=s.length, length_y=s.length / 2)
                kw["texture_direction"] = (0.0, 0.0, 1.0)
            return EmscatterRadioMaterial(
                f"{kind}-{obj}", surface=s, medium=indoor.medium_at(medium, f),
                thickness=thickness, method="spm", out_of_range="ignore", table_options=opts,
                **kw,
            )  # fmt: skip

        return make

    built = {}
    for kind in ("builtin", "isotropic", "textured"):
        sc = scenes.load(setup.scene, f, factory(kind))
        indoor.add_devices(sc, setup)
        built[kind] = sc
    path_solver, map_solver = rt.PathSolver(), rt.RadioMapSolver()

    def paths(sc):
        r = path_solver(
            sc, max_depth=3, samples_per_src=a.samples, max_num_paths_per_src=a.samples,
            refraction=True, diffuse_reflection=True,
        )  # fmt: skip
        r.a[0].numpy()

    def radio_map(sc):
        r = map_solver(
            sc, center=mi.Point3f(*setup.map_center), orientation=mi.Point3f(0, 0, 0),
            size=mi.Point2f(*setup.map_size), cell_size=mi.Point2f(0.1, 0.1),
            samples_per_tx=a.map_samples, max_depth=3, refraction=True, diffuse_reflection=True,
        )  # fmt: skip
        r.path_gain.numpy()

    results = {
        "command": "python benchmarks/bench_radio_texture.py" + (" --quick" if a.quick else ""),
        "cpus": os.cpu_count(),
        "samples": a.samples,
        "map_samples": a.map_samples,
        "repeat": a.repeat,
        "load_average_start": os.getloadavg(),
        "configs": {},
    }
    for name, fn in (("PathSolver +diffuse", paths), ("RadioMapSolver +diffuse", radio_map)):
        first = {}
        for kind, sc in built.items():
            t0 = time.perf_counter()
            fn(sc)
            first[kind] = time.perf_counter() - t0
        wall = {k: [] for k in built}
        cpu = {k: [] for k in built}
        for _ in range(a.repeat):
            for kind, sc in built.items():
                c0, t0 = time.process_time(), time.perf_counter()
                fn(sc)
                wall[kind].append(time.perf_counter() - t0)
                cpu[kind].append(time.process_time() - c0)
        med = {k: statistics.median(v) for k, v in wall.items()}
        mcpu = {k: statistics.median(v) for k, v in cpu.items()}
        row = {
            "median_seconds": med,
            "median_cpu_seconds": mcpu,
            "first_call_seconds": first,
            "textured_over_isotropic": med["textured"] / med["isotropic"],
            "textured_over_isotropic_cpu": mcpu["textured"] / mcpu["isotropic"],
            "textured_over_builtin": med["textured"] / med["builtin"],
            "isotropic_over_builtin": med["isotropic"] / med["builtin"],
        }
        results["configs"][name] = row
        print(
            f"{name:<24} built-in {med['builtin']:.3f} s, isotropic {med['isotropic']:.3f} s, "
            f"textured {med['textured']:.3f} s: textured/isotropic "
            f"{row['textured_over_isotropic']:.2f} (CPU {row['textured_over_isotropic_cpu']:.2f})"
            f", textured/built-in {row['textured_over_builtin']:.2f}",
            flush=True,
        )
    log = build_log()
    results["tables"] = [
        {k: e[k] for k in ("label", "method", "bistatic_points", "seconds")} for e in log
    ]
    results["load_average_end"] = os.getloadavg()
    out = pathlib.Path(__file__).parent / "results"
    out.mkdir(exist_ok=True)
    path = out / ("radio_texture_quick.json" if a.quick else "radio_texture.json")
    tmp = path.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(results, indent=2) + "\n")
    tmp.replace(path)  # atomic
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
