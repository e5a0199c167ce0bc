"""Surface measurement speed: H and D on a 1024² height map (target: under 1 s together).

    .venv/bin/python benchmarks/bench_measure.py   # → benchmarks/results/measure.json

Times are the median of 7 calls (after one warm-up call) on an exact fBm map (Stein 2002,
H = 0.7) made by emscatter's generator, and for the 1-D profile 2¹⁴ (Davies–Harte). The
target of issue 2 is "H and D measurement on 1024² in under 1 s": the default Hurst
estimator (the aliased log-periodogram) plus box counting, reported as
``hurst_and_box_counting_s``; every estimator and the full ``summarize(..., hurst=True)``
are timed beside it. The machine's load average at the start is saved with the numbers.
"""

from __future__ import annotations

import json
import os
import platform
import statistics
import sys
import time
from pathlib import Path

import numpy as np

from emscatter.spectra import FractionalBrownian
from emscatter.surfaces import measure as M
from emscatter.surfaces.generate import generate_surface

HERE = Path(__file__).resolve().parent
REPEAT = 7


def _time(fn) -> tuple[float, object]:
    out = fn()  # warm-up
    times = []
    for _ in range(REPEAT):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), out


def main() -> dict:
    res: dict = {
        "machine": {
            "nproc": os.cpu_count(),
            "python": sys.version.split()[0],
            "platform": platform.platform(),
            "numpy": np.__version__,
            "load_average_1min": os.getloadavg()[0],
        },
        "repeat": REPEAT,
        "statistic": "median wall time [s]",
        "cases": {},
    }
    cases = {
        "map_1024x1024": generate_surface(
            FractionalBrownian(0.7, 1.0, 1.0, 2), (1024, 1024), 1.0, rng=1
        ).heights,
        "profile_16384": generate_surface(
            FractionalBrownian(0.7, 1.0, 1.0, 1), 2**14, 1.0, rng=1
        ).heights,
    }
    for name, h in cases.items():
        row: dict = {"shape": list(h.shape), "true_hurst": 0.7}
        for m in M.HURST_METHODS:
            t, r = _time(lambda m=m, h=h: M.hurst_exponent(h, 1.0, m))
            row[f"hurst_{m}_s"] = t
            row[f"hurst_{m}"] = r.hurst
            row[f"hurst_{m}_stderr"] = r.stderr
        t, b = _time(lambda h=h: M.box_counting_dimension(h, 1.0))
        row["box_counting_s"] = t
        row["box_counting_dimension"] = b.dimension
        t, _ = _time(lambda h=h: (M.hurst_exponent(h, 1.0), M.box_counting_dimension(h, 1.0)))
        row["hurst_and_box_counting_s"] = t
        t, _ = _time(lambda h=h: M.summarize(h, 1.0, hurst=True))
        row["summarize_with_hurst_s"] = t
        row["target_s"] = 1.0
        row["meets_target"] = row["hurst_and_box_counting_s"] < 1.0
        res["cases"][name] = row
        print(
            f"{name:15s} H(periodogram)={row['hurst_periodogram']:.3f} "
            f"H(variogram)={row['hurst_variogram']:.3f} "
            f"D(box)={row['box_counting_dimension']:.3f}  "
            f"H+D {row['hurst_and_box_counting_s'] * 1e3:7.1f} ms  "
            f"all estimators + summary {row['summarize_with_hurst_s'] * 1e3:7.1f} ms"
        )
    out = HERE / "results" / "measure.json"
    out.parent.mkdir(exist_ok=True)
    out.write_text(json.dumps(res, indent=2) + "\n")
    print(f"wrote {out}")
    return res


if __name__ == "__main__":
    main()
