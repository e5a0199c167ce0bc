"""The compiled second-order SPM backscatter cross-pol
(:mod:`emscatter.solvers.spm.kernel_crosspol`, issue 20's speed target) against its numpy
reference (``crosspol._backscatter_hv_numpy``): the same nodes, partners and kernel, so the same
σ⁰⁽²²⁾_hv to rounding; and the switch that forces the reference."""

from __future__ import annotations

import math

import numpy as np
import pytest

from emscatter.solvers.spm import compiled, crosspol
from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation

pytest.importorskip("numba")
K = 2 * math.pi
ANGLES = np.radians([0.0, 0.05, 5.0, 20.0, 40.0, 55.0, 70.0, 85.0, 89.9])


@pytest.mark.parametrize(
    "rough, eps, phi_i",
    [
        (ExponentialCorrelation(0.13 / K, 0.5 / K), 3.0, 0.0),  # issue 20's grid corners
        (ExponentialCorrelation(0.3 / K, 20 / K), 30 + 3j, 0.0),
        (GaussianCorrelation(0.1 / K, 3 / K), 10 + 1j, 0.0),  # upper half plane
        (GaussianCorrelation(0.1 / K, 1 / K, length_y=2 / K), 3 + 0.5j, 0.4),  # whole plane
        (ExponentialCorrelation(0.1 / K, 2 / K, length_y=5 / K), 6 + 2j, 1.1),
        (ExponentialCorrelation(0.1 / K, 4 / K), 80 + 20j, 2.5),  # sea water-like, rotated
        (GaussianCorrelation(0.2 / K, 12 / K), 1.5 + 0.01j, 0.0),  # long ℓ, low contrast
    ],
)
def test_compiled_backscatter_hv_is_the_numpy_reference(rough, eps, phi_i, monkeypatch):
    """Every angle of the call in one jitted loop; ≤ 1e-10 relative (seen: ~4e-15)."""
    monkeypatch.setenv("EMSCATTER_KERNELS", "numba")
    for n in (6, 9):
        got = compiled.spm2_backscatter_hv(rough, complex(eps), K, ANGLES, phi_i, n, n)
        assert got is not None and np.all(np.isfinite(got)) and np.all(got > 0)
        ref = crosspol._backscatter_hv_numpy(rough, complex(eps), K, ANGLES, phi_i, n, n)
        np.testing.assert_allclose(got, ref, rtol=1e-10, atol=0.0)
        # the public entry takes the compiled path and returns the same
        pub = crosspol.backscatter_hv(rough, eps, K, ANGLES, phi_i, n_radial=n, n_azimuth=n)
        np.testing.assert_array_equal(pub, got)


def test_fourth_order_in_sigma_and_reciprocal_call_shapes(monkeypatch):
    """σ⁰⁽²²⁾ ∝ σ⁴ exactly (the kernel is σ-free); repeated and unsorted angles map back."""
    monkeypatch.setenv("EMSCATTER_KERNELS", "numba")
    a, b = ExponentialCorrelation(0.1 / K, 5 / K), ExponentialCorrelation(0.3 / K, 5 / K)
    th = np.radians([[40.0, 10.0], [40.0, 60.0]])
    hv_a = crosspol.backscatter_hv(a, 10 + 1j, K, th, n_radial=6, n_azimuth=6)
    hv_b = crosspol.backscatter_hv(b, 10 + 1j, K, th, n_radial=6, n_azimuth=6)
    assert hv_a.shape == th.shape and hv_a[0, 0] == hv_a[1, 0]
    np.testing.assert_allclose(hv_b, 81.0 * hv_a, rtol=1e-12)


def test_numpy_switch_forces_the_reference(monkeypatch):
    rough = GaussianCorrelation(0.1 / K, 3 / K)
    monkeypatch.setenv("EMSCATTER_KERNELS", "numpy")
    assert compiled.spm2_backscatter_hv(rough, 3 + 0j, K, ANGLES, 0.0, 6, 6) is None
    ref = crosspol.backscatter_hv(rough, 3.0, K, ANGLES[:3], n_radial=6, n_azimuth=6)
    monkeypatch.setenv("EMSCATTER_KERNELS", "numba")
    np.testing.assert_allclose(
        crosspol.backscatter_hv(rough, 3.0, K, ANGLES[:3], n_radial=6, n_azimuth=6), ref,
        rtol=1e-10)  # fmt: skip
    # a correlation the kernel does not cover stays on the reference
    from emscatter.spectra import PowerLawCorrelation

    assert compiled.spm2_backscatter_hv(PowerLawCorrelation(0.1 / K, 3 / K, hurst=0.8),
                                        3 + 0j, K, ANGLES, 0.0, 6, 6) is None  # fmt: skip
