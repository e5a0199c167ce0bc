"""The rendering part of ``emscatter demo``: a quick BRDF export and a small spectral render.

:func:`run` builds a geometric-optics table of rough gold (Mitsuba's own η/k data), writes it
as an RGL ``.bsdf`` for Mitsuba's ``measured`` plugin, and renders one row of spheres —
through the emscatter plugin, through ``measured`` reading that file, and Mitsuba's own
``roughconductor`` for reference — in a spectral variant. The main demo calls it in a
subprocess (``python -m emscatter.render.demo OUT_DIR [--quick]``): Dr.Jit variants are per
process, and the radio demo's Sionna RT must not share one with Mitsuba's scalar variants.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from pathlib import Path

import numpy as np

__all__ = ["run", "main"]

ALPHA = 0.2  # Beckmann slope 2σ/ℓ of the demo surface
SIGMA, LENGTH = 0.1e-6, 1e-6  # [m]


def run(out_dir: Path, quick: bool) -> list[Path]:
    """Write ``gold_go.bsdf``, ``render_demo.png`` and ``render_demo.json`` (timings, image
    differences) into ``out_dir``; return their paths."""
    import mitsuba as mi

    from ..brdf import build_table
    from ..brdf.export_rgl import write_rgl
    from ..io import write_json
    from ..materials import metal
    from ..spectra import GaussianCorrelation
    from . import mitsuba as em_mi
    from . import scenes

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    mi.set_variant("llvm_ad_spectral")
    timings = {}
    t0 = time.perf_counter()
    wl = np.linspace(360e-9, 830e-9, 6 if quick else 24)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # validity notes are recorded in the table metadata
        table = build_table(
            GaussianCorrelation(SIGMA, LENGTH),
            metal("Au"),
            wl,
            method="go",
            resolution=(24, 48) if quick else (90, 180),
        )
    timings["table_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    bsdf_path = write_rgl(
        out_dir / "gold_go.bsdf",
        table,
        channels="spectral",
        n_theta_i=16 if quick else 32,
        n_samples=32 if quick else 64,
    )
    timings["rgl_export_s"] = time.perf_counter() - t0
    bsdfs = {
        "emscatter plugin": em_mi.bsdf_dict(table),
        "measured (.bsdf)": {"type": "measured", "filename": str(bsdf_path)},
        "roughconductor": {
            "type": "roughconductor",
            "distribution": "beckmann",
            "alpha": ALPHA,
            "material": "Au",
        },
    }
    t0 = time.perf_counter()
    scene = scenes.sphere_row(
        list(bsdfs.values()), width=160 if quick else 640, spp=16 if quick else 256
    )
    img = scenes.render(scene)
    timings["render_s"] = time.perf_counter() - t0
    png = scenes.save_rows(
        out_dir / "render_demo.png",
        [(img, f"rough gold (GO table, α = {ALPHA}), spectral render", list(bsdfs))],
    )
    report = write_json(
        out_dir / "render_demo.json",
        {
            "table": table.describe(),
            "variant": mi.variant(),
            "files": [bsdf_path.name, png.name],
            "timings": timings,
            "quick": bool(quick),
        },
    )
    return [bsdf_path, png, report]


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("out_dir", type=Path)
    p.add_argument("--quick", action="store_true")
    a = p.parse_args(argv)
    paths = run(a.out_dir, a.quick)
    print(json.dumps([str(x) for x in paths]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
