"""``Scattering.from_geometry``: the fields it fills from a checked geometry equal the ones the
solvers passed by hand before (same arrays, no copy), a lazy coherent part stays lazy, a
sigma0 of the wrong shape is refused with both shapes named, and the three solvers that build
their result this way (IEM, Kirchhoff PO and GO) return their geometry's angles and dimension."""

from __future__ import annotations

import numpy as np
import pytest

from emscatter.scattering import Scattering
from emscatter.solvers.iem import model as iem
from emscatter.solvers.kirchhoff import go, po
from emscatter.solvers.kirchhoff.common import geometry
from emscatter.spectra import GaussianCorrelation

TI = np.deg2rad([[10.0], [30.0], [50.0]])  # (3, 1)
TS = np.deg2rad([0.0, 20.0, 40.0, 60.0])  # (4,)  -> shape (3, 4)


def _geometry(dim=2):
    return geometry(TI, TS, np.pi, 0.0, 3.2 + 0.1j, dim)


def test_fields_from_the_geometry_equal_the_hand_built_result():
    g = _geometry()
    sig = np.random.default_rng(1).random((2, 2, *g.shape))
    coh = np.random.default_rng(2).random((2, *g.shape))
    info = {"rtol": 1e-6}
    a = Scattering.from_geometry(g, sigma0=sig, coherent=coh, method="x", k=2.0, info=info)
    b = Scattering(
        sigma0=sig, coherent=coh, method="x", theta_i=g.theta_i, theta_s=g.theta_s,
        phi_s=g.phi_s, phi_i=g.phi_i, k=2.0, dimension=2, info=info,
    )  # fmt: skip
    for name in ("sigma0", "coherent", "theta_i", "theta_s", "phi_s", "phi_i"):
        assert getattr(a, name) is getattr(b, name), name  # stored as given: no copy
    assert (a.method, a.k, a.dimension, a.info) == (b.method, b.k, b.dimension, b.info)
    assert a.shape == (3, 4) and a.theta_i.shape == (3, 4)
    np.testing.assert_array_equal(a.theta_s[1], TS)
    assert Scattering.from_geometry(g, sigma0=sig, coherent=coh, method="x", k=2.0).info == {}


def test_dimension_from_the_geometry_or_given_and_lazy_coherent_kept():
    g1 = geometry(TI, TS, 0.0, 0.0, 3.2 + 0.1j, 1)
    sig = np.zeros((2, 2, *g1.shape))
    calls = []

    def coherent():
        calls.append(1)
        return np.ones((2, *g1.shape))

    r = Scattering.from_geometry(g1, sigma0=sig, coherent=coherent, method="x", k=1.0)
    assert r.dimension == 1 and not r.coherent_computed and not calls
    assert r.coherent.shape == (2, 3, 4) and calls == [1]
    r2 = Scattering.from_geometry(
        g1, sigma0=sig, coherent=np.ones((2, 3, 4)), method="x", k=1.0, dimension=2
    )
    assert r2.dimension == 2


def test_wrong_sigma0_shape_is_refused_with_both_shapes():
    g = _geometry()
    with pytest.raises(
        ValueError, match=r"sigma0 must have the shape .*\(2, 2, 3, 4\).*\(2, 3, 4\)"
    ):
        Scattering.from_geometry(
            g, sigma0=np.zeros((2, 3, 4)), coherent=np.zeros((2, 3, 4)), method="x", k=1.0
        )


@pytest.mark.parametrize(
    ("solver", "method"), [(iem, "iem"), (po, "kirchhoff-po"), (go, "kirchhoff-go")]
)
def test_solvers_return_their_geometry(solver, method):
    rough = GaussianCorrelation(sigma=0.02, length=0.2)  # kσ = 0.13 (IEM), PO/GO run anyway
    k = 2 * np.pi / 0.3
    res = solver.bistatic(rough, 3.2 + 0.1j, k, TI, TS, np.pi, 0.0)
    g = _geometry()
    assert res.method == method and res.dimension == 2 and res.shape == g.shape
    for name in ("theta_i", "theta_s", "phi_s", "phi_i"):
        np.testing.assert_array_equal(getattr(res, name), getattr(g, name), err_msg=name)
    assert np.all(np.isfinite(res.sigma0)) and np.all(res.sigma0 >= 0.0)
