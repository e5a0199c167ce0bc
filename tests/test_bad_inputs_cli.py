"""Bad command-line input (issue 23): every command checks all of its inputs and every output
path *before* computing, an option that does not apply is an error, and the error is one line
(exit status 2) naming the option, the value and what is allowed — with no file written.

The commands run in-process through ``emscatter.cli.main`` in an empty folder; the folder is
compared before and after, so "no output file was created" is checked for every case. Paths
under ``/proc`` and ``/sys`` stand for folders that take no new files even for root (where a
``chmod``-ed folder would still be writable); those cases need Linux.
"""

import os
import subprocess
import sys
from pathlib import Path

import pytest

from emscatter.cli import main

LINUX = sys.platform.startswith("linux") and Path("/proc/self").exists()
needs_linux = pytest.mark.skipif(not LINUX, reason="uses /proc and /sys as unwritable folders")


def _tree(root: Path) -> list[str]:
    return sorted(str(p.relative_to(root)) for p in root.rglob("*"))


@pytest.fixture
def workdir(tmp_path, monkeypatch):
    """An empty working folder with one file (``afile``) and one folder (``afolder``)."""
    (tmp_path / "afile").write_text("not a folder")
    (tmp_path / "afolder").mkdir()
    monkeypatch.chdir(tmp_path)
    return tmp_path


def _run(argv, workdir, capsys):
    before = _tree(workdir)
    rc = main(argv)
    err = capsys.readouterr().err
    assert _tree(workdir) == before, f"{argv} wrote {set(_tree(workdir)) - set(before)}"
    return rc, err


def _one_error_line(err: str) -> None:
    assert "Traceback" not in err, err
    errors = [line for line in err.splitlines() if ": error: " in line]
    assert len(errors) == 1, err


# (argv, fragments): each fragment list names the option, the value given and what is allowed.
CASES = [
    # ------------------------------------------------ brdf: options that do not apply
    (["brdf", "x.npz", "--format", "rgl"], ["--format rgl", "'x.npz'", ".bsdf"]),
    (["brdf", "x.binary", "--format", "npz"], ["--format npz", "'x.binary'", ".npz"]),
    (["brdf", "x.bsdf", "--format", "merl"], ["--format merl", "'x.bsdf'", ".binary"]),
    (["brdf", "x.npz", "--fit-json", "f.json"], ["--fit-json f.json", "only with --fit"]),
    (
        ["brdf", "x.npz", "--rgl-channels", "rgb"],
        ["--rgl-channels", "rgb", "to RGL .bsdf output only"],
    ),
    (
        ["brdf", "x.bsdf", "--format", "rgl", "--tol", "0.05", "--n-theta", "20"],
        ["--n-theta 20", "fixed grid only", "--tol"],
    ),
    (["brdf", "x.npz", "--tol", "0.05", "--n-phi", "30"], ["--n-phi 30", "fixed grid only"]),
    (["brdf", "x.npz", "--profile"], ["--profile", "a BRDF table needs a 2-D surface"]),
    (
        ["brdf", "x.npz", "--kind", "gaussian", "--hurst", "0.4"],
        ["--hurst 0.4", "--kind power-law only"],
    ),
    # ---------------------------------------------------------------- brdf: values
    (
        ["brdf", "x.npz", "--material", "unobtainium"],
        ["--material unobtainium", "unknown material 'unobtainium'", "ITU-R P.2040"],
    ),
    (
        ["brdf", "x.npz", "--material", "concrete"],
        ["--material concrete", "450 nm", "1 GHz–100 GHz"],
    ),
    (["brdf", "x.npz", "--material", "17-2j"], ["--material", "'17-2j'", "give 17+2j"]),
    (["brdf", "x.npz", "--method", "ipm"], ["--method", "'ipm'", "'go'", "'auto'"]),
    (
        ["brdf", "x.npz", "--wavelengths-nm", "0.55"],
        ["'0.55'", "10 nm – 1 m", "the unit here is nm"],
    ),
    (["brdf", "x.npz", "--wavelengths-nm", "650,550"], ["'650,550'", "must increase"]),
    (["brdf", "x.npz", "--n-theta", "1"], ["--n-theta", "got 1", "[2, 2000]"]),
    (["brdf", "x.npz", "--sigma", "0"], ["--sigma", "got 0", "> 0 m"]),
    (["brdf", "x.npz", "--tol", "1.5"], ["--tol", "got 1.5", "(0, 1)"]),
    (["brdf", "x.npz", "--energy", "clip"], ["--energy", "'clip'", "'rescale'"]),
    # ---------------------------------------------------------------- brdf: output paths
    (["brdf", "x.txt"], ["'x.txt'", "unknown extension '.txt'", ".npz, .binary, .bsdf"]),
    (["brdf", "afolder"], ["'afolder'", "it is a folder", "give a file name"]),
    (["brdf", "afile/x.npz"], ["'afile/x.npz'", "'afile' is a file, not a folder"]),
    (
        ["brdf", "x.npz", "--fit", "beckmann", "--fit-json", "f.txt"],
        ["--fit-json", "'f.txt'", "use one of .json"],
    ),
    (
        ["brdf", "x.npz", "--fit", "ggx", "--fit-json", "afile/f.json"],
        ["--fit-json", "'afile/f.json'", "is a file, not a folder"],
    ),
    # ---------------------------------------------------------------- curves
    (["curves", "--csv", "x.txt"], ["--csv", "'x.txt'", "use one of .csv"]),
    (["curves", "--json", "x.csv"], ["--json", "'x.csv'", "use one of .json"]),
    (["curves", "--png", "x.jpg"], ["--png", "'x.jpg'", ".png, .pdf, .svg"]),
    (["curves", "--csv", "afolder"], ["--csv", "'afolder'", "it is a folder"]),
    (["curves", "--json", "afile/deeper/x.json"], ["--json", "'afile' is a file"]),
    (
        ["curves", "--eps", "concrete", "--frequency", "5e8"],
        ["--eps concrete", "500 MHz", "1 GHz–100 GHz"],
    ),
    (["curves", "--eps", "concrte"], ["--eps", "'concrte'", "did you mean 'concrete'"]),
    (["curves", "--eps", "17-2j"], ["--eps", "'17-2j'", "Im < 0", "give 17+2j"]),
    (["curves", "--eps", "0"], ["--eps", "got 0", "nonzero"]),
    (["curves", "--eps", "inf"], ["--eps", "'inf'", "finite"]),
    (["curves", "--frequency", "28"], ["--frequency", "got 28", "did you mean 28 GHz"]),
    (["curves", "--wavelength", "5000"], ["--wavelength", "got 5000", "[1e-08, 1000] m"]),
    (
        ["curves", "--frequency", "1e9", "--wavelength", "0.3"],
        ["--wavelength", "not allowed with argument --frequency"],
    ),
    (
        ["curves", "--quantity", "backscatter", "--theta-s-deg", "30"],
        ["--theta-s-deg", "30", "--quantity bistatic only"],
    ),
    # ---------------------------------------------------------------- surface
    (["surface", "--kind", "gaussian", "--hurst", "0.3"], ["--hurst 0.3", "fbm or power-law"]),
    (["surface", "--length", "3"], ["--length 3", "not --kind fbm"]),
    (["surface", "--json", "s.txt"], ["--json", "'s.txt'", "use one of .json"]),
    (["surface", "--png", "afolder"], ["--png", "'afolder'", "it is a folder"]),
    # ---------------------------------------------------------------- demo, validate, bench
    (["demo", "--out", "afile"], ["--out", "'afile'", "not a folder; give a folder path"]),
    (["demo", "--quick", "--out", "afile/sub"], ["--out", "'afile/sub'", "is a file"]),
    (["validate", "--out", "afile"], ["--out", "'afile'", "not a folder"]),
    (["bench", "fortran"], ["unknown benchmark(s) ['fortran']", "kernels"]),
    (["bench", "--list", "--quick"], ["--quick", "not to --list"]),
    (["bench", "--list", "kernels"], ["--list", "kernels", "no benchmark names"]),
]

# Folders that take no new file even for root (os.access says they do).
LINUX_CASES = [
    (["curves", "--csv", "/proc/nonexistent/x.csv"], ["--csv", "/proc", "does not take new files"]),
    (["curves", "--png", "/sys/x.png"], ["--png", "'/sys/x.png'", "does not take new files"]),
    (["brdf", "/proc/x.npz"], ["'/proc/x.npz'", "does not take new files"]),
    (
        ["brdf", "x.npz", "--fit", "beckmann", "--fit-json", "/proc/x/f.json"],
        ["--fit-json", "'/proc/x/f.json'", "does not take new files"],
    ),
    (["surface", "--json", "/proc/x/s.json"], ["--json", "/proc", "does not take new files"]),
    (["demo", "--out", "/proc/x"], ["--out", "'/proc/x'", "does not take new files"]),
    (["validate", "--out", "/sys/x"], ["--out", "'/sys/x'", "does not take new files"]),
    (["radio", "--out", "/proc/x"], ["--out", "'/proc/x'", "does not take new files"]),
]


def _id(case):
    return " ".join(case[0])


@pytest.mark.parametrize("argv, fragments", CASES, ids=[_id(c) for c in CASES])
def test_bad_cli_input_is_one_line_and_writes_nothing(argv, fragments, workdir, capsys):
    rc, err = _run(argv, workdir, capsys)
    assert rc == 2, err
    for frag in fragments:
        assert frag in err, (frag, err)
    _one_error_line(err)


@needs_linux
@pytest.mark.parametrize("argv, fragments", LINUX_CASES, ids=[_id(c) for c in LINUX_CASES])
def test_unwritable_output_is_refused_before_computing(argv, fragments, workdir, capsys):
    rc, err = _run(argv, workdir, capsys)
    assert rc == 2, err
    for frag in fragments:
        assert frag in err, (frag, err)
    _one_error_line(err)


@pytest.mark.skipif(
    not hasattr(os, "geteuid") or os.geteuid() == 0, reason="root writes into 0o555 folders"
)
def test_read_only_folder_is_refused(workdir, capsys):
    ro = workdir / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    try:
        rc, err = _run(["curves", "--csv", "ro/x.csv"], workdir, capsys)
    finally:
        ro.chmod(0o755)
    assert rc == 2 and "--csv" in err and "'ro/x.csv'" in err and "not writable" in err, err


def test_the_probe_leaves_nothing_behind(workdir):
    """Checking a path writes a probe file and removes it: the folder stays as it was."""
    from emscatter.cli.paths import check_output_path

    before = _tree(workdir)
    assert check_output_path(workdir / "new" / "deeper" / "x.csv", (".csv",)) is None
    assert check_output_path(workdir / "out", folder=True) is None
    assert _tree(workdir) == before


def test_a_format_that_matches_is_accepted():
    from emscatter.cli.brdf import FORMATS
    from emscatter.cli.paths import check_format

    assert check_format(Path("t.BSDF"), None, FORMATS, "output") == "rgl"
    assert check_format(Path("t.npz"), "npz", FORMATS, "output") == "npz"


@needs_linux
def test_brdf_fit_json_refused_end_to_end_before_the_table(tmp_path):
    """The issue's case through a real process: the .npz must not be written first."""
    argv = ["brdf", "x.npz", "--fit", "beckmann", "--fit-json", "/proc/x/f.json"]
    out = subprocess.run(
        [sys.executable, "-m", "emscatter", *argv],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=tmp_path,
        env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)},
    )
    assert out.returncode == 2, out.stderr
    assert "--fit-json" in out.stderr and "/proc/x/f.json" in out.stderr
    assert "Traceback" not in out.stderr and len(out.stderr.strip().splitlines()) == 1
    assert list(tmp_path.iterdir()) == []
