"""Issue 22 (gofast): the public API checks a large float64 angle array and takes the copy it
records in one compiled pass (:mod:`emscatter.kernels.checks`): the same values bit for bit as
the numpy checks, never aliased to the caller's arrays, the same errors for bad input, and
the numpy backend untouched."""

from __future__ import annotations

import math

import numpy as np
import pytest

import emscatter as em
from emscatter import api
from emscatter.kernels.checks import copy_in_range

LAM = 0.1
ROUGH = em.GaussianCorrelation(0.3, 1.5)
N = 20_000  # above kernels.gate.MIN_GEOMETRIES


def _angles(n=N, seed=3):
    rng = np.random.default_rng(seed)
    ti = rng.uniform(0, math.pi / 2, n)
    ts = rng.uniform(0, math.pi / 2, n)
    ps = rng.uniform(-math.pi, math.pi, n)
    ti[:2], ts[:2], ps[:3] = (0.0, math.pi / 2), (math.pi / 2, 0.0), (-0.0, 0.0, 1e300)
    return ti, ts, ps


@pytest.fixture(autouse=True)
def _numba(monkeypatch):
    monkeypatch.setenv("EMSCATTER_KERNELS", "numba")
    monkeypatch.setenv("EMSCATTER_CACHE", "0")


def test_copy_in_range_is_a_bitwise_copy_and_rejects_out_of_range_and_nan():
    ti, _, ps = _angles()
    got = copy_in_range(ti, 0.0, math.pi / 2)
    assert got is not None and not np.shares_memory(got, ti)
    assert got.tobytes() == ti.tobytes()
    got = copy_in_range(ps, -math.inf, math.inf)  # signed zeros and huge values kept
    assert got.tobytes() == ps.tobytes()
    for bad in (math.nan, -1e-300, math.pi / 2 + 1e-15, math.inf):
        t = ti.copy()
        t[-1] = bad
        assert copy_in_range(t, 0.0, math.pi / 2) is None
    p = ps.copy()
    p[7] = math.inf
    assert copy_in_range(p, -math.inf, math.inf) is None  # inf ≤ inf but not finite


@pytest.mark.parametrize("monostatic", [False, True])
def test_api_results_equal_the_numpy_checked_path_bit_for_bit(monkeypatch, monostatic):
    ti, ts, ps = _angles()

    def call():
        if monostatic:
            return em.backscatter(ROUGH, 17 + 2j, wavelength=LAM, theta_i=ti, method="go",
                                  out_of_range="ignore")  # fmt: skip
        return em.bistatic(ROUGH, 17 + 2j, wavelength=LAM, theta_i=ti, theta_s=ts, phi_s=ps,
                           method="go", out_of_range="ignore")  # fmt: skip

    fused = call()
    monkeypatch.setattr(api, "_checked_copy", lambda *a, **k: None)  # the plain checks
    plain = call()
    assert fused.sigma0.tobytes() == plain.sigma0.tobytes()
    for name in ("theta_i", "theta_s", "phi_s", "phi_i"):
        a, b = getattr(fused, name), getattr(plain, name)
        assert a.tobytes() == b.tobytes()
    np.testing.assert_array_equal(fused.info["validity"]["angle_excess"],
                                  plain.info["validity"]["angle_excess"])  # fmt: skip
    for arr in (ti, ts, ps):  # recorded, not aliased
        assert not np.shares_memory(fused.theta_i, arr)
        assert not np.shares_memory(fused.phi_s, arr)


@pytest.mark.parametrize(
    "param, value, match",
    [("theta_i", math.nan, "theta_i"), ("theta_s", 2.0, "theta_s"), ("phi_s", math.inf, "phi_s")],
)
def test_bad_large_inputs_get_the_usual_message(param, value, match):
    ti, ts, ps = _angles()
    arrays = {"theta_i": ti, "theta_s": ts, "phi_s": ps}
    arrays[param] = arrays[param].copy()
    arrays[param][N // 2] = value
    with pytest.raises(ValueError, match=match):
        em.bistatic(ROUGH, 17 + 2j, wavelength=LAM, method="go", out_of_range="ignore", **arrays)


def test_numpy_backend_and_small_or_strided_inputs_take_the_plain_checks(monkeypatch):
    ti, _, _ = _angles()
    assert api._checked_copy(ti[::2], 0.0, math.pi / 2) is None  # not contiguous
    assert api._checked_copy(ti[:100], 0.0, math.pi / 2) is None  # small
    assert api._checked_copy(ti.astype(np.float32), 0.0, math.pi / 2) is None
    monkeypatch.setenv("EMSCATTER_KERNELS", "numpy")
    assert api._checked_copy(ti, 0.0, math.pi / 2) is None


def test_azimuth_gate_one_pass_agrees_with_min_max():
    from emscatter.kernels.gate import MAX_AZIMUTH, azimuth_ok

    _, _, ps = _angles()
    ps = ps.copy()
    ps[2] = 0.5
    assert azimuth_ok(ps)
    for bad in (math.nan, MAX_AZIMUTH * (1 + 1e-15), -math.inf):
        p = ps.copy()
        p[N - 1] = bad
        assert not azimuth_ok(p)
    p = ps.copy()
    p[0] = -MAX_AZIMUTH  # the bound itself is inside
    assert azimuth_ok(p)
