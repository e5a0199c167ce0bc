"""The command-line tool, run for real (in-process through main(), and one subprocess)."""

import csv
import json
import math
import re
import subprocess
import sys

import numpy as np
import pytest

from emscatter.cli import main
from emscatter.io import read_csv


def test_surface_command_draws_and_measures(tmp_path, capsys):
    png, js = tmp_path / "surface.png", tmp_path / "surface.json"
    rc = main(
        [
            "surface",
            "--kind",
            "fbm",
            "--hurst",
            "0.7",
            "--size",
            "256",
            "--png",
            str(png),
            "--json",
            str(js),
        ]
    )
    assert rc == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    stats = json.loads(js.read_text())
    assert stats["target_hurst"] == 0.7
    assert stats["schema"] == "emscatter.surface/1" and stats["inputs"]["size"] == 256
    assert abs(stats["measured_hurst_variogram"] - 0.7) < 0.1
    assert "measured_hurst_variogram" in capsys.readouterr().out


def test_curves_bistatic_writes_png_csv_json(tmp_path):
    out = {ext: tmp_path / f"c.{ext}" for ext in ("png", "csv", "json")}
    rc = main(
        [
            "curves",
            "--sigma",
            "0.02",
            "--length",
            "1",
            "--wavelength",
            "1",
            "--theta-s-deg",
            "0:89:10",
            "--png",
            str(out["png"]),
            "--csv",
            str(out["csv"]),
            "--json",
            str(out["json"]),
        ]
    )
    assert rc == 0
    header, cols, meta = read_csv(out["csv"])
    assert cols["theta_s_deg"].size == 10 and cols["sigma0_hh"][5] > 0
    assert meta["schema"] == "emscatter.curves/1"
    assert json.loads(out["json"].read_text())["result"]["method"] == "spm"


def test_curves_emissivity(tmp_path):
    csv_path = tmp_path / "e.csv"
    rc = main(
        [
            "curves",
            "--quantity",
            "emissivity",
            "--sigma",
            "0.02",
            "--wavelength",
            "1",
            "--theta-i-deg",
            "0:60:4",
            "--csv",
            str(csv_path),
        ]
    )
    assert rc == 0
    _, cols, _ = read_csv(csv_path)
    assert cols["theta_i_deg"].tolist() == [0, 20, 40, 60]
    assert np.all((0 < cols["e_h"]) & (cols["e_h"] < 1)) and np.all(cols["energy_ok"] == 1)


def test_bad_input_is_a_clear_error_and_writes_nothing(tmp_path, capsys):
    png = tmp_path / "bad.png"
    rc = main(["curves", "--sigma", "-1", "--png", str(png)])
    assert rc == 2
    assert "--sigma: must be > 0 m, got -1" in capsys.readouterr().err
    assert not png.exists() and not list(tmp_path.iterdir())
    assert main(["curves", "--eps", "seventeen"]) == 2
    assert "--eps: expected a complex permittivity" in capsys.readouterr().err


def test_console_script_runs(tmp_path):
    exe = [sys.executable, "-m", "emscatter.cli", "--version"]
    out = subprocess.run(exe, capture_output=True, text=True, check=True)
    assert out.stdout.startswith("emscatter ")


def test_atomic_writer_leaves_nothing_on_failure(tmp_path):
    from emscatter.io import atomic_path, write_json

    target = tmp_path / "x.json"
    with pytest.raises(RuntimeError), atomic_path(target) as tmp:
        tmp.write_text("half")
        raise RuntimeError("boom")
    assert not list(tmp_path.iterdir())
    with pytest.raises(ValueError):  # NaN is refused, not written as invalid JSON
        write_json(target, {"a": float("nan")})
    assert not list(tmp_path.iterdir())
    write_json(target, {"a": 1})
    assert json.loads(target.read_text()) == {"a": 1}
    assert oct(target.stat().st_mode & 0o777) != oct(0o600)


def test_demo_quick_writes_every_output(tmp_path):
    rc = main(["demo", "--out", str(tmp_path), "--quick"])
    assert rc == 0
    for name in (
        "figure_5_3.png",
        "figure_5_3.csv",
        "emissivity.png",
        "emissivity.csv",
        "methods_comparison.png",
        "surfaces/gaussian.png",
        "surfaces/stats.json",
    ):
        assert (tmp_path / name).stat().st_size > 0, name
    stats = json.loads((tmp_path / "surfaces" / "stats.json").read_text())
    assert abs(stats["fbm_H0.7"]["measured_hurst_periodogram"] - 0.7) < 0.1
    _, cols, meta = read_csv(tmp_path / "figure_5_3.csv")
    # the seed's Figure 5.3: the hh lobe peaks near the specular direction (45°)
    theta, hh = cols["theta_s_deg"], cols["sigma0_hh_sigma0.045"]
    assert 35 < theta[np.argmax(hh)] < 50
    assert meta["schema"] == "emscatter.demo/1" and meta["inputs"]["wavelength_m"] == 1.0
    _, cols, meta = read_csv(tmp_path / "emissivity.csv")
    assert np.all(cols["energy_ok_sigma0.045"] == 1) and meta["inputs"]["method"] == "spm"
    # the bridges' steps (each in its own interpreter): a BRDF export + render, the radio plate
    assert (tmp_path / "render" / "gold_go.bsdf").stat().st_size > 0
    assert (tmp_path / "render" / "render_demo.png").read_bytes()[:4] == b"\x89PNG"
    with open(tmp_path / "radio" / "radio_plate.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert rows and all(r["ok"] == "True" for r in rows)
    assert {r["kind"] for r in rows} == {"specular", "diffuse"}


def test_a_new_command_is_a_new_module(tmp_path, monkeypatch, capsys):
    """main() finds command modules with pkgutil: a file with register() is a command."""
    import emscatter.cli as cli

    (tmp_path / "hello.py").write_text(
        "from emscatter.cli.args import Number, add_command\n"
        "def register(sub):\n"
        "    p = add_command(sub, 'hello', help='say hello')\n"
        "    p.add_argument('--times', type=Number(low=0, high=10), default=1.0)\n"
        "    p.set_defaults(func=lambda a: print('hello ' * int(a.times)) or 0)\n"
    )
    monkeypatch.setattr(cli, "__path__", [*cli.__path__, str(tmp_path)])
    assert main(["hello", "--times", "2"]) == 0
    assert capsys.readouterr().out.strip() == "hello hello"
    assert main(["hello", "--times", "11"]) == 2
    assert "argument --times: must be in (0, 10), got 11" in capsys.readouterr().err
    names = [m.__name__.rsplit(".", 1)[1] for m in cli.command_modules()[0]]
    assert {"curves", "demo", "surface", "validate", "hello"} <= set(names)


@pytest.mark.parametrize(
    "quantity, angles, expected",
    [
        ("emissivity", "30", [30.0]),
        ("emissivity", "10,20,30", [10.0, 20.0, 30.0]),
        ("backscatter", "0:60:4", [0.0, 20.0, 40.0, 60.0]),
        ("backscatter", "25", [25.0]),
    ],
)
def test_every_angle_form_is_honoured(quantity, angles, expected, tmp_path):
    path = tmp_path / "x.csv"
    rc = main(["curves", "--quantity", quantity, "--theta-i-deg", angles, "--csv", str(path)])
    assert rc == 0
    _, cols, meta = read_csv(path)
    assert cols["theta_i_deg"].tolist() == expected
    assert meta["inputs"]["theta_i_deg"] == expected


def test_bistatic_computes_every_incidence_angle(tmp_path):
    path = tmp_path / "b.csv"
    argv = ["curves", "--theta-i-deg", "10:40:4", "--theta-s-deg", "0,30", "--csv", str(path)]
    assert main(argv) == 0
    _, cols, _ = read_csv(path)
    assert cols["theta_i_deg"].tolist() == [10, 10, 20, 20, 30, 30, 40, 40]
    assert cols["theta_s_deg"].tolist() == [0, 30] * 4
    import emscatter as em

    ref = em.bistatic(
        em.GaussianCorrelation(0.03, 1.0),
        17 + 2j,
        wavelength=1.0,
        theta_i=np.radians(40),
        theta_s=np.radians([0, 30]),
        phi_s=0.0,
    )
    np.testing.assert_allclose(cols["sigma0_hh"][-2:], ref.hh, rtol=1e-9)


def test_outputs_carry_every_input_and_reproduce_with_from(tmp_path, capsys):
    js, csv_path = tmp_path / "e.json", tmp_path / "e.csv"
    argv = [
        "curves",
        "--quantity",
        "emissivity",
        "--kind",
        "exponential",
        "--sigma",
        "0.004",
        "--length",
        "0.05",
        "--eps",
        "5+0.5i",
        "--frequency",
        "1.5e9",
        "--theta-i-deg",
        "0:60:3",
        "--json",
        str(js),
        "--csv",
        str(csv_path),
    ]
    assert main(argv) == 0
    data = json.loads(js.read_text())
    assert data["schema"] == "emscatter.curves/1" and data["emscatter_version"]
    inp = data["inputs"]
    assert inp["roughness"]["kind"] == "exponential" and inp["roughness"]["sigma_m"] == 0.004
    assert inp["eps"] == {"re": 5.0, "im": 0.5}
    assert inp["frequency_hz"] == 1.5e9 and abs(inp["wavelength_m"] - 0.19986163866666667) < 1e-12
    assert inp["method"] == "auto" and data["result"]["method"] == "spm"
    _, cols, meta = read_csv(csv_path)
    assert meta["inputs"] == inp
    for src, ext in ((js, "json"), (csv_path, "csv")):
        again = tmp_path / f"again_{ext}.json"
        png = tmp_path / f"again_{ext}.png"
        assert main(["curves", "--from", str(src), "--json", str(again), "--png", str(png)]) == 0
        re_data = json.loads(again.read_text())
        assert re_data["inputs"] == inp and re_data["columns"] == data["columns"]
        assert png.read_bytes()[:4] == b"\x89PNG"
    capsys.readouterr()


def test_help_shows_defaults_choices_and_only_real_commands(capsys):
    from emscatter.cli import command_modules

    assert main(["--help"]) == 0
    top = capsys.readouterr().out
    names = sorted(m.__name__.rsplit(".", 1)[1] for m in command_modules()[0])
    listed = re.findall(r"^    (\w+)\s", top, re.M)
    assert listed == names  # every command module, and nothing else
    for name in names:
        assert main([name, "--help"]) == 0
        text = capsys.readouterr().out
        assert "``" not in text and ":func:" not in text and ":class:" not in text
    assert main(["curves", "--help"]) == 0
    text = capsys.readouterr().out
    assert "(default: 0.03)" in text and "{bistatic,backscatter,emissivity}" in text
    assert "{warn,raise,nan,ignore}" in text and "auto" in text


def test_warnings_are_one_line_and_flagged_rows(tmp_path, capsys):
    path = tmp_path / "g.csv"
    argv = [
        "curves",
        "--quantity",
        "emissivity",
        "--method",
        "spm",
        "--eps",
        "pec",
        "--sigma",
        str(0.2 / (2 * math.pi)),  # issue 11's SPM over a PEC, kσ = 0.2, kℓ = 1 (λ = 1 m)
        "--length",
        str(1.0 / (2 * math.pi)),
        "--theta-i-deg",
        "60,85,88",
        "--csv",
        str(path),
    ]
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert (
        "emscatter curves: warning: method 'spm' at θi = 85°, 88°" in err and "Traceback" not in err
    )
    _, cols, _ = read_csv(path)
    assert cols["energy_ok"].tolist() == [1, 1, 0] and cols["valid"][1:].tolist() == [0, 0]
    assert cols["e_v"][2] < 0  # the data is shown as computed, flagged — never hidden


def test_emissivity_figure_shows_the_data_it_is_given():
    from emscatter.plots import emissivity_figure

    th = np.array([0.0, 45.0, 85.0, 88.0])
    eh, ev = np.array([0.6, 0.5, -0.27, -0.61]), np.array([0.65, 0.6, 0.1, -0.2])
    fig = emissivity_figure(th, {"go": (eh, ev)}, title="t", flagged=eh < 0)
    lo, hi = fig.axes[0].get_ylim()
    assert lo < -0.61 and hi >= 1.0
    assert any("energy not conserved" in t.get_text() for t in fig.axes[0].get_legend().get_texts())
    import matplotlib.pyplot as plt

    plt.close(fig)


def test_material_names_on_the_command_line_round_trip(tmp_path):
    js = tmp_path / "c.json"
    argv = [
        "curves",
        "--quantity",
        "backscatter",
        "--eps",
        "concrete",
        "--frequency",
        "3.5e9",
        "--sigma",
        "0.004",
        "--length",
        "0.05",
        "--theta-i-deg",
        "30",
        "--json",
        str(js),
    ]
    assert main(argv) == 0
    data = json.loads(js.read_text())
    assert data["inputs"]["eps"] == {"material": "concrete"}
    import emscatter as em
    from emscatter import materials

    eps = materials.itu("concrete").eps(frequency=3.5e9)
    ref = em.backscatter(
        em.GaussianCorrelation(0.004, 0.05), eps, frequency=3.5e9, theta_i=np.radians(30)
    )
    assert data["columns"]["sigma0_vv"][0] == pytest.approx(float(ref.vv), rel=1e-9)
    again = tmp_path / "again.json"
    assert main(["curves", "--from", str(js), "--json", str(again)]) == 0
    assert json.loads(again.read_text())["columns"] == data["columns"]
