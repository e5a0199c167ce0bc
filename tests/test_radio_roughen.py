"""Any Sionna scene rough in one call (issue 18): ``radio.roughen`` / ``radio.flatten`` /
``radio.compare_rough_flat`` on Sionna's own ``simple_street_canyon``, Sionna running for real in
a fresh interpreter (tests/radio_worker.py: Dr.Jit variants are per process)."""

from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

if importlib.util.find_spec("sionna") is None:
    pytest.skip("Sionna RT is not installed", allow_module_level=True)

HERE = Path(__file__).parent


def _run(*checks: str) -> dict:
    src = str(HERE.parent / "src")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([src, os.environ.get("PYTHONPATH", "")])}
    proc = subprocess.run(
        [sys.executable, str(HERE / "radio_worker.py"), *checks],
        capture_output=True, text=True, env=env, timeout=900,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-4000:]
    results = json.loads(proc.stdout.strip().splitlines()[-1])
    for name in checks:
        assert "error" not in results[name], results[name]["error"]
        assert results[name]["warnings"] == [], results[name]["warnings"]
    return {name: results[name]["result"] for name in checks}


def test_street_canyon_rough_in_one_call_flat_back_and_rough_minus_flat():
    r = _run("roughen_street_canyon", "roughen_errors")
    s = r["roughen_street_canyon"]
    # Sionna's materials are named concrete, brick, ... (not itu_*): matched by itu_type
    assert s["original_materials"] == ["brick", "concrete", "glass", "marble", "wood"]
    # every object replaced, ONE shared emscatter material per medium, originals gone
    assert s["types"] == ["EmscatterRadioMaterial"]
    assert s["materials"] == ["rough-brick", "rough-concrete", "rough-glass", "rough-marble",
                              "rough-wood"]  # fmt: skip
    assert s["shared"]["rough-glass"] == ["building_1", "building_5"]
    assert s["shared"]["rough-marble"] == ["building_3", "building_4"]
    rows = {row["object"]: row for row in s["rows"]}
    assert rows["building_2"]["sigma_m"] == pytest.approx(0.8e-3)  # default table, brick
    assert rows["building_1"]["correlation"] == "flat"  # glass stays flat
    assert all(row["roughness_from"].startswith("default table") for row in s["rows"])
    # tables only for the rough media that objects use, PO for brick (kσ ≈ 0.47, kℓ ≈ 4.7)
    assert s["tables"] == {"rough-wood": "spm", "rough-marble": "spm", "rough-brick": "po",
                           "rough-concrete": "spm"}  # fmt: skip
    assert s["rough_diffuse_finite"]
    # flat back: the same material instances, and bit-identical path gains (same seed)
    assert s["after_flatten"] == s["original_materials"] and s["same_instances"]
    assert s["flat_back_equal"]
    assert s["twice"] == s["materials"]  # a second roughen flattens first: no name clash
    # One rough brick wall (σ = 0.8 mm, ℓ = 8 mm; PO: |R_coh|² = |R|² e^{−(2kσ cosθ)²}), every
    # other medium flat (emscatter's flat slab = Sionna's ITU slab within 1e-4 dB), specular
    # paths only: the receivers that see the transmitter's image in the wall (0–3) lose power,
    # the one whose paths miss the wall (4) does not change.
    d = np.array(s["wall_minus_flat_specular_db"])
    assert np.all(d[:4] < -0.2), d
    assert abs(d[4]) < 1e-3, d
    # rough − flat radio map in one call (street in front of the brick wall, no diffuse):
    # finite where both maps are lit, NaN (documented) elsewhere, and a net specular loss
    assert s["map_cells_lit"] > 100
    assert s["map_finite_where_lit"] and s["map_nan_elsewhere"]
    assert s["map_median_db"] < 0 and s["map_mean_power_ratio_db"] < -0.02
    assert s["compare_paths_finite"]
    assert np.all(np.array(s["compare_paths_db"])[:4] < 0)  # with diffuse on: still a loss
    assert s["after_compare"] == s["original_materials"]  # the scene handed back as it was

    e = r["roughen_errors"]
    assert "mapping names ['granite']" in e["unknown_key"] and "'brick'" in e["unknown_key"]
    assert "mapping['brick'] must be (sigma, length)" in e["bad_value"]
    assert "(-0.001, 0.01)" in e["bad_value"]
    assert (
        "roughness must be (sigma, length)" in e["bad_roughness"] and "0.0004" in e["bad_roughness"]
    )
    assert e["out_of_band"].startswith("OutOfBandError: materials outside their ITU-R P.2040")
    assert "'brick' (objects building_2) at 50 GHz" in e["out_of_band"]
    assert "1–40 GHz" in e["out_of_band"] and "extrapolate=True" in e["out_of_band"]
    assert "was not roughened" in e["flatten_unroughened"]
    assert "no transmitter" in e["no_transmitter"]
    assert "reference must be 'original' or 'flat'" in e["bad_reference"]
    assert e["unchanged"]  # nothing changed by the failed calls


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--scene", "garage"], "invalid choice: 'garage'"),
        (["--scene", "gone.xml"], "no scene file at 'gone.xml'"),
        (["--scene", "simple_street_canyon", "--medium", "brick=-1,2"], "must be in (0, 1) m"),
        (["--scene", "simple_street_canyon", "--medium", "brickflat"], "expected NAME=SIGMA"),
        (["--scene", "simple_street_canyon", "--medium", "brick=1e-3"], "two numbers"),
        (["--scene", "simple_street_canyon", "--tx", "1,2"], "expected X,Y,Z in metres"),
        (["--scene", "etoile"], "--tx X,Y,Z [m] is required for scene 'etoile'"),
        (["--plate", "--medium", "brick=1e-3,1e-2"], "--medium and --tx apply to scenes"),
    ],
)
def test_cli_any_scene_bad_arguments_before_any_work(argv, message, tmp_path, capsys):
    from emscatter.cli import main

    out = tmp_path / "o"
    assert main(["radio", *argv, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err, err
    assert not out.exists()


def _cli(args):
    src = str(HERE.parent / "src")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([src, os.environ.get("PYTHONPATH", "")]),
           "MPLBACKEND": "Agg"}  # fmt: skip
    return subprocess.run([sys.executable, "-m", "emscatter.cli", "radio", *args],
                          capture_output=True, text=True, env=env, timeout=900)  # fmt: skip


def test_cli_any_scene_names_and_bands_checked_before_tracing(tmp_path):
    out = tmp_path / "o"
    p = _cli(
        ["--scene", "simple_street_canyon", "--medium", "granite=1e-3,1e-2", "--out", str(out)]
    )
    assert p.returncode == 2 and "mapping names ['granite']" in p.stderr and "'brick'" in p.stderr
    p = _cli(["--scene", "simple_street_canyon", "--frequencies-ghz", "28,50", "--out", str(out)])
    assert p.returncode == 2
    assert "'brick' (objects building_2) at 50 GHz" in p.stderr and "1–40 GHz" in p.stderr
    assert not out.exists()


def test_cli_street_canyon_rough_minus_flat_png_and_csv(tmp_path):
    from emscatter.io import read_csv

    args = ["--scene", "simple_street_canyon", "--medium", "brick=1.2e-3,8e-3", "--medium",
            "glass=flat", "--frequencies-ghz", "28", "--quick", "--out", str(tmp_path)]  # fmt: skip
    p = _cli(args)
    assert p.returncode == 0, p.stderr[-3000:]
    stem = tmp_path / "simple_street_canyon_28GHz"
    assert Path(f"{stem}_map.png").read_bytes()[:4] == b"\x89PNG"
    header, cols, meta = read_csv(f"{stem}_map.csv")
    assert header == ["x_m", "y_m", "z_m", "flat_db", "rough_db", "rough_minus_flat_db"]
    assert meta["frequency_hz"] == 28e9 and meta["reference"] == "original"
    lit = np.isfinite(cols["flat_db"]) & np.isfinite(cols["rough_db"])
    d = cols["rough_minus_flat_db"]
    assert lit.sum() > 500 and np.all(np.isfinite(d[lit])) and np.all(np.isnan(d[~lit]))
    assert np.allclose(cols["z_m"], 1.5)
    np.testing.assert_allclose(d[lit], cols["rough_db"][lit] - cols["flat_db"][lit], atol=1e-6)
    # the rough brick building (x ∈ [32, 64], y ∈ [10, 38]) passes less power (coherent
    # transmission through its rough walls and specular reflection both drop)
    x, y = cols["x_m"], cols["y_m"]
    inside = lit & (x > 35) & (x < 60) & (y > 13) & (y < 35)
    assert inside.sum() > 20 and np.median(d[inside]) < -0.5
    _, mats, _ = read_csv(f"{stem}_materials.csv")
    rows = dict(zip(mats["object"], mats["roughness_from"], strict=True))
    assert rows["building_2"] == "mapping['brick']" and rows["building_1"] == "mapping['glass']"
    assert rows["floor"] == "default table (concrete)"
    assert "rough − flat median" in p.stdout


def test_roughen_with_diffuse_transmission_where_a_slab_can_carry_it():
    s = _run("roughen_diffuse_transmission")["roughen_diffuse_transmission"]
    for row in s["rows"]:
        slab = row["correlation"] != "flat" and row["thickness_m"] is not None
        assert row["transmission"] == ("diffuse" if slab else "coherent"), row
    assert any(r["transmission"] == "diffuse" for r in s["rows"])  # the brick/concrete walls
    assert "coherent" in s["materials"].values() or all(
        r["transmission"] == "diffuse" for r in s["rows"]
    )
    assert "transmission must be one of ('coherent', 'diffuse')" in s["bad"]
    assert "'lambertian'" in s["bad"]
    # transmission_face reaches every material made; refused where nothing would use it
    assert s["faces"] and set(s["faces"].values()) == {"po"}
    coherent_po, unknown = s["bad_faces"]
    assert "transmission_face='po' applies to transmission='diffuse' only" in coherent_po
    assert "face must be one of ('auto', 'go', 'spm', 'po', 'iem'), got face='x'" in unknown


def test_cli_transmission_face_needs_diffuse_transmission_and_a_known_model():
    src = str(HERE.parent / "src")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([src, os.environ.get("PYTHONPATH", "")])}
    base = [sys.executable, "-m", "emscatter.cli", "radio", "--transmission-face"]
    p = subprocess.run(base + ["po"], capture_output=True, text=True, env=env, timeout=300)
    assert p.returncode == 2, p.stderr
    assert "--transmission-face applies only with --diffuse-transmission" in p.stderr
    p = subprocess.run(
        base + ["glass", "--diffuse-transmission"], capture_output=True, text=True, env=env,
        timeout=300,
    )  # fmt: skip
    assert p.returncode == 2, p.stderr
    assert "--transmission-face must be one of auto, go, spm, po, iem, got 'glass'" in p.stderr
    assert "Traceback" not in p.stderr


def test_cli_diffuse_transmission_is_for_scenes():
    src = str(HERE.parent / "src")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([src, os.environ.get("PYTHONPATH", "")])}
    p = subprocess.run(
        [sys.executable, "-m", "emscatter.cli", "radio", "--plate", "--diffuse-transmission"],
        capture_output=True, text=True, env=env, timeout=300,
    )  # fmt: skip
    assert p.returncode == 2, p.stderr
    assert "--diffuse-transmission applies to scenes" in p.stderr
    assert "Traceback" not in p.stderr
