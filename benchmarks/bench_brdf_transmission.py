"""Cost of the default 1 − T cap of build_table (issue 21): a GO table (90 × 90 × 180, 3
wavelengths) of gold (a conductor: T is not computed) and of glass (ε 2.25: the GO
transmittance per θi node, brdf/transmittance.py) with ``transmission="auto"`` (default)
against ``"off"``.

    .venv/bin/python benchmarks/bench_brdf_transmission.py [--repeat 3] [--n-theta 90]
    # → benchmarks/results/brdf_transmission.json
"""

from __future__ import annotations

import argparse
import statistics
import time
import warnings
from pathlib import Path

from emscatter.brdf import build_table
from emscatter.io import write_json
from emscatter.spectra import GaussianCorrelation

HERE = Path(__file__).resolve().parent
WL = [0.45e-6, 0.55e-6, 0.65e-6]
SURF = GaussianCorrelation(0.15e-6, 1.0e-6)  # Beckmann α = 0.3


def _time(material, transmission, n_theta, repeat):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            build_table(
                SURF,
                material,
                WL,
                method="go",
                resolution=(n_theta, 2 * n_theta),
                transmission=transmission,
            )
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main(argv=None) -> dict:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--n-theta", type=int, default=90)
    p.add_argument("--out", default=str(HERE / "results" / "brdf_transmission.json"))
    a = p.parse_args(argv)
    _time("Au", "off", 10, 1)  # warm-up (kernels, material data)
    res = {"n_theta": a.n_theta, "wavelengths_m": WL, "repeat": a.repeat, "seconds": {}}
    for name, mat in (("gold", "Au"), ("glass", 2.25)):
        for mode in ("auto", "off"):
            res["seconds"][f"{name}_{mode}"] = _time(mat, mode, a.n_theta, a.repeat)
    print(res)
    write_json(a.out, res)
    return res


if __name__ == "__main__":
    main()
