"""Issue 17: deterministic physical optics over a height map itself (``po_map``), by FFT.

Grating orders of a sinusoidal map against the grating equation and Beckmann's Kirchhoff
amplitudes ``J_m(q_z a)``; the blaze of a sawtooth; a flat map's Fresnel reflectivity; energy
of a perfect conductor; the average over 64 realizations (emscatter's own periodic generator)
against the statistical PO of :mod:`emscatter.solvers.kirchhoff.po`.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from scipy import special

import emscatter
from emscatter.fresnel import reflectivity
from emscatter.solvers.kirchhoff import po
from emscatter.solvers.kirchhoff.po_map import ENERGY_TOL, MapEnergyWarning, po_map
from emscatter.spectra import GaussianCorrelation
from emscatter.surfaces import generate_batch, height_map

LAM = 1.0
K = 2 * math.pi / LAM
EPS = 5 + 0.5j


def _sinusoid(a, periods, n=256, dx=LAM / 8, rows=32, axis=1):
    x = np.arange(n) * dx
    h = a * np.sin(2 * math.pi * periods * x / (n * dx))
    grid = h[None, :] * np.ones((rows, 1)) if axis == 1 else h[:, None] * np.ones((1, rows))
    return height_map(grid, (dx, dx), detrend="none"), n * dx / periods


@pytest.mark.parametrize("theta_i_deg", [0.0, 20.0, 45.0])
def test_grating_orders_of_a_sinusoid_follow_the_grating_equation(theta_i_deg):
    """Orders carrying power lie within 0.1° of ``sinθm = sinθi + mλ/Λ`` (Λ = 8λ, 4 periods in
    the map: only every 4th FFT order may carry power), and their efficiencies are the
    Kirchhoff grating amplitudes ``|q|⁴/(4 q_z² cosθi cosθm) J_m(q_z a)²`` of a PEC sinusoid
    (Beckmann & Spizzichino 1963, ch. 4; Jacobi–Anger). Measured: ≤ 1e-15 absolute."""
    a = 0.15 * LAM
    hm, period = _sinusoid(a, 4)
    ti = math.radians(theta_i_deg)
    r = po_map(hm, "pec", K, ti)
    idx = r.select(n=0)
    m = r.order[idx, 0]
    eta = r.efficiency[0, 0, idx] + r.efficiency[1, 0, idx]
    lit = eta > 1e-9
    assert lit.sum() >= 5
    assert np.all(m[lit] % 4 == 0)  # no power between the grating's own orders
    signed = np.sin(r.theta_s[idx]) * np.sign(np.cos(r.phi_s[idx]))
    want = np.degrees(np.arcsin(math.sin(ti) + (m[lit] // 4) * LAM / period))
    got = np.degrees(np.arcsin(signed[lit]))
    assert np.abs(got - want).max() < 0.1
    cs, ci = np.cos(r.theta_s[idx]), math.cos(ti)
    q2 = (signed - math.sin(ti)) ** 2 + (cs + ci) ** 2
    pred = q2**2 / (4 * (cs + ci) ** 2 * ci * cs) * special.jv(m // 4, K * (ci + cs) * a) ** 2
    np.testing.assert_allclose(eta, np.where(m % 4 == 0, pred, 0.0), atol=1e-12)
    assert np.all(r.efficiency[0, 1] < 1e-20)  # in the plane: no depolarization


def test_a_sawtooth_blazes_toward_its_facets_mirror_direction():
    """Facets of slope +0.2 (normal tilted toward −x) send normal incidence to −x, at
    ``2 atan 0.2 = 22.6°`` (the nearest order of the 8λ period: 22.0°)."""
    dx, n = LAM / 8, 256
    x = np.arange(n) * dx
    saw = 0.2 * ((x % (n * dx / 4)) - n * dx / 8)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MapEnergyWarning)  # the jumps: Kirchhoff's excess
        r = po_map(height_map(saw[None, :] * np.ones((32, 1)), dx, detrend="none"), "pec", K, 0.0)
    i = int(np.argmax(r.efficiency[0, 0]))
    assert math.cos(r.phi_s[i]) < 0
    assert abs(math.degrees(r.theta_s[i]) - math.degrees(2 * math.atan(0.2))) < 1.0


def test_a_flat_map_reflects_fresnel_into_the_specular_order_only():
    hm = height_map(1e-12 * np.random.default_rng(0).normal(size=(32, 32)), LAM / 8,
                    detrend="none")  # fmt: skip
    ti = math.radians(35)
    r = po_map(hm, EPS, K, ti, phi_i=0.7)
    rh, rv = reflectivity(EPS, ti)
    spec = r.efficiency[:, :, r.specular]
    assert spec[0, 0] == pytest.approx(rh, rel=1e-8)
    assert spec[1, 1] == pytest.approx(rv, rel=1e-8)
    assert r.reflectance == pytest.approx([rh, rv], rel=1e-8)
    assert r.theta_s[r.specular] == pytest.approx(ti) and r.phi_s[r.specular] == pytest.approx(0.7)


@pytest.mark.parametrize(
    ("sigma", "length", "tol"),
    [(0.05, 2.0, 1e-4), (0.1, 1.5, 1e-3)],
    ids=["slope0.035", "slope0.094"],
)
def test_energy_of_a_gentle_pec_map_is_one(sigma, length, tol):
    """A perfect conductor reflects everything; Kirchhoff's deficit is O(slope²). Measured
    (256², Δ = λ/8, θi = 0°, 30°): |r − 1| ≤ 6.4e-5 for rms slope 0.035, ≤ 6.8e-4 for 0.094;
    a dielectric map reflects less than 1."""
    s = emscatter.generate_surface(GaussianCorrelation(sigma, length), (256, 256), LAM / 8,
                                   periodic=True, rng=2)  # fmt: skip
    hm = height_map(s.heights, s.spacing, detrend="none")
    for ti in (0.0, math.radians(30)):
        r = po_map(hm, "pec", K, ti)
        assert np.all(r.reflectance <= 1 + ENERGY_TOL)
        assert np.abs(r.reflectance - 1).max() < tol, r.reflectance
        assert np.all(po_map(hm, EPS, K, ti).reflectance < 1)


def test_average_over_64_realizations_is_statistical_po_at_the_lobe():
    """64 periodic maps (256², Δ = λ/8, kσ = 0.75, kℓ = 9.4) averaged at their orders against
    :func:`po.bistatic` at the same directions: the lobe (σ⁰ ≥ 10 % of its peak, specular
    order left out: it holds the coherent part), summed over boxes of 9 × 9 orders (speckle:
    one order of one map is χ²₂). Measured worst box: 0.10 dB (hh), 0.09 dB (vv); whole lobe
    0.02 dB."""
    rough = GaussianCorrelation(0.12, 1.5)
    ti = math.radians(30)
    acc = None
    for s in generate_batch(rough, 64, (256, 256), LAM / 8, seed=1, periodic=True):
        r = po_map(height_map(s.heights, s.spacing, detrend="none"), EPS, K, ti)
        acc = r.sigma0 if acc is None else acc + r.sigma0
    acc /= 64
    stat = po.bistatic(rough, EPS, K, ti, r.theta_s, r.phi_s, coherent=False).sigma0
    key = np.floor_divide(r.order[:, 0], 9) * 1000 + np.floor_divide(r.order[:, 1], 9)
    for p in (0, 1):
        lobe = stat[p, p] > 0.1 * stat[p, p].max()
        lobe[r.specular] = False
        boxes = 0
        for kk in np.unique(key[lobe]):
            sel = lobe & (key == kk)
            if sel.sum() < 40:
                continue
            boxes += 1
            db = 10 * math.log10(acc[p, p][sel].sum() / stat[p, p][sel].sum())
            assert abs(db) < 0.3, (p, kk, db)
        assert boxes >= 3


def test_a_gaussian_footprint_tapers_a_non_periodic_map():
    """A non-periodic (exact-method) map under a footprint: the taper keeps the edges dark, the
    reflectance stays ≤ 1 and the orders within ``|Δk⊥| < 5/g`` of the specular one (the
    footprint's own diffraction lobe, ``|Ŵ|² ∝ e^{−K²g²/2}``) hold the coherent part
    ``|R_h|² e^{−(2kσcosθ)²}`` within 5 % (one realization)."""
    rough = GaussianCorrelation(0.03, 1.5)
    s = emscatter.generate_surface(rough, (256, 256), LAM / 8, rng=4)
    hm = height_map(s.heights, s.spacing, detrend="none")
    ti = math.radians(20)
    r = po_map(hm, EPS, K, ti, footprint=5.0)
    assert r.info["footprint"] == 5.0 and np.all(r.reflectance < 1)
    rh, _ = reflectivity(EPS, ti)
    coh = rh * math.exp(-((2 * K * 0.03 * math.cos(ti)) ** 2))
    dk = (2 * math.pi / hm.size[1]) * np.hypot(r.order[:, 0], r.order[:, 1])
    near = dk < 5 / 5.0
    assert near.sum() > 9  # the footprint spreads the specular beam over orders
    assert r.efficiency[0, 0, near].sum() == pytest.approx(coh, rel=0.05)


def test_bad_input_is_named():
    hm, _ = _sinusoid(0.1, 4)
    with pytest.raises(TypeError, match="HeightMap"):
        po_map(np.zeros((32, 32)), "pec", K, 0.1)
    with pytest.raises(ValueError, match="too coarse.*k\\(1 \\+ sinθi\\)"):
        po_map(hm, "pec", 4 * K, 0.1)
    with pytest.raises(ValueError, match="theta_i must be one angle"):
        po_map(hm, "pec", K, [0.1, 0.2])
    with pytest.raises(ValueError, match="footprint must be at most 1/6"):
        po_map(hm, "pec", K, 0.1, footprint=10.0)
    holes = np.random.default_rng(1).normal(size=(32, 32)) * 0.01
    holes[2, 3] = np.nan
    with pytest.raises(ValueError, match="1 masked holes"):
        po_map(height_map(holes, LAM / 8, holes="mask"), "pec", K, 0.1)
    with pytest.raises(ValueError, match="max_terms"):
        po_map(hm, "pec", K, 0.1, max_terms=2)
