"""``emscatter render``: render a sphere (or a user's Mitsuba scene) with a BRDF, write a PNG.

``SOURCE`` is an emscatter table (``.npz`` from ``emscatter brdf``), rendered through the
emscatter Mitsuba plugin (``--via plugin``, the default in ``llvm_*`` variants, coherent lobe
included) or converted to an RGL file for Mitsuba's ``measured`` (``--via measured``, the
default in ``scalar_*`` variants, where the plugin does not run), or an RGL ``.bsdf`` file
(Mitsuba's ``measured``). ``--scene FILE.xml``: the user's Mitsuba 3 scene, where a shape refers
to the BSDF as ``<ref id="emscatter"/>`` (its film sets the image size). The work is
:mod:`emscatter.render.job`; every input is checked before Mitsuba is started: the source
(exists, ``.npz``/``.bsdf``, an emscatter BRDF table), the outputs, the variant, ``--spp`` and
the size. Errors are one line with exit status 2.

A rough dielectric (``emscatter brdf glass.npz --material 2.25 --transmission``): SOURCE the
outside reflection, ``--btdf`` its BTDF table and ``--inner`` the inside reflection, rendered
through the ``emscatter_dielectric`` plugin (:mod:`emscatter.render.dielectric`; ``llvm_*``
RGB and spectral variants).

    emscatter render gold.npz --out gold.png --width 256 --spp 64 --variant llvm_ad_spectral
    emscatter render glass.npz --btdf glass_btdf.npz --inner glass_inner.npz --out glass.png
"""

from __future__ import annotations

import json
from pathlib import Path

from .args import Integer, Number, add_command, reject_unless
from .paths import OutputPath, check_distinct

SOURCES = (".npz", ".bsdf")


def register(subparsers) -> None:
    from ..render.job import EMITTERS, VIA

    p = add_command(
        subparsers,
        "render",
        help="render a sphere or a Mitsuba scene with a BRDF table (.npz) or .bsdf file",
        description=(
            'render a sphere (or a Mitsuba scene that uses <ref id="emscatter"/>) with an '
            "emscatter BRDF table (through the emscatter plugin or Mitsuba's measured), an RGL "
            ".bsdf file, or a dielectric's BRDF/BTDF pair; write a PNG (and an OpenEXR)"
        ),
    )
    p.add_argument("source", type=Path, help="BRDF table (.npz) or RGL file (.bsdf)")
    p.add_argument("--out", type=OutputPath(suffixes=(".png",)), required=True, help="PNG")
    p.add_argument(
        "--exr",
        type=OutputPath(suffixes=(".exr",)),
        default=None,
        help="also write the linear image as OpenEXR",
    )
    p.add_argument(
        "--via",
        choices=VIA,
        default=None,
        help="how a .npz table reaches Mitsuba (default: plugin in llvm_* variants, "
        "measured in scalar_* ones)",
    )
    p.add_argument(
        "--scene",
        type=Path,
        default=None,
        help='a Mitsuba 3 scene XML using <ref id="emscatter"/> (default: a sphere)',
    )
    p.add_argument(
        "--variant",
        default="llvm_ad_rgb",
        help="Mitsuba variant: scalar_rgb, scalar_spectral, llvm_ad_rgb, llvm_ad_spectral",
    )
    p.add_argument(
        "--width",
        type=Integer(low=8, high=8192),
        default=None,
        help="image width [px] (sphere scene; default 256)",
    )
    p.add_argument(
        "--height",
        type=Integer(low=8, high=8192),
        default=None,
        help="image height [px] (sphere scene; default: what fits)",
    )
    p.add_argument("--spp", type=Integer(low=1, high=1 << 20), default=64, help="samples per pixel")
    p.add_argument(
        "--emitter", choices=EMITTERS, default="sky+sun", help="lights of the sphere scene"
    )
    p.add_argument(
        "--exposure",
        type=Number(low=0.0),
        default=1.5,
        help="exposure of the PNG (linear scale before sRGB)",
    )
    p.add_argument("--seed", type=Integer(low=0), default=0, help="sampler seed")
    p.add_argument(
        "--no-coherent", action="store_true", help="leave out the plugin's coherent (delta) lobe"
    )
    p.add_argument(
        "--btdf",
        type=Path,
        default=None,
        help="a BTDF table (.npz, emscatter brdf --transmission): render SOURCE as a rough "
        "dielectric through the emscatter_dielectric plugin",
    )
    p.add_argument(
        "--inner",
        type=Path,
        default=None,
        help="with --btdf: the inside reflection table (OUT_inner.npz); without it nothing is "
        "reflected inside",
    )
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.set_defaults(func=run)


def _check_source(path: Path) -> Path:
    if path.suffix.lower() not in SOURCES:
        raise ValueError(
            f"SOURCE must be an emscatter BRDF table (.npz) or an RGL file (.bsdf), got "
            f"{str(path)!r}"
        )
    if not path.is_file():
        raise ValueError(f"SOURCE {str(path)!r} does not exist (or is not a file)")
    if path.suffix.lower() == ".npz":
        from ..brdf.export_npz import read_npz

        read_npz(path)  # a clear ValueError for a file that is not a BRDF table
    else:
        with open(path, "rb") as fh:
            head = fh.read(12)
        if not head.startswith(b"tensor_file"):
            raise ValueError(f"SOURCE {str(path)!r} is not an RGL tensor file (.bsdf)")
    return path


def _check_dielectric(a, source: Path) -> tuple[Path, Path | None]:
    """``(--btdf, --inner)`` once checked: .npz files of the right kinds, an .npz SOURCE, the
    plugin (not ``measured``: it has no transmission)."""
    from ..brdf.export_npz import read_btdf_npz, read_npz

    if source.suffix.lower() != ".npz":
        raise ValueError(f"--btdf needs an emscatter BRDF table (.npz) SOURCE, got {str(source)!r}")
    if a.via == "measured" or (a.via is None and a.variant.startswith("scalar")):
        raise ValueError(
            "--btdf renders through the emscatter_dielectric plugin (llvm_* variants; Mitsuba's "
            f"measured has no transmission), got --via {a.via} in {a.variant!r}"
        )
    out = []
    for opt, path, reader in (("--btdf", a.btdf, read_btdf_npz), ("--inner", a.inner, read_npz)):
        if path is None:
            out.append(None)
            continue
        path = path.expanduser()
        if path.suffix.lower() != ".npz" or not path.is_file():
            raise ValueError(f"{opt} must name an existing .npz table, got {str(path)!r}")
        try:
            reader(path)
        except ValueError as exc:
            raise ValueError(f"{opt} {str(path)!r}: {exc}") from None
        out.append(path)
    return out[0], out[1]


def run(a) -> int:
    from ..render.job import RenderJob, check_variant, render_job, via_for

    source = _check_source(a.source.expanduser())
    scene = None
    if a.scene is not None:
        scene = a.scene.expanduser()
        if scene.suffix.lower() != ".xml" or not scene.is_file():
            raise ValueError(
                f"--scene must name an existing Mitsuba scene .xml, got {str(scene)!r}"
            )
    reject_unless(
        a,
        scene is None,
        ("--width", "--height", "--emitter"),
        "only to the sphere scene (a user's --scene sets its own film and lights)",
    )
    reject_unless(
        a,
        source.suffix.lower() == ".npz",
        ("--via", "--no-coherent"),
        "only to an emscatter table (.npz) SOURCE",
    )
    reject_unless(a, a.btdf is not None, ("--inner",), "only with --btdf (a dielectric)")
    btdf = inner = None
    if a.btdf is not None:
        btdf, inner = _check_dielectric(a, source)
    check_distinct({"--out": a.out, "--exr": a.exr})
    check_variant(a.variant)
    job = RenderJob(
        source=source,
        out=a.out,
        variant=a.variant,
        via=a.via,
        scene=scene,
        width=a.width or 256,
        height=a.height,
        spp=a.spp,
        emitter=a.emitter,
        exr=a.exr,
        exposure=a.exposure,
        seed=a.seed,
        coherent=not a.no_coherent,
        btdf=btdf,
        inner=inner,
    )
    via_for(job)
    summary = render_job(job)
    if a.json:
        print(json.dumps(summary))
    else:
        w, h = summary["size"]
        rgb = ", ".join(f"{x:.4g}" for x in summary["mean_rgb"])
        print(
            f"rendered {w}×{h} px, {summary['spp']} spp, {summary['variant']}, "
            f"{summary['bsdf']['kind']}; mean linear RGB ({rgb}); {summary['seconds']:.3g} s"
        )
        for f in summary["files"]:
            print(f"wrote {f}")
    return 0
