"""The compiled resummed backscatter cross-pol
(:mod:`emscatter.solvers.iem.kernels.crosspol_resummed`, issue 20's speed target) against its
numpy reference (``crosspol_resummed._numpy``: the whole-plane node rule, both kernel
polarizations, the series by ``kirchhoff.po.series_sum``): the same σ⁰_hv to rounding, and the
switch that forces the reference."""

from __future__ import annotations

import math

import numpy as np
import pytest

import emscatter as em
from emscatter.solvers.iem import crosspol_resummed as cr

pytest.importorskip("numba")
K = 2 * math.pi
ANGLES = np.radians([0.05, 20.0, 40.0, 70.0])


@pytest.mark.parametrize(
    "rough, eps, phi_i",
    [
        (em.ExponentialCorrelation(0.13 / K, 0.5 / K), 3 + 1j, 0.0),  # NMM3D grid corners
        (em.ExponentialCorrelation(1.32 / K, 20 / K), 30 + 3j, 0.0),
        (em.GaussianCorrelation(1.3 / K, 6.0 / K), 15 + 2j, 0.0),  # upper half plane
        (em.GaussianCorrelation(0.8 / K, 4.0 / K, length_y=6.0 / K), 9 + 2.5j, 0.4),  # whole
        (em.ExponentialCorrelation(2.5 / K, 3.0 / K, length_y=5.0 / K), 6 + 2j, 1.1),
        (em.GaussianCorrelation(0.5 / K, 25.0 / K), 1.5 + 0.01j, 0.0),  # K ≳ 55: underflow
    ],
)
def test_compiled_resummed_is_the_numpy_reference(rough, eps, phi_i, monkeypatch):
    """≤ 1e-10 relative (seen: ≤ 5e-14 at 16 nodes); the public entry takes the compiled path."""
    monkeypatch.setenv("EMSCATTER_KERNELS", "numba")
    th = ANGLES[K * rough.sigma * np.cos(ANGLES) <= cr.MAX_KSIGMA_COS]
    got = cr._compiled(rough, complex(eps), K, th, phi_i, 8, 8)
    assert got is not None and np.all(np.isfinite(got)) and np.all(got > 0)
    ref = cr._numpy(rough, complex(eps), K, th, phi_i, 8, 8)
    np.testing.assert_allclose(got, ref, rtol=1e-10, atol=0.0)  # hv and vh (= hv)
    pub = cr.backscatter_resummed(rough, eps, K, th, phi_i, n_nodes=8)
    np.testing.assert_array_equal(pub, got[0])
    # radial and azimuth counts apart (auto's 10 × 8 rule): the same agreement
    got = cr._compiled(rough, complex(eps), K, th, phi_i, 10, 6)
    ref = cr._numpy(rough, complex(eps), K, th, phi_i, 10, 6)
    np.testing.assert_allclose(got, ref, rtol=1e-10, atol=0.0)
    pub = cr.backscatter_resummed(rough, eps, K, th, phi_i, n_nodes=10, n_azimuth=6)
    np.testing.assert_array_equal(pub, got[0])


def test_fourth_order_small_roughness_and_call_shapes(monkeypatch):
    """At Q → 0 the height series is the spectrum (T̂ → w): the compiled term tends to the
    compiled σ⁰⁽²²⁾ (relative O(Q)); repeated and unsorted angles map back."""
    from emscatter.solvers.spm.crosspol import backscatter_hv

    monkeypatch.setenv("EMSCATTER_KERNELS", "numba")
    rough = em.ExponentialCorrelation(0.01 / K, 3.0 / K)
    th = np.radians([[40.0, 10.0], [40.0, 60.0]])
    a = cr.backscatter_resummed(rough, 10 + 1j, K, th, n_nodes=8)
    b = backscatter_hv(rough, 10 + 1j, K, th, n_radial=8, n_azimuth=8)
    assert a.shape == th.shape and a[0, 0] == a[1, 0]
    np.testing.assert_allclose(a, b, rtol=3e-4)  # Q ≤ 1e-4
    assert np.all(a < b)  # e^{−Q} and the broadening lower it


def test_numpy_switch_forces_the_reference(monkeypatch):
    rough = em.GaussianCorrelation(0.3 / K, 3.0 / K)
    monkeypatch.setenv("EMSCATTER_KERNELS", "numpy")
    assert cr._compiled(rough, 3 + 0.1j, K, ANGLES, 0.0, 6, 6) is None
    monkeypatch.setenv("EMSCATTER_KERNELS", "numba")
    fast = cr.backscatter_resummed(rough, 3 + 0.1j, K, ANGLES[1], n_nodes=6)
    monkeypatch.setenv("EMSCATTER_KERNELS", "numpy")
    slow = cr.backscatter_resummed(rough, 3 + 0.1j, K, ANGLES[1], n_nodes=6)
    np.testing.assert_allclose(fast, slow, rtol=1e-10)


#: σ⁰_hv of the compiled kernel before issue 20's second speed pass (main at 6b1f311: the
#: complex Fourier evaluation ``Σ c_m e^{imψ}`` and one division per series term), at auto's
#: 10 × 8 rule: (spectrum, kσ, kℓₓ, kℓᵧ, φ, ε, θ [deg], σ⁰_hv). The cos/sin form and the
#: grouped series divisions round differently (seen ≤ 7e-15 relative over issue 20's grid
#: and a 3780-value box of both spectra): 1e-12 asserted.
_BEFORE = [
    ("exp", 0.13, 0.5, 0.5, 0.0, 3.0 + 0j, 40.0, 2.1397002700682094e-06),
    ("exp", 0.5, 3.0, 3.0, 0.0, 10 + 1j, 40.0, 0.0023108943233742514),
    ("exp", 1.32, 20.0, 20.0, 0.0, 30 + 3j, 40.0, 0.012048958079825626),
    ("exp", 2.5, 5.0, 5.0, 0.0, 3 + 1j, 20.0, 0.0226876125444019),
    ("exp", 1.2, 3.0, 6.0, 0.7, 30 + 3j, 55.0, 0.056582931963945975),  # whole plane
    ("exp", 0.8, 8.0, 2.0, 0.0, 3 + 1j, 30.0, 0.0008776820444036318),
    ("gauss", 0.5, 3.0, 3.0, 0.0, 10 + 1j, 40.0, 0.001168263174086834),
    ("gauss", 1.2, 8.0, 2.0, 0.0, 30 + 3j, 60.0, 8.521217291708849e-07),
    ("gauss", 2.5, 5.0, 5.0, 1.1, 3 + 1j, 25.0, 0.03333189885997065),
]


@pytest.mark.parametrize("case", _BEFORE)
def test_kernel_keeps_the_previous_values(case):
    """The faster kernel (cos/sin Fourier form, four series terms per division) gives the
    previous kernel's σ⁰_hv to 1e-12, on the array path and both one-angle paths (the same
    value to the bit)."""
    from emscatter.solvers.iem.kernels import crosspol_resummed as kern

    name, ks, kl, kly, phi, eps, deg, before = case
    spec = kern.EXPONENTIAL if name == "exp" else kern.GAUSSIAN
    th = math.radians(deg)
    v, done = kern.backscatter_resummed(np.array([th]), eps, K, ks / K, kl / K, kly / K, phi,
                                        spec, 10, n_azimuth=8)  # fmt: skip
    assert done[0]
    assert abs(v[0] - before) <= 1e-12 * before
    prep = kern.prepare_one(th, eps, K, kl / K, kly / K, phi, spec, 10, 8)
    assert kern.evaluate_one(prep, th, K, ks / K, kl / K, kly / K, spec) == v[0]
    # the fused one-angle call (reused scratch): the same double and the same remembered part
    one, part = kern.value_one(th, eps, K, ks / K, kl / K, kly / K, phi, spec, 10, 8)
    assert one == v[0]
    for a, b in zip(part, prep, strict=True):
        np.testing.assert_array_equal(a, b)
        assert not a.flags.writeable
