"""Band-limited surfaces for the 3-D MoM (emscatter.solvers.mom3d.truncated, bistatic's
``spectral_cutoff``): one continuous surface sampled on every grid, the variance of the kept
spectrum, and a cutoff the grid can hold (issue 19)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from emscatter.solvers import mom3d
from emscatter.solvers.mom3d.truncated import (
    cutoff_variance,
    exponential_cutoff_variance,
    truncated_heights,
)
from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation

K = 2 * math.pi
EXP = ExponentialCorrelation(0.3 / K, 3 / K)


def test_one_seed_gives_the_same_surface_on_every_grid():
    """8 and 16 points/λ over the same 6λ: the coarse map is the fine one's every other node
    (the same continuous band-limited surface, sampled, not redrawn)."""
    h8 = truncated_heights(EXP, 48, 1 / 8, 2 * K, np.random.default_rng(5))
    h16 = truncated_heights(EXP, 96, 1 / 16, 2 * K, np.random.default_rng(5))
    assert np.allclose(h8, h16[::2, ::2], rtol=0, atol=1e-12 * EXP.sigma)
    assert not np.allclose(h8, truncated_heights(EXP, 48, 1 / 8, 2 * K, np.random.default_rng(6)))


@pytest.mark.parametrize("kc", [1.0, 2.0, 3.0])
def test_variance_is_the_exponential_minus_its_tail(kc):
    """The kept modes sum to σ²(1 − 1/√(1 + K_c²ℓ²)) (∫₀^{K_c} 2πK w dK of the exponential) up
    to the lattice's sampling of the spectrum (ΔK = 2π/24λ); the ensemble variance at a node
    is that sum (400 maps, 3 standard errors)."""
    want = exponential_cutoff_variance(EXP.sigma, EXP.length, kc * K)
    got = cutoff_variance(EXP, 48, 1 / 8, kc * K)
    assert got == pytest.approx(want, rel=0.02)
    assert got < EXP.sigma**2
    rng = np.random.default_rng(11)
    h = np.array([truncated_heights(EXP, 16, 1 / 8, kc * K, rng)[3, 5] for _ in range(400)])
    assert abs(h.var() - got) < 3 * got * math.sqrt(2 / 400)


def test_a_cutoff_under_every_bragg_wavenumber_keeps_the_gaussian():
    """A Gaussian kℓ = 3 has no variance above 4k (w ∝ exp(−K²ℓ²/4), e^-36): the cut surface
    keeps all of σ² but the K = 0 mode's ``σ² w(0) ΔK²`` (ΔK = 2π/24λ, 0.12 %)."""
    g = GaussianCorrelation(0.3 / K, 3 / K)
    dc = g.spectrum(0.0, 0.0) * (2 * math.pi / 24) ** 2
    assert 1e-3 < dc < 2e-3
    want = g.sigma**2 * (1 - dc)
    assert cutoff_variance(g, 48, 1 / 8, 4 * K) == pytest.approx(want, rel=1e-5)


def test_bistatic_takes_the_cutoff_and_states_the_surface_variance():
    res = mom3d.bistatic(EXP, "pec", K, math.radians(30), math.radians(30), 0.0,
                         realizations=2, seed=1, length=2.0, points_per_wavelength=8,
                         spectral_cutoff=2 * K)  # fmt: skip
    assert res.info["spectral_cutoff"] == 2 * K
    assert res.info["surface_variance"] == pytest.approx(cutoff_variance(EXP, 16, 1 / 8, 2 * K))
    assert np.all(res.info["energy"] > 0.9)


def test_a_cutoff_beyond_the_grid_is_refused():
    with pytest.raises(ValueError, match=r"spectral_cutoff=.* above the grid's Nyquist"):
        mom3d.bistatic(EXP, "pec", K, 0.5, 0.5, realizations=2, length=2.0,
                       points_per_wavelength=8, spectral_cutoff=5 * K)  # fmt: skip
    with pytest.raises(ValueError, match="spectral_cutoff must be"):
        mom3d.bistatic(EXP, "pec", K, 0.5, 0.5, realizations=2, length=2.0,
                       spectral_cutoff=-1.0)  # fmt: skip
