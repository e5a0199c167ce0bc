"""``emscatter brdf``: builds and exports tables; clear one-line errors."""

from __future__ import annotations

import json

import numpy as np
import pytest

from emscatter.brdf.export_merl import read_merl
from emscatter.brdf.export_npz import read_npz
from emscatter.cli import main

SMALL = ["--method", "go", "--n-theta", "8", "--n-phi", "9", "--out-of-range", "ignore"]


def test_npz_with_fit(tmp_path, capsys):
    out = tmp_path / "gold.npz"
    fit = tmp_path / "fit.json"
    rc = main(
        [
            "brdf",
            str(out),
            "--material",
            "Au",
            "--sigma",
            "1.5e-7",
            "--length",
            "1e-6",
            "--wavelengths-nm",
            "450,550,650",
            "--fit",
            "beckmann",
            "--fit-json",
            str(fit),
            *SMALL,
        ]
    )
    assert rc == 0
    t = read_npz(out)
    assert t.values.shape == (3, 8, 8, 9) and t.metadata["material"]["name"] == "Au"
    np.testing.assert_allclose(t.wavelengths, [450e-9, 550e-9, 650e-9])
    text = capsys.readouterr().out
    assert "wrote" in text and "roughconductor" in text
    assert json.loads(fit.read_text())["alpha"] == pytest.approx(0.3, rel=1e-2)


def test_merl_output(tmp_path):
    out = tmp_path / "pec.binary"
    assert main(["brdf", str(out), "--material", "pec", "--wavelengths-nm", "550", *SMALL]) == 0
    m = read_merl(out)
    assert m.raw.shape == (3, 90, 90, 180)
    np.testing.assert_allclose(m.values[0], m.values[1], rtol=1e-15)  # grey: one wavelength


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--material", "unobtainium"], "unobtainium"),
        (["--material", "2-1j"], "Im"),
        (["--wavelengths-nm", "0.5"], "nm"),
        (["--wavelengths-nm", "650,450"], "increase"),
        (["--profile"], "2-D surface"),
        (["--sigma", "-1"], "sigma"),
        (["--n-theta", "1"], "n-theta"),
        (["--method", "nope"], "method"),
    ],
)
def test_errors_are_one_line(tmp_path, capsys, argv, message):
    rc = main(["brdf", str(tmp_path / "x.npz"), *SMALL, *argv])
    err = capsys.readouterr().err
    assert rc == 2 and message in err and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1
    assert not (tmp_path / "x.npz").exists()


def test_bad_output_suffix(tmp_path, capsys):
    assert main(["brdf", str(tmp_path / "x.txt"), *SMALL]) == 2
    assert ".npz" in capsys.readouterr().err
