"""Textured (anisotropic) radio materials without Sionna: the ψ-resolved σ⁰ tables of
emscatter.radio.texture, the texture frame and its degenerate rule, the CLI option parser."""

from __future__ import annotations

import math

import numpy as np
import pytest

from emscatter import materials
from emscatter.coherent import coherent_amplitude
from emscatter.fresnel import fresnel_cos
from emscatter.radio import tables as tb
from emscatter.radio import texture as tx
from emscatter.spectra import GaussianCorrelation as G

F = 28e9
K = 2 * math.pi * F / 299_792_458.0
EPS = complex(materials.as_material("concrete").eps(frequency=F))
OPTS = tb.TableOptions(n_cos=33, n_cos_spm=9, n_theta=19, n_alpha=19, n_s=48, n_psi=7)
ANISO = G(sigma=1e-3, length=30e-3, length_y=12e-3)  # inside PO's range at 28 GHz
SWAPPED = G(sigma=1e-3, length=12e-3, length_y=30e-3)


def _tables(surface, method="po"):
    ignore = "ignore" if method == "go" else "raise"  # GO: (2kσ)² = 1.4, its coherent part only
    return tx.build_textured_tables(surface, EPS, F, method=method, options=OPTS,
                                    out_of_range=ignore)  # fmt: skip


def test_equal_lengths_give_the_isotropic_tables():
    """ℓx = ℓy: every ψ block of the textured lobe equals the isotropic table (its α ≥ 0 half)
    to rounding, and so do the diffuse share and the coherent part."""
    iso = G(sigma=1e-3, length=20e-3)
    a = tb.build_tables(iso, EPS, F, method="po", options=OPTS)
    b = _tables(iso)
    half = b.lobe[:, :, OPTS.n_alpha - 1 :]
    assert np.allclose(b.alpha_nodes[OPTS.n_alpha - 1 :], a.alpha_nodes, atol=1e-12)
    assert np.max(np.abs(half - a.lobe[None])) <= 1e-7 * a.lobe.max()
    # the other half is the mirror image (isotropic roughness)
    assert np.max(np.abs(b.lobe[:, :, ::-1] - b.lobe)) <= 1e-7 * a.lobe.max()
    assert np.max(np.abs(b.incoherent - a.incoherent[None])) <= 1e-9
    assert np.max(np.abs(b.coherent_at(0.7) - a.coherent)) <= 1e-15


def test_rotating_the_texture_by_90_degrees_swaps_the_lengths():
    """Surface (ℓx, ℓy) with its axis turned by 90° = surface (ℓy, ℓx): the lobe at incidence
    azimuth ψ − π/2 (scattered φ − π/2) of the first equals the lobe at (ψ, φ) of the second."""
    a, b = _tables(ANISO), _tables(SWAPPED)
    rng = np.random.default_rng(3)
    n = 400
    ti = rng.uniform(0.05, 1.4, n)
    psi = rng.uniform(-math.pi, math.pi, n)
    ts = rng.uniform(0.0, 1.5, n)
    ps = psi + rng.uniform(-0.6, 0.6, n)  # near the forward direction, where the lobe is
    la = tx.interpolate_textured_lobe(a, ti, psi - math.pi / 2, ts, ps - math.pi / 2)
    lb = tx.interpolate_textured_lobe(b, ti, psi, ts, ps)
    assert la.max() > 0.05
    assert np.max(np.abs(la - lb)) <= 1e-6 * la.max()
    # and the texture frame: a direction turned by 90° in the plane gives the turned axis
    n_ = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.6, 0.8, 0.0]])
    x1, y1, _ = tx.texture_frame(n_, (0.3, -0.2, 1.0))
    x2, _, _ = tx.texture_frame(n_[2:], y1[2])
    assert np.allclose(x2[0], y1[2], atol=1e-12)


def test_textured_table_is_reciprocal():
    """σ⁰_qp(i → s) = σ⁰_pq(s → i) (reversed propagation: azimuths + π): the PO solver to
    rounding, the interpolated table within its interpolation error (2 % of the lobe peak)."""
    from emscatter import solvers

    po = solvers.get("po")
    ti, ts, phi_i, phi_s = 0.5, 0.8, 0.3, 1.2
    one = np.ones(1)

    def sig(a, b, c, d):
        return po.bistatic(ANISO, EPS, K, a * one, b * one, c * one, d * one, coherent=False)

    fwd = sig(ti, ts, phi_s, phi_i).sigma0[..., 0]
    rev = sig(ts, ti, phi_i + math.pi, phi_s + math.pi).sigma0[..., 0]
    assert np.allclose(fwd, rev.T, rtol=1e-12)

    tab = _tables(ANISO)
    rng = np.random.default_rng(5)
    n = 300
    ti = rng.uniform(0.2, 1.2, n)
    ts = rng.uniform(0.2, 1.2, n)
    pi_ = rng.uniform(-math.pi, math.pi, n)
    ps = pi_ + rng.uniform(-0.5, 0.5, n)
    a = tx.interpolate_textured_lobe(tab, ti, pi_, ts, ps) * np.cos(ti)
    b = tx.interpolate_textured_lobe(tab, ts, ps + math.pi, ti, pi_ + math.pi) * np.cos(ts)
    b = b[[0, 2, 1, 3]]  # (hh, hv, vh, vv) → transposed pairs
    peak = max(a.max(), b.max())
    assert peak > 0.02
    assert np.max(np.abs(a - b)) <= 0.02 * peak


@pytest.mark.parametrize("method", ["po", "go"])
def test_kirchhoff_coherent_factor_depends_on_sigma_only(method):
    """The Kirchhoff coherent factor of a Gaussian surface is exp(−2k²σ²cos²θ) (Beckmann &
    Spizzichino 1963, ch. 5; Ulaby, Moore & Fung vol. II §12-3): the same for ℓx ≠ ℓy as for
    any isotropic ℓ, so the textured tables' coherent part does not depend on ψ."""
    th = np.linspace(0.1, 1.4, 7)
    fres = np.stack(fresnel_cos(EPS, np.cos(th)))
    kirchhoff = np.exp(-2.0 * (K * 1e-3 * np.cos(th)) ** 2)
    for surf in (ANISO, SWAPPED, G(sigma=1e-3, length=5e-3)):
        amp = coherent_amplitude(surf, EPS, K, th, method=method, out_of_range="ignore")
        assert np.allclose(amp.amplitude, fres * kirchhoff, rtol=1e-9, atol=0)
    tab = _tables(ANISO, method)
    assert tab.coherent_azimuth_spread <= 1e-12


def test_textured_lobe_depends_on_azimuth_and_conserves_energy():
    """The lobe of an anisotropic surface changes with ψ (wide across the short ℓy: at ψ = 0
    the lobe is wider out of the plane of incidence than at ψ = π/2), and
    coherent + incoherent ≤ 1 at every ψ, θ."""
    tab = _tables(ANISO)
    assert tab.lobe.shape == (7, 19, 37, 48, 4)
    assert np.all(tab.coherent_power + tab.incoherent <= 1.0 + 1e-9)
    vv0, vv90 = tab.lobe[0, 10, ..., 3], tab.lobe[-1, 10, ..., 3]  # θ = 45°, vv
    assert np.max(np.abs(vv0 - vv90)) > 0.2 * max(vv0.max(), vv90.max())
    side = OPTS.n_alpha - 1 + (OPTS.n_alpha - 1) // 2  # α = π/2: out of the incidence plane
    assert vv0[side, 10] > 1.5 * vv90[side, 10]


def test_texture_frame_and_degenerate_rule():
    n = np.array([[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]])
    x, y, deg = tx.texture_frame(n, (0.0, 0.0, 1.0))  # vertical grooves
    assert deg.tolist() == [False, False, True, True]
    assert np.allclose(x[:2], [[0, 0, 1], [0, 0, 1]])
    # floor and ceiling: the world axis least aligned with the normal (x)
    assert np.allclose(x[2:], [[1, 0, 0], [1, 0, 0]])
    assert np.allclose(np.sum(x * n, axis=-1), 0.0) and np.allclose(np.cross(n, x), y)
    x, _, deg = tx.texture_frame([[1.0, 1e-9, 0.0]], (1.0, 0.0, 0.0))
    assert deg[0] and np.allclose(x, [[0, 0, 1]], atol=1e-8)  # least aligned: z (|n_z| = 0)
    psi, flip = tx.fold_azimuth(np.radians([30.0, 150.0, -30.0, -150.0, 210.0]))
    assert np.allclose(np.degrees(psi), 30.0) and flip.tolist() == [False, True, True, False, False]


def test_parse_medium_option_and_bad_input():
    out = tx.parse_medium_option("concrete=0.001,0.03,0.012@vertical")
    assert out["medium"] == "concrete" and out["texture_direction"] == (0.0, 0.0, 1.0)
    assert (out["surface"].length, out["surface"].length_y) == (0.03, 0.012)
    out = tx.parse_medium_option("itu:brick = 2e-3, 0.02 @ 1,1,0")
    assert out["surface"].is_isotropic
    assert np.allclose(out["texture_direction"], [2**-0.5, 2**-0.5, 0.0])
    out = tx.parse_medium_option("wood=0.001,0.01")
    assert out["texture_direction"] is None
    for bad, word in (
        ("concrete", "NAME=σ"),
        ("concrete=0.001,0.03,0.01", "@DIR"),
        ("concrete=0.001,-0.03", "positive"),
        ("concrete=a,b", "numbers"),
        ("concrete=0.001,0.03,0.01@0,0,0", "direction"),
        ("concrete=0.001,0.03,0.01@up", "direction"),
    ):
        with pytest.raises(ValueError, match=word):
            tx.parse_medium_option(bad)
    with pytest.raises(ValueError, match="texture_direction"):
        tx.check_direction((0, 0, float("nan")))
    with pytest.raises(ValueError, match="n_psi"):
        tb.TableOptions(n_psi=1)


def test_material_spec_carries_the_texture_direction():
    from emscatter import radio

    spec = radio.MaterialSpec(surface=ANISO, medium="concrete", method="po",
                              options=OPTS, texture_direction=(0, 0, 2))  # fmt: skip
    assert np.allclose(spec.texture_direction, [0, 0, 1])
    tab = spec.tables(F)
    assert isinstance(tab, tx.TexturedTables) and tab.lobe.shape[0] == OPTS.n_psi
    iso = radio.MaterialSpec(surface=G(sigma=1e-3, length=20e-3), medium="concrete",
                             method="po", options=OPTS)  # fmt: skip
    assert not isinstance(iso.tables(F), tx.TexturedTables)
    with pytest.raises(ValueError, match="texture_direction"):
        radio.MaterialSpec(surface=ANISO, medium="concrete", texture_direction=(0, 0, 0))
