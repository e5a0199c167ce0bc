"""Renders for tests/test_render_htsg_po.py in a fresh interpreter (Dr.Jit variants are per
process): ``python tests/htsg_render_worker.py WIDTH SPP`` runs
``validation/brdf/render_htsg_po.measure`` in ``llvm_ad_rgb`` and prints its numbers (table
differences in dB, image and region differences against the PO sphere) as JSON on its last
line."""

from __future__ import annotations

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "validation" / "brdf"))


def main(width: int, spp: int) -> None:
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    import render_htsg_po as R

    r = R.measure(width, spp)
    keys = ("db_60", "db_80", "image_difference", "region_difference", "resolution")
    print(json.dumps({k: r[k] for k in keys}))


if __name__ == "__main__":
    main(int(sys.argv[1]), int(sys.argv[2]))
