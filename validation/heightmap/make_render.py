"""Issue 17's figure, the rendered half: a brushed-metal-like height map through every step
(generated, written to .x3p, read back, measured, GO table) rendered on a sphere by the real
Mitsuba beside the sphere of its parametric Gaussian fit, with the mean image difference.

    PYTHONPATH=src .venv/bin/python validation/heightmap/make_render.py [--width 128 --spp 32]
    # → validation/heightmap/render.png and render.json (needs SurfaceTopography and Mitsuba)

Its own process (Dr.Jit variants are per process; ``make_figure.py`` runs it as a subprocess).
The map: gold, an anisotropic Gaussian (σ = 0.15 µm, ℓx = 1 µm, ℓy = 3 µm, the brushed case
of ``benchmarks/bench_heightmap.py``), 512² at Δ = 0.1 µm: rms slopes 0.21 / 0.07 (mean-square
0.042 / 0.0049), moderate, the GO lobe 8° rms in the narrow (y) direction (``brdf.sizing``'s
``√2 m``). Measured: GO on the map's slope density
(:class:`~emscatter.surfaces.measured.MeasuredRoughness`: kernel estimate, Gaussian tail beyond
the well-sampled slopes, ``slope_tail="gaussian"``). Fits: GO on the Gaussian with the map's
rms slopes, and on the Gaussian with the map's own σ and 1/e lengths
(``GaussianCorrelation(σ, ℓx, length_y=ℓy)``), what a user who only had ``summarize`` would
render. Tables anisotropic, 450/550/650 nm, rendered through the emscatter plugin
(:mod:`emscatter.render.mitsuba`) in ``llvm_ad_rgb`` with
:func:`emscatter.render.scenes.sphere_row`. The difference is
:func:`emscatter.render.scenes.image_difference` (8-px block means, relative to the fit's);
the same scene rendered with another seed gives the Monte Carlo floor it is read against.

Resolution: 48 × 96 directions (θ step 1.875°, φ step 3.75°; step/lobe 0.23: predicted
interpolation error in the lobe ≈ 2 % median, 9 % p90 by ``brdf.sizing.predicted_error``).
The library's default rule (step ≤ 0.1 lobe) would need 112 × 224 nodes, (112·224)² = 6.3e8
direction pairs a wavelength for an anisotropic table: far beyond a figure's two minutes;
the 24 × 48 grid used before (step/lobe 0.47, p90 ≈ 35 %) was too coarse. The moderate
slopes are kept (the brief's alternative) rather than the default rule's resolution.

The dark-centred ring the earlier render.png showed was not the resolution (it stayed at
48 × 96, and an isotropic GO table at 90 × 180 showed a plain blob, as Mitsuba's own
``roughconductor``): Mitsuba's sphere puts the pole of its (u, v) parametrization on its
local +z, here facing the camera, and an anisotropic BSDF's tangent (the map's x axis along
∂p/∂u) turns once around that pole, inside the highlight: a "spun" sphere, whose brushing
is circumferential around the point facing the viewer, and whose highlight is a ring. The
spheres are therefore turned pole-up (local z → world y, :func:`upright`): the map's x axis
runs along the latitude lines, the poles are out of the highlight, and the highlight is the
elongated streak of a brushed surface.

Differences: two spheres in different slots of the row differ by their light as much as by
their BSDF (the environment's parallax, the neighbours' glow: the measured and slope-fit
spheres read 8.8 % apart across slots, the figure's old 10 % / 20 %). Each pair is therefore
compared in the same slot, the row rendered three times rotated (own seeds) and the three
slots averaged: measured vs slope fit 2.1 %, vs σ/ℓ fit 2.1 %, against a Monte Carlo floor of
1.7 % (32 spp, 384 px; the map is drawn from a Gaussian, so its fits match it: the two fits
differ by 1 % in ℓy). Tables ≈ 100 s, total ≈ 150 s on 2 loaded cores.
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
import warnings
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1] / "src"))

import emscatter  # noqa: E402
from emscatter.brdf import build_table  # noqa: E402
from emscatter.brdf.sizing import lobe_width, predicted_error  # noqa: E402
from emscatter.io import write_json  # noqa: E402
from emscatter.spectra import GaussianCorrelation  # noqa: E402
from emscatter.surfaces.heightmap import height_map, read_height_map, write_height_map  # noqa: E402
from emscatter.surfaces.measured import measured_roughness  # noqa: E402

ROUGH = GaussianCorrelation(0.15e-6, 1.0e-6, length_y=3.0e-6)
SHAPE, DX = (512, 512), 0.1e-6
WL = [450e-9, 550e-9, 650e-9]
RES = (48, 96)


def tables():
    """(measured table, fit table, record): the map through .x3p, measured, both GO tables."""
    s = emscatter.generate_surface(ROUGH, SHAPE, DX, rng=17)
    with tempfile.TemporaryDirectory() as tmp:
        path = write_height_map(height_map(s.heights, s.spacing), Path(tmp) / "brushed.x3p")
        hm = read_height_map(path)
    m = measured_roughness(hm)
    fit = GaussianCorrelation(m.sigma, m.length, length_y=m.length_y)
    sx, sy = m.mean_square_slope()  # the Gaussian with the map's σ and rms slopes √2σ/ℓ
    slope_fit = GaussianCorrelation(m.sigma, math.sqrt(2 / sx) * m.sigma,
                                    length_y=math.sqrt(2 / sy) * m.sigma)  # fmt: skip
    kw = {"method": "go", "resolution": RES, "anisotropic": True, "out_of_range": "ignore",
          "progress": False}  # fmt: skip
    t_m = build_table(m, "Au", WL, **kw)
    t_f = build_table(fit, "Au", WL, **kw)
    t_s = build_table(slope_fit, "Au", WL, **kw)
    rec = {"map": {"shape": list(SHAPE), "spacing_m": DX, "drawn_from": ROUGH.describe(),
                   "file": "brushed.x3p (temporary)",
                   "measured": m.describe().replace(str(path), path.name)},
           "fit": fit.describe(), "slope_fit": slope_fit.describe(), "material": "Au",
           "wavelengths_m": WL,
           "table_resolution": list(RES), "method": "go",
           "slope_tail": {k: m.info["slope_tail"][k] for k in ("shape", "junction_rms",
                                                                "keeps")},
           "predicted_interpolation_error_median_p90": list(predicted_error(
               0.5 * math.pi / RES[0], lobe_width(m, WL, ["go"] * len(WL))))}  # fmt: skip
    return t_m, t_f, t_s, rec


def upright(scene: dict) -> dict:
    """Turn each sphere of a :func:`~emscatter.render.scenes.sphere_row` scene pole-up (its
    local z, the pole of its (u, v) parametrization, along world y; module docstring)."""
    import mitsuba as mi

    for key, shape in scene.items():
        if key.startswith("sphere_"):
            centre, radius = shape.pop("center"), shape.pop("radius")
            shape["to_world"] = (
                mi.ScalarTransform4f().translate(centre).rotate([1, 0, 0], -90).scale(radius)
            )
    return scene


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--width", type=int, default=128, help="image width [px]")
    ap.add_argument("--spp", type=int, default=32, help="samples per pixel")
    ap.add_argument("--out", type=Path, default=HERE / "render.png", help="figure (.png)")
    a = ap.parse_args(argv)
    warnings.simplefilter("ignore")
    t0 = time.perf_counter()
    t_m, t_f, t_s, rec = tables()
    t_tables = time.perf_counter() - t0

    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    from emscatter.render import scenes
    from emscatter.render.mitsuba import bsdf_dict

    bsdfs = [bsdf_dict(t) for t in (t_m, t_s, t_f)]
    scene = upright(scenes.sphere_row(bsdfs, width=a.width * 3, spp=a.spp))
    img = scenes.render(scene, seed=0, spp=a.spp)
    again = scenes.render(scene, seed=1, spp=a.spp)
    w = img.shape[1] // 3
    part = [slice(i * w, (i + 1) * w) for i in range(3)]
    # each BSDF in each slot (the row rotated twice more): a difference compares two BSDFs in
    # the same slot, so the slot's own light (environment parallax, the neighbours' glow) cancels
    slot = {0: img}
    for r in (1, 2):
        order = [(i + r) % 3 for i in range(3)]  # slot q holds BSDF order[q]
        sc = upright(scenes.sphere_row([bsdfs[i] for i in order], width=a.width * 3, spp=a.spp))
        slot[r] = scenes.render(sc, seed=1 + r, spp=a.spp)  # own seed: noise as the floor's

    def at(b: int, q: int):  # BSDF b's sphere in slot q
        return slot[(b - q) % 3][:, part[q]]

    def between(b0: int, b1: int) -> float:
        return sum(scenes.image_difference(at(b0, q), at(b1, q)) for q in range(3)) / 3

    diff_s, diff = between(0, 1), between(0, 2)
    diff_slot = scenes.image_difference(img[:, part[0]], img[:, part[1]])
    floor = sum(scenes.image_difference(img[:, q], again[:, q]) for q in part) / 3
    title = (f"brushed gold map (ℓy = 3 ℓx) → GO tables; mean |Δ| to the measured sphere "
             f"(same slot): "
             f"{100 * diff_s:.1f} % (slope fit), {100 * diff:.1f} % (1/e-length fit), "
             f"noise {100 * floor:.1f} %")  # fmt: skip
    labels = ["measured map", "Gaussian, map's rms slopes", "Gaussian, map's σ and 1/e ℓ"]
    scenes.save_rows(a.out, [(img, title, labels)])
    rec.update({"render": {"variant": "llvm_ad_rgb", "width_px": a.width * 3,
                           "height_px": int(img.shape[0]), "spp": a.spp, "emitter": "sky+sun",
                           "spheres": "pole-up (local z along world y): the map's x axis "
                           "along the latitude lines"},
                "mean_difference": diff, "mean_difference_slope_fit": diff_s,
                "monte_carlo_floor": floor,
                "mean_difference_slope_fit_across_slots": diff_slot,
                "difference_definition": "emscatter.render.scenes.image_difference (8-px "
                "block means, relative to the fit's sphere), each pair compared in the same "
                "slot of the row and averaged over the 3 slots (the row rendered in 3 "
                "rotations, seeds 0, 2, 3: independent noise, as the floor's); _across_slots: "
                "the measured sphere (slot 0) against the slope "
                "fit's (slot 1) of the figure, slot light included",
                "seconds": {"tables": round(t_tables, 2),
                            "total": round(time.perf_counter() - t0, 2)},
                "figure": a.out.name})  # fmt: skip
    write_json(a.out.with_suffix(".json"), rec)
    print(f"wrote {a.out}: mean difference {100 * diff_s:.2f} % (slope fit), "
          f"{100 * diff:.2f} % (1/e fit) (Monte Carlo floor "
          f"{100 * floor:.2f} %), {rec['seconds']}")  # fmt: skip
    if not (math.isfinite(diff) and math.isfinite(floor)):
        raise SystemExit("non-finite image difference")
    return rec


if __name__ == "__main__":
    main()
