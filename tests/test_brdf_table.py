"""BrdfTable: layout, interpolation, albedo quadrature, reciprocity; GO tables against
Mitsuba 3's ``roughconductor`` (run for real)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from brdf_helpers import SEPARABLE, mitsuba_fr, mitsuba_variant, random_directions
from emscatter.brdf import BrdfTable, build_table, frames
from emscatter.brdf.build import default_phi, default_phi_d, default_theta
from emscatter.spectra import GaussianCorrelation

ETA, KAPPA = 0.2, 3.0
EPS = (ETA + 1j * KAPPA) ** 2
WL = [0.5e-6]


def _random_iso(rng, n_wl=2, nt=7, nd=9):
    th = default_theta(nt)
    v = rng.uniform(0, 1, (n_wl, nt, nt, nd))
    v = v + v.transpose(0, 2, 1, 3)
    v[:, 0] = v[:, 0].mean(axis=-1, keepdims=True)  # at θ = 0 the azimuth is undefined
    v[:, :, 0] = v[:, :, 0].mean(axis=-1, keepdims=True)
    return BrdfTable(
        wavelengths=np.linspace(4e-7, 6e-7, n_wl),
        theta_i=th,
        theta_o=th,
        phi_d=default_phi_d(nd),
        values=v,
    )


def _random_aniso(rng, nt=5, npf=6):
    th, ph = default_theta(nt), default_phi(npf)
    v = rng.uniform(0, 1, (1, nt, npf, nt, npf))
    v = v + v.transpose(0, 3, 4, 1, 2)
    v[:, 0] = v[:, 0].mean(axis=1, keepdims=True)  # at θ = 0 the azimuth is undefined
    v[:, :, :, 0] = v[:, :, :, 0].mean(axis=3, keepdims=True)
    return BrdfTable(wavelengths=[5e-7], theta_i=th, theta_o=th, phi_i=ph, phi_o=ph, values=v)


def test_evaluate_reproduces_nodes_isotropic():
    rng = np.random.default_rng(0)
    t = _random_iso(rng)
    ti, to, pd = np.meshgrid(t.theta_i, t.theta_o, t.phi_d, indexing="ij")
    pi_ = rng.uniform(-5, 5, ti.shape)  # any φi: only Δφ matters
    sign = rng.choice([-1.0, 1.0], ti.shape)  # Δφ and −Δφ are the same node
    got = t.evaluate(frames.directions(ti, pi_), frames.directions(to, pi_ + sign * pd))
    np.testing.assert_allclose(got, t.values, rtol=1e-12, atol=1e-14)
    # scalar wavelength → no leading axis; between wavelengths → linear
    mid = t.evaluate_angles(ti, 0.0, to, pd, wavelength=5e-7)
    np.testing.assert_allclose(mid, t.values.mean(axis=0), rtol=1e-12)
    assert t.evaluate_angles(0.1, 0.0, 0.2, 3.0, wavelength=[4e-7, 6e-7]).shape == (2,)


def test_evaluate_reproduces_nodes_anisotropic():
    rng = np.random.default_rng(1)
    t = _random_aniso(rng)
    ti, pi_, to, po = np.meshgrid(*t.grid_axes, indexing="ij")
    wrap = 2 * math.pi * rng.integers(-2, 3, ti.shape)  # periodic in φ
    got = t.evaluate(frames.directions(ti, pi_ + wrap), frames.directions(to, po - wrap))
    np.testing.assert_allclose(got, t.values, rtol=1e-12, atol=1e-12)
    # halfway across the wrap interval [φ_last, 2π) is the mean of the two end nodes
    half = t.phi_o[-1] + 0.5 * (2 * math.pi - t.phi_o[-1])
    got = t.evaluate_angles(t.theta_i[2], t.phi_i[1], t.theta_o[3], half, wavelength=5e-7)
    want = 0.5 * (t.values[0, 2, 1, 3, -1] + t.values[0, 2, 1, 3, 0])
    assert got == pytest.approx(want, rel=1e-12)


def test_evaluate_at_chosen_wavelengths_and_without_copying_the_table():
    """Requested wavelengths (scalar, subsets, a non-adjacent pair) combine the table's
    wavelength columns linearly, and evaluation reads the table in place: a few points of a
    large table allocate far less than the table (a full copy per call once cost the
    anisotropic RGL export most of its time)."""
    import tracemalloc

    rng = np.random.default_rng(5)
    th, ph = default_theta(24), default_phi(48)
    wl = np.array([4e-7, 5e-7, 6e-7, 7e-7])
    v = rng.uniform(0, 1, (wl.size, th.size, ph.size, th.size, ph.size))
    t = BrdfTable(wavelengths=wl, theta_i=th, theta_o=th, phi_i=ph, phi_o=ph, values=v)
    wi = frames.directions(rng.uniform(0, 1.4, 50), rng.uniform(0, 6, 50))
    wo = frames.directions(rng.uniform(0, 1.4, 50), rng.uniform(0, 6, 50))
    full = t.evaluate(wi, wo)
    np.testing.assert_allclose(t.evaluate(wi, wo, wavelength=wl[[0, 3]]), full[[0, 3]], rtol=1e-13)
    np.testing.assert_allclose(t.evaluate(wi, wo, wavelength=wl[2]), full[2], rtol=1e-13)
    mid = t.evaluate(wi, wo, wavelength=[4.5e-7, 6.75e-7])
    np.testing.assert_allclose(mid[0], 0.5 * (full[0] + full[1]), rtol=1e-12)
    np.testing.assert_allclose(mid[1], 0.25 * full[2] + 0.75 * full[3], rtol=1e-12)
    tracemalloc.start()
    try:
        t.evaluate(wi, wo)
        t.evaluate(wi, wo, wavelength=5.5e-7)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 0.05 * v.nbytes, (peak, v.nbytes)


def test_horizon_grazing_and_wavelength_range():
    rng = np.random.default_rng(2)
    t = _random_iso(rng)
    up = np.array([0.3, 0.0, 0.9])
    down = np.array([0.3, 0.0, -0.1])
    flat = np.array([1.0, 0.0, 0.0])
    assert np.all(t.evaluate(up, down) == 0) and np.all(t.evaluate(flat, up) == 0)
    # beyond the last θ node (78.75° here) the last node's value holds up to grazing
    last = t.evaluate_angles(t.theta_i[-1], 0.0, 0.3, 1.0)
    near_grazing = t.evaluate_angles(math.radians(89.9), 0.0, 0.3, 1.0)
    np.testing.assert_allclose(near_grazing, last, rtol=1e-12)
    with pytest.raises(ValueError, match="outside the table's range"):
        t.evaluate(up, up, wavelength=7e-7)
    clamped = t.evaluate(up, up, wavelength=7e-7, wavelength_out_of_range="clamp")
    assert clamped == pytest.approx(t.evaluate(up, up, wavelength=6e-7))
    with pytest.raises(ValueError, match="polarized table"):
        t.evaluate(up, up, pol="hv")


def test_interpolant_is_reciprocal():
    rng = np.random.default_rng(3)
    for t in (_random_iso(rng), _random_aniso(rng)):
        assert t.reciprocity_error() == 0.0
        wi = random_directions(rng, 2000, math.radians(89))
        wo = random_directions(rng, 2000, math.radians(89))
        np.testing.assert_allclose(t.evaluate(wi, wo), t.evaluate(wo, wi), rtol=1e-12)


def test_albedo_weights_are_exact():
    rng = np.random.default_rng(4)
    # a Lambertian table (f = ρ/π) has albedo ρ, whatever the (non-uniform) grid
    th = np.sort(rng.uniform(0, 1.5, 6))
    t = BrdfTable(
        wavelengths=[5e-7],
        theta_i=th,
        theta_o=th,
        phi_d=[0.2, 1.0, 3.0],
        values=np.full((1, 6, 6, 3), 0.8 / math.pi),
    )
    np.testing.assert_allclose(t.albedo().total, 0.8, rtol=1e-13)
    a = _random_aniso(rng).replace(values=np.full((1, 5, 6, 5, 6), 1 / math.pi))
    np.testing.assert_allclose(a.albedo().total, 1.0, rtol=1e-13)
    # a non-constant table: the weights integrate its interpolant (dense midpoint rule)
    t = _random_iso(rng, n_wl=1)
    n = 1200
    tho = (np.arange(n) + 0.5) * (0.5 * math.pi / n)
    pdo = (np.arange(n) + 0.5) * (math.pi / n) - 0 * tho
    T, P = np.meshgrid(tho, pdo, indexing="ij")
    f = t.evaluate_angles(t.theta_i[3], 0.0, T, P)[0]
    dense = 2 * np.sum(f * np.cos(T) * np.sin(T)) * (0.5 * math.pi / n) * (math.pi / n)
    assert t.albedo().incoherent[0, 3] == pytest.approx(dense, rel=2e-5)


def test_table_rejects_bad_input():
    th = default_theta(4)
    ok = {
        "wavelengths": [5e-7],
        "theta_i": th,
        "theta_o": th,
        "phi_d": default_phi_d(3),
        "values": np.ones((1, 4, 4, 3)),
    }
    BrdfTable(**ok)
    bad = [
        ({"values": np.ones((1, 4, 4, 2))}, "shape"),
        ({"values": -np.ones((1, 4, 4, 3))}, "≥ 0"),
        ({"values": np.full((1, 4, 4, 3), np.nan)}, "NaN"),
        ({"theta_i": [0.0, 0.5, 0.4, 1.0]}, "increasing"),
        ({"theta_o": [0.0, 0.5, 1.0, 1.6]}, r"\[0, 1.5708\)"),
        ({"wavelengths": [-1.0]}, "positive"),
        ({"phi_i": default_phi(4)}, "not both"),
        ({"coherent": np.full((1, 4), 1.5)}, "≤ 1"),
    ]
    for change, match in bad:
        with pytest.raises(ValueError, match=match):
            BrdfTable(**{**ok, **change})


@pytest.fixture(scope="module")
def go_table():
    rough = GaussianCorrelation(0.15e-6, 1.0e-6)  # m = 0.3
    return build_table(
        rough, EPS, WL, method="go", resolution=(30, 61), out_of_range="ignore", shadowing=SEPARABLE
    )


def test_go_table_matches_mitsuba_at_nodes_and_between(go_table):
    mi = pytest.importorskip("mitsuba")
    if mitsuba_variant(mi) is None:
        pytest.skip("no Mitsuba variant loads here")
    t = go_table
    bsdf = {
        "type": "roughconductor",
        "distribution": "beckmann",
        "eta": ETA,
        "k": KAPPA,
        "alpha": 0.3,
    }
    rng = np.random.default_rng(5)
    i = rng.integers(0, t.theta_i.size, 600)
    o = rng.integers(0, t.theta_o.size, 600)
    d = rng.integers(0, t.phi_d.size, 600)
    pi_ = rng.uniform(0, 2 * math.pi, 600)
    wi = frames.directions(t.theta_i[i], pi_)
    wo = frames.directions(t.theta_o[o], pi_ + t.phi_d[d])
    theirs = mitsuba_fr(mi, bsdf, wi, wo)
    ours = t.evaluate(wi, wo, wavelength=WL[0])
    np.testing.assert_allclose(ours, t.values[0, i, o, d], rtol=1e-6, atol=1e-12 * ours.max())
    sig = theirs > 1e-4 * theirs.max()
    assert np.max(np.abs(ours - theirs)[sig] / theirs[sig]) < 1e-2
    # between nodes: the interpolation error of a 3°×3° grid on an α = 0.3 lobe
    wi = random_directions(rng, 3000, math.radians(80))
    wo = random_directions(rng, 3000, math.radians(80))
    theirs = mitsuba_fr(mi, bsdf, wi, wo)
    ours = t.evaluate(wi, wo, wavelength=WL[0])
    sig = theirs > 1e-2 * theirs.max()
    rel = np.abs(ours - theirs)[sig] / theirs[sig]
    assert np.median(rel) < 0.01 and np.percentile(rel, 90) < 0.05


def test_go_table_albedo_below_one_and_coherent_zero(go_table):
    alb = go_table.albedo()
    assert np.all(alb.total <= 1.0) and np.all(alb.coherent == 0)
    assert alb.total[0, 0] > 0.85  # a good metal, small slope: most energy reflected
    assert "GO" in go_table.metadata["coherent"]


def test_asymmetric_grid_is_reciprocal_within_interpolation_error():
    from emscatter.brdf.analytic import cook_torrance, table_from_function
    from emscatter.brdf.analytic.distributions import Beckmann

    def ct(wi, wo, lam):
        return cook_torrance(wi, wo, Beckmann(0.4), eps=EPS)

    ref = table_from_function(ct, WL, resolution=(24, 25))
    ti, to = default_theta(17), default_theta(29)  # θi and θo nodes differ
    ai, ao, pd = np.meshgrid(ti, to, ref.phi_d, indexing="ij")
    vals = ct(frames.directions(ai, 0.0), frames.directions(ao, pd), WL[0])[None]
    t = BrdfTable(wavelengths=WL, theta_i=ti, theta_o=to, phi_d=ref.phi_d, values=vals)
    assert not t.symmetric_grid
    rng = np.random.default_rng(9)
    wi = random_directions(rng, 4000, math.radians(75))
    wo = random_directions(rng, 4000, math.radians(75))
    exact = ct(wi, wo, WL[0])
    interp_err = np.abs(t.evaluate(wi, wo)[0] - exact)
    swap_err = np.abs(t.evaluate(wi, wo)[0] - t.evaluate(wo, wi)[0])
    assert swap_err.max() > 0  # not exact on an asymmetric grid ...
    scale = exact.max()
    assert swap_err.max() <= 2 * interp_err.max() + 1e-12 * scale  # ... but within the error
