"""Rough-surface generation: reproducibility, exactness, ensemble statistics, bad inputs.

Tolerances on ensemble statistics are set from the sampling error measured on the same
ensemble (standard error of the mean over realizations), never tuned to a seed.
Exactness of the embeddings is checked without sampling error: the generated field is
linear in the noise, so feeding unit noise vectors gives its covariance exactly.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.fft as sfft

from emscatter.spectra import (
    ExponentialCorrelation,
    FractionalBrownian,
    GaussianCorrelation,
    PowerLawCorrelation,
)
from emscatter.surfaces.generate import (
    Surface,
    _plan,
    _stein_coeffs,
    generate_batch,
    generate_surface,
)

# --------------------------------------------------------------------------- helpers


class _BasisNoise:
    """Stands in for a Generator: the noise, concatenated over successive calls, is the
    i-th unit vector, so the plan's output is the i-th column of the linear map
    noise → heights. Calls with ``size`` (Stein's extra N(0, 1) pair) get zeros: that
    term's covariance is added analytically."""

    def __init__(self, i: int):
        self.i = i
        self.n = 0

    def standard_normal(self, size=None, out=None):
        if out is None:
            return np.zeros(size)
        out[...] = 0.0
        j = self.i - self.n
        if 0 <= j < out.size:
            out.flat[j] = 1.0
        self.n += out.size
        return out


def exact_covariance(plan) -> np.ndarray:
    """Covariance matrix of the plan's output (flattened), from its linear map."""
    probe = _BasisNoise(0)
    plan.realize(probe)
    cols = [plan.realize(_BasisNoise(i)).ravel() for i in range(probe.n)]
    m = np.array(cols)
    return m.T @ m


def ensemble_acf(h: np.ndarray) -> np.ndarray:
    """Unbiased-by-count autocovariance of one non-periodic map (mean removed), FFT-based."""
    h0 = h - h.mean()
    s = tuple(2 * n for n in h.shape)
    f = sfft.rfftn(h0, s=s)
    ac = sfft.irfftn(f * f.conj(), s=s)
    g = sfft.rfftn(np.ones_like(h0), s=s)
    cnt = sfft.irfftn(g * g.conj(), s=s)
    return ac / np.maximum(np.rint(cnt), 1.0)


def structure_function(hs: list[np.ndarray], lags, axis=-1) -> np.ndarray:
    out = []
    for r in lags:
        vals = [
            np.mean(
                (
                    np.take(h, range(r, h.shape[axis]), axis)
                    - np.take(h, range(h.shape[axis] - r), axis)
                )
                ** 2
            )
            for h in hs
        ]
        out.append(np.mean(vals))
    return np.array(out)


def structure_function_each(hs: list[np.ndarray], r: int, axis=-1) -> np.ndarray:
    n = hs[0].shape[axis]
    return np.array(
        [np.mean((np.take(h, range(r, n), axis) - np.take(h, range(n - r), axis)) ** 2) for h in hs]
    )


# --------------------------------------------------------------------------- reproducibility

ROUGHS = [
    (GaussianCorrelation(1e-3, 8e-3), (64, 64), 1e-3, False),
    (ExponentialCorrelation(1e-3, 8e-3, dimension=1), 256, 1e-3, False),
    (FractionalBrownian(0.3, dimension=1), 256, 1.0, False),
    (FractionalBrownian(0.8, dimension=2), (64, 48), 1.0, False),
    (FractionalBrownian(0.6, dimension=2), (64, 64), 1.0, True),
    (GaussianCorrelation(1e-3, 8e-3), (64, 64), 1e-3, True),
]


@pytest.mark.parametrize("rough,shape,dx,periodic", ROUGHS)
def test_seeds_reproducible_and_distinct(rough, shape, dx, periodic):
    a = generate_surface(rough, shape, dx, periodic=periodic, rng=0)
    b = generate_surface(rough, shape, dx, periodic=periodic, rng=0)
    c = generate_surface(rough, shape, dx, periodic=periodic, rng=1)
    np.testing.assert_array_equal(a.heights, b.heights)
    assert not np.allclose(a.heights, c.heights)
    assert np.all(np.isfinite(a.heights))
    assert a.seed == 0 and c.seed == 1
    # a Generator advances: two draws from one generator differ
    g = np.random.default_rng(7)
    d1 = generate_surface(rough, shape, dx, periodic=periodic, rng=g)
    d2 = generate_surface(rough, shape, dx, periodic=periodic, rng=g)
    assert not np.allclose(d1.heights, d2.heights)
    np.testing.assert_array_equal(
        d1.heights,
        generate_surface(rough, shape, dx, periodic=periodic, rng=np.random.default_rng(7)).heights,
    )


def test_large_grid_threaded_noise_reproducible():
    # above the threading threshold the noise is drawn in fixed blocks: still reproducible
    f = FractionalBrownian(0.5, dimension=2)
    a = generate_surface(f, (1024, 1024), 1.0, periodic=True, rng=3)
    b = generate_surface(f, (1024, 1024), 1.0, periodic=True, rng=3)
    np.testing.assert_array_equal(a.heights, b.heights)


def test_global_numpy_state_untouched():
    legacy = np.random  # the legacy global state is the point of this test
    legacy.seed(1234)  # noqa: NPY002
    expect = legacy.random(3)  # noqa: NPY002
    legacy.seed(1234)  # noqa: NPY002
    generate_surface(GaussianCorrelation(1.0, 4.0), (32, 32), 1.0, rng=5)
    generate_surface(FractionalBrownian(0.4, dimension=1), 64, 1.0)
    generate_batch(FractionalBrownian(0.7), 2, (16, 16), 1.0, seed=1)
    np.testing.assert_array_equal(legacy.random(3), expect)  # noqa: NPY002


def test_rng_none_records_entropy():
    s = generate_surface(GaussianCorrelation(1.0, 4.0), (16, 16), 1.0)
    again = generate_surface(
        GaussianCorrelation(1.0, 4.0), (16, 16), 1.0, rng=np.random.SeedSequence(s.seed)
    )
    np.testing.assert_array_equal(s.heights, again.heights)


def test_batch_spawn_reproducible_and_distinct():
    rough = FractionalBrownian(0.6, dimension=2)
    b1 = generate_batch(rough, 4, (32, 32), 1.0, seed=11)
    b2 = generate_batch(rough, 4, (32, 32), 1.0, seed=11)
    for s1, s2 in zip(b1, b2, strict=True):
        np.testing.assert_array_equal(s1.heights, s2.heights)
    for i in range(4):
        for j in range(i + 1, 4):
            assert not np.allclose(b1[i].heights, b1[j].heights)
    # member i is the i-th spawned child
    child = np.random.SeedSequence(11).spawn(4)[2]
    np.testing.assert_array_equal(
        b1[2].heights, generate_surface(rough, (32, 32), 1.0, rng=child).heights
    )


def test_surface_object():
    g = GaussianCorrelation(2e-3, 1e-2, length_y=2e-2)
    s = generate_surface(g, (40, 50), (1e-3, 2e-3), rng=0)
    assert isinstance(s, Surface)
    assert s.shape == (40, 50) and s.dimension == 2
    assert s.spacing == (1e-3, 2e-3)
    np.testing.assert_allclose(s.x[:3], [0, 2e-3, 4e-3])
    np.testing.assert_allclose(s.y[:3], [0, 1e-3, 2e-3])
    assert s.size == pytest.approx((0.04, 0.1))
    t = s.target_stats()
    assert t["sigma"] == 2e-3
    assert t["rms_slope_x"] == pytest.approx(math.sqrt(2) * 2e-3 / 1e-2)
    assert t["rms_slope_y"] == pytest.approx(math.sqrt(2) * 2e-3 / 2e-2)
    assert t["rms_slope"] == pytest.approx(math.hypot(t["rms_slope_x"], t["rms_slope_y"]))
    assert s.info["exact"] and s.method == "circulant-embedding"
    r = s.realized_stats()
    assert set(r) >= {"sigma", "rms_slope_x", "rms_slope_y", "rms_slope"}
    e = generate_surface(ExponentialCorrelation(1.0, 4.0, dimension=1), 64, 1.0, rng=0)
    assert e.target_stats()["rms_slope"] is None  # infinite without a cutoff
    with pytest.raises(AttributeError):
        _ = e.y
    f = generate_surface(FractionalBrownian(0.3, dimension=2), (16, 16), 1.0, rng=0)
    assert f.target_stats()["fractal_dimension"] == pytest.approx(2.7)
    assert f.method == "stein-2002" and f.heights[0, 0] == 0.0


# --------------------------------------------------------------------------- exactness


@pytest.mark.parametrize("hurst", [0.2, 0.5, 0.8])
def test_davies_harte_covariance_exact(hurst):
    fbm = FractionalBrownian(hurst, increment_rms=0.3, lag=2.0, dimension=1)
    n, dx = 20, 0.5
    plan, _ = _plan(fbm, n, dx, False)
    cov = exact_covariance(plan)
    t = np.arange(n) * dx
    want = 0.5 * (
        fbm.structure_function(t[:, None])
        + fbm.structure_function(t[None, :])
        - fbm.structure_function(t[:, None] - t[None, :])
    )
    np.testing.assert_allclose(cov, want, atol=1e-12 * want.max())


@pytest.mark.parametrize("hurst", [0.3, 0.75, 0.9])
def test_stein_structure_function_exact(hurst):
    fbm = FractionalBrownian(hurst, increment_rms=2.0, lag=3.0, dimension=2)
    shape, sp = (9, 11), (0.7, 0.4)
    plan, _ = _plan(fbm, shape, sp, False)
    cov = exact_covariance(plan)
    yy, xx = np.meshgrid(np.arange(shape[0]) * sp[0], np.arange(shape[1]) * sp[1], indexing="ij")
    p = np.stack([yy.ravel(), xx.ravel()], axis=1)
    # Stein's linear term √(2 c2) x·N (unit coordinates) is drawn separately: add its covariance
    _, c2, _ = _stein_coeffs(2 * hurst, plan.info["stein_R"])
    unit = plan.info["unit_length"]
    scale2 = fbm.increment_rms**2 * 0.5 * (unit / fbm.lag) ** (2 * hurst)
    cov = cov + scale2 * 2 * c2 * (p @ p.T) / unit**2
    var = np.diag(cov)
    d_real = var[:, None] + var[None, :] - 2 * cov
    r = np.hypot(p[:, None, 0] - p[None, :, 0], p[:, None, 1] - p[None, :, 1])
    np.testing.assert_allclose(d_real, fbm.structure_function(r), atol=1e-10 * d_real.max())
    assert plan.info["exact"]


@pytest.mark.parametrize(
    "rough",
    [
        GaussianCorrelation(1.5, 3.0, length_y=2.0),
        ExponentialCorrelation(0.5, 4.0),
        PowerLawCorrelation(1.0, 3.0, hurst=0.3),
        ExponentialCorrelation(1.0, 3.0, dimension=1),
    ],
)
def test_circulant_covariance_exact(rough):
    shape = (10, 12) if rough.dimension == 2 else 40
    plan, _ = _plan(rough, shape, 1.0, False)
    cov = exact_covariance(plan)
    if rough.dimension == 2:
        yy, xx = np.meshgrid(np.arange(10.0), np.arange(12.0), indexing="ij")
        y, x = yy.ravel(), xx.ravel()
        want = rough.sigma**2 * rough.correlation(x[:, None] - x[None, :], y[:, None] - y[None, :])
    else:
        x = np.arange(40.0)
        want = rough.sigma**2 * rough.correlation(x[:, None] - x[None, :])
    assert plan.info["exact"] and plan.info["min_eigenvalue_ratio"] >= -1e-10
    np.testing.assert_allclose(cov, want, atol=1e-9 * rough.sigma**2)


def test_circulant_pads_when_needed():
    # ℓ large against the grid: the minimal 2× embedding is indefinite, padding fixes it
    plan, _ = _plan(GaussianCorrelation(1.0, 6.0), (10, 10), 1.0, False)
    assert plan.full[0] > 18 and plan.info["padding"][0] > 1.5 and plan.info["exact"]


def test_periodic_stationary_covariance_is_periodized():
    # periodic synthesis: stationary on the torus, variance exactly σ²
    g = GaussianCorrelation(2.0, 3.0)
    plan, _ = _plan(g, (12, 16), 1.0, True)
    cov = exact_covariance(plan)
    np.testing.assert_allclose(np.diag(cov), 4.0, rtol=1e-12)
    c = cov[0].reshape(12, 16)
    # covariance depends on the lag only, wrapping around the period
    np.testing.assert_allclose(cov[17].reshape(12, 16), np.roll(np.roll(c, 1, 0), 1, 1), atol=1e-12)


# --------------------------------------------------------------------------- ensembles


def _check_mean(values, target, nsem=4.0, rel_floor=0.0, bias=0.0):
    v = np.asarray(values)
    sem = v.std(ddof=1) / math.sqrt(v.size)
    assert abs(v.mean() - (target + bias)) <= nsem * sem + rel_floor * abs(target), (
        f"mean {v.mean():.5g} vs {target + bias:.5g} (sem {sem:.2g})"
    )
    return sem


def test_gaussian_ensemble_sigma_acf_slope():
    ell = 16.0
    g = GaussianCorrelation(1.0, ell)
    surfs = generate_batch(g, 24, (384, 384), 1.0, seed=2024)
    sig = [s.realized_stats()["sigma"] for s in surfs]
    sem = _check_mean(sig, 1.0, nsem=3.0)
    assert sem < 0.012 and abs(np.mean(sig) - 1) < 0.02
    acfs = np.array([ensemble_acf(s.heights) for s in surfs])
    for lag in (0, 8, 16, 32):  # 0, ℓ/2, ℓ, 2ℓ
        for axis_vals in (acfs[:, 0, lag], acfs[:, lag, 0]):
            # mean removal biases the ACF by −Var(mean) ≈ −σ² π ℓ²/L²
            _check_mean(
                axis_vals,
                math.exp(-((lag / ell) ** 2)),
                bias=-math.pi * ell**2 / 384**2,
                rel_floor=0.0,
            )
    # rms slope by central differences vs analytic √(2σ²/ℓ²); FD bias −(dx/ℓ)² = −0.4 %
    analytic = g.mean_square_slope()
    for key, ms in (("rms_slope_x", analytic[0]), ("rms_slope_y", analytic[1])):
        slopes = [s.realized_stats()[key] for s in surfs]
        assert np.mean(slopes) == pytest.approx(math.sqrt(ms), rel=0.03)


def test_exponential_and_anisotropic_ensembles():
    e = ExponentialCorrelation(2.0, 8.0)
    surfs = generate_batch(e, 16, (256, 256), 1.0, seed=5)
    sig = [s.realized_stats()["sigma"] for s in surfs]
    _check_mean(sig, 2.0, nsem=3.0)
    assert abs(np.mean(sig) / 2.0 - 1) < 0.02
    acfs = np.array([ensemble_acf(s.heights) for s in surfs])
    for lag in (0, 4, 8, 16):
        _check_mean(
            acfs[:, 0, lag], 4.0 * math.exp(-lag / 8.0), bias=-4.0 * 2 * math.pi * 64 / 256**2
        )
    a = GaussianCorrelation(1.0, 16.0, length_y=6.0)
    surfs = generate_batch(a, 16, (256, 384), 1.0, seed=6)
    sig = [s.realized_stats()["sigma"] for s in surfs]
    _check_mean(sig, 1.0, nsem=3.0)
    acfs = np.array([ensemble_acf(s.heights) for s in surfs])
    bias = -math.pi * 16 * 6 / (256 * 384)
    for lag in (3, 6, 12):  # along y: ℓy/2, ℓy, 2ℓy
        _check_mean(acfs[:, lag, 0], math.exp(-((lag / 6.0) ** 2)), bias=bias)
    for lag in (8, 16, 32):  # along x
        _check_mean(acfs[:, 0, lag], math.exp(-((lag / 16.0) ** 2)), bias=bias)
    sx = np.mean([s.realized_stats()["rms_slope_x"] for s in surfs])
    sy = np.mean([s.realized_stats()["rms_slope_y"] for s in surfs])
    assert sx == pytest.approx(math.sqrt(2) / 16, rel=0.03)
    # ℓy = 6 samples: central-difference bias −(1/6)² ≈ −2.8 %; compare with the FD expectation
    assert sy == pytest.approx(math.sqrt((1 - math.exp(-4 / 36)) / 2), rel=0.03)


@pytest.mark.parametrize("hurst", [0.2, 0.5, 0.8])
def test_fbm_profiles_structure_function(hurst):
    f = FractionalBrownian(hurst, increment_rms=0.5, lag=4.0, dimension=1)
    hs = [s.heights for s in generate_batch(f, 40, 4096, 0.25, seed=int(hurst * 10))]
    lags = np.unique(np.round(np.logspace(0, 2.5, 10)).astype(int))
    d = structure_function(hs, lags)
    slope = np.polyfit(np.log(lags * 0.25), np.log(d), 1)[0]
    assert slope / 2 == pytest.approx(hurst, abs=0.03)
    for r in (1, 4, 16):  # amplitude within 4 standard errors of the ensemble
        ratios = structure_function_each(hs, r) / f.structure_function(r * 0.25)
        sem = _check_mean(ratios, 1.0, nsem=4.0)
        assert sem < 0.06  # H = 0.8 increments are long-range correlated: wide spread


@pytest.mark.parametrize("hurst", [0.2, 0.5, 0.8])
def test_fbm_surfaces_structure_function(hurst):
    f = FractionalBrownian(hurst, increment_rms=1e-3, lag=1e-2, dimension=2)
    surfs = generate_batch(f, 40, (256, 256), 1e-3, seed=int(hurst * 100))
    assert surfs[0].method == "stein-2002"
    hs = [s.heights for s in surfs]
    lags = np.array([1, 2, 4, 8, 16, 32])
    for axis in (0, 1):
        d = structure_function(hs, lags, axis=axis)
        slope = np.polyfit(np.log(lags), np.log(d), 1)[0]
        assert slope / 2 == pytest.approx(hurst, abs=0.03)
        # amplitude: per-realization D(r)/D_target(r), mean within 4 standard errors (the
        # increments of H > 1/2 are long-range correlated: one realization varies a lot)
        for r in (1, 4):
            ratios = structure_function_each(hs, r, axis) / f.structure_function(r * 1e-3)
            sem = _check_mean(ratios, 1.0, nsem=4.0)
            assert sem < 0.08  # power enough to see a 30 % amplitude error


def test_periodic_paths():
    # periodic: the wrap-around increment is statistically an ordinary one
    g = GaussianCorrelation(1.0, 8.0)
    surfs = generate_batch(g, 16, (128, 128), 1.0, seed=9, periodic=True)
    inner = np.mean([np.mean((s.heights[:, 1] - s.heights[:, 0]) ** 2) for s in surfs])
    wrap = np.mean([np.mean((s.heights[:, 0] - s.heights[:, -1]) ** 2) for s in surfs])
    assert wrap == pytest.approx(inner, rel=0.15)
    exact = generate_batch(g, 16, (128, 128), 1.0, seed=9)
    wrap_exact = np.mean([np.mean((s.heights[:, 0] - s.heights[:, -1]) ** 2) for s in exact])
    assert wrap_exact > 20 * inner  # a non-periodic surface does not close on itself
    # variance exactly σ² in expectation (no mean removal: E h² = σ²)
    ms = [np.mean(s.heights**2) for s in surfs]
    _check_mean(ms, 1.0, nsem=3.5)
    # periodic fBm: DC removed, spectrum a power law K^(−2(H+1)) on grid frequencies only
    h = 0.6
    f = FractionalBrownian(h, dimension=2)
    s = generate_surface(f, (256, 256), 1.0, periodic=True, rng=1)
    assert s.method == "fft-periodic" and s.periodic
    assert abs(s.heights.mean()) < 1e-12 * s.heights.std()
    p = np.abs(sfft.rfft2(s.heights)) ** 2
    ky = sfft.fftfreq(256)[:, None]
    kx = sfft.rfftfreq(256)[None, :]
    k = np.hypot(ky, kx).ravel()
    sel = (k > 0.02) & (k < 0.4)
    slope = np.polyfit(np.log(k[sel]), np.log(p.ravel()[sel]), 1)[0]
    assert slope == pytest.approx(-2 * (h + 1), abs=0.1)


# --------------------------------------------------------------------------- bad inputs

G2 = GaussianCorrelation(1.0, 4.0)
G1 = GaussianCorrelation(1.0, 4.0, dimension=1)

BAD = [
    (lambda: GaussianCorrelation(0.0, 1.0), ValueError, "sigma"),
    (lambda: GaussianCorrelation(-1.0, 1.0), ValueError, "sigma"),
    (lambda: ExponentialCorrelation(1.0, 0.0), ValueError, "length"),
    (lambda: GaussianCorrelation(1.0, float("nan")), ValueError, "length"),
    (lambda: FractionalBrownian(0.0), ValueError, "hurst"),
    (lambda: FractionalBrownian(1.0), ValueError, "hurst"),
    (lambda: FractionalBrownian(1.2), ValueError, "hurst"),
    (lambda: generate_surface(G2, (7, 16), 1.0), ValueError, "shape"),
    (lambda: generate_surface(G1, 4, 1.0), ValueError, "shape"),
    (lambda: generate_surface(G2, (16, 16, 16), 1.0), TypeError, "shape"),
    (lambda: generate_surface(G2, 16.0, 1.0), TypeError, "shape"),
    (lambda: generate_surface(G2, "16", 1.0), TypeError, "shape"),
    (lambda: generate_surface(G2, 16, 1.0), ValueError, "shape"),  # 2-D roughness, profile shape
    (lambda: generate_surface(G1, (16, 16), 1.0), ValueError, "dimension"),
    (lambda: generate_surface(G2, (16, 16), 0.0), ValueError, "spacing"),
    (lambda: generate_surface(G2, (16, 16), -1.0), ValueError, "spacing"),
    (lambda: generate_surface(G2, (16, 16), float("nan")), ValueError, "spacing"),
    (lambda: generate_surface(G2, (16, 16), float("inf")), ValueError, "spacing"),
    (lambda: generate_surface(G2, (16, 16), (1.0, 1.0, 1.0)), ValueError, "spacing"),
    (lambda: generate_surface(G2, (16, 16), "1"), TypeError, "spacing"),
    (lambda: generate_surface(G2, (16, 16), 5.0), ValueError, "correlation length"),
    (lambda: generate_surface(G1, 64, 4.5), ValueError, "spacing"),
    (
        lambda: generate_surface(GaussianCorrelation(1.0, 4.0, length_y=0.5), (16, 16), 1.0),
        ValueError,
        "length_y",
    ),
    (
        lambda: generate_surface(ExponentialCorrelation(1.0, 0.5), (16, 16), 1.0),
        ValueError,
        "spacing",
    ),
    (lambda: generate_surface(G2, (16, 16), 1.0, rng=np.random.RandomState(0)), TypeError, "rng"),
    (lambda: generate_surface(G2, (16, 16), 1.0, rng=1.5), TypeError, "rng"),
    (lambda: generate_surface(G2, (16, 16), 1.0, rng="seed"), TypeError, "rng"),
    (lambda: generate_surface(G2, (16, 16), 1.0, rng=-3), ValueError, "rng"),
    (lambda: generate_surface(G2, (16, 16), 1.0, periodic="yes"), TypeError, "periodic"),
    (lambda: generate_surface("gaussian", (16, 16), 1.0), TypeError, "roughness"),
    (lambda: generate_batch(G2, 0, (16, 16), 1.0, seed=1), ValueError, "count"),
    (lambda: generate_batch(G2, 2, (16, 16), 1.0, seed=-1), TypeError, "seed"),
    (lambda: generate_batch(G2, 2, (16, 16), 1.0, seed=None), TypeError, "seed"),
]


@pytest.mark.parametrize("call,exc,word", BAD, ids=[f"bad{i}" for i in range(len(BAD))])
def test_bad_inputs_raise_naming_parameter(call, exc, word):
    with pytest.raises(exc, match=word):
        call()
