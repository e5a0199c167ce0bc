"""build_table caps a dielectric's reflection at 1 − T by default (issue 21): the GO
transmitted fraction T(θi) of brdf/transmittance.py against the BTDF table's exact albedo and
the smooth-interface limit, PO glass at 88°, conductors untouched, the transmission= options."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from emscatter.brdf import build_table
from emscatter.brdf.btdf_table import build_btdf_table, energy_budget
from emscatter.brdf.transmittance import go_transmittance, is_dielectric
from emscatter.fresnel import fresnel
from emscatter.spectra import GaussianCorrelation

LAM = 550e-9
EPS = 2.25
PO_SURF = GaussianCorrelation(sigma=0.05e-6, length=1e-6)  # Beckmann m = 0.1
TH = np.radians(np.arange(0, 90, 2.0))
PH = np.radians(np.linspace(0, 180, 91))


def _build(**kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return build_table(PO_SURF, EPS, [LAM], theta=TH, phi=PH, **kw)


@pytest.fixture(scope="module")
def fine_btdf():
    # 0.125° θt, 0.5° Δφ: its albedo errs by < 1e-3 at α = 0.1 (btdf_table.py docstring)
    return build_btdf_table(
        PO_SURF,
        EPS,
        [LAM],
        theta_i=TH,
        theta_t=np.radians(np.arange(0, 90, 0.125)),
        phi_d=np.radians(np.linspace(0, 180, 361)),
    )


def test_smooth_limit_is_fresnel_transmissivity():
    # a nearly flat interface transmits 1 − F(θi) (Born & Wolf §1.5.3): a law, no table
    th = np.radians([0, 20, 40, 60, 70, 80])
    t = go_transmittance(EPS, th, slope_variance=(1e-6, 1e-6))
    r = fresnel(EPS, th)
    f = 0.5 * (np.abs(r[0]) ** 2 + np.abs(r[1]) ** 2)
    assert np.allclose(t, 1 - f, atol=2e-3)
    # from inside (ε → 1/ε): total internal reflection beyond the critical angle 41.8°
    t_in = go_transmittance(1 / EPS, np.radians([10, 30, 50, 70]), slope_variance=(1e-6, 1e-6))
    assert t_in[2] < 1e-6 and t_in[3] < 1e-6 and t_in[0] > 0.9


@pytest.mark.parametrize("sv", [0.005, 0.045, 0.125])
def test_quadrature_converges(sv):
    th = np.radians(np.arange(0, 90, 3.0))
    ref = go_transmittance(EPS, th, slope_variance=(sv, sv), n_nodes=400)
    assert np.abs(go_transmittance(EPS, th, slope_variance=(sv, sv)) - ref).max() < 1e-3


def test_transmittance_equals_btdf_table_albedo(fine_btdf):
    t = go_transmittance(EPS, TH, slope_variance=(0.005, 0.005))
    assert np.abs(t - fine_btdf.albedo()[0]).max() < 1e-3  # measured 6.8e-4 (at 0°)


def test_po_glass_at_88_deg_r_plus_t_within_one(fine_btdf):
    # issue 21: PO glass at 88° reached R = 1.00 (R ≤ 1 only), the smooth interface reflects
    # 0.82 (n 1.5). By default the cap is 1 − T: R + T ≤ 1 within T's quadrature error at
    # every node, and R(88°) ends at the smooth Fresnel reflectance (PO's coherent lobe)
    po = _build(method="po")
    off = _build(method="po", transmission="off")
    energy = po.metadata["energy"]
    t_used = np.asarray(energy["T"])
    r = po.albedo().total
    assert np.all(r + t_used <= 1 + 1e-9)
    b = energy_budget(po, fine_btdf)
    clipped = t_used < b["T"] - 2e-3  # where PO's coherent lobe leaves less than T
    assert energy["transmission_clipped"] == int(clipped.sum()) > 0
    assert np.all((b["R"] + b["T"])[~clipped] <= 1 + 1e-3)
    rf = fresnel(EPS, TH[-1])
    smooth = 0.5 * (abs(rf[0]) ** 2 + abs(rf[1]) ** 2)
    assert abs(r[0, -1] - smooth) < 0.01
    # R ≤ 1 alone (the old table): R + T = 0.855 + 0.419 at 88°
    assert off.albedo().total[0, -1] + b["T"][0, -1] > 1.2
    assert po.reciprocity_error() < 1e-12
    assert energy["transmission_wavelengths"] == [LAM]


def test_btdf_table_as_transmission(fine_btdf):
    go = _build(method="go", transmission=fine_btdf)
    b = energy_budget(go, fine_btdf)
    assert np.all(b["R"] + b["T"] <= 1 + 1e-9)
    assert go.metadata["energy"]["transmission"] == "albedo of the given BtdfTable"


def test_conductor_tables_unchanged():
    for mat in ("pec", complex(-5.0, 2.0)):
        assert not is_dielectric(mat)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            auto = build_table(PO_SURF, mat, [LAM], method="go", theta=TH, phi=PH)
            off = build_table(
                PO_SURF, mat, [LAM], method="go", theta=TH, phi=PH, transmission="off"
            )
        assert np.array_equal(auto.values, off.values)
        assert not np.any(auto.metadata["energy"]["T"])
        assert auto.metadata["energy"]["transmission_wavelengths"] == []


def test_bad_transmission_is_named(fine_btdf):
    with pytest.raises(ValueError, match="transmission must be 'auto', 'off'.*'foo'"):
        build_table(PO_SURF, EPS, [LAM], method="go", transmission="foo")
    with pytest.raises(ValueError, match="wavelengths"):
        build_table(PO_SURF, EPS, [600e-9], method="go", theta=TH, phi=PH, transmission=fine_btdf)
