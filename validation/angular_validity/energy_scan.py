"""Energy against the per-angle validity checks: does "valid" imply 0 ≤ e ≤ 1?

For each approximation (spm, go, po) on 2-D Gaussian and exponential surfaces over a grid of
(kσ, kℓ), three permittivities (PEC, ε = 3, ε = 17 + 2i) and θi = 0–89°, the emissivity
e = 1 − r_coh − r_incoh (:func:`emscatter.emissivity`, tol 1e-3) is computed and compared
with the method's validity report at that angle (``check_validity(..., eps, theta_i)``:
roughness checks and ``angle_valid``). A violation is e < −0.01 or e > 1.01 (the coherent +
incoherent reflectivity leaving [0, 1] by more than the quadrature tolerance).

Run: PYTHONPATH=src python validation/angular_validity/energy_scan.py   (46 min on the loaded
2-core machine); ``--reclassify`` re-evaluates only the validity columns with the current
criteria (seconds). Writes energy_scan.csv and energy_scan_summary.md here.
"""

from __future__ import annotations

import csv
import math
import platform
import sys
import time
import warnings
from pathlib import Path

import numpy as np

import emscatter as em
from emscatter import solvers
from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation

HERE = Path(__file__).resolve().parent
K = 2 * math.pi
THETA = np.radians([0.0, 20.0, 40.0, 60.0, 70.0, 75.0, 80.0, 85.0, 88.0])
KS = (0.05, 0.2, 0.3, 0.6, 1.0, 2.0, 3.5, 6.0)
KL = (0.5, 1.0, 3.0, 6.0, 12.0, 25.0)
EPS = ("pec", 3.0, 17 + 2j)
TOL = 0.01


def scan() -> list[dict]:
    rows = []
    for cls in (GaussianCorrelation, ExponentialCorrelation):
        for ks in KS:
            for kl in KL:
                rough = cls(ks / K, kl / K)
                for eps in EPS:
                    for method in ("spm", "go", "po"):
                        with warnings.catch_warnings():
                            warnings.simplefilter("ignore")
                            e = em.emissivity(
                                rough, eps, wavelength=1.0, theta_i=THETA, method=method,
                                tol=1e-3, out_of_range="ignore",
                            )  # fmt: skip
                        for it, th in enumerate(THETA):
                            eh, ev = (float(e.emissivity[p, it]) for p in (0, 1))
                            rows.append({
                                "correlation": rough.name, "k_sigma": ks, "k_l": kl,
                                "eps": str(eps), "method": method,
                                "theta_deg": round(math.degrees(th), 3), "e_h": eh, "e_v": ev,
                            })  # fmt: skip
    return rows


def classify(rows: list[dict]) -> list[dict]:
    """Each row's validity (roughness checks and the angle's) with the current criteria."""
    cls = {"gaussian": GaussianCorrelation, "exponential": ExponentialCorrelation}
    eps_of = {str(e): e for e in EPS}
    reports = {}
    for r in rows:
        key = (r["correlation"], float(r["k_sigma"]), float(r["k_l"]), r["eps"], r["method"])
        if key not in reports:
            rough = cls[key[0]](key[1] / K, key[2] / K)
            mod = solvers.get(key[4])
            reports[key] = mod.check_validity(rough, K, eps=eps_of[key[3]], theta_i=THETA)
        rep = reports[key]
        it = int(np.argmin(np.abs(np.degrees(THETA) - float(r["theta_deg"]))))
        eh, ev = float(r["e_h"]), float(r["e_v"])
        r["valid"] = bool(rep["roughness_excess"] == 0 and rep["angle_valid"][it])
        r["angle_valid"] = bool(rep["angle_valid"][it])
        r["energy_violation"] = min(eh, ev) < -TOL or max(eh, ev) > 1 + TOL
    return rows


def main() -> None:
    t0 = time.perf_counter()
    if "--reclassify" in sys.argv:  # new criteria, same emissivities: no solver run
        with open(HERE / "energy_scan.csv", newline="") as fh:
            rows = list(csv.DictReader(fh))
        seconds = None
    else:
        rows = scan()
        seconds = time.perf_counter() - t0
    rows = classify(rows)
    with open(HERE / "energy_scan.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    lines = [
        "| method | (roughness, ε, θi) reported valid | of those: energy violated | "
        "violations flagged invalid | worst e among valid |",
        "|---|---|---|---|---|",
    ]
    for m in ("spm", "go", "po"):
        mr = [r for r in rows if r["method"] == m]
        v = [r for r in mr if r["valid"]]
        vb = [r for r in v if r["energy_violation"]]
        bad = [r for r in mr if r["energy_violation"]]
        worst = min((min(float(r["e_h"]), float(r["e_v"])) for r in v), default=math.nan)
        lines.append(
            f"| {m} | {len(v)} of {len(mr)} | {len(vb)} | {len(bad) - len(vb)} of {len(bad)} "
            f"| {worst:.3f} |"
        )
    md = "\n".join(lines) + "\n"
    if seconds is not None:
        md += (
            f"\nScan run time {seconds:.0f} s on {platform.node()} "
            f"(Python {sys.version.split()[0]}, numpy {np.__version__}).\n"
        )
    (HERE / "energy_scan_summary.md").write_text(md)
    print(md)
    for r in rows:
        if r["valid"] and r["energy_violation"]:
            print("VALID BUT VIOLATED", r)


if __name__ == "__main__":
    main()
