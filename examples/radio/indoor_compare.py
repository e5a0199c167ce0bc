"""Cross-check 2 — indoor scenes: Sionna's constant-S Lambertian materials against emscatter
materials (and emscatter without roughness), at 3.5, 28 and 140 GHz.

Per receiver: path gain and RMS delay spread; per scene: radio maps and their differences.
Writes ``indoor_receivers.csv``, ``indoor_summary.csv``, ``indoor_maps_<scene>.png`` and
``indoor_vs_frequency.png`` (how much roughness changes path gain and delay spread against
frequency).

    python examples/radio/indoor_compare.py --out validation/radio    # 3 scenes, ≈ 15 min
    python examples/radio/indoor_compare.py --quick --out /tmp/indoor # room, 2 frequencies
"""

from __future__ import annotations

import argparse
from pathlib import Path

from emscatter.radio import indoor
from emscatter.radio.tables import TableOptions


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--out", type=Path, default=Path("out/radio"), help="output folder")
    p.add_argument("--quick", action="store_true", help="room only, 3.5 and 140 GHz, few rays")
    a = p.parse_args(argv)
    if a.quick:
        result = indoor.compare(
            ("room",), (3.5e9, 140e9), samples=20_000, cell_size=0.5, max_depth=2,
            table_options=TableOptions(n_cos=65, n_cos_spm=9, n_theta=16, n_alpha=13, n_s=32),
        )  # fmt: skip
    else:
        # Sionna's box is ITU metal (1–100 GHz): 140 GHz is the documented extrapolation,
        # recorded per row (extrapolated_media) and in indoor_run.json.
        result = indoor.compare(
            ("room", "floor_wall", "box"), indoor.FREQUENCIES, samples=1_000_000, cell_size=0.1,
            extrapolate=True,
        )  # fmt: skip
    for path in indoor.write_outputs(result, a.out):
        print(path)
    for s in indoor.summarize(result["rows"]):
        print(
            f"{s['scene']:<10} {s['frequency_ghz']:6g} GHz  rough − flat: median |ΔPG| "
            f"{s['median_abs_dpg_vs_flat_db']:.2f} dB, |Δτ| {s['median_abs_dds_vs_flat_ns']:.2f} ns"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
