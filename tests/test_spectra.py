"""Spectrum normalizations (module docstring of emscatter.spectra) and slopes."""

import math

import numpy as np
import pytest
from scipy import integrate

from emscatter.spectra import (
    ExponentialCorrelation,
    FractionalBrownian,
    GaussianCorrelation,
    PowerLawCorrelation,
    _numeric_nfold,
    roughness,
)

KINDS = [
    GaussianCorrelation(0.3, 2.0),
    ExponentialCorrelation(0.3, 2.0),
    PowerLawCorrelation(0.3, 2.0, hurst=0.3),
    PowerLawCorrelation(0.3, 2.0, hurst=0.8),
]


@pytest.mark.parametrize("rough", KINDS, ids=lambda r: r.describe())
def test_spectra_integrate_to_one(rough):
    two_d = integrate.quad(lambda k: 2 * math.pi * k * rough.spectrum(k, 0.0), 0, np.inf)[0]
    one_d = integrate.quad(lambda k: rough.profile().spectrum(k), -np.inf, np.inf)[0]
    assert two_d == pytest.approx(1.0, rel=1e-6)
    assert one_d == pytest.approx(1.0, rel=1e-6)


@pytest.mark.parametrize("rough", KINDS, ids=lambda r: r.describe())
def test_spectrum_is_transform_of_correlation(rough):
    # 1-D: ρ(x) = ∫ w(k) cos(kx) dk, checked at a few lags.
    prof = rough.profile()
    for x in (0.5, 2.0, 5.0):
        rho = 2 * integrate.quad(lambda k: prof.spectrum(k), 0, np.inf, weight="cos", wvar=x)[0]
        assert rho == pytest.approx(float(prof.correlation(x)), abs=1e-6)


def test_ulaby_closed_forms():
    # Ulaby, Moore & Fung (1982) vol. II: Gaussian W = (ℓ²/2) exp(−K²ℓ²/4),
    # exponential W = ℓ² (1 + K²ℓ²)^(−3/2).
    ell, K = 0.7, np.linspace(0, 10, 7)
    g = GaussianCorrelation(1.0, ell).spectrum_ulaby(K)
    e = ExponentialCorrelation(1.0, ell).spectrum_ulaby(K)
    np.testing.assert_allclose(g, ell**2 / 2 * np.exp(-(K**2) * ell**2 / 4), rtol=1e-12)
    np.testing.assert_allclose(e, ell**2 * (1 + K**2 * ell**2) ** -1.5, rtol=1e-12)


def test_powerlaw_half_is_exponential():
    a = PowerLawCorrelation(1.0, 1.3, hurst=0.5)
    b = ExponentialCorrelation(1.0, 1.3)
    k = np.linspace(0, 20, 9)
    np.testing.assert_allclose(a.spectrum(k, 0.3 * k), b.spectrum(k, 0.3 * k), rtol=1e-12)
    np.testing.assert_allclose(a.correlation(k / 5), b.correlation(k / 5), rtol=1e-10)


@pytest.mark.parametrize("rough", KINDS[:3], ids=lambda r: r.describe())
def test_nfold_closed_forms_match_quadrature(rough):
    for n in (1, 3):
        np.testing.assert_allclose(
            rough.nfold_spectrum(n, 0.4, 0.1), _numeric_nfold(rough, n, 0.4, 0.1), rtol=1e-6
        )


def test_anisotropic_gaussian_slopes_and_seed_beckmann_m():
    sigma, tx, ty = 0.02, 0.5, 1.5
    rough = GaussianCorrelation(sigma, tx, ty)
    sx, sy = rough.mean_square_slope()
    assert sx == pytest.approx(2 * sigma**2 / tx**2)
    assert sy == pytest.approx(2 * sigma**2 / ty**2)
    # Seed eq. 3.1: m = tan β0 = 2σ/T is the *total* rms slope of an isotropic surface.
    iso = GaussianCorrelation(sigma, tx)
    assert math.sqrt(iso.total_mean_square_slope()) == pytest.approx(2 * sigma / tx)
    # the cutoff integral converges to the closed form
    assert rough.mean_square_slope(k_max=200 / tx)[0] == pytest.approx(sx, rel=1e-6)


def test_exponential_slope_needs_cutoff():
    rough = ExponentialCorrelation(0.01, 0.1)
    with pytest.raises(ValueError, match="k_max"):
        rough.mean_square_slope()
    s1 = rough.profile().mean_square_slope(k_max=1e3)[0]
    s2 = rough.profile().mean_square_slope(k_max=4e3)[0]
    # 1-D exponential: ⟨h'²⟩ = (2σ²/πℓ) k_max − …: grows linearly with the cutoff (∝ 1/dx).
    assert s2 / s1 == pytest.approx(4.0, rel=0.05)


@pytest.mark.parametrize(
    "factory, match",
    [
        (lambda: GaussianCorrelation(0.0, 1.0), "sigma must be > 0"),
        (lambda: GaussianCorrelation(-1.0, 1.0), "sigma must be > 0"),
        (lambda: GaussianCorrelation(1.0, 0.0), "length must be > 0"),
        (lambda: GaussianCorrelation(1.0, float("nan")), "length must be finite"),
        (lambda: GaussianCorrelation(1.0, 1.0, dimension=3), "dimension must be 1"),
        (lambda: GaussianCorrelation(1.0, 1.0, 2.0, dimension=1), "length_y"),
        (lambda: PowerLawCorrelation(1.0, 1.0, hurst=1.0), r"hurst must be in \(0.0, 1.0\)"),
        (lambda: FractionalBrownian(0.0), r"hurst must be in \(0.0, 1.0\)"),
        (lambda: FractionalBrownian(0.5, increment_rms=-1), "increment_rms must be > 0"),
        (lambda: roughness("sinusoid", sigma=1, length=1), "kind must be one of"),
    ],
)
def test_bad_roughness_inputs(factory, match):
    with pytest.raises(ValueError, match=match):
        factory()


def test_fbm_fractal_dimension_seed_eq_5_12():
    assert FractionalBrownian(0.3, dimension=1).fractal_dimension == pytest.approx(1.7)
    assert FractionalBrownian(0.3, dimension=2).fractal_dimension == pytest.approx(2.7)
    fb = FractionalBrownian(0.7, increment_rms=0.2, lag=3.0)
    assert fb.structure_function(6.0) == pytest.approx(0.04 * 2**1.4)
