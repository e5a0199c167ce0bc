"""The closed-form GO backscatter (solvers/go_monostatic.py) against the general formula."""

from __future__ import annotations

import math

import numpy as np
import pytest

import emscatter as em
from emscatter.solvers.kirchhoff import go
from emscatter.solvers.kirchhoff import go_backscatter as go_monostatic


@pytest.mark.parametrize("shadowing", [False, True, "separable", "correlated"])
@pytest.mark.parametrize("eps", ["pec", 5 + 0.5j, 17 + 2j, -30 + 5j])
@pytest.mark.parametrize("phi_i", [0.0, 0.7, -2.0])
def test_closed_form_backscatter_equals_the_general_formula(eps, shadowing, phi_i, monkeypatch):
    monkeypatch.setenv("EMSCATTER_KERNELS", "numpy")  # the reference path
    k = 2 * math.pi / 0.05
    rough = em.GaussianCorrelation(0.3 / k * 10, 2.0 / k * 10)
    edges = [0.0, 1e-9, math.pi / 2 - 1e-9, math.pi / 2]
    theta = np.concatenate([edges, np.radians(np.arange(89.5))])
    ref = go.bistatic(rough, eps, k, theta, theta, phi_i + math.pi, phi_i, shadowing=shadowing)
    got = em.backscatter(rough, eps, wavelength=0.05, theta_i=theta, phi_i=phi_i, method="go",
                         shadowing=shadowing, out_of_range="ignore")  # fmt: skip
    assert got.sigma0.shape == ref.sigma0.shape
    peak = ref.sigma0.max()
    np.testing.assert_allclose(got.sigma0, ref.sigma0, rtol=1e-12, atol=1e-14 * peak)
    assert np.all(got.sigma0[0, 1] == 0) and np.all(got.sigma0[1, 0] == 0)
    assert got.info["shadowing"] == ref.info["shadowing"]
    # the coherent part (lazy) is still the general one
    np.testing.assert_allclose(got.coherent, ref.coherent, rtol=1e-12, atol=1e-300)


def test_closed_form_is_used_only_where_it_holds():
    k = 100.0
    theta = np.radians([10.0, 30.0])
    eps = np.array(4.0 + 0j)
    iso = go.geometry(theta, theta, np.array(math.pi), np.array(0.0), eps, 2, checked=True)
    assert go_monostatic.covers(iso, 2, 0.02, 0.02, "smith")
    assert not go_monostatic.covers(iso, 2, 0.02, 0.02, "a new mode")  # no closed form here
    with pytest.raises(ValueError, match="a new mode"):
        go_monostatic.backscatter_sigma0(theta, 4.0, 0.02, "a new mode")
    assert not go_monostatic.covers(iso, 2, 0.02, 0.03, "smith")  # anisotropic slopes
    assert not go_monostatic.covers(iso, 1, 0.02, 0.0, "smith")  # a profile
    off = go.geometry(theta, theta, np.array(3.0), np.array(0.0), eps, 2, checked=True)
    assert not go_monostatic.covers(off, 2, 0.02, 0.02, "smith")  # not the backscatter azimuth
    many = go.geometry(theta, theta, np.array(math.pi), np.array(0.0), np.array([4.0, 5.0 + 0j]),
                       2, checked=True)  # fmt: skip
    assert not go_monostatic.covers(many, 2, 0.02, 0.02, None)  # several permittivities
    # anisotropic slopes through the API still take the general formula and agree with it
    rough = em.GaussianCorrelation(0.1, 1.0, length_y=1.5)
    got = em.backscatter(rough, 4.0, wavelength=2 * math.pi / k, theta_i=theta, phi_i=0.4,
                         method="go", out_of_range="ignore")  # fmt: skip
    ref = go.bistatic(rough, 4.0, k, theta, theta, 0.4 + math.pi, 0.4)
    np.testing.assert_allclose(got.sigma0, ref.sigma0, rtol=1e-12, atol=1e-300)
