"""emscatter.materials: conversions, the sign rule, metals from Mitsuba's own data (checked
against Mitsuba's `conductor`, run for real), ITU-R P.2040 (checked against Sionna RT's table)."""

from __future__ import annotations

import ast
import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest

from emscatter import ConventionError, fresnel
from emscatter import materials as mat
from emscatter.constants import EPSILON_0, SPEED_OF_LIGHT


# ----------------------------------------------------------------------------- conversions
def test_nk_eps_round_trip_and_branch():
    n = np.array([0.2, 1.5, 3.0, 0.05])
    k = np.array([3.0, 0.0, 0.01, 5.0])
    eps = mat.eps_from_nk(n, k)
    assert np.all(eps.imag >= 0)
    n2, k2 = mat.nk_from_eps(eps)
    np.testing.assert_allclose(n2, n, rtol=1e-12)
    np.testing.assert_allclose(k2, k, rtol=1e-12, atol=1e-15)
    # a lossless plasma (Re ε < 0, Im ε = 0) is pure k
    n3, k3 = mat.nk_from_eps(-4.0)
    assert n3 == pytest.approx(0.0, abs=1e-15) and k3 == pytest.approx(2.0)


def test_conductivity_conversion_and_sign_rule():
    f = 3.5e9
    eps = mat.eps_from_conductivity(5.24, 0.123, f)
    # ε″ = σ/(ωε₀) ≈ 17.98 σ / f[GHz] (ITU-R P.2040 eq. 9)
    assert eps.imag == pytest.approx(0.123 / (2 * math.pi * f * EPSILON_0), rel=1e-12)
    assert eps.imag == pytest.approx(17.98 * 0.123 / 3.5, rel=1e-3)
    er, sig = mat.conductivity_from_eps(eps, f)
    assert er == pytest.approx(5.24) and sig == pytest.approx(0.123, rel=1e-12)
    eng = mat.to_engineering(eps)
    assert eng.imag < 0 and mat.from_engineering(eng) == pytest.approx(eps)
    with pytest.raises(ConventionError, match="Im > 0"):
        mat.from_engineering(5 + 1j)
    with pytest.raises(ConventionError, match="numpy.conj"):
        mat.to_engineering(5 - 1j)


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: mat.eps_from_conductivity(5.0, -0.1, 1e9), "conductivity must be >= 0"),
        (lambda: mat.eps_from_conductivity(5.0, 0.1, 0.0), "frequency must be > 0"),
        (lambda: mat.eps_from_conductivity(5.0, 0.1, -1e9), "frequency must be > 0"),
        (lambda: mat.eps_from_nk(1.0, -0.5), "k >= 0"),
        (lambda: mat.Constant(3 - 1j), "Im\\(eps\\) < 0"),
        (lambda: mat.Constant(3).eps(), "exactly one of frequency"),
        (lambda: mat.Constant(3).eps(frequency=1e9, wavelength=1.0), "exactly one of frequency"),
        (lambda: mat.Constant(3).eps(wavelength=np.nan), "must be finite"),
        (lambda: mat.as_material(True), "eps must be"),
        (lambda: mat.as_material("concretee"), "unknown material 'concretee'"),
        (lambda: mat.itu("unobtainium"), "must be one of"),
        (lambda: mat.metal("Unobtainium"), "must be one of Mitsuba"),
        (lambda: mat.Drude(-1.0, 1e14), "must be > 0"),
        (lambda: mat.Tabulated([1e-6], eps=[2.0]), "≥ 2 samples"),
    ],
)
def test_bad_inputs_name_the_parameter(call, match):
    with pytest.raises((ValueError, TypeError), match=match):
        call()


def test_drude_limits():
    sigma0, gamma = 5.8e7, 4.0e13  # copper-like DC conductivity [S/m], collision rate [rad/s]
    cu = mat.Drude.from_conductivity(sigma0, gamma)
    f = np.array([1e9, 1e10])  # ω ≪ γ: ε → 1 + iσ₀/(ωε₀)
    np.testing.assert_allclose(
        cu.eps(frequency=f).imag, sigma0 / (2 * np.pi * f * EPSILON_0), rtol=1e-3
    )
    lam = np.array([400e-9, 1e-6, 10e-6])
    assert np.all(cu.eps(wavelength=lam).imag >= 0)
    assert np.all(cu.eps(wavelength=lam).real < 0)  # below the plasma frequency


def test_tabulated_interpolates_and_guards_its_band():
    lam = np.array([400e-9, 500e-9, 600e-9])
    t = mat.Tabulated(lam, n=[1.0, 2.0, 3.0], k=[0.0, 1.0, 2.0], name="toy")
    assert t.eps(wavelength=500e-9) == pytest.approx((2 + 1j) ** 2)
    assert t.eps(wavelength=450e-9) == pytest.approx((1.5 + 0.5j) ** 2)  # linear in n, k
    with pytest.raises(mat.OutOfBandError, match="400–600 nm.*λ = 700 nm"):
        t.eps(wavelength=700e-9)
    held = mat.Tabulated(lam, n=[1.0, 2.0, 3.0], k=[0.0, 1.0, 2.0], extrapolate=True)
    assert held.eps(wavelength=700e-9) == pytest.approx((3 + 2j) ** 2)
    assert mat.from_dict(t.to_dict()) == t


def test_material_arrays_keep_their_shape():
    f = np.full((3, 4), 5e9)
    assert mat.itu("concrete").eps(frequency=f).shape == (3, 4)
    assert mat.Constant(4 + 1j).eps(frequency=f).shape == (3, 4)
    assert mat.eps_at("pec", frequency=1e9) == "pec"
    assert mat.eps_at(17 + 2j, wavelength=1.0) == pytest.approx(17 + 2j)


# ----------------------------------------------------------------------------- metals
pytestmark_mitsuba = pytest.mark.skipif(
    importlib.util.find_spec("mitsuba") is None, reason="Mitsuba 3 not installed"
)


@pytestmark_mitsuba
def test_metals_read_mitsubas_own_files():
    names = mat.available_metals()
    assert {"Au", "Ag", "Cu", "Al", "Cr"} <= set(names)
    au = mat.metal("Au")
    assert "Au.eta.spd" in au.source and "luxpop" in au.source
    # the first sample of Au.eta.spd / Au.k.spd: 298.757050 nm, n = 1.795
    lam0 = au.wavelengths[0]
    assert lam0 == pytest.approx(298.757050e-9)
    n, _ = au.nk(wavelength=lam0)
    assert n == pytest.approx(1.795)
    with pytest.raises(mat.OutOfBandError, match="Au"):
        au.eps(wavelength=1.5e-6)


@pytestmark_mitsuba
@pytest.mark.parametrize("name", ["Au", "Cu", "Al"])
def test_metal_fresnel_equals_mitsuba_conductor(name):
    """emscatter's Fresnel with materials.metal(name) == Mitsuba's `conductor` with
    material=name, evaluated by Mitsuba itself (scalar_spectral) — same data, same interpolation.
    Agreement limited by Mitsuba's float32 (measured ≤ 2e-7)."""
    import mitsuba as mi

    mi.set_variant("scalar_spectral")
    bsdf = mi.load_dict({"type": "conductor", "material": name})
    ctx = mi.BSDFContext()
    metal = mat.metal(name)
    for lam in (350.0, 450.0, 550.0, 650.0, 800.0):
        eps = metal.eps(wavelength=lam * 1e-9)
        for theta in (0.0, 0.7, 1.3):
            si = mi.SurfaceInteraction3f()
            si.wi = mi.Vector3f(math.sin(theta), 0.0, math.cos(theta))
            si.wavelengths = mi.Spectrum([lam] * 4)
            _, weight = bsdf.sample(ctx, si, 0.5, mi.Point2f(0.5, 0.5))
            rh, rv = fresnel.fresnel(eps, theta)
            ours = 0.5 * (abs(rh) ** 2 + abs(rv) ** 2)
            assert weight[0] == pytest.approx(ours, rel=2e-6), (lam, theta)


# ----------------------------------------------------------------------------- ITU-R P.2040
def test_itu_values_and_bands():
    c = mat.itu("concrete")
    f = 3.5e9
    er, sig = c.eps_real_and_conductivity(f)
    assert er == pytest.approx(5.24) and sig == pytest.approx(0.0462 * 3.5**0.7822)
    assert c.eps(frequency=f) == pytest.approx(5.24 + 1j * sig / (2 * np.pi * f * EPSILON_0))
    assert c.eps(frequency=200e9).real == pytest.approx(5.17)  # the 110–330 GHz band
    with pytest.raises(mat.OutOfBandError, match="1 GHz–100 GHz, 110 GHz–330 GHz, got 105 GHz"):
        c.eps(frequency=105e9)
    with pytest.raises(mat.OutOfBandError, match="extrapolate=True"):
        mat.itu("metal").eps(frequency=140e9)
    with pytest.raises(mat.OutOfBandError):
        mat.itu("concrete").eps(frequency=0.5e9)
    ext = mat.itu("concrete", extrapolate=True)
    assert ext.eps(frequency=101e9).real == pytest.approx(5.24)  # nearest band (ends at 100)
    assert ext.eps(frequency=108e9).real == pytest.approx(5.17)  # nearest: 110–330
    assert ext.eps(frequency=0.5e9).real == pytest.approx(5.24)
    # overlapping bands: plasterboard 110–330 is listed before 100–400 (first match wins)
    assert mat.itu("plasterboard").eps(frequency=200e9).real == pytest.approx(2.56)
    assert mat.itu("plasterboard").eps(frequency=105e9).real == pytest.approx(2.65)


def _sionna_itu_table() -> dict | None:
    spec = importlib.util.find_spec("sionna")
    if spec is None or spec.origin is None:
        return None
    path = Path(spec.origin).parent / "rt" / "radio_materials" / "itu.py"
    if not path.is_file():
        return None
    tree = ast.parse(path.read_text())
    for node in tree.body:
        if isinstance(node, ast.Assign) and getattr(node.targets[0], "id", "") == (
            "ITU_MATERIALS_PROPERTIES"
        ):
            return ast.literal_eval(node.value)
    return None


def test_itu_table_is_sionnas():
    """Same materials, bands, order and coefficients as the installed Sionna RT (read from its
    source without importing it: Dr.Jit variants are per process)."""
    theirs = _sionna_itu_table()
    if theirs is None:
        pytest.skip("Sionna RT not installed")
    assert list(theirs) == list(mat.ITU_P2040)
    for name, bands in theirs.items():
        assert [(tuple(b), tuple(p)) for b, p in bands.items()] == [
            (tuple(b), tuple(p)) for b, p in mat.ITU_P2040[name]
        ], name


def test_itu_frequency_wavelength_agree():
    c = mat.itu("glass")
    assert c.eps(wavelength=SPEED_OF_LIGHT / 28e9) == pytest.approx(c.eps(frequency=28e9))
    assert mat.as_material("itu:glass").eps(frequency=28e9) == pytest.approx(c.eps(frequency=28e9))
