"""fit_microfacet: recovers the parameters of a geometric-optics table, reports the error of
a wrong model, and its Mitsuba dict loads and evaluates like the table in real Mitsuba."""

from __future__ import annotations

import math

import numpy as np
import pytest

from brdf_helpers import SEPARABLE, mitsuba_fr, mitsuba_variant, random_directions
from emscatter import materials
from emscatter.brdf import build_table
from emscatter.brdf.analytic.fit import fit_microfacet
from emscatter.spectra import GaussianCorrelation

WL = [0.45e-6, 0.55e-6, 0.65e-6]


@pytest.fixture(scope="module")
def gold():
    rough = GaussianCorrelation(0.15e-6, 1.0e-6)  # m = 2σ/T = 0.3
    return build_table(
        rough,
        "Au",
        WL,
        method="go",
        resolution=(24, 31),
        out_of_range="ignore",
        shadowing=SEPARABLE,
    )


@pytest.fixture(scope="module")
def gold_fit(gold):
    return fit_microfacet(gold, max_points=3000)


def test_fit_recovers_geometric_optics_parameters(gold, gold_fit):
    fit = gold_fit
    assert fit.alpha == pytest.approx(0.3, rel=1e-6)
    eta, k = materials.nk_from_eps(materials.eps_at("Au", wavelength=np.array(WL)))
    np.testing.assert_allclose(fit.eta, eta, rtol=1e-5)
    np.testing.assert_allclose(fit.k, k, rtol=1e-5)
    assert fit.errors["rms"] < 1e-8 and fit.errors["albedo_max_abs"] < 1e-8
    assert fit.mitsuba["type"] == "roughconductor" and fit.mitsuba["distribution"] == "beckmann"
    # a GGX lobe cannot be a Beckmann one: the fit says by how much
    ggx = fit_microfacet(gold, distribution="ggx", max_points=3000)
    assert ggx.errors["rms"] > 1e3 * fit.errors["rms"] and ggx.errors["p90_rel"] > 0.05


def test_fitted_dict_loads_in_mitsuba_and_matches_the_table(gold):
    mi = pytest.importorskip("mitsuba")
    if mitsuba_variant(mi) is None:
        pytest.skip("no Mitsuba variant loads here")
    one = gold.replace(
        wavelengths=gold.wavelengths[1:2],
        values=gold.values[1:2],
        coherent=gold.coherent[1:2],
        coherent_polarized=gold.coherent_polarized[:, 1:2],
    )
    fit = fit_microfacet(one, max_points=3000)
    assert isinstance(fit.mitsuba["eta"], float)
    rng = np.random.default_rng(2)
    wi = random_directions(rng, 3000, math.radians(70))
    wo = random_directions(rng, 3000, math.radians(70))
    theirs = mitsuba_fr(mi, fit.to_mitsuba(), wi, wo)
    ours = one.evaluate(wi, wo, wavelength=WL[1])
    sig = ours > 0.05 * ours.max()
    rel = np.abs(theirs - ours)[sig] / ours[sig]
    assert sig.sum() > 100 and np.median(rel) < 0.01 and np.percentile(rel, 90) < 0.05
    with pytest.raises(ValueError, match="three-wavelength"):
        fit.to_mitsuba("rgb")


def test_rgb_dict(gold_fit):
    rgb = gold_fit.to_mitsuba("rgb")
    assert rgb["eta"] == {"type": "rgb", "value": gold_fit.eta[::-1].tolist()}
    spec = gold_fit.to_mitsuba()["k"]["value"]
    assert [w for w, _ in spec] == pytest.approx([450.0, 550.0, 650.0])


def test_fit_dielectric_and_bad_input():
    rough = GaussianCorrelation(0.15e-6, 1.0e-6)
    glass = build_table(
        rough,
        2.25,
        [0.5e-6],
        method="go",
        resolution=(16, 19),
        out_of_range="ignore",
        shadowing=SEPARABLE,
        transmission="off",  # the raw GO reflection, as roughdielectric's (no 1 − T cap)
    )
    fit = fit_microfacet(glass, kind="dielectric")
    assert fit.mitsuba["type"] == "roughdielectric"
    assert fit.mitsuba["int_ior"] == pytest.approx(1.5, rel=1e-6)
    assert fit.alpha == pytest.approx(0.3, rel=1e-6)
    with pytest.raises(ValueError, match="distribution"):
        fit_microfacet(glass, distribution="phong")
    with pytest.raises(ValueError, match="kind"):
        fit_microfacet(glass, kind="metal")
    with pytest.raises(ValueError, match="theta_max_deg"):
        fit_microfacet(glass, theta_max_deg=95)
    with pytest.raises(TypeError, match="BrdfTable"):
        fit_microfacet({"alpha": 0.3})
