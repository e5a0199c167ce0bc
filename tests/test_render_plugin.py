"""The ``emscatter`` Mitsuba BSDF plugin, run for real in Mitsuba's LLVM variants.

* ``eval`` reproduces ``BrdfTable.evaluate`` (the same multilinear interpolant, float32),
  RGB and spectral, isotropic (Dr.Jit texture) and anisotropic / many-wavelength (gathers);
* ``sample`` and ``pdf`` agree (Mitsuba's own χ² test) and the sampled albedo
  ``E[f cosθo / pdf]`` equals the table's exact albedo;
* the coherent part is a delta component of the same BSDF with weight ``R_coh(θi)``.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from emscatter.brdf import build_table
from emscatter.brdf.colour import RGB_LUMINANCE, spectrum_to_rgb_weights
from emscatter.render import mitsuba as em_mi
from emscatter.render.plugin_data import prepare
from emscatter.spectra import GaussianCorrelation
from render_helpers import (
    dr,
    go_table,
    mi,
    mitsuba_eval,
    random_pairs,
    relative_errors,
    sampled_albedo,
    use_variant,
)


def _rgb(table, values):
    return spectrum_to_rgb_weights(table.wavelengths) @ values


@pytest.mark.parametrize(
    ("variant", "table_kw"),
    [
        ("llvm_ad_rgb", {}),
        ("llvm_ad_spectral", {}),
        ("llvm_ad_spectral", {"wavelengths": (450e-9, 500e-9, 550e-9, 600e-9, 650e-9, 700e-9)}),
        ("llvm_ad_rgb", {"resolution": (12, 16), "aspect": 0.6}),
        ("llvm_ad_spectral", {"resolution": (12, 16), "aspect": 0.6}),
        ("llvm_ad_mono", {}),
    ],
    ids=["rgb", "spectral", "spectral-6wl", "aniso-rgb", "aniso-spectral", "mono"],
)
def test_eval_is_the_table(variant, table_kw):
    use_variant(variant)
    table = go_table(**table_kw)
    bsdf = mi.load_dict(em_mi.bsdf_dict(table))
    wi, wo = random_pairs(np.random.default_rng(4), 20_000)
    want = table.evaluate(wi, wo) * wo[:, 2]  # (n_wl, n)
    if mi.is_rgb:
        got, want = mitsuba_eval(bsdf, wi, wo), _rgb(table, want).T
    elif mi.is_monochromatic:  # the luminance of the sRGB conversion
        got, want = mitsuba_eval(bsdf, wi, wo), (RGB_LUMINANCE @ _rgb(table, want))[:, None]
    else:
        lam = 0.5 * (table.wavelengths[1] + table.wavelengths[2])  # between two nodes
        got = mitsuba_eval(bsdf, wi, wo, wavelength_nm=lam * 1e9)
        want = table.evaluate(wi, wo, wavelength=lam)[:, None] * wo[:, 2:3]
    for c in range(got.shape[1]):
        err = relative_errors(got[:, c], want[:, c], floor=1e-4)
        assert err.max() < 2e-4, err.max()  # float32 texture vs float64 table


@pytest.mark.parametrize("variant", ["llvm_ad_rgb", "llvm_ad_spectral"])
def test_sampled_albedo_is_the_tables(variant):
    use_variant(variant)
    table = go_table()
    bsdf = mi.load_dict(em_mi.bsdf_dict(table))
    alb = table.albedo().incoherent
    for deg in (0.0, 35.0, 65.0, 80.0):
        got, bs = sampled_albedo(bsdf, math.radians(deg), wavelength_nm=550.0)
        if mi.is_rgb:
            got, want = got[1], np.interp(math.radians(deg), table.theta_i, _rgb(table, alb)[1])
        else:
            got, want = got[0], np.interp(math.radians(deg), table.theta_i, alb[1])
        assert got == pytest.approx(want, rel=5e-3), (deg, got, want)
        assert np.all(np.array(bs.sampled_type) == int(mi.BSDFFlags.GlossyReflection))


@pytest.mark.parametrize("aspect", [1.0, 0.6], ids=["isotropic", "anisotropic"])
def test_chi2_sampling_matches_pdf(aspect, tmp_path, monkeypatch):
    """Mitsuba's χ² goodness-of-fit test of ``sample`` against ``pdf`` (mitsuba.chi2); the
    density is piecewise constant in half-vector solid angle, so the test integrates it on a
    finer grid than its default (trapezoid rule, 16² points per histogram cell)."""
    use_variant("llvm_ad_rgb")
    monkeypatch.chdir(tmp_path)  # a failing test writes chi2_data.py into the working folder
    from mitsuba.chi2 import BSDFAdapter, ChiSquareTest, SphericalDomain

    table = go_table(
        alpha=0.4, **({} if aspect == 1.0 else {"resolution": (12, 16), "aspect": aspect})
    )
    d = em_mi.bsdf_dict(table)
    for deg, azimuth in ((20.0, 0.0), (60.0, 2.0)):
        th = math.radians(deg)
        wi = [math.sin(th) * math.cos(azimuth), math.sin(th) * math.sin(azimuth), math.cos(th)]
        sample_func, pdf_func = BSDFAdapter("emscatter", d, wi=wi)
        test = ChiSquareTest(
            domain=SphericalDomain(),
            sample_func=sample_func,
            pdf_func=pdf_func,
            sample_dim=3,
            sample_count=400_000,
            res=64,
            ires=16,  # the density is piecewise constant: integrate it finely
        )
        assert test.run(), test.messages


def _smooth_surface_table():
    """SPM on a slightly rough dielectric-like surface: a strong coherent (delta) part."""
    rough = GaussianCorrelation(15e-9, 400e-9)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return build_table(rough, 2.25 + 0.05j, [500e-9, 600e-9], method="spm", resolution=(24, 48))


def test_coherent_delta_lobe():
    use_variant("llvm_ad_rgb")
    table = _smooth_surface_table()
    assert table.coherent.max() > 0.01
    bsdf = mi.load_dict(em_mi.bsdf_dict(table))
    flags = bsdf.flags()
    assert flags & mi.BSDFFlags.DeltaReflection and flags & mi.BSDFFlags.GlossyReflection
    assert bsdf.component_count() == 2
    assert bsdf.flags(1) & mi.BSDFFlags.DeltaReflection
    assert not bsdf.flags(0) & mi.BSDFFlags.DeltaReflection
    th = math.radians(50.0)
    r_coh = _rgb(table, table.coherent_reflectance(th))
    # the delta component alone: mirror direction, weight R_coh(θi)
    ctx = mi.BSDFContext()
    ctx.component = 1
    got, bs = sampled_albedo(bsdf, th, n=1000, ctx=ctx)
    np.testing.assert_allclose(got, r_coh, rtol=2e-4)
    wo = np.array(bs.wo)  # (3, n)
    np.testing.assert_allclose(wo[0], -math.sin(th), atol=1e-6)
    np.testing.assert_allclose(wo[2], math.cos(th), atol=1e-6)
    assert np.all(np.array(bs.sampled_type) == int(mi.BSDFFlags.DeltaReflection))
    assert np.all(np.array(bs.sampled_component) == 1)
    # both components: the sampled albedo is incoherent + coherent
    got, bs = sampled_albedo(bsdf, th, n=400_000)
    inc = np.interp(th, table.theta_i, _rgb(table, table.albedo().incoherent)[1])
    assert got[1] == pytest.approx(inc + r_coh[1], rel=5e-3)
    types = np.array(bs.sampled_type)
    frac = np.mean(types == int(mi.BSDFFlags.DeltaReflection))
    assert frac == pytest.approx(r_coh.mean() / (r_coh.mean() + inc), abs=0.01)
    # eval and pdf exclude the delta; without the coherent option it is gone
    wi, wo = random_pairs(np.random.default_rng(5), 1000)
    glossy_only = mi.load_dict({**em_mi.bsdf_dict(table), "coherent": False})
    assert glossy_only.component_count() == 1
    np.testing.assert_allclose(mitsuba_eval(bsdf, wi, wo), mitsuba_eval(glossy_only, wi, wo))


def test_scene_dict_and_xml_use_the_registered_name():
    use_variant("llvm_ad_rgb")
    table = go_table()
    key = em_mi.register_table(table, "gold-demo")
    em_mi.register()
    xml = f'<bsdf version="3.0.0" type="emscatter"><string name="table" value="{key}"/></bsdf>'
    a = mi.load_string(xml)
    b = mi.load_dict({"type": "emscatter", "table": key})
    wi, wo = random_pairs(np.random.default_rng(6), 500)
    np.testing.assert_array_equal(mitsuba_eval(a, wi, wo), mitsuba_eval(b, wi, wo))
    assert "gold-demo" in str(a)
    em_mi.unregister_table(key)
    with pytest.raises(Exception, match="no table registered as 'gold-demo'"):
        mi.load_string(xml)


def test_errors_name_the_problem():
    use_variant("llvm_ad_rgb")
    em_mi.register()
    with pytest.raises(Exception, match="no table registered as 'nope'"):
        mi.load_dict({"type": "emscatter", "table": "nope"})
    with pytest.raises(Exception, match="give 'table'"):
        mi.load_dict({"type": "emscatter"})
    assert em_mi.channels_of_variant("llvm_ad_spectral_polarized") == "spectral"
    assert em_mi.channels_of_variant("scalar_rgb_polarized") == "rgb"
    with pytest.raises(ValueError, match="unknown Mitsuba variant"):
        em_mi.channels_of_variant("llvm_ad_xyz")
    with pytest.raises(TypeError, match="BrdfTable, BrdfFunction or MuellerTable"):
        em_mi.register_table(42)
    with pytest.raises(ValueError, match="sampling_resolution"):
        prepare(go_table(), "rgb", sampling_resolution=3)
    with pytest.raises(ValueError, match="channels must be one of"):
        prepare(go_table(), "xyz")


def test_anisotropic_coherent_lobe_follows_the_azimuth():
    """R_coh(θi, φi) of an anisotropic table, periodic in φi (between the last node and 2π too)."""
    from emscatter.brdf import BrdfTable
    from emscatter.brdf.build import default_phi, default_theta

    use_variant("llvm_ad_rgb")
    th, ph = default_theta(6), default_phi(8)
    values = np.full((1, 6, 8, 6, 8), 0.05)
    coh = 0.3 + 0.2 * np.cos(ph)[None, None, :] * np.ones((1, 6, 1))
    table = BrdfTable(
        wavelengths=[5.5e-7],
        theta_i=th,
        theta_o=th,
        phi_i=ph,
        phi_o=ph,
        values=values,
        coherent=coh,
    )
    bsdf = mi.load_dict(em_mi.bsdf_dict(table))
    ctx = mi.BSDFContext()
    ctx.component = 1
    th_i = math.radians(30.0)
    for phi in (0.3, 2.0, 5.9):  # 5.9 rad lies between the last node (5.50) and 2π
        si = dr.zeros(mi.SurfaceInteraction3f, 64)
        si.wi = mi.Vector3f(
            math.sin(th_i) * math.cos(phi), math.sin(th_i) * math.sin(phi), math.cos(th_i)
        )
        _, w = bsdf.sample(ctx, si, mi.Float(0.5), mi.Point2f(0.5, 0.5))
        want = table.coherent_reflectance(th_i, phi)[0]
        np.testing.assert_allclose(np.array(w)[1], want, rtol=1e-5)


def test_compact_lobe_wastes_no_samples():
    """The seed's uniform distribution (f = 0 beyond θh = 0.1 rad): cells outside the lobe get
    no samples, yet the sampled albedo is the table's (the ring around the support keeps every
    direction with f > 0 reachable)."""
    from emscatter.brdf.analytic import cook_torrance, table_from_function
    from emscatter.brdf.analytic.distributions import SeedDistribution

    use_variant("llvm_ad_rgb")
    dist = SeedDistribution("uniform", a=0.1)
    table = table_from_function(
        lambda wi, wo, lam: cook_torrance(wi, wo, dist, eps=(0.5 + 3j) ** 2),
        [550e-9],
        resolution=(45, 90),
    )
    bsdf = mi.load_dict(em_mi.bsdf_dict(table))
    for deg in (10.0, 50.0):
        th = math.radians(deg)
        si = dr.zeros(mi.SurfaceInteraction3f, 100_000)
        si.wi = mi.Vector3f(math.sin(th), 0.0, math.cos(th))
        rng = mi.PCG32(100_000, 7)
        _, w = bsdf.sample(
            mi.BSDFContext(),
            si,
            rng.next_float32(),
            mi.Point2f(rng.next_float32(), rng.next_float32()),
        )
        w = np.array(w)[1]
        want = np.interp(th, table.theta_i, table.albedo().incoherent[0])
        assert w.mean() == pytest.approx(want, rel=5e-3)
        assert np.mean(w == 0) < 0.06  # samples outside the lobe (weight 0): a few, at its edge
