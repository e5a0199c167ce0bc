"""The radio part of the demo: the quick large-plate check (Sionna RT in this process).

``run(out_dir, quick)`` is what the main demo calls, in a subprocess of its own (Dr.Jit
variants are per process): ``python -m emscatter.radio.demo --out DIR [--quick]``. It writes
``radio_plate.csv`` and ``radio_plate.png`` (:mod:`emscatter.radio.plate`) and returns their
paths. Quick: 28 GHz, the smoother roughness, 2·10⁵ rays; full: 3.5/28/140 GHz, two
roughnesses, 10⁶ rays.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

__all__ = ["run", "main"]


def run(out_dir: Path, quick: bool) -> list[Path]:
    """Run the plate check and write its CSV + PNG under ``out_dir``; returns the paths."""
    from . import plate

    rough = plate.roughnesses()
    if quick:
        cases = {"sigma0.2mm_l5mm": plate.PlateCase(28e9, rough["sigma0.2mm_l5mm"])}
        samples = 200_000
    else:
        cases = {
            f"{name}@{f / 1e9:g}GHz": plate.PlateCase(f, surf)
            for f in plate.FREQUENCIES
            for name, surf in rough.items()
        }
        samples = 1_000_000
    rows = plate.check(cases, samples=samples)
    paths = plate.write_outputs(rows, Path(out_dir), stem="radio_plate")
    bad = [r for r in rows if not r["ok"]]
    for r in rows:
        print(
            f"{r['frequency_ghz']:6g} GHz {r['case']:<28} {r['kind']:<9} {r['pair']}: "
            f"Sionna − emscatter = {r['diff_db']:+.4f} dB (tolerance {r['tolerance_db']} dB)"
        )
    if bad:
        print(f"{len(bad)} comparison(s) outside tolerance", file=sys.stderr)
    return paths


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m emscatter.radio.demo", description=__doc__)
    p.add_argument("--out", type=Path, default=Path("out"), help="output folder")
    p.add_argument("--quick", action="store_true", help="one frequency, one roughness")
    a = p.parse_args(argv)
    run(a.out, a.quick)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
