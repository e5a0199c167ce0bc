"""``emscatter farm brdf``: many tables from the command line, serially, on a 2-worker dask
LocalCluster and through a ``tcp://`` scheduler address — the same files, byte for byte, and
the same tables as :func:`emscatter.brdf.build_table`; bad input is one line, exit 2."""

from __future__ import annotations

import json
import socket
import time

import numpy as np
import pytest

from emscatter.brdf import build_table
from emscatter.brdf.export_npz import read_npz
from emscatter.cli import main
from emscatter.spectra import GaussianCorrelation

GRID = ["--method", "go", "--n-theta", "8", "--n-phi", "12", "--out-of-range", "ignore"]
VALUES = ["--sigma", "2e-7", "--sigma", "3.5e-7", "--material", "Au", "--material", "2.25",
          "--wavelengths-nm", "450,650"]  # fmt: skip
NAMES = ["Au-sigma2e-07-len1e-06", "eps2.25-sigma2e-07-len1e-06", "Au-sigma3.5e-07-len1e-06",
         "eps2.25-sigma3.5e-07-len1e-06"]  # fmt: skip


def _farm(out, *extra):
    return main(["farm", "brdf", "--out-dir", str(out), *VALUES, *GRID, *extra])


def _files(folder):
    return {p.name: p.read_bytes() for p in sorted(folder.glob("*.npz"))}


def test_serial_farm_writes_one_file_per_table_equal_to_build_table(tmp_path, capsys):
    assert _farm(tmp_path) == 0
    out = capsys.readouterr().out
    assert "wrote 4 tables" in out and "manifest" in out
    assert sorted(_files(tmp_path)) == sorted(f"{n}.npz" for n in NAMES)
    manifest = json.loads((tmp_path / "manifest.json").read_text())
    assert [t["name"] for t in manifest["tables"]] == NAMES  # roughness outermost
    assert manifest["tables"][1]["material"] == "2.25"
    got = read_npz(tmp_path / f"{NAMES[3]}.npz")
    ref = build_table(
        GaussianCorrelation(sigma=3.5e-7, length=1e-6, dimension=2), 2.25,
        np.array([450.0, 650.0]) * 1e-9, method="go", resolution=(8, 12), out_of_range="ignore",
    )  # fmt: skip
    assert got.values.tobytes() == ref.values.tobytes()
    assert np.array_equal(
        got.wavelengths, np.array([450.0, 650.0]) * 1e-9
    )  # nm × 1e-9, as emscatter brdf


def test_no_compress_writes_stored_npz_with_the_same_table(tmp_path, capsys):
    import zipfile

    packed, plain = tmp_path / "packed", tmp_path / "plain"
    assert _farm(packed) == 0 and _farm(plain, "--no-compress") == 0
    for name in NAMES:
        with zipfile.ZipFile(plain / f"{name}.npz") as z:  # stored, not deflated
            assert {i.compress_type for i in z.infolist()} == {zipfile.ZIP_STORED}
        a, b = read_npz(packed / f"{name}.npz"), read_npz(plain / f"{name}.npz")
        assert a.values.tobytes() == b.values.tobytes()


def test_local_cluster_and_tcp_scheduler_files_identical_to_serial(tmp_path, capsys):
    distributed = pytest.importorskip("dask.distributed")
    serial, local, remote = tmp_path / "serial", tmp_path / "local", tmp_path / "tcp"
    assert _farm(serial) == 0
    assert _farm(local, "--scheduler", "local", "--workers", "2") == 0
    assert "dask dashboard: http://" in capsys.readouterr().err
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
    ) as cluster:
        assert _farm(remote, "--scheduler", cluster.scheduler_address, "--batch", "1") == 0
    ref = _files(serial)
    assert len(ref) == 4
    assert _files(local) == ref  # byte for byte (the npz members carry no time stamp)
    assert _files(remote) == ref


def test_spec_file_toml_and_json_defaults_and_overrides(tmp_path):
    toml = tmp_path / "farm.toml"
    toml.write_text(
        'method = "go"\nn_theta = 8\nn_phi = 12\nout_of_range = "ignore"\n'
        "wavelengths_nm = [450, 650]\n\n"
        '[[table]]\nname = "gold"\nmaterial = "Au"\nsigma = 2e-7\n\n'
        '[[table]]\nname = "glass"\nmaterial = 2.25\nsigma = 3.5e-7\n'
        'wavelengths_nm = "500:600:3"\n',
        encoding="utf-8",
    )
    js = tmp_path / "farm.json"
    js.write_text(json.dumps([
        {"name": "gold", "material": "Au", "sigma": 2e-7, "wavelengths_nm": [450, 650]},
        {"name": "glass", "material": "2.25", "sigma": 3.5e-7, "wavelengths_nm": "500:600:3"},
    ]), encoding="utf-8")  # fmt: skip
    a, b = tmp_path / "a", tmp_path / "b"
    assert main(["farm", "brdf", "--out-dir", str(a), "--spec", str(toml)]) == 0
    assert main(["farm", "brdf", "--out-dir", str(b), "--spec", str(js), *GRID]) == 0
    assert _files(a) == _files(b) and sorted(_files(a)) == ["glass.npz", "gold.npz"]
    glass = read_npz(a / "glass.npz")
    assert np.allclose(glass.wavelengths, [500e-9, 550e-9, 600e-9])
    ref = build_table(
        GaussianCorrelation(sigma=3.5e-7, length=1e-6, dimension=2), 2.25,
        np.array([500.0, 550.0, 600.0]) * 1e-9, method="go", resolution=(8, 12),
        out_of_range="ignore",
    )  # fmt: skip
    assert glass.values.tobytes() == ref.values.tobytes()


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _spec(tmp_path, text, suffix=".toml"):
    path = tmp_path / f"s{suffix}"
    path.write_text(text, encoding="utf-8")
    return str(path)


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--scheduler", "mpi://host:1"], "argument --scheduler: expected 'local'"),
        (["--scheduler", "tcp://host"], "got 'tcp://host'"),
        (["--scheduler", "tcp://host:70000"], "port 1-65535"),
        (["--workers", "2"], "--workers applies with --scheduler local only"),
        (["--connect-timeout", "3"], "--connect-timeout applies with --scheduler tcp://"),
        (["--material", "Au", "--material", "Au"], "--material Au is given twice"),
        (["--sigma", "1e-7", "--sigma", "1e-07"], "--sigma 1e-07 is given twice"),
        (["--sigma", "-1e-7"], "argument --sigma: must be > 0 m"),
        (["--material", "unobtainium"], "field 'material' = 'unobtainium'"),
        (
            ["--spec", "SPEC:[[table]]\nname = 'a'\n[[table]]\nname = 'a'\n"],
            "table[1] name 'a' repeats table[0]'s",
        ),  # fmt: skip
        (["--spec", "SPEC:[[table]]\nsigmaa = 1e-7\n"], "table[0]: unknown key(s) ['sigmaa']"),
        (["--spec", "SPEC:[[table]]\nsigma = 'big'\n"], "table[0] key 'sigma' = 'big': must be"),
        (["--spec", "SPEC:[[table]]\nname = 'a/b'\n"], "key 'name' = 'a/b': must be a file name"),
        (["--spec", "SPEC:[[table]\n"], "not valid TOML"),
        (["--spec", "SPEC:sigma = 1e-7\n"], "no tables; list them under 'table'"),
        (["--spec", "missing.toml"], "--spec 'missing.toml': cannot read it"),
        (
            ["--spec", "SPEC:[[table]]\n", "--material", "Au", "--material", "Ag"],
            "--material is given 2 times with --spec",
        ),  # fmt: skip
    ],
)
def test_bad_input_is_one_line_exit_2(tmp_path, capsys, argv, message):
    argv = [_spec(tmp_path, a[5:]) if a.startswith("SPEC:") else a for a in argv]
    code = main(["farm", "brdf", "--out-dir", str(tmp_path / "out"), *argv])
    err = capsys.readouterr().err
    assert code == 2, err
    assert message in err and "Traceback" not in err
    assert err.count("\n") == 1 and err.startswith("emscatter farm brdf: error: ")
    assert not list(tmp_path.rglob("*.npz"))  # checked before any work


def test_unreachable_scheduler_one_line_exit_2_within_the_timeout(tmp_path, capsys):
    pytest.importorskip("dask.distributed")
    address = f"tcp://127.0.0.1:{_free_port()}"
    t0 = time.perf_counter()
    code = _farm(tmp_path, "--scheduler", address, "--connect-timeout", "1")
    err = capsys.readouterr().err
    assert code == 2 and time.perf_counter() - t0 < 20
    assert err.startswith(f"emscatter farm brdf: error: --scheduler {address}: no dask scheduler")
    assert err.count("\n") == 1 and not list(tmp_path.glob("*.npz"))


def test_skip_existing_leaves_built_tables_alone(tmp_path, capsys):
    assert _farm(tmp_path) == 0
    first = tmp_path / f"{NAMES[0]}.npz"
    first.write_bytes(b"kept")  # a marker: a rebuilt table would overwrite it
    (tmp_path / f"{NAMES[1]}.npz").unlink()
    capsys.readouterr()
    assert _farm(tmp_path, "--skip-existing") == 0
    assert "wrote 1 tables" in capsys.readouterr().out and first.read_bytes() == b"kept"
    assert len(_files(tmp_path)) == 4
    assert _farm(tmp_path) == 0 and first.read_bytes() != b"kept"  # without: rebuilt


def test_bar_auto_on_a_terminal_off_with_quiet(tmp_path, monkeypatch):
    import emscatter.brdf as brdf

    seen = []
    real = brdf.build_tables

    def spy(specs, **kw):  # records what the command asked for, then builds as usual
        seen.append(kw["progress"])
        return real(specs, **kw)

    monkeypatch.setattr(brdf, "build_tables", spy)
    assert _farm(tmp_path / "a") == 0
    assert _farm(tmp_path / "b", "--quiet") == 0
    assert seen == [None, False]  # default: drawn when stderr is a terminal; --quiet: never


def test_single_table_brdf_command_unchanged(tmp_path):
    argv = ["--material", "pec", "--wavelengths-nm", "550", *GRID]
    assert main(["brdf", str(tmp_path / "one.npz"), *argv]) == 0
    assert np.allclose(read_npz(tmp_path / "one.npz").wavelengths, [550e-9], rtol=1e-15)


def test_a_table_refused_on_a_worker_is_a_one_line_input_error(tmp_path, capsys):
    """--out-of-range raise: SPM far outside its range raises in the worker; the command
    names the table and exits 2 (bad input), as serially, not 1 (internal error)."""
    pytest.importorskip("dask.distributed")
    argv = ["--method", "spm", "--sigma", "5e-7", "--out-of-range", "raise", "--wavelengths-nm",
            "550", "--n-theta", "6", "--n-phi", "8", "--quiet"]  # fmt: skip
    for extra in ([], ["--scheduler", "local", "--workers", "1"]):
        code = main(["farm", "brdf", "--out-dir", str(tmp_path / str(len(extra))), *argv, *extra])
        err = capsys.readouterr().err
        assert code == 2, err
        line = err.strip().splitlines()[-1]
        assert line.startswith("emscatter farm brdf: error: ") and "outside its validity" in line
        if extra:
            assert "Au-sigma5e-07-len1e-06 failed" in line
