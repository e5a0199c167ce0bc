"""The resummed backscatter cross-pol (:mod:`emscatter.solvers.iem.crosspol_resummed`): its
small-roughness limit (second-order SPM, the exact fourth-order hv), reciprocity, saturation,
agreement with the IEM term in the Kirchhoff regime, convergence, input errors."""

import math

import numpy as np
import pytest

import emscatter as em
from emscatter.solvers.iem import crosspol
from emscatter.solvers.iem.crosspol_resummed import backscatter_resummed
from emscatter.solvers.iem.model import nominal_rms_slope
from emscatter.solvers.spm.crosspol import backscatter_hv

K = 2.0 * math.pi
TH = np.radians([20.0, 40.0])


def _iem(rough, eps):
    return crosspol.backscatter(rough, eps, K, TH, 0.0 * TH, slope=nominal_rms_slope(rough))


@pytest.mark.parametrize(
    "rough",
    [em.GaussianCorrelation(0.02 / K, 3.0 / K), em.ExponentialCorrelation(0.02 / K, 2.0 / K)],
)
def test_small_roughness_limit_is_spm2(rough):
    # T̂(Q, κ) = w(κ)(1 + O(Q)), Q = (kσ cosθ)² ≤ 4e-4: the resummed term is σ⁰⁽²²⁾
    a = backscatter_resummed(rough, 15 + 2j, K, TH)
    b = backscatter_hv(rough, 15 + 2j, K, TH)
    np.testing.assert_allclose(a, b, rtol=1e-3)


def test_reciprocity_hv_equals_vh():
    rough = em.GaussianCorrelation(0.8 / K, 4.0 / K, length_y=6.0 / K)
    hv, vh = backscatter_resummed(rough, 9 + 2.5j, K, TH, phi_i=0.4, both=True)
    np.testing.assert_allclose(hv, vh, rtol=1e-9)
    assert np.all(hv > 0)


def test_saturates_below_spm2_for_exponential():
    # the height series' e^{-Q} and broadening cut perturbation theory's σ⁴ growth: the ratio
    # to σ⁰⁽²²⁾ is < 1 and falls with kσ (kℓ = 8)
    ratios = []
    for ks in (0.3, 0.8, 1.3):
        rough = em.ExponentialCorrelation(ks / K, 8.0 / K)
        a = backscatter_resummed(rough, 15 + 2j, K, TH)
        ratios.append(a / backscatter_hv(rough, 15 + 2j, K, TH))
    ratios = np.array(ratios)
    assert np.all(ratios < 1.0)
    assert np.all(np.diff(ratios, axis=0) < 0)


def test_agrees_with_iem_term_in_kirchhoff_regime():
    # Gaussian kσ = 1.3, kℓ = 6 (measured: 0.09 / 0.13 dB): two kernels, one height series
    rough = em.GaussianCorrelation(1.3 / K, 6.0 / K)
    a = backscatter_resummed(rough, 15 + 2j, K, TH)
    assert np.all(np.abs(10 * np.log10(a / _iem(rough, 15 + 2j))) < 0.5)


def test_above_iem_term_at_small_kl():
    # exponential kσ = 0.3, kℓ = 1.2: the evanescent intermediate waves the IEM term omits
    # (measured on NMM3D's kℓ ≈ 1 cases: IEM term 5.5–7 dB below σ⁰⁽²²⁾)
    rough = em.ExponentialCorrelation(0.3 / K, 1.2 / K)
    a = backscatter_resummed(rough, 9 + 2.5j, K, TH)
    assert np.all(10 * np.log10(a / _iem(rough, 9 + 2.5j)) > 3.0)


def test_node_rule_converged_at_large_roughness():
    rough = em.ExponentialCorrelation(2.5 / K, 10.0 / K)
    a = backscatter_resummed(rough, 15 + 2j, K, TH)
    b = backscatter_resummed(rough, 15 + 2j, K, TH, n_nodes=24)
    np.testing.assert_allclose(a, b, rtol=1e-3)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(eps="pec"), "eps"),
        (dict(eps=-5 + 1j), "eps"),
        (dict(rough=em.GaussianCorrelation(1.0, 3.0, dimension=1)), "roughness"),
        (dict(rough=em.ExponentialCorrelation(5.0 / K, 10.0 / K)), "k\\*sigma"),
        (dict(theta=0.5 * math.pi), "theta"),
        (dict(n_nodes=2), "n_nodes"),
        (dict(n_azimuth=3), "n_azimuth"),
        (dict(k=-1.0), "k"),
        (dict(phi_i=float("nan")), "phi_i"),
    ],
)
def test_bad_input_names_the_parameter(kwargs, match):
    args = dict(rough=em.GaussianCorrelation(0.3 / K, 3.0 / K), eps=9 + 1j, k=K, theta=0.5)
    args.update(kwargs)
    extra = {k: args.pop(k) for k in ("n_nodes", "n_azimuth", "phi_i") if k in args}
    with pytest.raises(ValueError, match=match):
        backscatter_resummed(args["rough"], args["eps"], args["k"], args["theta"], **extra)
