"""The README's rough − flat figure (validation/radio/rough_minus_flat_maps.py) in quick mode:
Sionna RT for real, in a subprocess (Dr.Jit variants are per process)."""

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
SCRIPT = ROOT / "validation" / "radio" / "rough_minus_flat_maps.py"
needs_sionna = pytest.mark.skipif(
    importlib.util.find_spec("sionna") is None, reason="Sionna RT is not installed"
)


def _run(args, timeout=600):
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(ROOT / "src"), os.environ.get("PYTHONPATH", "")]),
        "MPLBACKEND": "Agg",
    }
    return subprocess.run(
        [sys.executable, str(SCRIPT), *args], capture_output=True, text=True, env=env,
        timeout=timeout,
    )  # fmt: skip


def test_bad_arguments_name_the_value():
    proc = _run(["--samples", "10"])
    assert proc.returncode == 2
    assert "--samples" in proc.stderr and "10" in proc.stderr


@needs_sionna
def test_rough_minus_flat_maps_quick(tmp_path):
    proc = _run(["--quick", "--out", str(tmp_path)])
    assert proc.returncode == 0, (proc.stdout[-3000:], proc.stderr[-3000:])
    assert (tmp_path / "radio_rough_minus_flat_maps.png").stat().st_size > 20_000
    with open(tmp_path / "rough_minus_flat_maps.csv", newline="") as fh:
        rows = list(csv.DictReader(line for line in fh if not line.startswith("#")))
    assert [(r["scene"], float(r["frequency_ghz"])) for r in rows] == [
        (s, f) for s in ("simple_street_canyon", "room") for f in (3.5, 28.0, 140.0)
    ]
    # each scene made rough in one call: its own ITU media, all of them in band (no extrapolation)
    media = {r["scene"]: set(r["media"].split()) for r in rows}
    assert media["simple_street_canyon"] == {"brick", "concrete", "glass", "marble", "wood"}
    assert media["room"] == {"ceiling_board", "concrete", "glass", "plasterboard", "wood"}
    for r in rows:
        assert int(r["cells_lit"]) > 100
        assert all(np.isfinite(float(r[k])) for k in ("median_db", "p05_db", "p95_db"))
    spread = {(r["scene"], float(r["frequency_ghz"])): float(r["p95_db"]) - float(r["p05_db"])
              for r in rows}  # fmt: skip
    for s in ("simple_street_canyon", "room"):
        # 3.5 GHz: kσ ≤ 0.06 for every default roughness (σ ≤ 0.8 mm), so the Rayleigh loss
        # 4(kσ cosθ)² is ≤ 0.07 dB and the diffuse power is ~1e-3 of the specular: the maps agree
        assert spread[(s, 3.5)] < 0.5
        # roughness matters more as frequency rises (kσ grows 8× and 40×)
        assert spread[(s, 3.5)] < spread[(s, 28.0)] and spread[(s, 3.5)] < spread[(s, 140.0)]
