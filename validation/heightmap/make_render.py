"""Issue 17's figure, the rendered half: a brushed-metal-like height map through every step
(generated, written to .x3p, read back, measured, GO table) rendered on a sphere by the real
Mitsuba beside the sphere of its parametric Gaussian fit, with the mean image difference.

    PYTHONPATH=src .venv/bin/python validation/heightmap/make_render.py [--width 128 --spp 32]
    # → validation/heightmap/render.png and render.json (needs SurfaceTopography and Mitsuba)

Its own process (Dr.Jit variants are per process; ``make_figure.py`` runs it as a subprocess).
The map: gold, an anisotropic Gaussian (σ = 0.15 µm, ℓx = 1 µm, ℓy = 3 µm, the brushed case
of ``benchmarks/bench_heightmap.py``), 512² at Δ = 0.1 µm. Measured: GO on the map's slope
histogram (:class:`~emscatter.surfaces.measured.MeasuredRoughness`). Fit: GO on the Gaussian
with the map's own σ and 1/e lengths (``GaussianCorrelation(σ, ℓx, length_y=ℓy)``), what a
user who only had ``summarize`` would render. Both tables anisotropic, 24 × 48 directions,
450/550/650 nm, rendered through the emscatter plugin (:mod:`emscatter.render.mitsuba`) in
``llvm_ad_rgb`` with :func:`emscatter.render.scenes.sphere_row`. The difference is
:func:`emscatter.render.scenes.image_difference` (8-px block means, relative to the fit's);
the same scene rendered with another seed gives the Monte Carlo floor it is read against.
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
from emscatter.io import write_json  # noqa: E402
from emscatter.spectra import GaussianCorrelation  # noqa: E402
from emscatter.surfaces.heightmap import height_map, read_height_map, write_height_map  # noqa: E402
from emscatter.surfaces.measured import measured_roughness  # noqa: E402

ROUGH = GaussianCorrelation(0.15e-6, 1.0e-6, length_y=3.0e-6)
SHAPE, DX = (512, 512), 0.1e-6
WL = [450e-9, 550e-9, 650e-9]
RES = (24, 48)


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
           "table_resolution": list(RES), "method": "go"}  # fmt: skip
    return t_m, t_f, t_s, rec


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
    scene = scenes.sphere_row(bsdfs, width=a.width * 3, spp=a.spp)
    img = scenes.render(scene, seed=0, spp=a.spp)
    again = scenes.render(scene, seed=1, spp=a.spp)
    w = img.shape[1] // 3
    part = [slice(i * w, (i + 1) * w) for i in range(3)]
    diff_s = scenes.image_difference(img[:, part[0]], img[:, part[1]])
    diff = scenes.image_difference(img[:, part[0]], img[:, part[2]])
    floor = sum(scenes.image_difference(img[:, q], again[:, q]) for q in part) / 3
    title = (f"brushed gold map (ℓy = 3 ℓx) → GO tables; mean |Δ| to the measured sphere: "
             f"{100 * diff_s:.1f} % (slope fit), {100 * diff:.1f} % (1/e-length fit), "
             f"noise {100 * floor:.1f} %")  # fmt: skip
    labels = ["measured map", "Gaussian, map's rms slopes", "Gaussian, map's σ and 1/e ℓ"]
    scenes.save_rows(a.out, [(img, title, labels)])
    rec.update({"render": {"variant": "llvm_ad_rgb", "width_px": a.width * 3,
                           "height_px": int(img.shape[0]), "spp": a.spp, "emitter": "sky+sun"},
                "mean_difference": diff, "mean_difference_slope_fit": diff_s,
                "monte_carlo_floor": floor,
                "difference_definition": "emscatter.render.scenes.image_difference (8-px "
                "block means, relative to the fit's sphere)",
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
