"""Issue 22: the speed-ups between the public API and the compiled kernels keep every value
bit for bit — the API equals its solver, the kernels' persistent thread pool gives the same
σ⁰ as one thread, φs − φi is not materialized at φi = +0 (x − 0.0 = x exactly) but still is
at φi = −0.0 and any other φi, and the API's checked φ are not copied twice (SPM)."""

from __future__ import annotations

import math
import threading

import numpy as np
import pytest

import emscatter as em
from emscatter import solvers
from emscatter.conventions import check_angle

LAM = 0.1
K = 2 * math.pi / LAM
EPS = 17 + 2j
N = 40_000  # above the compiled gate (kernels.gate.MIN_GEOMETRIES) and > 2 thread chunks
ROUGH = {
    "go": em.GaussianCorrelation(0.3, 1.5),
    "spm": em.GaussianCorrelation(0.1 / K, 2.0 / K),
}


def _angles(n=N, seed=0):
    rng = np.random.default_rng(seed)
    ti = rng.uniform(0, math.radians(89.9), n)
    ts = rng.uniform(0, math.radians(89.9), n)
    ps = rng.uniform(-math.pi, math.pi, n)
    ps[:3] = (-0.0, 0.0, math.pi)  # signed zeros pass through unchanged
    return ti, ts, ps


@pytest.fixture(autouse=True)
def _numba(monkeypatch):
    monkeypatch.setenv("EMSCATTER_KERNELS", "numba")
    monkeypatch.setenv("EMSCATTER_CACHE", "0")


@pytest.mark.parametrize("method", ["go", "spm"])
def test_api_equals_solver_bit_for_bit(method):
    ti, ts, ps = _angles()
    res = em.bistatic(ROUGH[method], EPS, wavelength=LAM, theta_i=ti, theta_s=ts, phi_s=ps,
                      method=method, out_of_range="ignore")  # fmt: skip
    ref = solvers.get(method).bistatic(ROUGH[method], EPS, K, ti, ts, ps, coherent=False)
    np.testing.assert_array_equal(res.sigma0, ref.sigma0)
    assert np.isfinite(res.sigma0).all()
    np.testing.assert_array_equal(res.phi_s, ps)  # the angles recorded, not aliased
    assert not np.shares_memory(res.phi_s, ps) and not np.shares_memory(res.theta_i, ti)


@pytest.mark.parametrize("method", ["go", "spm"])
def test_phi_i_zero_shortcut_matches_the_difference(method):
    """φi = +0.0 reads φs as φs − φi; φi = −0.0 and φi = 0.3 subtract: each equals the call
    with the difference made explicitly (φs − φi, φi = 0 is a rotation about the normal)."""
    ti, ts, ps = _angles(seed=1)
    mod = solvers.get(method)
    for phi_i in (0.0, -0.0, 0.3):
        a = mod.bistatic(ROUGH[method], EPS, K, ti, ts, ps, phi_i, coherent=False).sigma0
        d = np.asarray(ps - phi_i)
        b = mod.bistatic(ROUGH[method], EPS, K, ti, ts, d, 0.0, coherent=False).sigma0
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("method", ["go", "spm"])
def test_threads_do_not_change_values_and_are_reused(method):
    """The pool of :func:`emscatter.kernels._runtime.run_split` serves every kernel call: the
    same σ⁰ as one thread, and no new thread per call (a call used to start its own pool)."""
    from emscatter.kernels._runtime import run_chunked

    ti, ts, ps = _angles(seed=2)
    args = (ROUGH[method], EPS, K, ti, ts, ps)
    mod = solvers.get(method)
    first = mod.bistatic(*args, coherent=False).sigma0
    before = threading.active_count()
    again = mod.bistatic(*args, coherent=False).sigma0
    assert threading.active_count() == before
    np.testing.assert_array_equal(first, again)
    seen = np.zeros(N, dtype=np.int64)

    def part(a, b):
        seen[a:b] += 1

    run_chunked(part, N, threads=2)
    assert (seen == 1).all()  # every index once, split or not


def test_check_angle_copy_flag():
    a = np.linspace(0.0, 1.0, 11)
    assert check_angle("theta_i", a) is not a
    assert check_angle("theta_i", a, copy=False) is a
    with pytest.raises(ValueError, match=r"phi_s must be in \[-1e\+06"):
        check_angle("phi_s", np.array([0.0, 2e6]), low=-1e6, high=1e6, copy=False)
