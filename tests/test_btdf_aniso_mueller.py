"""The Mueller part of anisotropic GO BTDF tables (:mod:`emscatter.brdf.btdf_aniso`,
``polarized=True``): exact against the direct Mueller BTDF at the nodes under every mirror of
the folded φi, M00 equal to the unpolarized table (float64 and float32), ℓx = ℓy equal to the
isotropic Mueller table, reciprocity, the memory check (×17) and bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest

from emscatter.brdf import frames
from emscatter.brdf.btdf import mueller_btdf_at
from emscatter.brdf.btdf_aniso import AnisotropicBtdfTable, build_anisotropic_btdf_table
from emscatter.brdf.btdf_table import build_btdf_table
from emscatter.spectra import GaussianCorrelation

LAM = 550e-9
EPS = 2.25
# Beckmann α = 2σ/ℓ: 0.3 along x, 0.15 along y
ANISO = GaussianCorrelation(1.5e-7, 2 * 1.5e-7 / 0.3, length_y=2 * 1.5e-7 / 0.15, dimension=2)
KW = {"n_theta": 6, "n_phi_i": 5, "n_theta_t": 40, "n_phi": 80}  # φi 22.5°, Δφ 4.5° nodes


@pytest.fixture(scope="module")
def table():
    return build_anisotropic_btdf_table(ANISO, EPS, [LAM], polarized=True, **KW)


def _node_pairs(t, sign, offset):
    """Every node pair off the poles (θ = 0 has no h/v basis), φi mapped by a mirror
    (``sign = −1``) and/or a half turn (``offset = π``) out of the stored quarter."""
    ti, pi_, tt, pd = np.meshgrid(
        t.theta_i[1:], t.phi_i, t.theta_t[1::3], t.phi_d[::3], indexing="ij"
    )
    phi = sign * pi_ + offset
    return frames.directions(ti, phi), frames.directions(math.pi - tt, phi + sign * pd)


@pytest.mark.parametrize("frame", ["emscatter", "mitsuba"])
def test_equals_the_direct_mueller_btdf_at_nodes_under_every_mirror(table, frame):
    """At the nodes the table is :func:`mueller_btdf_at` to rounding (measured 5e-15 of the
    peak) for φi in all four quadrants: the mirrors act as P M P, the half turn not at all."""
    assert np.array_equal(table.mueller[:, 0, 0], table.values)
    for sign in (1.0, -1.0):
        for offset in (0.0, math.pi):
            wi, wo = _node_pairs(table, sign, offset)
            ref = mueller_btdf_at(ANISO, EPS, LAM, wi, wo, frame=frame)
            got = table.evaluate_mueller(wi, wo, LAM, frame=frame)
            assert ref[0, 0].max() > 0.1
            np.testing.assert_allclose(got, ref, rtol=0, atol=1e-12 * ref[0, 0].max())
            # the polarization is real: off the plane of incidence U and V mix in
            assert np.abs(ref[2, 0]).max() > 1e-3 * ref[0, 0].max()


def test_m00_is_the_unpolarized_table_between_nodes_float64_and_float32(table):
    """Random pairs anywhere (between nodes, any φi): M00 = :meth:`evaluate` to 1e-12 in
    float64 and to float32 rounding (1e-6) in a float32 table, whose M00 is its values."""
    rng = np.random.default_rng(4)
    n = 8000
    wi = frames.directions(rng.uniform(0, 1.4, n), rng.uniform(0, 2 * math.pi, n))
    wo = frames.directions(math.pi - rng.uniform(0, 1.4, n), rng.uniform(0, 2 * math.pi, n))
    f = table.evaluate(wi, wo, LAM)
    assert np.count_nonzero(f > 1e-3 * f.max()) > 500
    m = table.evaluate_mueller(wi, wo, LAM)
    np.testing.assert_allclose(m[0, 0], f, rtol=1e-12, atol=1e-14 * f.max())
    t32 = build_anisotropic_btdf_table(ANISO, EPS, [LAM], polarized=True, dtype="float32", **KW)
    assert t32.mueller.dtype == np.float32 and np.array_equal(t32.mueller[:, 0, 0], t32.values)
    m32 = t32.evaluate_mueller(wi, wo, LAM)
    np.testing.assert_allclose(m32, m, rtol=0, atol=1e-6 * f.max())


def test_isotropic_surface_equals_the_isotropic_mueller_table():
    """ℓx = ℓy: on the same θ and Δφ nodes the anisotropic Mueller table equals
    ``BtdfTable.evaluate_mueller`` (Mitsuba's frames) at random pairs, any φi, to rounding."""
    iso = GaussianCorrelation(1.5e-7, 1e-6, dimension=2)
    kw = {"n_theta": 10, "n_theta_t": 40}
    a = build_anisotropic_btdf_table(iso, EPS, [LAM], n_phi_i=3, n_phi=180, polarized=True, **kw)
    b = build_btdf_table(iso, EPS, [LAM], n_phi=91, polarized=True, **kw)
    rng = np.random.default_rng(2)
    n = 3000
    wi = frames.directions(rng.uniform(0.05, 1.4, n), rng.uniform(0, 2 * math.pi, n))
    wo = frames.directions(math.pi - rng.uniform(0.05, 1.4, n), rng.uniform(0, 2 * math.pi, n))
    ma, mb = a.evaluate_mueller(wi, wo, LAM), b.evaluate_mueller(wi, wo, LAM)
    assert mb[0, 0].max() > 0.1
    np.testing.assert_allclose(ma, mb, rtol=0, atol=1e-10 * mb[0, 0].max())


def test_reciprocity_eps_weighted_transpose():
    """Reciprocity of the transmitted field (Saxon 1955; the isotropic tests' form
    σ⁰_t,pq(ε; k̂i → k̂t) = ε σ⁰_t,qp(1/ε; −k̂t → −k̂i), tests/test_btdf_po.py) carried to the
    Mueller tables: f_t is symmetric in the two cosines, so M(ε; wi → wo) =
    ε D M(1/ε; wi′ → wo′)ᵀ D, D = diag(1, 1, 1, −1) (Mueller of a transposed Jones matrix), with
    the reverse path wi′ = (θt, φ(wo)), wo′ = (π − θi, φ(wi)) in emscatter's h/v bases. Both
    tables on swapped θ nodes and φ nodes that map onto each other: exact to rounding
    (measured 1e-15)."""
    th = np.radians(np.arange(0, 90, 4.5))
    kw = {"n_phi_i": 5, "n_phi": 80, "polarized": True}
    fwd = build_anisotropic_btdf_table(ANISO, EPS, [LAM], theta_i=th, theta_t=th[:12], **kw)
    rev = build_anisotropic_btdf_table(ANISO, 1 / EPS, [LAM], theta_i=th[:12], theta_t=th, **kw)
    ti, a, tt, dp = np.meshgrid(th[1:16], fwd.phi_i, th[1:12], fwd.phi_d[::5], indexing="ij")
    got = fwd.evaluate_mueller(
        frames.directions(ti, a), frames.directions(math.pi - tt, a + dp), LAM, frame="emscatter"
    )
    back = rev.evaluate_mueller(
        frames.directions(tt, a + dp), frames.directions(math.pi - ti, a), LAM, frame="emscatter"
    )
    d = np.array([1.0, 1.0, 1.0, -1.0])
    want = EPS * np.einsum("i,ji...,j->ij...", d, back, d)
    assert got[0, 0].max() > 0.1 and np.count_nonzero(got[0, 0] > 1e-3) > 1000
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-10 * got[0, 0].max())


def test_memory_check_counts_the_mueller_part_and_bad_input(table):
    n = 6 * 5 * 40 * 80 * 8  # bytes of the unpolarized values
    limit = 8 * n + 80 * 8 * (1 << 20)  # room for 1× (+ its chunk), not for 17×
    build_anisotropic_btdf_table(ANISO, EPS, [LAM], memory_limit_bytes=limit, **KW)
    with pytest.raises(MemoryError, match="polarized=False"):
        build_anisotropic_btdf_table(
            ANISO, EPS, [LAM], memory_limit_bytes=limit, polarized=True, **KW
        )
    with pytest.raises(ValueError, match="polarized must be True or False"):
        build_anisotropic_btdf_table(ANISO, EPS, [LAM], polarized="yes", **KW)
    plain = build_anisotropic_btdf_table(ANISO, EPS, [LAM], **KW)
    with pytest.raises(ValueError, match="no Mueller part"):
        plain.evaluate_mueller([0, 0, 1.0], [0, 0, -1.0])
    with pytest.raises(ValueError, match="frame must be"):
        table.evaluate_mueller([0, 0, 1.0], [0, 0, -1.0], frame="pbrt")
    bad = np.array(table.mueller)
    bad[0, 0, 0, 1, 1, 1, 1] += 1.0
    with pytest.raises(ValueError, match=r"mueller\[:, 0, 0\] must equal values"):
        table.replace(mueller=bad)
    with pytest.raises(ValueError, match="mueller must have shape"):
        table.replace(mueller=bad[..., :3])
    bad[0, 1, 2, 1, 1, 1, 1] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        table.replace(mueller=bad)
    assert isinstance(table.replace(metadata={"x": 1}), AnisotropicBtdfTable)
    assert "Mueller" in table.describe()
