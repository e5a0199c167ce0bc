"""Issue 17: ``emscatter brdf --height-map FILE`` and ``emscatter curves --height-map FILE``,
run in-process on a small map generated from a known Gaussian roughness and written to netCDF."""

from __future__ import annotations

import json

import numpy as np
import pytest

import emscatter
from emscatter.brdf.export_npz import read_npz
from emscatter.cli import main
from emscatter.spectra import GaussianCorrelation
from emscatter.surfaces.heightmap import height_map, write_height_map

pytest.importorskip("SurfaceTopography")

SIGMA, ELL, DX = 0.1e-6, 1.0e-6, 0.1e-6
GRID = ["--n-theta", "8", "--n-phi", "9", "--out-of-range", "ignore", "--wavelengths-nm", "550"]


@pytest.fixture(scope="module")
def map_file(tmp_path_factory):
    rough = GaussianCorrelation(SIGMA, ELL)
    s = emscatter.generate_surface(rough, (512, 512), DX, rng=4)
    return write_height_map(
        height_map(s.heights, s.spacing), tmp_path_factory.mktemp("maps") / "m.nc"
    )


def _one_line_error(capsys, rc, *needles):
    err = capsys.readouterr().err
    assert rc == 2 and "Traceback" not in err, err
    assert len(err.strip().splitlines()) == 1, err
    for n in needles:
        assert n in err, (n, err)


def test_brdf_from_a_height_map_matches_the_parametric_table(map_file, tmp_path, capsys):
    """GO tables from the map and from the Gaussian it was drawn from: the measured slopes
    (≈ √2 σ/ℓ) give the same lobe, peak within 10 % (a 512² map: 51 ℓ a side, slope variance
    estimated to a few %), and the table records the measured surface."""
    out_m, out_p = tmp_path / "m.npz", tmp_path / "p.npz"
    go = ["--method", "go", "--material", "pec"]
    assert main(["brdf", str(out_m), "--height-map", str(map_file), *go, *GRID]) == 0
    assert main(["brdf", str(out_p), "--sigma", repr(SIGMA), "--length", repr(ELL),
                 *go, *GRID, "--anisotropic"]) == 0  # fmt: skip
    assert "wrote" in capsys.readouterr().out
    tm, tp = read_npz(out_m), read_npz(out_p)
    fm, fp = np.asarray(tm.values), np.asarray(tp.values)
    assert fm.shape == fp.shape and np.all(np.isfinite(fm))
    assert fm.max() == pytest.approx(fp.max(), rel=0.10)
    assert "measured" in json.dumps(tm.metadata, default=str)


def test_curves_from_a_height_map_records_it_and_replays(map_file, tmp_path, capsys):
    js = tmp_path / "c.json"
    argv = ["curves", "--height-map", str(map_file), "--eps", "3", "--wavelength", "5e-6",
            "--theta-i-deg", "30", "--theta-s-deg", "0:60:7", "--method", "spm",
            "--out-of-range", "ignore", "--json", str(js)]  # fmt: skip
    assert main(argv) == 0
    meta = json.loads(js.read_text())
    r = meta["inputs"]["roughness"]
    assert r["height_map"] == str(map_file) and r["detrend"] == "plane"
    assert r["sigma_m"] == pytest.approx(SIGMA, rel=0.1)
    assert "--height-map" in meta["command"] and "--sigma" not in meta["command"]
    first = np.asarray(meta["columns"]["sigma0_vv"], dtype=float)
    assert np.all(np.isfinite(first)) and np.all(first > 0)
    # SPM on the map against SPM on the Gaussian it was drawn from (kσ ≈ 0.13): within 1 dB
    ref = tmp_path / "ref.json"
    assert main(["curves", "--sigma", repr(SIGMA), "--length", repr(ELL), *argv[3:-1],
                 str(ref)]) == 0  # fmt: skip
    want = np.asarray(json.loads(ref.read_text())["columns"]["sigma0_vv"], dtype=float)
    assert np.abs(10 * np.log10(first / want)).max() < 1.0
    again = tmp_path / "again.json"
    assert main(["curves", "--from", str(js), "--json", str(again)]) == 0
    replay = np.asarray(json.loads(again.read_text())["columns"]["sigma0_vv"], dtype=float)
    np.testing.assert_allclose(replay, first, rtol=1e-12)
    capsys.readouterr()


@pytest.mark.parametrize("command", ["brdf", "curves"])
def test_height_map_errors_are_one_line_and_come_first(command, map_file, tmp_path, capsys):
    out = [str(tmp_path / "x.npz")] if command == "brdf" else ["--json", str(tmp_path / "x.json")]
    hm = ["--height-map", str(map_file)]
    rc = main([command, *out, *hm, "--sigma", "1e-7"])
    _one_line_error(capsys, rc, "--height-map", "--sigma", "mutually exclusive")
    rc = main([command, *out, "--detrend", "none"])
    _one_line_error(capsys, rc, "--detrend", "only with --height-map")
    rc = main([command, *out, "--height-map", str(tmp_path / "missing.x3p")])
    _one_line_error(capsys, rc, "missing.x3p", "does not exist")
    bad = tmp_path / "plain.txt"
    np.savetxt(bad, np.random.default_rng(0).normal(size=(20, 24)))
    rc = main([command, *out, "--height-map", str(bad)])
    _one_line_error(capsys, rc, "plain.txt")
    rc = main([command, *out, *hm, "--segments", "0"])
    _one_line_error(capsys, rc, "--segments")
    assert not list(tmp_path.glob("x.*"))  # nothing written by a refused command


# ----------------------------------------------------------------------------- issue 17 gaps
@pytest.fixture(scope="module")
def brick_files(tmp_path_factory):
    """A brick-like map (Gaussian σ = 1.2 mm, ℓ = 8 mm, 1 mm spacing, 256², the radio CLI
    test's) with 40 NaN holes, and a 16² map too small for any spectrum estimate."""
    d = tmp_path_factory.mktemp("gaps")
    s = emscatter.generate_surface(GaussianCorrelation(1.2e-3, 8e-3), (256, 256), 1e-3, rng=4)
    h = np.array(s.heights)
    h[100:104, 30:40] = np.nan
    holes = write_height_map(height_map(h, s.spacing, holes="mask"), d / "holes.nc", unit="mm")
    tiny = height_map(np.random.default_rng(3).normal(size=(16, 16)) * 1e-7, DX)
    return holes, write_height_map(tiny, d / "tiny.nc")


def _command(command, tmp_path):
    if command == "brdf":
        return ["brdf", str(tmp_path / "x.npz"), "--method", "go", "--material", "pec", *GRID]
    if command == "curves":
        return ["curves", "--eps", "3", "--wavelength", "5e-6", "--theta-i-deg", "30",
                "--method", "spm", "--json", str(tmp_path / "x.json")]  # fmt: skip
    return ["radio", "--scene", "simple_street_canyon", "--frequencies-ghz", "28",
            "--out", str(tmp_path / "x")]  # fmt: skip


@pytest.mark.parametrize("command", ["brdf", "curves", "radio"])
def test_a_map_too_small_for_a_spectrum_is_a_one_line_error(command, brick_files, tmp_path,
                                                             capsys):  # fmt: skip
    """A 16² map: 2 Welch segments of 16 samples need ≥ 32 per axis (MIN_MAP_SAMPLES); every
    command refuses it before any work, naming the file and what is wrong."""
    rc = main([*_command(command, tmp_path), "--height-map", str(brick_files[1])])
    _one_line_error(capsys, rc, "tiny.nc", "too small for a spectrum estimate", "(16, 16)",
                    "at least 32 samples")  # fmt: skip
    assert not list(tmp_path.glob("x*"))


@pytest.mark.parametrize("command", ["brdf", "curves", "radio"])
def test_nan_holes_are_rejected_by_default_naming_the_option(command, brick_files, tmp_path,
                                                              capsys):  # fmt: skip
    argv = [*_command(command, tmp_path), "--height-map", str(brick_files[0])]
    rc = main(argv)
    _one_line_error(capsys, rc, "holes.nc", "40 NaN holes", "--holes mask")
    rc = main([*argv, "--holes", "fill"])
    assert rc == 2 and "--holes" in capsys.readouterr().err
    assert not list(tmp_path.glob("x*"))


def test_holes_mask_gives_a_result_and_records_it(brick_files, tmp_path, capsys):
    """``--holes mask``: curves and brdf run on the valid samples and say so in their metadata;
    the replayed command keeps the choice; without ``--height-map`` it is an error."""
    path = str(brick_files[0])
    js = tmp_path / "c.json"
    argv = ["curves", "--height-map", path, "--holes", "mask", "--eps", "5+0.5j",
            "--frequency", "28e9", "--theta-i-deg", "30", "--theta-s-deg", "0:60:7",
            "--method", "spm", "--out-of-range", "ignore", "--json", str(js)]  # fmt: skip
    assert main(argv) == 0
    meta = json.loads(js.read_text())
    r = meta["inputs"]["roughness"]
    assert r["holes"] == "mask" and r["holes_count"] == 40
    assert "40 NaN holes masked" in r["description"]
    assert "--holes" in meta["command"] and "mask" in meta["command"]
    col = np.asarray(meta["columns"]["sigma0_vv"], dtype=float)
    assert np.all(np.isfinite(col)) and np.all(col > 0)
    again = tmp_path / "again.json"
    assert main(["curves", "--from", str(js), "--json", str(again)]) == 0
    replay = np.asarray(json.loads(again.read_text())["columns"]["sigma0_vv"], dtype=float)
    np.testing.assert_allclose(replay, col, rtol=1e-12)
    out = tmp_path / "m.npz"
    assert main(["brdf", str(out), "--height-map", path, "--holes", "mask", "--method", "go",
                 "--material", "pec", *GRID]) == 0  # fmt: skip
    assert "40 NaN holes masked" in json.dumps(read_npz(out).metadata, default=str)
    capsys.readouterr()
    rc = main(["curves", "--holes", "mask", "--sigma", "1e-7", "--length", "1e-6", "--eps", "3",
               "--wavelength", "5e-6", "--theta-i-deg", "30"])  # fmt: skip
    _one_line_error(capsys, rc, "--holes", "only with --height-map")


def test_radio_holes_mask_is_recorded(brick_files):
    """The radio path (``MaterialSpec.from_height_map``, what ``emscatter radio --holes mask``
    calls): the masked map's record names the policy and the count."""
    from emscatter.radio import MaterialSpec

    spec = MaterialSpec.from_height_map(brick_files[0], holes="mask", frequencies=[28e9])
    assert spec.map_record["holes"] == {"policy": "mask", "count": 40}
    assert spec.surface.sigma == pytest.approx(1.2e-3, rel=0.1)


# ------------------------------------------------------------------- issue 17: --slope-tail
def _curves_go(path, tmp_path, name, *extra):
    """GO backscatter of the brick map at 28 GHz, θi = 0°, 10°, …, 80°."""
    js = tmp_path / f"{name}.json"
    argv = ["curves", "--quantity", "backscatter", "--height-map", path, "--holes", "mask",
            *extra, "--eps", "5+0.5j", "--frequency", "28e9", "--theta-i-deg", "0:80:9",
            "--method", "go", "--out-of-range", "ignore", "--json", str(js)]  # fmt: skip
    assert main(argv) == 0
    return json.loads(js.read_text())


def test_slope_tail_is_passed_recorded_and_changes_go_at_grazing(brick_files, tmp_path, capsys):
    """``--slope-tail none`` vs the default ``gaussian``: the recorded choice (and the fitted
    tail's record) in curves' metadata and its replayed command. GO backscatter at θi comes
    from facets tilted by θi: near normal incidence (slopes ≲ the map's rms slope
    √2 σ/ℓ ≈ 0.21) the two agree within 0.5 dB; from θi = 40° (tan θi = 0.84 ≈ 4 rms slopes,
    beyond the well-sampled slopes) the Gaussian tail gives ≥ 10 dB more, and ``none`` is 0
    beyond the histogram grid (measured: −29.6 vs −44.2 dB at 40°, finite vs 0 from 50°)."""
    path = str(brick_files[0])
    gauss = _curves_go(path, tmp_path, "g")
    none = _curves_go(path, tmp_path, "n", "--slope-tail", "none")
    rg, rn = gauss["inputs"]["roughness"], none["inputs"]["roughness"]
    assert rg["slope_tail"] == "gaussian" and rg["slope_tail_fit"]["shape"] == "gaussian"
    assert rn["slope_tail"] == "none" and rn["slope_tail_fit"]["shape"] == "none"
    assert "slope tail none" in rn["description"] and "slope tail gaussian" in rg["description"]
    assert "--slope-tail none" in none["command"] and "--slope-tail gaussian" in gauss["command"]
    g = np.asarray(gauss["columns"]["sigma0_vv"], dtype=float)
    n = np.asarray(none["columns"]["sigma0_vv"], dtype=float)
    assert np.all(np.isfinite(g)) and np.all(g > 0) and np.all(np.isfinite(n)) and np.all(n >= 0)
    assert np.abs(10 * np.log10(n[:2] / g[:2])).max() < 0.5
    assert np.all(g[4:] > 10 * n[4:]) and np.all(n[5:] == 0)
    again = tmp_path / "again.json"
    assert main(["curves", "--from", str(tmp_path / "n.json"), "--json", str(again)]) == 0
    replay = np.asarray(json.loads(again.read_text())["columns"]["sigma0_vv"], dtype=float)
    np.testing.assert_allclose(replay, n, rtol=1e-12)
    capsys.readouterr()


@pytest.mark.parametrize("command", ["brdf", "curves", "radio"])
def test_slope_tail_is_accepted_and_checked_by_every_command(command, brick_files, tmp_path,
                                                              capsys):  # fmt: skip
    """Each command takes ``--slope-tail`` with a map: a bad value is a one-line error naming
    the option and the choices (exit 2, nothing written); without ``--height-map`` it is an
    error too."""
    argv = [*_command(command, tmp_path), "--height-map", str(brick_files[0]), "--holes", "mask"]
    rc = main([*argv, "--slope-tail", "lorentzian"])
    _one_line_error(capsys, rc, "--slope-tail", "lorentzian", "gaussian", "exponential")
    base = _command(command, tmp_path)
    rc = main([*base, "--slope-tail", "none", *(["--sigma", "1e-7"] if command != "radio"
                                               else [])])  # fmt: skip
    _one_line_error(capsys, rc, "--slope-tail", "only with --height-map")
    assert not list(tmp_path.glob("x*"))


def test_brdf_records_the_slope_tail(brick_files, tmp_path, capsys):
    """``emscatter brdf --slope-tail exponential``: the table's metadata names it."""
    out = tmp_path / "e.npz"
    assert main(["brdf", str(out), "--height-map", str(brick_files[0]), "--holes", "mask",
                 "--slope-tail", "exponential", "--method", "go", "--material", "pec",
                 *GRID]) == 0  # fmt: skip
    assert "slope tail exponential" in json.dumps(read_npz(out).metadata, default=str)
    capsys.readouterr()


def test_radio_slope_tail_is_passed_and_recorded(brick_files):
    """The radio path (``MaterialSpec.from_height_map``, what ``emscatter radio --slope-tail``
    calls) records the slope tail it measured with."""
    from emscatter.radio import MaterialSpec

    spec = MaterialSpec.from_height_map(brick_files[0], holes="mask", slope_tail="none")
    assert spec.map_record["slope_tail"] == "none"
    assert spec.surface.info["slope_tail"]["shape"] == "none"
    spec = MaterialSpec.from_height_map(brick_files[0], holes="mask")
    assert spec.map_record["slope_tail"] == "gaussian"
