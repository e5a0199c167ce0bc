"""mom3d Monte Carlo on a process pool and on a dask LocalCluster: bit-identical to the serial
run (realization j's surface fixed by seeds[j]); bad client / threads / n_workers refused
before any work; worker warnings passed on (issue 19)."""

from __future__ import annotations

import concurrent.futures as cf
import math
import warnings

import numpy as np
import pytest

from emscatter import parallel
from emscatter.solvers import mom3d
from emscatter.spectra import GaussianCorrelation

K = 2 * math.pi  # λ = 1 m
ROUGH = GaussianCorrelation(0.3 / K, 3 / K, dimension=2)
TS = np.radians([0.0, 30.0, 50.0])
# a 2λ × 2λ PEC patch at 8 points/λ: 512 unknowns, dense, < 1 s per realization
TINY = {"realizations": 3, "seed": 11, "length": 2.0, "progress": False}


def _identical(a, b):
    assert a.sigma0.tobytes() == b.sigma0.tobytes()
    assert a.coherent.tobytes() == b.coherent.tobytes()
    for key in ("energy", "sigma0_std", "incoherent_reflectivity", "iterations", "reflectivity"):
        assert np.asarray(a.info[key]).tobytes() == np.asarray(b.info[key]).tobytes(), key


@pytest.fixture(scope="module")
def serial():
    return mom3d.bistatic(ROUGH, "pec", K, math.radians(30), TS, 0.0, **TINY)


def test_serial_result_is_sane(serial):
    """The reference itself: PEC energy per realization within 5 % (a 2λ patch loses 0.4–4.3 %
    past its edges, measured), σ⁰ finite and positive."""
    assert serial.info["energy"].shape == (3, 2)
    assert np.allclose(serial.info["energy"], 1.0, atol=0.05)
    assert np.all(serial.sigma0[0, 0] > 0) and np.all(np.isfinite(serial.sigma0))
    assert serial.info["bytes_per_worker"] >= serial.info["matrix_bytes"]
    samples = serial.info["sigma0_samples"]  # per-realization σ⁰: their mean is σ⁰
    assert samples.shape == (3, 2, 2, 3)
    assert np.allclose(samples.mean(axis=0), serial.sigma0, rtol=1e-10, atol=0)


def test_process_pool_bit_identical_to_serial(serial):
    with cf.ProcessPoolExecutor(2) as pool:
        par = mom3d.bistatic(ROUGH, "pec", K, math.radians(30), TS, 0.0, client=pool, **TINY)
    _identical(serial, par)


def test_dask_local_cluster_bit_identical_to_serial(serial):
    pytest.importorskip("dask.distributed")
    par = mom3d.bistatic(ROUGH, "pec", K, math.radians(30), TS, 0.0, client="local",
                         n_workers=2, **TINY)  # fmt: skip
    _identical(serial, par)


def test_dask_client_with_two_threads_is_bit_identical(serial):
    """A caller's own dask Client (left open), threads=2 per task, and the scheduler's
    address "tcp://…": the same bits."""
    distributed = pytest.importorskip("dask.distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=":0") as cluster:  # fmt: skip
        with distributed.Client(cluster) as client:
            par = mom3d.bistatic(ROUGH, "pec", K, math.radians(30), TS, 0.0, client=client,
                                 threads=2, **TINY)  # fmt: skip
            assert client.status == "running"
        by_address = mom3d.bistatic(ROUGH, "pec", K, math.radians(30), TS, 0.0,
                                    client=cluster.scheduler_address, **TINY)  # fmt: skip
    _identical(serial, par)
    _identical(serial, by_address)


def test_seed_none_gives_one_set_of_surfaces_on_a_pool():
    """seed=None draws fresh entropy once, in the caller: still a valid Monte Carlo."""
    with cf.ThreadPoolExecutor(2) as pool:
        res = mom3d.bistatic(ROUGH, "pec", K, math.radians(30), TS, 0.0, client=pool,
                             **{**TINY, "seed": None, "realizations": 2})  # fmt: skip
    # fresh surfaces each run: a TINY patch's energy spreads 0.94–1.0 between draws (0.946 seen)
    assert np.all(np.isfinite(res.sigma0)) and np.allclose(res.info["energy"], 1.0, atol=0.1)


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"client": "dask"}, r"client must be None \(serial\), 'local'"),
        ({"client": 3}, "client must be"),
        ({"threads": 0}, "threads must be a positive integer or None, got 0"),
        ({"threads": 1.5}, "threads must be a positive integer"),
        ({"n_workers": -2}, "n_workers must be a positive integer or None, got -2"),
    ],
)
def test_bad_parallel_arguments_are_refused_before_work(kw, match):
    with pytest.raises(ValueError, match=match):
        mom3d.bistatic(ROUGH, "pec", K, 0.5, TS, 0.0, **{**TINY, **kw})


def _warns(x):
    warnings.warn(f"task {x} warns", UserWarning, stacklevel=1)
    return x * x


def test_worker_warnings_are_passed_on_once_each_with_the_task_name():
    with cf.ProcessPoolExecutor(2) as pool, pytest.warns(UserWarning) as rec:
        out = parallel.run_ordered(pool, _warns, [(1,), (2,), (3,)], ["a", "b", "c"])
    assert out == [1, 4, 9]
    assert sorted(str(w.message) for w in rec) == ["a: task 1 warns", "b: task 2 warns",
                                                   "c: task 3 warns"]  # fmt: skip


def _fails(x):
    if x == 2:
        raise ArithmeticError("boom")
    return x


def test_a_failing_task_is_named():
    with cf.ThreadPoolExecutor(2) as pool, pytest.raises(RuntimeError, match="r2 failed: boom"):
        parallel.run_ordered(pool, _fails, [(1,), (2,)], ["r1", "r2"])


def test_progress_bar_counts_realizations_finished_in_workers(capsys):
    with cf.ThreadPoolExecutor(2) as pool:
        mom3d.bistatic(ROUGH, "pec", K, 0.5, TS, 0.0, client=pool,
                       **{**TINY, "progress": True})  # fmt: skip
    err = capsys.readouterr().err
    assert "mom3d realizations" in err and "/3 " in err and "energy" in err  # postfix set


def test_dielectric_on_a_process_pool_is_bit_identical():
    """Müller's equations (ε = 4 + 0.5i, a 1λ patch at 8 points per λ/Re√ε) on two workers."""
    kw = {**TINY, "realizations": 2, "length": 1.0}
    args = (ROUGH, 4 + 0.5j, K, 0.5, TS, 0.0)
    a = mom3d.bistatic(*args, **kw)
    with cf.ProcessPoolExecutor(2) as pool:
        b = mom3d.bistatic(*args, client=pool, **kw)
    _identical(a, b)
    assert np.all((a.info["reflectivity"] > 0) & (a.info["reflectivity"] < 1))


def test_local_cluster_size_is_capped_by_memory():
    """client="local" starts at most the CPU count ÷ threads workers and no more than 80 % of
    the free memory holds at bytes_per_worker each (at least one)."""
    import os

    from emscatter.solvers.mom3d.montecarlo import local_workers

    cpus = os.cpu_count() or 1
    assert local_workers(1, 1) == cpus
    assert local_workers(1, 2) == max(1, cpus // 2)
    assert local_workers(2**50, 1) == 1  # a petabyte each: one worker, never zero
