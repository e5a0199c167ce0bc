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
