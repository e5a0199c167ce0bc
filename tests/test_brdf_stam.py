"""Stam 1999's Gaussian-surface diffraction shader (``emscatter.brdf.analytic.stam``): equal to
HTSG without shadowing/effective roughness and to emscatter's PO (anisotropic too), close to
first-order SPM near the normal at small kσ, reciprocal, albedo, Beckmann equivalent."""

from __future__ import annotations

import math

import numpy as np
import pytest

from emscatter import api, spectra
from emscatter.brdf import frames
from emscatter.brdf.analytic import directional_albedo
from emscatter.brdf.analytic import empirical as E
from emscatter.brdf.analytic.htsg import htsg
from emscatter.brdf.analytic.stam import stam, stam_specular
from emscatter.solvers.kirchhoff import po

LAM = 0.55e-6
K = 2 * math.pi / LAM
GOLD = 0.2 + 3.0j


def _pairs(n, tmax_deg, seed=5):
    rng = np.random.default_rng(seed)
    th = rng.uniform(0, math.radians(tmax_deg), (2, n))
    ph = rng.uniform(0, 2 * math.pi, (2, n))
    return th, ph, frames.directions(th[0], ph[0]), frames.directions(th[1], ph[1])


@pytest.mark.parametrize("ks,tx,ty", [(0.3, 4.0, 4.0), (0.5, 5.0, 12.0), (2.0, 30.0, 10.0)])
def test_equals_emscatter_po_anisotropic(ks, tx, ty):
    s, tx, ty = ks / K, tx / K, ty / K
    th, ph, wi, wo = _pairs(400, 85)
    f = stam(wi, wo, LAM, s, tx, ty, GOLD)
    ti, ts, ps, pi_ = frames.to_emscatter(th[0], ph[0], th[1], ph[1])
    rough = spectra.GaussianCorrelation(s, tx, ty)
    res = po.bistatic(rough, GOLD**2, K, ti, ts, ps, pi_, coherent=False)
    fpo = res.unpolarized() / (4 * math.pi * np.cos(ti) * np.cos(ts))
    assert np.max(np.abs(f / fpo - 1)) < 1e-6


def test_isotropic_is_htsg_without_shadowing_and_effective_roughness():
    _, _, wi, wo = _pairs(500, 89)
    s, t = 1.0 / K, 8.0 / K
    a = stam(wi, wo, LAM, s, t, None, GOLD)
    b = htsg(wi, wo, LAM, s, t, GOLD, shadowing=False, effective_roughness=False)
    np.testing.assert_allclose(a, b, rtol=1e-12)
    th = np.radians([0.0, 40, 80])
    r = stam_specular(th, LAM, s, GOLD)
    assert np.all(r < 1) and r[0] == pytest.approx(
        np.exp(-((2 * K * s) ** 2)) * abs((GOLD - 1) / (GOLD + 1)) ** 2, rel=1e-12
    )


def test_first_order_against_spm_near_the_normal():
    """kσ = 0.05, θ ≤ 20°: Kirchhoff's tangent-plane polarization factors and SPM's α_pq
    agree there (0.03 dB); they part toward larger angles (catalogue.md)."""
    s, tau = 0.05 / K, 6.0 / K
    t = np.radians(np.arange(0.0, 20.1, 5.0))
    p = np.radians(np.arange(0.0, 180.1, 15.0))
    ti, to, pd = np.meshgrid(t, t, p, indexing="ij")
    f = stam(frames.directions(ti, 0 * ti), frames.directions(to, pd), LAM, s, tau, None, GOLD)
    a, b, c, d = frames.to_emscatter(ti, 0 * ti, to, pd)
    res = api.bistatic(
        spectra.GaussianCorrelation(s, tau),
        GOLD**2,
        theta_i=a,
        theta_s=b,
        phi_s=c,
        phi_i=d,
        wavelength=LAM,
        method="spm",
    )
    fs = res.unpolarized() / (4 * math.pi * np.cos(a) * np.cos(b))
    db = np.abs(10 * np.log10(f / fs))
    assert np.max(db) < 0.05


def test_reciprocal_and_registered():
    _, _, wi, wo = _pairs(4000, 89, seed=9)
    p = {"wavelength": LAM, "sigma": 0.7 / K, "tau_x": 5 / K, "tau_y": 15 / K, "n": GOLD}
    a = E.evaluate("stam", wi, wo, **p)
    b = E.evaluate("stam", wo, wi, **p)
    assert np.max(np.abs(a - b) / np.maximum(a, b)) < 1e-12
    eq = E.equivalent_beckmann("stam", sigma=0.1, tau_x=0.5, tau_y=1.0)
    assert eq.value == pytest.approx((0.4, 0.2))


def test_albedo_at_most_one_at_moderate_angles_and_po_excess_toward_grazing():
    th = np.radians([0.0, 30.0, 60.0, 89.0])
    s, t = 0.3 / K, 6.0 / K  # m = 0.1
    alb = directional_albedo(
        lambda wi, wo: stam(wi, wo, LAM, s, t, None, "pec"), th, n_theta=96, n_phi=96
    ) + stam_specular(th, LAM, s, "pec")
    assert np.all(alb[:3] < 1.005)  # PO's energy at normal incidence (1.0007 here)
    assert alb[3] > 1.0  # no shadowing: the model's own excess at grazing


def test_bad_input():
    w = np.array([0.0, 0.0, 1.0])
    with pytest.raises(ValueError, match="tau_y"):
        stam(w, w, LAM, 1e-7, 1e-6, -1.0)
    with pytest.raises(ValueError, match="sigma0|sigma"):
        stam(w, w, LAM, 0.0, 1e-6)
