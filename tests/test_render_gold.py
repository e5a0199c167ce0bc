"""A geometric-optics table of gold (Mitsuba's own Au η/k data, via ``emscatter.materials``),
rendered spectrally through the plugin and through ``measured`` (an RGL export), against
Mitsuba's ``roughconductor`` (Beckmann, same α, ``material="Au"``) at equal samples.

Criterion: mean absolute difference of 8×8-pixel block means ≤ 1 % of the mean, at a sample
count where ``roughconductor`` against itself (another seed) is well under that (asserted
< 0.3 %). What remains is the table's interpolation (2° nodes, 16 wavelengths over 360–830 nm)
and Mitsuba's rational approximation of Smith's G1 (≤ 0.35 % per factor, tests/test_mitsuba_go.py).
"""

from __future__ import annotations

import numpy as np
import pytest

from emscatter.brdf.export_rgl import write_rgl
from emscatter.render import mitsuba as em_mi
from emscatter.render import scenes
from render_helpers import go_table, use_variant

ALPHA = 0.25


@pytest.mark.slow
def test_gold_plugin_and_measured_match_roughconductor(tmp_path):
    use_variant("llvm_ad_spectral")
    lam = np.linspace(360e-9, 830e-9, 16)
    table = go_table(alpha=ALPHA, material="Au", wavelengths=tuple(lam))
    path = write_rgl(tmp_path / "gold.bsdf", table, channels="spectral")
    bsdfs = {
        "roughconductor": {
            "type": "roughconductor",
            "distribution": "beckmann",
            "alpha": ALPHA,
            "material": "Au",
        },
        "plugin": em_mi.bsdf_dict(table),
        "measured": {"type": "measured", "filename": str(path)},
    }
    imgs = {}
    for name, bsdf in bsdfs.items():
        scene = scenes.sphere_row([bsdf], width=64, spp=256, sampler="multijitter")
        imgs[name] = scenes.render(scene, seed=1)
    again = scenes.render(
        scenes.sphere_row([bsdfs["roughconductor"]], width=64, spp=256, sampler="multijitter"),
        seed=2,
    )
    ref = imgs["roughconductor"]
    noise = scenes.image_difference(again, ref)
    diffs = {k: scenes.image_difference(imgs[k], ref) for k in ("plugin", "measured")}
    print(
        f"roughconductor vs itself {noise:.4f}; "
        + ", ".join(f"{k} {v:.4f}" for k, v in diffs.items())
    )
    assert noise < 3e-3
    assert diffs["plugin"] < 1e-2 and diffs["measured"] < 1e-2
    # gold, not grey: red exceeds blue on the sphere
    assert ref[..., 0].mean() > 1.3 * ref[..., 2].mean()
