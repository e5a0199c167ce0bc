"""The 3-D method of moments (PEC) against the Kirchhoff approximation in its range (issue 19)."""

import math
import warnings

import numpy as np
import pytest

import emscatter as em
from emscatter.solvers import mom3d
from emscatter.spectra import GaussianCorrelation

K = 2 * math.pi  # λ = 1 m


@pytest.mark.slow
@pytest.mark.parametrize("theta_i", [20.0, 40.0])
def test_specular_lobe_agrees_with_kirchhoff(theta_i):
    """Gaussian PEC surface kσ = 1, kℓ = 7 (rms slope per axis √2σ/ℓ = 0.20, radius of
    curvature ≫ λ: Kirchhoff's range, Thorsos 1988; Tsang et al. 2000 vol. I ch. 5), a 6λ × 6λ
    patch at 8 points/λ (taper g = 1.5λ), 16 realizations: mom3d's σ⁰ summed over 15 lobe
    directions (θs = θi − 20° … θi + 20° by 10°, φs = 0, ±20°; pooled standard error
    ≈ 0.3 dB) against PO and GO (``emscatter.bistatic``), both co-pols.

    Measured (pooled, hh/vv): θi = 20° PO −1.07/−1.16 dB, GO −0.60/−0.70 dB; θi = 40° PO
    −0.50/−0.37 dB, GO −0.76/−0.63 dB. Convergence in patch size at θi = 40°: an 8λ patch
    (g = 2λ, 10 realizations) gives PO −0.59/−0.65 dB, GO −0.85/−0.91 dB (within its 0.4 dB
    standard error of the 6λ values). Single directions scatter by up to ±3 dB (≈ 1 dB
    standard error each at 16 realizations): hence the pooled lobe.
    Energy per realization within 4 % (measured ≥ 0.961, mean 0.981 … 0.994)."""
    rough = GaussianCorrelation(1.0 / K, 7.0 / K)
    ti = math.radians(theta_i)
    tt, pp = np.meshgrid(ti + np.radians([-20, -10, 0, 10, 20]), np.radians([-20, 0, 20]))
    ts, ps = np.abs(tt.ravel()), pp.ravel()
    res = mom3d.bistatic(rough, "pec", K, ti, ts, ps, realizations=16, seed=1, length=6.0)
    assert np.all(np.abs(res.info["energy"] - 1) < 0.04)
    for i in range(2):  # the Monte Carlo standard error of the pooled lobe is below 0.5 dB
        se = np.sqrt(np.sum(res.info["sigma0_std"][i, i] ** 2)) / res.sigma0[i, i].sum()
        assert 10 * np.log10(1 + se) < 0.5
    tolerance = {"go": 1.0, "po": 1.3}
    for method, tol in tolerance.items():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            ref = em.bistatic(
                rough,
                "pec",
                wavelength=1.0,
                theta_i=ti,
                theta_s=ts,
                phi_s=ps,
                method=method,
                out_of_range="ignore",
            )
        for pair in ("hh", "vv"):
            db = 10 * np.log10(res.pol(pair).sum() / ref.pol(pair).sum())
            print(f"mom3d vs {method} θi={theta_i:g}° {pair}: {db:+.2f} dB")
            assert abs(db) < tol, (method, pair, db)
