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

Dielectric (``--eps 4+0.5j 15+2j --sizes 2 3 4 --accel dense``): the dense Müller solve, at
the grid density ``mom3d.bistatic`` uses, 8 points per wavelength
*inside* the medium (λ₀/Re√ε: 16 points/λ₀ for ε = 4 + 0.5i, 31 for 15 + 2i), four unknowns
per node, complex128 ``(4N)²`` matrix, one realization (same surface, θi = 30°), both
polarizations. Rows over ``--max-gib`` (default 6) are not run: memory exact, time
extrapolated as ``(4N)²`` from the largest row run (``est``). Shared 2-core machine, load
average 8–10 (the 4λ rows ran at ≈ 25 % of a core; an idle machine is ~2–4× faster)::

    eps     L/λ pts/λ0 nodes unknowns GiB  RSS_MiB asm_s  gmres_s total_s its   R_h    R_v
    4+0.5i   2  16.0   1089   4356  0.28    489    8.2     5.3    13.8 21/21 0.1432 0.0899
    4+0.5i   3  16.0   2401   9604  1.37   1608   20.2    20.6    41.0 24/23 0.1505 0.0811
    4+0.5i   4  16.0   4225  16900  4.26   4571   78.0   136.7   215.2 25/24 0.1452 0.0828
    15+2i    2  31.1   3969  15876  3.76   4041   59.0   121.4   180.9 28/29 0.3857 0.2914
    15+2i    3  31.1   8836  35344 18.61      —   292e    602e    894e  (not run: memory)
    15+2i    4  31.1  15625  62500 58.21      —   914e   1881e   2796e  (not run: memory)

(``e``: extrapolated.) Memory is the wall: 4λ at ε = 15 + 2i needs a 58 GiB matrix (29 GiB
in complex64); the same 4λ patch as a PEC (8 points/λ₀) is a 64 MiB dense matrix.
Commands: ``--eps 4+0.5j --sizes 2 3 4 --accel dense`` and ``--eps 15+2j --sizes 2 3 4
--max-gib 5 --accel dense`` (each < 10 min on the loaded machine).

Dielectric SMCG (``--accel smcg``, or ``auto`` above 256 nodes: strong pairs within
r_d = 0.5λ₀ sparse in complex64, both media's far kernels by FFT, Taylor order 3,
:mod:`emscatter.solvers.mom3d.dielectric_smcg`), same surface and grid; ``s/it`` GMRES seconds
per iteration. Shared 2-core machine, load average 10–11 (7 other workers)::

    eps     L/λ pts/λ0 nodes unknowns GiB  RSS_MiB asm_s gmres_s s/it total_s its   R_h    R_v
    4+0.5i   2  16.0   1089   4356  0.05    187    1.3     6.8  0.16     8.5 21/21 0.1432 0.0899
    4+0.5i   4  16.0   4225  16900  0.15    317    6.4    56.8  1.00    63.6 29/28 0.1452 0.0828
    4+0.5i   6  16.0   9409  37636  0.34    624    9.2   146.3  2.32   156.2 32/31 0.1425 0.0814
    4+0.5i   8  16.0  16641  66564  0.61   1062   11.8   180.0  2.69   193.6 34/33 0.1414 0.0798

(R equal to the dense rows' to the digits shown at 2λ and 4λ; the dense 6λ and 8λ matrices
would be 21 and 66 GiB.) Under this load the far part (FFTs) is ≈ 3/4 of a product; the 12
spectral sums are since folded into 6 (half the inverse FFTs), not in these rows. Command:
``--eps 4+0.5j --sizes 2 4 6 8 --accel smcg`` (6.5 min on the loaded machine).
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


def _peak_rss_mib() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # KiB on Linux


def dielectric(eps_list, sizes, ppw: float, max_gib: float, accel: str = "dense",
               near_radius=None, order: int = 3) -> None:  # fmt: skip
    """The Müller solve (:mod:`emscatter.solvers.mom3d.dielectric`, dense, or the SMCG
    product of :mod:`emscatter.solvers.mom3d.dielectric_smcg`) at the grid density
    ``bistatic`` uses: ``ppw`` nodes per wavelength inside the medium, ``λ₀ / Re√ε``; one
    realization of the same Gaussian surface, both incident polarizations. Dense rows whose
    complex128 ``(4N)²`` matrix is over ``max_gib`` are not run: their memory is exact, their
    time extrapolated (marked ``est``) from the largest row run for that ε — assembly and each
    GMRES matvec scale as ``(4N)²``, iterations taken as that row's. ``s/it``: GMRES seconds
    per iteration (both polarizations' iterations together)."""
    from emscatter.solvers.mom3d.dielectric_model import (
        dielectric_accel,
        solve_dielectric_realization,
    )

    k = 2 * math.pi
    rough = GaussianCorrelation(0.3 / k, 3.0 / k)
    print(
        "eps        L/λ  accel  pts/λ0  nodes  unknowns  matrix_GiB  peak_RSS_MiB  assemble_s  "
        "gmres_s  s/it  total_s  iterations  R_h     R_v"
    )
    for eps in eps_list:
        lam = 1.0 / max(1.0, np.sqrt(eps).real)
        dx = lam / ppw
        ref = None
        for size in sorted(sizes):
            n = int(math.ceil(size / lam * ppw))
            mode = dielectric_accel(accel, n * n)
            unknowns = 4 * n * n
            gib = unknowns**2 * 16 / 2**30
            head = f"{eps!s:>9}  {size:3g}  {mode:>5}  {ppw / lam:6.1f}  {n * n:5d}  {unknowns:8d}"
            if mode == "dense" and gib > max_gib:
                head += f"  {gib:10.2f}"
                if ref is None:
                    print(f"{head}  (over --max-gib {max_gib:g}: not run, no row to scale)")
                    continue
                f = (unknowns / ref["unknowns"]) ** 2
                a, g = ref["seconds"]["assemble"] * f, ref["seconds"]["solve"] * f
                its = "/".join(map(str, ref["iterations"]))
                print(f"{head}  {'—':>12}  {a:8.0f}est  {g:5.0f}est  {'':>5} {a + g:5.0f}est  "
                      f"{its:>10}  (over --max-gib {max_gib:g}: not run)", flush=True)  # fmt: skip
                continue
            h = generate_surface(rough, (n, n), dx, rng=1).heights
            t0 = time.perf_counter()
            r = solve_dielectric_realization(h, dx, k, eps, math.radians(30), np.array([0.3]),
                                             np.array([0.0]), accel=mode,
                                             near_radius=near_radius,
                                             taylor_order=order)  # fmt: skip
            total = time.perf_counter() - t0
            s = r["seconds"]
            if mode == "dense":
                ref = r
            per_it = s["solve"] / max(1, sum(r["iterations"]))
            print(
                f"{head}  {r['matrix_bytes'] / 2**30:10.2f}  {_peak_rss_mib():12.0f}  "
                f"{s['assemble']:10.2f}  {s['solve']:7.2f}  {per_it:5.2f}  {total:7.2f}  "
                f"{'/'.join(map(str, r['iterations'])):>10}  "
                f"{r['reflectivity'][0]:.4f}  {r['reflectivity'][1]:.4f}",
                flush=True,
            )


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--sizes", type=float, nargs="+", default=[2.0, 4.0, 6.0, 8.0])
    ap.add_argument("--ppw", type=float, default=8.0)
    ap.add_argument("--accel", choices=("auto", "dense", "smcg"), default="auto")
    ap.add_argument("--near-radius", type=float, default=None, help="SMCG r_d [wavelengths]")
    ap.add_argument("--order", type=int, default=3, help="SMCG Taylor order")
    ap.add_argument(
        "--eps", type=complex, nargs="+", default=None,
        help="dielectric rows (Müller solve, --accel dense|smcg|auto) for these ε, e.g. 4+0.5j",
    )  # fmt: skip
    ap.add_argument(
        "--max-gib", type=float, default=6.0,
        help="dielectric: run rows up to this matrix size [GiB], extrapolate the rest",
    )  # fmt: skip
    args = ap.parse_args(argv)
    print("load average (1, 5, 15 min): {:.2f} {:.2f} {:.2f}".format(*os.getloadavg()))
    if args.eps:
        dielectric(args.eps, args.sizes, args.ppw, args.max_gib, args.accel, args.near_radius,
                   args.order)  # fmt: skip
        return
    k = 2 * math.pi
    rough = GaussianCorrelation(0.3 / k, 3.0 / k)
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
        rss = _peak_rss_mib()
        print(
            f"{size:4g}  {r['accel']:>5}  {r['unknowns']:8d}  {r['matrix_bytes'] / 2**20:10.0f}  "
            f"{rss:12.0f}  {s['assemble']:10.2f}  {s['solve']:7.2f}  {total:7.2f}  "
            f"{'/'.join(map(str, r['iterations'])):>10}  {e[0]:.4f}  {e[1]:.4f}",
            flush=True,
        )


if __name__ == "__main__":
    main()
