"""``emscatter radio --medium NAME=σ,ℓx,ℓy@DIR`` (issue 18: walls with a texture direction).

The option's parser is :func:`emscatter.radio.texture.parse_medium_option`; the run is Sionna for
real in a fresh interpreter (Dr.Jit variants are per process), with the quick settings of the
height-map CLI test (``tests/test_radio_height_map_cli.py``)."""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

HERE = Path(__file__).parent


def _main(argv, capsys):
    from emscatter.cli import main

    rc = main(["radio", *argv])
    return rc, capsys.readouterr().err


@pytest.mark.parametrize(
    "value, message",
    [
        ("brick=1e-3,8e-3,4e-3", "need a texture direction @DIR"),
        ("brick=1e-3,8e-3,4e-3@sideways", "bad direction 'sideways'"),
        ("brick=1e-3,8e-3,4e-3@0,0,0", "bad direction '0,0,0'"),
        ("brick=1e-3,-8e-3,4e-3@z", "need 2 or 3 positive numbers"),
        ("brick=1e-3,8e-3,nan@z", "brick=1e-3,8e-3,nan@z"),
    ],
)
def test_bad_textured_media_are_one_line_errors(value, message, tmp_path, capsys):
    out = tmp_path / "o"
    rc, err = _main(
        ["--scene", "simple_street_canyon", "--medium", value, "--out", str(out)], capsys
    )
    assert rc == 2
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and "argument --medium: " in lines[0] and message in lines[0], err
    assert "Traceback" not in err and not out.exists()


def test_builtin_json_refuses_a_textured_medium(tmp_path, capsys):
    rc, err = _main(
        ["--builtin-json", str(tmp_path / "b.json"), "--medium", "brick=1e-3,8e-3,4e-3@z"], capsys
    )
    assert rc == 2 and "isotropic built-in models" in err and "Traceback" not in err, err


def test_the_option_reaches_roughen_as_surface_and_direction():
    from emscatter.cli.radio import Textured, _medium, _texture_directions

    name, v = _medium("brick=1e-3,8e-3,4e-3@vertical")
    assert name == "brick" and isinstance(v, Textured)
    assert (v.surface.sigma, v.surface.length, v.surface.length_y) == (1e-3, 8e-3, 4e-3)
    assert v.direction == (0.0, 0.0, 1.0)

    class A:
        medium = [("brick", v), ("glass", None), ("concrete", (1e-3, 5e-3))]

    assert _texture_directions(A) == {"brick": (0.0, 0.0, 1.0)}
    assert _medium("concrete=1e-3,5e-3") == ("concrete", (1e-3, 5e-3))  # isotropic as before


@pytest.mark.skipif(importlib.util.find_spec("sionna") is None, reason="Sionna RT not installed")
def test_cli_street_canyon_with_grooved_brick(tmp_path):
    from emscatter.io import read_csv

    src = str(HERE.parent / "src")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([src, os.environ.get("PYTHONPATH", "")]),
           "MPLBACKEND": "Agg"}  # fmt: skip
    args = ["--scene", "simple_street_canyon", "--medium", "brick=1.2e-3,16e-3,6e-3@vertical",
            "--medium", "glass=flat", "--frequencies-ghz", "28", "--quick",
            "--out", str(tmp_path)]  # fmt: skip
    p = subprocess.run([sys.executable, "-m", "emscatter.cli", "radio", *args],
                       capture_output=True, text=True, env=env, timeout=900)  # fmt: skip
    assert p.returncode == 0, p.stderr[-3000:]
    stem = tmp_path / "simple_street_canyon_28GHz"
    _, mats, _ = read_csv(f"{stem}_materials.csv")
    rows = {o: i for i, o in enumerate(mats["object"])}
    b = rows["building_2"]
    assert mats["roughness_from"][b] == "mapping['brick']"
    assert float(mats["length_y_m"][b]) == pytest.approx(6e-3)
    _, cols, meta = read_csv(f"{stem}_map.csv")
    assert meta["frequency_hz"] == 28e9
    lit = np.isfinite(cols["flat_db"]) & np.isfinite(cols["rough_db"])
    d = cols["rough_minus_flat_db"]
    assert lit.sum() > 100 and np.all(np.isfinite(d[lit]))
    assert "rough − flat median" in p.stdout


def test_quiet_runs_the_command_with_bars_silenced(tmp_path, capsys, monkeypatch):
    """``emscatter radio --quiet``: the command body runs inside ``progress.silenced`` (the
    tables and sweeps it builds draw no bar in auto mode, even on a terminal); without it
    the auto policy is untouched."""
    from emscatter import progress
    from emscatter.cli import radio as cli_radio

    seen = []
    real = cli_radio._run

    def spy(a):
        seen.append(progress._SILENT.get())
        return real(a)

    monkeypatch.setattr(cli_radio, "_run", spy)
    out = tmp_path / "b.json"
    argv = ["--builtin-json", str(out), "--medium", "concrete=1e-3,8e-3", "--frequencies-ghz",
            "28", "--quick"]  # fmt: skip
    assert _main([*argv, "--quiet"], capsys)[0] == 0 and out.exists()
    assert _main(argv, capsys)[0] == 0
    assert seen == [True, False]
