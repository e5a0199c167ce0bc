"""Validity checks at many angles (method_resolution.angle_report's paths without a sort):
the same verdicts as each solver's own check_validity at every angle, the per-angle checks
skipped only where the policy does not need them (recorded), and the numba warm-up."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

import emscatter as em
from emscatter import method_resolution as mr
from emscatter.solvers.kirchhoff import go, po
from emscatter.solvers.select import ValidityWarning
from emscatter.solvers.spm import model as spm

LAM = 0.1
K = 2 * math.pi / LAM
N = 3 * mr._DISTINCT_MAX  # above the size where the distinct angles are sorted
CASES = [  # (method, module, roughness, eps): some angles fail for each (grazing, Q, r₁)
    ("go", go, em.GaussianCorrelation(0.3, 1.5), 17 + 2j),
    ("go", go, em.GaussianCorrelation(0.02, 0.2), "pec"),  # stationary phase fails too
    ("po", po, em.GaussianCorrelation(0.4 / K, 6.0 / K), 17 + 2j),
    ("spm", spm, em.GaussianCorrelation(0.1 / K, 2.0 / K), 17 + 2j),  # all pass: the bound
    ("spm", spm, em.ExponentialCorrelation(0.5 / K, 4.0 / K), 80 + 5j),  # r₁ fails below 32°
]


def _angles(n=N, seed=0):
    return np.random.default_rng(seed).uniform(0.0, math.radians(89.99), n)


def _span(text):  # a reason without its "(n of m angles)" denominator
    return re.sub(r" of \d+ angles\)", " angles)", text)


@pytest.mark.parametrize("method, module, rough, eps", CASES)
def test_many_angles_same_verdicts_as_the_solvers_own_check(method, module, rough, eps):
    ti = _angles()
    own = module.check_validity(rough, K, eps=eps, theta_i=ti)
    mr.clear_cache()
    rep = mr.angle_report(method, rough, K, eps=eps, theta_i=ti)
    np.testing.assert_array_equal(rep["angle_valid"], own["angle_valid"])
    np.testing.assert_allclose(rep["angle_excess"], own["angle_excess"], rtol=1e-12, atol=0)
    assert [_span(r) for r in rep["angle_reasons"]] == [_span(r) for r in own["angle_reasons"]]
    for r in rep["angle_reasons"]:  # all distinct here: the count is out of every angle
        assert f" of {N} angles)" in r
    expect_failures = not (method == "spm" and rough == CASES[3][2])
    assert bool((~own["angle_valid"]).any()) == expect_failures  # each case as designed


@pytest.mark.parametrize("method, module, rough, eps", CASES[:3])
def test_monotone_checks_are_flagged_and_decided_by_a_threshold(method, module, rough, eps):
    ti = np.sort(_angles(64))
    rep = module.check_validity(rough, K, eps=eps, theta_i=ti)
    assert rep["angle_monotone"] is True
    ok = rep["angle_valid"]
    assert not ok[np.argmin(ok) :].any() or ok.all()  # passes below one angle, fails above


def test_spm_safe_angle_decides_the_angles_below_it_and_only_those_above_are_checked(
    monkeypatch,
):
    """SPM's r₁ check does not grow with θi everywhere, but its report proves a θ_safe (the
    per-segment bound of the interpolated r₁): angle_report checks only the angles above it,
    with the verdicts, excesses and reasons of the check at every angle."""
    rough, eps = em.GaussianCorrelation(0.2 / K, 2.0 / K), "pec"  # TM fails near grazing
    ti = _angles()
    own = spm.check_validity(rough, K, eps=eps, theta_i=ti)
    safe = own["angle_safe_below"]
    assert own["angle_monotone"] is False and 0 < safe < math.radians(89.9)
    assert own["angle_valid"][ti <= safe].all() and not own["angle_valid"].all()
    mr.clear_cache()
    calls = []
    real = mr.validity_report

    def spy(*args, **kw):
        calls.append(np.size(kw.get("theta_i")))
        return real(*args, **kw)

    monkeypatch.setattr(mr, "validity_report", spy)  # counts the angles each check is given
    rep = mr.angle_report("spm", rough, K, eps=eps, theta_i=ti)
    monkeypatch.undo()
    assert max(calls) == np.count_nonzero(ti > safe) < ti.size  # only the angles above
    np.testing.assert_array_equal(rep["angle_valid"], own["angle_valid"])
    np.testing.assert_array_equal(rep["angle_excess"], own["angle_excess"])
    assert rep["angle_reasons"] == own["angle_reasons"]
    assert rep["angle_valid"].flags.writeable and rep["angle_valid"].base is not ti


def test_a_grid_is_checked_at_its_distinct_incidence_angles():
    rough, eps = em.GaussianCorrelation(0.3, 1.5), 17 + 2j
    th = np.radians(np.linspace(0.0, 89.5, 90))
    grid = np.meshgrid(th, np.zeros(60), np.zeros(50), indexing="ij")[0]  # materialized
    part, shape = mr._varying_part(grid)
    assert shape == (90, 1, 1)
    rep = mr.angle_report("go", rough, K, eps=eps, theta_i=grid)
    own = go.check_validity(rough, K, eps=eps, theta_i=th)
    np.testing.assert_array_equal(
        rep["angle_valid"], np.broadcast_to(own["angle_valid"][:, None, None], grid.shape)
    )
    assert rep["angle_reasons"] == own["angle_reasons"]  # "(n of 90 angles)", as before
    view = np.broadcast_to(th[:, None, None], grid.shape)  # a broadcast view: the same
    again = mr.angle_report("go", rough, K, eps=eps, theta_i=view)
    np.testing.assert_array_equal(again["angle_valid"], rep["angle_valid"])


def test_api_flags_and_nan_policy_unchanged_at_many_geometries():
    rough, eps = em.GaussianCorrelation(0.3, 1.5), 17 + 2j
    rng = np.random.default_rng(3)
    ti, ts = rng.uniform(0, 1.55, N), rng.uniform(0, 1.5, N)
    ps = rng.uniform(-math.pi, math.pi, N)
    kw = dict(wavelength=LAM, theta_i=ti, theta_s=ts, phi_s=ps, method="go")
    res = em.bistatic(rough, eps, out_of_range="nan", **kw)
    bad = ~go.check_validity(rough, K, eps=eps, theta_i=ti)["angle_valid"]
    assert bad.any() and not bad.all()
    np.testing.assert_array_equal(np.isnan(res.sigma0[0, 0]), bad)
    ign = em.bistatic(rough, eps, out_of_range="ignore", **kw)  # still checked and recorded
    np.testing.assert_array_equal(ign.info["validity"]["angle_valid"], ~bad)


def test_angle_checks_skipped_only_where_the_policy_does_not_need_them():
    rough = em.GaussianCorrelation(0.3 / K, 0.5 / K)  # GO far outside: kσ, slope
    assert not go.check_validity(rough, K)["valid"]
    ti = np.radians([10.0, 50.0, 89.0])
    res = em.backscatter(rough, 4.0, wavelength=LAM, theta_i=ti, method="go", out_of_range="nan")
    rep = res.info["validity"]
    assert rep["angle_check"].startswith("not checked") and "'nan'" in rep["angle_check"]
    assert "angle_valid" not in rep and np.all(np.isnan(res.sigma0))
    with pytest.warns(ValidityWarning):
        warned = em.backscatter(rough, 4.0, wavelength=LAM, theta_i=ti, method="go")
    assert "angle_valid" in warned.info["validity"] and "angle_check" not in warned.info["validity"]


def test_warm_up_runs_and_rejects_unknown_methods(capsys):
    from emscatter import warm

    pytest.importorskip("numba")
    lines = []
    times = warm.warm(("spm",), echo=lines.append)
    assert times["spm"] is not None and times["spm"] > 0, lines
    with pytest.raises(SystemExit):
        warm.main(["spm", "nonsense"])
    assert "nonsense" in capsys.readouterr().err
