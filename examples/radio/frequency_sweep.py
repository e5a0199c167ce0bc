"""Cross-check 3 — one wall from 1 to 300 GHz: how much the specular path loses to roughness,
from emscatter (method chosen per frequency) against the Ament/Rayleigh and Boithias factors.
No ray tracer needed: the specular path of a wall is its coherent reflection (cross-check 1
shows that Sionna reproduces it within 0.01 dB). Writes ``frequency_sweep.csv`` and ``.png``.

    python examples/radio/frequency_sweep.py --out validation/radio
    python examples/radio/frequency_sweep.py --quick --out /tmp/sweep
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from emscatter.radio import sweep


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--out", type=Path, default=Path("out/radio"), help="output folder")
    p.add_argument("--quick", action="store_true", help="12 frequencies, one angle")
    a = p.parse_args(argv)
    freqs = np.geomspace(1e9, 300e9, 12 if a.quick else 60)
    angles = (30.0,) if a.quick else (30.0, 70.0)
    wall = sweep.DEFAULT_WALL()
    results = [sweep.sweep(wall, "concrete", theta_deg=t, frequencies=freqs) for t in angles]
    for path in sweep.write_outputs(results, a.out):
        print(path)
    r = results[0]
    for f, m, e, am, bo in zip(r["frequency_ghz"], r["method"], r["emscatter_h_db"],
                               r["ament_db"], r["boithias_db"], strict=True):  # fmt: skip
        print(f"{f:8.2f} GHz  {m:<4} emscatter h {e:8.3f} dB  Ament {am:8.3f}  Boithias {bo:8.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
