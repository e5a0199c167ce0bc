"""Scenes for the radio cross-checks, built from Python without Blender.

* meshes from NumPy (:func:`quad`, :func:`box`) written as binary PLY files (:func:`write_ply`)
  and a Mitsuba/Sionna XML scene that references them (:func:`write_scene`);
* :func:`plate` — one large square plate (the specular / bistatic radar cross-check);
* :func:`furnished_room` — a 6 m × 5 m × 3 m room: concrete and plasterboard walls, a concrete
  floor, a ceiling board, a wooden table and a glass pane;
* Sionna's own ``box`` and ``floor_wall`` scenes (:data:`SIONNA_SCENES`).

:func:`load` loads any of them, or a user's Mitsuba/Sionna XML scene file, with Sionna, sets
the frequency *before* the materials are attached (so a material whose band excludes Sionna's
default 3.5 GHz can be used) and gives each object the material a callback makes for it; the
scene's own materials (the XML's placeholders, or Sionna's ITU materials) are removed, so that
none of them is frequency-updated later. Generated scenes go to a temporary directory that is
removed once Sionna has read it.
"""

from __future__ import annotations

import os
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from ..io import atomic_path

__all__ = [
    "Mesh",
    "quad",
    "box",
    "write_ply",
    "read_ply",
    "write_scene",
    "plate",
    "furnished_room",
    "SceneSpec",
    "SIONNA_SCENES",
    "load",
]

#: Scenes shipped with Sionna RT (``sionna.rt.scene.<name>``) and the ITU type of each object.
SIONNA_SCENES = {
    "box": {"box": ("metal", 1.0)},
    "floor_wall": {"floor": ("concrete", 0.1), "wall": ("brick", 0.1)},
}


@dataclass(frozen=True)
class Mesh:
    """A triangle mesh: ``vertices`` (n, 3) [m] and ``faces`` (m, 3) vertex indices."""

    vertices: np.ndarray
    faces: np.ndarray

    def __post_init__(self):
        v = np.asarray(self.vertices, dtype=float)
        f = np.asarray(self.faces, dtype=np.int64)
        if v.ndim != 2 or v.shape[1] != 3 or f.ndim != 2 or f.shape[1] != 3:
            raise ValueError(
                f"a mesh needs vertices (n, 3) and faces (m, 3), got {v.shape}, {f.shape}"
            )
        if f.size and (f.min() < 0 or f.max() >= len(v)):
            raise ValueError(f"face indices must lie in [0, {len(v) - 1}]")
        object.__setattr__(self, "vertices", v)
        object.__setattr__(self, "faces", f)

    def __add__(self, other: Mesh) -> Mesh:
        return Mesh(
            np.vstack([self.vertices, other.vertices]),
            np.vstack([self.faces, other.faces + len(self.vertices)]),
        )

    def area(self) -> float:
        a, b, c = (self.vertices[self.faces[:, i]] for i in range(3))
        return float(0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1).sum())


def quad(origin, u, v) -> Mesh:
    """The parallelogram ``origin + s u + t v``, ``s, t ∈ [0, 1]`` (two triangles) [m]."""
    o, u, v = (np.asarray(x, dtype=float) for x in (origin, u, v))
    return Mesh(np.stack([o, o + u, o + u + v, o + v]), np.array([[0, 1, 2], [0, 2, 3]]))


def box(center, size) -> Mesh:
    """An axis-aligned closed box (12 triangles, outward normals) of ``size`` (3,) [m]."""
    c, s = np.asarray(center, float), np.asarray(size, float) / 2
    corners = np.array([[x, y, z] for z in (-1, 1) for y in (-1, 1) for x in (-1, 1)], float)
    faces = np.array(
        [
            [0, 2, 1],
            [1, 2, 3],
            [4, 5, 6],
            [5, 7, 6],
            [0, 1, 4],
            [1, 5, 4],
            [2, 6, 3],
            [3, 6, 7],
            [0, 4, 2],
            [2, 4, 6],
            [1, 3, 5],
            [3, 7, 5],
        ]
    )
    return Mesh(c + corners * s, faces)


def write_ply(path, mesh: Mesh) -> Path:
    """Binary little-endian PLY (float32 vertices, uint32 faces), written atomically."""
    header = (
        "ply\nformat binary_little_endian 1.0\n"
        f"element vertex {len(mesh.vertices)}\n"
        "property float x\nproperty float y\nproperty float z\n"
        f"element face {len(mesh.faces)}\nproperty list uchar uint vertex_indices\nend_header\n"
    )
    faces = np.zeros(len(mesh.faces), dtype=[("n", "u1"), ("idx", "<u4", (3,))])
    faces["n"] = 3
    faces["idx"] = mesh.faces
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:
        fh.write(header.encode("ascii"))
        fh.write(mesh.vertices.astype("<f4").tobytes())
        fh.write(faces.tobytes())
    return Path(path)


def read_ply(path) -> Mesh:
    """Read back what :func:`write_ply` writes (for tests and inspection)."""
    data = Path(path).read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    lines = data[:end].decode("ascii").splitlines()
    nv = int(next(x for x in lines if x.startswith("element vertex")).split()[-1])
    nf = int(next(x for x in lines if x.startswith("element face")).split()[-1])
    verts = np.frombuffer(data, dtype="<f4", count=3 * nv, offset=end).reshape(nv, 3)
    faces = np.frombuffer(
        data, dtype=[("n", "u1"), ("idx", "<u4", (3,))], count=nf, offset=end + 12 * nv
    )
    return Mesh(verts.astype(float), faces["idx"].astype(np.int64))


@dataclass
class SceneSpec:
    """Objects of a generated scene: name → mesh, name → (medium, thickness [m] or None)."""

    meshes: dict
    media: dict
    notes: dict = field(default_factory=dict)


def write_scene(directory, spec: SceneSpec) -> Path:
    """PLY files and ``scene.xml`` (placeholder materials) under ``directory``; returns the XML."""
    d = Path(directory)
    (d / "meshes").mkdir(parents=True, exist_ok=True)
    parts = ['<scene version="2.1.0">']
    for name in spec.meshes:
        parts.append(
            f'  <bsdf type="radio-material" id={quoteattr("placeholder-" + name)}>'
            '<float name="relative_permittivity" value="1.0"/></bsdf>'
        )
    for name, mesh in spec.meshes.items():
        write_ply(d / "meshes" / f"{name}.ply", mesh)
        parts.append(
            f'  <shape type="ply" id={quoteattr(name)}>'
            f'<string name="filename" value={quoteattr(f"meshes/{name}.ply")}/>'
            '<boolean name="face_normals" value="true"/>'
            f'<ref id={quoteattr("placeholder-" + name)} name="bsdf"/></shape>'
        )
    parts.append("</scene>\n")
    xml = d / "scene.xml"
    with atomic_path(xml) as tmp:
        Path(tmp).write_text("\n".join(parts), encoding="utf-8")
    return xml


def plate(size: float = 40.0, *, medium="concrete", thickness=None) -> SceneSpec:
    """A square plate of side ``size`` [m] in the plane ``z = 0``, centred on the origin."""
    h = size / 2
    return SceneSpec(
        meshes={"plate": quad([-h, -h, 0.0], [size, 0.0, 0.0], [0.0, size, 0.0])},
        media={"plate": (medium, thickness)},
    )


def furnished_room() -> SceneSpec:
    """A 6 × 5 × 3 m room (x ∈ [0, 6], y ∈ [0, 5], z ∈ [0, 3]): concrete floor and two
    concrete walls, two plasterboard walls, a ceiling board, a wooden table
    (1.6 × 0.8 × 0.04 m top at 0.75 m) and a free-standing glass pane (1.2 × 1.0 m, 6 mm)."""
    lx, ly, lz = 6.0, 5.0, 3.0
    meshes = {
        "floor": quad([0, 0, 0], [lx, 0, 0], [0, ly, 0]),
        "ceiling": quad([0, 0, lz], [0, ly, 0], [lx, 0, 0]),
        "wall_south": quad([0, 0, 0], [0, 0, lz], [lx, 0, 0]),
        "wall_north": quad([0, ly, 0], [lx, 0, 0], [0, 0, lz]),
        "wall_west": quad([0, 0, 0], [0, ly, 0], [0, 0, lz]),
        "wall_east": quad([lx, 0, 0], [0, 0, lz], [0, ly, 0]),
        "table": box([3.6, 2.2, 0.75], [1.6, 0.8, 0.04]),
        "glass": quad([1.6, 3.4, 0.8], [1.2, 0.0, 0.0], [0.0, 0.0, 1.0]),
    }
    media = {
        "floor": ("concrete", 0.2),
        "ceiling": ("ceiling_board", 0.02),
        "wall_south": ("concrete", 0.2),
        "wall_north": ("concrete", 0.2),
        "wall_west": ("plasterboard", 0.0125),
        "wall_east": ("plasterboard", 0.0125),
        "table": ("wood", 0.04),
        "glass": ("glass", 0.006),
    }
    return SceneSpec(meshes, media, notes={"size": (lx, ly, lz)})


def load(scene, frequency: float, make_material=None, *, workdir=None, media=None):
    """A Sionna scene at ``frequency`` [Hz] with each object's material from
    ``make_material(object_name, medium, thickness) -> RadioMaterialBase``.

    ``scene`` is one of

    * a :class:`SceneSpec` — written as PLY + XML under ``workdir``, or, by default, under a
      temporary directory that is removed as soon as Sionna's ``load_scene`` has read it (also
      when loading fails or is interrupted): nothing is left in the temp dir;
    * the name of one of :data:`SIONNA_SCENES` (``"box"``, ``"floor_wall"``);
    * the path of a Mitsuba/Sionna XML scene file (``*.xml``, ``str`` or :class:`os.PathLike`),
      loaded with ``sionna.rt.load_scene``. Without ``make_material`` the scene keeps its own
      materials (only the frequency is set). With it, each object's ``(medium, thickness)``
      comes from ``media`` (object name → ``(medium, thickness [m] or None)``) or, for objects
      without an entry, from the object's ITU material in the XML (``itu_type``, thickness).

    ``media`` (optional) overrides the media of any scene, object by object.
    """
    import sionna.rt as rt

    if isinstance(scene, SceneSpec):
        if workdir is not None:
            sc = rt.load_scene(os.fspath(write_scene(Path(workdir), scene)), merge_shapes=False)
        else:
            # Sionna has read every file once load_scene returns: remove them right away.
            with tempfile.TemporaryDirectory(prefix="emscatter-radio-") as tmp:
                sc = rt.load_scene(os.fspath(write_scene(Path(tmp), scene)), merge_shapes=False)
        base = dict(scene.media)
    elif isinstance(scene, str) and scene in SIONNA_SCENES:
        sc = rt.load_scene(getattr(rt.scene, scene), merge_shapes=False)
        base = dict(SIONNA_SCENES[scene])
    elif isinstance(scene, str | os.PathLike) and Path(scene).suffix.lower() == ".xml":
        path = Path(scene)
        if not path.is_file():
            raise FileNotFoundError(
                f"scene: no XML scene file at {os.fspath(path)!r} (a Mitsuba/Sionna scene "
                "file, e.g. exported from Blender with Mitsuba's add-on)"
            )
        sc = rt.load_scene(os.fspath(path), merge_shapes=False)
        if make_material is None:
            sc.frequency = frequency
            return sc
        base = _xml_media(sc)
    else:
        raise ValueError(
            f"scene must be a SceneSpec, one of Sionna's scenes {sorted(SIONNA_SCENES)}, or the "
            f"path of a Mitsuba/Sionna XML scene file (*.xml); got {scene!r}"
        )
    if make_material is None:
        raise ValueError(
            "make_material is required for a generated or built-in scene: a callable "
            "(object_name, medium, thickness) -> radio material (e.g. "
            "emscatter.radio.indoor.material_factory('rough', frequency))"
        )
    if media is not None:
        base.update(media)
    missing = sorted(name for name in sc.objects if base.get(name) is None)
    if missing:
        raise ValueError(
            f"objects {missing} of the scene have no medium; give media={{name: (medium, "
            f"thickness)}} for them (known: {sorted(k for k, v in base.items() if v)})"
        )
    # The scene's own materials are updated at every frequency change even once unused, so an
    # ITU one out of its band (Sionna's metal box at 140 GHz) would fail: swap in loss-free
    # neutral materials, drop the originals, set the frequency, then attach the real ones.
    original = list(sc.radio_materials)
    for name, obj in sc.objects.items():
        obj.radio_material = rt.RadioMaterial(f"neutral-{name}", relative_permittivity=1.0)
    sc.remove(original)
    sc.frequency = frequency
    for name, obj in sc.objects.items():
        medium, thickness = base[name]
        obj.radio_material = make_material(name, medium, thickness)
    sc.remove([f"neutral-{name}" for name in sc.objects])
    return sc


def _xml_media(sc) -> dict:
    """``object → (medium, thickness)`` from the materials of a loaded XML scene: ITU materials
    give their ``itu_type``, emscatter materials their medium; others ``None`` (unknown)."""
    out = {}
    for name, obj in sc.objects.items():
        mat = obj.radio_material
        itu_type = getattr(mat, "itu_type", None)
        medium = itu_type if itu_type is not None else getattr(mat, "medium", None)
        thickness = getattr(mat, "thickness", None)
        if thickness is not None and not isinstance(thickness, float | int):
            thickness = float(np.asarray(thickness).ravel()[0])
        out[name] = None if medium is None else (medium, thickness)
    return out
