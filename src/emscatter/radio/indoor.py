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

Media outside their ITU-R P.2040 band (the ITU metal stops at 100 GHz) use the documented
extrapolation of :func:`emscatter.materials.itu` (``extrapolate=True``) in all three sets.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

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
    "material_factory",
    "run_scene",
]

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


def medium_at(name: str, frequency: float):
    """The ITU medium, extrapolated (documented) where the frequency is out of its band."""
    mat = materials.itu(name)
    if np.all(mat.in_band(frequency)):
        return mat
    return materials.itu(name, extrapolate=True)


def material_factory(kind: str, frequency: float, *, s: float = DEFAULT_S, table_options=None):
    """``make_material(object, medium, thickness)`` for :func:`emscatter.radio.scenes.load`."""
    import sionna.rt as rt

    from .material import EmscatterRadioMaterial

    if kind not in ("sionna", "flat", "rough"):
        raise ValueError(f"kind must be 'sionna', 'flat' or 'rough', got {kind!r}")

    def make(obj, medium, thickness):
        med = medium_at(medium, frequency)
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
) -> dict:
    """Path gain [linear] and RMS delay spread [s] per receiver, and (if ``cell_size``) a radio
    map of path gain [linear] (NaN where no ray arrived)."""
    import sionna.rt as rt

    scene = scenes.load(
        setup.scene, frequency, material_factory(kind, frequency, s=s, table_options=table_options)
    )
    add_devices(scene, setup)
    paths = rt.PathSolver()(
        scene,
        max_depth=max_depth,
        samples_per_src=int(samples),
        max_num_paths_per_src=int(samples),
        diffuse_reflection=True,
        refraction=True,
        seed=seed,
    )
    re, im = (np.asarray(x.numpy()) for x in paths.a)
    power = (re**2 + im**2)[:, 0, 0, 0, :]  # [rx, path]
    tau = np.asarray(paths.tau.numpy())
    tau = tau[:, 0, 0, 0, :] if tau.ndim == 5 else tau[:, 0, :]
    gain = power.sum(axis=1)
    spread = np.array([delay_spread(power[i], tau[i]) for i in range(power.shape[0])])
    out = {"path_gain": gain, "delay_spread": spread, "num_paths": int(power.shape[1])}
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
    progress=print,
) -> dict:
    """Every scene × frequency × material set (module docstring): ``{"rows": [...] per
    receiver, "maps": {(scene, f, kind): path gain map}}``."""
    rows, maps = [], {}
    for name in names:
        setup = SETUPS[name]
        for f in frequencies:
            for kind in KINDS:
                r = run_scene(
                    setup, kind, f, samples=samples, max_depth=max_depth, cell_size=cell_size,
                    map_samples=map_samples, table_options=table_options,
                )  # fmt: skip
                maps[(name, f, kind)] = r["radio_map"]
                for i, (g, ds) in enumerate(zip(r["path_gain"], r["delay_spread"], strict=True)):
                    rows.append(
                        {"scene": name, "frequency_ghz": f / 1e9, "kind": kind, "rx": i,
                         "path_gain_db": 10 * math.log10(g) if g > 0 else -math.inf,
                         "delay_spread_ns": ds * 1e9}
                    )  # fmt: skip
                if progress:
                    progress(
                        f"{name} {f / 1e9:g} GHz {kind}: path gain "
                        + ", ".join(f"{10 * math.log10(g):.1f}" for g in r["path_gain"] if g > 0)
                        + " dB"
                    )
    return {"rows": rows, "maps": maps}


def summarize(rows: list) -> list:
    """Per scene and frequency: median over receivers of ``|ΔPG|`` [dB] and ``|Δτ_rms|`` [ns]
    for rough − flat (what roughness does) and rough − sionna (against the constant-S model)."""
    out = []
    key = {(r["scene"], r["frequency_ghz"], r["kind"], r["rx"]): r for r in rows}
    for scene, f in sorted({(r["scene"], r["frequency_ghz"]) for r in rows}):
        rxs = sorted({r["rx"] for r in rows if r["scene"] == scene})
        entry = {"scene": scene, "frequency_ghz": f}
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
    """``<stem>_receivers.csv``, ``<stem>_summary.csv``, ``<stem>_maps_<scene>.png`` (radio map
    of the rough set and its differences per frequency) and ``<stem>_vs_frequency.png``."""
    from pathlib import Path

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..io import save_figure, write_csv

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
