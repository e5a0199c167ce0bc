"""The rest of the seed's chapter-2 catalogue (brdf.analytic.empirical): Lafortune 1997,
Strauss 1990, Neumann–Neumann–Szirmay-Kalos 1999 — reciprocity where the model has it (and a
measured failure where it does not), albedo ≤ 1 over parameter grids (and the regions where
the model itself breaks it), the chapter-3 Beckmann equivalence, tables."""

from __future__ import annotations

import math

import numpy as np
import pytest

from brdf_helpers import random_directions
from emscatter.brdf import analytic as A
from emscatter.brdf.analytic import empirical as E
from emscatter.brdf.analytic.equivalence import (
    ashikhmin_from_ward,
    beckmann_from_blinn,
    beckmann_from_phong,
)

GOLD = (0.2 + 3j) ** 2
THETA = np.radians([0.0, 30, 60, 75, 85, 89])

RECIPROCAL_CASES = {
    "lafortune-phong": lambda wi, wo: E.lafortune(wi, wo, E.lafortune_phong_lobe(20, 0.8)),
    "lafortune-multi": lambda wi, wo: E.lafortune(  # Lafortune 1997's anisotropic + retro lobes
        wi, wo, [[-1.1, -0.9, 1.0, 8.0], [0.5, 0.5, 0.6, 3.0]], kd=0.2
    ),
    "neumann-blinn": lambda wi, wo: E.neumann(wi, wo, 50, eps=GOLD, kd=0.1, ks=0.9),
    "neumann-phong": lambda wi, wo: E.neumann(wi, wo, 20, variant="phong", f0=0.9),
}


@pytest.mark.parametrize("name", sorted(RECIPROCAL_CASES))
def test_reciprocal_models_are_reciprocal(name):
    fn = RECIPROCAL_CASES[name]
    rng = np.random.default_rng(5)
    wi = random_directions(rng, 3000, math.radians(89))
    wo = random_directions(rng, 3000, math.radians(89))
    f = fn(wi, wo)
    np.testing.assert_allclose(f, fn(wo, wi), rtol=1e-12, atol=0)
    assert np.all(f >= 0) and np.all(np.isfinite(f)) and f.max() > 0


def test_strauss_is_not_reciprocal():
    """Strauss 1990's F(θi), c_s(θi) and the 1/cosθi of Q/(π cosθi) depend on the incidence
    alone: f(wi, wo) ≠ f(wo, wi) off the θi = θo diagonal (RECIPROCAL says so)."""
    assert not E.RECIPROCAL["strauss"]
    assert all(v for k, v in E.RECIPROCAL.items() if k != "strauss")
    rng = np.random.default_rng(3)
    wi = random_directions(rng, 2000, math.radians(85))
    wo = random_directions(rng, 2000, math.radians(85))
    a = E.strauss(wi, wo, 0.5, m=0.8, color=0.6)
    b = E.strauss(wo, wi, 0.5, m=0.8, color=0.6)
    rel = np.abs(a - b) / np.maximum(a, b)
    # measured: 34 % of the pairs differ by > 1 %, 99th percentile 0.50, max 0.72
    assert np.mean(rel > 0.01) > 0.2 and rel.max() > 0.5, (np.mean(rel > 0.01), rel.max())
    # on the diagonal (θi = θo, mirror pair) it is symmetric
    wi = wi[:5]
    wm = wi * np.array([-1.0, -1.0, 1.0])
    np.testing.assert_allclose(E.strauss(wi, wm, 0.5), E.strauss(wm, wi, 0.5), rtol=1e-12)


def test_lafortune_phong_lobe_is_normalized_phong():
    rng = np.random.default_rng(2)
    wi = random_directions(rng, 2000, math.radians(89))
    wo = random_directions(rng, 2000, math.radians(89))
    for n, rho in [(1.0, 1.0), (7.5, 0.4), (300.0, 0.9)]:
        np.testing.assert_allclose(
            E.lafortune(wi, wo, E.lafortune_phong_lobe(n, rho), kd=0.1),
            A.phong(wi, wo, n, ks=rho, kd=0.1),
            rtol=1e-10,
        )


def test_lafortune_albedo_at_normal_incidence_is_closed_form():
    """Lafortune lobe at wi = +z: (C_z cosθo)^n, albedo C_z^n 2π/(n+2) whatever C_x, C_y."""
    for lobe in ([-1.3, -0.7, 0.9, 6.0], [0.4, 0.8, 1.05, 30.0]):
        cz, n = lobe[2], lobe[3]
        alb = A.directional_albedo(lambda wi, wo, lobe=lobe: E.lafortune(wi, wo, lobe), [0.0])
        np.testing.assert_allclose(alb, cz**n * 2 * math.pi / (n + 2), rtol=1e-6)


@pytest.mark.parametrize("n", [1.0, 5.0, 20.0, 100.0, 1000.0])
def test_lafortune_phong_shaped_lobes_keep_albedo_below_one(n):
    alb = A.directional_albedo(lambda wi, wo: E.lafortune(wi, wo, E.lafortune_phong_lobe(n)), THETA)
    assert np.all(alb <= 1.0 + 5e-4), alb
    assert alb[0] == pytest.approx(1.0, abs=5e-4)


def test_lafortune_off_specular_lobes_break_energy():
    """The model's own failure (flagged in the module docstring): scaling C_x = C_y by r > 1
    over C_z (Lafortune's off-specular lobes) keeps the normal-incidence albedo and lets it
    exceed 1 toward grazing: n = 20, r = 1.05 → 1.10 at 30°; r = 1.2 → 7.5 at 60°."""
    cx, cy, cz, n = E.lafortune_phong_lobe(20)
    alb = A.directional_albedo(
        lambda wi, wo: E.lafortune(wi, wo, [1.05 * cx, 1.05 * cy, cz, n]), THETA
    )
    assert alb[0] == pytest.approx(1.0, abs=5e-4)
    assert alb.max() > 1.05
    alb = A.directional_albedo(
        lambda wi, wo: E.lafortune(wi, wo, [1.2 * cx, 1.2 * cy, cz, n]), THETA
    )
    assert alb.max() > 5


def test_strauss_terms():
    x = np.array([0.0, 1.0])
    np.testing.assert_allclose(E.strauss_fresnel(x), [0.0, 1.0], atol=1e-15)
    np.testing.assert_allclose(E.strauss_shadow(x), [1.0, 0.0], atol=1e-15)
    assert E.strauss_exponent(0.0) == 3.0 and E.strauss_exponent(0.5) == 6.0
    # s = 0, t = 0: r_d = 1, r_n = 0, at normal incidence F(0) = 0 → r_s = 0: Lambertian c/π
    wi = np.array([0.0, 0.0, 1.0])
    wo = random_directions(np.random.default_rng(1), 50, 1.5)
    np.testing.assert_allclose(E.strauss(wi, wo, 0.0, color=0.7), 0.7 / math.pi, rtol=1e-14)
    # diffuse albedo d r_d c with d = 1 − m s, r_d = (1 − s³)(1 − t) (Strauss 1990)
    s, m, t, c = 0.9, 0.4, 0.3, 0.8
    far = np.array([[math.sin(1.3), 0.0, math.cos(1.3)]])  # (R·V)^30 = 1e-17: no lobe
    ref = (1 - m * s) * (1 - s**3) * (1 - t) * c / math.pi
    np.testing.assert_allclose(E.strauss(wi, far, s, m=m, t=t, color=c), ref, rtol=1e-9)


def _strauss_albedo(theta, s, m, t, c):
    return A.directional_albedo(
        lambda wi, wo: E.strauss(wi, wo, s, m=m, t=t, color=c), theta, n_theta=96, n_phi=128
    )


def test_strauss_albedo_on_a_parameter_grid():
    """≤ 1 (quadrature 5e-4) over s ∈ [0.05, 0.98], m ∈ [0, 1], with a coloured (c = 0.2) or
    half-transparent (t = 0.5) surface up to θi = 89°, and for any c, t with s ≥ 0.3 up to
    θi = 60°. The model itself exceeds 1 for a white (c = 1) opaque (t = 0) surface, where
    Strauss's diffuse albedo ``(1 − m s)(1 − s³)`` and specular reflectance ``r_s`` are not
    bounded jointly, toward grazing (its specular ``Q_s/(π cosθi)`` has no cosθi to cancel):
    s = 0.05 reaches 1.009 at 75°, s = 0.3 1.35 and s = 0.6 1.54 at 89° (flagged in the
    module docstring and validation/brdf/catalogue.md)."""
    theta = np.radians([0.0, 30, 60, 75, 85, 89])
    worst = 0.0
    for s in (0.05, 0.3, 0.6, 0.9, 0.98):
        for m in (0.0, 1.0):
            for t, c in ((0.5, 1.0), (0.0, 0.2), (0.5, 0.2)):
                worst = max(worst, float(_strauss_albedo(theta, s, m, t, c).max()))
            if s >= 0.3:
                worst = max(worst, float(_strauss_albedo(theta[:3], s, m, 0.0, 1.0).max()))
    assert worst <= 1.0 + 5e-4, worst
    assert _strauss_albedo(np.radians([75.0]), 0.05, 0.0, 0.0, 1.0)[0] > 1.005
    assert _strauss_albedo(np.radians([89.0]), 0.3, 0.0, 0.0, 1.0)[0] > 1.3
    assert _strauss_albedo(np.radians([89.0]), 0.6, 0.0, 0.0, 1.0)[0] > 1.5


@pytest.mark.parametrize("variant", ["blinn", "phong"])
@pytest.mark.parametrize("n", [1.0, 10.0, 100.0, 1000.0])
def test_neumann_albedo_below_one_for_every_exponent(variant, n):
    for kw in ({}, {"eps": GOLD}, {"ks": 0.6, "kd": 0.4}):
        alb = A.directional_albedo(
            lambda wi, wo, kw=kw: E.neumann(wi, wo, n, variant=variant, **kw),
            THETA,
            n_theta=128,
            n_phi=128,
        )
        assert np.all(alb <= 1.0 + 5e-4), (kw, alb)
        assert np.all(alb > 0.01)


def test_neumann_phong_normal_incidence_albedo():
    """At wi = +z, max(cosθi, cosθo) = 1: albedo (n+1)/(2π) ∫ cosⁿθ cosθ dω = (n+1)/(n+2)."""
    for n in (2.0, 30.0):
        alb = A.directional_albedo(lambda wi, wo, n=n: E.neumann(wi, wo, n, variant="phong"), [0])
        assert alb[0] == pytest.approx((n + 1) / (n + 2), rel=1e-5)


def test_equivalent_beckmann_by_the_seed_criterion():
    # Strauss h = 3/(1 − s) is Table 3.1's (R·V)^h: the Phong equivalence
    s = 1 - 3 / 3.91
    assert E.equivalent_beckmann("strauss", s=s).value == pytest.approx(
        beckmann_from_phong(3.91).value, rel=1e-12
    )
    # the seed's m = 0.32 → Phong n = 3.9 → Strauss s ≈ 0.23, Blinn/NNSK n ≈ 17 (Figs. 3.4, 3.6)
    assert E.from_beckmann("strauss", 0.32)["s"] == pytest.approx(1 - 3 / 3.91, abs=0.005)
    assert E.from_beckmann("neumann", 0.32)["n"] == pytest.approx(17.0, abs=0.05)
    assert E.equivalent_beckmann("neumann", n=17).value == beckmann_from_blinn(17).value
    lobes = E.from_beckmann("lafortune", 0.2, rho=0.5)["lobes"]
    assert E.equivalent_beckmann("lafortune", lobes=lobes).value == pytest.approx(0.2, rel=2e-3)
    for model in ("phong", "blinn-phong", "neumann"):
        n = E.from_beckmann(model, 0.15)["n"]
        assert E.equivalent_beckmann(model, n=n).value == pytest.approx(0.15, rel=2e-3)
    with pytest.raises(ValueError, match="Phong-shaped"):
        E.equivalent_beckmann("lafortune", lobes=[-1.2, -1.0, 1.0, 10.0])
    with pytest.raises(ValueError, match="ward"):
        E.equivalent_beckmann("ward")


def test_seed_ward_ashikhmin_criterion():
    """The seed's §3.2.2 criterion as it states it: its figures are curves of γ, and the section
    on which both its pairs fit (Figs. 3.8–3.9: (10, 187) and (100, 100)) is φ = π/4, which
    fixes n_u + n_v; the exponents then split in the ratio m_x/m_y (its axes; n_u/n_v = m_y/m_x
    in ours). Ward (0.1, 0.8) → (175.7, 22.0): the seed's sums 197 and 200 are within 1.2 % of
    2N = 197.7; its split 187/10 = 18.7 is not the stated 8."""
    eq = ashikhmin_from_ward(0.1, 0.8, ratio="seed")
    nu, nv = eq.value
    assert nu / nv == pytest.approx(8.0, rel=1e-9)
    assert (nu, nv) == pytest.approx((175.7, 21.97), rel=2e-3)
    assert eq.error < 1e-3  # rms on the section, peak = 1
    assert 10 + 187 == pytest.approx(nu + nv, rel=0.005)
    assert 100 + 100 == pytest.approx(nu + nv, rel=0.015)
    with pytest.raises(ValueError, match="ratio"):
        ashikhmin_from_ward(0.1, 0.8, ratio="seeds")


def test_catalogue_models_make_tables():
    """Analytic models become BrdfTables the way the existing ones do (table_from_function):
    node values equal the model; reciprocity of the table follows the model's."""
    from emscatter.brdf import frames

    def laf(wi, wo, lam):
        return E.lafortune(wi, wo, E.lafortune_phong_lobe(12, 0.7), kd=0.2)

    def strauss(wi, wo, lam):
        return E.strauss(wi, wo, 0.6, m=0.5, color=0.8)

    tl = A.table_from_function(laf, [5e-7], resolution=(12, 13))
    ts = A.table_from_function(strauss, [5e-7], resolution=(12, 13))
    assert tl.reciprocity_error() < 1e-12
    assert ts.reciprocity_error() > 0.05
    ti, to, pd = np.meshgrid(tl.theta_i, tl.theta_o, tl.phi_d, indexing="ij")
    wi = frames.directions(ti.ravel(), np.zeros(ti.size))
    wo = frames.directions(to.ravel(), pd.ravel())
    np.testing.assert_allclose(tl.values[0].ravel(), laf(wi, wo, 5e-7), rtol=1e-12)
    np.testing.assert_allclose(ts.values[0].ravel(), strauss(wi, wo, 5e-7), rtol=1e-12)
    np.testing.assert_allclose(
        E.evaluate("strauss", wi, wo, s=0.6, m=0.5, color=0.8), strauss(wi, wo, 0), rtol=0
    )
    # the anisotropic one on an anisotropic grid: reciprocal, albedo ≤ 1, φ-dependent
    tp = A.table_from_function(
        lambda wi, wo, lam: E.poulin_fournier(wi, wo, 2.5, -0.3, ks=0.5, kd=0.5),
        [5e-7],
        resolution=(8, 12),
        anisotropic=True,
    )
    assert not tp.isotropic and tp.reciprocity_error() < 1e-12
    alb = tp.albedo().incoherent
    assert np.all(alb <= 1.0) and np.ptp(alb[0, -2]) > 0.05  # varies with φi at θi = 67.5°


def test_bad_parameters_are_named():
    wi = np.array([0.0, 0.0, 1.0])
    with pytest.raises(ValueError, match=r"s must be in \[0.0, 1.0\)"):
        E.strauss(wi, wi, 1.0)
    with pytest.raises(ValueError, match="m must be in"):
        E.strauss(wi, wi, 0.5, m=1.5)
    with pytest.raises(ValueError, match="lobes"):
        E.lafortune(wi, wi, [1.0, 2.0])
    with pytest.raises(ValueError, match="exponents"):
        E.lafortune(wi, wi, [-1.0, -1.0, 1.0, 0.0])
    with pytest.raises(ValueError, match="ks \\+ kd"):
        E.neumann(wi, wi, 10, ks=0.8, kd=0.4)
    with pytest.raises(ValueError, match="variant"):
        E.neumann(wi, wi, 10, variant="ward")
    with pytest.raises(ValueError, match="model must be one of"):
        E.evaluate("oren-nayar", wi, wi)
    with pytest.raises(ValueError, match="rho"):
        E.lafortune_phong_lobe(10, 1.5)


# --- Poulin & Fournier 1990 (brdf.analytic.cylinders) -----------------------------------


def _pf_brute_force(wi, wo, d, h, n_s=50.0, ks=1.0, kd=0.0, nodes=16000):
    """Independent reference: midpoint nodes on the arc and the base, a 2-D ray–circle test
    per node toward wi and wo (the neighbouring cylinders, both bounding ones on the base)."""
    pm = math.acos(-h)

    def proj(w):
        n = np.hypot(w[:, 0], w[:, 2])
        return (w[:, 0] / n)[:, None], (w[:, 2] / n)[:, None]

    def blocked(px, pz, ux, uz, cx, cz):
        dx, dz = cx - px, cz - pz
        t = dx * ux + dz * uz
        return (t > 0) & (dx * dx + dz * dz - t * t < 1)

    def local(ni, no):
        rv = 2 * ni * no - np.sum(wi * wo, -1)[:, None]
        return kd / math.pi + ks * (n_s + 2) / (2 * math.pi) * np.clip(rv, 0, 1) ** n_s

    phi = -pm + (np.arange(nodes) + 0.5) * 2 * pm / nodes
    nx, nz = np.sin(phi)[None], np.cos(phi)[None]
    ni, no = wi[:, :1] * nx + wi[:, 2:] * nz, wo[:, :1] * nx + wo[:, 2:] * nz
    v = (ni > 0) & (no > 0)
    for w in (wi, wo):
        ux, uz = proj(w)
        v &= ~blocked(nx, h + nz, ux, uz, np.where(ux >= 0, d, -d), h)
    tot = np.sum(np.where(v, local(ni, no) * ni * no, 0), 1) * 2 * pm / nodes
    half = math.sin(pm)
    length = d - 2 * half
    if length > 0:
        xb = (half + (np.arange(nodes) + 0.5) * length / nodes)[None]
        vb = np.ones((wi.shape[0], nodes), bool)
        for w in (wi, wo):
            ux, uz = proj(w)
            for cx in (0.0, d):
                vb &= ~blocked(xb, 0 * xb, ux, uz, cx, h)
        ci, co = wi[:, 2:], wo[:, 2:]
        tot = tot + np.sum(np.where(vb, local(ci, co) * ci * co, 0), 1) * length / nodes
    return tot / (d * wi[:, 2] * wo[:, 2])


PF_CASES = [
    (2.5, -0.3, {"ks": 0.0, "kd": 1.0}),
    (2.0, 0.0, {"ks": 0.5, "kd": 0.5, "n_s": 5.0}),
    (4.0, -0.1, {"n_s": 20.0}),
    (1.908, -0.3, {"ks": 0.8, "kd": 0.2}),
]


@pytest.mark.parametrize(("d", "h", "kw"), PF_CASES)
def test_poulin_fournier_matches_brute_force_and_is_reciprocal(d, h, kw):
    rng = np.random.default_rng(8)
    wi = random_directions(rng, 300, math.radians(89))
    wo = random_directions(rng, 300, math.radians(89))
    f = E.poulin_fournier(wi, wo, d, h, **kw)
    ref = _pf_brute_force(wi, wo, d, h, **kw)
    # measured: max |Δ| ≤ 2.6e-4 of the peak — the brute force's midpoint error at the
    # visibility edges (4000 → 16000 nodes moves it 1.2e-3 toward the closed-form limits)
    assert np.max(np.abs(f - ref)) < 5e-4 * ref.max()
    assert np.median(np.abs(f - ref) / np.maximum(ref, 1e-9)) < 1e-3
    np.testing.assert_allclose(f, E.poulin_fournier(wo, wi, d, h, **kw), rtol=1e-11)
    assert E.RECIPROCAL["poulin-fournier"]


def test_poulin_fournier_flat_limit_is_the_local_phong():
    rng = np.random.default_rng(9)
    wi = random_directions(rng, 500, math.radians(85))
    wo = random_directions(rng, 500, math.radians(85))
    f = E.poulin_fournier(wi, wo, 2.0, -0.99999, ks=0.7, kd=0.3, n_s=50)
    np.testing.assert_allclose(f, A.phong(wi, wo, 50, ks=0.7, kd=0.3), rtol=1e-3)


@pytest.mark.parametrize(("d", "h"), [(2.5, -0.3), (2.0, 0.0), (4.0, -0.1), (1.908, -0.3)])
def test_poulin_fournier_albedo_below_one_and_anisotropic(d, h):
    theta = np.radians([0.0, 30, 60, 75, 85, 89])
    for kw in ({"ks": 1.0, "kd": 0.0}, {"ks": 0.0, "kd": 1.0}):
        across = A.directional_albedo(
            lambda wi, wo, kw=kw: E.poulin_fournier(wi, wo, d, h, **kw),
            theta,
            n_theta=96,
            n_phi=128,
        )
        along = A.directional_albedo(
            lambda wi, wo, kw=kw: E.poulin_fournier(wi, wo, d, h, **kw),
            theta,
            phi_i=math.pi / 2,
            n_theta=96,
            n_phi=128,
        )
        assert np.all(across <= 1 + 5e-4) and np.all(along <= 1 + 5e-4), (across, along)
        assert np.all(across > 0.05) and np.all(along > 0.05)
        assert across[0] == pytest.approx(along[0], rel=1e-6)  # same wi = +z
        assert np.max(np.abs(across - along)) > 0.1  # anisotropic


def test_poulin_fournier_rms_slope():
    """m_x² = ∫ tan²φ cosφ dφ / d over the arc (slope −tanφ, dx = cosφ dφ), checked by
    quadrature; m_y = 0; diverges at h = 0 (vertical walls)."""
    from emscatter.brdf.grid import gauss_legendre

    d, h = 2.5, -0.3
    pm = math.acos(-h)
    x, w = gauss_legendre(400, -pm, pm)
    ref = math.sqrt(np.sum(w * np.tan(x) ** 2 * np.cos(x)) / d)
    eq = E.equivalent_beckmann("poulin-fournier", d=d, h=h)
    assert eq.value[0] == pytest.approx(ref, rel=1e-10) and eq.value[1] == 0.0
    from emscatter.brdf.analytic.cylinders import poulin_fournier_rms_slope

    assert poulin_fournier_rms_slope(2.0, 0.0) == math.inf
    with pytest.raises(ValueError, match="footprint"):
        E.poulin_fournier(np.array([0, 0, 1.0]), np.array([0, 0, 1.0]), 1.5, -0.3)
    with pytest.raises(ValueError, match="h must be in"):
        E.poulin_fournier(np.array([0, 0, 1.0]), np.array([0, 0, 1.0]), 2.5, 0.3)
