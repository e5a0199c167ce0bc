"""How many wavelengths a table needs for its colour (issue 21): brdf.colour.wavelengths_for."""

import numpy as np
import pytest

from emscatter.brdf.colour import COLOUR_TOL, colour_error, wavelengths_for
from emscatter.cli import main


@pytest.mark.parametrize("material", ["Au", "Ag"])
def test_count_meets_tol_and_one_fewer_does_not(material):
    lam = wavelengths_for(material, COLOUR_TOL)
    n = lam.size
    assert n > 2
    assert colour_error(material, lam) <= COLOUR_TOL
    assert colour_error(material, np.linspace(360e-9, 830e-9, n - 1)) > COLOUR_TOL


def test_gold_16_and_48_wavelengths_as_reported():
    # issue 21: 16-wavelength gold tables shift the colour by 1-2 % per channel, 48 by ~0.1 %
    e16 = colour_error("Au", np.linspace(360e-9, 830e-9, 16))
    e48 = colour_error("Au", np.linspace(360e-9, 830e-9, 48))
    assert 0.01 < e16 < 0.03 and e48 < 0.003
    assert wavelengths_for("Au", 0.02).size <= 16 < wavelengths_for("Au", 0.005).size


def test_flat_dielectric_needs_one():
    lam = wavelengths_for(2.25)
    assert lam.size == 1 and colour_error(2.25, lam) < 1e-12


@pytest.mark.parametrize("bad", [0, 1.5, -0.1, True, "x"])
def test_bad_tol(bad):
    with pytest.raises(ValueError, match="tol must be"):
        wavelengths_for("Au", bad)


def test_brdf_command_warns_with_the_count(tmp_path, capsys):
    args = ["brdf", str(tmp_path / "t.npz"), "--sigma", "1e-7", "--length", "1e-6",
            "--method", "go", "--n-theta", "8", "--n-phi", "16", "--material"]  # fmt: skip
    assert main([*args, "Au"]) == 0
    err = capsys.readouterr().err
    n = wavelengths_for("Au").size
    assert f"--wavelengths-nm 360:830:{n}" in err and "colour" in err
    assert main([*args, "2.25"]) == 0
    assert "colour" not in capsys.readouterr().err
