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


# ------------------------------------------------------------------ .pbsdf (Mueller) output
def test_pbsdf_output_read_back(tmp_path, capsys):
    """``--format pbsdf``: a GO Mueller table of glass (ε = 2.25) at the five default
    wavelengths, read back by read_pbsdf. At the nodes θh = 0 (mirror pairs θi = θo = θd) the
    file holds the facet's Fresnel Mueller matrix in the s/p frame (x ⊥ the plane of
    reflection): M01/M00 = (Rs − Rp)/(Rs + Rp) (Born & Wolf §1.5), 1 at Brewster's angle
    (to float32 where θd is one of the table's 3° nodes, 1e-2 between them);
    and the file equals write_pbsdf of the same table built through the Python API."""
    from emscatter.brdf.export_pbsdf import pbsdf_mueller, read_pbsdf
    from emscatter.brdf.mueller import build_mueller_table
    from emscatter.fresnel import fresnel_cos
    from emscatter.spectra import GaussianCorrelation

    out = tmp_path / "glass.pbsdf"
    argv = ["brdf", str(out), "--material", "2.25", "--method", "go", "--n-theta", "30",
            "--n-phi", "46", "--out-of-range", "ignore", "--quiet"]  # fmt: skip
    assert main(argv) == 0
    assert "wrote" in capsys.readouterr().out
    f = read_pbsdf(out)
    assert f["wvls"].tolist() == [450, 500, 550, 600, 650]
    m = f["M"].astype(float)  # (φd, θd, θh, λ, 4, 4)
    td = f["theta_d"][0].astype(float)
    ok = (td > 0.05) & (td < 1.3)
    mirror = m[0, ok, 0, 2]  # θh = 0, 550 nm
    rh, rv = fresnel_cos(2.25, np.cos(td[ok]))
    rs, rp = np.abs(rh) ** 2, np.abs(rv) ** 2
    ratio, want = mirror[:, 0, 1] / mirror[:, 0, 0], (rs - rp) / (rs + rp)
    on_node = np.abs(np.remainder(np.degrees(td[ok]) + 1e-6, 3.0)) < 1e-4  # table's 3° nodes
    assert on_node.sum() >= 8
    np.testing.assert_allclose(ratio[on_node], want[on_node], rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(ratio, want, atol=1e-2)  # between nodes: the table's interpolant
    assert np.max(mirror[:, 0, 1] / mirror[:, 0, 0]) > 0.99  # fully s-polarized near Brewster
    # the command's table is the API's (defaults: σ = 0.15 µm, ℓ = 1 µm, Gaussian)
    mt = build_mueller_table(
        GaussianCorrelation(sigma=0.15e-6, length=1e-6, dimension=2), 2.25,
        np.array([450, 500, 550, 600, 650]) * 1e-9, method="go", resolution=(30, 46),
        out_of_range="ignore",
    )  # fmt: skip
    np.testing.assert_allclose(m, pbsdf_mueller(mt)["M"].astype(np.float32), rtol=1e-6)


@pytest.mark.parametrize(
    "argv, names",
    [
        ([], ["--method auto", "--method go or spm"]),
        (["--method", "po"], ["--method po", "physical optics", "go or spm"]),
        (["--method", "iem"], ["--method iem", "go or spm"]),
        (["--method", "go", "--wavelengths-nm", "450,550,650"],
         ["--wavelengths-nm 450,550,650", "exactly 5", "450,500,550,600,650"]),
        (["--method", "go", "--wavelengths-nm", "450,500.5,550,600,650"],
         ["--wavelengths-nm", "500.5", "whole"]),
        (["--method", "go", "--anisotropic"], ["--anisotropic", "isotropic"]),
        (["--method", "go", "--tol", "0.01"], ["--tol 0.01", "fixed grid"]),
        (["--method", "go", "--float32"], ["--float32", "float32 always"]),
        (["--method", "go", "--rgl-channels", "rgb"], ["--rgl-channels rgb", "RGL"]),
        (["--method", "go", "--format", "rgl"], ["--format rgl", ".pbsdf", ".bsdf"]),
    ],
)  # fmt: skip
def test_pbsdf_bad_inputs(tmp_path, capsys, argv, names):
    """Every refusal names the option, the value and what is allowed, in one line, before
    any table is built (no file written)."""
    out = tmp_path / "x.pbsdf"
    rc = main(["brdf", str(out), "--n-theta", "8", "--n-phi", "9", *argv])
    err = capsys.readouterr().err
    assert rc == 2 and "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    for name in names:
        assert name in err, (name, err)
    assert list(tmp_path.iterdir()) == []


def test_pbsdf_suffix_with_another_format(tmp_path, capsys):
    assert main(["brdf", str(tmp_path / "x.npz"), "--format", "pbsdf", *SMALL]) == 2
    err = capsys.readouterr().err
    assert "--format pbsdf" in err and "'" + str(tmp_path / "x.npz") + "'" in err
    assert ".pbsdf" in err and list(tmp_path.iterdir()) == []
