"""Sionna's built-in scattering parameters fitted to emscatter's tables (emscatter.radio.builtin):
the fit against its own definitions, a known lobe recovered, the flags where no built-in model
stands in, the JSON export and (in a Sionna worker) the fitted RadioMaterial on the plate."""

from __future__ import annotations

import dataclasses
import importlib.util
import json
import math
import warnings

import numpy as np
import pytest

import emscatter as em
from emscatter import radio
from emscatter.fresnel import fresnel_cos
from emscatter.radio import builtin
from test_radio_sionna import _run  # the worker launcher (never imports Sionna here)

CONCRETE = em.GaussianCorrelation(sigma=0.4e-3, length=4e-3)  # emscatter's indoor table


def _spec(rough=CONCRETE, **kw):
    return radio.MaterialSpec(surface=rough, medium="concrete", thickness=None, **kw)


@pytest.fixture(scope="module")
def fit140():
    spec = _spec()
    return spec, spec.tables(140e9, label="builtin-fit"), builtin.builtin_equivalent(spec, 140e9)


def test_weights_integrate_the_lobe_to_the_tables_reflectivity(fit140):
    _, tab, _ = fit140
    w = builtin.lobe_weights(tab)
    ch = np.einsum("tasc,tas->ct", tab.lobe, w)
    np.testing.assert_allclose(ch[0] + ch[2], tab.incoherent[0], rtol=1e-12)
    np.testing.assert_allclose(ch[1] + ch[3], tab.incoherent[1], rtol=1e-12)
    # every built-in pattern is a unit-integral density on that quadrature
    idx = np.arange(3, 12)
    for name, kw in (("lambertian", {}), ("directive", {"alpha_r": 7}),
                     ("backscattering", {"alpha_r": 5, "alpha_i": 3, "lambda_": 0.7})):  # fmt: skip
        f = builtin.pattern_values(tab, idx, name, **kw)
        np.testing.assert_allclose(np.einsum("tas,tas->t", f, w[idx]), 1.0, rtol=1e-12)


def test_valid_case_reproduces_diffuse_fraction_and_lobe(fit140):
    """Concrete (σ = 0.4 mm, ℓ = 4 mm) at 140 GHz: claimed valid; S² is emscatter's diffuse share
    at the fit angle, the lobe misplaces the stated power, Sionna's per-polarization diffuse
    power S²|R_p|² is emscatter's within the stated error."""
    _, tab, eq = fit140
    assert eq["valid"], eq["flags"]
    assert eq["method"] == "po" and eq["emscatter_valid"]
    th = np.degrees(tab.theta_nodes)
    share = tab.incoherent.sum(0) / (tab.coherent_power.sum(0) + tab.incoherent.sum(0))
    assert eq["scattering_coefficient"] ** 2 == pytest.approx(np.interp(45.0, th, share), rel=1e-9)
    # issue 18's offline fit: α_R 32–50 at 140 GHz, S 0.99 → 0.87 between 30° and 60°
    pat = eq["scattering_pattern"]
    assert pat["name"] == "directive" and 30 <= pat["alpha_r"] <= 50
    assert eq["per_angle"]["S"][0] > 0.98 and 0.85 < eq["per_angle"]["S"][-1] < 0.9
    # stated errors: misplaced lobe power at 45° (measured 0.12) recomputed from the definition
    idx = np.flatnonzero((th >= 30) & (th <= 60))
    w = builtin.lobe_weights(tab)[idx]
    tot = tab.lobe[idx].sum(-1)
    f_em = tot / np.einsum("tas,tas->t", tot, w)[:, None, None]
    f_fit = builtin.pattern_values(tab, idx, "directive", alpha_r=pat["alpha_r"])
    mis = 0.5 * np.einsum("tas,tas->t", np.abs(f_em - f_fit), w)
    np.testing.assert_allclose(mis, eq["per_angle"]["lobe_misplaced"], rtol=1e-9)
    assert eq["error"]["lobe_misplaced_at_fit"] < 0.15
    assert eq["patterns"]["lambertian"]["misplaced_mean"] > 0.5  # a Lambertian wall is far off
    # diffuse power per incident polarization at the fit angle, Sionna's model vs emscatter
    rh, rv = fresnel_cos(tab.eps, np.cos(tab.theta_nodes))
    s2 = eq["scattering_coefficient"] ** 2
    for p, r in ((0, rh), (1, rv)):
        sionna = s2 * np.interp(45.0, th, np.abs(r) ** 2)
        ours = np.interp(45.0, th, tab.incoherent[p])
        assert (
            abs(10 * math.log10(sionna / ours))
            <= eq["error"]["diffuse_polarization_error_db_at_fit"] + 0.05
        )  # noqa: E501
    assert eq["error"]["diffuse_polarization_error_db_at_fit"] < 1.0
    # XPD: K_x is the cross-polarized share of emscatter's diffuse power
    ch = np.einsum("tasc,tas->ct", tab.lobe, builtin.lobe_weights(tab))
    kx = (ch[1] + ch[2]) / tab.incoherent.sum(0)
    assert eq["xpd_coefficient"] == pytest.approx(np.interp(45.0, th, kx), rel=1e-9)
    kx_fit = eq["xpd_coefficient"]
    assert eq["xpd_db"] == pytest.approx(10 * math.log10((1 - kx_fit) / kx_fit))


def test_a_builtin_lobe_is_recovered_exactly(fit140):
    """Tables whose lobe IS Sionna's DirectivePattern(α_R = 20): the fit finds 20 and misplaces
    nothing; with a Lambertian lobe it picks the Lambertian."""
    spec, tab, _ = fit140
    n = tab.theta_nodes.size
    for name, kw, want in (("directive", {"alpha_r": 20}, {"alpha_r": 20}),
                           ("lambertian", {}, {})):  # fmt: skip
        f = builtin.pattern_values(tab, np.arange(n), name, **kw)
        lobe = f[..., None] * np.array([0.45, 0.05, 0.05, 0.45])[None, None, None, :]
        fake = dataclasses.replace(tab, lobe=lobe * tab.incoherent.mean(0)[:, None, None, None])
        eq = builtin.builtin_equivalent(spec, 140e9, tables=fake)
        assert eq["scattering_pattern"] == {"name": name, **want}
        assert eq["error"]["lobe_misplaced_max"] < 1e-9
        assert eq["xpd_coefficient"] == pytest.approx(0.1, rel=1e-9)


def test_flag_fires_where_reflection_loss_goes_into_transmission():
    """Concrete σ = 0.5 mm, ℓ = 2 mm at 28 GHz (IEM, valid): emscatter reflects up to 0.66 dB
    less than Fresnel (the rest enters the wall); the S model conserves |R|² and is flagged."""
    spec = _spec(em.GaussianCorrelation(sigma=0.5e-3, length=2e-3))
    tab = spec.tables(28e9)
    eq = builtin.builtin_equivalent(spec, 28e9)
    assert eq["emscatter_valid"]
    th = np.degrees(tab.theta_nodes)
    sel = (th >= 30) & (th <= 60)
    rh, rv = fresnel_cos(tab.eps, np.cos(tab.theta_nodes))
    lost = (tab.coherent_power.sum(0) + tab.incoherent.sum(0)) / (np.abs(rh) ** 2 + np.abs(rv) ** 2)
    assert 10 * math.log10(lost[sel].min()) < -0.5
    assert not eq["valid"]
    assert any("transmission" in f and "conserves |R|²" in f for f in eq["flags"])
    assert eq["error"]["reflected_power_error_db_max"] > 0.5
    # the valid 140 GHz case is not flagged for transmission
    ok = builtin.builtin_equivalent(_spec(), 140e9)
    assert ok["error"]["reflected_power_error_db_max"] < 0.5


def test_flag_fires_where_one_S_cannot_serve_both_polarizations():
    """Concrete at 28 GHz (SPM): emscatter's v diffuse lies 3.3 dB below S²|R_v|² at 45°."""
    eq = builtin.builtin_equivalent(_spec(), 28e9)
    assert eq["method"] == "spm" and eq["emscatter_valid"]
    assert not eq["valid"]
    assert any("polarization" in f for f in eq["flags"])
    assert eq["error"]["diffuse_polarization_error_db_at_fit"] > 2.0
    # issue 18: S 0.41 → 0.29 (30° → 60°) and α_R 2–4 at 28 GHz
    per = eq["per_angle"]
    assert per["S"][0] > per["S"][-1] and 0.2 < per["S"][-1] < 0.35
    assert set(per["alpha_r"]) <= {2, 3, 4}


def test_json_round_trip_and_kwargs(tmp_path, fit140):
    _, _, eq = fit140
    path = builtin.write_json(tmp_path / "sub" / "fit.json", [eq])
    back = builtin.read_json(path)
    assert back == [json.loads(json.dumps(eq))]
    kw = builtin.sionna_material_kwargs(back[0])
    assert (
        kw["scattering_pattern"] == "directive"
        and kw["alpha_r"] == eq["scattering_pattern"]["alpha_r"]
    )
    assert kw["scattering_coefficient"] == eq["scattering_coefficient"]
    (tmp_path / "bad.json").write_text('{"schema": "other"}')
    with pytest.raises(ValueError, match="schema"):
        builtin.read_json(tmp_path / "bad.json")
    with pytest.raises(ValueError, match="fits\\[0\\]"):
        builtin.write_json(tmp_path / "x.json", [{"a": 1}])
    assert not (tmp_path / "x.json").exists()


@pytest.mark.parametrize(
    "kw, match",
    [
        ({"frequency": -1.0}, "frequency"),
        ({"angle_range_deg": (60.0, 30.0)}, "angle_range_deg"),
        ({"fit_angle_deg": 70.0}, "fit_angle_deg"),
        ({"alpha_max": 0}, "alpha_max"),
        ({"transmission_tolerance_db": 0.0}, "transmission_tolerance_db"),
        ({"polarization_tolerance_db": -1.0}, "polarization_tolerance_db"),
    ],
)
def test_bad_inputs(kw, match):
    args = {"frequency": 140e9, **kw}
    f = args.pop("frequency")
    with pytest.raises(ValueError, match=match):
        builtin.builtin_equivalent(_spec(), f, **args)


def test_bad_spec():
    with pytest.raises(TypeError, match="MaterialSpec"):
        builtin.builtin_equivalent("concrete", 28e9)


def test_cli_builtin_json(tmp_path, capsys):
    from emscatter.cli import main

    out = tmp_path / "fits.json"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rc = main(["radio", "--builtin-json", str(out), "--medium", "concrete=0.4e-3,4e-3",
                   "--frequencies-ghz", "28,140", "--quick"])  # fmt: skip
    assert rc == 0
    fits = builtin.read_json(out)
    assert [f["frequency_hz"] for f in fits] == [28e9, 140e9]
    assert [f["valid"] for f in fits] == [False, True]
    assert "NOT valid" in capsys.readouterr().out


@pytest.mark.skipif(importlib.util.find_spec("sionna") is None, reason="Sionna RT not installed")
def test_fitted_builtin_material_in_sionna_plate():
    """Sionna runs for real: the fitted built-in RadioMaterial against the emscatter material on
    the plate at 45°. Valid case (140 GHz): specular path within 0.1 dB, diffuse power within
    0.5 dB (measured 0.02 and 0.08–0.11 dB). Flagged case (28 GHz, polarization): the diffuse
    power is off by more than 1 dB per polarization, as the flag said."""
    res = _run("builtin_plate")["builtin_plate"]  # tests/radio_worker.py, a fresh interpreter
    assert "error" not in res, res["error"]
    r = res["result"]
    ok, bad = r["concrete_140GHz"], r["concrete_28GHz"]
    assert ok["valid"] and not bad["valid"]
    for pair in ("VV", "HH"):
        assert abs(ok[f"specular_{pair}_diff_db"]) < 0.1
        assert abs(ok[f"diffuse_{pair}_diff_db"]) < 0.5
        assert abs(bad[f"specular_{pair}_diff_db"]) < 0.5
        assert abs(bad[f"diffuse_{pair}_diff_db"]) > 1.0
