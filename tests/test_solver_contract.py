"""One contract, run against every registered approximate solver (scikit-rf / SMRT style).

Laws from shared/PHYSICS.md: physical outputs everywhere (no NaN, inf, negative σ⁰ or
warning) over the whole stability box of issue 3, reciprocity, the flat-surface limit,
emissivity in [0, 1], plus the result contract (shapes, method name).
"""

import math
import warnings

import numpy as np
import pytest

from emscatter import solvers
from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation, PowerLawCorrelation
from laws import assert_flat_limit, assert_physical, assert_reciprocal

METHODS = ["spm", "go", "po", "iem"]
K = 2 * math.pi  # λ = 1 m

DEG = np.radians([0.0, 10.0, 45.0, 70.0, 89.9])
TI, TS, PS = np.meshgrid(DEG, DEG, np.linspace(0, 2 * math.pi, 9), indexing="ij")
EPS_SET = [1.01, 17 + 2j, 1e7j, -20 + 1j, -5.0, "pec"]


def _solver(name):
    return solvers.get(name)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("k_sigma", [1e-4, 0.1, 3.0, 100.0])
@pytest.mark.parametrize("k_ell", [1e-2, 3.0, 1e4])
def test_stability_box(method, k_sigma, k_ell):
    mod = _solver(method)
    rough = GaussianCorrelation(k_sigma / K, k_ell / K)
    for eps in EPS_SET:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # numpy warnings (overflow, invalid) fail here
            for ti, ts, ps in ((TI, TS, PS), (DEG, DEG, 0.0), (DEG, DEG, math.pi)):
                res = mod.bistatic(rough, eps, K, ti, ts, ps, 0.0)
                assert_physical(res, where=f"{method} kσ={k_sigma} kℓ={k_ell} ε={eps}")
                assert res.sigma0.shape == (2, 2, *np.broadcast(ti, ts, ps).shape)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("dimension", [2, 1])
def test_contract_shapes_and_name(method, dimension):
    mod = _solver(method)
    rough = GaussianCorrelation(0.02, 0.5, dimension=dimension)
    res = mod.bistatic(rough, 5 + 1j, K, np.full((3, 1), 0.3), np.array([0.1, 0.4]), 0.0, 0.0)
    assert res.sigma0.shape == (2, 2, 3, 2)
    assert res.coherent.shape[0] == 2
    assert res.dimension == dimension
    assert isinstance(mod.check_validity(rough, K)["valid"], bool)
    if dimension == 1:  # no cross-polarization in a 2-D problem
        assert np.all(res.hv == 0) and np.all(res.vh == 0)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize(
    "rough",
    [
        GaussianCorrelation(0.03, 0.6),
        GaussianCorrelation(0.03, 0.4, 0.9),
        GaussianCorrelation(0.03, 0.6, dimension=1),
    ],
    ids=["iso", "aniso", "profile"],
)
@pytest.mark.parametrize("eps", [17 + 2j, "pec"])
def test_reciprocity(method, rough, eps):
    assert_reciprocal(_solver(method).bistatic, rough, eps, K, np.random.default_rng(7))


@pytest.mark.parametrize("method", ["spm", "po"])
@pytest.mark.parametrize("rough_cls", [GaussianCorrelation, ExponentialCorrelation])
def test_flat_limit(method, rough_cls):
    flat = rough_cls(1e-9, 0.5)
    assert_flat_limit(_solver(method).bistatic, flat, 17 + 2j, K)
    res = _solver(method).bistatic(flat, 17 + 2j, K, 0.4, np.radians([0, 30, 60]), 0.0, 0.0)
    assert np.all(res.sigma0 < 1e-12)


def test_power_law_spectrum_is_supported_by_spm_and_po():
    rough = PowerLawCorrelation(0.01, 0.5, hurst=0.7)
    for method in ("spm", "po"):
        res = _solver(method).bistatic(rough, 17 + 2j, K, 0.4, np.radians([0, 20, 60]), 0.0, 0.0)
        assert_physical(res, where=method)
        assert res.hh[1] > 0


# --------------------------------------------------------------------------- validity reports
REPORT_KEYS = {"valid", "reasons", "checks", "excess"}


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize(
    "rough",
    [
        GaussianCorrelation(0.2 / K, 1.0 / K),
        ExponentialCorrelation(3.0 / K, 10.0 / K),
        PowerLawCorrelation(1.0 / K, 8.0 / K, hurst=0.7, dimension=1),
    ],
    ids=["gauss", "exp", "powerlaw1d"],
)
def test_check_validity_interface(method, rough):
    """BOARD interface 1: every report names the failed check, its value, its limit and the
    factor; with theta_i the per-angle verdicts have theta_i's shape."""
    mod = _solver(method)
    rep = mod.check_validity(rough, K)
    assert REPORT_KEYS <= set(rep) and isinstance(rep["valid"], bool)
    assert math.isfinite(rep["excess"]) and rep["excess"] >= 0  # no infinite excess any more
    assert rep["valid"] == (not rep["reasons"]) == (rep["excess"] == 0)
    for name, d in rep["details"].items():
        assert rep["checks"][name] == d["ok"] == (d["ratio"] <= 1)
        if not d["ok"]:
            text = next(r for r in rep["reasons"] if r.startswith(name + ":"))
            assert f"{d['value']:.3g}" in text and f"{d['limit']:.3g}" in text and "×" in text
    ti = np.radians([[0.0, 30.0], [70.0, 89.0]])
    rep_a = mod.check_validity(rough, K, eps=17 + 2j, theta_i=ti)
    assert rep_a["angle_valid"].shape == ti.shape and rep_a["angle_valid"].dtype == bool
    assert rep_a["angle_excess"].shape == ti.shape
    assert rep_a["valid"] == (rep["valid"] and bool(np.all(rep_a["angle_valid"])))
    assert rep_a["excess"] >= rep["excess"]
    for text in rep_a["angle_reasons"]:
        assert "°" in text and "fails for θi" in text
    with pytest.raises(ValueError, match=f"not accepted by method '{method}'"):
        mod.check_validity(rough, K, no_such_option=1)


@pytest.mark.parametrize(
    ("method", "rough", "eps", "fails_above_deg"),
    [
        # SPM, PEC, TM near grazing: r₁ ∝ (kσ)²/cosθi (issue 11: e = −2.2 at 85–89°)
        ("spm", GaussianCorrelation(0.2 / K, 1.0 / K), "pec", 80.0),
        # GO: σ = 0.6 λ, ℓ = 4 λ (issue 11: e_h = −0.27 at 85°): Q = (2kσ cosθ)² < 10
        ("go", GaussianCorrelation(0.6, 4.0), 17 + 2j, 65.0),
        # PO: kσ = 1, kℓ = 10 (issue 11: e = −0.12 at 85°): shadowing no longer negligible
        ("po", GaussianCorrelation(1.0 / K, 10.0 / K), 17 + 2j, 75.0),
    ],
)
def test_angular_validity_flags_the_grazing_cases(method, rough, eps, fails_above_deg):
    ti = np.radians(np.arange(0.0, 90.0, 1.0))
    rep = _solver(method).check_validity(rough, K, eps=eps, theta_i=ti)
    assert rep["checks"][next(iter(rep["details"]))] is not None
    assert not rep["valid"]
    bad = np.degrees(ti[~rep["angle_valid"]])
    assert bad.min() <= fails_above_deg + 10 and bad.min() >= 20.0
    assert np.all(rep["angle_valid"][ti < np.radians(20.0)])
