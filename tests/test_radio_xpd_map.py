"""Cross-polar discrimination per radio-map cell (issue 18): Sionna RT's RadioMapSolver with the
field of each cell split into V/H receive ports (emscatter.radio.xpd_map), flat ITU walls
against emscatter's rough ones, and the CLI's ``--xpd-map`` (tests/radio_xpd_worker.py and the
CLI run in fresh interpreters: Dr.Jit variants are per process)."""

from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from emscatter.radio.roughening import compare_rough_flat
from emscatter.radio.xpd_map import polarized_radio_map, xpd_summary

HERE = Path(__file__).parent
SIONNA = importlib.util.find_spec("sionna") is not None


def _env():
    src = str(HERE.parent / "src")
    return {**os.environ, "PYTHONPATH": os.pathsep.join([src, os.environ.get("PYTHONPATH", "")]),
            "MPLBACKEND": "Agg"}  # fmt: skip


def test_summary_keeps_infinite_quartiles_and_ignores_unlit_cells():
    x = np.array([10.0, 20.0, 30.0, np.inf, np.inf, np.inf, np.inf, np.nan])
    s = xpd_summary(x)
    # order statistics, no interpolation: inf − inf never turns a quartile into NaN
    assert s["n"] == 7 and s["n_inf"] == 4
    assert s["q25"] == 20.0 and s["median"] == np.inf and s["q75"] == np.inf
    lit = np.array([1, 1, 1, 0, 0, 0, 0, 0], dtype=bool)
    assert xpd_summary(x, lit) == {"n": 3, "n_inf": 0, "q25": 10.0, "median": 20.0, "q75": 30.0}
    assert xpd_summary(x, np.zeros(8, dtype=bool))["n"] == 0


def test_bad_inputs_are_named_before_sionna_runs():
    class NoTx:
        transmitters = {}

    with pytest.raises(ValueError, match="xpd_map=True needs a radio map"):
        compare_rough_flat(object(), xpd_map=True, paths=True)
    with pytest.raises(TypeError, match="seed must be an integer, got 1.5"):
        polarized_radio_map(NoTx(), seed=1.5)
    with pytest.raises(ValueError, match="no transmitter"):
        polarized_radio_map(NoTx())
    p = subprocess.run([sys.executable, "-m", "emscatter.cli", "radio", "--plate", "--xpd-map"],
                       capture_output=True, text=True, env=_env(), timeout=300)  # fmt: skip
    assert p.returncode != 0 and "--xpd-map applies to scenes" in p.stderr
    assert "Traceback" not in p.stderr


@pytest.mark.skipif(not SIONNA, reason="Sionna RT not installed")
def test_xpd_per_cell_flat_limit_diffuse_and_path_consistency():
    proc = subprocess.run([sys.executable, str(HERE / "radio_xpd_worker.py"), "xpd_map_plate"],
                          capture_output=True, text=True, env=_env(), timeout=900)  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-4000:]
    res = json.loads(proc.stdout.strip().splitlines()[-1])["xpd_map_plate"]
    assert "error" not in res, res["error"]
    assert res["warnings"] == []
    r = res["result"]
    # the port maps carry Sionna's own map: V + H receive ports = RadioMapSolver's |E|² per cell,
    # same seed (measured 2e-6, float32)
    assert r["ports_same_support"] and r["ports_vs_sionna_max_rel"] < 1e-4
    # flat ITU concrete plate: LoS and the specular bounce off a horizontal plane keep TM in the
    # plane of incidence (θ̂) and TE (φ̂) apart, so cross-polar power is float32 rounding only
    # (measured: every one of 144 cells > 146 dB)
    assert r["flat_lit"] == 144 and r["flat"]["q25"] > 100
    # the rough plate's coherent specular field is also co-polar (diffuse off: > 145 dB) ...
    assert r["spec_cross_max_db_below_co"] > 100
    # ... and its diffuse lobe depolarizes: finite XPD in every cell, 25 dB median (measured
    # 23.6…26.3 dB quartiles), lower where the diffuse share of the cell's power is larger
    # (measured: 26.9 dB median over the third of cells with the lowest share, 23.5 dB over
    # the highest third; shares 0.04–1.3 %, the LoS dominates)
    assert r["rough_finite"] == 144 and 15 < r["rough"]["median"] < 35
    assert r["xpd_high_share_median"] < r["xpd_low_share_median"] - 1.5
    # a receiver at a cell centre: its link XPD from PathSolver (1 M rays, VH arrays) equals
    # the map's XPD of that cell within 2 dB and of the 3 × 3 cells around it within 1 dB
    # (measured worst 1.19 dB and 0.53 dB: Monte-Carlo noise of the diffuse cross-polar power)
    for row in r["receivers"]:
        assert abs(row["path_db"] - row["cell_db"]) < 2.0, row
        assert abs(row["path_db"] - row["block_db"]) < 1.0, row


@pytest.mark.skipif(not SIONNA, reason="Sionna RT not installed")
def test_cli_xpd_map_street_canyon(tmp_path):
    from emscatter.io import read_csv

    args = ["--scene", "simple_street_canyon", "--frequencies-ghz", "28", "--quick", "--quiet",
            "--xpd-map", "--rx", "60,2,1.5", "--rx", "50,-3,1.5",
            "--out", str(tmp_path)]  # fmt: skip
    p = subprocess.run([sys.executable, "-m", "emscatter.cli", "radio", *args],
                       capture_output=True, text=True, env=_env(), timeout=900)  # fmt: skip
    assert p.returncode == 0, p.stderr[-3000:]
    assert "cells lit in both): flat median" in p.stdout
    for name in ("28GHz_xpd_map.csv", "28GHz_xpd_map.png", "xpd_vs_frequency.csv",
                 "xpd_vs_frequency.png"):  # fmt: skip
        assert (tmp_path / f"simple_street_canyon_{name}").stat().st_size > 0
    header, cols, meta = read_csv(tmp_path / "simple_street_canyon_28GHz_xpd_map.csv")
    assert header[-4:] == ["rough_co_db", "rough_cross_db", "rough_xpd_db",
                           "rough_minus_flat_xpd_db"] and meta["frequency_hz"] == 28e9  # fmt: skip
    x, y = np.asarray(cols["x_m"]), np.asarray(cols["y_m"])
    flat, rough = np.asarray(cols["flat_xpd_db"]), np.asarray(cols["rough_xpd_db"])
    near = (np.hypot(x - 20.0, y) < 10.0) & np.isfinite(flat) & np.isfinite(rough)
    # within 10 m of the transmitter (20, 0, 10) the flat street is LoS + the ground's specular
    # bounce: co-polar to float32 rounding (measured median 154 dB); emscatter's rough ground
    # and walls depolarize (measured median 21 dB)
    assert near.sum() > 10
    assert np.median(flat[near]) > 100 and np.median(rough[near]) < 35
    # over the whole map the flat street's XPD is geometric (off-plane wall bounces, measured
    # median 25.2 dB) and the rough one lower (24.1 dB)
    fs, rs = meta["flat_summary"], meta["rough_summary"]
    assert 10 < fs["median"] < 60 and rs["median"] < fs["median"]
    # receivers in two cells: their link XPD from PathSolver paths (isotropic VH arrays) = the
    # XPD of the cell holding them, flat and rough, within 1.5 dB (measured worst 0.09 dB flat,
    # 0.27 dB rough; 3.1 m cells, 1e5 rays: Monte-Carlo noise of both solvers)
    _, paths, _ = read_csv(tmp_path / "simple_street_canyon_28GHz_paths.csv")
    for i, (rx, ry) in enumerate(((60.0, 2.0), (50.0, -3.0))):
        k = np.argmin(np.hypot(x - rx, y - ry))
        for state, cell in (("flat", flat), ("rough", rough)):
            assert abs(paths[f"{state}_xpd_db"][i] - cell[k]) < 1.5, (i, state)
    _, fcols, _ = read_csv(tmp_path / "simple_street_canyon_xpd_vs_frequency.csv")
    assert list(fcols["frequency_ghz"]) == [28.0]
    assert fcols["rough_median_db"][0] == pytest.approx(rs["median"])
