"""The bistatic multiple-scattering cross-polarization of the IEM (solvers/iem_crosspol.py) and
its small-roughness reference, second-order SPM (solvers/spm2_crosspol.py): reciprocity, the
backscatter value of the previous (backscatter-only) implementation, continuity through
backscatter, agreement with SPM2 at small kσ, energy, numba = numpy."""

from __future__ import annotations

import math

import numpy as np
import pytest

from emscatter import api
from emscatter.fresnel import fresnel_cos
from emscatter.solvers.iem import compiled as iem_jit
from emscatter.solvers.iem import crosspol as iem_crosspol
from emscatter.solvers.iem import model as iem
from emscatter.solvers.spm.crosspol import sigma0_22
from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation

K = 2 * math.pi
C = 299_792_458.0


def _db(x):
    return 10.0 * np.log10(x)


def _term(rough, eps, ti, ts, dphi, phi_i=0.0, order=8):
    """The multiple-scattering (hv, vh) alone, outer shadowing 1."""
    slope = iem.nominal_rms_slope(rough)
    ti, ts, dphi, phi_i = np.broadcast_arrays(
        *(np.asarray(a, float) for a in (ti, ts, dphi, phi_i))
    )
    return iem_crosspol.multiple_scattering(rough, eps, K, ti, ts, dphi, phi_i, slope=slope,
                                            shadow=np.ones(ti.shape), order=order)  # fmt: skip


CASES = [
    (ExponentialCorrelation(0.1 / K, 3.0 / K), 15 + 2j),
    (GaussianCorrelation(0.5 / K, 4.0 / K), "pec"),
    (ExponentialCorrelation(0.3 / K, 3.0 / K, length_y=5.0 / K), 5 + 0.3j),
]
IDS = ["exp-soil", "gauss-pec", "exp-aniso"]


def test_kernel_in_backscatter_is_fungs_closed_form():
    """At backscatter (θs = θi, Δφ = π) the bistatic kernel (Chen et al. 2003 appendix B/C
    combination at the intermediate wavevector) is Fung's F_hv (Fung, Li & Chen 1992 appendix;
    Ulaby & Long 2014 code 10.1): F_hv = (uv/cosθ)[(b − c)(1 − 3R) − (b − c/ε)(1 + R)
    + (a − d)(1 + 3R) − (a − dε)(1 − R)], a, b = (1 ± R)/q, c, d = (1 ± R)/q_t; PEC 4a uv/cosθ."""
    rng = np.random.default_rng(3)
    r = np.sqrt(rng.uniform(0, 0.98, 200))
    al = rng.uniform(0, 2 * math.pi, 200)
    u, v = r * np.cos(al), r * np.sin(al)
    q = np.sqrt(1 - r * r)
    for eps in (15 + 2j, 3.0 + 0.1j, "pec"):
        for th in (0.3, 0.8, 1.2):
            s, c = math.sin(th), math.cos(th)
            rh, rv = fresnel_cos(eps, c)
            R = 0.5 * (rv - rh)
            gam = iem_crosspol.kernel_coefficients(R, eps)
            f_hv, f_vh = iem_crosspol.kernel(s, c, s, c, 0.0, -1.0, u, v, eps, gam)
            a, b = (1 + R) / q, (1 - R) / q
            if eps == "pec":
                f = 4 * a
            else:
                qt = np.sqrt(eps - r * r)
                cc, d = (1 + R) / qt, (1 - R) / qt
                f = (b - cc) * (1 - 3 * R) - (b - cc / eps) * (1 + R)
                f = f + (a - d) * (1 + 3 * R) - (a - d * eps) * (1 - R)
            fung = np.abs(f * u * v / c)  # F̃ = cos²θ F in backscatter
            np.testing.assert_allclose(np.abs(f_hv) / c**2, fung, rtol=1e-10, atol=1e-14)
            np.testing.assert_allclose(np.abs(f_vh) / c**2, fung, rtol=1e-10, atol=1e-14)


def test_backscatter_value_of_the_backscatter_only_implementation():
    """At exact backscatter the continuous term is the previous backscatter-only value (main
    98c56ad, ``iem_crosspol.backscatter_hv``, whose C-band soil values are within 0.3 dB of SMRT
    ``IIEM_Fung02``: tests/test_iem.py) to its quadrature accuracy."""
    k = 2 * math.pi * 5.3e9 / C
    th = np.radians([20.0, 30.0, 40.0, 50.0])
    soil = iem.bistatic(ExponentialCorrelation(0.01, 0.05), 15 + 2j, k, th, th, math.pi)
    np.testing.assert_allclose(_db(soil.hv), [-15.63807, -16.43192, -17.64005, -19.48454],
                               atol=4e-3)  # fmt: skip
    rough = GaussianCorrelation(0.03, 0.25)
    th = np.radians([25.0, 45.0])
    diel = iem.bistatic(rough, 15 + 2j, K, th, th, math.pi)
    pec = iem.bistatic(rough, "pec", K, th, th, math.pi)
    np.testing.assert_allclose(diel.hv, [2.6889e-4, 1.0545e-4], rtol=1e-3)
    np.testing.assert_allclose(pec.hv, [1.97276e-3, 8.2112e-4], rtol=1e-3)
    np.testing.assert_array_equal(pec.hv, pec.vh)


@pytest.mark.parametrize(("rough", "eps"), CASES, ids=IDS)
def test_reciprocity_of_the_term(rough, eps):
    """σ⁰_hv(i → s) = σ⁰_vh(−s → −i) at random bistatic geometries, to rounding."""
    rng = np.random.default_rng(5)
    n = 24
    ti, ts = rng.uniform(0.0, 1.45, n), rng.uniform(0.0, 1.45, n)
    pi_, ps = rng.uniform(0, 2 * math.pi, n), rng.uniform(0, 2 * math.pi, n)
    hv, vh = _term(rough, eps, ti, ts, ps - pi_, pi_)
    rhv, rvh = _term(rough, eps, ts, ti, pi_ - ps, ps + math.pi)
    assert np.all(hv > 0) and np.all(vh > 0)
    np.testing.assert_allclose(hv, rvh, rtol=1e-10)
    np.testing.assert_allclose(vh, rhv, rtol=1e-10)


@pytest.mark.parametrize(("rough", "eps"), CASES, ids=IDS)
def test_continuous_through_backscatter(rough, eps):
    """No step and no cusp at backscatter: 1e-7 rad away the value is the backscatter one to
    1e-6; along θs the change is linear in the offset (Lipschitz, no √δ cusp) and along φs
    even, within ~quadratic."""
    t0 = 0.7
    d = np.array([1e-7, 1e-3, 1e-2])
    at = iem.bistatic(rough, eps, K, t0, t0, math.pi).hv
    for sign in (-1.0, 1.0):
        elev = iem.bistatic(rough, eps, K, t0, t0 + sign * d, math.pi).hv
        azim = iem.bistatic(rough, eps, K, t0, t0, math.pi + sign * d).hv
        for scan, power in ((elev, 1.0), (azim, 2.0)):
            rel = np.abs(scan / at - 1.0)
            assert rel[0] < 1e-6
            assert rel[1] <= 1.5 * rel[2] * (d[1] / d[2]) ** power + 1e-7, rel


def test_isotropic_surface_is_invariant_under_rotation_and_anisotropic_one_swaps_lengths():
    ti, ts, dp = np.array([0.3, 0.9]), np.array([0.6, 0.2]), np.array([2.0, 4.0])
    iso = ExponentialCorrelation(0.2 / K, 3.0 / K)
    np.testing.assert_allclose(_term(iso, 5 + 1j, ti, ts, dp, 0.0),
                               _term(iso, 5 + 1j, ti, ts, dp, 1.1), rtol=1e-10)  # fmt: skip
    a = ExponentialCorrelation(0.2 / K, 3.0 / K, length_y=6.0 / K)
    b = ExponentialCorrelation(0.2 / K, 6.0 / K, length_y=3.0 / K)
    np.testing.assert_allclose(_term(a, 5 + 1j, ti, ts, dp, 0.5 * math.pi),
                               _term(b, 5 + 1j, ti, ts, dp, 0.0), rtol=1e-9)  # fmt: skip


def test_quadrature_converged_in_bistatic_geometry():
    """Against 24 nodes per graded segment, over backscatter, specular, forward-grazing and
    out-of-plane geometries: the default order 8 (``crosspol_order``) is within 1e-2
    (measured ≤ 9e-3, at specular), order 12 within 1e-3 (measured ≤ 5e-4)."""
    ti = np.array([0.5, 0.5, 0.5, 1.2, 0.1, 0.9])
    ts = np.array([0.5, 0.5, 1.4, 1.2, 0.8, 0.0])
    dp = np.array([math.pi, 0.0, 0.3, 2.0, 1.0, 0.0])
    for rough, eps in CASES:
        ref = np.array(_term(rough, eps, ti, ts, dp, order=24))
        np.testing.assert_allclose(_term(rough, eps, ti, ts, dp, order=8), ref, rtol=1e-2)
        np.testing.assert_allclose(_term(rough, eps, ti, ts, dp, order=12), ref, rtol=1e-3)


@pytest.mark.skipif(not iem_jit.enabled(), reason="numba kernels off or numba not installed")
def test_compiled_kernel_equals_numpy_reference(monkeypatch):
    rough, eps = CASES[2]
    rng = np.random.default_rng(8)
    ti, ts = rng.uniform(0.0, 1.4, 9), rng.uniform(0.0, 1.4, 9)
    dp, pi_ = rng.uniform(0, 2 * math.pi, 9), rng.uniform(0, 2 * math.pi, 9)
    fast = np.array(_term(rough, eps, ti, ts, dp, pi_))
    fast_pec = np.array(_term(CASES[1][0], "pec", ti, ts, dp))
    monkeypatch.setenv("EMSCATTER_KERNELS", "numpy")
    np.testing.assert_allclose(fast, _term(rough, eps, ti, ts, dp, pi_), rtol=1e-9)
    np.testing.assert_allclose(fast_pec, _term(CASES[1][0], "pec", ti, ts, dp), rtol=1e-9)


# ----------------------------------------------------------------------------- SPM2
@pytest.mark.parametrize(
    ("rough", "tol"),
    [
        (GaussianCorrelation(0.05 / K, 3.0 / K), 3.0),
        (ExponentialCorrelation(0.05 / K, 3.0 / K), 2.0),
    ],
    ids=["gaussian", "exponential"],
)
def test_agrees_with_second_order_spm_at_small_k_sigma(rough, tol):
    """kσ = 0.05, kℓ = 3, ε = 15 + 2i, θi = 28.6°, in the plane of incidence (where the
    single-scattering hv vanishes, so SPM2's (2,2) term is the whole fourth-order hv):
    backscatter side and specular side, θs ≤ 40°: within 3 dB (Gaussian; measured 1.0–2.4) and
    2 dB (exponential; 0.0–1.4). The IEM omits evanescent intermediate waves, which carry the
    rest (validation/iem/README.md)."""
    ts = np.radians([0.0, 10.0, 20.0, 28.65, 40.0])
    for ps in (math.pi, 0.0):
        ref = sigma0_22(rough, 15 + 2j, K, 0.5, ts, ps)
        got = iem.bistatic(rough, 15 + 2j, K, 0.5, ts, ps)
        assert np.all(np.abs(_db(got.hv / ref[0, 1])) < tol), _db(got.hv / ref[0, 1])
        assert np.all(np.abs(_db(got.vh / ref[1, 0])) < tol), _db(got.vh / ref[1, 0])


def test_second_order_spm_is_reciprocal():
    """SPM2's (2,2) term obeys σ⁰_hv(i → s) = σ⁰_vh(−s → −i) (an exact law; the node sets
    differ between the two directions, so to quadrature accuracy), out of the plane too."""
    rough = ExponentialCorrelation(0.05 / K, 2.0 / K)
    ti, ts = np.array([0.3, 0.8]), np.array([0.6, 0.2])
    pi_, ps = np.array([0.0, 1.0]), np.array([2.0, 4.0])
    fwd = sigma0_22(rough, 6 + 1j, K, ti, ts, ps, pi_)
    rev = sigma0_22(rough, 6 + 1j, K, ts, ti, pi_ + math.pi, ps + math.pi)
    np.testing.assert_allclose(fwd, np.swapaxes(rev, 0, 1), rtol=2e-3)


def test_second_order_spm_rejects_conductors_and_profiles():
    with pytest.raises(ValueError, match="eps"):
        sigma0_22(GaussianCorrelation(0.01, 0.5), "pec", K, 0.3, 0.3, math.pi)
    with pytest.raises(ValueError, match="dimension"):
        sigma0_22(GaussianCorrelation(0.01, 0.5, dimension=1), 4.0, K, 0.3, 0.3, math.pi)


# ----------------------------------------------------------------------------- energy
def test_energy_the_term_brings_a_conductor_toward_zero_emissivity():
    """A perfect conductor must have e = 0 (albedo 1). Gaussian kσ = 1, kℓ = 5, θi = 0°, 30°:
    single scattering alone leaves e ≈ 0.03–0.06 (energy lost); the bistatic multiple-scattering
    hv, integrated over the hemisphere, restores it to |e| ≤ 0.025 without overshooting
    (albedo ≤ 1 within the quadrature tolerance)."""
    rough = GaussianCorrelation(1.0 / K, 5.0 / K)
    th = np.radians([0.0, 30.0])
    kw = dict(wavelength=1.0, theta_i=th, method="iem", tol=1e-3)
    single = api.emissivity(rough, "pec", crosspol=False, **kw).emissivity
    both = api.emissivity(rough, "pec", **kw).emissivity
    assert np.all(single > 0.03)
    assert np.all(both > -2e-3) and np.all(both < 0.025)
    assert np.all(np.abs(both) < 0.5 * np.abs(single))


def test_energy_overshoot_of_a_rough_conductor_is_flagged_not_silent():
    """Gaussian kσ = 2, kℓ = 10 (inside check_validity): the term overshoots for a perfect
    conductor (e ≈ −0.024 at nadir, single scattering alone +0.018; validation/iem/README.md);
    the energy balance flags it (energy_ok False, with a warning naming it)."""
    rough = GaussianCorrelation(2.0 / K, 10.0 / K)
    with pytest.warns(UserWarning, match="energy not conserved"):
        e = api.emissivity(rough, "pec", wavelength=1.0, theta_i=0.0, method="iem", tol=1e-3)
    assert not np.any(e.energy_ok)
    assert -0.04 < float(np.min(e.emissivity)) < -0.01
