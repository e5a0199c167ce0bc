"""PO (Kirchhoff) transmission into an absorbing medium
(:mod:`emscatter.solvers.kirchhoff.transmission.po`, Im ε > 0): the flat Fresnel flux,
continuity as Im ε → 0, agreement with the lossy SPM where both hold (as good as lossless),
and the errors; GO keeps refusing a lossy medium with the reason."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from emscatter.conventions import ConventionError
from emscatter.fresnel import fresnel_cos
from emscatter.solvers.kirchhoff.transmission import go as tgo
from emscatter.solvers.kirchhoff.transmission import po as tpo
from emscatter.solvers.spm import transmission as tspm
from emscatter.spectra import GaussianCorrelation

K = 2 * math.pi  # λ = 1 m


@pytest.mark.parametrize("eps", [4 + 0.4j, 70 + 30j, 0.3 + 0.05j, -10 + 1j])
def test_flat_flux_is_one_minus_fresnel_reflectance(eps):
    """σ → 0: T_coh = (1 − |R_p|²) exp(−σ² Re q_z²) → 1 − |R_p|² to 1e-12 |ε| (measured
    ≤ 3e-11 at ε = 70 + 30i, a metal included), σ⁰_t ∝ σ² → 0."""
    th = np.radians([0.0, 20.0, 45.0, 70.0, 85.0, 89.0])
    rough = GaussianCorrelation(sigma=1e-7, length=0.5, dimension=2)
    rh, rv = fresnel_cos(eps, np.cos(th))
    tc = tpo.coherent_transmissivity(rough, eps, K, th)
    np.testing.assert_allclose(tc, [1 - abs(rh) ** 2, 1 - abs(rv) ** 2], atol=1e-12 * abs(eps))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        s = tpo.bistatic_transmission(rough, eps, K, th, 0.3, 0.0, out_of_range="ignore")
    assert np.max(s.sigma0) < 1e-9


def test_lossless_limit_is_continuous():
    """Im ε = δ → 0: σ⁰_t and T_coh tend to the lossless values, the difference quadratic in
    δ here (|R|² and the flux factors are even in Im ε to first order at fixed Re ε; measured
    1.7e-11 / 1.7e-13 relative at δ = 1e-5 / 1e-6): asserted ratio 100 ± 10."""
    rough = GaussianCorrelation(0.5 / K, 3 / K, dimension=2)
    ti, tt = np.radians([10.0, 30.0, 60.0]), np.radians([5.0, 20.0, 40.0])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ref = tpo.bistatic_transmission(rough, 2.25, K, ti, tt, 0.5)
        diffs = []
        for d in (1e-5, 1e-6):
            res = tpo.bistatic_transmission(rough, 2.25 + 1j * d, K, ti, tt, 0.5)
            diffs.append(np.max(np.abs(res.sigma0 - ref.sigma0)) / ref.sigma0.max())
            assert np.max(np.abs(res.coherent - ref.coherent)) < 10 * d
    assert diffs[0] < 1e-9
    assert 90 < diffs[0] / diffs[1] < 110, diffs


@pytest.mark.parametrize("eps", [4 + 0.4j, 4 + 0.04j])
def test_agrees_with_lossy_spm_as_well_as_lossless(eps):
    """kσ = 0.3, kℓ = 12 and 20, θi = 30°: PO and SPM transmission of a lossy ε agree as well
    as at the lossless Re ε = 4 (max dB difference where the lobe is ≥ 1 % of its peak: 0.52 /
    0.53 dB lossy against 0.57 / 0.55 dB lossless, measured; asserted ≤ lossless + 0.05 dB),
    and so do their coherent transmissivities (5.0e-3 against 5.1e-3)."""
    th = math.radians(30.0)
    tt, pt = np.meshgrid(np.radians(np.linspace(0, 60, 121)), np.radians([0, 3, 8, 30]))
    for kl in (12.0, 20.0):
        rough = GaussianCorrelation(0.3 / K, kl / K, dimension=2)
        worst = []
        for e in (4.0, eps):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                a = tspm.bistatic_transmission(rough, e, K, th, tt, pt, out_of_range="ignore")
                b = tpo.bistatic_transmission(rough, e, K, th, tt, pt, out_of_range="ignore")
            au, bu = a.unpolarized(), b.unpolarized()
            sel = bu > 0.01 * bu.max()
            assert sel.sum() > 50
            db = np.max(np.abs(10 * np.log10(au[sel] / bu[sel])))
            coh = np.max(np.abs(a.coherent[:, 0, 0] - tpo.coherent_transmissivity(rough, e, K, th)))
            worst.append((db, coh))
        assert worst[1][0] <= worst[0][0] + 0.05, worst
        assert worst[1][1] <= worst[0][1] + 5e-4, worst


def test_bad_permittivities_are_clear_errors():
    """Im ε < 0 names the value and the exp(−iωt) convention; pec and ε = 1 are refused; GO
    transmission still needs a lossless ε and says why."""
    rough = GaussianCorrelation(0.5 / K, 3 / K, dimension=2)
    with pytest.raises(ConventionError, match=r"Im\(eps\) < 0.*exp\(-i omega t\)"):
        tpo.bistatic_transmission(rough, 4 - 0.4j, K, 0.1, 0.1, 0.0)
    with pytest.raises(ConventionError, match=r"Im\(eps\) < 0"):
        tpo.coherent_transmissivity(rough, 4 - 0.4j, K, 0.1)
    with pytest.raises(ValueError, match="perfect conductor"):
        tpo.coherent_transmissivity(rough, "pec", K, 0.1)
    with pytest.raises(ValueError, match="!= 1 for PO transmission"):
        tpo.bistatic_transmission(rough, 1.0, K, 0.1, 0.1, 0.0)
    with pytest.raises(ValueError, match="eps must be real for GO transmission"):
        tgo.bistatic_transmission(rough, 4 + 0.4j, K, 0.1, 0.1, 0.0)
