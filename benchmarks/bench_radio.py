"""Sionna RT solver time with emscatter materials against Sionna's built-in RadioMaterial.

Same scene (the furnished room of ``emscatter.radio.scenes``), same media, same rays and depth:
built-in ``RadioMaterial`` (ITU ε′, σ; ``S = 0.3`` Lambertian where diffuse reflection is on)
against ``EmscatterRadioMaterial`` with the roughness of ``emscatter.radio.indoor.ROUGHNESS``.
Targets: ``PathSolver`` ≤ 1.3×, ``RadioMapSolver`` ≤ 1.5× the built-in time. The last config
("+diffuse, XPD port map") times the emscatter scene with the V/H port map of
``emscatter.radio.xpd_map`` (one solver run: one transmit polarization; an XPD map takes two)
against the built-in material with Sionna's own map. The two materials
are timed alternately in one run, after one warm-up call each (kernel compilation and the
emscatter tables — whose one-off cost is reported apart), and the medians of ``--repeat``
calls are compared. Process CPU time is recorded beside wall time: on a loaded machine its
ratio is the steadier measure of the per-ray cost (the target is on wall time).

``--transmission diffuse`` gives every rough slab of the emscatter scene diffuse transmission
(``EmscatterRadioMaterial(transmission="diffuse")``; RadioMapSolver samples it, PathSolver
cannot and runs as with ``"coherent"``) and writes ``radio_diffuse_transmission*.json``.

Run: ``.venv/bin/python benchmarks/bench_radio.py`` (≈ 3 min on 2 cores) — prints and writes
``benchmarks/results/radio.json``. ``--quick`` for a smoke run.
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import platform
import statistics
import time


def _versions():
    import drjit
    import mitsuba
    import sionna.rt

    return {
        "sionna-rt": sionna.rt.__version__,
        "mitsuba": mitsuba.__version__,
        "drjit": drjit.__version__,
    }


def _with_diffuse_transmission(make):
    """The same emscatter materials with ``transmission="diffuse"`` on every rough slab."""
    from emscatter.radio.material import EmscatterRadioMaterial

    def wrapped(obj, medium, thickness):
        m = make(obj, medium, thickness)
        if m.surface is None or m.thickness is None:
            return m
        return EmscatterRadioMaterial(
            m.name, surface=m.surface, medium=m.medium, thickness=m.thickness,
            transmission="diffuse", out_of_range="ignore",
        )  # fmt: skip

    return wrapped


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--repeat", type=int, default=5)
    p.add_argument("--samples", type=int, default=1_000_000)
    p.add_argument("--map-samples", type=int, default=1_000_000)
    p.add_argument("--frequency", type=float, default=28e9)
    p.add_argument("--quick", action="store_true")
    p.add_argument("--transmission", choices=("coherent", "diffuse"), default="coherent")
    a = p.parse_args(argv)
    if a.quick:
        a.repeat, a.samples, a.map_samples = 2, 20_000, 20_000

    import mitsuba as mi
    import sionna.rt as rt

    from emscatter.radio import build_log, indoor, scenes

    setup = indoor.SETUPS["room"]
    f = a.frequency
    built = {}
    for kind in ("builtin", "emscatter"):
        make = indoor.material_factory("sionna" if kind == "builtin" else "rough", f)
        if kind == "emscatter" and a.transmission == "diffuse":
            make = _with_diffuse_transmission(make)
        sc = scenes.load(setup.scene, f, make)
        indoor.add_devices(sc, setup)
        built[kind] = sc

    path_solver = rt.PathSolver()
    map_solver = rt.RadioMapSolver()

    def paths(sc, diffuse):
        r = path_solver(
            sc, max_depth=3, samples_per_src=a.samples, max_num_paths_per_src=a.samples,
            refraction=True, diffuse_reflection=diffuse,
        )  # fmt: skip
        r.a[0].numpy()  # force evaluation

    def radio_map(sc, diffuse):
        r = map_solver(
            sc, center=mi.Point3f(*setup.map_center), orientation=mi.Point3f(0, 0, 0),
            size=mi.Point2f(*setup.map_size), cell_size=mi.Point2f(0.1, 0.1),
            samples_per_tx=a.map_samples, max_depth=3, refraction=True,
            diffuse_reflection=diffuse,
        )  # fmt: skip
        r.path_gain.numpy()

    from emscatter.radio.xpd_map import _solve_ports

    def port_map(sc, diffuse):
        if sc is not built["emscatter"]:  # the reference: built-in material, Sionna's own map
            return radio_map(sc, diffuse)
        _solve_ports(sc, 42, {
            "center": mi.Point3f(*setup.map_center), "orientation": mi.Point3f(0, 0, 0),
            "size": mi.Point2f(*setup.map_size), "cell_size": mi.Point2f(0.1, 0.1),
            "samples_per_tx": a.map_samples, "max_depth": 3, "refraction": True,
            "diffuse_reflection": diffuse,
        })  # fmt: skip

    configs = {
        "PathSolver specular+refraction": (paths, False, 1.3),
        "PathSolver +diffuse": (paths, True, 1.3),
        "RadioMapSolver specular+refraction": (radio_map, False, 1.5),
        "RadioMapSolver +diffuse": (radio_map, True, 1.5),
        "RadioMapSolver +diffuse, XPD port map": (port_map, True, 1.5),
    }
    results = {
        "command": "python benchmarks/bench_radio.py"
        + (" --quick" if a.quick else "")
        + (" --transmission diffuse" if a.transmission == "diffuse" else ""),
        "transmission": a.transmission,
        "machine": platform.processor() or platform.machine(),
        "cpus": os.cpu_count(),
        "versions": _versions(),
        "frequency_hz": f,
        "samples": a.samples,
        "map_samples": a.map_samples,
        "repeat": a.repeat,
        "load_average_start": os.getloadavg(),
        "configs": {},
    }
    for name, (fn, diffuse, target) in configs.items():
        first = {}
        for kind, sc in built.items():  # warm-up: kernel compilation (+ emscatter tables)
            t0 = time.perf_counter()
            fn(sc, diffuse)
            first[kind] = time.perf_counter() - t0
        times = {"builtin": [], "emscatter": []}
        cpu = {"builtin": [], "emscatter": []}
        for _ in range(a.repeat):
            for kind, sc in built.items():
                c0, t0 = time.process_time(), time.perf_counter()
                fn(sc, diffuse)
                times[kind].append(time.perf_counter() - t0)
                cpu[kind].append(time.process_time() - c0)
        med = {k: statistics.median(v) for k, v in times.items()}
        med_cpu = {k: statistics.median(v) for k, v in cpu.items()}
        ratio = med["emscatter"] / med["builtin"]
        ratio_cpu = med_cpu["emscatter"] / med_cpu["builtin"]
        results["configs"][name] = {
            "median_seconds": med,
            "all_seconds": times,
            "first_call_seconds": first,
            "ratio": ratio,
            "median_cpu_seconds": med_cpu,
            "ratio_cpu": ratio_cpu,
            "target": target,
            "meets_target": ratio <= target,
        }
        print(
            f"{name:<38} built-in {med['builtin']:.3f} s, emscatter {med['emscatter']:.3f} s: "
            f"ratio {ratio:.2f} (target ≤ {target}; CPU-time ratio {ratio_cpu:.2f})",
            flush=True,
        )
    log = build_log()
    results["tables"] = {
        "builds": len(log),
        "seconds_total": sum(e["seconds"] for e in log),
        "per_build": [{k: e[k] for k in ("label", "method", "seconds")} for e in log],
    }
    results["load_average_end"] = os.getloadavg()
    print(
        f"tables: {len(log)} builds, {results['tables']['seconds_total']:.1f} s once per frequency"
    )
    stem = "radio" if a.transmission == "coherent" else "radio_diffuse_transmission"
    out = (
        pathlib.Path(__file__).parent
        / "results"
        / (f"{stem}_quick.json" if a.quick else f"{stem}.json")
    )
    out.parent.mkdir(exist_ok=True)
    out.write_text(json.dumps(results, indent=2) + "\n")
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
