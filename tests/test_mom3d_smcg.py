"""The SMCG product of the 3-D PEC MFIE (issue 19): Taylor kernels, agreement of the product
and of the solved σ⁰ with the dense reference, energy conservation, bad input."""

import math

import numpy as np
import pytest

from emscatter.solvers import mom3d
from emscatter.solvers.mom3d.operator import assemble, make_patch
from emscatter.solvers.mom3d.smcg import smcg_operator, taylor_kernels
from emscatter.spectra import GaussianCorrelation
from emscatter.surfaces.generate import generate_surface

K = 2 * math.pi  # λ = 1 m
DX = 1 / 8  # 8 points per wavelength


def _patch(size, k_sigma, seed=2):
    n = int(size / DX)
    h = generate_surface(GaussianCorrelation(k_sigma / K, 3 / K), (n, n), DX, rng=seed).heights
    return make_patch(h, DX, DX)


def _rel(a, b):
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


def test_taylor_kernels_sum_to_the_exact_kernel():
    """``Σ_p g_p(ρ) Z^{2p}`` → ``(ikR − 1)e^{ikR}/(4πR³)`` at ``R = √(ρ² + Z²)``, the remainder
    within the docstring's Cauchy bound ``(e ξ/(P+1))^{P+1}``, ``ξ = kZ²/2ρ`` (here ξ = 0.5)."""
    rho, z = 2.5, 0.4
    r = math.hypot(rho, z)
    exact = (1j * K * r - 1) * np.exp(1j * K * r) / (4 * math.pi * r**3)
    g = taylor_kernels(K, np.array([rho]), 8)[:, 0]
    f_rho = abs(taylor_kernels(K, np.array([rho]), 0)[0, 0])
    xi = K * z * z / (2 * rho)
    errs = [abs(np.sum(g[: p + 1] * z ** (2 * np.arange(p + 1))) - exact) for p in range(9)]
    for p, e in enumerate(errs):
        assert e <= 3 * f_rho * (math.e * xi / (p + 1)) ** (p + 1), (p, e)
    assert errs[8] < 1e-9 * abs(exact)
    assert all(b < a for a, b in zip(errs, errs[1:], strict=False))


def test_all_strong_pairs_reproduce_the_dense_matrix():
    """With ``r_d`` beyond the patch diagonal every pair is strong: the sparse part alone is the
    dense matrix of :func:`.operator.assemble` (near-cell correction and J/2 included)."""
    p = _patch(3.0, 1.0)
    dense = assemble(p, K)
    op = smcg_operator(p, K, near_radius=10.0, dtype=np.complex128)
    assert op.strong.nnz == dense.size
    assert np.max(np.abs(op.strong.toarray() - dense)) < 1e-12 * np.max(np.abs(dense))
    v = np.random.default_rng(1).normal(size=2 * p.n) + 0j
    assert _rel(op @ v, dense @ v) < 1e-12


def test_smcg_product_equals_the_dense_product():
    """5λ × 5λ, kσ = 1, kℓ = 3, random vector: relative error of the SMCG product against the
    dense one falls with the Taylor order and is ≤ 1e-3 from order 2 at r_d = 2.5λ.
    Measured (complex128 strong part), r_d = 2.5λ: order 0…4 → 6.3e-3, 7.2e-4, 8.5e-5, 9.3e-6,
    9.5e-7; r_d = 1.5λ: 1.5e-2, 2.6e-3, 5.4e-4, 1.3e-4, 2.9e-5; r_d = 1λ: 2.7e-2 … 2.1e-4."""
    p = _patch(5.0, 1.0)
    dense = assemble(p, K)
    v = np.array([1, 1j]) @ np.random.default_rng(0).normal(size=(2, 2 * p.n))
    ref = dense @ v
    for rd, limits in ((2.5, (1e-2, 1.5e-3, 2e-4, 2e-5)), (1.5, (3e-2, 5e-3, 1e-3, 3e-4))):
        errs = []
        base = smcg_operator(p, K, near_radius=rd, taylor_order=0, dtype=np.complex128)
        for order, lim in enumerate(limits):
            op = base.with_order(order)
            errs.append(_rel(op @ v, ref))
            assert errs[-1] < lim, (rd, order, errs[-1])
        assert all(b < a / 3 for a, b in zip(errs, errs[1:], strict=False)), (rd, errs)
    op = smcg_operator(p, K, near_radius=2.5, taylor_order=2)  # complex64 strong part
    assert _rel(op @ v, ref) < 1e-3


def test_solved_sigma0_equals_the_dense_solution():
    """6λ × 6λ, kσ = 1, θi = 30°: σ⁰ of the SMCG solution (defaults r_d = 2.5λ, order 3) over
    the plane of incidence (θs −80…80°, every pol) within 0.1 dB of the dense solution, energy
    within 1e-4 (measured ≤ 0.0053 dB, energy to 3e-6)."""
    p = _patch(6.0, 1.0, seed=4)
    h = p.z.reshape(p.shape)
    ts = np.radians(np.arange(-80.0, 81.0, 5.0))
    ps, ts = np.where(ts < 0, math.pi, 0.0), np.abs(ts)
    args = (h, DX, K, math.radians(30), ts, ps)
    ref = mom3d.solve_realization(*args, accel="dense")
    fast = mom3d.solve_realization(*args, accel="smcg")
    assert ref["accel"] == "dense" and fast["accel"] == "smcg"
    assert fast["near_radius"] == 2.5 and fast["nonzeros"] > 0
    db = 10 * np.log10(np.abs(fast["amplitude"]) ** 2 / np.abs(ref["amplitude"]) ** 2)
    assert np.max(np.abs(db)) < 0.1
    assert np.allclose(fast["energy"], ref["energy"], atol=1e-4)


def test_flat_plate_is_a_mirror_with_smcg():
    """σ → 0 through the public call with ``accel="smcg"``: energy and coherent reflectivity 1."""
    flat = GaussianCorrelation(1e-9, 3 / K)
    res = mom3d.bistatic(flat, "pec", K, 0.5, [0.0, 0.6], math.pi, realizations=2, length=4.0,
                         accel="smcg", near_radius=1.5)  # fmt: skip
    assert res.info["accel"] == "smcg"
    assert np.allclose(res.info["energy"], 1.0, atol=3e-3)
    assert np.allclose(res.coherent[:, 0], 1.0, atol=3e-3)


@pytest.mark.slow
def test_energy_is_conserved_on_an_8_wavelength_patch():
    """PEC 8λ × 8λ (4096 nodes), Gaussian kσ = 0.3, kℓ = 3, θi = 30°, SMCG defaults: scattered /
    incident power within 1 % for both polarizations (measured: see the benchmark row)."""
    p = _patch(8.0, 0.3, seed=1)
    r = mom3d.solve_realization(p.z.reshape(p.shape), DX, K, math.radians(30), [0.3], [0.0],
                                accel="smcg")  # fmt: skip
    print("8λ SMCG energy", r["energy"], "seconds", r["seconds"], "iterations", r["iterations"])
    assert np.all(np.abs(r["energy"] - 1) < 0.01)
    assert np.all(np.array(r["residual"]) < 1e-4)


def test_bad_inputs_name_the_parameter():
    rough = GaussianCorrelation(0.01, 0.5)
    with pytest.raises(ValueError, match="accel must be one of"):
        mom3d.bistatic(rough, "pec", K, 0.3, 0.3, accel="fmm")
    with pytest.raises(ValueError, match="length=40 m .* SMCG sparse matrix"):
        mom3d.bistatic(rough, "pec", K, 0.3, 0.3, length=40.0)
    p = _patch(3.0, 1.0)
    h = p.z.reshape(p.shape)
    with pytest.raises(ValueError, match="near_radius=0.5 λ is too small for this surface"):
        mom3d.solve_realization(h, DX, K, 0.3, [0.3], [0.0], accel="smcg", near_radius=0.5)
    with pytest.raises(ValueError, match="near_radius must be"):
        mom3d.solve_realization(h, DX, K, 0.3, [0.3], [0.0], accel="smcg", near_radius=-1)
    with pytest.raises(ValueError, match="taylor_order must be an int in 0 … 8"):
        mom3d.solve_realization(h, DX, K, 0.3, [0.3], [0.0], accel="smcg", taylor_order=9)
    with pytest.raises(ValueError, match=r"near_radius=0.2 m must be ≥"):
        smcg_operator(p, K, near_radius=0.2)


def test_auto_takes_smcg_for_large_conducting_patches_only():
    """``accel="auto"``: dense up to SMCG_MIN_NODES nodes, SMCG above (dielectrics:
    tests/test_mom3d_dielsmcg.py);
    the default r_d grows with the surface's peak-to-valley height (Taylor convergence)."""
    from emscatter.solvers.mom3d import model

    assert model._accel_for("auto", model.SMCG_MIN_NODES, True) == "dense"
    assert model._accel_for("auto", model.SMCG_MIN_NODES + 1, True) == "smcg"
    assert model._accel_for("auto", 16, False) == "dense"
    flat, tall = np.zeros((4, 4)), np.array([[0.0, 3.0]])
    assert model._near_radius(None, flat, K) == model.NEAR_RADIUS
    assert model._near_radius(None, tall, K) == pytest.approx(3.0 / model.MAX_PTP_OVER_RD)
