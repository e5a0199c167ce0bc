"""The memories behind ``auto``'s backscatter hv at its issue-20 speed: the σ-independent node
parts of the resummed term (``iem.crosspol_resummed._PREP``: bounded, a hit equal to a
recompute bit for bit, a different ε / θ / ℓ a miss, a different σ a hit) and the one-geometry
fast path of :func:`emscatter.solvers.auto_crosspol.supplement` (the array path's value to the
bit), with the numpy reference as the fallback (equal to rounding)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import emscatter as em
from emscatter.solvers import auto_crosspol
from emscatter.solvers.iem import crosspol_resummed as cr

pytest.importorskip("numba")
K = 2 * math.pi
T40 = math.radians(40.0)
NODES = (auto_crosspol.RESUMMED_NODES, auto_crosspol.RESUMMED_AZIMUTH_NODES)


@pytest.fixture(autouse=True)
def _fresh(monkeypatch):
    monkeypatch.setenv("EMSCATTER_KERNELS", "numba")
    auto_crosspol.clear_cache()
    yield
    auto_crosspol.clear_cache()


@pytest.mark.parametrize(
    "rough, eps, phi",
    [
        (em.ExponentialCorrelation(0.5 / K, 3.0 / K), 10 + 1j, 0.0),  # half plane
        (em.GaussianCorrelation(0.4 / K, 2.0 / K, length_y=3.0 / K), 6 + 0.5j, 0.7),  # whole
    ],
)
def test_node_memory_hit_is_the_recompute_bit_for_bit(rough, eps, phi):
    cold = cr._value_one(rough, complex(eps), K, T40, phi, *NODES)
    assert len(cr._PREP) == 1 and cold > 0
    hit = cr._value_one(rough, complex(eps), K, T40, phi, *NODES)
    assert hit == cold and len(cr._PREP) == 1
    # the array path (the compiled kernel over several angles) gives the same double
    arr = cr._values(rough, complex(eps), K, np.array([0.3, T40]), phi, *NODES)
    assert arr[0, 1] == cold and arr[1, 1] == cold
    # a new σ at the same (ε, θ, ℓ): a hit, and the value of a cold computation
    other = type(rough)(2.0 * rough.sigma, rough.length, length_y=rough.length_y)
    warm = cr._value_one(other, complex(eps), K, T40, phi, *NODES)
    assert len(cr._PREP) == 1 and warm != cold
    cr.clear_memory()
    assert cr._value_one(other, complex(eps), K, T40, phi, *NODES) == warm
    # the numpy reference (no numba path): equal to rounding
    ref = cr._numpy(other, complex(eps), K, np.array([T40]), phi, *NODES)[0, 0]
    np.testing.assert_allclose(warm, ref, rtol=1e-10)


def test_different_eps_theta_or_length_misses():
    rough = em.ExponentialCorrelation(0.3 / K, 4.0 / K)
    a = cr._value_one(rough, 10 + 1j, K, T40, 0.0, *NODES)
    b = cr._value_one(rough, 10 + 1.5j, K, T40, 0.0, *NODES)  # ε differs in Im only
    c = cr._value_one(rough, 10 + 1j, K, T40 + 1e-9, 0.0, *NODES)
    d = cr._value_one(em.ExponentialCorrelation(0.3 / K, 4.5 / K), 10 + 1j, K, T40, 0.0, *NODES)
    assert len(cr._PREP) == 4 and len({a, b, c, d}) == 4
    assert abs(c / a - 1) < 1e-6  # (a neighbouring angle: its own nodes, nearly the value)


def test_node_memory_is_bounded_least_recent_out(monkeypatch):
    monkeypatch.setattr(cr, "_PREP_SIZE", 3)
    rough = em.ExponentialCorrelation(0.3 / K, 4.0 / K)
    for e in (3.0, 4.0, 5.0, 6.0):
        cr._value_one(rough, complex(e), K, T40, 0.0, *NODES)
    assert len(cr._PREP) == 3
    eps_kept = [key[3] for key in cr._PREP]
    assert eps_kept == [4.0, 5.0, 6.0]  # the first one out
    cr._value_one(rough, 4.0 + 0j, K, T40, 0.0, *NODES)  # a hit moves to the end
    cr._value_one(rough, 7.0 + 0j, K, T40, 0.0, *NODES)
    assert [key[3] for key in cr._PREP] == [6.0, 4.0, 7.0]


@pytest.mark.parametrize("name", ["spm", "po", "go", auto_crosspol.IEM_BACKSCATTER])
def test_one_geometry_fast_path_is_the_array_path(name):
    """One angle (scalars or size-1 arrays) takes the fast path; two copies of it take the
    array path: the same hv to the bit, in the caller's shape."""
    rough = em.ExponentialCorrelation(0.6 / K, 5.0 / K)
    eps = 15 + 2j
    one = auto_crosspol.supplement(name, rough, eps, K, T40, T40, math.pi, 0.0)
    assert one[1] == auto_crosspol.RESUMMED and np.shape(one[0]) == ()
    auto_crosspol.clear_cache()
    two = np.full(2, T40)
    arr = auto_crosspol.supplement(name, rough, eps, K, two, two, two * 0 + math.pi, two * 0)
    assert arr[1] == auto_crosspol.RESUMMED
    assert arr[0][0] == arr[0][1] == float(one[0]) > 0
    col = auto_crosspol.supplement(name, rough, eps, K, np.array([[T40]]), T40, math.pi, 0.0)
    assert col[0].shape == (1, 1) and col[0][0, 0] == float(one[0])
    # 0-d and size-1 arrays mixed, ε as a numpy scalar or a 0-d array: the same value
    for e in (np.complex128(eps), np.array(eps)):
        mix = auto_crosspol.supplement(name, rough, e, K, np.array(T40), np.array([T40]),
                                       np.float64(math.pi), np.zeros((1, 1, 1)))  # fmt: skip
        assert mix[0].shape == (1, 1, 1) and mix[0].ravel()[0] == float(one[0])
    # off backscatter, the fast path steps aside: nothing added in the plane
    off = auto_crosspol.supplement(name, rough, eps, K, T40, T40 + 0.1, math.pi, 0.0)
    assert off == (None, None)


def test_values_memory_clear_keeps_nodes_on_request():
    rough = em.ExponentialCorrelation(0.4 / K, 2.0 / K)
    em.backscatter(rough, 10 + 1j, wavelength=1.0, theta_i=T40)
    assert len(cr._PREP) >= 1
    auto_crosspol.clear_cache(nodes=False)
    assert len(cr._PREP) >= 1 and not auto_crosspol._CACHE
    auto_crosspol.clear_cache()
    assert not cr._PREP


def test_numpy_backend_takes_the_reference_and_no_memory(monkeypatch):
    rough = em.ExponentialCorrelation(0.5 / K, 3.0 / K)
    fast = cr._value_one(rough, 10 + 1j, K, T40, 0.0, *NODES)
    cr.clear_memory()
    monkeypatch.setenv("EMSCATTER_KERNELS", "numpy")
    slow = cr._value_one(rough, 10 + 1j, K, T40, 0.0, *NODES)
    assert not cr._PREP  # (the numpy path keeps no node parts)
    assert slow == cr._numpy(rough, 10 + 1j, K, np.array([T40]), 0.0, *NODES)[0, 0]
    np.testing.assert_allclose(fast, slow, rtol=1e-10)
