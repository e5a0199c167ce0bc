"""The seed's non-Gaussian slope distributions (Figs. 3.13–3.17) next to Beckmann: the same
Cook–Torrance model on copper (Mitsuba's η/k data) with only the distribution term changed —
uniform (a = 0.1), exponential (λ = 0.5), Rayleigh (σ = 0.1), Cauchy (a = 0.1), Simpson
(a = 1) — tabulated with ``emscatter.brdf.analytic.table_from_function`` and rendered through
the emscatter Mitsuba plugin.

    python examples/render/slope_distributions.py   # → docs/figures/render_distributions.png
    python examples/render/slope_distributions.py --quick   # tiny version (the tests)
"""

from __future__ import annotations

from pathlib import Path

import mitsuba as mi
import numpy as np

from emscatter.brdf.analytic import cook_torrance, table_from_function
from emscatter.brdf.analytic.distributions import Beckmann, SeedDistribution
from emscatter.materials import metal
from emscatter.render import mitsuba as em_mi
from emscatter.render import scenes
from emscatter.render.cli_options import example_settings

OUT = Path(__file__).resolve().parents[2] / "docs" / "figures" / "render_distributions.png"
DISTRIBUTIONS = [
    ("Beckmann m = 0.1", Beckmann(0.1)),
    ("uniform a = 0.1", SeedDistribution("uniform", a=0.1)),
    ("exponential λ = 0.5", SeedDistribution("exponential", lam=0.5)),
    ("Rayleigh σ = 0.1", SeedDistribution("rayleigh", sigma=0.1)),
    ("Cauchy a = 0.1", SeedDistribution("cauchy", a=0.1)),
    ("Simpson a = 1", SeedDistribution("simpson", a=1.0)),
]


def main(argv=None) -> Path:
    s = example_settings(__doc__.splitlines()[0], OUT, argv)
    mi.set_variant("llvm_ad_rgb")
    copper = metal("Cu")
    wl = np.linspace(420e-9, 680e-9, min(s.n_wavelengths, 7))
    chosen = DISTRIBUTIONS[:3] if s.quick else DISTRIBUTIONS
    bsdfs = []
    for _, dist in chosen:

        def fr(wi, wo, lam, dist=dist):
            return cook_torrance(wi, wo, dist, eps=copper.eps(wavelength=lam).item())

        table = table_from_function(fr, wl, resolution=s.resolution)
        bsdfs.append(em_mi.bsdf_dict(table))
    img = scenes.render(scenes.sphere_row(bsdfs, width=s.width, spp=s.spp))
    title = "Cook–Torrance on copper, the seed's slope distributions (eqs. 3.8–3.12)"
    return scenes.save_rows(s.out, [(img, title, [name for name, _ in chosen])])


if __name__ == "__main__":
    print(main())
