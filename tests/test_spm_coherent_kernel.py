"""The compiled second-order coherent amplitudes (:mod:`emscatter.solvers.spm.kernel_coherent`,
issue 22: 77 % of an SPM emissivity call) against the numpy reference they replace
(``second_order._second_order_R_numpy``, kept): the same nodes and the same boundary-value
arithmetic, so R⁽⁰⁾, R⁽²⁾, T⁽⁰⁾, T⁽²⁾ agree to rounding (≤ 1e-10 relative; seen ≤ 1.1e-12);
the public coherent reflectivity takes the compiled path; the node memo; the numpy switch."""

from __future__ import annotations

import math

import numpy as np
import pytest

from emscatter.solvers.spm import second_order as so
from emscatter.solvers.spm.first_order import coherent_reflectivity
from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation, PowerLawCorrelation

pytest.importorskip("numba")
K = 2 * math.pi / 0.1
ANGLES = np.radians([0.0, 0.05, 10.0, 30.0, 50.0, 70.0, 85.0, 89.0])


def _rel(a, b):
    """Largest elementwise relative difference (|a| = 0 entries compared absolutely)."""
    a, b = np.asarray(a), np.asarray(b)
    scale = np.where(np.abs(a) > 0, np.abs(a), 1.0)
    return float(np.max(np.abs(a - b) / scale))


CASES = [
    (GaussianCorrelation(0.1 / K, 2.0 / K), 17 + 2j, None, None),
    (GaussianCorrelation(0.1 / K, 2.0 / K), "pec", None, None),
    (GaussianCorrelation(0.05 / K, 8.0 / K), 3.0 + 0j, 3 * K, None),  # lossless, cut
    (GaussianCorrelation(0.05 / K, 1.0 / K), -18 + 0.5j, None, None),  # metal: plasmon pole
    (ExponentialCorrelation(0.1 / K, 2.0 / K), 17 + 2j, None, None),  # log-stretched tails
    (ExponentialCorrelation(0.1 / K, 2.0 / K), "pec", 10 * K, None),
    (ExponentialCorrelation(0.1 / K, 3.0 / K, length_y=6.0 / K), 6 + 2j, None, 0.7),  # aniso
    (GaussianCorrelation(0.1 / K, 20.0 / K, dimension=1), 17 + 2j, None, None),  # 1-D profile
    (ExponentialCorrelation(0.1 / K, 5.0 / K, dimension=1), "pec", 4 * K, None),
    (PowerLawCorrelation(0.1 / K, 3.0 / K, hurst=0.8), 10 + 1j, None, None),
]


@pytest.mark.parametrize("rough, eps, k_max, phi_i", CASES)
def test_compiled_amplitudes_are_the_numpy_reference(rough, eps, k_max, phi_i, monkeypatch):
    monkeypatch.setenv("EMSCATTER_KERNELS", "numba")
    e = eps if eps == "pec" else complex(eps)
    phis = None if phi_i is None else np.full(ANGLES.size, phi_i)
    ref = so._second_order_R_numpy(rough, e, K, ANGLES, 16, 16, True, phis, k_max)
    got = so._compiled_R(rough, e, K, ANGLES, 16, 16, phis, k_max)
    assert got is not None
    for name, a, b in zip(("R0", "R2", "T0", "T2"), ref, got, strict=True):
        assert np.all(np.isfinite(b)), name
        assert _rel(a, b) <= 1e-10, (name, _rel(a, b))
    assert np.any(np.abs(ref[1]) > 0)  # R⁽²⁾ is not trivially zero
    # the dispatching entry returns the compiled values (R0, R2; with T0, T2 on request)
    two = so._second_order_R(rough, e, K, ANGLES, 16, 16, phi_i=phis, k_max=k_max)
    assert len(two) == 2 and np.array_equal(two[1], got[1])


def test_public_coherent_reflectivity_unchanged(monkeypatch):
    """|R⁽⁰⁾|² + 2 Re(R⁽⁰⁾* R⁽²⁾) through the public function, numba against numpy."""
    rough = ExponentialCorrelation(0.1 / K, 2.0 / K)
    th = np.radians(np.linspace(0.0, 85.0, 70))  # ≥ 64 angles: compiled even before loading
    monkeypatch.setenv("EMSCATTER_CACHE", "0")
    monkeypatch.setenv("EMSCATTER_KERNELS", "numpy")
    ref = coherent_reflectivity(rough, 17 + 2j, K, th)
    monkeypatch.setenv("EMSCATTER_KERNELS", "auto")
    got = coherent_reflectivity(rough, 17 + 2j, K, th)
    assert _rel(ref, got) <= 1e-10
    # in h the rough surface reflects less coherently than the flat one (energy to σ⁰; v
    # near the Brewster angle may exceed the flat |R_v|², which is small there)
    flat = coherent_reflectivity(rough, 17 + 2j, K, th, order=0)
    assert np.all(got[0] < flat[0])


def test_nodes_memoized_and_read_only(monkeypatch):
    monkeypatch.setenv("EMSCATTER_KERNELS", "numba")
    rough = GaussianCorrelation(0.1 / K, 2.0 / K)
    so._angle_nodes.cache_clear()
    a = so._compiled_R(rough, 17 + 2j, K, ANGLES[:3], 16, 16, None, None)
    info = so._angle_nodes.cache_info()
    b = so._compiled_R(rough, 17 + 2j, K, ANGLES[:3], 16, 16, None, None)
    assert so._angle_nodes.cache_info().hits == info.hits + 3
    assert all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))
    kx, _, wt = so._angle_nodes(rough, 17 + 2j, K, float(ANGLES[1]), 16, 16, 0.0, None)
    with pytest.raises(ValueError):
        wt[0] = 1.0
    assert kx.size == wt.size > 0


def test_numpy_switch_and_small_calls_take_the_reference(monkeypatch):
    rough = GaussianCorrelation(0.1 / K, 2.0 / K)
    monkeypatch.setenv("EMSCATTER_KERNELS", "numpy")
    assert so._compiled_R(rough, 17 + 2j, K, ANGLES, 16, 16, None, None) is None
    assert so._compiled_R(rough, 17 + 2j, K, ANGLES[:0], 16, 16, None, None) is None
