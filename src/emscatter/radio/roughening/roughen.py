"""Any Sionna RT scene rough in one call, and flat again in another.

::

    import sionna.rt as rt
    from emscatter import radio

    scene = rt.load_scene(rt.scene.simple_street_canyon, merge_shapes=False)
    scene.frequency = 28e9
    handle = radio.roughen(scene)                        # the default table below
    handle = radio.roughen(scene, mapping={"brick": (0.8e-3, 8e-3), "glass": None})
    print(handle.describe())                             # object → medium, σ, ℓ, material
    radio.flatten(scene)                                 # the scene's own materials back

:func:`roughen` gives every object of the scene the emscatter equivalent of its radio material
(:class:`~emscatter.radio.material.EmscatterRadioMaterial`, same medium and slab thickness, plus
roughness):

* the **medium** comes from the original material: an ITU material
  (``ITURadioMaterial``) gives its ``itu_type`` (Sionna's street canyon names its materials
  ``concrete``, ``brick``, …: the type is what is matched, not the name), a plain
  ``RadioMaterial`` its ``relative_permittivity`` and ``conductivity`` (a
  :class:`~emscatter.radio.medium.ConductiveMedium`), an emscatter material its own medium;
* the **roughness** of an object is looked up, first match wins, in ``mapping`` (keys: the
  object's name, its material's name, or its ITU type; values ``(σ, ℓ)`` [m] of a Gaussian
  correlation, a :class:`~emscatter.spectra.Roughness`, or ``None`` / ``"flat"``), then in
  ``roughness`` (one value for every object), then in :data:`DEFAULT_ROUGHNESS` by ITU type
  (its source: :data:`DEFAULT_ROUGHNESS_SOURCE`); a non-ITU material without an entry stays flat
  (said so in :meth:`Roughened.describe`);
* objects with the same medium, thickness and roughness share ONE emscatter material, named
  ``rough-<medium>`` (``-2``, ``-3`` … when thickness or roughness differ, or the name is taken);
* the originals are removed from the scene (Sionna frequency-updates every material of a scene,
  used or not) and kept by the returned :class:`Roughened` handle, which :func:`flatten` (or
  :meth:`Roughened.flatten`) puts back — the same instances, so the flat scene is the scene
  the user had, result for result;
* every ITU medium is checked against its ITU-R P.2040 bands at the scene frequency and at any
  ``frequencies`` given, before anything changes: an
  :class:`~emscatter.materials.OutOfBandError` naming medium, objects, frequency and bands,
  unless ``extrapolate=True`` (the documented extrapolation of :func:`emscatter.materials.itu`).

Roughening an already roughened scene first flattens it. The original's Sionna scattering
coefficient ``S`` and pattern are not carried over: emscatter's lobe replaces them.
"""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass

import numpy as np

from ... import materials
from ...spectra import GaussianCorrelation, Roughness
from ..indoor import ROUGHNESS as _INDOOR_ROUGHNESS
from ..slab_faces import check_face
from ..tables import check_surface
from ..texture import check_direction, check_textured_surface

__all__ = [
    "DEFAULT_ROUGHNESS",
    "DEFAULT_ROUGHNESS_SOURCE",
    "Assignment",
    "Roughened",
    "as_roughness",
    "plan",
    "roughen",
    "flatten",
    "roughened",
]

#: Roughness per ITU-R P.2040 material type (Gaussian correlation, σ and ℓ [m]; ``None``: flat).
DEFAULT_ROUGHNESS: dict[str, Roughness | None] = {
    **_INDOOR_ROUGHNESS,  # concrete, brick, plasterboard, ceiling_board, wood, metal, glass
    "vacuum": None,
    "clear_acrylic": None,  # cast sheet: optically smooth
    "chipboard": GaussianCorrelation(sigma=0.1e-3, length=2e-3),
    "plywood": GaussianCorrelation(sigma=0.05e-3, length=2e-3),  # as wood
    "floorboard": GaussianCorrelation(sigma=0.05e-3, length=2e-3),  # as wood
    "marble": GaussianCorrelation(sigma=0.1e-3, length=5e-3),  # honed stone cladding
    "vinyl_tile": GaussianCorrelation(sigma=0.02e-3, length=2e-3),
    "carpet_tile": GaussianCorrelation(sigma=1.0e-3, length=3e-3),
    "asphalt_concrete": GaussianCorrelation(sigma=1.0e-3, length=10e-3),
    "very_dry_ground": GaussianCorrelation(sigma=10e-3, length=100e-3),
    "medium_dry_ground": GaussianCorrelation(sigma=10e-3, length=100e-3),
    "wet_ground": GaussianCorrelation(sigma=10e-3, length=100e-3),
}

#: Where :data:`DEFAULT_ROUGHNESS` comes from (recorded in every :class:`Roughened` table).
DEFAULT_ROUGHNESS_SOURCE = (
    "emscatter's representative table (emscatter.radio.DEFAULT_ROUGHNESS; the indoor media as "
    "emscatter.radio.indoor.ROUGHNESS): plastered concrete and brick rough at "
    "millimetre-wave scale, boards and wood nearly smooth, glass and acrylic flat, ground at "
    "the centimetre scale of bare soil (Ulaby, Moore & Fung 1982, vol. II ch. 11). "
    "Representative values, not measurements of any building: give measured (σ, ℓ) with mapping="
)


def as_roughness(value, what: str = "roughness") -> Roughness | None:
    """``None`` / ``"flat"`` → ``None``; a :class:`~emscatter.spectra.Roughness` (isotropic,
    checked); or ``(σ, ℓ)`` [m] → :class:`~emscatter.spectra.GaussianCorrelation`. A clear
    ValueError naming ``what``, the value and what is allowed otherwise."""
    if value is None or (isinstance(value, str) and value.strip().lower() == "flat"):
        return None
    if isinstance(value, Roughness):
        try:
            return check_surface(value) if value.is_isotropic else check_textured_surface(value)
        except ValueError as exc:
            raise ValueError(f"{what}: {exc}") from None
    if isinstance(value, tuple | list) and len(value) in (2, 3):
        try:
            vals = [float(v) for v in value]
        except (TypeError, ValueError):
            vals = [math.nan]
        if all(math.isfinite(v) and v > 0 for v in vals):
            ly = vals[2] if len(vals) == 3 else None
            return GaussianCorrelation(sigma=vals[0], length=vals[1], length_y=ly)
    raise ValueError(
        f"{what} must be (sigma, length) or (sigma, length_x, length_y) in metres (finite and "
        "> 0, e.g. (0.4e-3, 4e-3); ℓx ≠ ℓy needs roughen(texture_direction=...)), "
        f"an emscatter Roughness (e.g. GaussianCorrelation(sigma=..., length=...)), or None / "
        f"'flat'; got {value!r}"
    )


@dataclass(frozen=True)
class Assignment:
    """One object of a roughened scene: its original material (``original``, its ``itu_type``
    or ``None``), the emscatter ``medium``, ``thickness`` [m] (``None``: half-space), the
    ``surface`` (``None``: flat), where that roughness came from (``source``) and the name of
    the emscatter ``material`` it now has."""

    object: str
    original: str
    itu_type: str | None
    medium: object
    medium_key: str
    thickness: float | None
    surface: Roughness | None
    source: str
    material: str = ""

    def row(self) -> dict:
        s = self.surface
        return {
            "object": self.object,
            "original_material": self.original,
            "itu_type": self.itu_type or "",
            "medium": self.medium_key,
            "thickness_m": self.thickness,
            "correlation": "flat" if s is None else s.name,
            "sigma_m": 0.0 if s is None else float(s.sigma),
            "length_m": 0.0 if s is None else float(s.length),
            "length_y_m": 0.0 if s is None else float(s.length_y),
            "roughness_from": self.source,
            "material": self.material,
        }


_HANDLES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def roughened(scene) -> Roughened | None:
    """The :class:`Roughened` handle of ``scene`` if :func:`roughen` changed it, else ``None``."""
    return _HANDLES.get(scene)


class Roughened:
    """What :func:`roughen` did to a scene, and how to undo it (:meth:`flatten`).

    ``assignments`` (one :class:`Assignment` per object), ``materials`` (name → the shared
    emscatter material), ``originals`` (object name → its original material instance)."""

    def __init__(self, scene, assignments, materials_, originals):
        self._scene = weakref.ref(scene)
        self.assignments: list[Assignment] = assignments
        self.materials: dict = materials_
        self.originals: dict = originals
        self.active = True

    @property
    def scene(self):
        return self._scene()

    def rows(self) -> list[dict]:
        """One dict per object (:meth:`Assignment.row` and its material's ``transmission``
        model), for a table or a CSV."""
        return [
            {**a.row(), "transmission": self.materials[a.material].transmission}
            for a in self.assignments
        ]

    def describe(self) -> str:
        lines = [f"{len(self.assignments)} objects, {len(self.materials)} emscatter materials:"]
        for r in self.rows():
            rough = (
                "flat"
                if r["correlation"] == "flat"
                else f"σ = {r['sigma_m'] * 1e3:g} mm, ℓ = {r['length_m'] * 1e3:g} mm"
            )
            lines.append(
                f"  {r['object']}: {r['original_material']} ({r['medium']}) → {r['material']}: "
                f"{rough} [{r['roughness_from']}]"
            )
        return "\n".join(lines)

    def flatten(self):
        """Put the original materials back (the same instances) and remove the emscatter ones;
        returns the scene. Doing it twice is harmless."""
        scene = self.scene
        if not self.active or scene is None:
            return scene
        for name, obj in scene.objects.items():
            if name in self.originals:
                obj.radio_material = self.originals[name]
        scene.remove([n for n, m in self.materials.items() if not m.is_used])
        self.active = False
        if _HANDLES.get(scene) is self:
            del _HANDLES[scene]
        return scene


def _scalar(x) -> float:
    return float(np.asarray(x.numpy() if hasattr(x, "numpy") else x).ravel()[0])


def _medium_of(obj_name, mat, extrapolate: bool):
    """``(itu_type, medium, medium_key, thickness)`` of a Sionna radio material."""
    from sionna.rt import ITURadioMaterial, RadioMaterial

    from ..material import EmscatterRadioMaterial
    from ..medium import ConductiveMedium

    if isinstance(mat, EmscatterRadioMaterial):
        med = mat.medium
        return None, med, getattr(med, "name", mat.name), mat.thickness
    if isinstance(mat, ITURadioMaterial):
        itu = str(mat.itu_type)
        if itu not in materials.available_itu():
            raise ValueError(
                f"object {obj_name!r}: ITU type {itu!r} of material {mat.name!r} is not one of "
                f"emscatter's ITU-R P.2040 media {materials.available_itu()}"
            )
        return itu, materials.itu(itu, extrapolate=extrapolate), itu, _scalar(mat.thickness)
    if isinstance(mat, RadioMaterial):
        if mat.frequency_update_callback is not None:
            raise ValueError(
                f"object {obj_name!r}: material {mat.name!r} computes its permittivity with a "
                "frequency_update_callback, which has no emscatter equivalent; give the object an "
                "ITURadioMaterial or a constant RadioMaterial first"
            )
        med = ConductiveMedium(_scalar(mat.relative_permittivity), _scalar(mat.conductivity))
        return None, med, mat.name, _scalar(mat.thickness)
    raise ValueError(
        f"object {obj_name!r}: material {getattr(mat, 'name', mat)!r} is a "
        f"{type(mat).__name__}, which roughen cannot translate (it takes ITURadioMaterial, "
        "RadioMaterial and EmscatterRadioMaterial)"
    )


def _frequencies(scene, frequencies) -> list[float]:
    out = [_scalar(scene.frequency)]
    if frequencies is not None:
        fs = np.atleast_1d(np.asarray(frequencies, dtype=float)).ravel()
        if not (fs.size and np.all(np.isfinite(fs)) and np.all(fs > 0)):
            raise ValueError(f"frequencies must be positive numbers [Hz], got {frequencies!r}")
        out += [float(f) for f in fs]
    return out


def check_bands(assignments, frequencies, *, extrapolate: bool = False) -> list[dict]:
    """The ITU media of ``assignments`` against their ITU-R P.2040 bands at ``frequencies``
    [Hz]: ``[{"medium", "objects", "frequency_ghz", "bands_ghz"}]`` for those outside, an
    :class:`~emscatter.materials.OutOfBandError` naming them all unless ``extrapolate``."""
    out = []
    by_medium: dict[str, list[str]] = {}
    for a in assignments:
        if a.itu_type is not None:
            by_medium.setdefault(a.itu_type, []).append(a.object)
    for medium, objs in sorted(by_medium.items()):
        mat = materials.itu(medium)
        for f in sorted(set(frequencies)):
            if not np.all(mat.in_band(f)):
                bands = [(lo / 1e9, hi / 1e9) for lo, hi in mat.bands]
                out.append(
                    {
                        "medium": medium,
                        "objects": objs,
                        "frequency_ghz": f / 1e9,
                        "bands_ghz": bands,
                    }
                )
    if out and not extrapolate:
        what = "; ".join(
            f"{e['medium']!r} (objects {', '.join(e['objects'][:4])}"
            f"{', …' if len(e['objects']) > 4 else ''}) at {e['frequency_ghz']:g} GHz (ITU-R "
            "P.2040 bands " + ", ".join(f"{lo:g}–{hi:g} GHz" for lo, hi in e["bands_ghz"]) + ")"
            for e in out
        )
        raise materials.OutOfBandError(
            f"materials outside their ITU-R P.2040 bands: {what}. Pick frequencies inside the "
            "bands, or extrapolate=True (CLI: --extrapolate) to use the documented "
            "extrapolation"
        )
    return out


def plan(scene, roughness=None, mapping=None, *, frequencies=None, extrapolate=False):
    """The :class:`Assignment` of every object of ``scene`` (module docstring), without
    changing the scene; raises for a bad ``mapping`` key or value and out of band."""
    if not isinstance(extrapolate, bool):
        raise TypeError(f"extrapolate must be True or False, got {extrapolate!r}")
    handle = _HANDLES.get(scene)
    originals = {} if handle is None or not handle.active else handle.originals
    if mapping is not None and not isinstance(mapping, dict):
        raise TypeError(
            f"mapping must be a dict name → (sigma, length) [m] | Roughness | None, got "
            f"{type(mapping).__name__}"
        )
    user = {str(k): as_roughness(v, f"mapping[{k!r}]") for k, v in (mapping or {}).items()}
    common = None if roughness is None else as_roughness(roughness, "roughness")
    used_keys: set[str] = set()
    out = []
    for name, obj in scene.objects.items():
        mat = originals.get(name, obj.radio_material)
        itu, medium, key, thickness = _medium_of(name, mat, extrapolate)
        for k in (name, mat.name, itu):
            if k is not None and k in user:
                surface, source = user[k], f"mapping[{k!r}]"
                used_keys.add(k)
                break
        else:
            if roughness is not None:
                surface, source = common, "roughness="
            elif itu is not None:
                surface, source = DEFAULT_ROUGHNESS.get(itu), f"default table ({itu})"
            else:
                surface, source = None, "flat: not an ITU material and not in mapping"
        out.append(Assignment(name, mat.name, itu, medium, key, thickness, surface, source))
    unknown = sorted(set(user) - used_keys)
    if unknown:
        known = sorted(
            {a.object for a in out} | {a.original for a in out} | {a.itu_type for a in out} - {None}
        )
        raise ValueError(
            f"mapping names {unknown}, which match no object, material or ITU type of the "
            f"scene; known names: {known}"
        )
    check_bands(out, _frequencies(scene, frequencies), extrapolate=extrapolate)
    return out


def _shared_names(assignments, scene, prefix: str) -> list[Assignment]:
    """One material name per (medium, thickness, roughness), not taken in the scene."""
    names: dict[tuple, str] = {}
    taken = set(scene.radio_materials)
    out = []
    for a in assignments:
        group = (a.medium_key, a.thickness, a.surface)
        if group not in names:
            base = f"{prefix}{a.medium_key}"
            name, i = base, 1
            while name in taken or name in names.values():
                i += 1
                name = f"{base}-{i}"
            names[group] = name
        out.append(Assignment(**{**a.__dict__, "material": names[group]}))
    return out


#: The transmission models :func:`roughen` takes (:class:`EmscatterRadioMaterial`'s).
TRANSMISSIONS = ("coherent", "diffuse")


def _transmission_for(a, transmission: str) -> str:
    """``"diffuse"`` only where the material can carry it: an isotropic rough slab."""
    if transmission == "diffuse" and (
        a.surface is None or a.thickness is None or not a.surface.is_isotropic
    ):
        return "coherent"
    return transmission


def roughen(
    scene,
    roughness=None,
    mapping=None,
    *,
    frequencies=None,
    extrapolate: bool = False,
    method: str = "auto",
    out_of_range: str = "warn",
    table_options=None,
    flat: bool = False,
    prefix: str = "rough-",
    texture_direction=None,
    transmission: str = "coherent",
    transmission_face: str = "auto",
) -> Roughened:
    """Every object of the Sionna ``scene`` gets its emscatter equivalent (module docstring);
    returns the :class:`Roughened` handle (``flatten()`` undoes it).

    ``roughness``: one ``(σ, ℓ)`` [m] / Roughness / ``None`` for every object not in
    ``mapping`` (default: :data:`DEFAULT_ROUGHNESS` by ITU type); ``mapping``: object, material
    or ITU-type name → ``(σ, ℓ)`` / Roughness / ``None``; ``frequencies`` [Hz]: more
    frequencies to check the bands at (the scene's is always checked); ``flat=True``: every
    object flat (emscatter's flat equivalents, equal to Sionna's own ITU slab);
    ``method``, ``out_of_range``, ``table_options``: as for
    :class:`~emscatter.radio.material.EmscatterRadioMaterial`. Tables are built lazily, at the
    first trace, only for used materials. ``texture_direction``: world direction of the ``ℓx``
    axis of every anisotropic roughness (``(σ, ℓx, ℓy)``; :mod:`emscatter.radio.texture`), or
    a dict material name or ITU type → direction (per medium, keyed as ``mapping``), required
    where one is given. ``transmission``: ``"coherent"`` (default, Sionna's own slab model) or
    ``"diffuse"`` (:class:`~emscatter.radio.material.EmscatterRadioMaterial`'s diffuse
    transmission through rough slabs, carried by RadioMapSolver only): it applies to the
    isotropic rough slabs; flat objects, half-spaces (no thickness) and textured walls keep the
    coherent slab, and ``rows()`` names each object's model (``"transmission"``).
    ``transmission_face``: the slab faces' model of the diffuse transmission, one of
    :data:`emscatter.radio.slab_faces.FACES` (default ``"auto"``; with
    ``transmission="coherent"`` only ``"auto"`` is accepted: nothing would use another)."""
    from ..material import EmscatterRadioMaterial

    if isinstance(texture_direction, dict):
        directions = {
            str(k): check_direction(v, f"texture_direction[{k!r}]")
            for k, v in texture_direction.items()
        }
    else:
        common_dir = None if texture_direction is None else check_direction(texture_direction)
        directions = {}

    def direction_of(a):
        if not directions:
            return common_dir
        for key in (a.original, a.itu_type, a.medium_key):
            if key in directions:
                return directions[key]
        return None

    assignments = plan(scene, roughness, mapping, frequencies=frequencies, extrapolate=extrapolate)
    if flat:
        assignments = [
            Assignment(**{**a.__dict__, "surface": None, "source": "flat=True"})
            for a in assignments
        ]
    textured = [
        a.object
        for a in assignments
        if a.surface is not None and not a.surface.is_isotropic and direction_of(a) is None
    ]
    if textured:
        raise ValueError(
            f"roughen: anisotropic roughness (ℓx ≠ ℓy) on {textured[:4]} needs "
            "texture_direction=(dx, dy, dz), the world direction of the ℓx axis (e.g. (0, 0, 1): "
            "vertical grooves)"
        )
    if not isinstance(prefix, str) or not prefix:
        raise ValueError(f"prefix must be a non-empty string, got {prefix!r}")
    if transmission not in TRANSMISSIONS:
        raise ValueError(f"transmission must be one of {TRANSMISSIONS}, got {transmission!r}")
    face = check_face(transmission_face)
    if face != "auto" and transmission != "diffuse":
        raise ValueError(
            f"transmission_face={face!r} applies to transmission='diffuse' only, got "
            f"transmission={transmission!r}"
        )
    old = _HANDLES.get(scene)
    if old is not None and old.active:
        old.flatten()
    assignments = _shared_names(assignments, scene, prefix)
    made: dict[str, EmscatterRadioMaterial] = {}
    for a in assignments:
        if a.material not in made:
            made[a.material] = EmscatterRadioMaterial(
                a.material,
                surface=a.surface,
                medium=a.medium,
                thickness=a.thickness,
                method=method,
                out_of_range=out_of_range,
                table_options=table_options,
                texture_direction=None
                if a.surface is None or a.surface.is_isotropic
                else direction_of(a),
                transmission=_transmission_for(a, transmission),
                transmission_face=face,
            )
    originals = {}
    for a in assignments:
        obj = scene.objects[a.object]
        originals[a.object] = obj.radio_material
        obj.radio_material = made[a.material]
    # the originals now unused: out of the scene (Sionna updates every material it holds)
    gone = {m.name for m in originals.values()}
    scene.remove([n for n in gone if n in scene.radio_materials and not scene.get(n).is_used])
    handle = Roughened(scene, assignments, made, originals)
    _HANDLES[scene] = handle
    return handle


def flatten(scene):
    """Undo :func:`roughen` on ``scene`` (its original materials back); returns the scene.
    ValueError if the scene was not roughened."""
    handle = _HANDLES.get(scene)
    if handle is None or not handle.active:
        raise ValueError(
            "flatten: this scene was not roughened by emscatter.radio.roughen (or was flattened "
            "already)"
        )
    return handle.flatten()
