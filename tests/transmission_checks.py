"""Checks the transmission tests share (tests/test_btdf_po.py, tests/test_btdf_spm.py,
tests/test_iem_transmission.py): the Gauss–Legendre rule on an interval, a hemisphere's dΩ
quadrature, Fresnel's flat transmissivity and the ε-weighted reciprocity of a transmission σ⁰."""

from __future__ import annotations

import math

import numpy as np

from emscatter.fresnel import fresnel_cos

K = 2 * math.pi  # λ = 1 m: lengths in the callers are in wavelengths


def gauss_legendre(n: int, a: float, b: float):
    """Nodes and weights of the ``n``-point Gauss–Legendre rule on ``[a, b]``."""
    x, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * (b - a) * x + 0.5 * (b + a), 0.5 * (b - a) * w


def hemisphere(n: int, kink=None):
    """(θ, φ, dΩ weights) over a hemisphere (``2n × n`` Gauss–Legendre nodes); θ split at
    ``kink`` [rad] (the branch angle where the integrand has a square-root kink: |k⊥| = k of
    the other medium)."""
    if kink is None:
        t, wt = gauss_legendre(2 * n, 0.0, 0.5 * math.pi)
    else:
        (a, wa), (b, wb) = gauss_legendre(n, 0.0, kink), gauss_legendre(n, kink, 0.5 * math.pi)
        t, wt = np.r_[a, b], np.r_[wa, wb]
    p, wp = gauss_legendre(n, 0.0, 2 * math.pi)
    tt, pp = np.meshgrid(t, p, indexing="ij")
    return tt, pp, np.outer(wt * np.sin(t), wp)


def fresnel_t(eps, theta) -> np.ndarray:
    """Fresnel's flat transmissivity ``1 − |R_p|²`` (h, v) at incidence ``theta`` [rad]."""
    rh, rv = fresnel_cos(eps, np.cos(theta))
    return np.array([1 - abs(rh) ** 2, 1 - abs(rv) ** 2])


def assert_eps_weighted_reciprocity(bistatic_transmission, rough, *, lit_share: float,
                                    eps: float = 2.25, n: int = 400, seed: int = 3,
                                    theta_i_max: float = 1.2):  # fmt: skip
    """``σ⁰_t,pq(ε, k; k̂i → k̂t) = ε σ⁰_t,qp(1/ε, √ε k; −k̂t → −k̂i)`` (Tsang, Kong & Ding 2000
    §9.4 reciprocity across an interface) at ``n`` random geometries (θi < ``theta_i_max``
    rad, θt < 0.6 rad, any azimuths), to 1e-10 of the largest σ⁰; more than half of the
    geometries must carry σ⁰ above ``lit_share`` of the largest (so the check is not one of
    zeros)."""
    rng = np.random.default_rng(seed)
    ti, tt = rng.uniform(0, theta_i_max, n), rng.uniform(0, 0.6, n)
    pt, pi_ = rng.uniform(-math.pi, math.pi, n), rng.uniform(-math.pi, math.pi, n)
    kw = {"out_of_range": "ignore"}
    f = bistatic_transmission(rough, eps, K, ti, tt, pt, pi_, **kw).sigma0
    g = bistatic_transmission(
        rough, 1 / eps, math.sqrt(eps) * K, tt, ti, pi_ + math.pi, pt + math.pi, **kw
    ).sigma0
    assert np.count_nonzero(f.sum(axis=(0, 1)) > lit_share * f.max()) > n // 2
    np.testing.assert_allclose(f, eps * np.swapaxes(g, 0, 1), atol=1e-10 * f.max())
