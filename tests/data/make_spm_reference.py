"""Generate tests/data/spm_backscatter_reference.csv (NOT run by the tests).

Peer-computed first-order SPM backscatter: SMRT (Picard et al., GMD 2018), package ``smrt`` 1.7,
``smrt.interface.iem_fung92.IEM_Fung92`` — the integral-equation model of Fung, Li & Chen,
IEEE TGRS 30(2) 1992 — evaluated at small roughness (kσ ≤ 0.02), where IEM reduces to the
first-order small-perturbation method (Fung et al. 1992, §V; the series' n = 1 term is
Rice's SPM and the higher terms and exp(−2k²σ²cos²θ) factors differ from 1 by < 1e-3).
SMRT has no stand-alone SPM module (checked: smrt/interface/ in 1.7).

Run with a scratch venv that has SMRT::

    python3 -m venv /tmp/smrtvenv && /tmp/smrtvenv/bin/pip install smrt
    /tmp/smrtvenv/bin/python tests/data/make_spm_reference.py

Columns: theta_deg, eps_re, eps_im, ksigma, kl, acf, then sigma0_hh, sigma0_vv from SMRT with
``series_truncation=1`` (the n = 1 term of Fung's series: first-order SPM), then
iem_hh, iem_vv with SMRT's default 10-term series (linear, per unit area). The full series
differs from SPM where the first-order Bragg term W(2k sinθ) is tiny (Gaussian spectra at
large kℓ sinθ): there IEM's n ≥ 2 terms dominate. These rows are kept and labelled
(``iem_equals_spm`` = 0 where the two SMRT columns differ by more than 0.01 dB).
SMRT returns the diffuse reflection coefficient σ⁰/(4π cosθ); we multiply back.
SMRT's permittivity convention is Im ε ≥ 0, like emscatter's.
"""

import csv
import pathlib

import numpy as np
import smrt
from smrt.interface.iem_fung92 import IEM_Fung92

FREQ = 10e9  # Hz
C = 299792458.0
K = 2 * np.pi * FREQ / C

CASES = []
for acf in ("gaussian", "exponential"):
    for ks, kl in ((0.01, 1.0), (0.02, 3.0), (0.01, 6.0)):
        for eps in (3.0 + 0.1j, 17.0 + 2.0j, 80.0 + 40.0j):
            for th in (10.0, 30.0, 45.0, 60.0):
                CASES.append((th, eps, ks, kl, acf))


def main():
    rows = []
    for th, eps, ks, kl, acf in CASES:
        vals = []
        for nterms in (1, 10):
            m = IEM_Fung92(
                roughness_rms=ks / K,
                corr_length=kl / K,
                autocorrelation_function=acf,
                warning_handling="nan",
                series_truncation=nterms,
            )
            mu = np.array([np.cos(np.radians(th))])
            r = m.diffuse_reflection_matrix(FREQ, 1.0, eps, mu, mu, np.pi, 2)
            vv = float(np.asarray(r[0]).ravel()[0]) * 4 * np.pi * mu[0]
            hh = float(np.asarray(r[1]).ravel()[0]) * 4 * np.pi * mu[0]
            vals += [hh, vv]
        same = int(np.all(np.abs(10 * np.log10(np.array(vals[:2]) / np.array(vals[2:]))) < 0.01))
        rows.append((th, eps.real, eps.imag, ks, kl, acf, *vals, same))
    out = pathlib.Path(__file__).with_name("spm_backscatter_reference.csv")
    with out.open("w", newline="") as fh:
        fh.write(
            f"# SMRT {smrt.__version__ if hasattr(smrt, '__version__') else '1.7'} "
            f"iem_fung92 small-roughness limit = first-order SPM; f = {FREQ:g} Hz\n"
        )
        wr = csv.writer(fh)
        wr.writerow(
            [
                "theta_deg",
                "eps_re",
                "eps_im",
                "ksigma",
                "kl",
                "acf",
                "sigma0_hh",
                "sigma0_vv",
                "iem_hh",
                "iem_vv",
                "iem_equals_spm",
            ]
        )
        for row in rows:
            wr.writerow([f"{v:.10g}" if isinstance(v, float) else v for v in row])
    print(f"wrote {len(rows)} rows to {out}")


if __name__ == "__main__":
    main()
