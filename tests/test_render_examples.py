"""The scripts a user copies (``examples/render/``) and the demo's rendering step, run for real in
their quick modes, each in a fresh interpreter as a user would run them (Dr.Jit variants are
per process)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("mitsuba")

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = sorted((ROOT / "examples" / "render").glob("*.py"))


def _run(args, tmp_path):
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    proc = subprocess.run(
        [sys.executable, *args], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=600
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    return proc.stdout


def _check_png(path: Path):
    import matplotlib.image

    img = matplotlib.image.imread(path)
    assert img.ndim == 3 and img.shape[0] > 50 and img.shape[1] > 100
    assert np.ptp(img[..., :3]) > 0.3  # lit spheres on a darker background, not a blank frame


@pytest.mark.slow
@pytest.mark.parametrize("script", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_example_quick_mode(script, tmp_path):
    out = tmp_path / f"{script.stem}.png"
    stdout = _run([str(script), "--quick", "--out", str(out)], tmp_path)
    assert str(out) in stdout
    _check_png(out)


def test_examples_exist():
    names = {p.stem for p in EXAMPLES}
    assert {"roughness_rows", "slope_distributions", "spm_vs_kirchhoff", "metals_spectral"} <= names


def test_example_rejects_bad_options(tmp_path):
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    proc = subprocess.run(
        [sys.executable, str(EXAMPLES[0]), "--out", "figure.jpg"],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 2 and "--out must name a .png file" in proc.stderr


@pytest.mark.slow
def test_demo_render_step(tmp_path):
    """What ``emscatter demo`` runs in a subprocess: an RGL export Mitsuba loads, and a render."""
    stdout = _run(["-m", "emscatter.render.demo", str(tmp_path / "out"), "--quick"], tmp_path)
    paths = [Path(p) for p in json.loads(stdout.strip().splitlines()[-1])]
    bsdf, png, report = paths
    assert bsdf.suffix == ".bsdf" and png.suffix == ".png" and report.suffix == ".json"
    from emscatter.brdf.export_rgl import read_rgl

    fields = read_rgl(bsdf)
    assert fields["spectra"].shape[2] == 6  # the quick table's wavelengths
    _check_png(png)
    info = json.loads(report.read_text())
    assert info["variant"] == "llvm_ad_spectral" and info["timings"]["rgl_export_s"] < 10
