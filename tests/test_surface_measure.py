"""Rough-surface measurement (emscatter.surfaces.measure): seeded ensembles against the
analytic statistics of the spectra module, exact fBm, and surfaces made by another library.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from emscatter.spectra import ExponentialCorrelation, FractionalBrownian, GaussianCorrelation
from emscatter.surfaces import measure as M
from emscatter.surfaces.generate import generate_batch

DX = 1e-3  # [m]


# --------------------------------------------------------------------------- ensembles
@pytest.fixture(scope="module")
def gaussian_maps():
    rough = GaussianCorrelation(sigma=1.0, length=16 * DX)
    # The realized σ of one 512² map with ℓ = 16 samples scatters by ≈ 2.7 % (≈ L²/(πℓ²)
    # independent patches), so the 32-map mean has a standard error of ≈ 0.5 %: the 1 %
    # tolerance of the issue is 2 standard errors (seeds 0–5 give 0.988–1.005).
    return rough, [s.heights for s in generate_batch(rough, 32, (512, 512), DX, seed=0)]


@pytest.fixture(scope="module")
def exponential_maps():
    rough = ExponentialCorrelation(sigma=1.0, length=16 * DX)
    return rough, [s.heights for s in generate_batch(rough, 32, (512, 512), DX, seed=7)]


# 512 samples are 32 correlation lengths of 16: right at the ~30 threshold, so the fitted ℓ
# (±3 % per map) sometimes crosses it and warns; these ensembles accept that warning.
at_threshold = pytest.mark.filterwarnings("ignore::emscatter.surfaces.measure.ShortRecordWarning")


@at_threshold
def test_gaussian_sigma_length_slope(gaussian_maps):
    rough, maps = gaussian_maps
    sig = np.mean([M.rms_height(h) for h in maps])
    assert sig == pytest.approx(1.0, rel=0.01)
    cl = [M.correlation_length(h, DX, "gaussian") for h in maps]
    for attr in ("length", "length_x", "length_y"):
        assert np.mean([getattr(c, attr) for c in cl]) == pytest.approx(16 * DX, rel=0.03), attr
    # 1/e lag of exp(-r²/ℓ²) is ℓ as well
    l_e = np.mean([M.correlation_length(h, DX, "1/e").length for h in maps])
    assert l_e == pytest.approx(16 * DX, rel=0.03)
    # analytic slopes: per direction √(2σ²/ℓ²), total √(4σ²/ℓ²) (spectra.mean_square_slope).
    # Forward difference: E[Δh²]/dx² = 2σ²(1−ρ(dx))/dx², relative bias −dx²/(2ℓ²) = −0.2 %
    # in ⟨h_x²⟩ at ℓ = 16 dx (central differences: −0.8 %); the spectral slope has none.
    sx_true = math.sqrt(rough.mean_square_slope()[0])
    tot_true = math.sqrt(rough.total_mean_square_slope())
    for method in ("difference", "spectral"):
        s = [M.rms_slope(h, DX, method) for h in maps]
        assert np.mean([v.x for v in s]) == pytest.approx(sx_true, rel=0.03), method
        assert np.mean([v.y for v in s]) == pytest.approx(sx_true, rel=0.03), method
        assert np.mean([v.total for v in s]) == pytest.approx(tot_true, rel=0.03), method


@at_threshold
def test_exponential_sigma_length(exponential_maps):
    rough, maps = exponential_maps
    assert np.mean([M.rms_height(h) for h in maps]) == pytest.approx(1.0, rel=0.01)
    cl = [M.correlation_length(h, DX, "exponential") for h in maps]
    assert np.mean([c.length for c in cl]) == pytest.approx(16 * DX, rel=0.03)
    # the per-axis fits use one line of the ACF, which for this long-tailed correlation is
    # ≈ 2× noisier (seeds 0, 1, 2, 7: within −3.1 … +1.2 %)
    for attr in ("length_x", "length_y"):
        assert np.mean([getattr(c, attr) for c in cl]) == pytest.approx(16 * DX, rel=0.05), attr
    # a Gaussian model fitted to it is visibly wrong (the fit can tell the two apart)
    lg = np.mean([M.correlation_length(h, DX, "gaussian").length for h in maps[:4]])
    assert abs(lg / (16 * DX) - 1) > 0.05
    # finite-difference slope of a non-differentiable surface: 2σ²(1−e^(−dx/ℓ))/dx²
    sx = np.mean([M.rms_slope(h, DX).x for h in maps])
    assert sx == pytest.approx(math.sqrt(2 * (1 - math.exp(-1 / 16))) / DX, rel=0.02)


def test_psd_normalization(gaussian_maps):
    rough, maps = gaussian_maps
    ps = [M.psd(h, DX) for h in maps]
    k = ps[0].k
    p = np.mean([q.psd for q in ps], axis=0)
    dk = 2 * math.pi / (512 * DX)
    # ∫ psd d²K = ∫ 2πK psd dK ≈ σ² (radial bins of width dk up to Nyquist; corners excluded,
    # where this spectrum is negligible)
    assert np.sum(2 * math.pi * k * p * dk) == pytest.approx(1.0, rel=0.03)
    # shape: σ² w(K) where the spectrum is well above the window leakage floor
    # (bins from 4 Fourier steps up, away from the Hann-smoothed peak; ≥ 25·32 modes a bin)
    sel = (k > 3.5 * dk) & (k < 2.5 / rough.length)
    ratio = p[sel] / rough.height_spectrum(k[sel])
    assert np.all(np.abs(ratio - 1) < 0.12), ratio
    assert np.mean(ratio) == pytest.approx(1.0, abs=0.03)
    # 1-D profiles: 2 ∫_0^∞ psd dk ≈ σ², shape σ² w(k)
    prof = rough.profile()
    rows = np.concatenate([h[::64] for h in maps])
    p1 = np.mean([M.psd(r, DX).psd for r in rows], axis=0)
    k1 = M.psd(rows[0], DX).k
    dk1 = k1[1] - k1[0]
    # the two-sided integral counts k = 0 and the Nyquist wavenumber once; it returns the
    # realized variance, which the mean removal lowers by ≈ √π ℓ/L = 5.5 % for 32ℓ profiles
    var_realized = np.mean([M.rms_height(r) ** 2 for r in rows])
    assert var_realized == pytest.approx(1 - math.sqrt(math.pi) / 32, rel=0.03)
    assert (2 * np.sum(p1) - p1[0] - p1[-1]) * dk1 == pytest.approx(var_realized, rel=0.02)
    sel = (k1 > 2 * dk1) & (k1 < 2.5 / prof.length)
    assert np.all(np.abs(p1[sel] / prof.height_spectrum(k1[sel]) - 1) < 0.15)


def test_autocorrelation_matches_model(gaussian_maps):
    rough, maps = gaussian_maps
    a = M.autocorrelation(maps[0], DX, max_lag=40 * DX)
    ly, lx = a.lags
    assert a.acf[0, lx.size // 2] == pytest.approx(1.0)
    mean_acf = np.mean([M.autocorrelation(h, DX, max_lag=40 * DX).acf for h in maps], axis=0)
    model = rough.correlation(lx[None, :], ly[:, None])
    assert np.max(np.abs(mean_acf - model)) < 0.03
    a1 = M.autocorrelation(maps[0][0], DX)
    assert a1.acf[0] == pytest.approx(1.0) and a1.lags[1] == pytest.approx(DX)


# --------------------------------------------------------------------------- Hurst
@pytest.mark.parametrize("hurst", [0.2, 0.5, 0.8])
def test_hurst_exact_fbm(hurst):
    """Default estimator (aliased log-periodogram): mean within ±0.02 over 20 exact fBm
    realizations, 2-D 512² (Stein 2002) and 1-D 2¹⁴ (Davies–Harte); the structure function
    scales as r^(2H) (variogram slope) with the fBm's level."""
    maps = generate_batch(FractionalBrownian(hurst, 1.0, 1.0, 2), 20, (512, 512), 1.0, seed=11)
    res = [M.hurst_exponent(s.heights, s.spacing) for s in maps]
    assert res[0].method == "periodogram"
    assert np.mean([r.hurst for r in res]) == pytest.approx(hurst, abs=0.02)
    assert np.mean([r.slope for r in res]) == pytest.approx(-(2 * hurst + 2), abs=0.04)
    # its standard error is calibrated: of the size of the scatter between realizations
    sd = np.std([r.hurst for r in res], ddof=1)
    assert 0.5 < np.mean([r.stderr for r in res]) / sd < 2.0
    # structure function: slope 2H, level increment_rms² = 1 at lag 1 (log S(1) = 0)
    vg = [M.hurst_exponent(s.heights, 1.0, "variogram") for s in maps]
    assert np.mean([r.slope for r in vg]) == pytest.approx(2 * hurst, abs=0.04)
    assert np.mean([r.intercept for r in vg]) == pytest.approx(0.0, abs=0.1)
    profs = generate_batch(FractionalBrownian(hurst, 1.0, 1.0, 1), 20, 2**14, 1.0, seed=12)
    res1 = [M.hurst_exponent(s.heights, 1.0) for s in profs]
    assert np.mean([r.hurst for r in res1]) == pytest.approx(hurst, abs=0.02)
    assert res1[0].fractal_dimension == pytest.approx(2 - res1[0].hurst)
    # the variogram (slope 2H) and the madogram (slope H) agree on the same records
    for method, order in (("variogram", 2), ("madogram", 1)):
        r1 = [M.hurst_exponent(s.heights, 1.0, method) for s in profs]
        assert np.mean([r.hurst for r in r1]) == pytest.approx(hurst, abs=0.02)
        assert np.mean([r.slope for r in r1]) == pytest.approx(order * hurst, abs=0.02 * order)


@pytest.mark.parametrize("hurst", [0.2, 0.5, 0.8])
def test_hurst_surfacetopography(hurst):
    """Cross-check on SurfaceTopography's periodic self-affine surfaces (Fourier synthesis,
    PSD C0 q^(−2−2H) cut off at π/dx). They are band-limited, so the variogram is biased at
    small lags (local slope → 1); the periodogram of a periodic record (window=None) is the
    matching estimator, and reaches the same ±0.02."""
    gen = pytest.importorskip("SurfaceTopography.Generation")
    rng = np.random.default_rng(5)
    h2 = [
        M.hurst_exponent(
            gen.fourier_synthesis(
                (512, 512), (1.0, 1.0), hurst=hurst, rms_height=1.0, rng=rng
            ).heights(),
            1 / 512,
            "periodogram",
            window=None,
        ).hurst
        for _ in range(20)
    ]
    assert np.mean(h2) == pytest.approx(hurst, abs=0.02)
    h1 = [
        M.hurst_exponent(
            gen.fourier_synthesis((2**14,), (1.0,), hurst=hurst, rms_height=1.0, rng=rng).heights(),
            2**-14,
            "periodogram",
            window=None,
        ).hurst
        for _ in range(20)
    ]
    assert np.mean(h1) == pytest.approx(hurst, abs=0.02)


def test_variogram_on_exact_fbm_maps():
    """The variogram on exact 2-D fBm: unbiased within its scatter at H = 0.5."""
    maps = generate_batch(FractionalBrownian(0.5, 1.0, 1.0, 2), 8, (512, 512), 1.0, seed=3)
    hs = [M.hurst_exponent(s.heights, 1.0, "variogram").hurst for s in maps]
    assert np.mean(hs) == pytest.approx(0.5, abs=3 * np.std(hs, ddof=1) / math.sqrt(8) + 1e-3)


def test_box_counting_fbm_and_its_bias():
    """Box counting gives D between d and d+1, increasing as H decreases, and is biased
    toward d for rough records (measured in validation/hurst_estimators.md)."""
    d2 = []
    for hurst in (0.2, 0.8):
        s = generate_batch(FractionalBrownian(hurst, 1.0, 1.0, 2), 2, (512, 512), 1.0, seed=4)
        d2.append(np.mean([M.box_counting_dimension(x.heights, 1.0).dimension for x in s]))
    assert 2.0 < d2[1] < d2[0] < 3.0
    assert d2[0] < 3 - 0.2 - 0.05  # biased low for H = 0.2 (true D = 2.8)
    p = generate_batch(FractionalBrownian(0.5, 1.0, 1.0, 1), 1, 2**14, 1.0, seed=4)[0]
    b = M.box_counting_dimension(p.heights, 1.0)
    assert 1.0 < b.dimension < 2.0 and b.r2 > 0.98
    assert b.hurst == pytest.approx(2 - b.dimension)
    # a smooth plane is 2-dimensional, a straight line 1-dimensional
    yy, xx = np.mgrid[0:256, 0:256]
    assert M.box_counting_dimension(0.3 * xx + 0.1 * yy, 1.0).dimension == pytest.approx(
        2, abs=0.02
    )
    assert M.box_counting_dimension(np.arange(4096.0), 1.0).dimension == pytest.approx(1, abs=0.02)


@at_threshold
def test_summarize_and_surface_measure(gaussian_maps):
    _, maps = gaussian_maps
    out = M.summarize(maps[0], DX, hurst=True)
    assert out["rms_height"] == pytest.approx(M.rms_height(maps[0]))
    assert out["correlation_length"] == pytest.approx(16 * DX, rel=0.1)
    for m in M.HURST_METHODS:
        assert math.isfinite(out[f"hurst_{m}"]) and out[f"hurst_{m}_stderr"] > 0
        assert out[f"fractal_dimension_{m}"] == pytest.approx(3 - out[f"hurst_{m}"])
    assert 2 <= out["box_counting_dimension"] <= 3
    # a smooth Gaussian surface is not self-affine: the periodogram fit says so
    assert any("not self-affine" in w for w in out["warnings"])
    s = generate_batch(FractionalBrownian(0.7, 1.0, 1.0, 2), 1, (256, 256), 1.0, seed=1)[0]
    res = s.measure(hurst=True)
    assert "correlation_length" in res and isinstance(res["warnings"], list)
    assert res["hurst_variogram"] == pytest.approx(0.7, abs=0.1)


# --------------------------------------------------------------------------- bad input
def test_not_self_affine_warns():
    white = np.random.default_rng(2).standard_normal((128, 128))
    with pytest.warns(RuntimeWarning, match=r"reached the bound.*H = 0\.00"):
        M.hurst_exponent(white, 1.0)


def test_short_record_warns():
    rough = GaussianCorrelation(sigma=1.0, length=16.0)
    h = generate_batch(rough, 1, (256, 256), 1.0, seed=0)[0].heights
    with pytest.warns(M.ShortRecordWarning, match=r"1[56]\.\d correlation lengths \(< 30\)"):
        M.correlation_length(h, 1.0)


GOOD2 = np.random.default_rng(0).standard_normal((16, 16))


@pytest.mark.parametrize(
    "call, exc, match",
    [
        (
            lambda: M.rms_height(np.r_[np.ones(9), np.nan]),
            ValueError,
            "heights must be finite.*nan",
        ),
        (
            lambda: M.rms_height(np.r_[np.ones(9), np.inf]),
            ValueError,
            "heights must be finite.*inf",
        ),
        (lambda: M.rms_height(np.ones(7)), ValueError, "at least 8 samples.*\\(7,\\)"),
        (lambda: M.rms_slope(np.ones((8, 5)), 1.0), ValueError, "at least 8.*\\(8, 5\\)"),
        (lambda: M.psd(np.ones((8, 8, 8)), 1.0), ValueError, "ndim 1.*or 2.*ndim=3"),
        (lambda: M.rms_height(5.0), ValueError, "ndim=0"),
        (lambda: M.rms_height(np.array(["a"] * 9)), TypeError, "heights.*real"),
        (lambda: M.rms_slope(GOOD2, 0.0), ValueError, "spacing must be finite and > 0.*0.0"),
        (lambda: M.rms_slope(GOOD2, -1e-3), ValueError, "spacing.*> 0.*-0.001"),
        (lambda: M.rms_slope(GOOD2, (1.0, -1.0)), ValueError, "spacing.*> 0"),
        (lambda: M.rms_slope(GOOD2, np.nan), ValueError, "spacing.*nan"),
        (lambda: M.rms_slope(GOOD2, (1.0, 1.0, 1.0)), ValueError, "spacing.*\\(dy, dx\\)"),
        (lambda: M.rms_slope(GOOD2, "1"), TypeError, "spacing"),
        (lambda: M.rms_slope(GOOD2, 1.0, "central"), ValueError, "method.*difference.*central"),
        (lambda: M.hurst_exponent(GOOD2, 1.0, "dfa"), ValueError, "method.*variogram.*'dfa'"),
        (lambda: M.correlation_length(GOOD2, 1.0, "cauchy"), ValueError, "model.*'cauchy'"),
        (lambda: M.psd(GOOD2, 1.0, window="kaiser"), ValueError, "window.*hann.*kaiser"),
        (
            lambda: M.hurst_exponent(np.arange(64.0) ** 0.5, 1.0, "variogram", lags=[1, 2, 40]),
            ValueError,
            "lags must be.*\\[1, 31\\]",
        ),
        (
            lambda: M.hurst_exponent(np.arange(64.0), 1.0, "periodogram", band=(0.5, 0.2)),
            ValueError,
            "band must be.*0 <= low < high <= 1.*0.5",
        ),
        (
            lambda: M.box_counting_dimension(np.arange(64.0), 1.0, sizes=[1, 2, 64]),
            ValueError,
            "sizes must be.*\\[1, 32\\]",
        ),
        (lambda: M.hurst_exponent(GOOD2, 1.0, groups=1), ValueError, "groups.*>= 2.*1"),
        (
            lambda: M.hurst_exponent(np.add.outer(np.arange(64.0), np.arange(64.0)), 1.0),
            ValueError,
            "periodogram vanishes",
        ),
        (
            lambda: M.hurst_exponent(GOOD2, 1.0, "periodogram", lags=[1, 2, 3]),
            ValueError,
            "lags is used by the variogram and madogram methods only",
        ),
        (
            lambda: M.hurst_exponent(GOOD2, 1.0, "variogram", band=(0, 0.5)),
            ValueError,
            "band is used by the periodogram method only",
        ),
        (
            lambda: M.hurst_exponent(GOOD2, 1.0, window="hamming"),
            ValueError,
            "window.*hann.*hamming",
        ),
        (
            lambda: M.correlation_length(np.random.default_rng(1).standard_normal(64), 1.0),
            ValueError,
            "spacing is coarser than the correlation length",
        ),
    ],
)
def test_bad_input(call, exc, match):
    with pytest.raises(exc, match=match):
        call()
