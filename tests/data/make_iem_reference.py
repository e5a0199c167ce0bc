"""Generate tests/data/iem_smrt_reference.csv (NOT run by the tests).

Peer-computed integral-equation backscatter from SMRT 1.7 (Picard, Sandells & Löwe,
Geosci. Model Dev. 11, 2763, 2018):

* ``smrt.interface.iem_fung92.IEM_Fung92`` — the IEM of Fung, Li & Chen, IEEE TGRS 30(2),
  356 (1992), co-polarized backscatter; run with ``series_truncation=40`` (converged for these
  cases: the last term is < 1e-12 of the sum; SMRT overflows to NaN beyond ~60 terms at these
  wavenumbers) and with its default 10 terms;
* ``smrt.interface.iiem_fung02.IIEM_Fung02`` — SMRT's improved IEM (Fung et al. 2002 with the
  transition of Fung & Chen 2004, from the Ulaby & Long 2014 codes), defaults, including the
  multiple-scattering cross-pol ``hv`` (Fung et al. 1992 appendix).

Run with a scratch venv that has SMRT::

    python3 -m venv /tmp/smrtvenv && /tmp/smrtvenv/bin/pip install smrt
    /tmp/smrtvenv/bin/python tests/data/make_iem_reference.py

Columns: model, acf, frequency_hz, rms_height_m, corr_length_m, k_sigma, k_l, eps_re,
eps_im, theta_deg, sigma0_hh, sigma0_vv, sigma0_hv (linear, per unit area; SMRT returns
σ⁰/(4π cosθ), multiplied back here; ``hv`` empty where the model has none). SMRT's
permittivity convention is Im ε ≥ 0, like emscatter's.
"""

import csv
import pathlib
import warnings
from importlib.metadata import version

import numpy as np
from smrt.interface.iem_fung92 import IEM_Fung92
from smrt.interface.iiem_fung02 import IIEM_Fung02

C = 299792458.0
OUT = pathlib.Path(__file__).with_name("iem_smrt_reference.csv")
THETA = np.array([10.0, 30.0, 50.0, 70.0])
ROUGH = [  # (frequency, rms height, correlation length)
    (5.3e9, 0.002, 0.02),
    (5.3e9, 0.004, 0.03),
    (5.3e9, 0.01, 0.05),
    (5.3e9, 0.0144, 0.08),
    (1.25e9, 0.02, 0.1),
]
EPS = [3.0 + 0.1j, 15.0 + 2.0j]
#: A long series (Gaussian, kσ = 2.5, kℓ = 20): SMRT's default 10 terms only (it overflows
#: to NaN before converging at these wavenumbers); the converged value comes from emscatter,
#: whose 1992 configuration matches SMRT's converged rows above to 1e-6.
SHORT = (5.3e9, 0.0225, 0.18)


def backscatter(model, f, eps, theta_deg, npol):
    mu = np.cos(np.radians(theta_deg))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        R = model.diffuse_reflection_matrix(f, 1, eps, mu, mu, np.pi, npol)
    if npol == 2:  # IEM_Fung92: (npol, n) with 0 = v, 1 = h
        vv, hh, hv = np.asarray(R[0]).ravel(), np.asarray(R[1]).ravel(), None
    else:  # IIEM_Fung02: (npol, npol, dphi, mu_s, mu_i)
        vv = np.asarray(R[0, 0, 0]).diagonal()
        hh = np.asarray(R[1, 1, 0]).diagonal()
        hv = np.asarray(R[0, 1, 0]).diagonal()
    s = 4 * np.pi * mu
    return s * hh, s * vv, None if hv is None else s * hv


def main():
    rows = []
    for acf in ("gaussian", "exponential"):
        for f, sig, ell in ROUGH:
            k = 2 * np.pi * f / C
            for eps in EPS:
                models = {
                    "iem_fung92_converged": (IEM_Fung92(roughness_rms=sig, corr_length=ell,
                        autocorrelation_function=acf, series_truncation=40,
                        warning_handling="nothing"), 2),
                    "iem_fung92_default": (IEM_Fung92(roughness_rms=sig, corr_length=ell,
                        autocorrelation_function=acf, warning_handling="nothing"), 2),
                    "iiem_fung02_default": (IIEM_Fung02(roughness_rms=sig, corr_length=ell,
                        autocorrelation_function=acf, warning_handling="nothing"), 3),
                }  # fmt: skip
                for name, (model, npol) in models.items():
                    hh, vv, hv = backscatter(model, f, eps, THETA, npol)
                    for i, th in enumerate(THETA):
                        rows.append([name, acf, f, sig, ell, round(k * sig, 6), round(k * ell, 6),
                                     eps.real, eps.imag, th, repr(float(hh[i])),
                                     repr(float(vv[i])),
                                     "" if hv is None else repr(float(hv[i]))])  # fmt: skip
    f, sig, ell = SHORT
    k = 2 * np.pi * f / C
    for eps in EPS:
        model = IEM_Fung92(roughness_rms=sig, corr_length=ell, autocorrelation_function="gaussian",
                           warning_handling="nothing")  # fmt: skip
        hh, vv, _ = backscatter(model, f, eps, THETA, 2)
        for i, th in enumerate(THETA):
            rows.append(["iem_fung92_default_long_series", "gaussian", f, sig, ell,
                         round(k * sig, 6), round(k * ell, 6), eps.real, eps.imag, th,
                         repr(float(hh[i])), repr(float(vv[i])), ""])  # fmt: skip
    with open(OUT, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow([f"# SMRT {version('smrt')}; see make_iem_reference.py"])
        w.writerow(["model", "acf", "frequency_hz", "rms_height_m", "corr_length_m", "k_sigma",
                    "k_l", "eps_re", "eps_im", "theta_deg", "sigma0_hh", "sigma0_vv",
                    "sigma0_hv"])  # fmt: skip
        w.writerows(rows)
    print(f"wrote {len(rows)} rows to {OUT}")


if __name__ == "__main__":
    main()
