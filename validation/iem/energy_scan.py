"""Energy of the IEM: emissivity e = 1 − r_coh − r_incoh over a grid of roughness, angle and
permittivity, by the shared hemispherical quadrature (api.emissivity, tol = 1e-3).

    PYTHONPATH=src python validation/iem/energy_scan.py   # → validation/iem/energy_scan.csv
    PYTHONPATH=src python validation/iem/energy_scan.py --pec  # → energy_scan_pec.csv

``--pec``: the perfect conductor only, at the conductor angles (θ ≤ 45°, the angle limit of
``iem.check_validity`` for conductors), with the model as it is now (bistatic multiple-scattering
hv included; ``energy_scan.csv`` predates that term and is an upper bound on e there).

A perfect conductor must give e = 0 and any medium e ∈ [0, 1]; the table shows where the
single-scattering model breaks energy (mostly v near grazing, and the exponential correlation's
deficit shared with physical optics) and is what the angle limit of ``iem.check_validity`` is
set from (validation/iem/README.md).
"""

from __future__ import annotations

import csv
import math
import warnings
from pathlib import Path

import numpy as np

from emscatter import api
from emscatter.io import atomic_path
from emscatter.solvers.iem import model as iem
from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation

K = 2 * math.pi
THETA = np.radians([0.0, 20.0, 40.0, 50.0, 60.0, 70.0, 80.0])


OUT = Path(__file__).with_name("energy_scan.csv")
OUT_PEC = Path(__file__).with_name("energy_scan_pec.csv")
THETA_PEC = np.radians([0.0, 20.0, 30.0, 45.0])


def main(out=OUT, *, media=("pec", 3.0, 15 + 2j), theta=THETA):
    rows = []
    for cls in (GaussianCorrelation, ExponentialCorrelation):
        for ks in (0.2, 0.5, 1.0, 2.0, 3.0):
            for kl in (2.0, 5.0, 10.0, 20.0):
                rough = cls(ks / K, kl / K)
                slope = max(iem.nominal_rms_slope(rough))
                for eps in media:
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore")
                        e = api.emissivity(rough, eps, wavelength=1.0, theta_i=theta, method="iem",
                                           tol=1e-3, out_of_range="ignore")  # fmt: skip
                    for i, th in enumerate(np.degrees(theta)):
                        rows.append([rough.name, ks, kl, round(slope, 3), str(eps), th,
                                     round(float(e.h[i]), 4), round(float(e.v[i]), 4),
                                     round(float(e.error[:, i].max()), 5)])  # fmt: skip
                print(rough.name, ks, kl, flush=True)
    with atomic_path(out) as tmp, open(tmp, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["correlation", "k_sigma", "k_l", "nominal_slope", "eps", "theta_deg", "e_h",
                    "e_v", "quadrature_error"])  # fmt: skip
        w.writerows(rows)


if __name__ == "__main__":
    import sys

    if "--pec" in sys.argv[1:]:
        main(OUT_PEC, media=("pec",), theta=THETA_PEC)
    else:
        main()
