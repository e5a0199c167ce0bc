"""Sionna RT runs for real (CPU, LLVM backend) with emscatter materials — each group of checks in
a fresh interpreter (tests/radio_worker.py), because Dr.Jit variants are per process and the
pytest-xdist workers also run Mitsuba tests."""

from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

# Never import sionna here: it would set this worker's Dr.Jit variant (Mitsuba tests share it).
if importlib.util.find_spec("sionna") is None:
    pytest.skip("Sionna RT is not installed", allow_module_level=True)

HERE = Path(__file__).parent
SRC = HERE.parent / "src"


def _run(*checks: str) -> dict:
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(SRC), os.environ.get("PYTHONPATH", "")]),
    }
    proc = subprocess.run(
        [sys.executable, str(HERE / "radio_worker.py"), *checks],
        capture_output=True, text=True, env=env, timeout=900,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-4000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


def _ok(results: dict, name: str) -> dict:
    out = results[name]
    assert "error" not in out, out["error"]
    assert out["warnings"] == [], out["warnings"]
    return out["result"]


# One test per subprocess: pytest-xdist may send tests of one file to different workers, and
# each group costs a Sionna start-up and kernel compilation.


def test_flat_equals_builtin_convention_and_errors():
    r = _run("flat_builtin", "slab_convention", "errors")
    # The bridge adds nothing where physics adds nothing: a flat emscatter material in the
    # furnished room (walls, floor, table, glass; reflections and refractions to depth 3) gives
    # Sionna's built-in RadioMaterial path by path within 1e-3 dB, same delays, same radio map.
    flat = _ok(r, "flat_builtin")
    assert flat["paths"] > 100
    assert flat["same_delays"]
    assert flat["max_path_db"] < 1e-3
    assert flat["map_same_support"] and flat["map_cells"] > 100
    assert flat["max_map_db"] < 1e-3
    # emscatter's slab (exp(-iωt)) conjugated equals Sionna's ITU slab (exp(+jωt)), float32
    assert _ok(r, "slab_convention")["max_abs_diff"] < 5e-5
    err = _ok(r, "errors")
    # out of band although no object uses the material (Sionna updates every material)
    assert err["out_of_band"].startswith("OutOfBandError: radio material 'idle-metal'")
    assert "1 GHz–100 GHz" in err["out_of_band"] and "extrapolate=True" in err["out_of_band"]
    assert "already used by another scene" in err["reuse"]
    assert "thickness must be a positive number" in err["thickness"]
    assert "conductivity must be >= 0" in err["conductivity"] and "-0.1 S/m" in err["conductivity"]
    assert "unknown material 'unobtainium'" in err["unknown"] and "concrete" in err["unknown"]
    assert "method must be 'auto' or one of" in err["method"] and "'sqm'" in err["method"]
    assert "NaN would reach the ray tracer" in err["policy"]
    assert "isotropic 2-D roughness" in err["anisotropic"]


def test_xml_scene_and_rough_materials_in_both_solvers():
    r = _run("xml_plugin", "rough_solvers")
    xml = _ok(r, "xml_plugin")
    assert xml["type"] == "EmscatterRadioMaterial"
    assert xml["surface_sigma"] == pytest.approx(4e-4) and xml["thickness"] == pytest.approx(0.2)
    assert xml["method"] == "spm"
    assert xml["num_paths"] > 100  # diffuse paths from the rough floor
    assert xml["paths_finite"] and xml["map_finite"] and xml["map_cells_lit"] > 50
    rough = _ok(r, "rough_solvers")
    assert rough["finite"] and rough["nonneg"] and rough["delays_finite"]
    assert rough["kinds"] == ["diffraction", "diffuse", "refraction", "specular"]
    assert all(0 < g < 1e-6 for g in rough["gain"])
    assert rough["map_lit"] > 50 and rough["map_max"] < 1e-6


def test_tables_only_for_used_materials_and_solved_frequencies():
    r = _ok(_run("evaluations"), "evaluations")
    f28, f140 = 28e9, 140e9
    step1, step2, step3 = ([tuple(x) for x in s] for s in r["log"])
    # loaded at Sionna's default 3.5 GHz, solved at 28 GHz: two used materials, one build each
    assert sorted(step1) == [("floor-mat", f28), ("wall-mat", f28)]
    # 140 GHz: one more build each (Sionna keeps frequencies in float32)
    new = step2[len(step1) :]
    assert sorted(n for n, _ in new) == ["floor-mat", "wall-mat"]
    assert all(f == pytest.approx(f140, rel=1e-7) for _, f in new)
    # back to 28 GHz: the slice is picked on the host, nothing is rebuilt
    assert step3 == step2
    assert r["used"]["unused-mat"] is False and r["unused_tables"] == []
    assert all(p > 0 for p in r["points"])
