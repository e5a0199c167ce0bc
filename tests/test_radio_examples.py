"""The three radio cross-check scripts (quick mode), the ``emscatter radio`` command and the
demo's plate check. Scripts that run Sionna RT run in a subprocess (fresh Dr.Jit variant)."""

from __future__ import annotations

import csv
import importlib.util
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples" / "radio"
# Sionna runs in subprocesses only (never imported here: it would set this worker's variant).
needs_sionna = pytest.mark.skipif(
    importlib.util.find_spec("sionna") is None, reason="Sionna RT is not installed"
)


def _env():
    path = os.pathsep.join([str(ROOT / "src"), os.environ.get("PYTHONPATH", "")])
    return {**os.environ, "PYTHONPATH": path, "MPLBACKEND": "Agg"}


def _run(args, timeout=900):
    proc = subprocess.run(
        [sys.executable, *args], capture_output=True, text=True, env=_env(), timeout=timeout
    )
    assert proc.returncode == 0, (proc.stdout[-3000:], proc.stderr[-3000:])
    return proc


def _rows(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def test_frequency_sweep_quick(tmp_path):
    import runpy

    mod = runpy.run_path(str(EXAMPLES / "frequency_sweep.py"))
    assert mod["main"](["--quick", "--out", str(tmp_path)]) == 0
    assert (tmp_path / "frequency_sweep.png").stat().st_size > 10_000
    rows = _rows(tmp_path / "frequency_sweep.csv")
    assert len(rows) == 12
    em_h = np.array([float(r["emscatter_h_db"]) for r in rows])
    ament = np.array([float(r["ament_db"]) for r in rows])
    boithias = np.array([float(r["boithias_db"]) for r in rows])
    kirchhoff = np.array([r["method"] in ("po", "go") for r in rows])
    spm = np.array([r["method"] == "spm" for r in rows])
    kl = np.array([float(r["k_length"]) for r in rows])
    assert kirchhoff.any() and spm.any()
    # the Kirchhoff mean field is Ament's factor
    np.testing.assert_allclose(em_h[kirchhoff], ament[kirchhoff], atol=1e-9)
    # small kℓ: the second-order SPM mean field loses more than Ament (transition layer)
    small = spm & (kl < 1)
    assert small.any() and np.all(em_h[small] < ament[small])
    # Boithias never loses more than Ament, and much less once g = (2kσ cosθ)² ≫ 1
    assert np.all(boithias >= ament - 1e-12)
    assert boithias[-1] - ament[-1] > 10.0
    # roughness matters more as frequency rises
    assert np.all(np.diff(em_h[kirchhoff]) < 0)


@needs_sionna
def test_plate_check_quick(tmp_path):
    _run([str(EXAMPLES / "plate_check.py"), "--quick", "--out", str(tmp_path)])
    rows = _rows(tmp_path / "plate_check.csv")
    assert (tmp_path / "plate_check.png").stat().st_size > 10_000
    spec = [r for r in rows if r["kind"] == "specular"]
    dif = [r for r in rows if r["kind"] == "diffuse"]
    assert {r["pair"] for r in spec} == {"VV", "HH"} and {r["pair"] for r in dif} == {
        "VV",
        "HH",
        "HV",
    }
    assert all(abs(float(r["diff_db"])) < 0.01 for r in spec)
    assert all(abs(float(r["diff_db"])) < 0.2 for r in dif)
    assert all(r["ok"] == "True" for r in rows)


@needs_sionna
def test_indoor_compare_quick(tmp_path):
    proc = _run([str(EXAMPLES / "indoor_compare.py"), "--quick", "--out", str(tmp_path)])
    for name in ("indoor_maps_room.png", "indoor_vs_frequency.png"):
        assert (tmp_path / name).stat().st_size > 10_000
    rows = _rows(tmp_path / "indoor_receivers.csv")
    assert {r["kind"] for r in rows} == {"sionna", "flat", "rough"}
    pg = {(r["frequency_ghz"], r["kind"], r["rx"]): float(r["path_gain_db"]) for r in rows}
    assert all(np.isfinite(v) and -150 < v < -20 for v in pg.values())
    summ = {float(r["frequency_ghz"]): r for r in _rows(tmp_path / "indoor_summary.csv")}
    lo, hi = summ[3.5], summ[140.0]
    # roughness matters more as frequency rises: rough − flat grows from 3.5 to 140 GHz
    assert float(lo["median_abs_dpg_vs_flat_db"]) < 0.05
    assert float(hi["median_abs_dpg_vs_flat_db"]) > 4 * float(lo["median_abs_dpg_vs_flat_db"])
    assert "rough − flat" in proc.stdout


@needs_sionna
def test_cli_radio_plate_quick_is_the_demo_check(tmp_path):
    proc = _run(["-m", "emscatter.cli", "radio", "--plate", "--quick", "--out", str(tmp_path)])
    assert (tmp_path / "radio_plate.png").exists()
    rows = _rows(tmp_path / "radio_plate.csv")
    assert rows and all(r["ok"] == "True" for r in rows)
    assert "radio_plate.csv" in proc.stdout


@pytest.mark.parametrize(
    "argv, message",
    [
        (["radio", "--frequencies-ghz", "0.5"], "must be in [1, 1000] GHz, got 0.5"),
        (["radio", "--frequencies-ghz", "28,abc"], "expected a number, got 'abc'"),
        (["radio", "--scene", "garage"], "invalid choice: 'garage'"),
        (["radio", "--samples", "10"], "--samples: must be in [1000"),
    ],
)
def test_cli_radio_bad_arguments(argv, message, capsys):
    from emscatter.cli import main

    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err


@pytest.mark.parametrize(
    "argv, named",
    [
        # the default frequencies (3.5, 28, 140 GHz) take Sionna's ITU metal box past 100 GHz
        (["--scene", "box"], ["'metal' in scene 'box' at 140 GHz", "1–100 GHz"]),
        (["--scene", "all", "--frequencies-ghz", "28,140"], ["'metal' in scene 'box' at 140 GHz"]),
        (
            ["--frequencies-ghz", "500"],
            [
                "'concrete' in scene 'room' at 500 GHz",
                "1–100 GHz, 110–330 GHz",
                "'plasterboard'",
                "'wood'",
                "100–400 GHz",
            ],
        ),  # fmt: skip
    ],
)
def test_cli_radio_out_of_band_is_an_error_before_any_work(argv, named, tmp_path, capsys):
    import time

    from emscatter.cli import main

    out = tmp_path / "radio"
    t0 = time.perf_counter()
    assert main(["radio", *argv, "--out", str(out)]) == 2
    assert time.perf_counter() - t0 < 10  # checked before Sionna starts or a table is built
    err = capsys.readouterr().err
    assert err.startswith("emscatter radio: error: materials outside their ITU-R P.2040 bands")
    assert all(n in err for n in named), err
    assert "--extrapolate" in err and "Traceback" not in err
    assert not out.exists()


def test_cli_radio_extrapolate_does_not_apply_to_the_plate(tmp_path, capsys):
    from emscatter.cli import main

    assert main(["radio", "--plate", "--extrapolate", "--out", str(tmp_path / "p")]) == 2
    assert "--extrapolate applies to the indoor scenes, not to --plate" in capsys.readouterr().err
    assert not (tmp_path / "p").exists()


@needs_sionna
def test_cli_radio_quick_twice_gives_identical_csvs(tmp_path):
    # 140 GHz, rough room: ≈ 46 k candidate paths for 20 k rays (the buffer used to overflow
    # and drop paths in thread order: −111.0 vs −137.1 dB between two runs at 500 GHz)
    runs = [tmp_path / "a", tmp_path / "b"]
    for out in runs:
        _run(["-m", "emscatter.cli", "radio", "--quick", "--frequencies-ghz", "140",
              "--out", str(out)])  # fmt: skip
    for name in ("indoor_receivers.csv", "indoor_summary.csv"):
        assert (runs[0] / name).read_bytes() == (runs[1] / name).read_bytes(), name
    import json

    run = json.loads((runs[0] / "indoor_run.json").read_text())
    assert run["settings"]["extrapolate"] is False and run["extrapolated"] == []
    rough = [b for b in run["path_buffers"] if b["kind"] == "rough"]
    assert rough and all(not b["full"] and b["stored"] > 20_000 for b in rough)
    rows = _rows(runs[0] / "indoor_receivers.csv")
    assert {r["extrapolated_media"] for r in rows} == {"none"}


@needs_sionna
def test_cli_radio_extrapolate_is_recorded_in_the_outputs(tmp_path):
    proc = _run(["-m", "emscatter.cli", "radio", "--scene", "box", "--quick", "--frequencies-ghz",
                 "28,140", "--extrapolate", "--out", str(tmp_path)])  # fmt: skip
    assert "extrapolating 'metal' (box) to 140 GHz" in proc.stdout
    rows = _rows(tmp_path / "indoor_receivers.csv")
    by_f = {r["frequency_ghz"]: r["extrapolated_media"] for r in rows}
    assert by_f == {"28": "none", "140": "metal"}
    summ = {
        r["frequency_ghz"]: r["extrapolated_media"] for r in _rows(tmp_path / "indoor_summary.csv")
    }
    assert summ == {"28": "none", "140": "metal"}
    import json

    run = json.loads((tmp_path / "indoor_run.json").read_text())
    assert run["settings"]["extrapolate"] is True
    assert run["extrapolated"] == [
        {"scene": "box", "medium": "metal", "frequency_ghz": 140.0, "bands_ghz": [[1.0, 100.0]]}
    ]
