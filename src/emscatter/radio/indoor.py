"""Cross-check 2: indoor scenes with Sionna's default materials against emscatter materials.

Three material sets on the same geometry, at each frequency:

* ``"sionna"`` — Sionna's usual model: the ITU-R P.2040 medium with one constant scattering
  coefficient ``S`` (:data:`DEFAULT_S`) and a Lambertian lobe, whatever the roughness or the
  frequency;
* ``"flat"`` — emscatter material without roughness (identical to Sionna's ``RadioMaterial``
  with ``S = 0``: the bridge adds nothing where physics adds nothing);
* ``"rough"`` — emscatter material with the roughness of :data:`ROUGHNESS`: coherent reflection,
  lobe and cross-polarization from the solvers, per angle and frequency.

Per receiver: the path gain ``Σ|a|²`` and the RMS delay spread of the power-delay profile; per
scene a radio map (path gain on a horizontal plane). ``rough − flat`` isolates what roughness
does; ``rough − sionna`` is what replacing the constant-``S`` model changes.

A medium outside its ITU-R P.2040 bands (the ITU metal stops at 100 GHz: Sionna's ``box`` at
140 GHz) is an :class:`~emscatter.materials.OutOfBandError` naming the medium, the frequency and
the bands, raised by :func:`check_bands` before anything is computed — unless
``extrapolate=True``, which uses the documented extrapolation of :func:`emscatter.materials.itu`
in all three sets and records each extrapolated medium in the results (``"extrapolated"``).

Path buffer: Sionna keeps at most ``max_num_paths_per_src`` candidate paths per source and
drops the rest — in thread order with its default candidate generator, so a full buffer made a
run irreproducible (rough materials: 20 k rays give ≈ 46 k candidates at depth 2).
:func:`run_scene` sizes it at :data:`PATHS_PER_RAY` candidates per ray, enlarges it (×4, up to
:data:`MAX_PATHS_PER_RAY`) and reruns when it was filled, and warns
(:class:`PathBufferWarning`) if it is still full. It uses Sionna's deterministic candidate
generator (``PathSolver(deterministic=True)``: candidates kept and de-duplicated in ray order)
and sums path powers in float64 in a fixed (sorted) order, so the same seed gives the same
numbers, bit for bit.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import asdict, dataclass

import numpy as np

from .. import materials
from ..spectra import GaussianCorrelation
from . import scenes

__all__ = [
    "ROUGHNESS",
    "DEFAULT_S",
    "SceneSetup",
    "SETUPS",
    "medium_at",
    "check_bands",
    "material_factory",
    "run_scene",
    "PathBufferWarning",
    "PATHS_PER_RAY",
    "MAX_PATHS_PER_RAY",
]

#: Candidate paths kept per ray at first (Sionna's cap ``max_num_paths_per_src`` = this × the
#: rays per source): the quick rough room (20 k rays, depth 2) needs ≈ 2.3 per ray; a cap of
#: 10 per ray gave the same path gain three times in a row (issue 23: −92.745 dB).
PATHS_PER_RAY = 10
#: The largest cap tried (per ray) before :class:`PathBufferWarning`.
MAX_PATHS_PER_RAY = 160


class PathBufferWarning(UserWarning):
    """Sionna's path buffer was full: candidate paths were dropped, so path gains and delay
    spreads miss part of the power."""


#: Sionna's constant scattering coefficient for the "sionna" set (Degli-Esposti et al. 2007
#: report S ≈ 0.2–0.4 for building walls at UHF; one value for every material and frequency).
DEFAULT_S = 0.3

#: Roughness statistics per medium [m] (Gaussian correlation): plastered concrete and brick
#: are rough at millimetre-wave scale, plasterboard and wood nearly smooth, glass flat.
ROUGHNESS = {
    "concrete": GaussianCorrelation(sigma=0.4e-3, length=4e-3),
    "brick": GaussianCorrelation(sigma=0.8e-3, length=8e-3),
    "plasterboard": GaussianCorrelation(sigma=0.05e-3, length=2e-3),
    "ceiling_board": GaussianCorrelation(sigma=0.5e-3, length=3e-3),
    "wood": GaussianCorrelation(sigma=0.05e-3, length=2e-3),
    "metal": GaussianCorrelation(sigma=0.1e-3, length=5e-3),
    "glass": None,
}


@dataclass(frozen=True)
class SceneSetup:
    """Geometry (a :class:`~emscatter.radio.scenes.SceneSpec` or a Sionna scene name), a
    transmitter, receivers and a radio-map plane (centre, size [m])."""

    name: str
    scene: object
    tx: tuple
    rx: tuple
    map_center: tuple
    map_size: tuple


SETUPS = {
    "room": SceneSetup(
        "room",
        scenes.furnished_room(),
        tx=(1.0, 1.0, 2.5),
        rx=((4.8, 3.8, 1.2), (2.2, 4.3, 1.2), (3.6, 2.2, 0.4), (5.2, 1.0, 1.6), (0.8, 4.2, 1.5)),
        map_center=(3.0, 2.5, 1.2),
        map_size=(6.0, 5.0),
    ),
    "floor_wall": SceneSetup(
        "floor_wall",
        "floor_wall",
        tx=(1.5, -1.0, 1.5),
        rx=((1.5, 1.2, 1.5), (0.6, 0.0, 1.0), (-1.2, 0.5, 1.5)),
        map_center=(0.0, 0.0, 1.5),
        map_size=(4.0, 4.0),
    ),
    "box": SceneSetup(
        "box",
        "box",
        tx=(-2.0, -2.0, 2.5),
        rx=((2.0, 1.0, 1.5), (3.5, -3.0, 1.0), (-3.0, 3.5, 2.0)),
        map_center=(0.0, 0.0, 1.5),
        map_size=(9.8, 9.8),
    ),
}


def medium_at(name: str, frequency: float, *, extrapolate: bool = False):
    """The ITU medium at ``frequency`` [Hz]: :class:`~emscatter.materials.OutOfBandError`
    (naming the medium, the frequency and its bands) out of its bands, or with
    ``extrapolate=True`` the documented extrapolation there."""
    mat = materials.itu(name)
    if np.all(mat.in_band(frequency)):
        return mat
    if not extrapolate:
        mat.eps(frequency=frequency)  # raises OutOfBandError with the medium's bands
    return materials.itu(name, extrapolate=True)


def scene_media(name: str) -> dict:
    """``object → (ITU medium, thickness)`` of the setup ``name`` (:data:`SETUPS`)."""
    if name not in SETUPS:
        raise ValueError(f"scene must be one of {sorted(SETUPS)}, got {name!r}")
    scene = SETUPS[name].scene
    return scenes.SIONNA_SCENES[scene] if isinstance(scene, str) else scene.media


def check_bands(names, frequencies, *, extrapolate: bool = False) -> list[dict]:
    """Every medium of the scenes ``names`` checked at every frequency [Hz] before anything is
    computed: ``[{"scene", "medium", "frequency_ghz", "bands_ghz"}, ...]`` for those out of
    their ITU-R P.2040 bands — an :class:`~emscatter.materials.OutOfBandError` listing them all
    unless ``extrapolate=True`` (then the list says what was extrapolated)."""
    out = []
    for name in names:
        for medium in sorted({m for m, _ in scene_media(name).values()}):
            mat = materials.itu(medium)
            for f in frequencies:
                if not np.all(mat.in_band(f)):
                    bands = [(lo / 1e9, hi / 1e9) for lo, hi in mat.bands]
                    out.append({"scene": name, "medium": medium, "frequency_ghz": f / 1e9,
                                "bands_ghz": bands})  # fmt: skip
    if out and not extrapolate:
        what = "; ".join(
            f"{e['medium']!r} in scene {e['scene']!r} at {e['frequency_ghz']:g} GHz (ITU-R P.2040 "
            "bands " + ", ".join(f"{lo:g}–{hi:g} GHz" for lo, hi in e["bands_ghz"]) + ")"
            for e in out
        )
        raise materials.OutOfBandError(
            f"materials outside their ITU-R P.2040 bands: {what}. Pick frequencies inside the "
            "bands, or extrapolate=True (CLI: --extrapolate) to use the documented "
            "extrapolation (recorded in the outputs)"
        )
    return out


def material_factory(
    kind: str,
    frequency: float,
    *,
    s: float = DEFAULT_S,
    table_options=None,
    extrapolate: bool = False,
):
    """``make_material(object, medium, thickness)`` for :func:`emscatter.radio.scenes.load`
    (``extrapolate``: see :func:`medium_at`)."""
    import sionna.rt as rt

    from .material import EmscatterRadioMaterial

    if kind not in ("sionna", "flat", "rough"):
        raise ValueError(f"kind must be 'sionna', 'flat' or 'rough', got {kind!r}")

    def make(obj, medium, thickness):
        med = medium_at(medium, frequency, extrapolate=extrapolate)
        if kind == "sionna":
            er, sig = med.eps_real_and_conductivity(frequency)
            return rt.RadioMaterial(
                f"{kind}-{obj}",
                thickness=thickness,
                relative_permittivity=float(er),
                conductivity=float(sig),
                scattering_coefficient=s,
                scattering_pattern="lambertian",
            )
        surface = ROUGHNESS.get(medium) if kind == "rough" else None
        return EmscatterRadioMaterial(
            f"{kind}-{obj}",
            surface=surface,
            medium=med,
            thickness=thickness,
            table_options=table_options,
        )

    return make


def add_devices(scene, setup: SceneSetup, polarization: str = "V") -> None:
    """The setup's transmitter ``"tx"`` and receivers ``"rx0"``, ``"rx1"``, ... with isotropic
    antennas of one polarization."""
    import sionna.rt as rt

    arr = rt.PlanarArray(num_rows=1, num_cols=1, pattern="iso", polarization=polarization)
    scene.tx_array = arr
    scene.rx_array = arr
    scene.add(rt.Transmitter("tx", position=list(setup.tx)))
    for i, p in enumerate(setup.rx):
        scene.add(rt.Receiver(f"rx{i}", position=list(p)))


def delay_spread(power: np.ndarray, tau: np.ndarray) -> float:
    """RMS delay spread [s] of a power-delay profile (powers [linear], delays [s])."""
    p = np.asarray(power, dtype=float)
    t = np.asarray(tau, dtype=float)
    total = p.sum()
    if total <= 0:
        return math.nan
    mean = (p * t).sum() / total
    return float(math.sqrt(max((p * t * t).sum() / total - mean * mean, 0.0)))


def run_scene(
    setup: SceneSetup,
    kind: str,
    frequency: float,
    *,
    samples: int,
    max_depth: int = 3,
    cell_size: float | None = 0.1,
    map_samples: int | None = None,
    s: float = DEFAULT_S,
    table_options=None,
    seed: int = 1,
    extrapolate: bool = False,
    paths_per_ray: int = PATHS_PER_RAY,
) -> dict:
    """Path gain [linear] and RMS delay spread [s] per receiver, and (if ``cell_size``) a radio
    map of path gain [linear] (NaN where no ray arrived).

    ``paths_per_ray`` sizes Sionna's path buffer (module docstring); ``"path_buffer"`` in the
    result says how large it was (``"cap"`` per source), how many candidates it kept
    (``"stored"``) and whether it was ``"full"`` (then a :class:`PathBufferWarning` was
    given)."""
    import sionna.rt as rt

    scene = scenes.load(
        setup.scene,
        frequency,
        material_factory(
            kind, frequency, s=s, table_options=table_options, extrapolate=extrapolate
        ),
    )
    add_devices(scene, setup)
    samples = int(samples)
    per_ray = max(int(paths_per_ray), 1)
    while True:
        # deterministic: candidates kept and de-duplicated in ray order, not thread order
        solver = rt.PathSolver(deterministic=True)
        counter = _count_candidates(solver)
        cap = per_ray * samples
        paths = solver(
            scene,
            max_depth=max_depth,
            samples_per_src=samples,
            max_num_paths_per_src=cap,
            diffuse_reflection=True,
            refraction=True,
            seed=seed,
        )
        stored = counter.get("stored")
        full = stored is not None and stored >= cap * counter["sources"]
        if not full or per_ray >= MAX_PATHS_PER_RAY:
            break
        per_ray = min(4 * per_ray, MAX_PATHS_PER_RAY)
    if full:
        warnings.warn(
            f"{setup.name} at {frequency / 1e9:g} GHz ({kind}): Sionna's path buffer was full "
            f"({cap} candidate paths per source for {samples} rays, depth {max_depth}): the "
            "candidates beyond it were dropped, so path gains and delay spreads miss part of "
            "the power. Use fewer rays (samples), a smaller max_depth, or paths_per_ray > "
            f"{per_ray}.",
            PathBufferWarning,
            stacklevel=2,
        )
    re, im = (np.asarray(x.numpy(), dtype=np.float64) for x in paths.a)
    power = (re**2 + im**2)[:, 0, 0, 0, :]  # [rx, path]
    tau = np.asarray(paths.tau.numpy(), dtype=np.float64)
    tau = tau[:, 0, 0, 0, :] if tau.ndim == 5 else tau[:, 0, :]
    # The solver returns paths in thread order: sort each receiver's paths (by delay, then
    # power) so that the float64 sums below do not depend on it.
    order = np.lexsort((power, tau), axis=-1)
    power = np.take_along_axis(power, order, axis=-1)
    tau = np.take_along_axis(tau, order, axis=-1)
    gain = power.sum(axis=1)
    spread = np.array([delay_spread(power[i], tau[i]) for i in range(power.shape[0])])
    out = {
        "path_gain": gain,
        "delay_spread": spread,
        "num_paths": int(power.shape[1]),
        "path_buffer": {"cap": cap, "stored": stored, "full": bool(full)},
    }
    if cell_size:
        rm = rt.RadioMapSolver()(
            scene,
            center=mi_point(setup.map_center),
            orientation=mi_point((0.0, 0.0, 0.0)),
            size=mi_point2(setup.map_size),
            cell_size=mi_point2((cell_size, cell_size)),
            samples_per_tx=int(map_samples or samples),
            max_depth=max_depth,
            diffuse_reflection=True,
            refraction=True,
            seed=seed,
        )
        pg = np.asarray(rm.path_gain.numpy())[0]
        out["radio_map"] = np.where(pg > 0, pg, np.nan)
    out["tables"] = [
        m.active_tables.describe()
        for m in scene.radio_materials.values()
        if getattr(m, "active_tables", None) is not None and m.is_used
    ]
    return out


def _count_candidates(solver) -> dict:
    """Wraps this solver's candidate generator (Sionna RT 2.x, ``PathSolver._candidate_generator``)
    to record how many candidate paths its buffer kept (``"stored"``, all sources, read before
    the image method drops invalid ones) and the number of ``"sources"``; ``{}`` after the call
    if this Sionna has no such generator (the buffer cannot be checked)."""
    rec: dict = {}
    gen = getattr(solver, "_candidate_generator", None)
    if gen is None or not callable(gen):
        return rec

    def counting(*args, **kwargs):
        import drjit as dr

        buf = gen(*args, **kwargs)
        counter = getattr(buf, "paths_counter", None)
        if counter is not None:
            if hasattr(counter, "numpy"):  # a Dr.Jit UInt: evaluates the candidate kernels
                dr.eval(counter)
                counter = np.asarray(counter.numpy()).max()
            rec["stored"] = int(counter)
            rec["sources"] = int(dr.width(kwargs["src_positions"]))
        return buf

    solver._candidate_generator = counting
    return rec


def mi_point(p):
    import mitsuba as mi

    return mi.Point3f(*(float(x) for x in p))


def mi_point2(p):
    import mitsuba as mi

    return mi.Point2f(*(float(x) for x in p))


FREQUENCIES = (3.5e9, 28e9, 140e9)
KINDS = ("sionna", "flat", "rough")


def compare(
    names=("room",),
    frequencies=FREQUENCIES,
    *,
    samples: int = 300_000,
    map_samples: int | None = None,
    cell_size: float = 0.1,
    max_depth: int = 3,
    table_options=None,
    extrapolate: bool = False,
    progress=print,
) -> dict:
    """Every scene × frequency × material set (module docstring): ``{"rows": [...] per
    receiver, "maps": {(scene, f, kind): path gain map}, "extrapolated": [...],
    "path_buffers": [...], "settings": {...}}``.

    Every medium is checked against its ITU-R P.2040 bands first (:func:`check_bands`): out of
    band is an :class:`~emscatter.materials.OutOfBandError` before any ray is traced, unless
    ``extrapolate=True``; each row's ``"extrapolated_media"`` names the media extrapolated
    there (``"none"``)."""
    if not isinstance(extrapolate, bool):
        raise TypeError(f"extrapolate must be True or False, got {extrapolate!r}")
    names, frequencies = tuple(names), tuple(float(f) for f in frequencies)
    extrapolated = check_bands(names, frequencies, extrapolate=extrapolate)
    rows, maps, buffers = [], {}, []
    for name in names:
        setup = SETUPS[name]
        for f in frequencies:
            here = sorted({e["medium"] for e in extrapolated
                           if e["scene"] == name and e["frequency_ghz"] == f / 1e9})  # fmt: skip
            for kind in KINDS:
                r = run_scene(
                    setup, kind, f, samples=samples, max_depth=max_depth, cell_size=cell_size,
                    map_samples=map_samples, table_options=table_options, extrapolate=extrapolate,
                )  # fmt: skip
                maps[(name, f, kind)] = r["radio_map"]
                buffers.append({"scene": name, "frequency_ghz": f / 1e9, "kind": kind,
                                **r["path_buffer"]})  # fmt: skip
                for i, (g, ds) in enumerate(zip(r["path_gain"], r["delay_spread"], strict=True)):
                    rows.append(
                        {"scene": name, "frequency_ghz": f / 1e9, "kind": kind, "rx": i,
                         "path_gain_db": 10 * math.log10(g) if g > 0 else -math.inf,
                         "delay_spread_ns": ds * 1e9,
                         "extrapolated_media": " ".join(here) or "none"}
                    )  # fmt: skip
                if progress:
                    progress(
                        f"{name} {f / 1e9:g} GHz {kind}: path gain "
                        + ", ".join(f"{10 * math.log10(g):.1f}" for g in r["path_gain"] if g > 0)
                        + " dB"
                    )
    settings = {
        "scenes": list(names),
        "frequencies_ghz": [f / 1e9 for f in frequencies],
        "samples": int(samples),
        "map_samples": map_samples,
        "cell_size_m": cell_size,
        "max_depth": int(max_depth),
        "table_options": None if table_options is None else asdict(table_options),
        "extrapolate": extrapolate,
    }
    return {
        "rows": rows,
        "maps": maps,
        "extrapolated": extrapolated,
        "path_buffers": buffers,
        "settings": settings,
    }


def summarize(rows: list) -> list:
    """Per scene and frequency: median over receivers of ``|ΔPG|`` [dB] and ``|Δτ_rms|`` [ns]
    for rough − flat (what roughness does) and rough − sionna (against the constant-S model)."""
    out = []
    key = {(r["scene"], r["frequency_ghz"], r["kind"], r["rx"]): r for r in rows}
    for scene, f in sorted({(r["scene"], r["frequency_ghz"]) for r in rows}):
        rxs = sorted({r["rx"] for r in rows if r["scene"] == scene})
        entry = {"scene": scene, "frequency_ghz": f}
        extra = {r.get("extrapolated_media", "none") for r in rows
                 if r["scene"] == scene and r["frequency_ghz"] == f}  # fmt: skip
        entry["extrapolated_media"] = " ".join(sorted(extra))
        for ref in ("flat", "sionna"):
            rough = [key[(scene, f, "rough", i)] for i in rxs]
            other = [key[(scene, f, ref, i)] for i in rxs]
            dpg = [a["path_gain_db"] - b["path_gain_db"] for a, b in zip(rough, other, strict=True)]
            dds = [
                a["delay_spread_ns"] - b["delay_spread_ns"]
                for a, b in zip(rough, other, strict=True)
            ]
            entry[f"median_abs_dpg_vs_{ref}_db"] = float(np.median(np.abs(dpg)))
            entry[f"max_abs_dpg_vs_{ref}_db"] = float(np.max(np.abs(dpg)))
            entry[f"median_abs_dds_vs_{ref}_ns"] = float(np.median(np.abs(dds)))
        out.append(entry)
    return out


def write_outputs(result: dict, out_dir, stem: str = "indoor") -> list:
    """``<stem>_receivers.csv``, ``<stem>_summary.csv``, ``<stem>_run.json`` (the settings,
    the media extrapolated out of their bands, the path-buffer use), ``<stem>_maps_<scene>.png``
    (radio map of the rough set and its differences per frequency) and
    ``<stem>_vs_frequency.png``."""
    from pathlib import Path

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..io import save_figure, write_csv, write_json

    out = Path(out_dir)
    rows = result["rows"]
    written = []
    cols = list(rows[0])
    written.append(
        write_csv(
            out / f"{stem}_receivers.csv", cols, [np.array([r[c] for r in rows]) for c in cols]
        )
    )
    summ = summarize(rows)
    cols = list(summ[0])
    written.append(
        write_csv(out / f"{stem}_summary.csv", cols, [np.array([r[c] for r in summ]) for c in cols])
    )
    run = {
        "settings": result.get("settings", {}),
        "extrapolated": result.get("extrapolated", []),
        "path_buffers": result.get("path_buffers", []),
    }
    written.append(write_json(out / f"{stem}_run.json", run))
    maps = result["maps"]
    for scene in sorted({k[0] for k in maps}):
        setup = SETUPS[scene]
        freqs = sorted({k[1] for k in maps if k[0] == scene})
        fig, axes = plt.subplots(len(freqs), 3, figsize=(12, 3.3 * len(freqs)), squeeze=False)
        (cx, cy, _), (sx, sy) = setup.map_center, setup.map_size
        ext = (cx - sx / 2, cx + sx / 2, cy - sy / 2, cy + sy / 2)
        for row, f in zip(axes, freqs, strict=True):
            rough = 10 * np.log10(maps[(scene, f, "rough")])
            vs_sionna = rough - 10 * np.log10(maps[(scene, f, "sionna")])
            vs_flat = rough - 10 * np.log10(maps[(scene, f, "flat")])
            panels = (
                (rough, f"{f / 1e9:g} GHz: path gain, emscatter rough [dB]", "viridis", None),
                (vs_sionna, f"rough − Sionna S = {DEFAULT_S:g} [dB]", "RdBu_r", 6),
                (vs_flat, "rough − flat [dB]", "RdBu_r", 6),
            )
            for ax, (img, title, cmap, lim) in zip(row, panels, strict=True):
                kw = {"vmin": -lim, "vmax": lim} if lim else {}
                im = ax.imshow(img, origin="lower", extent=ext, cmap=cmap, **kw)  # [y, x]
                ax.plot(*setup.tx[:2], "r*", ms=9)
                ax.set_title(title, fontsize=9)
                fig.colorbar(im, ax=ax, shrink=0.85)
        fig.suptitle(f"{scene}: radio maps at z = {setup.map_center[2]:g} m (Tx ★)")
        written.append(save_figure(fig, out / f"{stem}_maps_{scene}.png"))
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4))
    for i, scene in enumerate(sorted({s["scene"] for s in summ})):
        ss = [s for s in summ if s["scene"] == scene]
        f = [s["frequency_ghz"] for s in ss]
        for ax, key in ((a1, "median_abs_dpg_vs_{}_db"), (a2, "median_abs_dds_vs_{}_ns")):
            ax.semilogx(
                f,
                [s[key.format("flat")] for s in ss],
                "o-",
                color=f"C{i}",
                label=f"{scene}: rough − flat",
            )
            ax.semilogx(f, [s[key.format("sionna")] for s in ss], "s--", color=f"C{i}", mfc="none",
                        label=f"{scene}: rough − Sionna S = 0.3")  # fmt: skip
    a1.set_ylabel("median |Δ path gain| over receivers [dB]")
    a2.set_ylabel("median |Δ RMS delay spread| [ns]")
    for ax in (a1, a2):
        ax.set_xlabel("frequency [GHz]")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle("Roughness matters more as frequency rises (emscatter materials in Sionna RT)")
    written.append(save_figure(fig, out / f"{stem}_vs_frequency.png"))
    return written
