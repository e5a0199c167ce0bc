"""Sphere renders of the seed's ch. 4 figures through the real Mitsuba and the emscatter plugin.

Run: ``PYTHONPATH=src python validation/brdf/porosity/make_figures.py [OUT_DIR]`` (default: this
folder). Writes ``fig4_3_porosity.png`` (Blinn–Phong k_s = 0.5, k_d = 0.4: α = 0 vs 0.35, seed
Fig. 4.3), ``wet_sequence.png`` (α = 0.35, pores filled 0 → 1; seed §4.6, Fig. 4.16 below),
``pollution_sequence.png`` (t = 0, 0.2, 0.4, 0.6 at α = 0.35, seed Fig. 4.10; α = 0 … 0.6 at
t = 0.4, Fig. 4.11) and ``figures.json`` (parameters, albedos, timings). The porosity parameters
go to the plugin as scene-dict parameters (applied to the table at load time).
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
KS, KD, N_BP = 0.5, 0.4, 40.0  # seed Fig. 4.3: Blinn–Phong k_s = 0.5, k_d = 0.4
WL = [550e-9]


def main(out_dir: Path) -> int:
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    from emscatter.brdf import porosity as P
    from emscatter.brdf.analytic import blinn_phong, table_from_function
    from emscatter.io import write_json
    from emscatter.render import mitsuba as em_mi
    from emscatter.render import scenes

    t0 = time.perf_counter()
    base = table_from_function(
        lambda wi, wo, wl: blinn_phong(wi, wo, N_BP, ks=KS), WL, resolution=(30, 60)
    )
    key = em_mi.register_table(base)
    common = {"diffuse_albedo": KD, "specular_albedo": KS, "pore_shape": 2.0, "pore_slope": 0.08}

    def bsdf(**params):
        return {"type": "emscatter", "table": key, "sampling_resolution": 32, **common, **params}

    rows_spec = {
        "fig4_3_porosity.png": [
            ("seed Fig. 4.3: Blinn–Phong ks = 0.5, kd = 0.4, porosity off / on",
             [("α = 0", bsdf(porosity=0.0)), ("α = 0.35", bsdf(porosity=0.35))]),
        ],
        "wet_sequence.png": [
            ("seed §4.6: wetting, α = 0.35, pore filling Δt/t_fill",
             [(f"{w:g}", bsdf(porosity=0.35, wetness=w)) for w in (0.0, 0.25, 0.5, 0.75, 1.0)]),
            ("seed Fig. 4.16: fully wet, α varied",
             [(f"α = {a:g}", bsdf(porosity=a, wetness=1.0)) for a in (0.0, 0.2, 0.4, 0.6)]),
        ],
        "pollution_sequence.png": [
            ("seed Fig. 4.10: pollution over time, α = 0.35, t_fill = 0.6",
             [(f"t = {t:g}", bsdf(porosity=0.35, pollution_time=t, pollution_fill_time=0.6))
              for t in (0.0, 0.2, 0.4, 0.6)]),
            ("seed Fig. 4.11: t = 0.4 (t_fill = 0.6), α varied",
             [(f"α = {a:g}", bsdf(porosity=a, pollution_time=0.4, pollution_fill_time=0.6))
              for a in (0.0, 0.2, 0.4, 0.6)]),
        ],
    }  # fmt: skip
    report = {"base": base.describe(), "variant": mi.variant(), "figures": {}}
    for name, rows in rows_spec.items():
        rendered = []
        for title, spheres in rows:
            scene = scenes.sphere_row([b for _, b in spheres], width=90 * len(spheres), spp=32)
            rendered.append((scenes.render(scene), title, [lab for lab, _ in spheres]))
        scenes.save_rows(out_dir / name, rendered, exposure=1.0)
        report["figures"][name] = {
            title: {
                lab: {
                    "params": {k: v for k, v in b.items() if k in P.PLUGIN_PARAMS},
                    "mean_albedo": float(
                        P.from_plugin_params(
                            base, {k: v for k, v in b.items() if k in P.PLUGIN_PARAMS}
                        )
                        .albedo()
                        .total.mean()
                    ),
                }
                for lab, b in spheres
            }
            for title, spheres in rows
        }
    report["seconds"] = round(time.perf_counter() - t0, 1)
    write_json(out_dir / "figures.json", report)
    print(json.dumps({"seconds": report["seconds"], "out": [*rows_spec, "figures.json"]}))
    return 0


if __name__ == "__main__":
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else HERE
    out.mkdir(parents=True, exist_ok=True)
    sys.exit(main(out))
