"""Cross-check 1 — a large rough plate under Sionna RT with the emscatter material.

Sionna's specular (image) path against emscatter's coherent reflection × the free-space image
path (tolerance 0.01 dB), and Sionna's diffuse power against the bistatic radar equation
integrated over the plate with emscatter's σ⁰ (tolerance 0.2 dB; the Monte Carlo standard error
of Sionna's estimate is shown beside it), at 3.5, 28 and 140 GHz, two roughnesses, co- and
cross-polarizations. Writes ``plate_check.csv`` and ``plate_check.png``.

    python examples/radio/plate_check.py --out validation/radio      # ≈ 3 min on 2 cores
    python examples/radio/plate_check.py --quick --out /tmp/plate     # one case, seconds
"""

from __future__ import annotations

import argparse
from pathlib import Path

from emscatter.radio import plate


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--out", type=Path, default=Path("out/radio"), help="output folder")
    p.add_argument("--quick", action="store_true", help="28 GHz, one roughness, 2e5 rays")
    a = p.parse_args(argv)
    rough = plate.roughnesses()
    freqs = (28e9,) if a.quick else plate.FREQUENCIES
    names = list(rough)[:1] if a.quick else list(rough)
    cases = {
        f"{name}@{f / 1e9:g}GHz": plate.PlateCase(frequency=f, surface=rough[name], theta_deg=60.0)
        for f in freqs
        for name in names
    }
    rows = plate.check(cases, samples=200_000 if a.quick else 1_000_000)
    for path in plate.write_outputs(rows, a.out):
        print(path)
    worst = {k: max(abs(r["diff_db"]) for r in rows if r["kind"] == k) for k in plate.TOLERANCE_DB}
    print("largest |Sionna − emscatter|:", ", ".join(f"{k} {v:.4f} dB" for k, v in worst.items()))
    return 0 if all(r["ok"] for r in rows) else 1


if __name__ == "__main__":
    raise SystemExit(main())
