"""Sionna RT solve time of a user's scene made rough in one call (``emscatter.radio.roughen``)
against the same scene with Sionna's built-in materials, with the new features on (issue 18).

Scene: Sionna's own ``simple_street_canyon`` at 28 GHz, one transmitter, six receivers, both
arrays one isotropic dual-polarized (``"VH"``) element — what the per-path XPD
(:mod:`emscatter.radio.xpd`) needs. Built-in: the scene's ITU materials with ``S = 0.3``
Lambertian (so that diffuse reflection costs the built-in model something too); emscatter:
``roughen(scene)`` (the default roughness table, one shared material per medium). Targets:
``PathSolver`` ≤ 1.3×, ``RadioMapSolver`` with diffuse ≤ 1.5× the built-in wall time; the
XPD map (:func:`emscatter.radio.xpd_map.polarized_radio_map`: a V and an H transmitter, the
V/H receive-port split) against two plain built-in maps (the same two transmitters). The two
are timed alternately after one warm-up call each (kernel compilation; emscatter's tables are
built once per frequency and reported apart); medians of ``--repeat`` calls. Process CPU time is
recorded beside wall time (the steadier measure on a loaded machine).

Run: ``.venv/bin/python benchmarks/bench_radio_scenes.py`` (≈ 3 min on 2 cores) — prints and
writes ``benchmarks/results/radio_scenes.json`` (atomically). ``--quick`` for a smoke run.
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import platform
import statistics
import time

TX = (20.0, 0.0, 10.0)
RX = ((60.0, 2.0, 1.5), (50.0, -3.0, 1.5), (75.0, 0.0, 1.5), (60.0, 5.0, 1.5),
      (-20.0, 0.0, 1.5), (24.0, 25.0, 1.5))  # fmt: skip


def _scene(f: float):
    import sionna.rt as rt

    sc = rt.load_scene(rt.scene.simple_street_canyon, merge_shapes=False)
    sc.frequency = f
    sc.tx_array = sc.rx_array = rt.PlanarArray(
        num_rows=1, num_cols=1, pattern="iso", polarization="VH"
    )
    sc.add(rt.Transmitter("tx", position=list(TX)))
    for i, p in enumerate(RX):
        sc.add(rt.Receiver(f"rx{i}", position=list(p)))
    return sc


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--samples", type=int, default=300_000)
    p.add_argument("--map-samples", type=int, default=300_000)
    p.add_argument("--frequency", type=float, default=28e9)
    p.add_argument("--quick", action="store_true")
    a = p.parse_args(argv)
    if a.quick:
        a.repeat, a.samples, a.map_samples = 1, 20_000, 20_000

    import mitsuba as mi
    import sionna.rt as rt

    from emscatter import radio
    from emscatter.radio import build_log, reset_build_log
    from emscatter.radio.xpd import path_xpd

    f = a.frequency
    builtin = _scene(f)
    for mat in builtin.radio_materials.values():
        mat.scattering_coefficient = 0.3
    rough = _scene(f)
    reset_build_log()
    t0 = time.perf_counter()
    radio.roughen(rough)
    roughen_seconds = time.perf_counter() - t0
    built = {"builtin": builtin, "emscatter": rough}
    path_solver, map_solver = rt.PathSolver(), rt.RadioMapSolver()
    xpd = {}

    def paths(sc, diffuse, kind):
        r = path_solver(sc, max_depth=3, samples_per_src=a.samples, refraction=True,
                        diffuse_reflection=diffuse, seed=1)  # fmt: skip
        xpd[kind] = path_xpd(r)["link_db"][:, 0].tolist()  # evaluates the fields

    def radio_map(sc, diffuse, kind):
        r = map_solver(
            sc, center=mi.Point3f(0.0, 0.0, 1.5), orientation=mi.Point3f(0, 0, 0),
            size=mi.Point2f(180.0, 120.0), cell_size=mi.Point2f(2.0, 2.0),
            samples_per_tx=a.map_samples, max_depth=3, refraction=True,
            diffuse_reflection=diffuse, seed=1,
        )  # fmt: skip
        r.path_gain.numpy()

    from emscatter.radio.xpd_map import polarized_radio_map

    map_kw = {"center": (0.0, 0.0, 1.5), "orientation": (0.0, 0.0, 0.0), "size": (180.0, 120.0),
              "cell_size": (2.0, 2.0), "samples_per_tx": a.map_samples, "max_depth": 3,
              "refraction": True}  # fmt: skip

    def xpd_map(sc, diffuse, kind):
        if kind == "emscatter":
            polarized_radio_map(sc, seed=1, diffuse_reflection=diffuse, **map_kw)
            return
        saved = sc.tx_array
        try:
            for pol in ("V", "H"):
                sc.tx_array = rt.PlanarArray(num_rows=1, num_cols=1, pattern="iso",
                                             polarization=pol)  # fmt: skip
                radio_map(sc, diffuse, kind)
        finally:
            sc.tx_array = saved

    configs = {
        "PathSolver specular+refraction, VH (XPD)": (paths, False, 1.3),
        "PathSolver +diffuse, VH (XPD)": (paths, True, 1.3),
        "RadioMapSolver +diffuse": (radio_map, True, 1.5),
        "RadioMapSolver +diffuse, XPD map (V, H tx)": (xpd_map, True, 1.5),
    }
    results = {
        "command": "python benchmarks/bench_radio_scenes.py" + (" --quick" if a.quick else ""),
        "scene": "sionna.rt.scene.simple_street_canyon",
        "machine": platform.processor() or platform.machine(),
        "cpus": os.cpu_count(),
        "frequency_hz": f,
        "samples": a.samples,
        "map_samples": a.map_samples,
        "repeat": a.repeat,
        "roughen_seconds": roughen_seconds,
        "load_average_start": os.getloadavg(),
        "configs": {},
    }
    for name, (fn, diffuse, target) in configs.items():
        first = {}
        for kind, sc in built.items():
            t0 = time.perf_counter()
            fn(sc, diffuse, kind)
            first[kind] = time.perf_counter() - t0
        times = {k: [] for k in built}
        cpu = {k: [] for k in built}
        for _ in range(a.repeat):
            for kind, sc in built.items():
                c0, t0 = time.process_time(), time.perf_counter()
                fn(sc, diffuse, kind)
                times[kind].append(time.perf_counter() - t0)
                cpu[kind].append(time.process_time() - c0)
        med = {k: statistics.median(v) for k, v in times.items()}
        med_cpu = {k: statistics.median(v) for k, v in cpu.items()}
        ratio = med["emscatter"] / med["builtin"]
        ratio_cpu = med_cpu["emscatter"] / med_cpu["builtin"]
        row = {"median_seconds": med, "all_seconds": times, "first_call_seconds": first,
               "ratio": ratio, "median_cpu_seconds": med_cpu, "ratio_cpu": ratio_cpu,
               "target": target, "meets_target": ratio <= target}  # fmt: skip
        if fn is paths:
            row["link_xpd_db"] = dict(xpd)
        results["configs"][name] = row
        print(
            f"{name:<42} built-in {med['builtin']:.3f} s, emscatter {med['emscatter']:.3f} s: "
            f"ratio {ratio:.2f} (target ≤ {target}; CPU-time ratio {ratio_cpu:.2f})",
            flush=True,
        )
    log = build_log()
    results["tables"] = {"builds": len(log), "seconds_total": sum(e["seconds"] for e in log)}
    results["load_average_end"] = os.getloadavg()
    out = (
        pathlib.Path(__file__).parent
        / "results"
        / ("radio_scenes_quick.json" if a.quick else "radio_scenes.json")
    )
    out.parent.mkdir(exist_ok=True)
    tmp = out.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(results, indent=2) + "\n")
    os.replace(tmp, out)
    print(f"tables: {len(log)} builds, {results['tables']['seconds_total']:.1f} s; wrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
