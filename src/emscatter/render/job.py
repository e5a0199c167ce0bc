"""One render from the command line (``emscatter render``): a BRDF source, a scene, an image.

Sources (:func:`bsdf_for`):

* an emscatter table ``.npz`` (``emscatter brdf``), rendered through the emscatter plugin
  (:mod:`emscatter.render.mitsuba`, coherent delta lobe included) or, with
  ``via="measured"``, exported to an RGL ``.bsdf`` (:func:`emscatter.brdf.export_rgl.write_rgl`,
  channels of the variant, into a temporary folder) and rendered by Mitsuba's ``measured``;
* an RGL ``.bsdf`` file, rendered by Mitsuba's ``measured``.

Scenes: one unit sphere (:func:`emscatter.render.scenes.sphere_row`, the same camera and
lights as the demo and the examples), or the user's Mitsuba scene XML in which a shape refers
to the BSDF as ``<ref id="emscatter"/>``: the BSDF is inserted as the scene's first child
(``id="emscatter"``) into a temporary copy beside the file (so its relative paths resolve),
which is loaded and removed.

Output: an 8-bit sRGB PNG (:func:`emscatter.render.scenes.save_png`) and optionally an OpenEXR
of the linear image, both written atomically. A non-finite pixel is an error, never a file.
Dr.Jit variants are per process: :func:`render_job` sets the variant of its process.
"""

from __future__ import annotations

import math
import re
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..io import atomic_path
from .scenes import EMITTERS

__all__ = ["VIA", "RenderJob", "check_variant", "bsdf_for", "render_job", "via_for", "EMITTERS"]

#: How an ``.npz`` table reaches Mitsuba.
VIA = ("plugin", "measured")


_REF = re.compile(r"<ref\s+[^>]*id\s*=\s*[\"']emscatter[\"']")
_SCENE_TAG = re.compile(r"<scene\b[^>]*>")


@dataclass(frozen=True)
class RenderJob:
    """Everything one render needs (checked by :mod:`emscatter.cli.render`)."""

    source: Path  # .npz table or .bsdf file
    out: Path  # .png
    variant: str = "llvm_ad_rgb"
    via: str | None = None  # None: the plugin in llvm_* variants, measured in scalar_* ones
    scene: Path | None = None  # a user's Mitsuba XML, else one sphere
    width: int = 256  # [px], sphere scene
    height: int | None = None  # [px], sphere scene (default: what fits)
    spp: int = 64
    emitter: str = "sky+sun"
    exr: Path | None = None
    exposure: float = 1.5
    seed: int = 0
    coherent: bool = True  # the plugin's delta lobe
    btdf: Path | None = None  # a BTDF table: SOURCE is a dielectric's outside reflection
    inner: Path | None = None  # with btdf: the inside reflection table
    info: dict = field(default_factory=dict)


def check_variant(variant: str) -> str:
    """``variant`` if Mitsuba has it and this command can render in it, else ``ValueError``
    naming the allowed ones (RGB and spectral variants; polarized ones need a Mueller table)."""
    import mitsuba as mi

    usable = [v for v in mi.variants() if ("rgb" in v or "spectral" in v) and "polarized" not in v]
    if variant not in usable:
        why = (
            "polarized variants need a Mueller table, which emscatter render does not take yet"
            if "polarized" in str(variant)
            else "it is not an RGB or spectral variant of this Mitsuba build"
        )
        raise ValueError(f"variant must be one of {usable}, got {variant!r} ({why})")
    return variant


def via_for(job: RenderJob) -> str:
    """How a table is rendered: ``job.via``, else the plugin in ``llvm_*`` variants and
    ``measured`` in ``scalar_*`` ones (the plugin's lookups are Dr.Jit arrays: it runs in the
    vectorized variants only). ``ValueError`` for the plugin in a scalar variant."""
    scalar = job.variant.startswith("scalar")
    if job.via is None:
        return "measured" if scalar else "plugin"
    if job.via not in VIA:
        raise ValueError(f"via must be one of {list(VIA)}, got {job.via!r}")
    if job.via == "plugin" and scalar:
        raise ValueError(
            f"the emscatter plugin runs in the llvm_* variants, not in {job.variant!r}: use "
            "--via measured (the table converted to an RGL file) or an llvm_* variant"
        )
    return job.via


def _mitsuba_error(exc: Exception, tmp: str | None = None, path: Path | None = None) -> str:
    """Mitsuba's message on one line: the last exception of a Python traceback inside it,
    the temporary copy of a scene named as the user's file."""
    msg = " ".join(str(exc).split())
    if "Traceback" in msg:
        head, _, tail = msg.partition("Traceback")
        last = re.findall(r"(\w+(?:Error|Exception): .*)$", tail)
        msg = head.rstrip(": ") + (f": {last[-1]}" if last else "")
    if tmp is not None and path is not None:
        msg = msg.replace(tmp, str(path))
    return msg


def _read_table(path: Path):
    from ..brdf.export_npz import read_npz

    return read_npz(path)


def bsdf_for(job: RenderJob, workdir: Path) -> tuple[dict, dict]:
    """The BSDF dict for ``job`` in the current variant and a description of it; ``workdir``
    holds a converted ``.bsdf`` (``via="measured"`` for a table)."""
    import mitsuba as mi

    from . import mitsuba as em_mi

    src = job.source
    if src.suffix.lower() == ".bsdf":
        return {"type": "measured", "filename": str(src)}, {"kind": "measured", "file": src.name}
    table = _read_table(src)
    if job.btdf is not None:
        return _dielectric_bsdf(job, table)
    if via_for(job) == "plugin":
        bsdf = em_mi.bsdf_dict(table, coherent=job.coherent)
        return bsdf, {"kind": "plugin", "table": table.describe()}
    from ..brdf.export_rgl import write_rgl

    channels = em_mi.channels_of_variant(mi.variant())
    path = write_rgl(workdir / f"{src.stem}.bsdf", table, channels=channels)
    return {"type": "measured", "filename": str(path)}, {
        "kind": "measured (converted)",
        "table": table.describe(),
        "channels": channels,
    }


def _dielectric_bsdf(job: RenderJob, table) -> tuple[dict, dict]:
    """The ``emscatter_dielectric`` plugin (:mod:`.dielectric`) of SOURCE, ``--btdf`` and
    ``--inner``; mismatched tables (wavelengths, an anisotropic BRDF) are a ``ValueError``."""
    from ..brdf.export_npz import read_btdf_npz
    from . import dielectric as em_d

    if via_for(job) != "plugin":
        raise ValueError("a dielectric (--btdf) renders through the plugin only, not measured")
    bt = read_btdf_npz(job.btdf)
    inner = None if job.inner is None else _read_table(job.inner)
    try:
        bsdf = em_d.bsdf_dict(table, bt, inner, coherent=job.coherent)
    except TypeError as exc:  # a table of the wrong kind: bad input, one line
        raise ValueError(f"dielectric tables: {exc}") from None
    described = {"kind": "dielectric plugin", "table": table.describe(), "btdf": bt.describe()}
    if inner is not None:
        described["inner"] = inner.describe()
    return bsdf, described


def _xml_bsdf(bsdf: dict) -> str:
    if bsdf["type"] == "emscatter_dielectric":
        return (
            f'<bsdf type="{bsdf["type"]}" id="emscatter"><string name="tables" '
            f'value="{bsdf["tables"]}"/><boolean name="coherent" '
            f'value="{str(bsdf["coherent"]).lower()}"/></bsdf>'
        )
    if bsdf["type"] == "measured":
        return (
            f'<bsdf type="measured" id="emscatter"><string name="filename" '
            f'value="{bsdf["filename"]}"/></bsdf>'
        )
    return (
        f'<bsdf type="{bsdf["type"]}" id="emscatter"><string name="table" value="{bsdf["table"]}"/>'
        f'<boolean name="coherent" value="{str(bsdf["coherent"]).lower()}"/>'
        f'<integer name="sampling_resolution" value="{bsdf["sampling_resolution"]}"/></bsdf>'
    )


def _load_user_scene(path: Path, bsdf: dict):
    import mitsuba as mi

    text = path.read_text(encoding="utf-8")
    if not _REF.search(text):
        raise ValueError(
            f'scene {str(path)!r} must refer to the BSDF to render as <ref id="emscatter"/> '
            "inside a shape (emscatter render inserts the BSDF under that id)"
        )
    tag = _SCENE_TAG.search(text)
    if tag is None:
        raise ValueError(f"scene {str(path)!r} has no <scene ...> element (not a Mitsuba 3 scene)")
    patched = text[: tag.end()] + _xml_bsdf(bsdf) + text[tag.end() :]
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=".xml", dir=path.parent)
    try:
        with open(fd, "w", encoding="utf-8") as fh:
            fh.write(patched)
        try:
            return mi.load_file(tmp)
        except RuntimeError as exc:
            msg = _mitsuba_error(exc, tmp, path)
            raise ValueError(f"Mitsuba could not load scene {str(path)!r}: {msg}") from None
    finally:
        Path(tmp).unlink(missing_ok=True)


def _write_exr(path: Path, img: np.ndarray) -> Path:
    import mitsuba as mi

    with atomic_path(path, suffix=".exr") as tmp:
        mi.Bitmap(np.ascontiguousarray(img, dtype=np.float32)).write(str(tmp))
    return path


def render_job(job: RenderJob) -> dict:
    """Render ``job`` (sets its variant in this process); returns a summary: files written,
    image size, mean linear RGB, time [s]. ``ValueError`` for bad input (one line)."""
    import drjit as dr
    import mitsuba as mi

    from . import scenes

    mi.set_variant(check_variant(job.variant))
    via_for(job)  # before any work
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="emscatter-render-") as work:
        bsdf, described = bsdf_for(job, Path(work))
        if job.scene is None:
            scene = scenes.sphere_row(
                [bsdf], width=job.width, height=job.height, spp=job.spp, emitter=job.emitter
            )
            try:
                loaded = mi.load_dict(scene)
            except RuntimeError as exc:
                raise ValueError(
                    f"Mitsuba could not load the BSDF: {_mitsuba_error(exc)}"
                ) from None
        else:
            loaded = _load_user_scene(job.scene, bsdf)
        img = mi.render(loaded, seed=int(job.seed), spp=int(job.spp))
        dr.eval(img)
        img = np.array(img, dtype=np.float64)[..., :3]
    bad = int(np.size(img) - np.count_nonzero(np.isfinite(img)))
    if bad:
        raise RuntimeError(f"the render has {bad} non-finite pixel values; no image written")
    written = [scenes.save_png(job.out, img, exposure=job.exposure)]
    if job.exr is not None:
        written.append(_write_exr(job.exr, img))
    mean = img.reshape(-1, 3).mean(axis=0)
    return {
        "files": [str(p) for p in written],
        "size": [int(img.shape[1]), int(img.shape[0])],
        "spp": int(job.spp),
        "variant": job.variant,
        "bsdf": described,
        "mean_rgb": [float(x) for x in mean],
        "seconds": round(time.perf_counter() - t0, 3),
        "finite": math.isfinite(float(mean.sum())),
    }
