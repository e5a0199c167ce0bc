"""``emscatter brdf --transmission`` (BRDF + OUT_btdf.npz + OUT_inner.npz of a rough dielectric)
and ``emscatter render --btdf/--inner`` (the emscatter_dielectric plugin): real tables, a real
small render in a subprocess (Dr.Jit variants are per process), one-line errors."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from emscatter.brdf.btdf_table import energy_budget
from emscatter.brdf.export_npz import read_btdf_npz, read_npz
from emscatter.cli import main

GLASS = [
    "--material", "2.25", "--sigma", "1.5e-7", "--length", "1e-6", "--wavelengths-nm", "550",
    "--method", "go", "--n-theta", "24", "--n-phi", "49", "--out-of-range", "ignore",
]  # fmt: skip


@pytest.fixture(scope="module")
def glass(tmp_path_factory):
    d = tmp_path_factory.mktemp("glass")
    assert main(["brdf", str(d / "glass.npz"), *GLASS, "--transmission", "--quiet"]) == 0
    return d


def test_brdf_transmission_writes_the_three_tables(glass):
    brdf = read_npz(glass / "glass.npz")
    bt = read_btdf_npz(glass / "glass_btdf.npz")
    inner = read_npz(glass / "glass_inner.npz")
    assert bt.eps[0] == pytest.approx(2.25) and bt.theta_i.size == 24
    # the pair within the energy budget: R + T ≤ 1 at every incidence node (cap_energy)
    b = energy_budget(brdf, bt)
    assert np.all(b["R"] + b["T"] <= 1 + 1e-9)
    # the inside table is the reflection of 1/ε: total internal reflection beyond 41.8°,
    # where the (lossless, GO) albedo is the whole incident power up to GO's shadowing loss
    per = inner.metadata["per_wavelength"][0]
    assert per["eps"][0] == pytest.approx(1 / 2.25)
    alb = inner.albedo().total[0]
    tir = np.degrees(inner.theta_i) > 50
    # α = 0.3: tilted facets still let some light out just past 41.8° (measured 0.76 at 52°,
    # 0.96 at 86°)
    assert np.all(alb[tir] > 0.7) and alb[-1] > 0.9 and np.all(alb <= 1 + 1e-9)
    assert np.all(np.diff(alb[tir]) > 0)
    assert not [p for p in glass.iterdir() if p.name.startswith(".")]  # no temp files left


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["--material", "Au"], "--transmission needs a lossless dielectric: --material Au"),
        (["--material", "2.25+0.1j"], "--transmission needs a lossless dielectric"),
        (["--anisotropic"], "isotropic"),
    ],
)
def test_brdf_transmission_bad_input(tmp_path, capsys, argv, needle):
    rc = main(["brdf", str(tmp_path / "x.npz"), *GLASS, *argv, "--transmission"])
    err = capsys.readouterr().err
    assert rc == 2 and needle in err and "Traceback" not in err, err
    assert len(err.strip().splitlines()) == 1
    assert not list(tmp_path.iterdir())


def test_brdf_transmission_needs_npz(tmp_path, capsys):
    rc = main(["brdf", str(tmp_path / "x.binary"), *GLASS, "--transmission"])
    err = capsys.readouterr().err
    assert rc == 2 and "--transmission writes .npz" in err


def _render(*args, cwd):
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    return subprocess.run(
        [sys.executable, "-m", "emscatter", "render", *map(str, args)],
        capture_output=True,
        text=True,
        cwd=cwd,
        env=env,
        timeout=600,
    )


@pytest.fixture(scope="module")
def mitsuba():
    return pytest.importorskip("mitsuba")


def test_render_dielectric_sphere(glass, mitsuba):
    args = ["glass.npz", "--btdf", "glass_btdf.npz", "--inner", "glass_inner.npz"]
    r = _render(*args, "--out", "g.png", "--width", "24", "--spp", "4", "--json", cwd=glass)
    assert r.returncode == 0, r.stderr
    s = json.loads(r.stdout.strip().splitlines()[-1])
    assert s["bsdf"]["kind"] == "dielectric plugin" and "inner" in s["bsdf"]
    assert np.all(np.isfinite(s["mean_rgb"])) and min(s["mean_rgb"]) > 0.01
    assert (glass / "g.png").stat().st_size > 0


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["glass.npz", "--inner", "glass_inner.npz"], "--inner"),
        (["glass.npz", "--btdf", "missing.npz"], "--btdf must name an existing .npz"),
        (["glass.npz", "--btdf", "glass_inner.npz"], "--btdf"),  # a BRDF, not a BTDF
        (["glass.npz", "--btdf", "glass_btdf.npz", "--via", "measured"], "measured"),
        (["glass.npz", "--btdf", "glass_btdf.npz", "--variant", "scalar_rgb"], "llvm_*"),
    ],
)
def test_render_dielectric_bad_input(glass, mitsuba, args, needle):
    r = _render(*args, "--out", "bad.png", cwd=glass)
    assert r.returncode == 2, (r.returncode, r.stderr)
    assert "Traceback" not in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert needle in r.stderr, r.stderr
    assert not (glass / "bad.png").exists()
