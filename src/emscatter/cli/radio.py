"""``emscatter radio``: Sionna RT scenes with emscatter materials against Sionna's defaults.

Two modes: the indoor cross-check (``--scene room|floor_wall|box|all``: Sionna S = 0.3, flat
and rough sets) and, with ``--medium`` or ``--tx`` or any other scene (a Sionna scene name such
as ``simple_street_canyon``, or a Mitsuba/Sionna ``*.xml`` file), "any scene rough": the scene's
own materials against emscatter's rough equivalents (:func:`emscatter.radio.roughen`), radio
maps of rough − flat as PNG and CSV per frequency (``--xpd-map``: also cross-polar
discrimination per cell, flat and rough, and its median and quartiles against frequency,
:mod:`emscatter.radio.xpd_map`; ``--diffuse-transmission``: the rough slabs' diffuse
transmission too, with ``--transmission-face`` the faces' model; either flag selects this mode).
Every argument, the media named, the bands and the output folder are checked before a ray is
traced.

``--height-map FILE`` (with ``--detrend``, ``--unit``, ``--segments``, ``--tail`` as for
``emscatter brdf`` and ``curves``, and ``--map-model measured|fit``) takes a medium's roughness
from a measured map through :meth:`emscatter.radio.MaterialSpec.from_height_map` (the map's
ring-averaged spectrum, or σ, ℓ of a fitted correlation), with the band each frequency needs
checked against the map before a ray is traced: ``--medium NAME=map`` gives it to the media
named, without any ``NAME=map`` it is the roughness of every medium not named by ``--medium``.
The map's record (file, choices, σ, ℓ, band checks) is written to ``<scene>_height_map.json``.
"""

from __future__ import annotations

import argparse
import importlib.util
import math
import re
from pathlib import Path
from typing import NamedTuple

from .args import Integer, Number, OutputFolder, OutputPath, add_command, reject_unless
from .heightmap_args import HEIGHT_MAP_OPTIONS, add_height_map_args, map_error

SCENES = ("room", "floor_wall", "box")


class Textured(NamedTuple):
    """An anisotropic ``--medium`` value: the surface and the world direction of its ℓx axis."""

    surface: object
    direction: tuple | None


#: The ``--medium NAME=map`` value: the medium's roughness is ``--height-map``'s.
MAP = "map"
#: How ``--height-map`` becomes a radio roughness (``radio.from_map.surface_from_map``).
MAP_MODELS = ("measured", "fit")
#: Transmitters [m] for the scenes that need none on the command line (simple_street_canyon:
#: in the main street, 10 m up, facing the brick building_2).
DEFAULT_TX = {"simple_street_canyon": (20.0, 0.0, 10.0)}


def sionna_scene_names() -> list[str]:
    """Scenes shipped with Sionna RT (folders of ``sionna/rt/scenes``), found without importing
    Sionna (it sets a Dr.Jit variant)."""
    spec = importlib.util.find_spec("sionna")
    if spec is None or not spec.submodule_search_locations:
        return []
    root = Path(next(iter(spec.submodule_search_locations))) / "rt" / "scenes"
    if not root.is_dir():
        return []
    return sorted(p.name for p in root.iterdir() if p.is_dir() and not p.name.startswith("_"))


def _scene(text: str) -> str:
    """An indoor set-up, ``all``, a Sionna scene name, or an existing ``*.xml`` file."""
    if text in (*SCENES, "all"):
        return text
    if text.lower().endswith(".xml"):
        if not Path(text).expanduser().is_file():
            raise argparse.ArgumentTypeError(f"no scene file at {text!r} (a Mitsuba/Sionna XML)")
        return str(Path(text).expanduser())
    names = sionna_scene_names()
    if text in names:
        return text
    raise argparse.ArgumentTypeError(
        f"invalid choice: {text!r} (choose from {', '.join((*SCENES, 'all'))}, a Sionna scene "
        f"({', '.join(names) or 'Sionna RT is not installed'}) or a *.xml scene file)"
    )


def _medium(text: str) -> tuple[str, object]:
    """``NAME=σ,ℓ`` [m] (Gaussian correlation), ``NAME=σ,ℓx,ℓy@DIR`` (anisotropic, ``DIR`` the
    world direction of the ℓx axis: ``x|y|z|vertical`` or ``dx,dy,dz``;
    :func:`emscatter.radio.texture.parse_medium_option`), ``NAME=flat`` or ``NAME=map`` (the
    roughness of ``--height-map``) → ``(NAME, (σ, ℓ) | Textured | None | "map")``."""
    m = re.fullmatch(r"\s*([^=\s]+)\s*=\s*(.+?)\s*", text)
    if m is None:
        raise argparse.ArgumentTypeError(
            "expected NAME=SIGMA,LENGTH in metres (e.g. brick=0.8e-3,8e-3), "
            "NAME=SIGMA,LENGTH_X,LENGTH_Y@DIR, NAME=flat or NAME=map (with --height-map), "
            f"got {text!r}"
        )
    name, value = m.groups()
    if value.lower() == "flat":
        return name, None
    if value.lower() == "map":
        return name, MAP
    if "@" in value or value.count(",") == 2:
        from ..radio.texture import parse_medium_option

        try:
            parsed = parse_medium_option(f"{name}={value}")
        except ValueError as exc:
            raise argparse.ArgumentTypeError(str(exc).removeprefix("--medium ")) from None
        return name, Textured(parsed["surface"], parsed["texture_direction"])
    parts = value.split(",")
    if len(parts) != 2:
        raise argparse.ArgumentTypeError(
            f"{name}: expected SIGMA,LENGTH in metres (two numbers, e.g. 0.8e-3,8e-3) or "
            f"SIGMA,LENGTH_X,LENGTH_Y@DIR, got {value!r}"
        )
    sigma = Number(low=0.0, high=1.0, unit="m")(parts[0].strip())
    length = Number(low=0.0, high=100.0, unit="m")(parts[1].strip())
    return name, (sigma, length)


def _point(text: str) -> tuple[float, float, float]:
    """``X,Y,Z`` [m]: three finite numbers within ±1e6 m."""
    parts = text.split(",")
    if len(parts) != 3:
        raise argparse.ArgumentTypeError(
            f"expected X,Y,Z in metres (three comma-separated numbers), got {text!r}"
        )
    out = []
    for axis, part in zip("XYZ", parts, strict=True):
        try:
            out.append(float(Number(low=-1e6, high=1e6, unit="m")(part.strip())))
        except argparse.ArgumentTypeError as exc:
            raise argparse.ArgumentTypeError(f"{axis} of {text!r}: {exc}") from None
    return tuple(out)  # type: ignore[return-value]


def _frequencies_ghz(text: str) -> tuple[float, ...]:
    """``'3.5,28,140'`` [GHz] → Hz; each in [1, 1000] GHz."""
    out = []
    for part in text.split(","):
        v = Number(low=1.0, high=1000.0, low_open=False, high_open=False, unit="GHz")(part.strip())
        out.append(v * 1e9)
    if not out:
        raise argparse.ArgumentTypeError("give at least one frequency [GHz], e.g. '3.5,28,140'")
    return tuple(out)


def register(subparsers) -> None:
    r = add_command(
        subparsers,
        "radio",
        help="indoor scenes in Sionna RT: emscatter rough materials vs Sionna's constant-S ones",
        description=(
            "Runs Sionna RT (CPU) on an indoor scene with three material sets: Sionna's ITU "
            "materials with a constant scattering coefficient S = 0.3 and a Lambertian lobe, "
            "emscatter materials without roughness, and emscatter rough materials. Writes path "
            "gain and RMS delay spread per receiver (CSV), radio-map difference images and a "
            "summary against frequency (PNG). --plate runs the large-plate cross-check instead."
        ),
    )
    r.add_argument(
        "--scene",
        default="room",
        type=_scene,
        metavar="NAME|FILE",
        help=(
            "room, floor_wall, box or all (the indoor cross-check), or any Sionna scene name "
            "(simple_street_canyon, ...) or a Mitsuba/Sionna *.xml file (rough − flat maps)"
        ),
    )
    r.add_argument(
        "--medium",
        action="append",
        type=_medium,
        default=[],
        metavar="NAME=SIGMA,LENGTH",
        help=(
            "roughness of an ITU type, material or object of the scene: rms height and "
            "correlation length [m] (Gaussian), NAME=SIGMA,LENGTH_X,LENGTH_Y@DIR (anisotropic: "
            "DIR = x|y|z|vertical|dx,dy,dz, the world direction of the LENGTH_X axis), or "
            "NAME=flat; repeat for more. Unnamed media "
            "take emscatter's default table (emscatter.radio.DEFAULT_ROUGHNESS)"
        ),
    )
    r.add_argument(
        "--tx", type=_point, default=None, metavar="X,Y,Z", help="transmitter position [m]"
    )
    r.add_argument(
        "--rx",
        type=_point,
        action="append",
        default=None,
        metavar="X,Y,Z",
        help=(
            "receiver position [m], repeat for more (any-scene mode): adds <scene>_<f>_paths.csv "
            "with flat and rough path gains and cross-polar discrimination per link "
            "(flat_xpd_db, rough_xpd_db: co- over cross-polar power, isotropic V/H antennas)"
        ),
    )
    r.add_argument(
        "--map-height",
        type=Number(low=-1e4, high=1e4, unit="m"),
        default=1.5,
        help="height z of the radio-map plane [m] (any-scene mode)",
    )
    r.add_argument(
        "--frequencies-ghz",
        type=_frequencies_ghz,
        default="3.5,28,140",
        metavar="LIST",
        help="comma-separated frequencies [GHz]",
    )
    r.add_argument(
        "--samples",
        type=Integer(low=1000, high=100_000_000),
        default=300_000,
        help="rays per source",
    )
    r.add_argument("--max-depth", type=Integer(low=1, high=8), default=3, help="bounces")
    r.add_argument(
        "--cell-size",
        type=Number(low=0.0, high=100.0, unit="m"),
        default=None,
        help="radio-map cell size [m] (default 0.1 m indoors, 1/100 of the scene elsewhere)",
    )
    r.add_argument(
        "--extrapolate",
        action="store_true",
        help=(
            "allow materials outside their ITU-R P.2040 bands (e.g. ITU metal, 1–100 GHz, at "
            "140 GHz) with the documented extrapolation, recorded in the CSV and JSON outputs; "
            "without it such a run is an error before anything is computed"
        ),
    )
    r.add_argument(
        "--builtin-json",
        type=OutputPath(suffixes=(".json",)),
        default=None,
        metavar="FILE",
        help=(
            "write Sionna's built-in parameters (scattering coefficient S, lobe, XPD coefficient) "
            "fitted to emscatter per --medium (default: emscatter's roughness table, media in "
            "band) and frequency, with the fit's error and flags where no built-in model stands "
            "in (emscatter.radio.builtin_equivalent); no ray is traced"
        ),
    )
    add_height_map_args(r)
    r.add_argument(
        "--map-model",
        default="measured",
        choices=MAP_MODELS,
        help=(
            "with --height-map: the map's ring-averaged measured spectrum, or σ, ℓ of the "
            "correlation family (Gaussian or exponential) that fits the map best"
        ),
    )
    r.add_argument(
        "--xpd-map",
        action="store_true",
        help=(
            "any-scene mode: also cross-polar discrimination per radio-map cell, flat and rough "
            "(isotropic V and H transmitters, V/H receive ports): <scene>_<f>_xpd_map.csv/.png "
            "and <scene>_xpd_vs_frequency.csv/.png (median and quartiles per frequency)"
        ),
    )
    r.add_argument(
        "--diffuse-transmission",
        action="store_true",
        help=(
            "any-scene mode: rough slabs (isotropic, with a thickness) also scatter diffusely "
            "into the back hemisphere (radio maps only: Sionna's PathSolver cannot carry it)"
        ),
    )
    r.add_argument(
        "--transmission-face",
        default="auto",
        metavar="MODEL",
        help=(
            "with --diffuse-transmission: the slab faces' model, auto (GO where it holds, else "
            "the first of SPM, PO, IEM valid from both sides), go, spm, po or iem "
            "(emscatter.radio.slab_faces.FACES)"
        ),
    )
    r.add_argument("--quick", action="store_true", help="few rays, coarse maps and tables")
    r.add_argument(
        "--quiet",
        action="store_true",
        help="no progress bar (drawn on stderr only when it is a terminal and the work runs past "
        "2 s anyway)",
    )
    r.add_argument("--plate", action="store_true", help="run the large-plate cross-check")
    r.add_argument("--out", type=OutputFolder(), default="out/radio", help="output folder")
    r.set_defaults(func=run)


def run(a) -> int:
    """``emscatter radio`` (module docstring); ``--quiet`` silences every progress bar of the
    tables and sweeps it builds (:func:`emscatter.progress.silenced`)."""
    from ..progress import silenced

    with silenced(a.quiet):
        return _run(a)


def _check_transmission_face(a) -> None:
    """``--transmission-face``: one of the slab faces' models, and only with
    ``--diffuse-transmission`` (ValueError naming the option otherwise)."""
    from ..radio.slab_faces import FACES

    if a.transmission_face not in FACES:
        raise ValueError(
            f"--transmission-face must be one of {', '.join(FACES)}, got {a.transmission_face!r}"
        )
    reject_unless(
        a, a.diffuse_transmission, ("--transmission-face",), "only with --diffuse-transmission"
    )


def _run(a) -> int:
    from pathlib import Path

    out = Path(a.out)
    if a.plate and a.height_map:
        raise ValueError("--height-map applies to scenes, not to --plate")
    a.map_spec = _map_spec(a)  # the map read and its band checked before anything else
    _check_transmission_face(a)
    for flag, on in (("--xpd-map", a.xpd_map), ("--diffuse-transmission", a.diffuse_transmission)):
        if on and (a.plate or a.builtin_json is not None):
            raise ValueError(
                f"{flag} applies to scenes (radio maps), not to --plate or --builtin-json"
            )
    if a.builtin_json is not None:
        if a.plate or a.tx is not None or a.extrapolate:
            raise ValueError(
                "--builtin-json fits materials only: drop --plate, --tx and --extrapolate"
            )
        return run_builtin_json(a)
    if a.plate and a.extrapolate:
        raise ValueError(
            "--extrapolate applies to the indoor scenes, not to --plate (its media are in band)"
        )
    if a.plate and (a.medium or a.tx is not None or a.rx):
        raise ValueError("--medium and --tx apply to scenes, not to --plate")
    if a.plate:
        from ..radio import demo

        for p in demo.run(out, a.quick):
            print(f"  {p}")
        return 0
    if (a.medium or a.tx is not None or a.rx or a.height_map or a.xpd_map
            or a.diffuse_transmission or a.scene not in (*SCENES, "all")):  # fmt: skip
        return run_any_scene(a)
    if a.cell_size is None:
        a.cell_size = 0.1
    from ..radio import indoor
    from ..radio.tables import TableOptions

    names = SCENES if a.scene == "all" else (a.scene,)
    # Every medium against its ITU-R P.2040 bands before any ray is traced (OutOfBandError,
    # naming medium, frequency and bands, unless --extrapolate).
    extrapolated = indoor.check_bands(names, a.frequencies_ghz, extrapolate=a.extrapolate)
    for e in extrapolated:
        print(
            f"extrapolating {e['medium']!r} ({e['scene']}) to {e['frequency_ghz']:g} GHz, outside "
            "its ITU-R P.2040 bands (recorded in the outputs)"
        )
    kw = {
        "samples": a.samples,
        "cell_size": a.cell_size,
        "max_depth": a.max_depth,
        "extrapolate": a.extrapolate,
    }
    if a.quick:
        kw.update(samples=min(a.samples, 20_000), cell_size=max(a.cell_size, 0.5), max_depth=2)
        kw["table_options"] = TableOptions(n_cos=65, n_cos_spm=9, n_theta=16, n_alpha=13, n_s=32)
    result = indoor.compare(names, a.frequencies_ghz, **kw)
    for p in indoor.write_outputs(result, out):
        print(f"  {p}")
    for s in indoor.summarize(result["rows"]):
        print(
            f"{s['scene']:<10} {s['frequency_ghz']:7g} GHz   rough − flat: median |Δ path gain| "
            f"{s['median_abs_dpg_vs_flat_db']:.2f} dB, |Δ delay spread| "
            f"{s['median_abs_dds_vs_flat_ns']:.2f} ns;   rough − Sionna S=0.3: "
            f"{s['median_abs_dpg_vs_sionna_db']:.2f} dB, {s['median_abs_dds_vs_sionna_ns']:.2f} ns"
        )
    return 0


def _map_spec(a):
    """The :class:`~emscatter.radio.MaterialSpec` of ``--height-map`` (its ``surface`` and
    ``map_record``), or None; every option and the band of every frequency checked here,
    before Sionna is imported. ValueError naming the option or the file."""
    reject_unless(a, a.height_map is not None, (*HEIGHT_MAP_OPTIONS, "--map-model"),
                  "only with --height-map FILE")  # fmt: skip
    named = [n for n, v in a.medium if v is MAP]
    if a.height_map is None:
        if named:
            raise ValueError(
                f"--medium {named[0]}=map takes the roughness of --height-map FILE, which is "
                "missing: give the map, or NAME=SIGMA,LENGTH"
            )
        return None
    from ..radio import MaterialSpec
    from ..surfaces.heightmap import HeightMapError

    try:
        return MaterialSpec.from_height_map(
            a.height_map, model=a.map_model, segments=a.segments, tail=a.tail, unit=a.unit,
            detrend=a.detrend, holes=a.holes, slope_tail=a.slope_tail,
            frequencies=a.frequencies_ghz,
        )  # fmt: skip
    except (HeightMapError, ImportError, ValueError) as exc:
        raise map_error(a.height_map, exc) from None


def _map_roughness(a) -> tuple[dict, object]:
    """``(mapping, roughness)`` for :func:`~emscatter.radio.roughening.roughen`: ``--medium``'s
    entries with ``NAME=map`` replaced by the map's roughness; without any ``NAME=map`` the
    map's roughness is the common one (every medium not named by ``--medium``)."""
    spec = getattr(a, "map_spec", None)
    mapping = {
        n: (spec.surface if v is MAP else v.surface if isinstance(v, Textured) else v)
        for n, v in a.medium
    }
    if spec is None or any(v is MAP for _, v in a.medium):
        return mapping, None
    return mapping, spec.surface


def _texture_directions(a) -> dict | None:
    """``{medium: direction}`` of the anisotropic ``--medium NAME=σ,ℓx,ℓy@DIR`` entries (None
    when there are none), for :func:`~emscatter.radio.roughening.roughen`'s
    ``texture_direction``."""
    dirs = {n: v.direction for n, v in a.medium if isinstance(v, Textured) and v.direction}
    return dirs or None


def _write_map_record(a, out: Path, stem: str) -> None:
    spec = getattr(a, "map_spec", None)
    if spec is None:
        return
    from ..io import write_json

    record = {"height_map": str(a.height_map), "detrend": a.detrend, "unit": a.unit,
              "applies_to": [n for n, v in a.medium if v is MAP] or "every medium not named "
              "by --medium", **spec.map_record}  # fmt: skip
    print(f"  {write_json(out / f'{stem}_height_map.json', record)}")
    band = ", ".join(
        f"{b['frequency_hz'] / 1e9:g} GHz {100 * b['fraction_below']:.0f}% of |K| ≤ 2k below "
        "the map's band"
        for b in spec.map_record.get("band", [])
    )
    print(
        f"height map {a.height_map}: σ = {spec.map_record['sigma_m']:.4g} m, ℓ(1/e) = "
        f"{spec.map_record['length_1_over_e_m']:.4g} m ({a.map_model}; {band})"
    )


def _quick_tables():
    from ..radio.tables import TableOptions

    return TableOptions(n_cos=65, n_cos_spm=9, n_theta=16, n_alpha=13, n_s=32)


def _load_any(a):
    """The Sionna scene of ``--scene`` with its own (ITU) materials, at Sionna's default
    frequency (the bands are checked by emscatter before the frequency is set)."""
    import sionna.rt as rt

    from ..radio import indoor, scenes

    if a.scene == "all":
        raise ValueError("--scene all is the indoor cross-check; name one scene with --medium/--tx")
    if a.scene in indoor.SETUPS and not isinstance(indoor.SETUPS[a.scene].scene, str):
        spec = indoor.SETUPS[a.scene].scene  # the generated room: Sionna's ITU materials
        return scenes.load(
            spec, 3.5e9,
            lambda o, m, t: rt.ITURadioMaterial(f"itu-{o}", itu_type=m, thickness=t),
        )  # fmt: skip
    if a.scene.lower().endswith(".xml"):
        return rt.load_scene(a.scene, merge_shapes=False)
    return rt.load_scene(getattr(rt.scene, a.scene), merge_shapes=False)


def run_any_scene(a) -> int:
    """Rough − flat radio maps of any scene (module docstring)."""
    import numpy as np

    from ..radio import indoor
    from ..radio.roughening import compare_rough_flat, plan, write_comparison
    from ..radio.xpd_map import write_xpd_map, write_xpd_vs_frequency, xpd_summary

    tx = a.tx
    if tx is None:
        setup = indoor.SETUPS.get(a.scene)
        tx = setup.tx if setup is not None else DEFAULT_TX.get(a.scene)
    if tx is None:
        raise ValueError(
            f"--tx X,Y,Z [m] is required for scene {a.scene!r} (where the transmitter stands)"
        )
    mapping, common = _map_roughness(a)
    freqs = a.frequencies_ghz
    import sionna.rt as rt

    if a.extrapolate:
        raise ValueError(
            "--extrapolate applies to the indoor cross-check (--scene room|floor_wall|box|all); "
            "the scene's own ITU materials, the flat reference here, stop at their bands"
        )
    sc = _load_any(a)
    # every name, medium and band checked before a ray is traced
    plan(sc, common, mapping=mapping, frequencies=freqs, extrapolate=a.extrapolate)
    arr = rt.PlanarArray(num_rows=1, num_cols=1, pattern="iso", polarization="V")
    sc.tx_array = sc.rx_array = arr
    sc.add(rt.Transmitter("tx", position=[float(x) for x in tx]))
    for i, p in enumerate(a.rx or ()):
        sc.add(rt.Receiver(f"rx{i}", position=[float(x) for x in p]))
    box = sc.mi_scene.bbox()
    lo, hi = np.array(box.min), np.array(box.max)
    size = hi[:2] - lo[:2]
    cell = a.cell_size or float(max(size.max() / 100.0, 0.05))
    samples, depth, opts = a.samples, a.max_depth, None
    if a.quick:
        samples, depth, opts = min(samples, 100_000), min(depth, 2), _quick_tables()
        cell = max(cell, float(size.max() / 60.0))
    stem = Path(a.scene).stem
    out = Path(a.out)
    _write_map_record(a, out, stem)
    xpd_rows = []
    for f in freqs:
        sc.frequency = f
        res = compare_rough_flat(
            sc, common, mapping=mapping, extrapolate=a.extrapolate, table_options=opts,
            frequencies=freqs, xpd=bool(a.rx), texture_direction=_texture_directions(a),
            xpd_map=a.xpd_map, transmission="diffuse" if a.diffuse_transmission else "coherent",
            transmission_face=a.transmission_face,
            paths={"samples_per_src": samples, "max_depth": depth} if a.rx else False,
            radio_map={"center": (*((lo[:2] + hi[:2]) / 2), a.map_height),
                       "orientation": (0.0, 0.0, 0.0), "size": tuple(size),
                       "cell_size": (cell, cell), "samples_per_tx": samples, "max_depth": depth},
        )  # fmt: skip
        for p in write_comparison(res, out, f"{stem}_{f / 1e9:g}GHz", title=stem, tx_xy=tx[:2]):
            print(f"  {p}")
        d = res["radio_map"]["difference_db"]
        lit = res["radio_map"]["lit"]
        med = float(np.median(d[lit])) if lit.any() else math.nan
        print(
            f"{stem} {f / 1e9:g} GHz: rough − flat median {med:+.2f} dB over {int(lit.sum())} "
            f"cells lit in both ({cell:g} m cells, {samples} rays, depth {depth})"
        )
        if a.xpd_map:
            for p in write_xpd_map(res, out, f"{stem}_{f / 1e9:g}GHz", title=stem, tx_xy=tx[:2]):
                print(f"  {p}")
            xm = res["xpd_map"]
            both = xm["flat"]["lit"][0] & xm["rough"]["lit"][0]  # the same cells for both
            row = {"frequency_hz": f, **{s: xpd_summary(xm[s]["xpd_db"][0], both)
                                         for s in ("flat", "rough")}}  # fmt: skip
            xpd_rows.append(row)
            print(
                f"  XPD per cell ({row['flat']['n']} cells lit in both): flat median "
                f"{row['flat']['median']:.1f} dB (quartiles "
                f"{row['flat']['q25']:.1f}…{row['flat']['q75']:.1f}), rough median "
                f"{row['rough']['median']:.1f} dB ({row['rough']['q25']:.1f}…"
                f"{row['rough']['q75']:.1f})"
            )
        for i, name in enumerate(res.get("receivers", []) if a.rx else []):
            pg, x = res["path_gain"], res["xpd"]
            print(
                f"  {name}: rough − flat {pg['difference_db'][i, 0]:+.2f} dB, XPD flat "
                f"{x['flat'][i, 0]:.1f} dB, rough {x['rough'][i, 0]:.1f} dB"
            )
    if xpd_rows:
        for p in write_xpd_vs_frequency(xpd_rows, out, stem, title=stem):
            print(f"  {p}")
    return 0


def run_builtin_json(a) -> int:
    """``--builtin-json FILE``: one fit per medium and frequency (no Sionna needed)."""
    from ..materials import OutOfBandError
    from ..radio import MaterialSpec, builtin
    from ..radio.roughening import DEFAULT_ROUGHNESS
    from ..spectra import GaussianCorrelation

    opts = _quick_tables() if a.quick else None
    if a.map_spec is not None and not any(v is MAP for _, v in a.medium):
        raise ValueError(
            "--builtin-json with --height-map: name the medium the map is of with --medium "
            "NAME=map (e.g. --medium concrete=map)"
        )
    textured = [n for n, v in a.medium if isinstance(v, Textured)]
    if textured:
        raise ValueError(
            f"--builtin-json fits Sionna's isotropic built-in models; --medium {textured[0]}= "
            "is anisotropic (σ,ℓx,ℓy@DIR): give it as NAME=σ,ℓ"
        )
    given = {n: (None if v is None else a.map_spec.surface if v is MAP
                 else GaussianCorrelation(sigma=v[0], length=v[1]))
             for n, v in a.medium}  # fmt: skip
    media = given or {n: r for n, r in DEFAULT_ROUGHNESS.items() if r is not None}
    fits = []
    for name, rough in media.items():
        spec = MaterialSpec(surface=rough, medium=name, thickness=None, options=opts)
        spec.material()  # an unknown medium fails here, naming it
        for f in a.frequencies_ghz:
            try:
                eq = builtin.builtin_equivalent(spec, f)
            except OutOfBandError:
                if given:
                    raise
                print(f"  skipped {name} at {f / 1e9:g} GHz: outside its ITU-R P.2040 bands")
                continue
            fits.append(eq)
            pat = eq["scattering_pattern"]
            lobe = ", ".join(f"{k}={v}" for k, v in pat.items() if k != "name")
            state = "valid" if eq["valid"] else "NOT valid: " + " | ".join(eq["flags"])
            print(
                f"{name} {f / 1e9:g} GHz: S = {eq['scattering_coefficient']:.3f}, "
                f"{pat['name']}({lobe}), K_x = {eq['xpd_coefficient']:.3f}, lobe power misplaced "
                f"{100 * eq['error']['lobe_misplaced_at_fit']:.0f} % ({state})"
            )
    if not fits:
        raise ValueError("no medium in band at the frequencies given; name one with --medium")
    print(f"  {builtin.write_json(a.builtin_json, fits)}")
    return 0
