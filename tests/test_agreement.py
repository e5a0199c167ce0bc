"""Two approximations agree where both are valid (shared/PHYSICS.md, "laws").

SPM (first order) vs Kirchhoff physical optics near the specular direction.
Overlap region: kσ ≤ 0.15 (SPM: kσ ≲ 0.3, Thorsos & Jackson 1989) and kℓ ≥ 10 (Kirchhoff:
radius of curvature ≫ λ, kℓ ≳ 6, Thorsos 1988) with small slopes (√2σ/ℓ ≤ 0.02). There the PO
series is dominated by its n = 1 term, which equals first-order SPM up to the factor
exp(−q_z²σ²) and the local-specular Fresnel factor: near specular both corrections are
O((kσ)²), ≈ 0.15 dB at kσ = 0.1 — so 0.5 dB is a real test, not a formality.
"""

import math

import numpy as np
import pytest

from emscatter.solvers.kirchhoff import po as kirchhoff_po
from emscatter.solvers.spm import model as spm
from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation

K = 2 * math.pi


@pytest.mark.parametrize("k_sigma", [0.05, 0.1, 0.15])
@pytest.mark.parametrize("k_ell", [10.0, 20.0])
@pytest.mark.parametrize("cls", [GaussianCorrelation, ExponentialCorrelation])
@pytest.mark.parametrize("eps", [17 + 2j, 3.0, "pec"])
def test_spm_and_physical_optics_agree_near_specular(k_sigma, k_ell, cls, eps):
    rough = cls(k_sigma / K, k_ell / K)
    for ti_deg in (10.0, 30.0, 50.0):
        ti = math.radians(ti_deg)
        ts = np.radians(ti_deg + np.array([-6.0, -3.0, 0.0, 3.0, 6.0]))
        a = spm.bistatic(rough, eps, K, ti, ts, 0.0)
        b = kirchhoff_po.bistatic(rough, eps, K, ti, ts, 0.0)
        for p in (0, 1):
            diff = 10 * np.log10(a.sigma0[p, p] / b.sigma0[p, p])
            assert np.max(np.abs(diff)) < 0.5, (ti_deg, p, diff)


def test_disagreement_grows_outside_the_overlap():
    # At kσ = 0.3 the PO damping exp(−q_z²σ²) is no longer negligible: > 0.5 dB apart.
    rough = GaussianCorrelation(0.3 / K, 10 / K)
    ti = math.radians(10)
    a = spm.bistatic(rough, 17 + 2j, K, ti, ti, 0.0).hh
    b = kirchhoff_po.bistatic(rough, 17 + 2j, K, ti, ti, 0.0).hh
    assert 10 * math.log10(a / b) > 0.5
