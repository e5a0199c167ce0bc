"""Monte Carlo runner: reproducible seeds, statistics, and the same numbers on every
executor, including a real dask.distributed LocalCluster on loopback."""

from __future__ import annotations

import math
import sys
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor

import numpy as np
import pytest

from emscatter import montecarlo
from emscatter.solvers.mom import model as mom
from emscatter.spectra import GaussianCorrelation


def draw(rng: np.random.Generator) -> dict[str, np.ndarray]:
    return {"normal": rng.standard_normal(3), "uniform": rng.uniform()}


def test_seeds_statistics_and_validation():
    n = 37
    res = montecarlo.run(draw, n, seed=123, progress=False, chunk=5)
    # the reference: realization i uses SeedSequence(123).spawn(n)[i]
    seeds = np.random.SeedSequence(123).spawn(n)
    samples = np.array([np.random.default_rng(s).standard_normal(3) for s in seeds])
    np.testing.assert_allclose(res.mean["normal"], samples.mean(axis=0), rtol=0, atol=1e-14)
    np.testing.assert_allclose(
        res.std_error["normal"], samples.std(axis=0, ddof=1) / math.sqrt(n), rtol=1e-12
    )
    assert res.n == n and res.entropy == 123
    # chunking is a bookkeeping detail: the statistics agree to rounding
    other = montecarlo.run(draw, n, seed=123, progress=False, chunk=8)
    np.testing.assert_allclose(other.mean["normal"], res.mean["normal"], rtol=1e-13)
    # a bare array is returned as a bare array
    arr = montecarlo.run(lambda r: r.uniform(size=2), 4, seed=1, progress=False)
    assert isinstance(arr.mean, np.ndarray) and arr.mean.shape == (2,)
    with pytest.raises(ValueError, match="n_realizations"):
        montecarlo.run(draw, 1, seed=0, progress=False)
    with pytest.raises(TypeError, match="n_realizations"):
        montecarlo.run(draw, 2.5, seed=0, progress=False)
    with pytest.raises(ValueError, match="chunk"):
        montecarlo.run(draw, 4, seed=0, progress=False, chunk=0)
    with pytest.raises(TypeError, match="executor"):
        montecarlo.run(draw, 4, seed=0, progress=False, executor=object())
    with pytest.raises(RuntimeError, match="realization 0 failed"):
        montecarlo.run(lambda r: 1 / 0, 4, seed=0, progress=False)
    with pytest.raises(ValueError, match="non-finite"):
        montecarlo.run(lambda r: np.nan, 4, seed=0, progress=False)


def test_thread_and_process_pools_give_the_serial_numbers():
    serial = montecarlo.run(draw, 40, seed=9, progress=False)
    with ThreadPoolExecutor(3) as ex:
        threads = montecarlo.run(draw, 40, seed=9, executor=ex, progress=False)
    with ProcessPoolExecutor(2) as ex:
        procs = montecarlo.run(draw, 40, seed=9, executor=ex, progress=False)
    for res in (threads, procs):
        for key in ("normal", "uniform"):
            np.testing.assert_array_equal(res.mean[key], serial.mean[key])
            np.testing.assert_array_equal(res.std_error[key], serial.std_error[key])


@pytest.mark.filterwarnings("ignore:Port .* is already in use:UserWarning")
@pytest.mark.filterwarnings("ignore:unclosed .*:ResourceWarning")
def test_dask_local_cluster_gives_the_serial_numbers():
    """A real dask.distributed LocalCluster (scheduler and 2 worker processes on
    127.0.0.1): same seeds → same numbers as the serial run, for a toy function and for a
    small method-of-moments Monte Carlo."""
    distributed = pytest.importorskip("distributed")
    import cloudpickle

    # workers do not have tests/ on their path: ship this module's functions by value
    cloudpickle.register_pickle_by_value(sys.modules[__name__])
    rough = GaussianCorrelation(0.05, 1.0, dimension=1)
    ts = np.radians([0.0, 20.0, 40.0])
    kw = dict(realizations=4, seed=5, length=20.0, progress=False)
    serial_toy = montecarlo.run(draw, 24, seed=77, progress=False)
    serial_mom = mom.bistatic(rough, "pec", 2 * math.pi, 0.3, ts, **kw)
    cluster = client = None
    try:
        cluster = distributed.LocalCluster(
            n_workers=2,
            threads_per_worker=1,
            processes=True,
            host="127.0.0.1",
            dashboard_address=None,
            silence_logs=40,
        )
        client = distributed.Client(cluster, timeout=60)
        client.wait_for_workers(2, timeout=120)
        ex = client.get_executor()
        toy = montecarlo.run(draw, 24, seed=77, executor=ex, progress=False)
        par = mom.bistatic(rough, "pec", 2 * math.pi, 0.3, ts, executor=ex, **kw)
    finally:
        cloudpickle.unregister_pickle_by_value(sys.modules[__name__])
        if client is not None:
            client.close(timeout=30)
        if cluster is not None:
            cluster.close(timeout=30)
    assert toy.info["executor"] == "ClientExecutor"
    for key in ("normal", "uniform"):
        np.testing.assert_array_equal(toy.mean[key], serial_toy.mean[key])
        np.testing.assert_array_equal(toy.std_error[key], serial_toy.std_error[key])
    np.testing.assert_allclose(par.sigma0, serial_mom.sigma0, rtol=1e-12, atol=0)
    np.testing.assert_allclose(par.coherent, serial_mom.coherent, rtol=1e-12)
    np.testing.assert_allclose(
        par.info["standard_error"], serial_mom.info["standard_error"], rtol=1e-12
    )
