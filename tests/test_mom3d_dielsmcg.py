"""The SMCG product of Müller's dielectric equations (issue 19, :mod:`.dielectric_smcg`): the
radial Taylor series, the strong part against the dense matrix, the product and the solved
amplitudes against the dense solver, energy R + T for a lossless medium, bad input."""

import math

import numpy as np
import pytest

from emscatter.solvers import mom3d
from emscatter.solvers.mom3d import model
from emscatter.solvers.mom3d.dielectric import assemble_dielectric
from emscatter.solvers.mom3d.dielectric_model import (
    DIELECTRIC_SMCG_MIN_NODES,
    solve_dielectric_realization,
)
from emscatter.solvers.mom3d.dielectric_smcg import dielectric_smcg_operator, radial_series
from emscatter.solvers.mom3d.operator import make_patch
from emscatter.spectra import GaussianCorrelation
from emscatter.surfaces.generate import generate_surface

K = 2 * math.pi  # λ = 1 m


def _heights(size, eps, k_sigma, seed=5):
    """A Gaussian (kℓ = 3) patch at 8 points per wavelength inside the dielectric."""
    dx = 1.0 / (8 * max(1.0, np.sqrt(complex(eps)).real))
    n = int(round(size / dx))
    rough = GaussianCorrelation(k_sigma / K, 3 / K)
    return generate_surface(rough, (n, n), dx, rng=np.random.default_rng(seed)).heights, dx


def _rel(a, b):
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


def test_radial_series_sums_to_the_lossy_kernel():
    """``Σ_p c_p(ρ) Z^{2p}`` → ``G''(R)`` of the lossy medium (complex ``k₂``), ``R = √(ρ² + Z²)``,
    the error falling with the order (ρ = 0.5λ, Z = 0.15λ: ξ = |k₂|Z²/2ρ ≈ 0.29)."""
    k2 = K * np.sqrt(4 + 0.5j)
    rho, z = 0.5, 0.15
    r = math.hypot(rho, z)
    exact = (2 - 2j * k2 * r - (k2 * r) ** 2) * np.exp(1j * k2 * r) / (4 * math.pi * r**3)
    c = radial_series(k2, {3: 2.0, 2: -2j * k2, 1: -(k2**2)}, np.array([rho]), 8)[:, 0]
    errs = [abs(np.sum(c[: p + 1] * z ** (2 * np.arange(p + 1))) - exact) for p in range(9)]
    assert all(b < a for a, b in zip(errs, errs[1:], strict=False)), errs
    assert errs[8] < 1e-8 * abs(exact)


def test_all_strong_pairs_reproduce_the_dense_matrix():
    """With ``r_d`` beyond the patch diagonal every pair is strong: the sparse part alone is the
    dense Müller matrix (self cell, near-cell correction, unit diagonal included)."""
    h, dx = _heights(1.0, 4 + 0.5j, 0.3)
    p = make_patch(h, dx, dx)
    dense = assemble_dielectric(p, K, 4 + 0.5j)
    op = dielectric_smcg_operator(p, K, 4 + 0.5j, near_radius=10.0, dtype=np.complex128)
    assert op.strong.nnz == dense.size
    assert np.max(np.abs(op.strong.toarray() - dense)) < 1e-12 * np.max(np.abs(dense))


@pytest.mark.parametrize("eps", [4 + 0.5j, 3.0])
def test_product_equals_the_dense_product(eps):
    """1.5λ × 1.5λ, kσ = 0.3, random vector, r_d = 0.5λ: the relative error of the product
    against the dense one falls with the Taylor order and is ≤ 1e-4 from order 3 (here, order
    0…4: 3.7e-3 … 7.7e-8 for ε = 4 + 0.5i, 2.9e-3 … 5.9e-9 for ε = 3). Measured
    (ε = 4 + 0.5i, 3λ, kσ = 0.3) order 0…4: 5.3e-3, 6.0e-4, 7.2e-5, 8.1e-6, 8.4e-7 at
    r_d = 0.5λ; 1.3e-3, 7.1e-5, 4.1e-6, 2.2e-7, 1.1e-8 at 1λ."""
    h, dx = _heights(1.5, eps, 0.3)
    p = make_patch(h, dx, dx)
    dense = assemble_dielectric(p, K, eps)
    v = np.random.default_rng(1).normal(size=4 * p.n) * (1 + 0.5j)
    ref = dense @ v
    op = dielectric_smcg_operator(p, K, eps, near_radius=0.5, taylor_order=0,
                                  dtype=np.complex128)  # fmt: skip
    errs = [_rel(op.with_order(order) @ v, ref) for order in range(5)]
    print("dielectric SMCG product error by order", eps, errs)
    assert all(b < a for a, b in zip(errs, errs[1:], strict=False)), errs
    assert errs[3] < 1e-4


@pytest.mark.parametrize("eps", [4 + 0.5j, 3.0])
def test_solved_amplitudes_equal_the_dense_solution(eps):
    """1.25λ patch, kσ = 0.3, θi = 30°: SMCG and dense solves give the same amplitudes to
    the GMRES tolerance (1e-6), the same reflectivity and, lossless, the same R + T to 1e-4
    (on this small patch the discretization and taper put it at 0.978/0.995 with either
    product: within 2.5 % of 1). Measured on 2λ patches (kσ 0.15/0.3): amplitudes
    within 3e-6 (ε = 3) and 8e-7 (ε = 4 + 0.5i) of the largest, σ⁰ within 1e-4 dB in the
    lobes, R + T 0.9939/0.9925 with both (ε = 3, kσ = 0.3)."""
    h, dx = _heights(1.25, eps, 0.3)
    ts = np.radians(np.linspace(0, 80, 9))
    ts, ps = np.concatenate([ts, ts]), np.repeat([0.0, math.pi], 9)
    out = {
        acc: solve_dielectric_realization(
            h, dx, K, eps, math.radians(30), ts, ps, accel=acc, tol=1e-6
        )  # fmt: skip
        for acc in ("dense", "smcg")
    }
    a, b = out["dense"]["amplitude"], out["smcg"]["amplitude"]
    assert out["smcg"]["accel"] == "smcg" and out["dense"]["accel"] == "dense"
    assert np.max(np.abs(a - b)) < 2e-5 * np.max(np.abs(a))
    assert np.allclose(out["smcg"]["reflectivity"], out["dense"]["reflectivity"], rtol=1e-4)
    assert out["smcg"]["matrix_bytes"] < out["dense"]["matrix_bytes"]
    if np.isreal(eps):
        e_s = out["smcg"]["reflectivity"] + out["smcg"]["transmissivity"]
        e_d = out["dense"]["reflectivity"] + out["dense"]["transmissivity"]
        assert np.allclose(e_s, e_d, atol=1e-4) and np.all(np.abs(e_s - 1) < 0.025), (e_s, e_d)


def test_bistatic_selects_the_dielectric_smcg():
    """``bistatic(..., accel="smcg")`` on a dielectric runs the SMCG product (recorded in
    ``info``) and gives the dense run's σ⁰, coherent power and energy for the same seeds
    (a 1λ patch: its R + T, 0.95–0.97, is the small patch's, the same with either)."""
    rough = GaussianCorrelation(0.15 / K, 3 / K)
    res = {
        acc: mom3d.bistatic(rough, 3.0, K, 0.5, [0.2, 0.5, 0.8], [0.0, 0.0, math.pi],
                            realizations=2, seed=1, length=1.0, accel=acc, tol=1e-6)
        for acc in ("dense", "smcg")
    }  # fmt: skip
    assert res["smcg"].info["accel"] == "smcg" and res["dense"].info["accel"] == "dense"
    assert np.allclose(res["smcg"].sigma0, res["dense"].sigma0, rtol=1e-3)
    assert np.allclose(res["smcg"].coherent, res["dense"].coherent, rtol=1e-4)
    assert np.allclose(res["smcg"].info["energy"], res["dense"].info["energy"], atol=1e-4)


def test_auto_takes_the_dielectric_smcg_above_its_crossover():
    assert model._accel_for("auto", DIELECTRIC_SMCG_MIN_NODES, False) == "dense"
    assert model._accel_for("auto", DIELECTRIC_SMCG_MIN_NODES + 1, False) == "smcg"
    assert model._accel_for("smcg", 10, False) == "smcg"


def test_bad_inputs_name_the_parameter():
    h, dx = _heights(1.0, 4 + 0.5j, 0.3)
    args = (h, dx, K, 4 + 0.5j, 0.3, [0.3], [0.0])
    with pytest.raises(ValueError, match="accel must be one of"):
        solve_dielectric_realization(*args, accel="fmm")
    with pytest.raises(ValueError, match="taylor_order must be an int in 0 … 8"):
        solve_dielectric_realization(*args, accel="smcg", taylor_order=9)
    with pytest.raises(ValueError, match="near_radius must be"):
        solve_dielectric_realization(*args, accel="smcg", near_radius=-1)
    with pytest.raises(ValueError, match="too small for this surface"):
        solve_dielectric_realization(h * 40, dx, K, 4 + 0.5j, 0.3, [0.3], [0.0], accel="smcg",
                                     near_radius=0.5)  # fmt: skip
    with pytest.raises(ValueError, match="taylor_order must be an int"):
        dielectric_smcg_operator(make_patch(h, dx, dx), K, 3.0, near_radius=0.5).with_order(-1)
    with pytest.raises(ValueError, match=r"near_radius=0.01 m must be ≥"):
        dielectric_smcg_operator(make_patch(h, dx, dx), K, 4 + 0.5j, near_radius=0.01)
    rough = GaussianCorrelation(0.01, 0.5)
    with pytest.raises(ValueError, match="dielectric SMCG sparse matrix"):
        mom3d.bistatic(rough, 15 + 2j, K, 0.3, 0.3, length=30.0, accel="smcg")
