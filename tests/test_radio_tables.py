"""The radio bridge without Sionna: coherent amplitudes, the time-convention flip, the rough
slab, the per-frequency tables, media and scenes (NumPy only, in-process)."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import emscatter as em
from emscatter import materials
from emscatter.coherent import (
    ament_factor,
    boithias_factor,
    coherent_amplitude,
    kirchhoff_transmission_factor,
    rayleigh_parameter,
)
from emscatter.conventions import ConventionError, wavenumber
from emscatter.fresnel import fresnel
from emscatter.radio import (
    ConductiveMedium,
    EnergyWarning,
    MaterialSpec,
    RadioValidityWarning,
    TableOptions,
    build_log,
    build_tables,
    reset_build_log,
    resolve_medium,
    scenes,
    slab_coefficients,
    to_sionna,
)
from emscatter.radio.convention import from_sionna, sionna_eps_conductivity, sionna_permittivity
from emscatter.radio.tables import (
    clear_cache,
    interpolate_lobe,
    lobe_coordinates,
    lobe_directions,
)
from emscatter.solvers.kirchhoff import common as kirchhoff_common
from emscatter.solvers.select import ValidityError
from emscatter.solvers.spm import model as spm

SMALL = TableOptions(n_cos=33, n_cos_spm=9, n_theta=12, n_alpha=13, n_s=32)
EPS = 5.24 + 0.6j
TH = np.radians([0.0, 20.0, 45.0, 70.0, 85.0])


# ------------------------------------------------------------------ coherent amplitude
@pytest.mark.parametrize(
    "rough, f, method",
    [
        (em.GaussianCorrelation(sigma=0.2e-3, length=5e-3), 28e9, "spm"),
        (em.GaussianCorrelation(sigma=1e-3, length=10e-3), 28e9, "po"),
        (em.GaussianCorrelation(sigma=3e-3, length=20e-3), 140e9, "go"),
    ],
)
def test_coherent_amplitude_power_is_the_solvers_coherent_reflectivity(rough, f, method):
    k = wavenumber(frequency=f)
    c = coherent_amplitude(rough, EPS, k, TH)
    assert c.method == method
    if method == "spm":
        ref = spm.coherent_reflectivity(rough, EPS, k, TH)
    else:
        ref = kirchhoff_common.coherent_reflectivity(rough, EPS, k, TH)
    np.testing.assert_allclose(np.abs(c.amplitude) ** 2, ref, rtol=1e-12, atol=1e-300)
    np.testing.assert_allclose(c.power, ref, rtol=1e-12, atol=1e-300)
    if method != "spm":  # the Kirchhoff mean field's factor is real: Fresnel's phase
        rh, rv = fresnel(EPS, TH)
        np.testing.assert_allclose(np.angle(c.amplitude[0]), np.angle(rh), atol=1e-12)
        np.testing.assert_allclose(np.angle(c.amplitude[1]), np.angle(rv), atol=1e-12)


def test_coherent_amplitude_flat_limit_is_fresnel():
    k = wavenumber(frequency=3.5e9)
    c = coherent_amplitude(em.GaussianCorrelation(sigma=1e-7, length=5e-3), EPS, k, TH)
    rh, rv = fresnel(EPS, TH)
    np.testing.assert_allclose(c.amplitude, np.stack([rh, rv]), rtol=0, atol=1e-9)


def test_roughness_factors():
    k, sigma = wavenumber(frequency=28e9), 1e-3
    th = np.radians([0.0, 30.0, 60.0, 89.0])
    g = rayleigh_parameter(k, sigma, th)
    np.testing.assert_allclose(g, (2 * k * sigma * np.cos(th)) ** 2)
    np.testing.assert_allclose(ament_factor(k, sigma, th), np.exp(-g / 2))
    # Boithias: exp(-g/2) I0(g/2) = 1 - g/2 + 3g²/16 ... for small g; ~1/sqrt(π g) for large
    small = 1e-3
    assert boithias_factor(k, math.sqrt(small) / (2 * k), 0.0) == pytest.approx(
        1 - small / 2 + 3 * small**2 / 16, rel=1e-9
    )
    big = 400.0
    assert boithias_factor(k, math.sqrt(big) / (2 * k), 0.0) == pytest.approx(
        1 / math.sqrt(math.pi * big), rel=2e-3
    )
    assert np.all(boithias_factor(k, sigma, th) >= ament_factor(k, sigma, th))
    # Kirchhoff transmission: exp(-σ²(k1z-k2z)²/2); no change across an index-matched interface
    assert kirchhoff_transmission_factor(1.0, 1.0, 1.0) == 1.0


# ------------------------------------------------------------------ time convention
def test_time_convention_flip_is_one_conjugation():
    eps = materials.itu("concrete").eps(frequency=28e9)
    eta = sionna_permittivity(eps)
    assert np.imag(eta) < 0 and eta == np.conj(eps)
    # Sionna's η = ε′ − jσ/(ωε₀) with the ITU (ε′, σ) at 28 GHz
    er, sig = materials.itu("concrete").eps_real_and_conductivity(28e9)
    assert eta == pytest.approx(er - 1j * sig / (2 * math.pi * 28e9 * 8.8541878128e-12), rel=1e-9)
    assert sionna_eps_conductivity(eps, 28e9) == pytest.approx((float(er), float(sig)), rel=1e-12)
    r = fresnel(eps, 0.3)[1]
    assert to_sionna(r) == np.conj(r) and from_sionna(to_sionna(r)) == r
    with pytest.raises(ConventionError, match="numpy.conj"):
        sionna_permittivity(5.0 - 1.0j)


# ------------------------------------------------------------------ slab
def _itu_slab_engineering(eta, c, k, d):
    """ITU-R P.2040-3 eqs. 43–44 as printed (exp(+jωt))."""
    s2 = 1 - c * c
    root = np.sqrt(eta - s2)
    rte = (c - root) / (c + root)
    rtm = (eta * c - root) / (eta * c + root)
    q = k * d * root
    e1, e2 = np.exp(-1j * q), np.exp(-2j * q)
    out = []
    for r in (rte, rtm):
        den = 1 - r * r * e2
        out.append((r * (1 - e2) / den, (1 - r * r) * e1 / den))
    return out[0][0], out[1][0], out[0][1], out[1][1]


def test_flat_slab_is_the_itu_slab_and_conserves_energy():
    c = np.linspace(0.01, 1.0, 40)
    k = wavenumber(frequency=28e9)
    for eps, d in ((6.3 + 0.05j, 0.006), (2.7 + 0.1j, 0.0125), (5.24, 0.1)):
        ours = np.stack(slab_coefficients(eps, c, k, d))
        theirs = np.stack(_itu_slab_engineering(np.conj(eps), c, k, d))
        np.testing.assert_allclose(to_sionna(ours), theirs, atol=1e-12)
    # loss-free slab: |R|² + |T|² = 1 per polarization
    rh, rv, th, tv = slab_coefficients(4.0, c, k, 0.02)
    np.testing.assert_allclose(np.abs(rh) ** 2 + np.abs(th) ** 2, 1.0, atol=1e-12)
    np.testing.assert_allclose(np.abs(rv) ** 2 + np.abs(tv) ** 2, 1.0, atol=1e-12)


def test_rough_slab_limits():
    c = np.linspace(0.05, 1.0, 20)
    k = wavenumber(frequency=140e9)
    eps = materials.itu("concrete").eps(frequency=140e9)
    front = np.stack(fresnel(eps, np.arccos(c))) * 0.5
    # half-space: the front face only, nothing transmitted
    rh, rv, th, tv = slab_coefficients(eps, c, k, None, sigma=1e-3, front=front)
    np.testing.assert_allclose(np.stack([rh, rv]), front)
    assert np.all(th == 0) and np.all(tv == 0)
    # thick lossy wall: the back face is invisible, R → front face
    rh, rv, _, _ = slab_coefficients(eps, c, k, 0.5, sigma=1e-3, front=front)
    np.testing.assert_allclose(np.stack([rh, rv]), front, atol=1e-12)
    # roughness never adds coherent transmission; its factors stay bounded
    flat = np.stack(slab_coefficients(eps, c, k, 0.01)[2:])
    rough = np.stack(slab_coefficients(eps, c, k, 0.01, sigma=0.3e-3)[2:])
    assert np.all(np.abs(rough) <= np.abs(flat) + 1e-15)
    # a Drude-like metal (Re ε < 0) must not blow the Kirchhoff factors up
    out = np.stack(slab_coefficients(-1e4 + 1e6j, c, k, 0.01, sigma=1e-3))
    assert np.all(np.isfinite(out)) and np.all(np.abs(out) <= 1 + 1e-9)


# ------------------------------------------------------------------ tables
def test_lobe_grid_coordinates_invert():
    th = np.radians(np.linspace(0, 80, 5))
    alpha = np.linspace(0, math.pi, 7)
    s = np.linspace(0.0, 0.99, 9)
    ts, ps = lobe_directions(th, alpha, s, 1.7)
    a2, s2 = lobe_coordinates(th[:, None, None], ts, ps, 1.7)
    np.testing.assert_allclose(s2, np.broadcast_to(s, s2.shape), atol=1e-9)
    rho_pos = s2 > 1e-6
    np.testing.assert_allclose(
        a2[rho_pos], np.broadcast_to(alpha[:, None], a2.shape)[rho_pos], atol=1e-7
    )


def test_table_incoherent_reflectivity_matches_emissivity_quadrature():
    # The lobe table integrates to emscatter's own incoherent reflectivity (shared quadrature
    # of emscatter.emissivity, tol 1e-4) within 1.5 %: the diffuse share of each ray.
    rough = em.GaussianCorrelation(sigma=0.2e-3, length=5e-3)
    f = 28e9
    t = build_tables(rough, EPS, f, options=TableOptions(n_cos=33, n_cos_spm=9))
    idx = [0, 15, 30]
    e = em.emissivity(rough, EPS, frequency=f, theta_i=t.theta_nodes[idx], method="spm")
    np.testing.assert_allclose(t.incoherent[:, idx], e.incoherent, rtol=0.015)
    assert t.method == "spm" and t.valid and t.energy_excess < 0.01
    # trilinear lookup reproduces the nodes
    ti, ts, ps = (
        t.theta_nodes[5],
        *lobe_directions(t.theta_nodes[5:6], t.alpha_nodes, t.s_nodes, t.grading),
    )
    lob = interpolate_lobe(t, np.full(ts.shape, ti), ts, ps)
    np.testing.assert_allclose(np.moveaxis(lob, 0, -1), t.lobe[5:6], rtol=1e-6, atol=1e-15)


def test_flat_tables_cost_no_solver_call_and_cache_reuses():
    clear_cache()
    reset_build_log()
    t = build_tables(None, EPS, 28e9, options=SMALL)
    assert t.flat and t.method is None and np.all(t.lobe == 0) and np.all(t.delta == 0)
    assert build_log() == []
    rough = em.GaussianCorrelation(sigma=0.11e-3, length=3e-3)
    a = build_tables(rough, EPS, 28e9, options=SMALL, label="a")
    b = build_tables(rough, EPS, 28e9, options=SMALL, label="b")
    assert a is b
    assert [e["label"] for e in build_log()] == ["a"]
    assert build_log()[0]["bistatic_points"] == SMALL.n_theta * SMALL.n_alpha * SMALL.n_s


def test_roughness_without_valid_solver_warns_naming_what_to_change():
    clear_cache()
    rough = em.GaussianCorrelation(sigma=2e-3, length=2e-3)  # kℓ ≈ 6, slope 1.4 at 140 GHz
    with pytest.warns(RadioValidityWarning, match="no method is valid") as rec:
        build_tables(rough, EPS, 140e9, options=SMALL, label="wall")
    msg = str(rec[0].message)
    assert "'wall' at 140 GHz" in msg and "method=" in msg and "out_of_range='raise'" in msg
    with pytest.raises(ValidityError, match="outside its validity range"):
        build_tables(rough, EPS, 141e9, options=SMALL, out_of_range="raise")
    with pytest.raises(ValueError, match="NaN would reach the ray tracer"):
        build_tables(rough, EPS, 142e9, options=SMALL, out_of_range="nan")


def test_energy_is_conserved_in_the_tables():
    # physical optics without shadowing exceeds r_coh + r_incoh = 1 near grazing; the lobe is
    # scaled there (recorded), silently only above 60°.
    clear_cache()
    rough = em.GaussianCorrelation(sigma=1e-3, length=10e-3)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        t = build_tables(rough, EPS, 140e9, options=SMALL, method="po")
    assert t.method == "po" and t.energy_excess > 0.05
    assert np.all(t.coherent_power + t.incoherent <= 1 + 1e-9)
    scaled = t.energy_scale < 1 - 1e-9
    assert np.any(scaled) and np.degrees(t.theta_nodes[np.any(scaled, axis=0)]).min() > 60
    with pytest.warns(EnergyWarning, match="scaled down"):
        build_tables(
            rough,
            EPS,
            140e9,
            options=TableOptions(**{**SMALL.__dict__, "energy_warn_below_deg": 89.5}),
            method="po",
        )


def test_anisotropic_roughness_is_refused():
    rough = em.GaussianCorrelation(sigma=1e-4, length=5e-3, length_y=1e-2)
    with pytest.raises(ValueError, match="isotropic 2-D roughness"):
        build_tables(rough, EPS, 28e9, options=SMALL)


# ------------------------------------------------------------------ media
def test_media_and_their_errors():
    m = resolve_medium(eps_real=4.0, conductivity=0.02)
    assert isinstance(m, ConductiveMedium)
    assert m.eps(frequency=1e9) == pytest.approx(
        materials.eps_from_conductivity(4.0, 0.02, 1e9), rel=1e-12
    )
    assert resolve_medium("itu:glass").name == "glass"
    assert resolve_medium(3 + 0.1j).eps(frequency=5e9) == 3 + 0.1j
    with pytest.raises(ValueError, match="conductivity must be >= 0"):
        resolve_medium(eps_real=4.0, conductivity=-1.0)
    with pytest.raises(ValueError, match="unknown material 'granite'"):
        resolve_medium("granite")
    with pytest.raises(ValueError, match="not both"):
        resolve_medium("concrete", eps_real=4.0, conductivity=0.1)
    with pytest.raises(ValueError, match="needs a medium"):
        resolve_medium(eps_real=4.0)
    with pytest.raises(ValueError, match="medium='metal'"):
        resolve_medium("pec")
    spec = MaterialSpec(surface=em.GaussianCorrelation(sigma=1e-4, length=5e-3), medium="marble")
    with pytest.raises(materials.OutOfBandError, match=r"1 GHz–60 GHz.*extrapolate=True"):
        spec.tables(80e9)


# ------------------------------------------------------------------ scenes
def test_ply_round_trip_and_room(tmp_path):
    b = scenes.box([1.0, 2.0, 3.0], [2.0, 4.0, 6.0])
    assert b.area() == pytest.approx(2 * (2 * 4 + 2 * 6 + 4 * 6))
    back = scenes.read_ply(scenes.write_ply(tmp_path / "b.ply", b))
    np.testing.assert_allclose(back.vertices, b.vertices, rtol=1e-7)
    np.testing.assert_array_equal(back.faces, b.faces)
    room = scenes.furnished_room()
    assert set(room.meshes) == set(room.media)
    assert room.meshes["floor"].area() == pytest.approx(30.0)
    assert {m for m, _ in room.media.values()} >= {"concrete", "plasterboard", "glass", "wood"}
    xml = scenes.write_scene(tmp_path / "room", room).read_text()
    assert xml.count('type="ply"') == len(room.meshes)
    assert xml.count('type="radio-material"') == len(room.meshes)
    with pytest.raises(ValueError, match="face indices"):
        scenes.Mesh(np.zeros((3, 3)), [[0, 1, 3]])


# ------------------------------------------------------------------ numbers of any numeric type
def test_numpy_numbers_are_accepted_wherever_a_number_is():
    assert MaterialSpec(medium="concrete", thickness=np.float32(0.2)).thickness == pytest.approx(
        0.2, rel=1e-7
    )
    assert MaterialSpec(medium="concrete", thickness=np.int64(1)).thickness == 1.0
    m = resolve_medium(eps_real=np.float32(4.0), conductivity=np.int64(0))
    assert m.eps(frequency=1e9) == 4.0
    assert resolve_medium(np.float32(4.0)).eps(frequency=1e9) == 4.0
    # np.int64 grid sizes give the same options (the same cache key) as ints
    assert TableOptions(n_cos=np.int64(33), n_theta=np.int32(12)) == TableOptions(
        n_cos=33, n_theta=12
    )
    spec = MaterialSpec(surface=em.GaussianCorrelation(sigma=0.2e-3, length=5e-3),
                        medium="concrete", options=SMALL)  # fmt: skip
    # 28 GHz is exact in float32: a np.float32 frequency gives the very same tables
    a, b = spec.tables(28e9), spec.tables(np.float32(28e9))
    assert b.frequency == 28e9
    np.testing.assert_array_equal(a.lobe, b.lobe)


@pytest.mark.parametrize("value", [-0.1, 0, 0.0, math.nan, math.inf, "0.1", True, 1j])
def test_a_bad_thickness_is_refused_before_any_table(value):
    # MaterialSpec(thickness=-0.1).tables(28e9) used to build tables for a negative slab
    with pytest.raises(ValueError) as info:
        MaterialSpec(medium="concrete", thickness=value).tables(28e9)
    msg = str(info.value)
    assert msg.startswith("thickness must be a positive number of metres")
    assert repr(value) in msg and "None for a half-space" in msg


@pytest.mark.parametrize("value", [-3, -3.0, 0, -3 + 1j, np.float32(-3)])
def test_a_non_positive_permittivity_is_refused_like_eps_real(value):
    with pytest.raises(ValueError) as info:
        resolve_medium(value)
    msg = str(info.value)
    assert "Re ε > 0" in msg and repr(value) in msg and "medium='metal'" in msg
    # the same rule as eps_real
    with pytest.raises(ValueError, match="eps_real must be > 0"):
        resolve_medium(eps_real=-3, conductivity=0.0)


def test_a_boolean_is_not_a_medium():
    with pytest.raises(TypeError, match="medium must be an ITU-R P.2040 name.*got True"):
        resolve_medium(True)
