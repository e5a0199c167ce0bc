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
    arr = rt.PlanarArray(num_rows=1, num_cols=1, pattern="iso", polarization="V")
    scene.tx_array = arr
    scene.rx_array = arr
    scene.add(rt.Transmitter("tx", position=list(setup.tx)))
    for i, p in enumerate(setup.rx):
        scene.add(rt.Receiver(f"rx{i}", position=list(p)))
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
