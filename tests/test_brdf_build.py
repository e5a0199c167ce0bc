"""build_table: the reciprocal half plus reciprocity equals direct evaluation, the coherent
part is kept apart, "auto" per wavelength, the energy remedy, clear errors."""

from __future__ import annotations

import math

import numpy as np
import pytest

from brdf_helpers import SEPARABLE
from emscatter import api
from emscatter.brdf import build_table, frames
from emscatter.brdf.build import default_phi, default_phi_d, default_theta
from emscatter.brdf.energy import reciprocal_energy_scale
from emscatter.solvers.spm import model as spm
from emscatter.spectra import GaussianCorrelation

EPS = 4.0 + 0.3j
LAM = 0.5e-6


def _direct(rough, eps, name, ti, pi_, to, po, **opt):
    """f_r per polarization pair by a direct api.bistatic call on every node."""
    et, es, ps, ei = frames.to_emscatter(ti, pi_, to, po)
    res = api.bistatic(
        rough,
        eps,
        wavelength=LAM,
        theta_i=et,
        theta_s=es,
        phi_s=ps,
        phi_i=ei,
        method=name,
        out_of_range="ignore",
        **opt,
    )
    return res.sigma0 / (4 * math.pi * np.cos(ti) * np.cos(to))


def test_isotropic_half_grid_equals_direct_polarized():
    rough = GaussianCorrelation(0.02e-6, 0.3e-6)
    t = build_table(
        rough, EPS, [LAM], method="spm", resolution=(10, 13), polarized=True, out_of_range="ignore"
    )
    th, pd = default_theta(10), default_phi_d(13)
    ti, to, d = np.meshgrid(th, th, pd, indexing="ij")
    direct = _direct(rough, EPS, "spm", ti, 0.3, to, 0.3 + d)
    assert t.metadata["energy"]["remedy_applied"] is False
    np.testing.assert_allclose(t.polarized[:, :, 0], direct, rtol=1e-10, atol=1e-14)
    np.testing.assert_allclose(t.values[0], 0.5 * direct.sum(axis=(0, 1)), rtol=1e-10)
    assert t.reciprocity_error() == 0.0
    # the coherent part: SPM's second-order reflectivity on the θi nodes, not in the table
    coh = spm.coherent_reflectivity(rough, EPS, 2 * math.pi / LAM, th)
    np.testing.assert_allclose(t.coherent_polarized[:, 0], coh, rtol=1e-12)
    np.testing.assert_allclose(t.coherent[0], coh.mean(axis=0), rtol=1e-12)
    np.testing.assert_allclose(t.coherent_reflectance(th, pol="v", wavelength=LAM), coh[1])


def test_physical_optics_half_grid_equals_direct():
    rough = GaussianCorrelation(0.1e-6, 0.8e-6)
    t = build_table(
        rough,
        EPS,
        [LAM],
        method="po",
        resolution=(6, 7),
        polarized=True,
        out_of_range="ignore",
        energy="off",
    )
    th, pd = default_theta(6), default_phi_d(7)
    ti, to, d = np.meshgrid(th, th, pd, indexing="ij")
    direct = _direct(rough, EPS, "po", ti, 1.0, to, 1.0 + d)
    np.testing.assert_allclose(t.polarized[:, :, 0], direct, rtol=1e-7, atol=1e-14)


def test_anisotropic_half_grid_equals_direct():
    rough = GaussianCorrelation(0.3e-6, 1.0e-6, length_y=2.5e-6)
    t = build_table(
        rough,
        "pec",
        [LAM],
        method="go",
        resolution=(6, 8),
        polarized=True,
        out_of_range="ignore",
        energy="off",
    )
    assert not t.isotropic
    ti, pi_, to, po = np.meshgrid(
        default_theta(6), default_phi(8), default_theta(6), default_phi(8), indexing="ij"
    )
    direct = _direct(rough, "pec", "go", ti, pi_, to, po)
    np.testing.assert_allclose(t.polarized[:, :, 0], direct, rtol=1e-9, atol=1e-14)
    assert t.reciprocity_error() == 0.0
    assert np.all(t.coherent == 0) and "GO" in t.metadata["coherent"]
    # GO over a PEC at m_x = 0.6 exceeds albedo 1 at grazing: the remedy per (θ, φ) node
    assert t.albedo().total.max() > 1
    fixed = build_table(
        rough, "pec", [LAM], method="go", resolution=(6, 8), polarized=True, out_of_range="ignore"
    )
    assert fixed.albedo().total.max() <= 1 and fixed.reciprocity_error() == 0.0
    np.testing.assert_allclose(fixed.values, 0.5 * fixed.polarized.sum(axis=(0, 1)))


def test_auto_picks_per_wavelength():
    rough = GaussianCorrelation(0.05e-6, 1.0e-6)
    t = build_table(rough, EPS, [0.3e-6, 10e-6], resolution=(6, 7))
    solvers = [p["solver"] for p in t.metadata["per_wavelength"]]
    assert solvers == ["po", "spm"] and t.metadata["solver"] == "po+spm"
    assert all(p["valid"] for p in t.metadata["per_wavelength"])


def test_energy_remedy_is_reciprocal_and_recorded():
    # physical optics over a PEC reflects up to 2× what it receives near grazing
    rough = GaussianCorrelation(0.1e-6, 0.8e-6)
    kw = {"method": "po", "resolution": (24, 25), "out_of_range": "ignore"}
    raw = build_table(rough, "pec", [LAM], energy="off", **kw)
    fixed = build_table(rough, "pec", [LAM], **kw)
    before = raw.albedo().total[0]
    after = fixed.albedo().total[0]
    e = fixed.metadata["energy"]
    assert before.max() > 1.5 and raw.metadata["energy"]["albedo_exceeds_one"]
    assert after.max() <= 1.0 and e["remedy_applied"]
    assert e["max_albedo_before"][0] == pytest.approx(before.max())
    assert e["max_albedo_after"][0] == pytest.approx(after.max())
    assert e["theta_i_deg_exceeding"][0] == np.degrees(fixed.theta_i[before > 1]).round(4).tolist()
    assert fixed.reciprocity_error() == 0.0
    s = np.array(e["scale"][0])
    np.testing.assert_allclose(fixed.values[0], raw.values[0] * s[:, None, None] * s[None, :, None])
    # nodes whose albedo was fine and whose partners were fine are untouched
    fine = s == 1
    np.testing.assert_array_equal(
        fixed.values[0][np.ix_(fine, fine)], raw.values[0][np.ix_(fine, fine)]
    )
    # the remedy reduces only what it must: rows where it acted end exactly at the limit
    acted = s < 1
    assert np.all(after[acted] > 1 - 1e-6)


def test_energy_scale_solver():
    k = np.array([[0.5, 0.2], [0.2, 1.3]])
    s, _ = reciprocal_energy_scale(k, np.array([0.0, 0.1]))
    alb = s * (k @ s) + [0.0, 0.1]
    assert alb.max() <= 1.0 and s[0] == 1.0 and alb[1] == pytest.approx(1.0, abs=1e-9)
    with pytest.raises(ValueError, match="coherent"):
        reciprocal_energy_scale(k, np.array([0.0, 1.2]))


def test_build_errors_name_the_parameter():
    rough = GaussianCorrelation(0.1e-6, 1e-6)
    bad = [
        ({"surface": GaussianCorrelation(0.1e-6, 1e-6, dimension=1)}, "2-D surface"),
        ({"wavelengths": [5e-7, 4e-7]}, "increasing"),
        ({"wavelengths": [-1.0]}, "wavelength"),
        ({"method": "nope"}, "method"),
        ({"energy": "clip"}, "energy"),
        ({"resolution": (1, 5)}, "n_theta"),
        ({"theta": [0.0, 1.7]}, "theta"),
        ({"material": -1j}, "Im"),
        ({"out_of_range": "nan"}, "out_of_range"),
    ]
    base = {
        "surface": rough,
        "material": "pec",
        "wavelengths": [LAM],
        "method": "go",
        "resolution": (4, 5),
        "out_of_range": "ignore",
    }
    for change, match in bad:
        kw = {**base, **change}
        with pytest.raises(ValueError, match=match):
            build_table(kw.pop("surface"), kw.pop("material"), kw.pop("wavelengths"), **kw)


def test_adaptive_resolution_meets_its_target():
    from emscatter.brdf.analytic import cook_torrance
    from emscatter.brdf.analytic.distributions import Beckmann

    rough = GaussianCorrelation(0.2e-6, 1.0e-6)  # m = 0.4
    t = build_table(
        rough, EPS, [LAM], method="go", tol=0.1, out_of_range="ignore", shadowing=SEPARABLE
    )
    rep = t.metadata["resolution"]
    assert rep["adaptive"] and rep["converged"] and rep["max_error_theta"] <= 0.1
    assert not np.allclose(np.diff(t.theta_i), np.diff(t.theta_i)[0])  # refined, non-uniform
    rng = np.random.default_rng(0)
    ti, to = rng.uniform(0, 1.45, (2, 20000))
    pd = rng.uniform(0, math.pi, 20000)
    wi, wo = frames.directions(ti, 0.0), frames.directions(to, pd)
    ref = cook_torrance(wi, wo, Beckmann(0.4), eps=EPS)  # = GO (tests/test_brdf_analytic.py)
    w = np.cos(ti) * np.cos(to)
    g = t.evaluate(wi, wo, wavelength=LAM) * w
    err = np.abs(g - ref * w) / np.maximum(ref * w, 0.01 * (ref * w).max())
    assert np.percentile(err, 99) < 0.1 and err.max() < 0.3
    with pytest.raises(ValueError, match="tol"):
        build_table(rough, EPS, [LAM], method="go", tol=2.0, out_of_range="ignore")


@pytest.mark.parametrize("method", ["spm", "go"])
def test_table_albedo_equals_api_reflectivity(method):
    """The whole chain (f = σ⁰/(4π cosθi cosθo), polarization averaging, coherent part, the
    interpolant's quadrature) against emscatter's independent hemispherical integration."""
    rough = {
        "spm": GaussianCorrelation(0.02e-6, 0.5e-6),
        "go": GaussianCorrelation(0.3e-6, 1.0e-6),
    }[method]
    t = build_table(
        rough, EPS, [LAM], method=method, resolution=(20, 31), out_of_range="ignore", energy="off"
    )
    th = t.theta_i[[0, 6, 14]]  # 0°, 27°, 63°
    em = api.emissivity(
        rough, EPS, wavelength=LAM, theta_i=th, method=method, out_of_range="ignore"
    )
    # GO's σ⁰ is the whole Kirchhoff intensity: its table has no coherent lobe, so compare
    # the incoherent part (api.emissivity adds the Kirchhoff coherent term to GO)
    ref = em.incoherent.mean(axis=0) + (em.coherent.mean(axis=0) if method == "spm" else 0)
    np.testing.assert_allclose(t.albedo().total[0, [0, 6, 14]], ref, atol=3e-4)
