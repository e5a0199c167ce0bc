"""Reciprocity of one realization of the 3-D method of moments vs points per wavelength
(issue 19): the reaction ``⟨B, A⟩ = ∫(E_B·J_A − H_B·M_A) dS`` of beam B (incident from
``−k_s``) on the currents of beam A (from ``k_i``) equals ``⟨A, B⟩`` (Lorentz; the tapered-beam
form of ``σ_qp(k_i → k_s) = σ_pq(−k_s → −k_i)``), for all four pairs of polarizations.

What is measured (as in tests/test_mom3d.py and tests/test_mom3d_dielectric.py): the reaction
is an *amplitude*; ``worst`` = ``max|R_AB − R_BA| / max|R_AB|`` over the four pairs, stated
also as the power bound ``20 log10(1 + worst)`` dB; ``hv_db``, ``vh_db`` =
``20 log10(|R_AB| / |R_BA|)`` of the cross-polarized pairs (a power ratio in dB);
``copol_db`` the largest of the two co-polarized pairs.

Surface (the same at every sampling, :func:`surface`): Gaussian kσ = 0.3, kℓ = 3; θi = 30°,
θs = 45°, φs = 70°; PEC on a 4λ patch, ε = 3 on a 2λ patch (points per free-space λ;
inside ε = 3 it is ``ppw/√3``).

Run: PYTHONPATH=src python validation/mom3d/reciprocity.py [--pec 6 8 11] [--pec-sizes 6 8]
     [--diel 8 11 14]   (≈ 3 min on 2 loaded cores)
Writes reciprocity.md here.
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np

from emscatter.io import atomic_path
from emscatter.solvers.mom3d import solve_realization
from emscatter.solvers.mom3d.dielectric_model import solve_dielectric_realization

HERE = Path(__file__).resolve().parent
K = 2 * math.pi
TI, TS, PS = math.radians(30), math.radians(45), math.radians(70)


def reactions(x, y, magnetic):
    """``[pol of y's incident field, pol of x's currents]`` reactions (2, 2)."""
    out = np.empty((2, 2), complex)
    for qi, q in enumerate("hv"):
        e, h = y["beam"].fields(x["points"], q)
        for p in range(2):
            out[qi, p] = np.sum(e * x["u" if magnetic else "current"][p])
            if magnetic:
                out[qi, p] -= np.sum(h * x["w"][p])
    return out


def surface(n, dx, modes=400, seed=5):
    """The same Gaussian surface (kσ = 0.3, kℓ = 3) at any sampling: a sum of ``modes``
    random cosines whose wavevectors are drawn from the Gaussian spectrum of
    ``C(r) = σ² e^{−r²/ℓ²}`` (normal, ``√2/ℓ`` per axis) [m]."""
    sigma, ell = 0.3 / K, 3 / K
    rng = np.random.default_rng(seed)
    kv = rng.normal(scale=math.sqrt(2) / ell, size=(modes, 2))
    ph = rng.uniform(0, 2 * math.pi, modes)
    xs = (np.arange(n) - (n - 1) / 2) * dx
    x, y = np.meshgrid(xs, xs)
    arg = x[..., None] * kv[:, 0] + y[..., None] * kv[:, 1] + ph
    return sigma * math.sqrt(2.0 / modes) * np.cos(arg).sum(axis=-1)


def measure(eps, ppw, length):
    dx = 1.0 / ppw
    n = int(round(length * ppw))
    h = surface(n, dx)
    t0 = time.perf_counter()
    if eps == "pec":
        a = solve_realization(h, dx, K, TI, [TS], [PS], accel="dense")
        b = solve_realization(h, dx, K, TS, [TI], [math.pi], phi_i=PS + math.pi, accel="dense")
    else:
        a = solve_dielectric_realization(h, dx, K, eps, TI, [TS], [PS])
        b = solve_dielectric_realization(h, dx, K, eps, TS, [TI], [math.pi], phi_i=PS + math.pi)
    mag = eps != "pec"
    rab, rba = reactions(a, b, mag), reactions(b, a, mag).T
    worst = float(np.max(np.abs(rab - rba)) / np.max(np.abs(rab)))
    ratio_db = 20 * np.log10(np.abs(rab) / np.abs(rba))
    return {
        "eps": str(eps), "ppw": ppw, "length": length,
        "unknowns": (2 if eps == "pec" else 4) * n * n,
        "worst_pct": 100 * worst, "worst_db": 20 * math.log10(1 + worst),
        "hv_db": float(ratio_db[0, 1]), "vh_db": float(ratio_db[1, 0]),
        "copol_db": float(np.max(np.abs(np.diag(ratio_db)))),
        "seconds": time.perf_counter() - t0,
    }  # fmt: skip


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--pec", type=float, nargs="*", default=[6.0, 8.0, 11.0])
    ap.add_argument("--diel", type=float, nargs="*", default=[8.0, 11.0, 14.0])
    ap.add_argument("--pec-sizes", type=float, nargs="*", default=[6.0, 8.0],
                    help="PEC patch sides [λ] at 8 points/λ (truncation)")  # fmt: skip
    ap.add_argument("--out", type=Path, default=HERE)
    a = ap.parse_args(argv)
    rows = []
    for ppw in a.pec:
        rows.append(measure("pec", ppw, 4.0))
        print(rows[-1], flush=True)
    for size in a.pec_sizes:
        rows.append(measure("pec", 8.0, size))
        print(rows[-1], flush=True)
    for ppw in a.diel:
        rows.append(measure(3.0, ppw, 2.0))
        print(rows[-1], flush=True)
    lines = [
        "# Reciprocity of one mom3d realization vs points per wavelength",
        "",
        "Reactions are amplitudes; `worst` = max |R_AB − R_BA| / max |R_AB| over the four "
        "pol pairs (and the power bound 20 log10(1 + worst)); hv, vh, co-pol: "
        "20 log10 |R_AB/R_BA| (power ratio). Gaussian kσ = 0.3, kℓ = 3, θi = 30°, "
        "θs = 45°, φs = 70°. Made by `reciprocity.py`.",
        "",
        "| medium | patch λ | points/λ | unknowns | worst % | worst dB | hv dB | vh dB | "
        "co-pol dB | s |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['eps']} | {r['length']:g} | {r['ppw']:g} | {r['unknowns']} | "
            f"{r['worst_pct']:.2f} | {r['worst_db']:.3f} | {r['hv_db']:+.3f} | "
            f"{r['vh_db']:+.3f} | {r['copol_db']:.3f} | {r['seconds']:.0f} |"
        )
    with atomic_path(a.out / "reciprocity.md") as tmp:
        Path(tmp).write_text("\n".join(lines) + "\n", encoding="utf-8")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
