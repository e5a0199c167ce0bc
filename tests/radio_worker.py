"""Sionna RT checks run in a fresh interpreter (Dr.Jit variants are per process, and pytest-xdist
workers also run Mitsuba tests): ``python tests/radio_worker.py CHECK [CHECK ...]`` prints one
JSON object ``{check: result}`` on its last line. Used by tests/test_radio_sionna.py.
"""

from __future__ import annotations

import math
import os
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np


def _paths_power(paths):
    re, im = (np.asarray(x.numpy()) for x in paths.a)
    p = (re**2 + im**2)[:, 0, 0, 0, :]
    tau = np.asarray(paths.tau.numpy())
    tau = tau[:, 0, 0, 0, :] if tau.ndim == 5 else tau[:, 0, :]
    return p, tau


def _add_devices(scene, tx, rxs, pol="V"):
    import sionna.rt as rt

    arr = rt.PlanarArray(num_rows=1, num_cols=1, pattern="iso", polarization=pol)
    scene.tx_array = arr
    scene.rx_array = arr
    scene.add(rt.Transmitter("tx", position=list(tx)))
    for i, p in enumerate(rxs):
        scene.add(rt.Receiver(f"rx{i}", position=list(p)))


def _both_solvers(scene):
    """Path powers (PathSolver) and radio-map path gains (RadioMapSolver, 6 m × 6 m at 1.5 m
    height, 0.5 m cells) of ``scene`` with two bounces and diffuse reflection."""
    import mitsuba as mi
    import sionna.rt as rt

    paths = rt.PathSolver()(scene, max_depth=2, samples_per_src=50_000, diffuse_reflection=True)
    p, _ = _paths_power(paths)
    rm = rt.RadioMapSolver()(
        scene, center=mi.Point3f(0, 0, 1.5), orientation=mi.Point3f(0, 0, 0),
        size=mi.Point2f(6, 6), cell_size=mi.Point2f(0.5, 0.5), samples_per_tx=50_000,
        max_depth=2, diffuse_reflection=True,
    )  # fmt: skip
    return p, np.asarray(rm.path_gain.numpy())


def check_flat_builtin():
    """Flat emscatter material vs Sionna's RadioMaterial, per path and per radio-map cell."""
    import mitsuba as mi
    import sionna.rt as rt

    from emscatter.radio import indoor, scenes
    from emscatter.radio.material import EmscatterRadioMaterial

    f = 28e9
    setup = indoor.SETUPS["room"]
    out = {}

    def builtin(obj, medium, thickness):
        er, sig = indoor.medium_at(medium, f).eps_real_and_conductivity(f)
        return rt.RadioMaterial(
            f"b-{obj}", thickness=thickness, relative_permittivity=float(er),
            conductivity=float(sig),
        )  # fmt: skip

    def flat(obj, medium, thickness):
        return EmscatterRadioMaterial(f"e-{obj}", medium=medium, thickness=thickness)

    results = {}
    for name, make in (("builtin", builtin), ("emscatter", flat)):
        scene = scenes.load(setup.scene, f, make)
        _add_devices(scene, setup.tx, setup.rx)
        paths = rt.PathSolver(deterministic=True)(
            scene, max_depth=3, samples_per_src=20_000, refraction=True
        )
        p, tau = _paths_power(paths)
        rm = rt.RadioMapSolver()(
            scene, center=mi.Point3f(3.0, 2.5, 1.2), orientation=mi.Point3f(0, 0, 0),
            size=mi.Point2f(6.0, 5.0), cell_size=mi.Point2f(0.25, 0.25), samples_per_tx=20_000,
            max_depth=3, refraction=True, seed=3,
        )  # fmt: skip
        results[name] = (p, tau, np.asarray(rm.path_gain.numpy())[0])
    (pb, tb, mb), (pe, te, me) = results["builtin"], results["emscatter"]
    worst = 0.0
    npaths = 0
    same_delays = True
    for i in range(pb.shape[0]):
        kb, ke = pb[i] > 0, pe[i] > 0
        ob, oe = np.argsort(tb[i][kb]), np.argsort(te[i][ke])
        xb, xe = pb[i][kb][ob], pe[i][ke][oe]
        if xb.size != xe.size:
            same_delays = False
            continue
        same_delays &= bool(np.allclose(tb[i][kb][ob], te[i][ke][oe], rtol=0, atol=1e-12))
        worst = max(worst, float(np.max(np.abs(10 * np.log10(xe / xb)))))
        npaths += int(xb.size)
    both = (mb > 0) & (me > 0)
    out["paths"] = npaths
    out["same_delays"] = same_delays
    out["max_path_db"] = worst
    out["map_cells"] = int(both.sum())
    out["map_same_support"] = bool(np.array_equal(mb > 0, me > 0))
    out["max_map_db"] = float(np.max(np.abs(10 * np.log10(me[both] / mb[both]))))
    return out


def check_xml_plugin():
    """An XML scene names the class; rough material runs in both solvers with diffuse on."""

    import emscatter.radio.material as m
    from emscatter.radio import scenes

    # The files live only until Sionna has read them (load_scene returns): nothing is left in
    # the temp dir, also when loading fails.
    with tempfile.TemporaryDirectory(prefix="radio-xml-") as tmp:
        d = Path(tmp)
        scenes.write_ply(d / "floor.ply", scenes.quad([-5, -5, 0], [10, 0, 0], [0, 10, 0]))
        (d / "scene.xml").write_text(
            '<scene version="2.1.0">\n'
            f'<bsdf type="{m.PLUGIN_NAME}" id="rough-floor">'
            '<string name="medium" value="concrete"/>'
            '<float name="rms_height" value="0.0004"/>'
            '<float name="correlation_length" value="0.004"/>'
            '<float name="thickness" value="0.2"/></bsdf>\n'
            '<shape type="ply" id="floor"><string name="filename" value="floor.ply"/>'
            '<ref id="rough-floor" name="bsdf"/></shape>\n</scene>\n'
        )
        # a user's XML file through emscatter's loader: its own materials kept
        scene = scenes.load(d / "scene.xml", 28e9)
    mat = scene.get("rough-floor")
    _add_devices(scene, (0, 0, 2.0), [(2.0, 0.5, 1.5)])
    p, pg = _both_solvers(scene)
    return {
        "type": type(mat).__name__,
        "surface_sigma": float(mat.surface.sigma),
        "thickness": mat.thickness,
        "method": mat.active_tables.method,
        "num_paths": int(np.count_nonzero(p)),
        "paths_finite": bool(np.all(np.isfinite(p))),
        "map_finite": bool(np.all(np.isfinite(pg))),
        "map_cells_lit": int(np.count_nonzero(pg > 0)),
        "describe": mat.to_string(),
    }


def check_evaluations():
    """Tables only for the used materials at the frequencies actually solved."""
    import sionna.rt as rt

    import emscatter as em
    from emscatter.radio import build_log, reset_build_log, scenes
    from emscatter.radio.material import EmscatterRadioMaterial
    from emscatter.radio.tables import TableOptions, clear_cache

    clear_cache()
    reset_build_log()
    spec = scenes.SceneSpec(
        meshes={
            "floor": scenes.quad([-4, -4, 0], [8, 0, 0], [0, 8, 0]),
            "wall": scenes.quad([4, -4, 0], [0, 8, 0], [0, 0, 3]),
        },
        media={"floor": ("concrete", 0.2), "wall": ("plasterboard", 0.0125)},
    )
    surfaces = {
        "floor": em.GaussianCorrelation(sigma=0.31e-3, length=4e-3),
        "wall": em.GaussianCorrelation(sigma=0.07e-3, length=2e-3),
    }

    opts = TableOptions(n_cos=65, n_cos_spm=9, n_theta=16, n_alpha=13, n_s=32)

    def make(obj, medium, thickness):
        return EmscatterRadioMaterial(obj + "-mat", surface=surfaces[obj], medium=medium,
                                      thickness=thickness, table_options=opts)  # fmt: skip

    # Loaded at Sionna's default 3.5 GHz, then moved: nothing may be built at 3.5 GHz.
    sc = scenes.load(spec, 3.5e9, make)
    unused = EmscatterRadioMaterial(
        "unused-mat", surface=em.GaussianCorrelation(sigma=0.5e-3, length=5e-3), medium="brick",
        table_options=opts,
    )  # fmt: skip
    sc.add(unused)
    _add_devices(sc, (0, 0, 2.0), [(2.0, 1.0, 1.5)])
    log = []
    import mitsuba as mi

    for f in (28e9, 140e9, 28e9):
        sc.frequency = f
        rt.PathSolver()(sc, max_depth=2, samples_per_src=20_000, diffuse_reflection=True)
        rt.RadioMapSolver()(
            sc, center=mi.Point3f(0, 0, 1.5), orientation=mi.Point3f(0, 0, 0),
            size=mi.Point2f(4, 4), cell_size=mi.Point2f(1, 1), samples_per_tx=10_000,
            max_depth=2, diffuse_reflection=True,
        )  # fmt: skip
        log.append([(e["label"], e["frequency"]) for e in build_log()])
    used = {m.name: m.is_used for m in sc.radio_materials.values()}
    return {
        "log": [[list(x) for x in step] for step in log],
        "used": used,
        "unused_tables": sorted(unused.tables),
        "points": [e["bistatic_points"] for e in build_log()],
    }


def check_errors():
    """Out-of-band (used or not), reuse in a second scene, bad props."""
    import sionna.rt as rt

    import emscatter as em
    from emscatter.radio import scenes
    from emscatter.radio.material import EmscatterRadioMaterial

    out = {}
    spec = scenes.plate(4.0)
    sc = scenes.load(spec, 28e9, lambda o, m, t: EmscatterRadioMaterial("p", medium="concrete"))
    metal = EmscatterRadioMaterial("idle-metal", medium="metal")  # ITU metal: 1–100 GHz
    sc.add(metal)
    try:
        sc.frequency = 140e9
        out["out_of_band"] = None
    except ValueError as exc:
        out["out_of_band"] = f"{type(exc).__name__}: {exc}"
    sc2 = rt.load_scene()
    try:
        sc2.add(metal)
        out["reuse"] = None
    except ValueError as exc:
        out["reuse"] = str(exc)
    try:
        EmscatterRadioMaterial("w", surface=em.GaussianCorrelation(sigma=1e-3, length=1e-2),
                               medium="concrete", thickness=-1)  # fmt: skip
        out["thickness"] = None
    except ValueError as exc:
        out["thickness"] = str(exc)
    try:
        EmscatterRadioMaterial("w", eps_real=4.0, conductivity=-0.1)
        out["conductivity"] = None
    except ValueError as exc:
        out["conductivity"] = str(exc)
    for key, kwargs in (
        ("unknown", {"medium": "unobtainium"}),
        ("method", {"medium": "concrete", "method": "sqm"}),
        ("policy", {"medium": "concrete", "out_of_range": "nan"}),
        (
            "anisotropic",
            {"medium": "concrete",
             "surface": em.GaussianCorrelation(sigma=1e-4, length=5e-3, length_y=1e-2)},
        ),
    ):  # fmt: skip
        try:
            EmscatterRadioMaterial("w", **kwargs)
            out[key] = None
        except ValueError as exc:
            out[key] = str(exc)
    return out


def check_rough_solvers():
    """Rough materials at 140 GHz in both solvers with every interaction type on (specular,
    diffuse, refraction, diffraction): finite, non-negative, and energy stays below the
    transmitter's (path gain < 1)."""
    import mitsuba as mi
    import sionna.rt as rt

    from emscatter.radio import indoor, scenes
    from emscatter.radio.tables import TableOptions

    f = 140e9
    setup = indoor.SETUPS["room"]
    opts = TableOptions(n_cos=65, n_cos_spm=9, n_theta=16, n_alpha=13, n_s=32)
    scene = scenes.load(setup.scene, f, indoor.material_factory("rough", f, table_options=opts))
    _add_devices(scene, setup.tx, setup.rx)
    paths = rt.PathSolver()(
        scene, max_depth=2, samples_per_src=20_000, refraction=True, diffuse_reflection=True,
        diffraction=True,
    )  # fmt: skip
    p, tau = _paths_power(paths)
    types = np.asarray(paths.interactions.numpy())
    rm = rt.RadioMapSolver()(
        scene, center=mi.Point3f(*setup.map_center), orientation=mi.Point3f(0, 0, 0),
        size=mi.Point2f(*setup.map_size), cell_size=mi.Point2f(0.5, 0.5),
        samples_per_tx=20_000, max_depth=2, diffuse_reflection=True, refraction=True,
    )  # fmt: skip
    pg = np.asarray(rm.path_gain.numpy())
    from sionna.rt.constants import InteractionType as it

    return {
        "gain": p.sum(axis=1).tolist(),
        "finite": bool(np.all(np.isfinite(p)) and np.all(np.isfinite(pg))),
        "nonneg": bool(np.all(p >= 0) and np.all(pg >= 0)),
        "delays_finite": bool(np.all(np.isfinite(tau[p > 0]))),
        "map_lit": int(np.count_nonzero(pg > 0)),
        "map_max": float(pg.max()),
        "kinds": sorted(
            name
            for name, v in (
                ("specular", it.SPECULAR),
                ("diffuse", it.DIFFUSE),
                ("refraction", it.REFRACTION),
                ("diffraction", it.DIFFRACTION),
            )
            if np.any(types == v)
        ),  # fmt: skip
    }


def check_slab_convention():
    """emscatter's NumPy slab (exp(−iωt)) conjugated = Sionna's own ITU slab coefficients."""
    import drjit as dr
    import mitsuba as mi
    import sionna.rt  # noqa: F401  (sets the variant)
    from sionna.rt.utils import itu_coefficients_single_layer_slab

    from emscatter import materials
    from emscatter.radio import slab_coefficients, to_sionna
    from emscatter.radio.convention import sionna_permittivity

    c = np.linspace(0.01, 1.0, 50)
    worst = 0.0
    for name, f, d in (("concrete", 3.5e9, 0.1), ("glass", 28e9, 0.006), ("wood", 140e9, 0.04)):
        eps = complex(materials.itu(name).eps(frequency=f))
        k = 2 * math.pi * f / 299_792_458.0
        ours = np.stack(slab_coefficients(eps, c, k, d))
        eta = complex(sionna_permittivity(eps))
        got = itu_coefficients_single_layer_slab(
            mi.Float(c), mi.Complex2f(eta.real, eta.imag), mi.Float(d), 299_792_458.0 / f
        )
        theirs = np.stack([np.asarray(dr.real(g)) + 1j * np.asarray(dr.imag(g)) for g in got])
        worst = max(worst, float(np.max(np.abs(to_sionna(ours) - theirs))))
    return {"max_abs_diff": worst}


def _error(fn):
    """``"Type: message"`` of what ``fn()`` raises, or ``None``."""
    try:
        fn()
    except Exception as exc:  # the test asserts type and message
        return f"{type(exc).__name__}: {exc}"
    return None


def check_inputs():
    """Numbers of Sionna's own type, a user's XML scene file, bad scene arguments, and no
    temporary files left when loading fails."""
    import mitsuba as mi
    import sionna.rt as rt

    from emscatter.radio import scenes
    from emscatter.radio.material import EmscatterRadioMaterial

    out = {}
    sionna_d = rt.RadioMaterial("sionna-own", relative_permittivity=2.0, thickness=0.05).thickness
    out["sionna_thickness_type"] = type(sionna_d).__name__
    for key, d in (("mi_float", mi.Float(0.1)), ("sionna_own", sionna_d),
                   ("np_float32", np.float32(0.1)), ("np_int64", np.int64(1))):  # fmt: skip
        out[key] = EmscatterRadioMaterial(f"t-{key}", medium="concrete", thickness=d).thickness
    m = EmscatterRadioMaterial("c", eps_real=mi.Float(4.0), conductivity=mi.Float(0.5))
    out["conductive"] = [m.medium.eps_real, m.medium.conductivity_s_per_m]
    out["two_lanes"] = _error(
        lambda: EmscatterRadioMaterial("x", medium="concrete", thickness=mi.Float([0.1, 0.2]))
    )
    out["medium_negative"] = _error(lambda: EmscatterRadioMaterial("x", medium=-3))
    out["eps_real_negative"] = _error(
        lambda: EmscatterRadioMaterial("x", eps_real=-3, conductivity=0.0)
    )

    made = []

    def make(obj, medium, thickness):
        made.append([obj, medium, thickness])
        return EmscatterRadioMaterial(f"em-{obj}", medium=medium, thickness=thickness)

    def leftovers():
        return sorted(n for n in os.listdir(tempfile.gettempdir()) if n.startswith("emscatter-"))

    with tempfile.TemporaryDirectory(prefix="radio-xml-") as tmp:
        d = Path(tmp)
        scenes.write_ply(d / "floor.ply", scenes.quad([-5, -5, 0], [10, 0, 0], [0, 10, 0]))
        scenes.write_ply(d / "wall.ply", scenes.quad([5, -5, 0], [0, 10, 0], [0, 0, 3]))
        (d / "user.xml").write_text(
            '<scene version="2.1.0">\n'
            '<bsdf type="itu-radio-material" id="itu-concrete"><string name="type" '
            'value="concrete"/><float name="thickness" value="0.2"/></bsdf>\n'
            '<bsdf type="radio-material" id="plain"><float name="relative_permittivity" '
            'value="3.0"/></bsdf>\n'
            '<shape type="ply" id="floor"><string name="filename" value="floor.ply"/>'
            '<ref id="itu-concrete" name="bsdf"/></shape>\n'
            '<shape type="ply" id="wall"><string name="filename" value="wall.ply"/>'
            '<ref id="plain" name="bsdf"/></shape>\n</scene>\n'
        )
        xml = d / "user.xml"
        # the plain material has no medium to hand to make_material: a clear error
        out["xml_no_medium"] = _error(lambda: scenes.load(xml, 28e9, make))
        made.clear()
        sc = scenes.load(str(xml), 28e9, make, media={"wall": ("glass", 0.006)})
        out["xml_made"] = sorted(made)
        out["xml_materials"] = sorted(
            type(obj.radio_material).__name__ for obj in sc.objects.values()
        )
        out["xml_frequency"] = float(sc.frequency[0])
        kept = scenes.load(xml, 28e9)  # without make_material: the file's own materials
        out["xml_kept"] = sorted(type(o.radio_material).__name__ for o in kept.objects.values())
    out["xml_missing"] = _error(lambda: scenes.load(d / "gone.xml", 28e9, make))
    out["bad_name"] = _error(lambda: scenes.load("garage", 28e9, make))

    # a generated scene's folder is gone once loaded, and also when loading fails
    before = leftovers()
    scenes.load(scenes.plate(4.0), 28e9, make)

    def broken(obj, medium, thickness):
        raise RuntimeError("a material callback that fails")

    out["broken"] = _error(lambda: scenes.load(scenes.plate(4.0), 28e9, broken))
    out["left"] = sorted(set(leftovers()) - set(before))
    return out


def check_path_buffer():
    """The rough room at 140 GHz (20 k rays, depth 2, ≈ 46 k candidates): Sionna's buffer at
    one path per ray is full (warned), the default size is not, and two runs agree exactly."""
    from emscatter.radio import indoor
    from emscatter.radio.tables import TableOptions

    opts = TableOptions(n_cos=65, n_cos_spm=9, n_theta=16, n_alpha=13, n_s=32)
    setup = indoor.SETUPS["room"]
    kw = {"samples": 20_000, "max_depth": 2, "cell_size": None, "table_options": opts}
    out = {}
    limit = indoor.MAX_PATHS_PER_RAY
    indoor.MAX_PATHS_PER_RAY = 1  # the old sizing: one candidate per ray, never grown
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            small = indoor.run_scene(setup, "rough", 140e9, paths_per_ray=1, **kw)
    finally:
        indoor.MAX_PATHS_PER_RAY = limit
    out["small_buffer"] = small["path_buffer"]
    out["small_warnings"] = [
        f"{w.category.__name__}: {w.message}" for w in caught if "buffer" in str(w.message)
    ]
    grown = indoor.run_scene(setup, "rough", 140e9, paths_per_ray=2, **kw)
    out["grown_buffer"] = grown["path_buffer"]
    runs = [indoor.run_scene(setup, "rough", 140e9, **kw) for _ in range(2)]
    out["buffer"] = runs[0]["path_buffer"]
    out["gain_db"] = [(10 * np.log10(r["path_gain"])).tolist() for r in runs]
    out["spread"] = [r["delay_spread"].tolist() for r in runs]
    out["grown_gain_db"] = (10 * np.log10(grown["path_gain"])).tolist()
    out["small_gain_db"] = (10 * np.log10(small["path_gain"])).tolist()
    return out


# simple_street_canyon: main street y ∈ [-8.6, 9.6]; the brick building_2 (x ∈ [32.4, 63.5])
# faces it at y = 10.3. Receivers 0–3 see the transmitter's image in that wall face.
STREET_TX = (20.0, 0.0, 10.0)
STREET_RX = ((60.0, 2.0, 1.5), (50.0, -3.0, 1.5), (75.0, 0.0, 1.5), (60.0, 5.0, 1.5),
             (-20.0, 0.0, 1.5), (24.0, 25.0, 1.5))  # fmt: skip


def check_roughen_street_canyon():
    """Sionna's simple_street_canyon rough in one call at 28 GHz: one shared material per
    medium, originals gone, flat-back = the original results, rough − flat of the expected sign."""
    import sionna.rt as rt

    from emscatter import radio
    from emscatter.radio.material import EmscatterRadioMaterial
    from emscatter.radio.tables import TableOptions

    opts = TableOptions(n_cos=65, n_cos_spm=9, n_theta=16, n_alpha=13, n_s=32)
    sc = rt.load_scene(rt.scene.simple_street_canyon, merge_shapes=False)
    sc.frequency = 28e9
    arr = rt.PlanarArray(num_rows=1, num_cols=1, pattern="iso", polarization="V")
    sc.tx_array = sc.rx_array = arr
    sc.add(rt.Transmitter("tx", position=list(STREET_TX)))
    for i, p in enumerate(STREET_RX):
        sc.add(rt.Receiver(f"rx{i}", position=list(p)))
    before = {n: (o.radio_material.name, id(o.radio_material)) for n, o in sc.objects.items()}
    original_names = sorted(sc.radio_materials)
    out = {"original_materials": original_names}
    specular = {"max_depth": 2, "samples_per_src": 50_000, "diffuse_reflection": False,
                "refraction": False, "los": False}  # fmt: skip

    def gains(**kw):
        paths = rt.PathSolver(deterministic=True)(sc, seed=1, **{**specular, **kw})
        return radio.roughening.path_gains(paths)[:, 0]

    flat0 = gains()
    handle = radio.roughen(sc, table_options=opts)
    out["types"] = sorted({type(o.radio_material).__name__ for o in sc.objects.values()})
    out["materials"] = sorted(sc.radio_materials)
    out["shared"] = {m: sorted(n for n, o in sc.objects.items() if o.radio_material.name == m)
                     for m in sc.radio_materials}  # fmt: skip
    out["rows"] = handle.rows()
    out["describe"] = handle.describe()
    # the default table: the SPM mean field raises v-pol |R| at grazing beyond Brewster
    # (street-level floor bounces), so this sign is not fixed; recorded for the report
    out["default_minus_flat_specular_db"] = (10 * np.log10(gains() / flat0)).tolist()
    out["rough_diffuse_finite"] = bool(np.all(np.isfinite(gains(diffuse_reflection=True))))
    out["tables"] = {
        m.name: m.active_tables.method
        for m in sc.radio_materials.values()
        if isinstance(m, EmscatterRadioMaterial) and m.active_tables is not None
    }
    radio.flatten(sc)
    out["after_flatten"] = sorted(sc.radio_materials)
    out["same_instances"] = all(
        (o.radio_material.name, id(o.radio_material)) == before[n] for n, o in sc.objects.items()
    )
    out["flat_back_equal"] = bool(np.array_equal(gains(), flat0))
    # roughen twice (a second call flattens first): no "name already used" error
    radio.roughen(sc, mapping={"brick": (1.2e-3, 8e-3), "glass": None}, table_options=opts)
    radio.roughen(sc, table_options=opts)
    out["twice"] = sorted(sc.radio_materials)
    radio.flatten(sc)
    # one rough wall (brick, building_2; PO at 28 GHz), every other medium flat
    wall = {"roughness": "flat", "mapping": {"brick": (0.8e-3, 8e-3)}, "table_options": opts}
    radio.roughen(sc, **wall)
    out["wall_minus_flat_specular_db"] = (10 * np.log10(gains() / flat0)).tolist()
    radio.flatten(sc)
    # rough − flat in one call: path gains and radio maps
    res = radio.compare_rough_flat(
        sc, **wall, paths={"max_depth": 2, "samples_per_src": 50_000},
        radio_map={"center": (55.0, 0.0, 1.5), "orientation": (0.0, 0.0, 0.0),
                   "size": (50.0, 16.0), "cell_size": (2.0, 2.0), "samples_per_tx": 200_000,
                   "max_depth": 2, "diffuse_reflection": False},
    )  # fmt: skip
    d = res["radio_map"]["difference_db"]
    lit = res["radio_map"]["lit"]
    out["map_cells_lit"] = int(lit.sum())
    out["map_finite_where_lit"] = bool(np.all(np.isfinite(d[lit])))
    out["map_nan_elsewhere"] = bool(np.all(np.isnan(d[~lit])))
    out["map_median_db"] = float(np.median(d[lit]))
    out["map_mean_power_ratio_db"] = float(
        10 * np.log10(res["radio_map"]["rough"][lit].sum() / res["radio_map"]["flat"][lit].sum())
    )
    out["compare_paths_db"] = res["path_gain"]["difference_db"][:, 0].tolist()
    out["compare_paths_finite"] = bool(np.all(np.isfinite(res["path_gain"]["rough"])))
    out["after_compare"] = sorted(sc.radio_materials)
    return out


def check_roughen_errors():
    """Bad mappings, out of band, flatten of a scene never roughened, nothing to compare."""
    import sionna.rt as rt

    from emscatter import radio

    sc = rt.load_scene(rt.scene.simple_street_canyon, merge_shapes=False)
    sc.frequency = 28e9
    names = sorted(sc.radio_materials)
    out = {
        "unknown_key": _error(lambda: radio.roughen(sc, mapping={"granite": (1e-3, 1e-2)})),
        "bad_value": _error(lambda: radio.roughen(sc, mapping={"brick": (-1e-3, 1e-2)})),
        "bad_roughness": _error(lambda: radio.roughen(sc, roughness=0.4e-3)),
        "out_of_band": _error(lambda: radio.roughen(sc, frequencies=[50e9])),
        "flatten_unroughened": _error(lambda: radio.flatten(sc)),
        "no_transmitter": _error(lambda: radio.compare_rough_flat(sc, radio_map=True)),
        "bad_reference": _error(lambda: radio.compare_rough_flat(sc, reference="sionna")),
    }
    out["unchanged"] = sorted(sc.radio_materials) == names
    return out


def _plate_builtin_powers(case, kwargs, *, samples, diffuse):
    """Sionna's built-in RadioMaterial with ``kwargs`` on the plate of ``case``: path gain per
    antenna pair (as :func:`emscatter.radio.plate.sionna_plate` for the emscatter material)."""
    import sionna.rt as rt

    from emscatter.radio import scenes

    def make(name, medium, thickness):
        return rt.RadioMaterial(f"bi-{name}", **kwargs)

    scene = scenes.load(scenes.plate(case.size), case.frequency, make)
    arr = rt.PlanarArray(num_rows=1, num_cols=1, pattern="iso", polarization="VH")
    scene.tx_array = scene.rx_array = arr
    scene.add(rt.Transmitter("tx", position=case.tx.tolist()))
    scene.add(rt.Receiver("rx", position=case.rx.tolist()))
    paths = rt.PathSolver()(
        scene, max_depth=1, samples_per_src=int(samples), max_num_paths_per_src=int(samples),
        los=False, specular_reflection=not diffuse, diffuse_reflection=diffuse,
        refraction=False, seed=1,
    )  # fmt: skip
    re, im = (np.asarray(x.numpy()) for x in paths.a)
    power = re**2 + im**2
    ant = {"V": 0, "H": 1}
    return {pair: float(power[0, ant[pair[0]], 0, ant[pair[1]]].sum()) for pair in ("VV", "HH")}


def check_builtin_plate():
    """The fitted built-in material (radio.builtin_equivalent → sionna.rt.RadioMaterial) against
    the emscatter material on the plate at the fit angle: the specular image path and the
    diffuse power, VV and HH."""
    import emscatter as em
    from emscatter.radio import MaterialSpec
    from emscatter.radio.builtin import builtin_equivalent, sionna_material_kwargs
    from emscatter.radio.plate import PlateCase, sionna_plate

    out = {}
    for name, f, rough in (
        ("concrete_28GHz", 28e9, em.GaussianCorrelation(sigma=0.4e-3, length=4e-3)),
        ("concrete_140GHz", 140e9, em.GaussianCorrelation(sigma=0.4e-3, length=4e-3)),
    ):
        spec = MaterialSpec(surface=rough, medium="concrete", thickness=None)
        eq = builtin_equivalent(spec, f)
        kw = {**sionna_material_kwargs(eq), "thickness": 1.0}  # 1 m of concrete: a half-space
        case = PlateCase(frequency=f, surface=rough, medium="concrete", theta_deg=45.0)
        row = {"S": eq["scattering_coefficient"], "pattern": eq["scattering_pattern"],
               "valid": eq["valid"]}  # fmt: skip
        for kind, diffuse, n in (("specular", False, 10_000), ("diffuse", True, 300_000)):
            em_p = sionna_plate(case, samples=n, diffuse=diffuse)
            bi_p = _plate_builtin_powers(case, kw, samples=n, diffuse=diffuse)
            for pair in ("VV", "HH"):
                row[f"{kind}_{pair}_emscatter_db"] = 10 * math.log10(em_p[pair])
                row[f"{kind}_{pair}_builtin_db"] = 10 * math.log10(bi_p[pair])
                row[f"{kind}_{pair}_diff_db"] = 10 * math.log10(bi_p[pair] / em_p[pair])
        out[name] = row
    return out


# Calibration (issue 18): a 6 m concrete plate, receivers near and far from the specular
# direction, one (rx 4) whose specular point (x = 3.7 m) is off the plate: diffuse only.
CAL_TX = (-2.0, 0.0, 2.0)
CAL_RX = ((2.0, 0.0, 2.0), (3.0, 0.5, 1.0), (1.0, -1.0, 3.0), (1.5, 0.0, 0.5), (6.5, 0.0, 1.0),
          (0.5, 2.5, 1.5))  # fmt: skip
CAL_TRUTH = {"28": (28e9, 0.5e-3, 4e-3), "140": (140e9, 0.3e-3, 3e-3)}


def check_calibration_truth():
    """The synthetic truth for the calibration: Sionna RT's specular and diffuse path gains on
    the plate with the emscatter rough material of known σ, ℓ at 28 and 140 GHz."""
    import emscatter as em
    from emscatter.radio import calibration as cal

    geo = cal.PlateGeometry(tx=CAL_TX, rx=CAL_RX, size=6.0)
    out = {}
    for key, (f, s, length) in CAL_TRUTH.items():
        surface = em.GaussianCorrelation(sigma=s, length=length)
        g = cal.sionna_gains(geo, f, surface, medium="concrete", samples=300_000)
        out[key] = {kind: {pair: v.tolist() for pair, v in per.items()} for kind, per in g.items()}
    return out


def check_xpd_plate():
    """XPD per path on the rough concrete plate at 28 GHz (dual-polarized antennas, receiver
    out of the transmitter's plane of incidence): diffuse-only paths against emscatter's σ⁰ at
    each path's vertex, the link XPD of diffuse paths against the radar-equation quadrature, and
    the flat limit (all interactions, σ → 0 and flat)."""
    import sionna.rt as rt

    import emscatter as em
    from emscatter.radio import calibration as cal
    from emscatter.radio import scenes
    from emscatter.radio.material import EmscatterRadioMaterial
    from emscatter.radio.xpd import diffuse_xpd, path_xpd

    f, tx, rx = 28e9, (-2.0, 0.0, 2.0), (1.5, 1.5, 1.5)
    rough = em.GaussianCorrelation(sigma=0.4e-3, length=4e-3)

    def solve(surface, diffuse_only, n=300_000):
        sc = scenes.load(scenes.plate(6.0), f, lambda o, m, t: EmscatterRadioMaterial(
            "xpd-plate", surface=surface, medium="concrete", thickness=None))  # fmt: skip
        arr = rt.PlanarArray(num_rows=1, num_cols=1, pattern="iso", polarization="VH")
        sc.tx_array = sc.rx_array = arr
        sc.add(rt.Transmitter("tx", position=list(tx)))
        sc.add(rt.Receiver("rx", position=list(rx)))
        return rt.PathSolver()(
            sc, max_depth=1, samples_per_src=n, max_num_paths_per_src=n, los=False,
            specular_reflection=not diffuse_only, diffuse_reflection=True, refraction=False,
            seed=1,
        )  # fmt: skip

    paths = solve(rough, True)
    x = path_xpd(paths)
    v = np.asarray(paths.vertices.numpy())[0, 0, 0]  # first bounce [path, 3]
    ok = x["valid"][0, 0] & (x["co"][0, 0] > 0)
    pred = diffuse_xpd(rough, f, tx, rx, v[ok], medium="concrete")
    got = x["per_path_db"][0, 0][ok]
    fin = np.isfinite(got) & np.isfinite(pred["xpd_db"])
    geo = cal.PlateGeometry(tx=tx, rx=[rx], size=6.0)
    quad = cal.predict(geo, f, rough)["diffuse"]
    out = {
        "n_paths": int(ok.sum()),
        "n_finite": int(fin.sum()),
        "per_path_median_abs_diff_db": float(np.median(np.abs(got[fin] - pred["xpd_db"][fin]))),
        "per_path_p90_abs_diff_db": float(
            np.percentile(np.abs(got[fin] - pred["xpd_db"][fin]), 90)
        ),
        "per_path_range_db": [float(np.min(got[fin])), float(np.max(got[fin]))],
        "link_diffuse_db": float(x["link_db"][0, 0]),
        "link_diffuse_quadrature_db": float(
            10 * np.log10((quad["VV"][0] + quad["HH"][0]) / (quad["HV"][0] + quad["VH"][0]))
        ),
        "method": pred["method"],
    }
    link = {}
    for label, surface in (("0.4mm", rough),
                           ("0.1mm", em.GaussianCorrelation(sigma=0.1e-3, length=4e-3)),
                           ("0.01mm", em.GaussianCorrelation(sigma=0.01e-3, length=4e-3)),
                           ("flat", None)):  # fmt: skip
        px = path_xpd(solve(surface, False))
        link[label] = float(px["link_db"][0, 0])
        if label == "flat":
            spec = px["per_path_db"][0, 0][px["valid"][0, 0]]
            out["flat_specular_per_path_db"] = spec.tolist()
    out["link_all_db"] = link
    return out


def check_height_map_plate():
    """The plate (45°, 28 GHz, half-space concrete) with a material built from a measured map
    (MaterialSpec.from_height_map: a 1024² map drawn from σ = 0.4 mm, ℓ = 4 mm) against the
    analytic roughness it was drawn from: diffuse path gains VV and HH (issue 17)."""
    import emscatter as em
    from emscatter.radio import MaterialSpec
    from emscatter.radio.plate import PlateCase, sionna_plate
    from emscatter.surfaces.heightmap import height_map

    f, rough = 28e9, em.GaussianCorrelation(sigma=0.4e-3, length=4e-3)
    s = em.generate_surface(rough, (1024, 1024), 0.5e-3, rng=2)
    spec = MaterialSpec.from_height_map(height_map(s.heights, s.spacing), frequencies=[f])
    out = {}
    gains = {}
    for name, surface in (("map", spec.surface), ("analytic", rough)):
        case = PlateCase(frequency=f, surface=surface, medium="concrete", theta_deg=45.0,
                         method="spm")  # fmt: skip
        gains[name] = sionna_plate(case, samples=300_000, diffuse=True)
    for pair in ("VV", "HH"):
        out[f"{pair}_map_db"] = 10 * math.log10(gains["map"][pair])
        out[f"{pair}_analytic_db"] = 10 * math.log10(gains["analytic"][pair])
        out[f"{pair}_diff_db"] = out[f"{pair}_map_db"] - out[f"{pair}_analytic_db"]
    return out


CHECKS = {name[6:]: fn for name, fn in globals().items() if name.startswith("check_")}


# Anisotropic roughness (issue 18): a textured plate. The texture axis X is the world direction
# projected onto the plate (z = 0), so for direction x the surface frame is the world frame.
def _textured_plate(case, direction, *, samples, diffuse, options=None, textured=True):
    """Path gains (VV, HH, HV, VH), the solve time [s] (second solve: tables and kernels
    cached) and the tables of the plate with a textured emscatter material."""
    import time

    import sionna.rt as rt

    from emscatter.radio import scenes
    from emscatter.radio.material import EmscatterRadioMaterial
    from emscatter.radio.plate import _ANT, POL_PAIRS

    def make(name, medium, thickness):
        kw = {"texture_direction": direction} if textured else {}
        return EmscatterRadioMaterial(
            "em-plate", surface=case.surface, medium=case.medium, thickness=None,
            method=case.method, table_options=options, **kw,
        )  # fmt: skip

    scene = scenes.load(scenes.plate(case.size), case.frequency, make)
    arr = rt.PlanarArray(num_rows=1, num_cols=1, pattern="iso", polarization="VH")
    scene.tx_array = scene.rx_array = arr
    scene.add(rt.Transmitter("tx", position=case.tx.tolist()))
    scene.add(rt.Receiver("rx", position=case.rx.tolist()))
    solver = rt.PathSolver()
    kw = dict(max_depth=1, samples_per_src=int(samples), max_num_paths_per_src=int(samples),
              los=False, specular_reflection=not diffuse, diffuse_reflection=diffuse,
              refraction=False, seed=1)  # fmt: skip
    solver(scene, **kw)
    seconds = math.inf
    for _ in range(3):  # best of 3: the machine may be loaded
        t0 = time.perf_counter()
        paths = solver(scene, **kw)
        re, im = (np.asarray(x.numpy()) for x in paths.a)
        seconds = min(seconds, time.perf_counter() - t0)
    power = re**2 + im**2
    out = {p: float(power[0, _ANT[p[0]], 0, _ANT[p[1]]].sum()) for p in POL_PAIRS}
    contrib = power[0, 1, 0, 1]
    n = max(int(np.count_nonzero(contrib)), 1)
    out["noise_vv"] = float(math.sqrt(n) * contrib.std() / max(contrib.sum(), 1e-300))
    out["seconds"] = seconds
    return out, scene.get("em-plate").active_tables


def check_textured_plate():
    """Textured plate at 28 GHz, 60°, PO tables: diffuse power vs the σ⁰ quadrature of the
    anisotropic surface; direction x with (ℓx, ℓy) = direction y with (ℓy, ℓx); ℓx = ℓy through
    the textured path = the isotropic material; specular = image × Fresnel × Kirchhoff; solve
    times textured / isotropic."""
    from emscatter.radio.plate import PlateCase, diffuse_prediction, specular_prediction
    from emscatter.spectra import GaussianCorrelation as G

    f, n = 28e9, int(os.environ.get("ANISO_SAMPLES", "300000"))
    aniso = G(sigma=1e-3, length=30e-3, length_y=12e-3)  # inside PO's range at 28 GHz
    swapped = G(sigma=1e-3, length=12e-3, length_y=30e-3)
    iso = G(sigma=1e-3, length=10e-3)
    case = PlateCase(f, aniso, method="po", size=20.0)
    out = {"samples": n, "load": os.getloadavg()[0]}
    dif, tab = _textured_plate(case, (1, 0, 0), samples=n, diffuse=True)
    out["diffuse"] = dif
    out["method"] = tab.method
    out["diffuse_prediction"] = diffuse_prediction(case)
    out["diffuse_rotated"] = _textured_plate(
        PlateCase(f, swapped, method="po", size=20.0), (0, 1, 0), samples=n, diffuse=True
    )[0]
    out["specular"] = _textured_plate(case, (1, 0, 0), samples=10_000, diffuse=False)[0]
    out["specular_prediction"] = specular_prediction(case)
    ci = PlateCase(f, iso, method="po", size=20.0)
    for key, textured in (("iso_textured", True), ("iso_plain", False)):
        out[key] = _textured_plate(ci, (0, 0, 1), samples=n, diffuse=True, textured=textured)[0]
        out[key + "_specular"] = _textured_plate(
            ci, (0, 0, 1), samples=10_000, diffuse=False, textured=textured
        )[0]
    from emscatter.radio.material import EmscatterRadioMaterial

    mat = EmscatterRadioMaterial
    out["errors"] = {
        "no_direction": _error(lambda: mat("a", surface=aniso, medium="wood")),
        "flat": _error(lambda: mat("b", medium="wood", texture_direction=(0, 0, 1))),
        "zero": _error(lambda: mat("c", surface=aniso, medium="wood", texture_direction=(0, 0, 0))),
    }
    return out


CHECKS["textured_plate"] = check_textured_plate


def check_textured_scenes():
    """Textured materials where users meet them: an XML scene naming a textured material
    (vertical grooves on a wall and, by the degenerate rule, on the floor) in both solvers;
    roughen(simple_street_canyon) with (σ, ℓx, ℓy) and a texture direction; the solve-time
    ratio textured / isotropic (same σ, ℓ = ℓx) with diffuse on (best of 3, tables built)."""
    import time

    import mitsuba as mi
    import sionna.rt as rt

    import emscatter.radio.material as m
    from emscatter import radio
    from emscatter.radio import scenes
    from emscatter.radio.tables import TableOptions

    out = {"load": os.getloadavg()[0], "cpus": os.cpu_count()}
    with tempfile.TemporaryDirectory(prefix="radio-xml-") as tmp:
        d = Path(tmp)
        scenes.write_ply(d / "floor.ply", scenes.quad([-5, -5, 0], [10, 0, 0], [0, 10, 0]))
        scenes.write_ply(d / "wall.ply", scenes.quad([-5, 3, 0], [10, 0, 0], [0, 0, 4]))
        shapes = "".join(
            f'<shape type="ply" id="{n}"><string name="filename" value="{n}.ply"/>'
            '<ref id="grooved" name="bsdf"/></shape>\n'
            for n in ("floor", "wall")
        )
        (d / "scene.xml").write_text(
            '<scene version="2.1.0">\n'
            f'<bsdf type="{m.PLUGIN_NAME}" id="grooved">'
            '<string name="medium" value="concrete"/>'
            '<float name="rms_height" value="0.001"/>'
            '<float name="correlation_length" value="0.03"/>'
            '<float name="correlation_length_y" value="0.012"/>'
            '<string name="texture_direction" value="0 0 1"/>'
            f'<float name="thickness" value="0.2"/></bsdf>\n{shapes}</scene>\n'
        )
        scene = scenes.load(d / "scene.xml", 28e9)
    mat = scene.get("grooved")
    _add_devices(scene, (0, 0, 2.0), [(2.0, 0.5, 1.5), (-2.0, 2.0, 1.0)])
    p, pg = _both_solvers(scene)
    out["xml"] = {
        "lengths": [mat.surface.length, mat.surface.length_y],
        "direction": [float(v) for v in mat._texture],
        "psi_nodes": int(mat.active_tables.psi_nodes.size),
        "num_paths": int(np.count_nonzero(p)),
        "finite": bool(np.all(np.isfinite(p)) and np.all(np.isfinite(pg))),
        "nonneg": bool(np.all(p >= 0) and np.all(pg >= 0)),
        "below_one": bool(p.sum(axis=1).max() < 1 and pg.max() < 1),
        "map_cells_lit": int(np.count_nonzero(pg > 0)),
    }
    opts = TableOptions(n_cos=65, n_cos_spm=9, n_theta=16, n_alpha=13, n_s=32, n_psi=5)
    sc = rt.load_scene(rt.scene.simple_street_canyon, merge_shapes=False)
    sc.frequency = 28e9
    arr = rt.PlanarArray(num_rows=1, num_cols=1, pattern="iso", polarization="V")
    sc.tx_array = sc.rx_array = arr
    sc.add(rt.Transmitter("tx", position=list(STREET_TX)))
    for i, q in enumerate(STREET_RX):
        sc.add(rt.Receiver(f"rx{i}", position=list(q)))
    out["no_direction"] = _error(
        lambda: radio.roughen(sc, "flat", {"brick": (1e-3, 30e-3, 12e-3)}, table_options=opts)
    )
    out["unchanged"] = not any(isinstance(x, m.EmscatterRadioMaterial)
                               for x in sc.radio_materials.values())  # fmt: skip
    h = radio.roughen(sc, "flat", {"brick": (1e-3, 30e-3, 12e-3)}, table_options=opts,
                      texture_direction={"brick": (2, 0, 0)})  # fmt: skip
    out["per_medium_direction"] = [float(v) for v in h.materials["rough-brick"]._texture]
    radio.flatten(sc)
    grooved = {"brick": (1e-3, 30e-3, 12e-3)}
    out["bad_direction"] = _error(
        lambda: radio.roughen(sc, "flat", grooved, texture_direction={"brick": "up"})
    )
    kw = {"max_depth": 2, "samples_per_src": 100_000, "diffuse_reflection": True, "seed": 1}
    rmkw = {"center": mi.Point3f(55.0, 0.0, 1.5), "orientation": mi.Point3f(0, 0, 0),
            "size": mi.Point2f(50.0, 16.0), "cell_size": mi.Point2f(2.0, 2.0),
            "samples_per_tx": 200_000, "max_depth": 2, "diffuse_reflection": True}  # fmt: skip

    def timed(fn):
        fn()  # tables and kernels
        best = math.inf
        for _ in range(3):
            t0 = time.perf_counter()
            res = fn()
            best = min(best, time.perf_counter() - t0)
        return best, res

    def path_run():
        g = radio.roughening.path_gains(rt.PathSolver()(sc, **kw))
        return g

    def map_run():
        return np.asarray(rt.RadioMapSolver()(sc, **rmkw).path_gain.numpy())

    times = {}
    for key, value, direction in (
        ("isotropic", (1e-3, 30e-3), None),
        ("textured", (1e-3, 30e-3, 12e-3), (0, 0, 1)),
    ):
        h = radio.roughen(sc, "flat", {"brick": value}, table_options=opts,
                          texture_direction=direction)  # fmt: skip
        if key == "textured":
            out["rows_brick"] = [r for r in h.rows() if r["itu_type"] == "brick"][:1]
        tp, g = timed(path_run)
        tm, pgm = timed(map_run)
        times[key] = {"paths_s": tp, "map_s": tm}
        out[key + "_finite"] = bool(np.all(np.isfinite(g)) and np.all(np.isfinite(pgm)))
        out[key + "_gain"] = np.asarray(g)[:, 0].tolist()
        radio.flatten(sc)
    out["times"] = times
    out["ratio_paths"] = times["textured"]["paths_s"] / times["isotropic"]["paths_s"]
    out["ratio_map"] = times["textured"]["map_s"] / times["isotropic"]["map_s"]
    return out


CHECKS["textured_scenes"] = check_textured_scenes


def _oblique_prediction(case, beta, order=6):
    """Radar-equation diffuse gain (VV, HH, HV) of the plate with the texture axis at azimuth
    ``beta`` [rad] in the plate (as emscatter.radio.plate.diffuse_prediction, azimuths taken
    relative to the texture axis)."""
    from emscatter.constants import SPEED_OF_LIGHT
    from emscatter.conventions import wavenumber
    from emscatter.radio.plate import POL_PAIRS, _graded_nodes
    from emscatter.solvers import get

    k = wavenumber(frequency=case.frequency)
    lam = SPEED_OF_LIGHT / case.frequency
    x0, h, half = float(case.rx[0]), case.height, case.size / 2
    xs, wx = _graded_nodes(half, 0.005, 2 * x0 + 2 * h, h / 4, order)
    ys, wy = _graded_nodes(half, 0.005, 2 * h, h / 4, order)
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    p = np.stack([X, Y, np.zeros_like(X)], axis=-1)
    d1, d2 = p - case.tx, case.rx - p
    r1, r2 = np.linalg.norm(d1, axis=-1), np.linalg.norm(d2, axis=-1)
    ti = np.arccos(np.clip(-d1[..., 2] / r1, 0.0, 1.0))
    ts = np.arccos(np.clip(d2[..., 2] / r2, 0.0, 1.0))
    pi_ = np.arctan2(d1[..., 1], d1[..., 0]) - beta
    ps = np.arctan2(d2[..., 1], d2[..., 0]) - beta
    sig = get(case.method).bistatic(case.surface, case.eps, k, ti, ts, ps, pi_,
                                    coherent=False).sigma0  # fmt: skip
    w = wx[:, None] * wy[None, :]
    tot = np.einsum("psxy,xy->ps", lam**2 * sig / ((4 * math.pi) ** 3 * r1**2 * r2**2), w)
    return {pair: float(tot[s, i]) for pair, (s, i) in POL_PAIRS.items()}


def check_textured_plate_oblique():
    """The textured plate with the texture axis at 37° in the plate (ψ between table nodes, both
    signs of the folded azimuth): diffuse power vs the quadrature; the 0° and 90° predictions
    beside it (how much the azimuth matters here)."""
    from emscatter.radio.plate import PlateCase
    from emscatter.spectra import GaussianCorrelation as G

    n = int(os.environ.get("ANISO_SAMPLES", "300000"))
    case = PlateCase(28e9, G(sigma=1e-3, length=30e-3, length_y=12e-3), method="po", size=20.0)
    beta = math.radians(37.0)
    out = {"samples": n}
    out["diffuse"] = _textured_plate(
        case, (math.cos(beta), math.sin(beta), 0.0), samples=n, diffuse=True
    )[0]
    out["prediction"] = _oblique_prediction(case, beta)
    out["prediction_0"] = _oblique_prediction(case, 0.0)
    out["prediction_90"] = _oblique_prediction(case, 0.5 * math.pi)
    return out


CHECKS["textured_plate_oblique"] = check_textured_plate_oblique


def check_slab_diffuse_flat():
    """The flat limit of emscatter.radio.slab_diffuse: its coherent R, T power = Sionna's own ITU
    slab (itu_coefficients_single_layer_slab), in dB, and no diffuse power."""
    import drjit as dr
    import mitsuba as mi
    import sionna.rt  # noqa: F401  (sets the variant)
    from sionna.rt.utils import complex_sqrt, itu_coefficients_single_layer_slab

    from emscatter import materials
    from emscatter.radio.convention import sionna_permittivity
    from emscatter.radio.slab_diffuse import diffuse_transmission

    theta = np.radians(np.arange(0.0, 86.0, 5.0))
    worst_db, worst_diffuse = {}, 0.0
    for name, f, d in (("brick", 28e9, 0.1), ("glass", 28e9, 0.006), ("concrete", 3.5e9, 0.2)):
        eps = complex(materials.itu(name).eps(frequency=f))
        b = diffuse_transmission(None, eps, f, d, theta=theta)
        eta = complex(sionna_permittivity(eps))
        got = itu_coefficients_single_layer_slab(
            mi.Float(np.cos(theta)), mi.Complex2f(eta.real, eta.imag), mi.Float(d),
            299_792_458.0 / f,
        )  # fmt: skip
        pw = np.stack([np.asarray(dr.squared_norm(g)) for g in got])  # r_te, r_tm, t_te, t_tm
        pairs = ((b.r_coh, pw[:2]), (b.t_coh, pw[2:]))
        db = [np.max(np.abs(10 * np.log10(o / t))) for o, t in pairs]
        worst_db[name] = float(max(db))
        worst_diffuse = max(worst_diffuse, float(np.max(b.r_diff + b.t_diff)))
    # Sionna's float32 complex_sqrt loses digits in Im √η for low loss (brick at 28 GHz:
    # −0.00657822 against −0.00658438): its slab's loss over 0.1 m differs by 0.09 %.
    root = complex_sqrt(mi.Complex2f(3.91, -0.026039678))
    return {"max_db": worst_db, "max_diffuse": worst_diffuse,
            "sionna_sqrt_imag": float(np.asarray(dr.imag(root))[0])}  # fmt: skip


CHECKS["slab_diffuse_flat"] = check_slab_diffuse_flat


def check_roughen_diffuse_transmission():
    """``roughen(transmission="diffuse")``: the isotropic rough slabs take the material's diffuse
    transmission; flat objects and half-spaces keep the coherent slab; rows() name the model."""
    import sionna.rt as rt

    from emscatter import radio

    sc = rt.load_scene(rt.scene.simple_street_canyon, merge_shapes=False)
    sc.frequency = 28e9
    handle = radio.roughen(sc, transmission="diffuse")
    rows = handle.rows()
    out = {"rows": [{k: r[k] for k in ("object", "correlation", "thickness_m", "transmission")}
                    for r in rows],
           "materials": {name: m.transmission for name, m in handle.materials.items()}}  # fmt: skip
    radio.flatten(sc)
    try:
        radio.roughen(sc, transmission="lambertian")
        out["bad"] = None
    except ValueError as exc:
        out["bad"] = str(exc)
    handle = radio.roughen(sc, transmission="diffuse", transmission_face="po")
    out["faces"] = {name: m.transmission_face for name, m in handle.materials.items()}
    radio.flatten(sc)
    for kw in ({"transmission_face": "po"}, {"transmission": "diffuse", "transmission_face": "x"}):
        try:
            radio.roughen(sc, **kw)
            out.setdefault("bad_faces", []).append(None)
        except ValueError as exc:
            out.setdefault("bad_faces", []).append(str(exc))
    return out


CHECKS["roughen_diffuse_transmission"] = check_roughen_diffuse_transmission


def main(argv):
    from worker_checks import run_checks  # beside this script (its folder is on sys.path)

    return run_checks(CHECKS, argv)


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
