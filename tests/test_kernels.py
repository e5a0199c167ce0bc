"""Compiled kernels (emscatter.kernels) against the numpy reference path they replace."""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest

from emscatter import kernels
from emscatter.solvers.kirchhoff import compiled as kirchhoff_compiled
from emscatter.solvers.spm import compiled as spm_compiled
from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation, PowerLawCorrelation

numba = pytest.importorskip("numba")

RTOL = 1e-12  # relative, elementwise
FLOOR = 1e-14  # of the polarization's largest value, where the numpy formula cancels


def _agree(got, ref):
    """The kernels' promise (emscatter.kernels docstring); returns the fraction of points
    that needed the absolute floor."""
    got, ref = np.asarray(got), np.asarray(ref)
    assert got.shape == ref.shape
    assert np.all(np.isfinite(got)) and np.all(got >= 0)
    peak = np.max(np.abs(ref), axis=-1, keepdims=True)
    err = np.abs(got - ref)
    ok = err <= RTOL * np.abs(ref) + FLOOR * peak
    assert ok.all(), (
        f"{np.count_nonzero(~ok)} points off; worst relative "
        f"{np.max(err / np.maximum(np.abs(ref), 1e-300)):.3g}"
    )
    return float(np.mean(err > RTOL * np.abs(ref)))


def _geometries(n, seed=0):
    rng = np.random.default_rng(seed)
    hi = math.pi / 2
    ti, ts = rng.uniform(0, hi, n), rng.uniform(0, hi, n)
    dphi = rng.uniform(-2 * math.pi, 2 * math.pi, n)
    # edges: normal incidence, grazing, backscatter, specular, in-plane, large azimuths
    edge_t = np.array([0.0, hi, 1e-9, hi - 1e-9, 0.7, 0.7, 0.7, 1.2, 0.3, 0.0])
    edge_s = np.array([0.0, hi, 0.5, 0.2, 0.7, 0.7, 0.0, 1.2, 0.9, hi])
    edge_p = np.array([0.0, math.pi, 1.0, 0.0, math.pi, 0.0, 2.0, -math.pi, 1e5, -3e5])
    return (np.concatenate([edge_t, ti]), np.concatenate([edge_s, ts]),
            np.concatenate([edge_p, dphi]))  # fmt: skip


@pytest.fixture
def numpy_path(monkeypatch):
    monkeypatch.setenv("EMSCATTER_KERNELS", "numpy")


# ----------------------------------------------------------------------------- math
def test_vector_math_matches_numpy_and_scipy():
    from scipy import special

    from emscatter.kernels import _vmath as vm
    from emscatter.kernels._runtime import jit

    @jit(cache=False)
    def run(x, e, s, c, h, f):
        for i in range(x.size):
            e[i] = vm.vexp(x[i])
            c[i] = vm.vcos(x[i])
            s[i] = vm.vsin(min(max(x[i], 0.0), 0.5 * math.pi))
            f[i] = vm.verfcx(min(max(x[i], 0.0), vm.ERFCX_HI))
            h[i] = vm.vsin(x[i])

    rng = np.random.default_rng(1)
    x = np.concatenate(
        [rng.uniform(-5, 5, 20000), rng.uniform(-745, 709.0, 20000), rng.uniform(-1e6, 1e6, 5000),
         [0.0, -0.0, 1e-300, -745.1, 709.5, 0.5 * math.pi, math.pi, 6.0]]
    )  # fmt: skip
    outs = [np.empty_like(x) for _ in range(5)]
    run(x, *outs)
    e, s, c, h, f = outs

    def ulps(a, b):
        return np.abs(a - b) / np.spacing(np.maximum(np.abs(b), np.finfo(float).tiny))

    inrange = np.abs(x) < 709.0
    ref_e = np.exp(x[inrange])
    normal = ref_e > 1e-300
    assert np.max(ulps(e[inrange][normal], ref_e[normal])) <= 4
    assert np.max(np.abs(e[inrange][~normal] - ref_e[~normal])) < 1e-300
    assert np.all(e[x < -746] == 0) and np.all(np.isinf(e[x > 710]))
    xs = np.clip(x, 0, 0.5 * math.pi)
    assert np.max(ulps(s, np.sin(xs))) <= 4
    assert np.max(np.abs(c - np.cos(x))) <= 4e-16 and np.max(np.abs(h - np.sin(x))) <= 4e-16
    big = np.abs(np.cos(x)) > 1e-3
    assert np.max(ulps(c[big], np.cos(x[big]))) <= 8
    xa = np.clip(x, 0, vm.ERFCX_HI)
    assert np.max(np.abs(f / special.erfcx(xa) - 1)) <= 4e-15
    assert vm.ERFCX_MAX_REL_ERR <= 4e-15


# ----------------------------------------------------------------------------- SPM1
@pytest.mark.parametrize("eps", ["pec", 17 + 2j, -20 + 3j, 2.0, 1.5 + 0.01j])
@pytest.mark.parametrize("kind", [GaussianCorrelation, ExponentialCorrelation])
def test_spm1_kernel_matches_numpy_reference(kind, eps, numpy_path):
    from emscatter.solvers.spm.kernel import EXPONENTIAL, GAUSSIAN, spm1_sigma0
    from emscatter.solvers.spm.model import _sigma0_first

    k = 2 * math.pi / 0.03
    rough = kind(0.1 / k, 2.0 / k)
    ti, ts, dphi = _geometries(40_000)
    ref = _sigma0_first(rough, eps, k, ti, ts, dphi, 0.0, np.empty((2, 2, ti.size)))
    got = np.empty_like(ref)
    code = GAUSSIAN if kind is GaussianCorrelation else EXPONENTIAL
    spm1_sigma0(ti, ts, dphi, "pec" if eps == "pec" else complex(eps), k=k, sigma=rough.sigma,
                length=rough.length, spectrum=code, out=got, threads=2)  # fmt: skip
    frac = _agree(got, ref)
    assert frac < 0.05  # the floor is for the cancellation spots only


def test_spm_bistatic_same_with_and_without_kernels(monkeypatch):
    from emscatter.solvers.spm import model as spm

    rough = GaussianCorrelation(0.002, 0.02)
    ti, ts, dphi = _geometries(3000, seed=3)
    args = (rough, 17 + 2j, 2 * math.pi / 0.05, ti, ts, dphi)
    monkeypatch.setenv("EMSCATTER_KERNELS", "numpy")
    ref = spm.bistatic(*args, coherent=False).sigma0
    monkeypatch.setenv("EMSCATTER_KERNELS", "numba")
    _agree(spm.bistatic(*args, coherent=False).sigma0, ref)


# ----------------------------------------------------------------------------- GO
@pytest.mark.parametrize(
    "shadowing", [False, "smith", "separable", "correlated", "direction-correlated"]
)
@pytest.mark.parametrize("eps", ["pec", 17 + 2j, -30 + 5j])
def test_go_kernel_matches_numpy_reference(eps, shadowing, numpy_path):
    from emscatter.solvers.kirchhoff import go
    from emscatter.solvers.kirchhoff.go_kernel import go_sigma0

    k = 2 * math.pi
    rough = GaussianCorrelation(0.1, 1.0)
    ti, ts, dphi = _geometries(40_000, seed=2)
    ref = go.bistatic(rough, eps, k, ti, ts, dphi, shadowing=shadowing, threads=1)
    got = np.empty((2, 2, ti.size))
    coh = np.empty((2, ti.size))
    go_sigma0(ti, ts, dphi, eps, slope_variance=ref.info["slope_variance"][0],
              shadowing=shadowing or None, out=got, coherent_out=coh, k=k, sigma=rough.sigma,
              threads=2)  # fmt: skip
    frac = _agree(got, ref.sigma0)
    assert frac < 0.1
    np.testing.assert_allclose(coh, ref.coherent, rtol=1e-12, atol=1e-300)


@pytest.mark.parametrize("shadowing", [False, "smith", "correlated"])
@pytest.mark.parametrize("eps", ["pec", 17 + 2j])
def test_go_grid_kernel_matches_numpy_reference(eps, shadowing, monkeypatch):
    """A grid of directions (each direction's trigonometry and Λ computed once): the solver
    with the kernel equals its numpy path, σ⁰ and the coherent part."""
    from emscatter.solvers.kirchhoff import go

    rough = GaussianCorrelation(0.1, 1.0)
    hi = math.pi / 2
    ti = np.concatenate([[0.0, 1e-9, hi], np.linspace(0.05, 1.5, 7)])[None, None, :]
    ts = np.concatenate([[0.0, hi - 1e-9, 0.7], np.linspace(0.0, hi, 60)])[None, :, None]
    ps = np.concatenate([[0.0, math.pi, -math.pi, 1e5], np.linspace(-7.0, 7.0, 53)])[:, None]
    args = (rough, eps, 2 * math.pi, ti, ts, ps[..., None], 0.0)
    monkeypatch.setenv("EMSCATTER_KERNELS", "numpy")
    ref = go.bistatic(*args, shadowing=shadowing, threads=1)
    monkeypatch.setenv("EMSCATTER_KERNELS", "numba")
    for threads in (1, 2):
        got = go.bistatic(*args, shadowing=shadowing, threads=threads)
        assert got.sigma0.shape == ref.sigma0.shape == (2, 2, 57, 63, 10)
        frac = _agree(got.sigma0.reshape(2, 2, -1), ref.sigma0.reshape(2, 2, -1))
        assert frac < 0.1
        np.testing.assert_allclose(got.coherent, ref.coherent, rtol=1e-12, atol=1e-300)


def test_go_direction_weight_in_the_loop_is_the_numpy_weight_and_2pi_periodic():
    """λ(ψ), ψ = arccos(−cos Δφ), computed in the compiled loop as π − |Δφ mod± 2π| (no
    arccos): the numpy formula's value (to arccos's conditioning near ψ = 0) over the
    kernel's whole azimuth range |Δφ| ≤ 1e6, and σ⁰ unchanged by Δφ → Δφ + 2πm."""
    pytest.importorskip("numba")
    from emscatter.solvers.kirchhoff import go_kernel as gk

    d = np.concatenate([
        [0.0, math.pi, -math.pi, math.pi - 1e-9, 2 * math.pi, 1e6, -1e6],
        np.random.default_rng(1).uniform(-1e6, 1e6, 200),
        np.random.default_rng(2).uniform(-7.0, 7.0, 200),
    ])  # fmt: skip
    got = np.array([gk._direction_weight(x) for x in d])
    np.testing.assert_allclose(got, gk.directional_weight(d), rtol=0, atol=1e-7)
    assert np.all((got >= 0) & (got < 4.41 * math.pi / (4.41 * math.pi + 1) + 1e-12))
    rng = np.random.default_rng(3)
    n = 4096
    ti, ts = rng.uniform(0, 1.5, n), rng.uniform(0, 1.5, n)
    base = rng.uniform(-math.pi, math.pi, n)
    shifted = base + 2 * math.pi * rng.integers(-1000, 1000, n)
    a, b = np.empty((2, 2, n)), np.empty((2, 2, n))
    for dphi, out in ((base, a), (shifted, b)):
        gk.go_sigma0(ti, ts, dphi, 17 + 2j, slope_variance=0.04,
                     shadowing="direction-correlated", out=out)  # fmt: skip
    # base + 2πm is Δφ to its rounding (|Δφ| ≤ 6.3e3: ~1e-12 rad), which σ⁰ feels ~1e-7
    np.testing.assert_allclose(b, a, rtol=1e-6, atol=1e-12 * a.max())


@pytest.mark.parametrize("eps", ["pec", 17 + 2j])
def test_go_kernels_direction_correlated_shadowing_match_its_numpy_formula(eps, numpy_path):
    """accuracy's continuous default (1/(1 + max Λ + λ(ψ) min Λ), Ginneken et al. 1998) in the
    flat and the grid kernel, against that formula on the numpy reference's pieces."""
    from emscatter.solvers.kirchhoff import common as kc
    from emscatter.solvers.kirchhoff import go
    from emscatter.solvers.kirchhoff.go_kernel import go_sigma0, go_sigma0_grid

    s2 = 0.02
    ti = np.linspace(0.0, 1.5, 9)[None, None, :]
    ts = np.linspace(0.0, math.pi / 2, 31)[None, :, None]
    dphi = np.concatenate([[0.0, math.pi, -math.pi], np.linspace(-6.0, 6.0, 40)])[:, None, None]
    g = kc.geometry(ti, ts, dphi, 0.0, eps, 2)
    loc = g.chunk()
    lam_i = kc.smith_lambda(kc._a(loc.ci, loc.si, s2))
    lam_s = kc.smith_lambda(kc._a(loc.cs, loc.ss, s2))
    psi = np.arccos(np.clip(-loc.cd, -1.0, 1.0))
    corr = 4.41 * psi / (4.41 * psi + 1.0)
    shadow = 1.0 / (1.0 + np.maximum(lam_i, lam_s) + corr * np.minimum(lam_i, lam_s))
    ref = kc.fresnel_factors(loc, 2, go.slope_pdf_factor(loc, s2, s2, 2) * shadow)
    flat = np.empty_like(ref)
    go_sigma0(g.ti_flat, g.ts_flat, np.ascontiguousarray(g.dphi), eps, slope_variance=s2,
              shadowing="direction-correlated", out=flat)  # fmt: skip
    grid = np.empty_like(ref)
    go_sigma0_grid(ti, ts, dphi, g.shape, eps, slope_variance=s2,
                   shadowing="direction-correlated", out=grid)  # fmt: skip
    _agree(flat, ref)
    _agree(grid, ref)
    # at backscatter (Δφ = π, θs = θi) it is the monostatic 1/(1 + Λi)
    back = np.empty((2, 2, 9))
    t = ti.ravel()
    go_sigma0(t, t, np.full(9, math.pi), eps, slope_variance=s2,
              shadowing="direction-correlated", out=back)  # fmt: skip
    mono = np.empty_like(back)
    go_sigma0(t, t, np.full(9, math.pi), eps, slope_variance=s2, shadowing="smith", out=mono)
    _agree(back, mono)


# ----------------------------------------------------------------------------- selection
def test_dispatch_honours_the_switch_and_covers_only_its_cases(monkeypatch):
    out = np.zeros((2, 2, 4))
    x = np.full(4, 0.3)
    g = GaussianCorrelation(0.01, 0.1)
    monkeypatch.setenv("EMSCATTER_KERNELS", "numpy")
    assert kernels.backend() == "numpy"
    assert not spm_compiled.spm1_sigma0(g, "pec", 60.0, x, x, x, out)
    assert not out.any()
    monkeypatch.setenv("EMSCATTER_KERNELS", "numba")
    assert kernels.backend() == "numba"
    assert spm_compiled.spm1_sigma0(g, "pec", 60.0, x, x, x, out) and out.any()
    # not covered: anisotropic, power law, profiles, arrays of eps, huge azimuths
    assert not spm_compiled.covered_spm1(GaussianCorrelation(0.01, 0.1, length_y=0.2), "pec")
    assert not spm_compiled.covered_spm1(PowerLawCorrelation(0.01, 0.1, hurst=0.7), "pec")
    assert not spm_compiled.covered_spm1(GaussianCorrelation(0.01, 0.1, dimension=1), "pec")
    assert not spm_compiled.covered_spm1(g, np.array([3.0, 4.0]))
    assert not spm_compiled.spm1_sigma0(g, "pec", 60.0, x, x, np.full(4, 2e6), out)
    assert not kirchhoff_compiled.covered_go(2, 0.02, 0.03, "pec", "smith")
    monkeypatch.setenv("EMSCATTER_KERNELS", "fortran")
    with pytest.raises(ValueError, match="EMSCATTER_KERNELS.*fortran"):
        kernels.backend()


def test_auto_keeps_a_small_one_off_call_on_numpy():
    """In a fresh process a 90-angle call does not import numba; a large one does."""
    code = (
        "import sys, numpy as np, emscatter as em; from emscatter.solvers import spm; "
        "g = em.GaussianCorrelation(0.002, 0.02); t = np.radians(np.arange(90.0)); "
        "spm.bistatic(g, 4.0, 125.0, t, t, t + np.pi, coherent=False); "
        "small = 'numba' in sys.modules; "
        "x = np.random.default_rng(0).uniform(0, 1.5, 5000); "
        "spm.bistatic(g, 4.0, 125.0, x, x, x, coherent=False); "
        "print(small, 'numba' in sys.modules)"
    )
    env = {**__import__("os").environ, "EMSCATTER_KERNELS": "auto"}
    out = subprocess.run(
        [sys.executable, "-W", "ignore", "-c", code],
        capture_output=True,
        text=True,
        check=True,
        env=env,
    )
    assert out.stdout.split() == ["False", "True"]


def test_kernels_package_is_light_and_compiles_nothing_at_import():
    code = (
        "import sys, emscatter, emscatter.kernels, emscatter.kernels.gate; "
        "import emscatter.solvers.spm.compiled, emscatter.solvers.kirchhoff.compiled; "
        "print([m for m in ('numba', 'llvmlite') if m in sys.modules])"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_numba_cache_goes_to_the_configured_directory(tmp_path):
    code = (
        "import numpy as np; from emscatter.solvers.spm import compiled as spm_compiled; "
        "from emscatter.spectra import GaussianCorrelation as G; x = np.full(8, 0.3); "
        "o = np.empty((2, 2, 8)); "
        "assert spm_compiled.spm1_sigma0(G(0.01, 0.1), 4.0, 60.0, x, x, x, o)"
    )
    env = {**__import__("os").environ, "EMSCATTER_NUMBA_CACHE_DIR": str(tmp_path)}
    env.pop("NUMBA_CACHE_DIR", None)
    env["EMSCATTER_KERNELS"] = "numba"
    subprocess.run([sys.executable, "-c", code], check=True, env=env, capture_output=True)
    assert list(tmp_path.rglob("*.nbi")), "no numba cache index written"


# ----------------------------------------------------------------------------- PO series
@pytest.mark.parametrize(
    "rough",
    [
        GaussianCorrelation(0.5 / (2 * math.pi), 5 / (2 * math.pi)),
        GaussianCorrelation(3 / (2 * math.pi), 20 / (2 * math.pi)),
        GaussianCorrelation(30 / (2 * math.pi), 100 / (2 * math.pi)),  # peaks ≥ 400: reference
        ExponentialCorrelation(0.5 / (2 * math.pi), 5 / (2 * math.pi)),
        GaussianCorrelation(0.5 / (2 * math.pi), 5 / (2 * math.pi), dimension=1),
        ExponentialCorrelation(0.5 / (2 * math.pi), 5 / (2 * math.pi), dimension=1),
    ],
    ids=["gauss-ks0.5", "gauss-ks3", "gauss-ks30", "exp-ks0.5", "gauss-1d", "exp-1d"],
)
def test_po_series_kernel_matches_numpy_reference(rough, monkeypatch):
    from emscatter.solvers.kirchhoff import po

    ti, ts, dphi = _geometries(4000, seed=4)
    if rough.dimension == 1:
        dphi = np.where(np.cos(dphi) >= 0, 0.0, math.pi)
    args = (rough, 17 + 2j, 2 * math.pi, ti, ts, dphi)
    monkeypatch.setenv("EMSCATTER_KERNELS", "numpy")
    ref = po.bistatic(*args, rtol=1e-13, coherent=False).sigma0
    monkeypatch.setenv("EMSCATTER_KERNELS", "numba")
    _agree(po.bistatic(*args, rtol=1e-13, coherent=False).sigma0, ref)
    # at the default rtol = 1e-8 both meet the tail bound: within rtol of each other (at small
    # Q, where the reference's blocks over-sum most, within ~1e-12)
    monkeypatch.setenv("EMSCATTER_KERNELS", "numpy")
    ref8 = po.bistatic(*args, coherent=False).sigma0
    monkeypatch.setenv("EMSCATTER_KERNELS", "numba")
    got8 = po.bistatic(*args, coherent=False).sigma0
    peak = ref8.max(axis=-1, keepdims=True)
    assert np.all(np.abs(got8 - ref8) <= 2e-8 * np.abs(ref8) + 1e-14 * peak)


def test_default_threads_capped_by_env_and_per_thread(monkeypatch):
    import threading

    from emscatter.kernels import _runtime, default_threads, thread_cap

    monkeypatch.delenv("EMSCATTER_THREADS", raising=False)
    full = default_threads()
    assert full == min(__import__("os").cpu_count() or 1, 8)
    monkeypatch.setenv("EMSCATTER_THREADS", "1")
    assert default_threads() == 1
    monkeypatch.setenv("EMSCATTER_THREADS", "zero")
    with pytest.raises(ValueError, match="EMSCATTER_THREADS must be a positive integer, got 'ze"):
        default_threads()
    monkeypatch.delenv("EMSCATTER_THREADS")
    seen = set()

    def part(a, b):  # which threads run the chunks
        seen.add(threading.get_ident())

    with thread_cap(1):
        assert default_threads() == 1
        other = []
        t = threading.Thread(target=lambda: other.append(default_threads()))
        t.start()
        t.join()
        assert other == [full]  # the cap is this thread's only
        _runtime.run_chunked(part, 1 << 20)
    assert seen == {threading.get_ident()}  # one chunk, in the calling thread
    assert default_threads() == full
    with pytest.raises(ValueError, match="threads must be a positive integer, got 0"):
        with thread_cap(0):
            pass
