"""The IEM's monostatic fast path (issue 22: IEM backscatter through the API ahead of SMRT at a
few angles): ``bistatic.checked(..., monostatic=True)`` goes from the API's checked angles
straight into the compiled exact-backscatter kernel (``backscatter_path.monostatic``), without
the general geometry. Pinned against the reference it replaces, computed here: the solver's
general ``bistatic`` (geometry → backscatter chunk → ``_backscatter``) on the same inputs —
σ⁰, ``info`` and the angle arrays bit for bit, over correlations, roughness, permittivities,
the four complementary models, both Fresnel choices, the three shadowing modes, azimuths
(+0, −0, rotated), shapes and 1-D profiles; and the option memory refuses what the checks
refuse."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

import emscatter as em
from emscatter.solvers.iem import backscatter_path as back_path
from emscatter.solvers.iem import compiled as iem_jit
from emscatter.solvers.iem import model as iem
from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation, PowerLawCorrelation

FREQ = 5.3e9
K = 2 * math.pi * FREQ / 299792458.0
FUNG92 = dict(complementary="fung92", fresnel="incident", first_order="model", shadowing=False)
MODELS = {
    "fung92": FUNG92,
    "default": {},
    "aiem": dict(complementary="aiem"),
    "upper-incident": dict(complementary="aiem-upper", fresnel="incident"),
}
needs_numba = pytest.mark.skipif(not iem_jit.enabled(), reason="numba kernels off")


def _same(a, b):
    """The two results are the same object field by field (σ⁰ and angles bit for bit)."""
    assert a.sigma0.shape == b.sigma0.shape
    assert np.array_equal(a.sigma0, b.sigma0)  # bit for bit (both finite: no NaN here)
    assert np.all(np.isfinite(a.sigma0))
    for name in ("theta_i", "theta_s", "phi_s", "phi_i"):
        x, y = getattr(a, name), getattr(b, name)
        assert x.shape == y.shape and np.array_equal(x, y), name
    assert a.info == b.info and a.method == b.method == "iem"
    assert a.k == b.k and a.dimension == b.dimension
    assert np.isnan(a.coherent).all() and a.coherent.shape == b.coherent.shape


def _pair(rough, eps, theta, phi_i, **opts):
    th = np.asarray(theta, dtype=float)
    pi_ = np.asarray(phi_i, dtype=float)
    ps = np.asarray(pi_ + math.pi, dtype=float)
    kw = dict(coherent=False, crosspol=False, **opts)
    ref = iem.bistatic(rough, eps, K, th, th, ps, pi_, **kw)  # the general path
    fast = iem.bistatic.checked(rough, eps, K, th, th, ps, pi_, monostatic=True, **kw)
    return ref, fast, (th, ps, pi_)


CASES = list(
    itertools.product(
        [ExponentialCorrelation, GaussianCorrelation],
        [0.05, 0.5, 1.5, 2.5],  # kσ
        [15 + 2j, 3.0, 80 + 40j, "pec"],
        list(MODELS),
    )
)


@needs_numba
@pytest.mark.parametrize("corr, ks, eps, model", CASES)
def test_monostatic_path_is_the_general_path(corr, ks, eps, model):
    rough = corr(ks / K, 0.03)
    theta = np.radians(np.linspace(0.0, 85.0, 9))
    ref, fast, (th, ps, pi_) = _pair(rough, eps, theta, 0.0, **MODELS[model])
    _same(fast, ref)
    opt, mode = iem._options(*_option_args(MODELS[model]))
    slope = iem.nominal_rms_slope(rough)
    assert back_path.monostatic(rough, eps, K, th, ps, pi_, opt, slope, mode) is not None


def _option_args(opts):
    o = {**iem._DEFAULTS, "coherent": False, "crosspol": False, **opts}
    names = ("rtol", "max_terms", "fresnel", "complementary", "first_order", "reciprocal",
             "shadowing", "crosspol", "crosspol_order", "coherent", "threads")  # fmt: skip
    return [o[n] for n in names]


@needs_numba
@pytest.mark.parametrize("shadowing", [False, "height-correlated", "direction-correlated"])
@pytest.mark.parametrize("phi_i", [0.0, -0.0, 0.7, -2.5])
@pytest.mark.parametrize("theta", [0.4, [0.2], np.radians(np.arange(12.0).reshape(3, 4) * 7)])
def test_azimuths_shapes_and_shadowing(shadowing, phi_i, theta):
    rough = ExponentialCorrelation(1.2 / K, 0.03)
    for opts in ({}, FUNG92):
        ref, fast, _ = _pair(rough, 15 + 2j, theta, phi_i, **{**opts, "shadowing": shadowing})
        _same(fast, ref)


@needs_numba
@pytest.mark.parametrize("corr", [ExponentialCorrelation, GaussianCorrelation])
def test_profiles_anisotropy_rms_slope_and_options(corr):
    theta = np.radians(np.linspace(1.0, 80.0, 7))
    cases = [
        (corr(0.9 / K, 0.03, dimension=1), {}),  # a 1-D profile
        (corr(0.9 / K, 0.03, length_y=0.05), dict(shadowing=False)),  # anisotropic lengths
        (corr(0.9 / K, 0.03), dict(rms_slope=0.2, rtol=1e-12, max_terms=10**5, threads=1)),
        (corr(0.9 / K, 0.03), dict(reciprocal=False, first_order="model")),
    ]
    for rough, opts in cases:
        for phi_i in (0.0, 1.1):
            ref, fast, _ = _pair(rough, 15 + 2j, theta, phi_i, **opts)
            _same(fast, ref)


def test_uncovered_calls_take_the_general_path(monkeypatch):
    """Where the fast path does not apply (an ε or φi array, a power-law spectrum, an
    anisotropic shadowing slope, coherent or cross-pol asked for, numpy kernels), the entry
    is the general ``bistatic``: same result, and ``monostatic`` declines."""
    theta = np.radians([10.0, 30.0, 50.0])
    exp = ExponentialCorrelation(0.8 / K, 0.03)
    cases = [
        (exp, np.array([15 + 2j, 10 + 1j, 5.0]), 0.0, {}),
        (exp, 15 + 2j, np.array([0.0, 0.1, 0.2]), {}),
        (PowerLawCorrelation(0.8 / K, 0.03, hurst=0.7), 15 + 2j, 0.0, {}),
        (exp, 15 + 2j, 0.0, dict(rms_slope=(0.1, 0.3))),
    ]
    for rough, eps, phi_i, opts in cases:
        th, pi_ = np.asarray(theta), np.asarray(phi_i, dtype=float)
        ps = pi_ + math.pi
        kw = dict(coherent=False, crosspol=False, **opts)
        ref = iem.bistatic(rough, eps, K, th, th, ps, pi_, **kw)
        got = iem.bistatic.checked(rough, eps, K, th, th, ps, pi_, monostatic=True, **kw)
        assert np.array_equal(got.sigma0, ref.sigma0) and got.info == ref.info
    th, ps, pi_ = np.asarray(theta), np.asarray(math.pi), np.asarray(0.0)
    for extra in (dict(coherent=True, crosspol=False), dict(coherent=False, crosspol=True)):
        ref = iem.bistatic(exp, 15 + 2j, K, th, th, ps, pi_, **extra)
        got = iem.bistatic.checked(exp, 15 + 2j, K, th, th, ps, pi_, monostatic=True, **extra)
        assert np.array_equal(got.sigma0, ref.sigma0)
        assert np.array_equal(got.coherent, ref.coherent, equal_nan=True)
    monkeypatch.setenv("EMSCATTER_KERNELS", "numpy")
    opt, mode = iem._options(*_option_args({}))
    assert back_path.monostatic(exp, 15 + 2j, K, th, ps, pi_, opt, (0.1, 0.1), mode) is None
    ref = iem.bistatic(exp, 15 + 2j, K, th, th, ps, pi_, coherent=False, crosspol=False)
    got = iem.bistatic.checked(exp, 15 + 2j, K, th, th, ps, pi_, monostatic=True,
                               coherent=False, crosspol=False)  # fmt: skip
    assert np.array_equal(got.sigma0, ref.sigma0)


@pytest.mark.parametrize("opts", [{}, FUNG92])
@pytest.mark.parametrize("n", [1, 10, 100])
def test_api_backscatter_equals_the_general_solver(opts, n):
    """Through ``emscatter.backscatter`` (the call of the SMRT benchmark) the σ⁰ and the
    solver's info are the general path's, bit for bit."""
    rough = ExponentialCorrelation(2.5 / K, 0.03)
    theta = np.radians(np.linspace(0.5, 70.0, n))
    res = em.backscatter(rough, 15 + 2j, frequency=FREQ, theta_i=theta, method="iem",
                         out_of_range="ignore", crosspol=False, coherent=False, **opts)  # fmt: skip
    ref = iem.bistatic(rough, 15 + 2j, K, theta, theta, np.asarray(math.pi), np.asarray(0.0),
                       coherent=False, crosspol=False, **opts)  # fmt: skip
    assert np.array_equal(res.sigma0, ref.sigma0)
    info = {k: v for k, v in res.info.items() if k != "validity"}
    assert info == {k: v for k, v in ref.info.items() if k != "coherent"}


def test_option_memory_refuses_what_the_checks_refuse():
    rough = ExponentialCorrelation(0.5 / K, 0.03)
    th, ps, pi_ = np.asarray([0.3]), np.asarray(math.pi), np.asarray(0.0)
    ok = iem.bistatic.checked(rough, 15 + 2j, K, th, th, ps, pi_, monostatic=True,
                              coherent=False, crosspol=False, shadowing=True)  # fmt: skip
    assert ok.info["shadowing"] == "direction-correlated"
    bad = [dict(shadowing=1), dict(rtol=True), dict(rtol=1.0), dict(max_terms=1.0),
           dict(fresnel="tranistion"), dict(crosspol=1), dict(threads=0)]  # fmt: skip
    for opts in bad:  # after the accepted True/1e-8/..., the equal-valued 1 etc. still fail
        name = next(iter(opts))
        kw = {"coherent": False, "crosspol": False, **opts}
        with pytest.raises((ValueError, TypeError), match=name):
            iem.bistatic(rough, 15 + 2j, K, th, th, ps, pi_, **kw)
        with pytest.raises((ValueError, TypeError), match=name):
            iem.bistatic.checked(rough, 15 + 2j, K, th, th, ps, pi_, monostatic=True, **kw)
    kw = dict(monostatic=True, coherent=False, crosspol=False)
    plain = iem.bistatic.checked(rough, 15 + 2j, K, th, th, ps, pi_, **kw)
    arr = iem.bistatic.checked(rough, 15 + 2j, K, th, th, ps, pi_, rtol=np.array(1e-8), **kw)
    assert np.array_equal(arr.sigma0, plain.sigma0)  # an unhashable option: checked each call
    with pytest.raises(TypeError):
        iem.bistatic.checked(rough, 15 + 2j, K, th, th, ps, pi_, colour=1, **kw)


def test_auto_backscatter_keeps_the_cross_pol_memory():
    """``method="auto"`` on an IEM regime: the entry's signature still says it takes
    ``crosspol``, so the API runs the co-pol path (``crosspol=False``, the fast one) and adds
    the multiple-scattering hv from :mod:`emscatter.solvers.auto_crosspol`, as before."""
    from emscatter import api
    from emscatter.solvers import auto_crosspol

    rough = ExponentialCorrelation(0.5 / K, 3.3 / K)
    theta = np.radians([20.0, 40.0])
    res = em.backscatter(rough, 15 + 2j, frequency=FREQ, theta_i=theta, out_of_range="ignore")
    assert res.method == "iem"
    assert res.info["crosspol"] == "multiple scattering (backscatter; solvers.auto_crosspol)"
    entry = api._solver_entry(em.solvers.get("iem"))
    assert api._takes(entry, "crosspol") and api._takes(entry, "monostatic")
    ps, pi_ = np.asarray(math.pi), np.asarray(0.0)
    co = iem.bistatic(rough, 15 + 2j, K, theta, theta, ps, pi_, coherent=False, crosspol=False)
    hv, _ = auto_crosspol.supplement(auto_crosspol.IEM_BACKSCATTER, rough, 15 + 2j, K, theta,
                                     theta, ps, pi_)  # fmt: skip
    assert np.array_equal(res.sigma0[0, 0], co.sigma0[0, 0])
    assert np.array_equal(res.sigma0[1, 1], co.sigma0[1, 1])
    assert np.array_equal(res.sigma0[0, 1], co.sigma0[0, 1] + hv) and np.all(hv > 0)
