"""One shared checker of the laws every solver must pass (SMRT / scikit-rf style).

Used by ``tests/test_solver_contract.py`` against every registered solver, and available to
each solver's own tests. Each function asserts; the messages say which law failed where.
"""

from __future__ import annotations

import math

import numpy as np

from emscatter.fresnel import reflectivity


def random_geometry(rng: np.random.Generator, n: int, *, dimension: int = 2):
    """Random (θi, θs, φs, φi) with θ in [0, 85°]."""
    ti = rng.uniform(0, math.radians(85), n)
    ts = rng.uniform(0, math.radians(85), n)
    pi_ = rng.uniform(0, 2 * math.pi, n)
    if dimension == 1:
        ps = pi_ + math.pi * rng.integers(0, 2, n)
    else:
        ps = rng.uniform(0, 2 * math.pi, n)
    return ti, ts, ps, pi_


def assert_physical(result, *, where: str = "") -> None:
    """σ⁰ and coherent reflectivity finite, non-negative; coherent ≤ 1."""
    s, c = result.sigma0, result.coherent
    assert np.all(np.isfinite(s)), f"non-finite sigma0 {where}"
    assert np.all(s >= 0), f"negative sigma0 (min {s.min():g}) {where}"
    assert np.all(np.isfinite(c)), f"non-finite coherent reflectivity {where}"
    assert np.all((c >= 0) & (c <= 1 + 1e-12)), f"coherent reflectivity outside [0, 1] {where}"


def assert_reciprocal(bistatic, rough, eps, k, rng, *, n=200, rtol=1e-10, **opts) -> None:
    """σ⁰_pq(i → s) = σ⁰_qp(−s → −i): swap (θi, φi) ↔ (θs, φs + π) and transpose pols."""
    ti, ts, ps, pi_ = random_geometry(rng, n, dimension=rough.dimension)
    fwd = bistatic(rough, eps, k, ti, ts, ps, pi_, **opts).sigma0
    rev = bistatic(rough, eps, k, ts, ti, pi_ + math.pi, ps + math.pi, **opts).sigma0
    rev_t = np.swapaxes(rev, 0, 1)
    scale = np.max(np.abs(fwd), axis=(0, 1), keepdims=True) + 1e-300
    err = np.max(np.abs(fwd - rev_t) / scale)
    assert err <= rtol, f"reciprocity violated: max relative difference {err:.3g} > {rtol:g}"


def assert_flat_limit(bistatic, rough_flat, eps, k, *, atol_coh=1e-6, **opts) -> None:
    """σ → 0: coherent reflectivity → Fresnel, incoherent σ⁰ → 0 (relative to σ⁰ scale)."""
    ti = np.radians([0.0, 20.0, 45.0, 70.0])
    res = bistatic(rough_flat, eps, k, ti, ti, 0.0 * ti, 0.0 * ti, **opts)
    fres = reflectivity(eps, ti) if not isinstance(eps, str) else np.ones((2, ti.size))
    np.testing.assert_allclose(res.coherent, fres, atol=atol_coh)


def assert_energy(r_total, *, upper_tol=1e-6, lossless=False, atol=None) -> None:
    """Never r > 1; for a lossless medium / PEC r ≈ 1 within ``atol``."""
    r = np.asarray(r_total)
    assert np.all(r <= 1 + upper_tol), f"reflectivity above 1: max {r.max():.6g}"
    assert np.all(r >= 0), f"negative reflectivity: min {r.min():.6g}"
    if lossless:
        np.testing.assert_allclose(r, 1.0, atol=atol)
