"""The API's cached per-call validity report (dispatch.call_report): same verdicts as the solver's
own check, a fresh dict per call, shared arrays read-only, the per-angle policy still applied."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import emscatter as em
from emscatter import method_resolution as dispatch
from emscatter.solvers.kirchhoff import go
from emscatter.solvers.select import ValidityError


def test_repeated_calls_share_one_report_safely():
    rough = em.GaussianCorrelation(0.05, 0.5)
    theta = np.radians([10.0, 40.0, 88.0])
    first = em.backscatter(rough, 4.0, wavelength=0.1, theta_i=theta, method="go",
                           out_of_range="ignore")  # fmt: skip
    rep = first.info["validity"]
    # the merged report equals the solver's own check with the angles
    own = go.check_validity(rough, 2 * math.pi / 0.1, theta_i=theta)
    np.testing.assert_array_equal(rep["angle_valid"], own["angle_valid"])
    assert rep["roughness_valid"] == go.check_validity(rough, 2 * math.pi / 0.1)["valid"]
    assert rep["valid"] == (rep["roughness_valid"] and bool(np.all(own["angle_valid"])))
    # a caller editing its report does not change the next call's
    rep["valid"] = "edited"
    with pytest.raises(ValueError):
        rep["angle_valid"][0] = not rep["angle_valid"][0]  # read-only (shared)
    second = em.backscatter(rough, 4.0, wavelength=0.1, theta_i=theta, method="go",
                            out_of_range="ignore")  # fmt: skip
    assert second.info["validity"] is not rep and second.info["validity"]["valid"] != "edited"
    np.testing.assert_array_equal(second.sigma0, first.sigma0)


def test_per_angle_policy_still_applies_with_the_cached_report():
    rough = em.GaussianCorrelation(0.05, 0.5)
    theta = np.radians([10.0, 89.5])
    k = 2 * math.pi / 0.1
    bad = ~go.check_validity(rough, k, theta_i=theta)["angle_valid"]
    assert bad.any() and not bad.all()  # one angle outside (grazing), one inside
    kw = dict(wavelength=0.1, theta_i=theta, method="go")
    for _ in range(2):  # the second call hits the cache
        res = em.backscatter(rough, 4.0, out_of_range="nan", **kw)
        assert np.all(np.isnan(res.sigma0[..., bad])) and np.all(np.isfinite(res.sigma0[..., ~bad]))
        with warnings.catch_warnings(record=True) as seen:
            warnings.simplefilter("always")
            em.backscatter(rough, 4.0, out_of_range="warn", **kw)
        assert any("89.5" in str(w.message) for w in seen)
        with pytest.raises(ValidityError):
            em.backscatter(rough, 4.0, out_of_range="raise", **kw)
    dispatch.clear_cache()
