"""Rows of spheres as in the seed's Fig. 2.7: the rms height σ varied at a fixed correlation
length ℓ, then ℓ varied at a fixed σ — Kirchhoff (geometric optics) tables of aluminium
(Mitsuba's own η/k data), rendered through the emscatter Mitsuba plugin.

    python examples/render/roughness_rows.py            # → docs/figures/render_roughness.png
    python examples/render/roughness_rows.py --quick    # tiny version (what the tests run)

The seed's smoothest spheres (σ = 0.1 at τ = 20, τ = 100 at σ = 1) have lobes a fraction of a
degree wide, finer than the 1° nodes of a default table; these rows stop at slope 2σ/ℓ = 0.04.
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

OUT = Path(__file__).resolve().parents[2] / "docs" / "figures" / "render_roughness.png"
UM = 1e-6
SIGMAS = [2.5, 1.5, 1.0, 0.6, 0.4]  # [µm] at ℓ = 20 µm
LENGTHS = [8.0, 12.0, 20.0, 30.0, 50.0]  # [µm] at σ = 1 µm


def row(surfaces, settings, wavelengths):
    bsdfs = []
    for rough in surfaces:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the validity notes are in the table metadata
            table = build_table(
                rough, metal("Al"), wavelengths, method="go", resolution=settings.resolution
            )
        bsdfs.append(em_mi.bsdf_dict(table))
    scene = scenes.sphere_row(bsdfs, width=settings.width, spp=settings.spp)
    return scenes.render(scene)


def main(argv=None) -> Path:
    s = example_settings(__doc__.splitlines()[0], OUT, argv)
    mi.set_variant("llvm_ad_rgb")
    wl = np.linspace(420e-9, 680e-9, min(s.n_wavelengths, 7))
    sig = SIGMAS[:3] if s.quick else SIGMAS
    lens = LENGTHS[:3] if s.quick else LENGTHS
    a = row([GaussianCorrelation(x * UM, 20 * UM) for x in sig], s, wl)
    b = row([GaussianCorrelation(1 * UM, x * UM) for x in lens], s, wl)
    return scenes.save_rows(
        s.out,
        [
            (
                a,
                "(a) ℓ = 20 µm, σ varied — Kirchhoff GO, aluminium",
                [f"σ = {x:g} µm" for x in sig],
            ),
            (b, "(b) σ = 1 µm, ℓ varied", [f"ℓ = {x:g} µm" for x in lens]),
        ],
    )


if __name__ == "__main__":
    print(main())
