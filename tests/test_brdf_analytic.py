"""The seed's analytic models: normalized distributions, Smith Λ, Cook–Torrance = emscatter's
geometric optics, reciprocity and energy of every model."""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest

from brdf_helpers import SEPARABLE, go_fr, random_directions
from emscatter.brdf import analytic as A
from emscatter.brdf import build_table, frames
from emscatter.brdf.analytic.distributions import (
    GGX,
    AshikhminShirleyDistribution,
    Beckmann,
    BlinnPhongDistribution,
    SeedDistribution,
    _Radial,
)
from emscatter.brdf.grid import gauss_legendre
from emscatter.spectra import GaussianCorrelation

EPS = (0.2 + 3j) ** 2
# the seed's Figs. 3.13–3.17 parameters
SEED = [
    SeedDistribution("uniform", a=0.1),
    SeedDistribution("exponential", lam=0.5),
    SeedDistribution("rayleigh", sigma=0.1),
    SeedDistribution("cauchy", a=0.1),
    SeedDistribution("simpson", a=1.0),
]
DISTS = [
    Beckmann(0.3),
    Beckmann(0.1, 0.5),
    GGX(0.2, 0.4),
    BlinnPhongDistribution(17),
    AshikhminShirleyDistribution(10, 187),
    *SEED,
]


def _hemisphere_integral(fn, breaks=(), n=300, m=128):
    pts = sorted({0.0, 0.5 * math.pi, *breaks})
    xs, ws = [], []
    x, w = gauss_legendre(n)
    for lo, hi in zip(pts[:-1], pts[1:], strict=True):
        xs.append(lo + 0.5 * (hi - lo) * (x + 1))
        ws.append(0.5 * (hi - lo) * w)
    th, wt = np.concatenate(xs), np.concatenate(ws)
    xp, wp = gauss_legendre(m)
    T, P = np.meshgrid(th, math.pi * (xp + 1), indexing="ij")
    val = fn(frames.directions(T, P), T) * np.sin(T)
    return np.einsum("ij,i,j->", val, wt, math.pi * wp)


@pytest.mark.parametrize("dist", DISTS, ids=lambda d: d.describe())
def test_distributions_are_normalized(dist):
    total = _hemisphere_integral(lambda h, t: dist(h) * np.cos(t), getattr(dist, "breaks", ()))
    assert total == pytest.approx(1.0, abs=1e-6)


def test_numeric_smith_lambda_matches_beckmann_closed_form():
    class RadialBeckmann(_Radial):
        name = "radial-beckmann"

        def shape(self, t):
            return np.exp(-(np.tan(t) ** 2) / 0.09) / np.cos(t) ** 4

    w = frames.directions(np.radians([10, 40, 60, 75, 85, 89, 89.9]), 0.3)
    g_num = 1 / (1 + RadialBeckmann().smith_lambda(w))
    g_exact = 1 / (1 + Beckmann(0.3).smith_lambda(w))
    np.testing.assert_allclose(g_num, g_exact, rtol=1e-4)
    assert RadialBeckmann().rms_slope == pytest.approx(0.3, rel=1e-6)


def test_seed_fresnel_equals_complex_fresnel():
    c = np.linspace(0.0, 1.0, 101)
    for n, k in ((0.2, 3.0), (1.5, 0.0), (1.6, 0.2), (0.05, 4.2)):
        np.testing.assert_allclose(
            A.fresnel_seed(n, k, c), A.fresnel_unpolarized((n + 1j * k) ** 2, c), rtol=1e-12
        )


@pytest.mark.parametrize("eps", [EPS, "pec", 2.25])
@pytest.mark.parametrize("shadow", [True, False])
def test_cook_torrance_beckmann_is_geometric_optics(eps, shadow):
    rng = np.random.default_rng(3)
    wi = random_directions(rng, 3000, math.radians(89))
    wo = random_directions(rng, 3000, math.radians(89))
    for rough, dist in (
        (GaussianCorrelation(0.15, 1.0), Beckmann(0.3)),
        (GaussianCorrelation(0.1, 0.5, length_y=1.5), Beckmann(0.4, 0.4 / 3)),
    ):
        ct = A.cook_torrance(wi, wo, dist, eps=eps, shadowing_kind="smith" if shadow else "none")
        go_f = go_fr(rough, eps, wi, wo, shadowing=SEPARABLE if shadow else False)
        np.testing.assert_allclose(ct, go_f, rtol=1e-10, atol=1e-300)


def _ct_seed(dist, wi, wo):
    return A.cook_torrance(wi, wo, dist, f0=0.9)


MODELS = {
    "ct-beckmann-smith": lambda wi, wo: A.cook_torrance(wi, wo, Beckmann(0.3), eps=EPS),
    "ct-ggx-smith": lambda wi, wo: A.cook_torrance(wi, wo, GGX(0.3), eps="pec"),
    "ct-blinn-phong-smith": lambda wi, wo: A.cook_torrance(wi, wo, BlinnPhongDistribution(17)),
    "ct-beckmann-schlick": lambda wi, wo: A.cook_torrance(wi, wo, shadowing_kind="schlick"),
    "ct-beckmann-blinn": lambda wi, wo: A.cook_torrance(wi, wo, shadowing_kind="blinn"),
    "ct-as-blinn": lambda wi, wo: A.cook_torrance(
        wi, wo, AshikhminShirleyDistribution(10, 187), shadowing_kind="blinn"
    ),
    **{f"ct-{d.name}-smith": functools.partial(_ct_seed, d) for d in SEED},
    "ward": lambda wi, wo: A.ward(wi, wo, 0.3),
    "ward-aniso": lambda wi, wo: A.ward(wi, wo, 0.1, 0.8),
    "ward-corrected": lambda wi, wo: A.ward(wi, wo, 0.3, corrected=True),
    "phong": lambda wi, wo: A.phong(wi, wo, 4, ks=0.6, kd=0.4),
    "ashikhmin-shirley": lambda wi, wo: A.ashikhmin_shirley(wi, wo, 10, 187, rs=0.05, rd=0.9),
}
THETA = np.radians([0.0, 30, 60, 75, 85, 89])


@pytest.mark.parametrize("name", sorted(MODELS))
def test_models_are_reciprocal_and_conserve_energy(name):
    fn = MODELS[name]
    rng = np.random.default_rng(11)
    wi = random_directions(rng, 2000, math.radians(89))
    wo = random_directions(rng, 2000, math.radians(89))
    np.testing.assert_allclose(fn(wi, wo), fn(wo, wi), rtol=1e-12)
    assert np.all(fn(wi, wo) >= 0)
    breaks = SEED[0].breaks if "uniform" in name else ()
    alb = A.directional_albedo(fn, THETA, n_theta=96, n_phi=128, theta_h_breaks=breaks)
    assert np.all(alb <= 1.0 + 5e-4), f"albedo {alb}"  # quadrature error ~1e-4
    assert np.all(alb > 0.05)


def test_normalizations_and_documented_energy_excess():
    # normalized Phong: albedo k_s at normal incidence exactly; Beckmann CT with small slope ≈ 1
    alb = A.directional_albedo(lambda wi, wo: A.phong(wi, wo, 4), [0.0])
    assert alb[0] == pytest.approx(1.0, abs=1e-6)
    alb = A.directional_albedo(lambda wi, wo: A.cook_torrance(wi, wo, Beckmann(0.1)), [0.0])
    assert alb[0] == pytest.approx(1.0, abs=1e-3)
    # the usual Blinn–Phong (n+8)/(8π) normalization overshoots at normal incidence
    alb = A.directional_albedo(lambda wi, wo: A.blinn_phong(wi, wo, 17), [0.0])
    assert 1.05 < alb[0] < 1.08
    # without shadowing, Cook–Torrance (= GO) exceeds 1 at grazing, as GO does
    alb = A.directional_albedo(
        lambda wi, wo: A.cook_torrance(wi, wo, shadowing_kind="none"), np.radians([30.0, 89.0])
    )
    assert alb[0] < 1 < 5 < alb[1]


def test_analytic_table_equals_geometric_optics_table():
    rough = GaussianCorrelation(0.15e-6, 1.0e-6)
    go = build_table(
        rough,
        EPS,
        [5e-7],
        method="go",
        resolution=(12, 13),
        out_of_range="ignore",
        shadowing=SEPARABLE,
    )
    ct = A.table_from_function(
        lambda wi, wo, lam: A.cook_torrance(wi, wo, Beckmann(0.3), eps=EPS),
        [5e-7],
        resolution=(12, 13),
    )
    assert not go.metadata["energy"]["remedy_applied"]
    np.testing.assert_allclose(ct.values, go.values, rtol=1e-9, atol=1e-300)
    assert ct.reciprocity_error() < 1e-12


def test_bad_parameters_are_named():
    with pytest.raises(ValueError, match="kind"):
        SeedDistribution("gamma", a=1)
    with pytest.raises(ValueError, match="lam"):
        SeedDistribution("exponential", a=1)
    with pytest.raises(ValueError, match="alpha"):
        Beckmann(-0.1)
    with pytest.raises(ValueError, match="shadowing"):
        A.cook_torrance([0, 0, 1], [0, 0, 1], shadowing_kind="torrance")
    with pytest.raises(ValueError, match="Schlick"):
        A.cook_torrance([0, 0, 1], [0, 0, 1], GGX(0.2), shadowing_kind="schlick")
    with pytest.raises(ValueError, match="Smith"):
        A.cook_torrance([0, 0, 1], [0, 0, 1], AshikhminShirleyDistribution(5, 5))
    with pytest.raises(ValueError, match="not both"):
        A.cook_torrance([0, 0, 1], [0, 0, 1], eps=2.0, f0=0.5)
