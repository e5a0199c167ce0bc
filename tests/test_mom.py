"""Method of moments for 1-D rough surfaces: laws, convergence, published agreement.

Lengths in wavelengths (λ = 1 m, k = 2π rad/m).
"""

from __future__ import annotations

import math
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest
from scipy import special

from emscatter.fresnel import fresnel
from emscatter.solvers.kirchhoff import po as kirchhoff_po
from emscatter.solvers.mom import model as mom
from emscatter.solvers.mom.operators import hankel01, self_single, solve_fb, solve_lu
from emscatter.solvers.spm import model as spm
from emscatter.spectra import GaussianCorrelation
from emscatter.surfaces.generate import generate_surface

K = 2 * math.pi


def grid(length: float, ppw: float) -> tuple[np.ndarray, float]:
    dx = 1.0 / ppw
    n = int(round(length / dx))
    return (np.arange(n) - (n - 1) / 2) * dx, dx


def rough_heights(sigma, ell, n, dx, seed):
    return generate_surface(GaussianCorrelation(sigma, ell, dimension=1), n, dx, rng=seed).heights


# --------------------------------------------------------------------------- kernels


def test_hankel_matches_scipy_real_and_complex():
    z = np.concatenate([np.linspace(0.01, 60, 6001), np.geomspace(60, 5e3, 500)])
    h0, h1 = hankel01(z)
    np.testing.assert_allclose(h0, special.hankel1(0, z), rtol=5e-7)
    np.testing.assert_allclose(h1, special.hankel1(1, z), rtol=5e-7)
    zc = z * (4.1 + 0.25j) / abs(4.1 + 0.25j)  # lossy medium 2 (Im k2 > 0)
    h0, h1 = hankel01(zc)
    keep = zc.imag < 30
    np.testing.assert_allclose(h0[keep], special.hankel1(0, zc[keep]), rtol=1e-7)
    np.testing.assert_allclose(h1[keep], special.hankel1(1, zc[keep]), rtol=1e-7)


def test_single_layer_rule_converges_at_third_order():
    """Trapezoidal rule + Sidi–Israeli self weight for ∫(i/4)H0(k|x−x'|)u(x')dx' with a
    smooth, oscillating density: error falls ≥ 6× per halving of dx (O(dx³))."""
    kx, w = K * 0.5, 4.0

    def row(ppw):
        x, dx = grid(40.0, ppw)
        x = x - x[np.argmin(np.abs(x))]  # node at 0
        m = np.argmin(np.abs(x))
        r = np.abs(x)
        r[m] = 1.0
        h0, _ = hankel01(K * r, True, False)
        s = 0.25j * dx * h0
        s[m] = self_single(dx, K, np.zeros(1))[0]
        return s @ (np.exp(1j * kx * x - (x / w) ** 2))

    ref = row(160)
    e10, e20, e40 = (abs(row(p) / ref - 1) for p in (10, 20, 40))
    assert e10 < 3e-3
    assert e10 / e20 > 6 and e20 / e40 > 6


@pytest.mark.parametrize("theta_deg", [0.0, 30.0, 60.0])
def test_incident_power_quadrature_equals_thorsos_closed_form(theta_deg):
    # Thorsos (1988), incident power of the tapered wave:
    # P = g√(π/2) cosθi [1 − (1 + 2tan²θi)/(2k²g²cos²θi)]
    th = math.radians(theta_deg)
    for g in (3.0, 10.0):
        assert mom.incident_power(K, th, g) == pytest.approx(
            mom.incident_power_thorsos(K, th, g), rel=1e-10
        )


def test_forward_backward_matches_lu_and_falls_back():
    x, dx = grid(30.0, 10)
    h = rough_heights(0.1, 1.0, x.size, dx, 5)
    lu = mom.solve_realization(x, h, "pec", K, 0.4, polarization="h", solver="lu", energy=False)
    fb = mom.solve_realization(x, h, "pec", K, 0.4, polarization="h", solver="fb", energy=False)
    assert fb.solver == "fb" and fb.residual < 1e-6
    np.testing.assert_allclose(fb.amplitude, lu.amplitude, rtol=1e-4, atol=1e-6)
    bad = mom.solve_realization(
        x, h, "pec", K, 0.4, polarization="h", solver="fb", max_iter=1, energy=False
    )
    assert bad.solver == "lu-fallback"
    np.testing.assert_allclose(bad.amplitude, lu.amplitude, rtol=1e-10, atol=1e-12)
    # the residual that FB reports is the true one
    a = np.random.default_rng(0).standard_normal((64, 64)) * 0.05 + np.eye(64) * 2
    b = np.ones(64, complex)
    sol, ok, _, res, _ = solve_fb(a.astype(complex), b, block=8, tol=1e-12)
    assert ok
    assert np.linalg.norm(a @ sol - b) / np.linalg.norm(b) == pytest.approx(res, abs=1e-15)
    np.testing.assert_allclose(sol, solve_lu(a.astype(complex).copy(), b), rtol=1e-8)


# --------------------------------------------------------------------------- flat surface


@pytest.mark.parametrize("theta_deg", [0.0, 30.0, 60.0])
def test_flat_pec_reflects_minus_one_te_plus_one_tm(theta_deg):
    x, _ = grid(40.0, 10)
    th = math.radians(theta_deg)
    for pol, expected in (("h", -1.0), ("v", 1.0)):
        r = mom.solve_realization(x, np.zeros_like(x), "pec", K, th, polarization=pol)
        assert abs(r.reflection_coefficient - expected) < 3e-3, (pol, r.reflection_coefficient)
        assert abs(r.reflected - 1) < 1e-3


@pytest.mark.parametrize(("eps", "length"), [(4.0, 20.0), (17 + 2j, 12.0)])
def test_flat_dielectric_gives_fresnel(eps, length):
    ppw = 10 * abs(np.sqrt(eps))
    x, _ = grid(length, ppw)
    th = math.radians(30)
    rh, rv = fresnel(eps, th)
    for pol, ref in (("h", rh), ("v", rv)):
        r = mom.solve_realization(x, np.zeros_like(x), eps, K, th, polarization=pol)
        assert abs(r.reflection_coefficient - ref) < 3e-3, (pol, r.reflection_coefficient, ref)
        assert r.reflected == pytest.approx(abs(ref) ** 2, abs=3e-3)
        # energy: reflected + transmitted (far field in medium 2 if lossless, else flux)
        assert abs(r.energy_error) < 1e-3


# --------------------------------------------------------------------------- rough surface laws


@pytest.mark.parametrize("seed", [1, 2])
def test_rough_pec_conserves_energy_per_realization(seed):
    # Tsang et al. (2001) vol. II ch. 4 (energy check): scattered power = incident power for a PEC
    x, dx = grid(40.0, 10)
    h = rough_heights(0.1, 1.0, x.size, dx, seed)  # kσ = 0.63, kℓ = 6.3, rms slope 0.14
    for pol in ("h", "v"):
        r = mom.solve_realization(x, h, "pec", K, math.radians(20), polarization=pol)
        assert abs(r.energy_error) < 1e-3, (pol, r.energy_error)


def test_rough_lossless_dielectric_conserves_energy():
    eps = 4.0
    x, dx = grid(20.0, 20)
    h = rough_heights(0.05, 0.7, x.size, dx, 3)
    for pol in ("h", "v"):
        r = mom.solve_realization(x, h, eps, K, math.radians(30), polarization=pol)
        assert 0.05 < r.reflected < 0.3
        assert abs(r.reflected + r.transmitted - 1) < 1e-2, (pol, r.reflected, r.transmitted)
        # the flux through the surface tells the same story as the far field below it
        assert r.absorbed_flux == pytest.approx(r.transmitted, abs=5e-3)


@pytest.mark.parametrize("eps", ["pec", 4.0])
def test_results_converge_from_10_to_20_points_per_wavelength(eps):
    n_eff = 1.0 if eps == "pec" else 2.0
    x20, dx20 = grid(30.0, 20 * n_eff)
    h20 = rough_heights(0.1, 1.0, x20.size, dx20, 11)
    x10, h10 = x20[::2], h20[::2]  # the same surface, every other sample
    ts = np.radians(np.linspace(-80, 80, 161))
    for pol in ("h", "v"):
        kw = dict(polarization=pol, theta_s=ts, energy=False)
        s10 = mom.solve_realization(x10, h10, eps, K, math.radians(30), **kw).sigma
        s20 = mom.solve_realization(x20, h20, eps, K, math.radians(30), **kw).sigma
        strong = s20 > s20.max() / 1000  # within 30 dB of the peak (avoids speckle nulls)
        assert strong.sum() > 50
        ddb = np.abs(10 * np.log10(s10[strong] / s20[strong]))
        assert ddb.max() < 0.1, (pol, ddb.max())


# --------------------------------------------------------------------------- bad inputs


def test_bad_inputs_raise_or_warn():
    x, dx = grid(30.0, 10)
    h = np.zeros_like(x)
    with pytest.raises(ValueError, match="points per wavelength"):
        mom.solve_realization(x[::3], h[::3], "pec", K, 0.3, polarization="h")
    with pytest.warns(mom.MomWarning, match="points per wavelength"):
        mom.solve_realization(x[::2], h[::2], "pec", K, 0.3, polarization="h", energy=False)
    with pytest.raises(ValueError, match="taper_g"):
        mom.solve_realization(x, h, "pec", K, 0.3, polarization="h", taper_g=20.0)
    with pytest.warns(mom.MomWarning, match="L/4"):
        mom.solve_realization(x, h, "pec", K, 0.3, polarization="h", taper_g=10.0, energy=False)
    with pytest.warns(mom.MomWarning, match="too narrow"):
        mom.solve_realization(x, h, "pec", K, 1.4, polarization="h", taper_g=2.0, energy=False)
    bad = h.copy()
    bad[7] = np.nan
    with pytest.raises(ValueError, match="heights must be finite"):
        mom.solve_realization(x, bad, "pec", K, 0.3, polarization="h")
    with pytest.raises(ValueError, match="same length"):
        mom.solve_realization(x, h[:-1], "pec", K, 0.3, polarization="h")
    xn = x.copy()
    xn[10] += 0.03
    with pytest.raises(ValueError, match="uniformly spaced"):
        mom.solve_realization(xn, h, "pec", K, 0.3, polarization="h")
    with pytest.raises(ValueError, match="polarization"):
        mom.solve_realization(x, h, "pec", K, 0.3, polarization="x")
    with pytest.raises(ValueError, match="Im"):
        mom.solve_realization(x, h, 4 - 1j, K, 0.3, polarization="h")
    rough2d = GaussianCorrelation(0.1, 1.0)
    with pytest.raises(ValueError, match="dimension=1"):
        mom.bistatic(rough2d, "pec", K, 0.3, 0.3, realizations=2, progress=False)
    rough = GaussianCorrelation(0.1, 1.0, dimension=1)
    with pytest.raises(ValueError, match="plane of incidence"):
        mom.bistatic(rough, "pec", K, 0.3, 0.3, phi_s=1.0, realizations=2, progress=False)
    with pytest.raises(ValueError, match="n_realizations"):
        mom.bistatic(rough, "pec", K, 0.3, 0.3, realizations=1, progress=False)
    assert not mom.check_validity(rough2d, K)["valid"]
    rep = mom.check_validity(rough, K, points_per_wavelength=5)
    assert not rep["valid"] and "points per wavelength" in rep["reasons"][0]
    assert mom.check_validity(rough, K)["valid"]


# --------------------------------------------------------------------------- Monte Carlo


def test_bistatic_contract_energy_and_reproducibility():
    rough = GaussianCorrelation(0.05, 1.0, dimension=1)
    ts = np.radians([0.0, 15.0, 30.0, 45.0, 60.0])
    ps = np.array([0.0, 0.0, 0.0, math.pi, math.pi])
    kw = dict(realizations=4, seed=7, length=30.0, progress=False)
    res = mom.bistatic(rough, "pec", K, math.radians(30), ts, ps, **kw)
    assert res.sigma0.shape == (2, 2, 5) and res.coherent.shape == (2, 5)
    assert res.dimension == 1 and res.method == "mom"
    assert np.all(res.hv == 0) and np.all(res.vh == 0)
    assert np.all(res.hh > 0) and np.all(res.vv > 0)
    assert res.info["standard_error"].shape == (2, 2, 5)
    for p in ("h", "v"):
        s = res.info["per_polarization"][p]
        # coherent + incoherent = total scattered = 1 for a perfect conductor
        assert s["coherent_reflectivity"] + s["incoherent_reflectivity"] == pytest.approx(
            s["reflected"], rel=1e-9
        )
        assert abs(s["reflected"] - 1) < 1e-3
        assert 0.3 < s["coherent_reflectivity"] < 1.0
    with ThreadPoolExecutor(2) as ex:
        again = mom.bistatic(rough, "pec", K, math.radians(30), ts, ps, executor=ex, **kw)
    np.testing.assert_array_equal(again.sigma0, res.sigma0)
    np.testing.assert_array_equal(again.coherent, res.coherent)
    # an array of incidence angles (as emscatter.bistatic passes it) = one run per angle
    ti = np.where(np.arange(5) < 3, math.radians(30), math.radians(45))
    many = mom.bistatic(rough, "pec", K, ti, ts, ps, **kw)
    np.testing.assert_allclose(many.sigma0[..., :3], res.sigma0[..., :3], rtol=1e-12)
    other = mom.bistatic(rough, "pec", K, math.radians(45), ts[3:], ps[3:], **kw)
    np.testing.assert_allclose(many.sigma0[..., 3:], other.sigma0, rtol=1e-12)
    only_h = mom.bistatic(rough, "pec", K, math.radians(30), ts, ps, polarizations="h", **kw)
    assert np.all(np.isnan(only_h.vv)) and only_h.info["not_computed"] == ["v"]
    np.testing.assert_array_equal(only_h.hh, res.hh)


SPM_SEED = 3
PO_SEED = 4


def _window_db(res, signed, lo_deg, hi_deg, p):
    sel = (signed >= math.radians(lo_deg)) & (signed <= math.radians(hi_deg))
    return 10 * np.log10(res.sigma0[p, p][sel].mean())


def _signed_grid():
    t = np.radians(np.arange(0.0, 86.0, 1.0))
    th = np.concatenate([t, t[1:]])
    ph = np.concatenate([np.zeros_like(t), np.full(t.size - 1, math.pi)])
    return th, ph, np.where(ph == 0, th, -th)


@pytest.mark.slow
def test_agrees_with_first_order_spm_at_small_k_sigma():
    """Thorsos & Jackson (1989, JASA 86, 261): first-order perturbation theory is accurate
    for kσ ≪ 1 (here kσ = 0.1, kℓ = 3, Gaussian spectrum, θi = 30°). σ⁰ averaged over 30–40°
    wide angular windows (away from the coherent lobe) within 0.5 dB, PEC TE and TM; the
    Monte Carlo error of a window mean is ~0.1–0.2 dB with 48 realizations of 60 λ."""
    rough = GaussianCorrelation(0.1 / K, 3.0 / K, dimension=1)
    th, ph, signed = _signed_grid()
    ti = math.radians(30)
    res = mom.bistatic(rough, "pec", K, ti, th, ph, realizations=48, seed=SPM_SEED,
                       length=60.0, progress=False)  # fmt: skip
    ref = spm.bistatic(rough, "pec", K, ti, th, ph)
    # coherent reflectivity vs the second-order SPM coherent term (Tsang vol. III)
    np.testing.assert_allclose(res.coherent[:, 0], ref.coherent[:, 0], atol=0.01)
    for lo, hi in ((-80, -40), (-40, -10), (-10, 22), (38, 80)):
        for p in (0, 1):
            d = _window_db(res, signed, lo, hi, p) - _window_db(ref, signed, lo, hi, p)
            assert abs(d) < 0.5, (lo, hi, p, d)


@pytest.mark.slow
def test_agrees_with_physical_optics_for_large_k_ell():
    """Thorsos (1988, JASA 83, 78): the Kirchhoff approximation holds for kℓ ≳ 6 at moderate
    kσ (here kℓ = 8, kσ = 0.5, θi = 30°, Gaussian spectrum). σ⁰ averaged over 10° windows
    of the main lobe (within 10 dB of PO's peak; single-scattering PO without shadowing is
    not expected to hold far outside it) agrees within 1 dB, PEC TE and TM."""
    rough = GaussianCorrelation(0.5 / K, 8.0 / K, dimension=1)
    th, ph, signed = _signed_grid()
    ti = math.radians(30)
    res = mom.bistatic(rough, "pec", K, ti, th, ph, realizations=48, seed=PO_SEED,
                       length=60.0, progress=False)  # fmt: skip
    ref = kirchhoff_po.bistatic(rough, "pec", K, ti, th, ph)
    windows = [(lo, lo + 10) for lo in range(-40, 80, 10) if not 20 < lo + 5 < 40]
    for p in (0, 1):
        levels = [_window_db(ref, signed, lo, hi, p) for lo, hi in windows]
        main_lobe = [w for w, lv in zip(windows, levels, strict=True) if lv > max(levels) - 10]
        assert len(main_lobe) >= 4
        for lo, hi in main_lobe:
            d = _window_db(res, signed, lo, hi, p) - _window_db(ref, signed, lo, hi, p)
            assert abs(d) < 1.0, (lo, hi, p, d)


def test_correlation_length_below_grid_spacing_fails_before_running():
    import math

    from emscatter.solvers.mom import model as mom
    from emscatter.spectra import GaussianCorrelation

    k = 2 * math.pi
    rough = GaussianCorrelation(0.05 / k, 0.5 / k, dimension=1)  # kℓ = 0.5: ℓ < λ/10
    with pytest.raises(ValueError, match="coarser than the correlation length"):
        mom.bistatic(rough, "pec", k, 0.3, 0.3, realizations=4, seed=0, progress=False)
