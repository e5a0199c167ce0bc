"""Backscatter cross-pol of the second-order kernel at low contrast (issue 20's ε = 3 + i
residual: a check of the kernel, not a fit). In the Born approximation (first order in ε − 1)
the backscatter cross-pol vanishes at every order in the heights (the scattered amplitude is
``(ε − 1) ê_s · ê_i ∫ e^{i(k_i − k_s)·r} dV`` and ``ĥ_s · v̂_i = 0`` in backscatter), so the
hv amplitude is second order in ``δ = ε − 1`` and σ⁰_hv is ``O(δ⁴)`` — up to the logarithm
of the horizon (``k_z1 → 0`` where ``k_z2 → √δ k``: the branch points merge). A source term
of the kernel wrong at first order in δ would give ``O(δ²)``."""

from __future__ import annotations

import math

import numpy as np
import pytest

import emscatter as em
from emscatter.solvers.iem.crosspol_resummed import backscatter_resummed
from emscatter.solvers.spm.crosspol import backscatter_hv

K = 2 * math.pi
TH = np.radians([20.0, 40.0, 60.0])
DELTAS = np.array([1e-1, 1e-2, 1e-3, 1e-4])


@pytest.mark.parametrize(
    "rough", [em.GaussianCorrelation(0.1 / K, 3 / K), em.ExponentialCorrelation(0.1 / K, 3 / K)]
)
@pytest.mark.parametrize("term", ["spm2", "resummed"])
def test_hv_is_fourth_order_in_the_contrast(rough, term):
    def hv(d):
        if term == "spm2":
            return backscatter_hv(rough, 1 + d, K, TH, n_radial=10, n_azimuth=10)
        return backscatter_resummed(rough, 1 + d, K, TH, n_nodes=10)

    scaled = np.array([hv(d) / d**4 for d in DELTAS])  # (δ, θ)
    assert np.all(scaled > 0)
    step = scaled[1:] / scaled[:-1]  # per decade of δ: a logarithm's growth, not ×100 (δ²)
    assert np.all((step > 1.0) & (step < 2.0)), step
    growth = np.diff(scaled, axis=0) / scaled[0]  # a + b log(1/δ): equal steps per decade
    np.testing.assert_allclose(growth[1:], growth[:-1], rtol=0.35)


@pytest.mark.parametrize("eps", [3 + 1j, 1.2 + 0.05j])
def test_second_order_kernel_is_reciprocal_out_of_the_plane_at_low_contrast(eps):
    """σ⁰⁽²²⁾_qp(i → s) = σ⁰⁽²²⁾_pq(−s → −i) (Tsang, Kong & Ding 2000 vol. I §1.5) at a
    bistatic geometry out of the plane, where no symmetry of the node rule helps: every source
    term of the kernel (h², h∇h, the first-order waves') and both pairings take part. The two
    directions have different node rules: equal to the quadrature's accuracy (8 nodes: seen
    ≤ 6e-7; 16: ≤ 1e-6 at printed precision) at ε = 3 + i, the NMM3D residual's medium."""
    from emscatter.solvers.spm.crosspol import sigma0_22

    rough = em.ExponentialCorrelation(0.26 / K, 3.0 / K)
    ti, ts, ps = math.radians(30.0), math.radians(50.0), math.radians(70.0)
    fwd = sigma0_22(rough, eps, K, ti, ts, ps, 0.0, n_radial=8, n_azimuth=8)
    rev = sigma0_22(rough, eps, K, ts, ti, math.pi, ps + math.pi, n_radial=8, n_azimuth=8)
    np.testing.assert_allclose(fwd, rev.T, rtol=1e-5)
    assert fwd[0, 1] > 0 and fwd[1, 0] > 0
