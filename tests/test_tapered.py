"""The exponential maps' surface (validation/tapered.py): an exponential spectrum with a smooth
inner cutoff, its correlation and n-fold spectra, and every solver on it."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from emscatter import solvers
from emscatter.solvers.kirchhoff import po
from emscatter.spectra import ExponentialCorrelation
from emscatter.surfaces.generate import generate_surface
from emscatter.validation.tapered import TaperedExponential, tapered_from

K = 2 * math.pi


@pytest.fixture(scope="module")
def rough():
    return tapered_from(0.5 / K, 3.0 / K, 2.5 * K)


def test_spectrum_is_the_exponential_below_the_cut(rough):
    pure = ExponentialCorrelation(0.5 / K, 3.0 / K, dimension=1)
    kk = np.linspace(0, 1.2 * K, 50)  # the maps' Bragg band at θi = 20°
    np.testing.assert_allclose(rough.height_spectrum(kk), pure.height_spectrum(kk), rtol=3e-4)
    fine = np.linspace(-4 * K, 4 * K, 40001)
    assert np.trapezoid(rough.spectrum(fine), fine) == pytest.approx(1.0, abs=1e-6)
    assert rough.spectrum(3.5 * K) < 1e-12 * rough.spectrum(0.0)
    assert rough.sigma < pure.sigma and rough.untapered_sigma == pure.sigma
    with pytest.raises(ValueError, match="1-D"):
        TaperedExponential(0.1, 1.0, cut=3.0)


def test_correlation_and_realizations(rough):
    u = np.array([0.0, 0.05, 0.3, 1.0, 3.0])
    x = u * rough.length
    kk = np.linspace(0, 4 * K, 200001)
    direct = [2 * np.trapezoid(rough.spectrum(kk) * np.cos(kk * xi), kk) for xi in x]
    np.testing.assert_allclose(rough.correlation(x), direct, atol=2e-6)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the circulant embedding is exact (no clipped eigenvalue)
        h = generate_surface(rough, 1 << 15, 1 / 20, rng=5).heights
    assert np.std(h) == pytest.approx(rough.sigma, rel=0.1)
    kf = 2 * math.pi * np.fft.fftfreq(h.size, d=1 / 20)
    slope = np.real(np.fft.ifft(1j * kf * np.fft.fft(h)))[500:-500]
    assert np.var(slope) == pytest.approx(rough.mean_square_slope()[0], rel=0.15)


def test_nfold_spectra(rough):
    f = rough.log_nfold_table()
    s = np.array([0.05, 0.5, 2.0, 5.0])
    np.testing.assert_allclose(
        np.exp(f(1.0, s)), rough.spectrum(s / rough.length) / rough.length, rtol=3e-4
    )
    m2 = rough.mean_square_slope()[0] * rough.length**2 / rough.sigma**2  # −ρ''(0) in u
    for n in (1.0, 7.0, 100.0, 1000.0, 3000.0):  # each w_n integrates to one (both sides)
        sg = np.linspace(0, max(4 * rough.cut, 10 * math.sqrt(n * m2)), 40001)
        assert 2 * np.trapezoid(np.exp(f(n, sg)), sg) == pytest.approx(1.0, rel=2e-3)
    # continuity at the switch to the Gaussian limit (n > 1024)
    assert np.exp(f(1025.0, 1.0)) / np.exp(f(1024.0, 1.0)) == pytest.approx(1.0, abs=0.01)


@pytest.mark.parametrize("method", ["spm", "go", "po", "iem"])
def test_every_solver_takes_it(rough, method):
    signed = np.array([-50.0, -10.0, 20.0, 45.0])
    ts, ps = np.radians(np.abs(signed)), np.where(signed >= 0, 0.0, math.pi)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # validity notes
        res = solvers.get(method).bistatic(rough, 3.0, K, math.radians(20), ts, ps)
    assert np.all(np.isfinite(res.sigma0)) and np.all(res.sigma0[0, 0] > 0)


def test_po_tends_to_the_exponential_as_the_cut_recedes():
    """The n-fold table (PO's hook): with the cut far beyond the spectrum that matters, PO on
    the tapered profile is PO on the exponential."""
    pure = ExponentialCorrelation(0.3 / K, 3.0 / K, dimension=1)
    signed = np.array([-40.0, 0.0, 20.0, 40.0])
    ts, ps = np.radians(np.abs(signed)), np.where(signed >= 0, 0.0, math.pi)
    ref = po.bistatic(pure, "pec", K, 0.3, ts, ps).sigma0[0, 0]
    err = []
    for taper in (2.5, 10.0):  # measured: 0.030, 0.0077 (and 0.0031 at 25)
        r = tapered_from(pure.sigma, pure.length, taper * K)
        err.append(np.max(np.abs(np.log(po.bistatic(r, "pec", K, 0.3, ts, ps).sigma0[0, 0] / ref))))
    assert err[1] < err[0] / 3 and err[1] < 0.01
