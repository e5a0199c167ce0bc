"""Validity maps: the auto selector against the method of moments, and MoM vs SPM2 emissivity.

The committed maps (validation/validity_maps/, made by ``emscatter validate --full``) are read
back; small live cells and the emissivity comparison are computed here (tiny MoM runs).
"""

from __future__ import annotations

import dataclasses
import warnings
from pathlib import Path

import numpy as np
import pytest

from emscatter import validity_maps as vm

MAPS = Path(__file__).resolve().parents[1] / "validation" / "validity_maps"
PEC_CSV = MAPS / "validity_pec.csv"


def _read(path: Path) -> list[dict]:
    return vm.read_map(path)


# --------------------------------------------------------------------------- metric
def test_sigma0_error_metric_recovers_a_known_offset():
    mom = np.array([1.0, 0.5, 0.2, 1e-4])  # last bin > 20 dB below the peak: left out
    se = 0.05 * mom
    approx = mom * 10 ** (np.array([1.0, -1.0, 1.0, 9.0]) / 10)
    e = vm._sigma0_error(mom, se, approx)
    assert e["n_bins"] == 3
    assert e["error_dB"] == pytest.approx(1.0, abs=1e-12)
    assert e["max_error_dB"] == pytest.approx(1.0, abs=1e-12)
    noisy = se.copy()
    noisy[1] = 0.6 * mom[1]  # standard error above half the mean: left out
    assert vm._sigma0_error(mom, noisy, approx)["n_bins"] == 2


def test_bin_means_are_trapezoid_averages():
    theta = np.arange(-60.0, 60.5, 1.0)
    vals = 2.0 + 0 * theta
    np.testing.assert_allclose(vm._bin_means(theta, vals, np.arange(-60, 61, 10.0)), 2.0)
    lin = vm._bin_means(theta, theta, np.array([0.0, 10.0]))
    assert lin[0] == pytest.approx(5.0)


def test_selector_failure_detection():
    def rows(auto, errs):
        return [
            {"k_sigma": 1.0, "k_l": 5.0, "method": m, "pol": p, "error_dB": e, "auto": auto}
            for m, e in errs.items()
            for p in "hv"
        ]

    assert vm.selector_failures(rows("spm1", {"spm1": 3.0, "go": 0.5, "po": 2.0}))
    assert not vm.selector_failures(rows("go", {"spm1": 3.0, "go": 0.5, "po": 2.0}))
    assert not vm.selector_failures(rows("po", {"spm1": 3.0, "go": 1.5, "po": 2.0}))


def test_config_rejects_bad_values():
    with pytest.raises(ValueError, match="realizations"):
        dataclasses.replace(vm.TINY, realizations=1)
    with pytest.raises(ValueError, match="k_sigma"):
        dataclasses.replace(vm.TINY, k_sigma=(0.1, -1.0))
    with pytest.raises(ValueError, match="theta_i_deg"):
        dataclasses.replace(vm.TINY, theta_i_deg=75.0)


# --------------------------------------------------------------------------- committed map
PUBLISHED = {"pec": vm.FULL, "eps3+0j": vm.FULL_DIELECTRIC}


def _committed(tag: str) -> list[dict]:
    path = MAPS / f"validity_{tag}.csv"
    if not path.exists():
        pytest.fail(f"{path} missing: run `emscatter validate --full --out {MAPS}`")
    return _read(path)


@pytest.fixture(scope="module")
def committed():
    return _committed("pec")


@pytest.mark.parametrize("tag", sorted(PUBLISHED))
def test_committed_map_auto_never_loses_to_a_method_within_1dB(tag):
    assert vm.selector_failures(_committed(tag)) == []


@pytest.mark.parametrize("tag", sorted(PUBLISHED))
def test_committed_map_auto_column_is_the_current_selector(tag):
    # the map must be regenerated (or `vm.reselect`) whenever a VALIDITY criterion changes
    for r in _committed(tag):
        assert r["auto"] == vm.auto_choice(r["k_sigma"], r["k_l"], PUBLISHED[tag]), r


@pytest.mark.parametrize("tag", sorted(PUBLISHED))
def test_committed_map_has_every_cell_and_method(tag):
    cfg, rows = PUBLISHED[tag], _committed(tag)
    cells = {(r["k_sigma"], r["k_l"]) for r in rows}
    assert len(cells) == len(cfg.k_sigma) * len(cfg.k_l)
    assert len(rows) == len(cells) * len(vm.METHODS) * 2
    assert {r["realizations"] for r in rows if r["status"] == "ok"} == {cfg.realizations}
    computed = [r for r in rows if r["status"] == "ok"]
    assert len(computed) > 0.6 * len(rows)


def test_committed_map_spm1_holds_at_small_k_sigma(committed):
    # Thorsos & Jackson (1989, JASA 86, 261): first-order SPM accurate for kσ ≪ 1.
    small = [r for r in committed if r["method"] == "spm1" and r["k_sigma"] <= 0.1]
    assert small
    for r in small:
        assert r["error_dB"] < 1.0, r


def test_committed_map_po_holds_in_thorsos_regime(committed):
    # Thorsos (1988, JASA 83, 78): Kirchhoff accurate for kℓ ≳ 6 at moderate kσ.
    rows = [
        r
        for r in committed
        if r["method"] == "po" and r["k_l"] >= 10 and 0.3 <= r["k_sigma"] <= 1.6
    ]
    assert rows
    for r in rows:
        assert r["error_dB"] < 1.0, r


# --------------------------------------------------------------------------- live cells
@pytest.fixture(scope="module")
def live(tmp_path_factory):
    out = tmp_path_factory.mktemp("validity")
    cfg = dataclasses.replace(
        vm.TINY, k_sigma=(0.1, 1.0), k_l=(10.0,), realizations=12, min_length_wl=16.0
    )
    paths = vm.run_validation(out, config=cfg, progress=False)
    return cfg, paths


def test_run_validation_writes_files(live):
    cfg, paths = live
    names = {p.name for p in paths}
    assert {"validity_pec.csv", "validity_pec.json", "validity_pec_h.png"} <= names
    for p in paths:
        assert p.stat().st_size > 0
    rows = _read(next(p for p in paths if p.suffix == ".csv"))
    assert len(rows) == len(cfg.k_sigma) * len(cfg.k_l) * len(vm.METHODS) * 2
    with open(next(p for p in paths if p.name.endswith("_h.png")), "rb") as fh:
        assert fh.read(8) == b"\x89PNG\r\n\x1a\n"


def test_live_cells_auto_choice_is_within_1dB(live):
    cfg, paths = live
    rows = _read(next(p for p in paths if p.suffix == ".csv"))
    assert vm.selector_failures(rows) == []
    by = {(r["k_sigma"], r["method"], r["pol"]): r for r in rows}
    # kσ = 0.1: auto → SPM; kσ = 1, kℓ = 10: auto → PO (SPM invalid, 10+ dB off)
    assert by[(0.1, "spm1", "h")]["auto"] == "spm1"
    assert by[(1.0, "po", "h")]["auto"] == "po"
    for p in "hv":
        assert by[(0.1, "spm1", p)]["error_dB"] < 1.0
        assert by[(1.0, "po", p)]["error_dB"] < 1.0
        assert by[(1.0, "spm1", p)]["error_dB"] > 3.0


# --------------------------------------------------------------------------- emissivity
@pytest.mark.parametrize("theta_deg", [0.0, 40.0])
def test_mom_emissivity_matches_spm2_at_small_k_sigma(theta_deg):
    # Lossy dielectric 1-D Gaussian profile, kσ = 0.1, kℓ = 1, ε = 5 + 0.5i: MoM
    # e = 1 − ⟨reflected power⟩/P_inc (4 realizations, 15 points per wavelength in the
    # dielectric) vs the second-order SPM e = 1 − r_coh(SPM2) − r_incoh(SPM1): within 0.005
    # (issue 4). The roughness effect e − e_flat is 0.0015–0.0046 here, so also require the
    # MoM to reproduce it: |MoM − SPM| < |SPM − flat|/2 + 2 SE.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = vm.mom_emissivity(
            0.1,
            1.0,
            5 + 0.5j,
            theta_deg,
            realizations=4,
            length_wl=16.0,
            points_per_wavelength=15.0,
        )
    for p in "hv":
        d = r[p]
        assert abs(d["difference"]) < 0.005, (p, d)
        assert abs(d["difference"]) < 0.5 * abs(d["spm"] - d["fresnel"]) + 2 * d["mom_se"], (p, d)
        assert d["mom"] > d["fresnel"]  # roughness raises the emissivity here
        assert d["mom_se"] < 1e-3


def test_committed_emissivity_table_within_0p005():
    # validation/validity_maps/emissivity_mom_spm2.csv (vm.emissivity_table): MoM vs SPM2
    # emissivity, kσ = 0.1–0.2, ε = 5 + 0.5i and 17 + 2i, θi = 0° and 40°, both pols.
    import csv

    with open(MAPS / "emissivity_mom_spm2.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 2 * len(vm.EMISSIVITY_CASES)
    for r in rows:
        assert abs(float(r["difference"])) < 0.005, r
        assert float(r["e_mom"]) > float(r["e_flat"]) - 3 * float(r["e_mom_se"]), r
