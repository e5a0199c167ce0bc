"""``emscatter.brdf.build_tables``: many tables serially, on a process pool and on a dask
LocalCluster, bit-identical; every spec checked before any work; the build's progress bar."""

from __future__ import annotations

import concurrent.futures as cf
import re
import warnings

import numpy as np
import pytest

from emscatter.brdf import build_table, build_tables, farm, table_specs
from emscatter.cli import main
from emscatter.solvers.select import ValidityWarning
from emscatter.spectra import GaussianCorrelation

GRID = {"method": "go", "resolution": (12, 16)}


def _surfaces():
    return [GaussianCorrelation(sigma=s * 1e-6, length=1e-6, dimension=2) for s in (0.2, 0.35)]


def _specs(**kw):
    return table_specs(_surfaces(), ["Au", 2.25], [[450e-9, 650e-9], [550e-9]], **GRID, **kw)


def _same(a, b):
    assert a.values.dtype == b.values.dtype and a.values.tobytes() == b.values.tobytes()
    assert np.array_equal(a.coherent, b.coherent)
    assert a.metadata["per_wavelength"] == b.metadata["per_wavelength"]


def test_serial_farm_equals_build_table_in_order():
    specs = _specs(out_of_range="ignore")
    assert len(specs) == 8 and specs[0]["name"] == "s0-Au-w0"
    tables = build_tables(specs, progress=False)
    for spec, table in zip(specs, tables, strict=True):
        kw = {k: v for k, v in spec.items() if k != "name"}
        _same(table, build_table(**kw))
        assert np.array_equal(table.wavelengths, spec["wavelengths"])


def test_process_pool_bit_identical_to_serial():
    specs = _specs(out_of_range="ignore", dtype="float32")
    serial = build_tables(specs, progress=False)
    with cf.ProcessPoolExecutor(2) as pool:
        parallel = build_tables(specs, client=pool, progress=False)
    for a, b in zip(serial, parallel, strict=True):
        _same(a, b)


def test_dask_local_cluster_bit_identical_to_serial():
    pytest.importorskip("dask.distributed")
    specs = _specs(out_of_range="ignore")[:4]
    serial = build_tables(specs, progress=False)
    parallel = build_tables(specs, client="local", n_workers=2, progress=False)
    for a, b in zip(serial, parallel, strict=True):
        _same(a, b)


def test_worker_warnings_come_back_once_with_the_spec_name():
    specs = _specs()[:2]  # out_of_range="warn": GO's stationary-phase check fails at grazing θ
    with cf.ProcessPoolExecutor(2) as pool, warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        build_tables(specs, client=pool, progress=False)
    texts = [str(w.message) for w in caught if issubclass(w.category, ValidityWarning)]
    assert texts and all(t.startswith(("s0-Au-w0: ", "s0-Au-w1: ")) for t in texts)
    assert len(texts) == len(set(texts))


class _Recording(cf.ThreadPoolExecutor):
    """A real executor that counts what it is given (a bad spec must stop before any)."""

    submitted = 0

    def submit(self, *a, **k):
        type(self).submitted += 1
        return super().submit(*a, **k)


@pytest.mark.parametrize(
    "change, message",
    [
        ({"wavelengths": None}, "lacks the field(s) ['wavelengths']"),
        ({"colour": "red"}, "unknown field(s) ['colour']"),
        ({"material": "unobtainium"}, "field 'material' = 'unobtainium'"),
        ({"method": "nope"}, "field 'method' must be one of"),
        ({"wavelengths": [650e-9, 450e-9]}, "field 'wavelengths'"),
        ({"surface": GaussianCorrelation(sigma=1e-7, length=1e-6, dimension=1)}, "field 'surface'"),
        ({"options": ["threads"]}, "field 'options' must be a dict"),
    ],
)
def test_bad_spec_names_the_field_before_any_work(change, message):
    specs = _specs()
    bad = {**specs[5], **change}
    if change.get("wavelengths", 0) is None:
        del bad["wavelengths"]
    specs[5] = bad
    _Recording.submitted = 0
    with _Recording(1) as pool, pytest.raises(ValueError) as err:
        build_tables(specs, client=pool, progress=False)
    assert message in str(err.value) and "specs[5]" in str(err.value)
    assert _Recording.submitted == 0


@pytest.mark.parametrize(
    "kw, message",
    [
        ({"client": "mpi://x"}, "client must be None (serial), 'local', a scheduler address"),
        ({"threads": 0}, "threads must be a positive integer"),
        ({"n_workers": -1}, "n_workers must be a positive integer"),
        ({"progress": "yes"}, "progress must be True, False or None"),
    ],
)
def test_bad_arguments(kw, message):
    with pytest.raises(ValueError, match=re.escape(message)):
        build_tables(_specs()[:1], **kw)


def test_threads_cap_reaches_solvers_that_take_it():
    go = farm._cap_threads({"method": "go"}, 1, in_worker=False)
    assert go["threads"] == 1
    assert "threads" not in farm._cap_threads({"method": "spm"}, 1, in_worker=False)
    assert "threads" not in farm._cap_threads({"method": "auto"}, 1, in_worker=False)
    assert farm._cap_threads({"method": "go", "threads": 4}, 1, in_worker=False)["threads"] == 4


def test_build_table_bar_on_request_quiet_off_a_terminal(capsys):
    rough = _surfaces()[0]
    build_table(rough, "Au", [450e-9, 550e-9], **GRID, out_of_range="ignore", progress=True)
    assert "BRDF table" in capsys.readouterr().err
    build_table(rough, "Au", [450e-9, 550e-9], **GRID, out_of_range="ignore")  # stderr: no tty
    assert "BRDF table" not in capsys.readouterr().err
    build_tables(_specs(out_of_range="ignore")[:2], progress=True)
    err = capsys.readouterr().err
    assert "BRDF tables" in err and "/2" in err


def test_cli_quiet(tmp_path, monkeypatch):
    from emscatter.brdf import build

    seen = []
    real = build.build_progress

    def spy(n, progress=None):  # records what the command asked for, then draws as usual
        seen.append(progress)
        return real(n, progress)

    monkeypatch.setattr(build, "build_progress", spy)
    argv = ["--material", "pec", "--wavelengths-nm", "550", "--method", "go"]
    argv += ["--n-theta", "8", "--n-phi", "12", "--out-of-range", "ignore"]
    assert main(["brdf", str(tmp_path / "a.npz"), *argv, "--quiet"]) == 0
    assert main(["brdf", str(tmp_path / "b.npz"), *argv]) == 0
    assert seen == [False, None]  # --quiet: never; default: only on a terminal


@pytest.mark.parametrize("batch", [1, 3, None])
def test_batched_tasks_give_the_serial_tables_in_order(batch):
    specs = _specs(out_of_range="ignore")
    serial = build_tables(specs, progress=False)
    with cf.ProcessPoolExecutor(2) as pool:
        parallel = build_tables(specs, client=pool, batch=batch, progress=False)
    for a, b in zip(serial, parallel, strict=True):
        _same(a, b)


def test_auto_batch_is_about_four_tasks_per_worker():
    assert [len(r) for r in farm._batches(64, None, 2)] == [8] * 8
    assert [len(r) for r in farm._batches(10, None, None)] == [1] * 10  # workers unknown
    assert [len(r) for r in farm._batches(10, 4, 2)] == [4, 4, 2]
    with cf.ProcessPoolExecutor(3) as pool:
        assert farm._workers_of(pool, pool, None, 1) == 3


def test_out_dir_workers_write_the_files_and_paths_come_back(tmp_path):
    from emscatter.brdf.export_npz import read_npz

    specs = _specs(out_of_range="ignore")[:4]
    serial = build_tables(specs, progress=False)
    with cf.ProcessPoolExecutor(2) as pool:
        paths = build_tables(specs, client=pool, out_dir=tmp_path, batch=2, progress=False)
    assert [p.name for p in paths] == [f"{s['name']}.npz" for s in specs]
    for table, path in zip(serial, paths, strict=True):
        assert path.parent == tmp_path
        _same(table, read_npz(path))
    again = build_tables(specs[:1], out_dir=tmp_path, progress=False)  # serial: same file
    _same(serial[0], read_npz(again[0]))
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(p.name for p in paths)


@pytest.mark.parametrize(
    "kw, message",
    [
        ({"batch": 0}, "batch must be a positive integer or None, got 0"),
        ({"batch": 2.5}, "batch must be a positive integer or None, got 2.5"),
        ({"out_dir": "/nonexistent-emscatter-folder"}, "is not an existing folder"),
        ({"out_dir": 3}, "out_dir must be a folder path or None, got 3"),
    ],
)
def test_bad_batch_and_out_dir(kw, message):
    with pytest.raises(ValueError, match=message.replace("(", r"\(")):
        build_tables(_specs()[:1], **kw)


def test_out_dir_compress_false_stores_the_arrays_and_reads_back_identical(tmp_path):
    import zipfile

    from emscatter.brdf.export_npz import read_npz

    specs = _specs(out_of_range="ignore")[:4]
    serial = build_tables(specs, progress=False)
    stored, packed = tmp_path / "stored", tmp_path / "packed"
    stored.mkdir()
    packed.mkdir()
    with cf.ProcessPoolExecutor(2) as pool:
        paths = build_tables(
            specs, client=pool, out_dir=stored, compress=False, batch=2, progress=False
        )
    deflated = build_tables(specs[:1], out_dir=packed, progress=False)[0]  # the default
    for table, path in zip(serial, paths, strict=True):
        _same(table, read_npz(path))
        with zipfile.ZipFile(path) as z:
            assert {i.compress_type for i in z.infolist()} == {zipfile.ZIP_STORED}
    with zipfile.ZipFile(deflated) as z:
        assert zipfile.ZIP_DEFLATED in {i.compress_type for i in z.infolist()}
    _same(read_npz(deflated), read_npz(paths[0]))  # same values, stored or deflated


@pytest.mark.parametrize(
    "kw, message",
    [
        ({"compress": "no"}, "compress must be True or False, got 'no'"),
        ({"compress": 0}, "compress must be True or False, got 0"),
        ({"compress": False}, "compress=False applies to the files out_dir receives"),
    ],
)
def test_bad_compress_names_it(kw, message):
    with pytest.raises(ValueError, match=message):
        build_tables(_specs(out_of_range="ignore")[:1], progress=False, **kw)


def test_out_dir_needs_unique_file_names(tmp_path):
    specs = _specs(out_of_range="ignore")[:2]
    specs[1] = {**specs[1], "name": specs[0]["name"]}
    match = r"specs\[1\] field 'name' = 's0-Au-w0' repeats specs\[0\]"
    with pytest.raises(ValueError, match=match):
        build_tables(specs, out_dir=tmp_path, progress=False)
    specs[1] = {**specs[1], "name": "a/b"}
    with pytest.raises(ValueError, match=r"specs\[1\] field 'name' = 'a/b'"):
        build_tables(specs, out_dir=tmp_path, progress=False)
    assert not list(tmp_path.iterdir())  # checked before any work


def test_dask_batched_out_dir_bit_identical_to_serial(tmp_path):
    pytest.importorskip("dask.distributed")
    from emscatter.brdf.export_npz import read_npz

    specs = _specs(out_of_range="ignore")[:4]
    serial = build_tables(specs, progress=False)
    paths = build_tables(specs, client="local", n_workers=2, out_dir=tmp_path, progress=False)
    for a, p in zip(serial, paths, strict=True):
        _same(a, read_npz(p))


def test_local_cluster_dashboard_on_a_free_port_not_8787():
    """The farm's LocalCluster (emscatter.parallel) takes a free dashboard port: with 8787
    taken, no "Port 8787 is already in use" warning and the same tables."""
    pytest.importorskip("dask.distributed")
    import socket

    blocker = socket.socket()
    try:
        blocker.bind(("127.0.0.1", 8787))
        blocker.listen()
    except OSError:  # already taken by someone else: the case under test all the same
        pass
    try:
        specs = _specs(out_of_range="ignore")[:2]
        serial = build_tables(specs, progress=False)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            parallel = build_tables(specs, client="local", n_workers=2, progress=False)
    finally:
        blocker.close()
    assert not [w for w in caught if "8787" in str(w.message)]
    for a, b in zip(serial, parallel, strict=True):
        _same(a, b)


def _worker_settings():
    import os

    import numba

    names = ("MALLOC_MMAP_THRESHOLD_", "MALLOC_TRIM_THRESHOLD_", "NUMBA_NUM_THREADS",
             "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")  # fmt: skip
    return {n: os.environ.get(n) for n in names}, numba.get_num_threads()


def test_local_cluster_workers_one_thread_and_glibc_heap_of_a_plain_process():
    """The "local" cluster's workers start with the thread caps (numba 1 thread) and glibc's
    heap thresholds set before they start (dask's MALLOC_TRIM_THRESHOLD_=65536 would leave
    every numpy temporary over 128 kB a fresh mapping: ×1.6 the CPU of a PO table)."""
    pytest.importorskip("dask.distributed")
    from emscatter.parallel import WORKER_MALLOC, dask_client, open_executor

    executor, close = open_executor("local", 2, 1)
    try:
        got = dask_client(executor).run(_worker_settings)
    finally:
        close()
    assert len(got) == 2
    for env, numba_threads in got.values():
        assert numba_threads == 1
        assert env["MALLOC_MMAP_THRESHOLD_"] == str(WORKER_MALLOC["MALLOC_MMAP_THRESHOLD_"])
        assert env["MALLOC_TRIM_THRESHOLD_"] == str(WORKER_MALLOC["MALLOC_TRIM_THRESHOLD_"])
        assert env["NUMBA_NUM_THREADS"] == env["OMP_NUM_THREADS"] == "1"
        assert env["OPENBLAS_NUM_THREADS"] == env["MKL_NUM_THREADS"] == "1"


def test_limited_threads_caps_the_wheels_openblas_and_restores_it():
    """Without threadpoolctl, emscatter.parallel caps the OpenBLAS of numpy's and scipy's
    wheels itself, so a serial run uses the BLAS thread count of a "local" worker
    (OPENBLAS_NUM_THREADS=threads) and gets its bits."""
    from emscatter import parallel

    controls = parallel._openblas_controls()
    if not controls:
        pytest.skip("no OpenBLAS from the numpy/scipy wheels here (a system BLAS)")
    before = [int(get()) for get, _ in controls]
    with parallel.limited_threads(1, wheel_blas=True):
        assert [int(get()) for get, _ in controls] == [1] * len(controls)
    assert [int(get()) for get, _ in controls] == before
