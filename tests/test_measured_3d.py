"""The 3-D measured-error table (emscatter.validation.measured_table_3d → solvers/data/
measured_errors_3d.json) and its use in rank_methods: a 3-D cell reorders only where a
difference exceeds 2 combined Monte Carlo standard errors (issues 19, 20)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from emscatter.io import read_csv
from emscatter.solvers import measured, select
from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation, PowerLawCorrelation
from emscatter.validation.measured_table_3d import bootstrap_cell, write_measured_3d
from synthetic_table_3d import write_table

K = 2 * math.pi
ROOT = Path(__file__).resolve().parents[1]
SAMPLES = ROOT / "validation" / "mom3d" / "pec_table_samples.json"
DIELECTRIC_SAMPLES = ROOT / "validation" / "mom3d" / "dielectric_table_samples.json"
CSV = ROOT / "validation" / "mom3d" / "pec_table.csv"
NAMES = ("spm", "go", "po", "iem")


@pytest.fixture
def table(tmp_path, monkeypatch):
    """Point the package's 3-D table at a synthetic one: ``table(errors, se, pair_se, ...)``;
    ``table(None)`` makes it missing (no 3-D cell anywhere)."""

    def use(errors, se=None, pair_se=None, *, theta=(20.0, 40.0), ks=(0.1, 0.3, 1.0),
            kl=(3.0, 7.0)):  # fmt: skip
        path = tmp_path / "m3d.json"
        if errors is not None:
            write_table(path, errors, se, pair_se, theta=theta, ks=ks, kl=kl)
        else:
            path = tmp_path / "missing.json"
        monkeypatch.setattr(measured, "TABLE_3D_PATH", path)
        measured.load_table_3d.cache_clear()
        return path

    yield use
    measured.load_table_3d.cache_clear()


# ----------------------------------------------------------------------------- the bootstrap
def _speckle(n, rng, mean):
    """n realizations of speckle: the intensity of a complex Gaussian field is exponential."""
    return mean * rng.exponential(size=(n, *mean.shape))


def test_bootstrap_se_falls_as_one_over_root_n_and_the_pair_se_is_paired():
    rng = np.random.default_rng(3)
    true = np.broadcast_to(np.geomspace(1.0, 0.05, 12), (2, 12))
    models = {"a": true * 10**0.1, "b": true * 10**0.2}  # 1 dB and 2 dB high everywhere
    got = {n: bootstrap_cell(_speckle(n, rng, true), models, seed=1) for n in (16, 256)}
    # the error is the model's offset (noise averages out at 256)
    assert got[256]["errors"]["a"] == pytest.approx(1.0, abs=0.3)
    assert got[256]["errors"]["b"] == pytest.approx(2.0, abs=0.3)
    ratio = got[16]["se"]["a"] / got[256]["se"]["a"]
    assert 2.5 < ratio < 6.5  # √(256/16) = 4
    # both errors move with the same reference: their difference is far less noisy
    for g in got.values():
        assert g["pair_se"]["a|b"] < 0.5 * math.hypot(g["se"]["a"], g["se"]["b"])


def test_bootstrap_needs_two_realizations():
    with pytest.raises(ValueError, match="realizations must be at least 2"):
        bootstrap_cell(np.ones((1, 2, 12)), {"a": np.ones((2, 12))})


# ----------------------------------------------------------------------------- the shipped one
def test_samples_errors_agree_with_the_csv():
    """The bootstrap's full-sample error is pec_table.csv's error (the larger of h and v)."""
    header, cols, _ = read_csv(CSV)
    csv = {}
    for i in range(len(cols[header[0]])):
        key = (cols["correlation"][i], float(cols["theta_i_deg"][i]), float(cols["k_sigma"][i]),
               float(cols["k_l"][i]), cols["method"][i])  # fmt: skip
        csv[key] = max(csv.get(key, -math.inf), float(cols["error_dB"][i]))
    cells = json.loads(SAMPLES.read_text())["cells"]
    assert sum(c.get("correlation", "gaussian") == "gaussian" for c in cells) == 12
    inverse = {"spm1": "spm", "po": "po", "go": "go", "iem": "iem"}
    for c in cells:
        models = {inverse[m]: v for m, v in c["models"].items()}
        got = bootstrap_cell(np.asarray(c["mom"]), models, n_boot=50)
        for row, name in inverse.items():
            key = (c.get("correlation", "gaussian"), c["theta_i_deg"], c["k_sigma"], c["k_l"], row)
            assert got["errors"][name] == pytest.approx(csv[key], abs=1e-6)


def test_shipped_table_is_what_the_writer_makes_from_the_samples(tmp_path):
    made = write_measured_3d([SAMPLES, DIELECTRIC_SAMPLES], tmp_path / "t.json")
    assert made.read_text() == measured.TABLE_3D_PATH.read_text()


def test_shipped_table_loads_and_the_lookup_applies_where_it_measured():
    measured.load_table_3d.cache_clear()
    got = measured.measured_errors_3d(GaussianCorrelation(0.33 / K, 3.2 / K), K, "pec",
                                      math.radians(38))  # fmt: skip
    assert got["map"] == "pec3d" and got["cell"] == (40.0, 0.3, 3.0)
    assert set(got["errors"]) == set(NAMES) and got["realizations"] >= 8
    assert all(math.isfinite(e) and e >= 0 for e in got["errors"].values())
    assert all(0 < s < 2 for s in got["se"].values())
    assert got["pair_se"][("spm", "iem")] == got["pair_se"][("iem", "spm")] > 0
    # a θi array within one slice is fine
    arr = measured.measured_errors_3d(GaussianCorrelation(0.1 / K, 3 / K), K, "pec",
                                      np.radians([15.0, 25.0]))  # fmt: skip
    assert arr["cell"] == (20.0, 0.1, 3.0)


@pytest.mark.parametrize(
    ("rough", "eps", "theta"),
    [
        (GaussianCorrelation(0.3 / K, 3 / K, dimension=1), "pec", 40),  # a profile: 1-D maps
        (GaussianCorrelation(0.3 / K, 3 / K), 20.0, 40),  # a dielectric far from ε = 4 + 0.5i
        (PowerLawCorrelation(0.3 / K, 3 / K, hurst=0.8), "pec", 40),  # another correlation
        (GaussianCorrelation(0.3 / K, 3 / K), "pec", None),  # no incidence given
        (GaussianCorrelation(0.3 / K, 3 / K), "pec", [20, 40]),  # spans two slices
        (GaussianCorrelation(0.3 / K, 3 / K), "pec", 60),  # beyond half a step of 40°
        (GaussianCorrelation(0.3 / K, 30 / K), "pec", 40),  # kℓ beyond the cells
        (GaussianCorrelation(0.3 / K, 3 / K, 6 / K), "pec", 40),  # anisotropic
    ],
)
def test_lookup_is_none_where_the_3d_cells_do_not_apply(rough, eps, theta):
    measured.load_table_3d.cache_clear()
    ti = None if theta is None else np.radians(theta)
    assert measured.measured_errors_3d(rough, K, eps, ti) is None


# ----------------------------------------------------------------------------- the rule
ROUGH = GaussianCorrelation(0.1 / K, 3 / K)  # SPM valid and first by the criteria at 20°
TI = math.radians(20)


def test_a_significant_3d_cell_reorders(table):
    table({"spm": 3.0, "iem": 0.5}, {"spm": 0.3, "iem": 0.3}, {"spm|iem": 0.2})
    ranked = select.rank_methods(ROUGH, K, eps="pec", theta_i=TI)
    name, rep = ranked[0]
    assert name == "iem" and rep["picked_by"] == "measured-3d"
    assert rep["measured_3d"]["cell"] == (20.0, 0.1, 3.0)
    assert rep["measured_3d_error_dB"] == 0.5 and rep["measured_3d_se_dB"] == 0.3
    assert dict(ranked)["spm"]["measured_3d_error_dB"] == 3.0
    assert math.isnan(dict(ranked)["go"]["measured_3d_error_dB"])


def test_a_difference_within_two_standard_errors_changes_nothing(table):
    table(None)
    before = select.rank_methods(ROUGH, K, eps="pec", theta_i=TI)
    table({"spm": 1.2, "iem": 0.8}, {"spm": 0.5, "iem": 0.5}, {"spm|iem": 0.25})  # 0.4 < 0.5
    after = select.rank_methods(ROUGH, K, eps="pec", theta_i=TI)
    assert [n for n, _ in after] == [n for n, _ in before]
    assert after[0][1].get("picked_by") != "measured-3d"
    assert after[0][1]["measured_3d_error_dB"] == 1.2


@pytest.mark.parametrize(
    ("errors", "expected"),
    [
        ({"spm": 0.9, "iem": 0.2}, "spm"),  # the pick is within the 1-D maps' 1 dB: it stays
        ({"spm": 1.6, "iem": 1.3}, "spm"),  # neither within 1 dB and the gap below it
        ({"spm": 3.0, "iem": 1.5}, "iem"),  # better by more than 1 dB
        ({"spm": 1.4, "iem": 0.9}, "iem"),  # the other within 1 dB
    ],
)
def test_significant_differences_below_the_maps_tolerance_keep_the_pick(table, errors, expected):
    # every difference here is significant (paired SE 0.01 dB): the tolerance alone decides
    table(errors, {"spm": 0.05, "iem": 0.05}, {"spm|iem": 0.01})
    assert select.rank_methods(ROUGH, K, eps="pec", theta_i=TI)[0][0] == expected


@pytest.mark.parametrize(("se", "expected"), [(1.0, "spm"), (0.5, "iem")])
def test_without_a_pair_se_the_standard_errors_combine_in_quadrature(table, se, expected):
    # 3.0 − 0.5 = 2.5 dB against 2·√2·se: 2.83 (not significant) or 1.41 (significant)
    table({"spm": 3.0, "iem": 0.5}, {"spm": se, "iem": se})
    assert select.rank_methods(ROUGH, K, eps="pec", theta_i=TI)[0][0] == expected


def test_a_3d_cell_takes_precedence_over_the_1d_correction(table):
    # Gaussian PEC kσ = 0.39, kℓ = 0.92 at 20°: the 1-D map moves the criteria's IEM behind SPM
    # (test_measured); a 3-D cell measuring SPM significantly worse keeps the IEM.
    rough = GaussianCorrelation(0.3873 / K, 0.9247 / K)
    cell = {"ks": (0.3873,), "kl": (0.9247,)}
    table(None)
    assert select.rank_methods(rough, K, eps="pec", theta_i=TI)[0][1]["picked_by"] == "measured"
    table({"spm": 3.0, "iem": 0.5}, {"spm": 0.3, "iem": 0.3}, {"spm|iem": 0.2}, **cell)
    name, rep = select.rank_methods(rough, K, eps="pec", theta_i=TI)[0]
    assert name == "iem" and rep["picked_by"] == "measured-3d"
    table({"spm": 3.0, "iem": 0.5}, {"spm": 2.0, "iem": 2.0}, {"spm|iem": 2.0}, **cell)
    name, rep = select.rank_methods(rough, K, eps="pec", theta_i=TI)[0]
    assert name == "spm" and rep["picked_by"] == "measured"  # not significant: 1-D as before


def test_shipped_table_changes_a_pick_only_where_significant(table, monkeypatch):
    """Over 2-D Gaussian PEC roughness around the 3-D cells and θi 15–45°: the shipped table
    leaves every pick of the ranking without it, except where a 3-D cell decided — and there
    the difference is beyond 2 combined standard errors."""
    grid = [(ks, kl, t) for ks in (0.08, 0.1, 0.2, 0.3, 0.5, 1.0, 1.5)
            for kl in (2.2, 3.0, 5.0, 7.0, 9.0)
            for t in (15.0, 20.0, 30.0, 40.0, 45.0)]  # fmt: skip
    table(None)
    before = {g: select.rank_methods(GaussianCorrelation(g[0] / K, g[1] / K), K, eps="pec",
                                     theta_i=math.radians(g[2]))[0][0] for g in grid}  # fmt: skip
    shipped = Path(measured.__file__).with_name("data") / "measured_errors_3d.json"
    assert shipped.exists()
    monkeypatch.setattr(measured, "TABLE_3D_PATH", shipped)
    measured.load_table_3d.cache_clear()
    decided = 0
    for g in grid:
        rough = GaussianCorrelation(g[0] / K, g[1] / K)
        name, rep = select.rank_methods(rough, K, eps="pec", theta_i=math.radians(g[2]))[0]
        if rep.get("picked_by") == "measured-3d" and name != before[g]:
            decided += 1
            meas = measured.measured_errors_3d(rough, K, "pec", math.radians(g[2]))
            other = before[g]
            gap = abs(meas["errors"][other] - meas["errors"][name])
            assert gap > measured.SIGNIFICANCE * measured.combined_se(meas, other, name)
            assert meas["errors"][other] > measured.TOL_DB  # the pick it replaced was > 1 dB off
            assert meas["errors"][name] <= measured.TOL_DB or gap > measured.TOL_DB
        else:
            assert name == before[g], g
    print(f"3-D cells decided {decided} of {len(grid)} picks")
    assert decided > 0  # measured: 50 of 175 (SPM → IEM at kσ 0.2–0.5), 64 realizations


def test_shipped_table_prefers_the_iem_to_first_order_spm_at_k_sigma_0_3():
    """Gaussian PEC kσ = 0.3, kℓ = 3, θi = 40°: both valid by their criteria, SPM first; the
    3-D cell measures SPM1 1.86 dB off and the IEM 0.60 dB (64 realizations, paired SE of the
    difference 0.16 dB): the IEM goes first. Cf. the IEM's second-order terms that SPM1 lacks
    (Fung, Li & Chen 1992)."""
    measured.load_table_3d.cache_clear()
    rough = GaussianCorrelation(0.3 / K, 3 / K)
    ranked = select.rank_methods(rough, K, eps="pec", theta_i=math.radians(40))
    name, rep = ranked[0]
    assert name == "iem" and rep["picked_by"] == "measured-3d" and rep["valid"]
    spm = dict(ranked)["spm"]
    assert spm["valid"] and spm["measured_3d_error_dB"] - rep["measured_3d_error_dB"] > 1.0


def test_writer_and_loader_name_what_is_wrong(tmp_path):
    with pytest.raises(FileNotFoundError, match="samples=.*no such file"):
        write_measured_3d(tmp_path / "none.json", tmp_path / "t.json")
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"schema": "other/1", "cells": []}))
    with pytest.raises(ValueError, match="schema 'other/1', expected one of"):
        write_measured_3d(bad, tmp_path / "t.json")
    broken = tmp_path / "broken.json"
    broken.write_text(json.dumps({"maps": [{"tag": "x", "k_sigma": [0.1]}]}))
    with pytest.raises(ValueError, match="map without 'theta_i_deg'"):
        measured.load_table_3d(str(broken))


def test_lookup_takes_a_table_by_path(table):
    path = table({"spm": 1.5, "iem": 0.5}, {"spm": 0.2, "iem": 0.1}, {"spm|iem": 0.05})
    got = measured.measured_errors_3d(ROUGH, K, "pec", TI, path=path)
    assert got["map"] == "synthetic" and got["errors"]["spm"] == 1.5
    assert measured.combined_se(got, "iem", "spm") == 0.05
    assert measured.significant_pick(got, "spm", NAMES) == "iem"
    assert measured.significant_pick(got, "iem", NAMES) is None


def test_shipped_table_has_the_exponential_cells_and_the_lookup_finds_them():
    """The exponential PEC cells (pec_table.py, band-limited at K_c = 2k) make their own map,
    ``pec3d_exp``: an exponential surface near them is looked up there, never in the Gaussian
    map, and a Gaussian one never in it."""
    measured.load_table_3d.cache_clear()
    got = measured.measured_errors_3d(ExponentialCorrelation(0.11 / K, 3.2 / K), K, "pec",
                                      math.radians(22))  # fmt: skip
    assert got["map"] == "pec3d_exp" and got["cell"] == (20.0, 0.1, 3.0)
    assert got["realizations"] >= 4 and set(got["errors"]) == set(NAMES)
    assert all(math.isfinite(e) and e >= 0 for e in got["errors"].values())
    gauss = measured.measured_errors_3d(GaussianCorrelation(0.11 / K, 3.2 / K), K, "pec",
                                        math.radians(22))  # fmt: skip
    assert gauss["map"] == "pec3d"
    assert gauss["errors"] != got["errors"]
