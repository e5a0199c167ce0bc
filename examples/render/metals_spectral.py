"""Metals at visible wavelengths, rendered spectrally (Mitsuba ``llvm_ad_spectral``): geometric
optics tables (Beckmann slope α = 2σ/ℓ = 0.2) of gold, silver, copper, aluminium and chromium
from Mitsuba's own η/k data (``emscatter.materials.metal``), through the emscatter plugin (top)
and Mitsuba's ``roughconductor`` with the same α and ``material=`` (bottom).

    python examples/render/metals_spectral.py           # → docs/figures/render_metals.png
    python examples/render/metals_spectral.py --quick   # tiny version (what the tests run)
"""

from __future__ import annotations

import warnings
from pathlib import Path

import mitsuba as mi
import numpy as np

from emscatter.brdf import build_table
from emscatter.materials import metal
from emscatter.render import mitsuba as em_mi
from emscatter.render import scenes
from emscatter.render.cli_options import example_settings
from emscatter.spectra import GaussianCorrelation

OUT = Path(__file__).resolve().parents[2] / "docs" / "figures" / "render_metals.png"
METALS = ["Au", "Ag", "Cu", "Al", "Cr"]
ALPHA = 0.2
SURFACE = GaussianCorrelation(0.1e-6, 1e-6)  # σ = 0.1 µm, ℓ = 1 µm: α = 2σ/ℓ = 0.2


def main(argv=None) -> Path:
    s = example_settings(__doc__.splitlines()[0], OUT, argv)
    mi.set_variant("llvm_ad_spectral")
    names = METALS[:2] if s.quick else METALS
    wl = np.linspace(360e-9, 830e-9, s.n_wavelengths if s.quick else 20)
    # 1.5° nodes resolve α = 0.2 and keep five 20-wavelength tables at ~35 MB each
    resolution = s.resolution if s.quick else (60, 120)
    ours, theirs = [], []
    for name in names:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            table = build_table(SURFACE, metal(name), wl, method="go", resolution=resolution)
        ours.append(em_mi.bsdf_dict(table))
        theirs.append(
            {"type": "roughconductor", "distribution": "beckmann", "alpha": ALPHA, "material": name}
        )
    a = scenes.render(scenes.sphere_row(ours, width=s.width, spp=s.spp))
    b = scenes.render(scenes.sphere_row(theirs, width=s.width, spp=s.spp))
    diff = scenes.image_difference(a, b)
    return scenes.save_rows(
        s.out,
        [
            (a, f"emscatter GO tables, {wl.size} wavelengths, spectral render", names),
            (
                b,
                f"Mitsuba roughconductor (Beckmann α = {ALPHA}) — mean difference {diff:.1%}",
                names,
            ),
        ],
    )


if __name__ == "__main__":
    print(main())
