"""GO's compiled per-angle validity pass (solvers/kirchhoff/go_validity.py) against the numpy
reference (``go.check_validity`` with ``theta_i``), and through the API's angle report."""

from __future__ import annotations

import math

import numpy as np
import pytest

import emscatter as em
from emscatter import method_resolution as mr
from emscatter.solvers.kirchhoff import go
from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation

K = 2 * math.pi / 0.1

CASES = [
    GaussianCorrelation(0.3, 1.5),  # kσ ≈ 19: fails above ~85° (both criteria)
    GaussianCorrelation(0.01, 0.05),  # Q < 10 at normal incidence: every angle fails
    GaussianCorrelation(0.05, 0.1),  # steep slopes: the illuminated fraction fails first
    GaussianCorrelation(1.0, 200.0),  # gentle: every angle up to 89.9° passes Smith
    ExponentialCorrelation(0.3, 1.5),  # slope variance with the 2k cutoff
]


def _angles(n, seed=0):
    rng = np.random.default_rng(seed)
    t = rng.uniform(0, math.radians(89.9), n)
    t[:4] = [0.0, math.pi / 2, math.radians(89.9), 1e-300]  # the ends of the range
    return t


@pytest.mark.parametrize("rough", CASES, ids=lambda r: f"{type(r).__name__}-{r.sigma}-{r.length}")
def test_compiled_angle_entries_equal_the_numpy_report(rough, monkeypatch):
    monkeypatch.setenv("EMSCATTER_KERNELS", "numba")
    ti = _angles(50_000)
    ref = go.check_validity(rough, K, theta_i=ti)
    fast = go.angle_entries(rough, K, ti)
    assert fast is not None
    np.testing.assert_array_equal(fast["angle_valid"], ref["angle_valid"])
    np.testing.assert_allclose(fast["angle_excess"], ref["angle_excess"], rtol=1e-12, atol=0)
    assert fast["angle_reasons"] == ref["angle_reasons"]


def test_the_threshold_separates_pass_from_fail_where_the_reference_does(monkeypatch):
    """Angles packed around the threshold (1e-13 rad apart): the verdicts are the
    reference's bit for bit (the 1e-6 margin puts every close angle on the exact path)."""
    monkeypatch.setenv("EMSCATTER_KERNELS", "numba")
    rough = GaussianCorrelation(0.3, 1.5)
    lo, hi = 0.0, math.pi / 2
    for _ in range(3):  # the first failing angle, to ~1e-12 rad
        grid = np.linspace(lo, hi, 10_001)
        j = int(np.argmin(go.check_validity(rough, K, theta_i=grid)["angle_valid"]))
        lo, hi = grid[j - 1], grid[j]
    ti = hi + np.arange(-5000, 5000) * 1e-13
    ref = go.check_validity(rough, K, theta_i=ti)
    fast = go.angle_entries(rough, K, ti)
    assert 0 < ref["angle_valid"].sum() < ti.size  # the threshold is inside
    np.testing.assert_array_equal(fast["angle_valid"], ref["angle_valid"])
    assert fast["angle_reasons"] == ref["angle_reasons"]


def test_numpy_backend_and_few_angles_take_the_reference(monkeypatch):
    rough = GaussianCorrelation(0.3, 1.5)
    monkeypatch.setenv("EMSCATTER_KERNELS", "numpy")
    assert go.angle_entries(rough, K, _angles(50_000)) is None
    monkeypatch.setenv("EMSCATTER_KERNELS", "numba")
    assert go.angle_entries(rough, K, _angles(100)) is None


def test_api_validity_report_is_the_same_with_and_without_kernels(monkeypatch):
    rough = GaussianCorrelation(0.3, 1.5)
    n = 30_000
    rng = np.random.default_rng(1)
    ti = rng.uniform(0, math.radians(89.9), n)
    ts = rng.uniform(0, math.radians(89.9), n)
    ps = rng.uniform(-math.pi, math.pi, n)
    out = {}
    for backend in ("numpy", "numba"):
        monkeypatch.setenv("EMSCATTER_KERNELS", backend)
        out[backend] = em.bistatic(rough, 17 + 2j, wavelength=0.1, theta_i=ti, theta_s=ts,
                                   phi_s=ps, method="go", out_of_range="ignore")  # fmt: skip
        rep = mr.angle_report("go", rough, K, eps=17 + 2j, theta_i=ti)
        out[backend + "_report"] = rep
    a, b = out["numpy"].info["validity"], out["numba"].info["validity"]
    np.testing.assert_array_equal(a["angle_valid"], b["angle_valid"])
    np.testing.assert_allclose(a["angle_excess"], b["angle_excess"], rtol=1e-12, atol=0)
    assert a["angle_reasons"] == b["angle_reasons"] and len(a["angle_reasons"]) == 2
    assert a["valid"] is b["valid"] is False
    assert all(f"of {n} angles)" in r for r in b["angle_reasons"])
    # σ⁰: the kernels' promise (tests/test_kernels.py: 1e-12 relative, a 1e-14 floor of the
    # polarization's peak where the numpy formula cancels)
    got, ref = out["numba"].sigma0, out["numpy"].sigma0
    peak = np.max(ref, axis=-1, keepdims=True)
    assert np.all(np.abs(got - ref) <= 1e-12 * ref + 1e-14 * peak)
    # out_of_range="nan" blanks the same angles on both paths
    for backend in ("numpy", "numba"):
        monkeypatch.setenv("EMSCATTER_KERNELS", backend)
        out[backend] = em.bistatic(rough, 17 + 2j, wavelength=0.1, theta_i=ti, theta_s=ts,
                                   phi_s=ps, method="go", out_of_range="nan")  # fmt: skip
    nan_a, nan_b = np.isnan(out["numpy"].sigma0), np.isnan(out["numba"].sigma0)
    np.testing.assert_array_equal(nan_a, nan_b)
    assert nan_a.any() and not nan_a.all()
