import math

import numpy as np
import pytest

from emscatter.fresnel import fresnel, reflectivity


def test_normal_incidence_glass():
    # n = 1.5 (ε = 2.25): R = ((1 − n)/(1 + n))² = 0.04 (Born & Wolf §1.5)
    np.testing.assert_allclose(reflectivity(2.25, 0.0), [0.04, 0.04], rtol=1e-12)


def test_brewster_angle_zero_tm():
    eps = 4.0
    _, rv = fresnel(eps, math.atan(math.sqrt(eps)))
    assert abs(rv) < 1e-12


def test_lossless_energy_balance():
    eps, th = 3.2, np.radians(np.linspace(0, 89, 30))
    rh, rv = fresnel(eps, th)
    c, root = np.cos(th), np.sqrt(eps - np.sin(th) ** 2)
    th_ = 2 * c / (c + root)
    tv = 2 * np.sqrt(eps) * c / (eps * c + root)  # T_v = 4εc√(ε−s²)/(εc+√(ε−s²))²
    np.testing.assert_allclose(np.abs(rh) ** 2 + np.abs(th_) ** 2 * root / c, 1, rtol=1e-12)
    np.testing.assert_allclose(np.abs(rv) ** 2 + np.abs(tv) ** 2 * root / c, 1, rtol=1e-12)


@pytest.mark.parametrize("eps", [1e7j, -50 + 2j, -50.0, 17 + 2j, 1.01, 1.0])
def test_bounded_and_finite(eps):
    th = np.radians(np.linspace(0, 90, 91))
    r = reflectivity(eps, th)
    assert np.all(np.isfinite(r)) and np.all(r <= 1 + 1e-12) and np.all(r >= 0)


def test_large_eps_tends_to_pec():
    rh, rv = fresnel(1e12j, np.radians(30))
    assert rh == pytest.approx(-1, abs=1e-5) and rv == pytest.approx(1, abs=1e-5)
    rh, rv = fresnel("pec", np.radians(30))
    assert rh == -1 and rv == 1


def test_lossless_metal_total_reflection():
    np.testing.assert_allclose(reflectivity(-20.0, np.radians([0, 40, 80])), 1.0, rtol=1e-12)
