"""Natural media: soil (Dobson et al. 1985 / Peplinski et al. 1995, Mironov et al. 2009) and
sea water (Klein & Swift 1977, Meissner & Wentz 2004) — published values, cross-checks
between the models, the laws (Im ε ≥ 0 under exp(−iωt)), range checks and use through the
API by name and as objects."""

from __future__ import annotations

import math

import numpy as np
import pytest

import emscatter as em
from emscatter import materials as mat
from emscatter.constants import EPSILON_0

T20 = 293.15  # K


# ----------------------------------------------------------------------------- sea water
@pytest.mark.parametrize("cls", [mat.KleinSwiftWater, mat.MeissnerWentzWater])
def test_conductivity_of_standard_sea_water(cls):
    # Practical Salinity Scale 1978 (UNESCO 1981, Tech. Pap. Mar. Sci. 36): S = 35 is by
    # definition the salinity of water with the conductivity of standard KCl solution at
    # 15 °C and 1 atm, C(35, 15, 0) = 42.914 mS/cm = 4.2914 S/m.
    sigma = cls(temperature=288.15, salinity=35.0).parameters()[-1]
    assert sigma == pytest.approx(4.2914, rel=1.5e-3)


@pytest.mark.parametrize("cls", [mat.KleinSwiftWater, mat.MeissnerWentzWater])
def test_pure_water_static_permittivity_and_relaxation(cls):
    # Malmberg & Maryott, J. Res. NBS 56 (1956) 1, their fit ε = 87.740 − 0.40008 T +
    # 9.398e-4 T² − 1.410e-6 T³ (T in °C): εs = 78.30 at 25 °C, 80.10 at 20 °C;
    # Kaatze, J. Chem. Eng. Data 34 (1989) 371: τ = 8.27 ps at 25 °C.
    w25, w20 = cls(temperature=298.15, salinity=0.0), cls(temperature=T20, salinity=0.0)
    p25 = w25.parameters()
    assert p25[0] == pytest.approx(78.30, rel=4e-3)
    assert w20.parameters()[0] == pytest.approx(80.10, rel=4e-3)
    tau = p25[1] if cls is mat.KleinSwiftWater else 1 / (2 * math.pi * p25[3])
    assert tau == pytest.approx(8.27e-12, rel=0.03)
    # the static limit of the model is εs (Debye: ε → εs + iσ/(ωε₀) as ω → 0, σ = 0 here)
    if cls is mat.KleinSwiftWater:
        assert w25.eps(frequency=0.1e9).real == pytest.approx(p25[0], rel=2e-3)


def test_sea_water_models_agree_where_both_hold():
    # two independent fits (one Debye term fitted at 1.43/2.65 GHz; two Debye terms fitted on
    # satellite data and lab data to 400 GHz) where both hold: 1.4–10 GHz, 10–30 °C, 0–35 psu
    # (measured: ≤ 1.9 %, largest at 10 GHz and 35 psu).
    f = np.array([1.4e9, 2.65e9, 5e9, 10e9])
    worst = 0.0
    for t in (283.15, 293.15, 303.15):
        for s in (0.0, 10.0, 35.0):
            ks = mat.KleinSwiftWater(temperature=t, salinity=s).eps(frequency=f)
            mw = mat.MeissnerWentzWater(temperature=t, salinity=s).eps(frequency=f)
            worst = max(worst, float(np.max(np.abs(ks - mw) / np.abs(mw))))
    assert worst < 0.025, worst


def test_sea_water_at_l_band_is_conduction_dominated():
    # 1.4 GHz, 35 psu, 20 °C: the loss is the ionic conduction σ/(ωε₀) (σ = 4.79 S/m, PSS-78
    # at 20 °C: rt(20)·C(35,15,0) = 1.1163 × 4.2914) plus a small Debye part; ε′ is just below
    # the static εs ≈ 72.5. Both models, Im ε ≥ 0 under exp(−iωt).
    f = 1.4e9
    cond = 4.790 / (2 * math.pi * f * EPSILON_0)  # 61.5
    for w in (mat.KleinSwiftWater(), mat.MeissnerWentzWater()):
        e = complex(w.eps(frequency=f))
        assert 70.5 < e.real < 72.5, e
        assert cond < e.imag < cond + 7.0, (e, cond)


def test_meissner_wentz_high_frequency_limit_and_loss_sign():
    w = mat.MeissnerWentzWater(temperature=T20, salinity=35.0)
    f = np.geomspace(1e9, 400e9, 200)
    e = w.eps(frequency=f)
    assert np.all(e.imag > 0)
    assert np.all(np.diff(e.real) < 0)  # normal dispersion: ε′ falls with frequency
    eps_inf = w.parameters()[2]
    assert eps_inf < e.real[-1] < 10.0  # approaches ε∞ (≈ 4.4) from above


# ----------------------------------------------------------------------------- soil
def _hallikainen_14ghz(mv, sand_pct, clay_pct):
    # Hallikainen, Ulaby, Dobson, El-Rayes & Wu, "Microwave dielectric behavior of wet soil —
    # Part I", IEEE TGRS 23 (1985) 25–34: polynomial fit of the measured ε′ at 1.4 GHz,
    # ε′ = (a0 + a1 S + a2 C) + (b0 + b1 S + b2 C) m_v + (c0 + c1 S + c2 C) m_v², S, C in %.
    a = 2.862 - 0.012 * sand_pct + 0.001 * clay_pct
    b = 3.803 + 0.462 * sand_pct - 0.341 * clay_pct
    c = 119.006 - 0.500 * sand_pct + 0.633 * clay_pct
    return a + b * mv + c * mv**2


@pytest.mark.parametrize(("model", "tol"), [("dobson", 0.12), ("mironov", 0.06)])
def test_soil_models_follow_the_measured_fit_at_l_band(model, tol):
    # loam of Hallikainen et al. (1985, soil 2: 42 % sand, 8.5 % clay)
    for mv in (0.2, 0.3, 0.4):
        kw = {"sand": 0.42} if model == "dobson" else {}
        e = mat.soil(model, moisture=mv, clay=0.085, **kw).eps(frequency=1.4e9)
        ref = _hallikainen_14ghz(mv, 42.0, 8.5)
        assert abs(e.real - ref) / ref < tol, (model, mv, complex(e), ref)


def test_dobson_and_mironov_agree_over_their_common_band():
    f = np.array([1.4e9, 3e9, 5e9, 10e9, 18e9])
    for mv in (0.2, 0.3, 0.4):
        d = mat.DobsonSoil(moisture=mv, sand=0.42, clay=0.085).eps(frequency=f)
        m = mat.MironovSoil(moisture=mv, clay=0.085).eps(frequency=f)
        assert np.all(np.abs(d.real - m.real) / m.real < 0.15), (mv, d, m)


def test_mironov_refractive_mixing_structure():
    # GRMDM (Mironov et al. 2009, eqs. 11–13): the complex index n + iκ is linear in m_v with
    # one slope up to m_vt (bound water) and another beyond; at m_v = 0 it is the dry soil's
    # (n_d, κ_d) of eqs. 17–18 (C = 20 %: n_d = 1.634 − 0.1078 + 0.0110, κ_d = 0.0314).
    f = 5e9
    dry = np.sqrt(complex(mat.MironovSoil(moisture=0.0, clay=0.2).eps(frequency=f)))
    assert dry.real == pytest.approx(1.634 - 0.539e-2 * 20 + 0.2748e-4 * 400, rel=1e-12)
    assert dry.imag == pytest.approx(0.03952 - 0.04038e-2 * 20, rel=1e-12)
    mvt = 0.02863 + 0.30673e-2 * 20
    mvs = np.array([0.0, 0.3 * mvt, 0.6 * mvt, mvt, mvt + 0.1, mvt + 0.2, mvt + 0.3])
    idx = np.array([np.sqrt(complex(mat.MironovSoil(m, 0.2).eps(frequency=f))) for m in mvs])
    below, above = np.diff(idx[:4]) / np.diff(mvs[:4]), np.diff(idx[3:]) / np.diff(mvs[3:])
    np.testing.assert_allclose(below, below[0], rtol=1e-9)
    np.testing.assert_allclose(above, above[0], rtol=1e-9)
    assert abs(above[0]) > abs(below[0])  # free water raises the index faster than bound


@pytest.mark.parametrize("soil", [mat.DobsonSoil, mat.MironovSoil])
def test_soil_laws_loss_sign_and_moisture(soil):
    f = np.geomspace(*soil().band, 60)
    prev = None
    for mv in (0.05, 0.1, 0.2, 0.3, 0.4):
        e = soil(moisture=mv).eps(frequency=f)
        assert np.all(np.isfinite(e)) and np.all(e.imag > 0) and np.all(e.real > 1)
        if prev is not None:
            assert np.all(e.real > prev.real)  # wetter soil, higher ε′
        prev = e


def test_peplinski_correction_is_applied_below_l_band():
    # Peplinski, Ulaby & Dobson, IEEE TGRS 33 (1995) 803: ε′ → 1.15 ε′ − 0.68 below 1.4 GHz
    # with their σeff; at 1.4 GHz the two fits meet with a step (documented: ~10 % in ε′)
    s = mat.DobsonSoil(moisture=0.25, sand=0.3, clay=0.3, bulk_density=1500.0)
    lo, hi = s.eps(frequency=np.array([1.4e9 * (1 - 1e-9), 1.4e9]))
    assert 0.0 < abs(lo.real - hi.real) / hi.real < 0.15
    # the real part below 1.4 GHz is Dobson's form × 1.15 − 0.68: undo it and compare with
    # the 1.4-GHz side at the same frequency (ε′ barely depends on σeff at 1.4 GHz)
    assert (lo.real + 0.68) / 1.15 == pytest.approx(hi.real, rel=0.01)


# ----------------------------------------------------------------------------- checks
@pytest.mark.parametrize(
    ("make", "words"),
    [
        (lambda: mat.DobsonSoil(moisture=0.7), ["moisture", "0.7", "[0.01, 0.6]"]),
        (lambda: mat.DobsonSoil(moisture=0.0), ["moisture", "= 0 ", "[0.01, 0.6]"]),
        (lambda: mat.DobsonSoil(sand=1.2), ["sand", "1.2", "[0, 1]"]),
        (lambda: mat.DobsonSoil(sand=0.7, clay=0.5), ["sand + clay", "1.2"]),
        (lambda: mat.DobsonSoil(bulk_density=1.4), ["bulk_density", "1.4", "kg/m³"]),
        (lambda: mat.DobsonSoil(temperature=20.0), ["temperature", "20 K", "273.15"]),
        (lambda: mat.DobsonSoil(moisture=0.5, bulk_density=1600.0), ["porosity", "0.5"]),
        (lambda: mat.MironovSoil(clay=0.9), ["clay", "0.9", "[0, 0.76]"]),
        (lambda: mat.MironovSoil(moisture=-0.1), ["moisture", "-0.1", "[0, 0.6]"]),
        (lambda: mat.KleinSwiftWater(salinity=45.0), ["salinity", "45", "[0, 40] psu"]),
        (lambda: mat.KleinSwiftWater(temperature=330.0), ["temperature", "330", "313.15"]),
        (lambda: mat.MeissnerWentzWater(temperature=310.0), ["temperature", "310", "307.15"]),
        (lambda: mat.MeissnerWentzWater(salinity=float("nan")), ["salinity", "finite"]),
        (lambda: mat.MironovSoil(moisture="wet"), ["moisture", "real number", "'wet'"]),
    ],
)
def test_out_of_range_parameters_name_parameter_value_and_range(make, words):
    with pytest.raises((ValueError, TypeError)) as info:
        make()
    for w in words:
        assert w in str(info.value), (w, str(info.value))


@pytest.mark.parametrize(
    ("medium", "f", "band"),
    [
        (mat.DobsonSoil(), 20e9, "300 MHz–18 GHz"),
        (mat.MironovSoil(), 0.1e9, "300 MHz–26.5 GHz"),
        (mat.KleinSwiftWater(), 37e9, "100 MHz–10 GHz"),
        (mat.MeissnerWentzWater(), 0.5e9, "1 GHz–400 GHz"),
    ],
)
def test_out_of_band_names_band_frequency_and_the_other_model(medium, f, band):
    with pytest.raises(mat.OutOfBandError) as info:
        medium.eps(frequency=np.array([1.4e9, f]))
    text = str(info.value)
    assert band in text and mat.format_frequency(f) in text and "Ways out" in text


def test_dobson_refuses_a_negative_loss_instead_of_nan():
    # σeff of Dobson's regression is < 0 for coarse light soils: ε″ of the soil water would
    # be negative and the fractional power NaN
    with pytest.raises(ValueError, match="non-physical loss.*sand = 0.9"):
        mat.DobsonSoil(sand=0.9, clay=0.05, bulk_density=1200.0).eps(frequency=1.4e9)


# ----------------------------------------------------------------------------- names, API
@pytest.mark.parametrize(
    ("name", "cls"),
    [
        ("soil", mat.MironovSoil),
        ("Soil:Dobson", mat.DobsonSoil),
        ("sea_water", mat.MeissnerWentzWater),
        ("sea water", mat.MeissnerWentzWater),
        ("seawater:klein-swift", mat.KleinSwiftWater),
        ("fresh_water", mat.MeissnerWentzWater),
    ],
)
def test_names_resolve_to_the_media_and_round_trip(name, cls):
    m = mat.as_material(name)
    assert isinstance(m, cls)
    assert mat.from_dict(m.to_dict()) == m
    assert np.all(mat.eps_at(name, frequency=[1.4e9, 5e9]).imag > 0)


def test_an_unknown_soil_name_says_how_to_make_one():
    with pytest.raises(ValueError, match="MironovSoil\\(moisture=0.3, clay=0.1\\)"):
        mat.as_material("soil:wet")


def test_media_work_through_the_api_like_their_permittivity():
    rough = em.roughness("gaussian", sigma=0.002, length=0.02)  # kσ ≤ 0.21 to 5 GHz
    f = 1.4e9
    for medium in ("soil", mat.DobsonSoil(moisture=0.3), mat.MeissnerWentzWater()):
        eps = complex(mat.as_material(medium).eps(frequency=f))
        kw = dict(frequency=f, theta_i=np.radians([20.0, 40.0]), method="spm")
        a = em.emissivity(rough, medium, **kw)
        b = em.emissivity(rough, eps, **kw)
        np.testing.assert_allclose(a.emissivity, b.emissivity, rtol=1e-12)
        assert np.all((a.emissivity > 0) & (a.emissivity < 1))
    # a band: the medium is evaluated at each frequency
    band = em.bistatic(
        rough, "sea_water", frequency=[1.4e9, 5e9], theta_i=0.5, theta_s=0.5, phi_s=math.pi,
        method="spm",
    )  # fmt: skip
    one = em.bistatic(
        rough, complex(mat.as_material("sea_water").eps(frequency=5e9)), frequency=5e9,
        theta_i=0.5, theta_s=0.5, phi_s=math.pi, method="spm",
    )  # fmt: skip
    np.testing.assert_allclose(band.sigma0[..., 1], one.sigma0, rtol=1e-12)


def test_smrt_klein_swift_agrees_if_installed():
    smrt_water = pytest.importorskip("smrt.permittivity.saline_water")
    psu = pytest.importorskip("smrt.core.globalconstants").PSU
    f = np.array([1.4e9, 5e9])
    ours = mat.KleinSwiftWater(temperature=T20, salinity=35.0).eps(frequency=f)
    theirs = np.array(
        [complex(smrt_water.seawater_permittivity_klein76(x, T20, 35 * psu)) for x in f]
    )
    theirs = np.where(theirs.imag < 0, np.conj(theirs), theirs)
    np.testing.assert_allclose(ours, theirs, rtol=2e-3)
