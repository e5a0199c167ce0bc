"""The fast far field of the 3-D MoM (issue 19): the Taylor-in-height / Gaussian-gridding
sum of :mod:`emscatter.solvers.mom3d.gridsum` against the direct sum it replaces."""

import math

import numpy as np
import pytest

from emscatter.solvers import mom3d
from emscatter.solvers.mom3d.farfield import amplitudes, hemisphere, pol_vectors
from emscatter.solvers.mom3d.gridsum import grid_of, grid_sums, gridding_width, taylor_terms
from emscatter.solvers.mom3d.operator import make_patch
from emscatter.spectra import GaussianCorrelation
from emscatter.surfaces.generate import generate_surface

K = 2 * math.pi  # λ = 1 m
DX = 1 / 8


def _patch(size, k_sigma, seed=1, shape=None):
    ny, nx = shape or (int(size / DX), int(size / DX))
    h = generate_surface(GaussianCorrelation(k_sigma / K, 3 / K), (ny, nx), DX, rng=seed).heights
    p = make_patch(h, DX, DX)
    return p, np.stack([p.x, p.y, p.z], axis=1)


def _direct(src, pts, kvec):
    return src @ np.exp(-1j * (kvec @ pts.T)).T


@pytest.mark.parametrize(("size", "k_sigma", "shape"), [(4, 0.3, None), (6, 1.0, (40, 56))])
def test_grid_sums_equal_the_direct_sum(size, k_sigma, shape):
    """Random sources on the hemisphere quadrature (and a few directions below the horizon):
    the error stays within the docstring's bound ``tol Σ|s|`` at tol = 1e-7, 1e-4 and 1e-10,
    and falls with tol (measured 1e-10 … 1e-9 of max|S| at 1e-7)."""
    p, pts = _patch(size, k_sigma, shape=shape)
    th, ph, _ = hemisphere(24)
    th = np.concatenate([th, [2.0, 2.8]])
    ph = np.concatenate([ph, [0.4, 4.0]])
    kvec = K * pol_vectors(th, ph)[0]
    rng = np.random.default_rng(0)
    src = rng.normal(size=(3, p.n)) + 1j * rng.normal(size=(3, p.n))
    ref = _direct(src, pts, kvec)
    grid = grid_of(pts)
    assert (grid.ny, grid.nx) == p.shape and grid.dx == pytest.approx(DX)
    errs = []
    for tol in (1e-4, 1e-7, 1e-10):
        err = np.max(np.abs(grid_sums(src, p.z, grid, kvec, tol=tol) - ref), axis=1)
        assert np.all(err <= tol * np.abs(src).sum(axis=1)), (tol, err)
        errs.append(err.max())
    assert errs[2] < errs[1] < errs[0]
    assert errs[1] < 1e-7 * np.abs(ref).max()


def test_fast_far_field_of_a_solved_current_equals_the_direct_one():
    """A solved 6λ current (kσ = 1, θi = 30°): the hemisphere amplitudes by both sums agree to
    1e-6 of the largest (measured ~1e-9), σ⁰ within 1e-4 dB wherever it is above 1e-6 of its
    peak, and the energy ratio to 1e-8."""
    p, pts = _patch(6, 1.0, seed=4)
    r = mom3d.solve_realization(p.z.reshape(p.shape), DX, K, math.radians(30), [0.3], [0.0])
    th, ph, wt = hemisphere(r["n_mu"])
    area = DX * DX
    fast = amplitudes(pts, area, K, r["current"], th, ph, method="fast")
    ref = amplitudes(pts, area, K, r["current"], th, ph, method="direct")
    assert np.max(np.abs(fast - ref)) < 1e-6 * np.max(np.abs(ref))
    big = np.abs(ref) ** 2 > 1e-6 * np.max(np.abs(ref) ** 2)
    db = 10 * np.log10(np.abs(fast[big]) ** 2 / np.abs(ref[big]) ** 2)
    assert np.max(np.abs(db)) < 1e-4
    e_fast = np.einsum("spd,d->p", np.abs(fast) ** 2, wt)
    e_ref = np.einsum("spd,d->p", np.abs(ref) ** 2, wt)
    assert np.allclose(e_fast, e_ref, rtol=1e-8)
    # the public call's hemisphere went through the fast path (N·D above FAST_MIN_WORK)
    assert np.allclose(r["hemisphere"], fast, rtol=0, atol=1e-12 * np.abs(ref).max())


def test_orders_and_widths_follow_their_bounds():
    """Q: smallest order with x^Q/Q! ≤ tol; w grows like log(1/tol)."""
    for x, tol in ((0.5, 1e-8), (3.0, 1e-7), (10.0, 1e-6)):
        q = taylor_terms(x, tol)
        assert x**q / math.factorial(q) <= tol < x ** (q - 1) / math.factorial(q - 1)
    assert gridding_width(1e-4) < gridding_width(1e-7) < gridding_width(1e-10)
    with pytest.raises(ValueError, match="more than 80 terms"):
        taylor_terms(60.0, 1e-8)


def test_points_off_a_grid_take_the_direct_sum_or_are_refused():
    p, pts = _patch(2, 0.3)
    jitter = pts.copy()
    jitter[5, 0] += 1e-3
    assert grid_of(jitter) is None
    u = np.ones((1, p.n, 3), dtype=complex)
    th, ph = np.array([0.3, 1.0]), np.array([0.0, 2.0])
    a = amplitudes(jitter, DX * DX, K, u, th, ph)  # auto: direct
    assert a.shape == (2, 1, 2) and np.all(np.isfinite(a))
    with pytest.raises(ValueError, match="method='fast' needs points on a regular"):
        amplitudes(jitter, DX * DX, K, u, th, ph, method="fast")
    with pytest.raises(ValueError, match="method must be one of"):
        amplitudes(pts, DX * DX, K, u, th, ph, method="nufft")


def test_fast_dielectric_far_field_equals_the_direct_one():
    """A solved rough dielectric patch (Müller, ε = 3 lossless, kσ = 0.3, 3λ at 14 points per
    free-space λ, θi = 40°): :func:`amplitudes_em` by both sums, above (air) and below (the
    medium, index √3) the interface, agree to 1e-6 of the largest amplitude and within the
    docstring's bound ``tol area (Σ|u| + n Σ|w|)``; σ⁰ within 1e-4 dB wherever it is above
    1e-6 of its peak; reflectivity and transmissivity to 1e-8; the public call with
    ``farfield="fast"`` returns the fast sums, and a bad ``farfield`` is refused first."""
    from emscatter.solvers.mom3d.dielectric_model import solve_dielectric_realization
    from emscatter.solvers.mom3d.farfield import FAST_TOL, amplitudes_em

    dx = 1 / 14
    h = generate_surface(GaussianCorrelation(0.3 / K, 3 / K), (42, 42), dx, rng=2).heights
    ti = math.radians(40)
    r = solve_dielectric_realization(h, dx, K, 3.0, ti, [ti], [math.pi], farfield="fast")
    pts, u, w, area, n2 = r["points"], r["u"], r["w"], dx * dx, math.sqrt(3.0)
    th, ph, wt = hemisphere(r["n_mu"])
    th2, ph2, wt2 = hemisphere(max(24, math.ceil(r["n_mu"] * n2)))
    cases = [(1.0, u, w, th, ph, wt), (n2, -u, -w, math.pi - th2, ph2, wt2)]
    for n_med, a, b, t, p, weights in cases:
        fast = amplitudes_em(pts, area, K, n_med, a, b, t, p, method="fast")
        ref = amplitudes_em(pts, area, K, n_med, a, b, t, p, method="direct")
        err = np.abs(fast - ref)
        assert err.max() < 1e-6 * np.abs(ref).max(), (n_med, err.max() / np.abs(ref).max())
        bound = FAST_TOL * area * (np.abs(a).sum(axis=(1, 2)) + n_med * np.abs(b).sum(axis=(1, 2)))
        assert np.all(err.max(axis=(0, 2)) <= bound), (err.max(axis=(0, 2)), bound)
        big = np.abs(ref) ** 2 > 1e-6 * np.max(np.abs(ref) ** 2)
        db = 10 * np.log10(np.abs(fast[big]) ** 2 / np.abs(ref[big]) ** 2)
        assert np.max(np.abs(db)) < 1e-4, np.max(np.abs(db))
        e_fast = np.einsum("spd,d->p", np.abs(fast) ** 2, weights)
        e_ref = np.einsum("spd,d->p", np.abs(ref) ** 2, weights)
        assert np.allclose(e_fast, e_ref, rtol=1e-8)
    again = amplitudes_em(pts, area, K, 1.0, u, w, th, ph, method="fast")
    np.testing.assert_allclose(r["hemisphere"], again, rtol=0, atol=1e-14 * np.abs(again).max())
    assert abs(r["reflectivity"] + r["transmissivity"] - 1).max() < 0.012
    with pytest.raises(ValueError, match="farfield must be one of"):
        solve_dielectric_realization(h, dx, K, 3.0, ti, [ti], [math.pi], farfield="nufft")
