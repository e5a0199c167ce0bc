"""Time per realization and memory of the 3-D PEC method of moments vs patch size (issue 19).

Run: ``PYTHONPATH=src python benchmarks/bench_mom3d.py [--sizes 2 4 6 8] [--ppw 8]
[--accel dense|smcg|auto] [--near-radius 2.5] [--order 3]``.
Prints the load average, then one line per patch side (in wavelengths): the product used
(dense matrix or SMCG, :mod:`emscatter.solvers.mom3d.smcg`), unknowns, matrix bytes (SMCG:
sparse strong part plus kernel spectra), the process's peak resident memory so far (sizes run
in increasing order, so it is the peak of the largest so far), assembly, GMRES and total
seconds, GMRES iterations and the energy ratio (1 for a PEC), for a Gaussian surface
kσ = 0.3, kℓ = 3 at θi = 30°, both incident polarizations, through the public
``emscatter.solvers.mom3d.solve_realization`` (one realization of ``mom3d.bistatic``).

Measured on the shared 2-core development machine (load average ≈ 4, other jobs running;
rerun on an idle machine for final numbers), 8 points/λ, SMCG defaults r_d = 2.5λ, order 3::

    L/λ  accel  unknowns  matrix_MiB  peak_RSS_MiB  assemble_s  gmres_s  total_s  iterations
      8  dense      8192         512           690        2.59     1.22     4.31         7/7
      8   smcg      8192         178           363        3.28     3.39     7.37         7/7
     16   smcg     32768         826          1264        9.37    20.06    41.48         8/8
     32   smcg    131072        3540          4887       28.62    45.03   178.36         9/8

(energy 0.9925/0.9945 at 8λ by both products, 0.9940/0.9953 at 16λ, 0.9955/0.9957 at 32λ).
At 32λ the far field on the hemisphere quadrature was 105 of the 178 s (direct ``O(N · n_mu²)``
sum). With the fast sum of :mod:`emscatter.solvers.mom3d.gridsum` (Taylor in height +
gridding NUFFT, error ≤ 1e-7 Σ|u|ΔA) the far field takes ≈ 1 s at 16λ and ≈ 2 s at 32λ
(loaded machine, load ≈ 3.5, other runs of this session beside it)::

     16   smcg     32768         826          1253        7.39    22.14    30.19         8/8
     32   smcg    131072        3540          4922       52.36   106.18   160.25         9/8

(energies unchanged: 0.9940/0.9953, 0.9955/0.9957; the 32λ assembly and GMRES times here are
inflated by the load, not by the far field). 16λ dense would need an 8 GiB matrix.
Commands: ``--sizes 8 16 --accel
smcg``, ``--sizes 32 --accel smcg`` and ``--sizes 8 --accel dense``.
"""

from __future__ import annotations

import argparse
import math
import os
import resource
import time

import numpy as np

from emscatter.solvers.mom3d import solve_realization
from emscatter.spectra import GaussianCorrelation
from emscatter.surfaces.generate import generate_surface


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--sizes", type=float, nargs="+", default=[2.0, 4.0, 6.0, 8.0])
    ap.add_argument("--ppw", type=float, default=8.0)
    ap.add_argument("--accel", choices=("auto", "dense", "smcg"), default="auto")
    ap.add_argument("--near-radius", type=float, default=None, help="SMCG r_d [wavelengths]")
    ap.add_argument("--order", type=int, default=3, help="SMCG Taylor order")
    args = ap.parse_args(argv)
    k = 2 * math.pi
    rough = GaussianCorrelation(0.3 / k, 3.0 / k)
    print("load average (1, 5, 15 min): {:.2f} {:.2f} {:.2f}".format(*os.getloadavg()))
    print(
        "L/λ  accel  unknowns  matrix_MiB  peak_RSS_MiB  assemble_s  gmres_s  total_s  "
        "iterations  energy_h  energy_v"
    )
    for size in sorted(args.sizes):
        n = int(math.ceil(size * args.ppw))
        dx = 1.0 / args.ppw
        h = generate_surface(rough, (n, n), dx, rng=1).heights
        t0 = time.perf_counter()
        r = solve_realization(h, dx, k, math.radians(30), np.array([0.3]), np.array([0.0]),
                              accel=args.accel, near_radius=args.near_radius,
                              taylor_order=args.order)  # fmt: skip
        total = time.perf_counter() - t0
        s, e = r["seconds"], r["energy"]
        rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # KiB on Linux
        print(
            f"{size:4g}  {r['accel']:>5}  {r['unknowns']:8d}  {r['matrix_bytes'] / 2**20:10.0f}  "
            f"{rss:12.0f}  {s['assemble']:10.2f}  {s['solve']:7.2f}  {total:7.2f}  "
            f"{'/'.join(map(str, r['iterations'])):>10}  {e[0]:.4f}  {e[1]:.4f}",
            flush=True,
        )


if __name__ == "__main__":
    main()
