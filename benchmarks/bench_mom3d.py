"""Time per realization and memory of the 3-D PEC method of moments vs patch size (issue 19).

Run: ``PYTHONPATH=src python benchmarks/bench_mom3d.py [--sizes 2 4 6 8] [--ppw 8]``.
Prints one line per patch side (in wavelengths): unknowns, dense matrix bytes, assembly,
GMRES and total seconds, GMRES iterations and the energy ratio (1 for a PEC), for a Gaussian
surface kσ = 0.3, kℓ = 3 at θi = 30°.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from emscatter.solvers.mom3d import solve_realization
from emscatter.spectra import GaussianCorrelation
from emscatter.surfaces.generate import generate_surface


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--sizes", type=float, nargs="+", default=[2.0, 4.0, 6.0, 8.0])
    ap.add_argument("--ppw", type=float, default=8.0)
    args = ap.parse_args(argv)
    k = 2 * math.pi
    rough = GaussianCorrelation(0.3 / k, 3.0 / k)
    print("L/λ  unknowns  matrix_MiB  assemble_s  gmres_s  total_s  iterations  energy_h  energy_v")
    for size in args.sizes:
        n = int(math.ceil(size * args.ppw))
        dx = 1.0 / args.ppw
        h = generate_surface(rough, (n, n), dx, rng=1).heights
        t0 = time.perf_counter()
        r = solve_realization(h, dx, k, math.radians(30), np.array([0.3]), np.array([0.0]))
        total = time.perf_counter() - t0
        s = r["seconds"]
        print(
            f"{size:4g}  {r['unknowns']:8d}  {r['matrix_bytes'] / 2**20:10.0f}  "
            f"{s['assemble']:10.2f}  {s['solve']:7.2f}  {total:7.2f}  "
            f"{'/'.join(map(str, r['iterations'])):>10}  {r['energy'][0]:.4f}  {r['energy'][1]:.4f}"
        )


if __name__ == "__main__":
    main()
