"""The shared hemispherical quadrature against integrands with known integrals."""

import math

import numpy as np
import pytest

from emscatter.emissivity import hemispherical_reflectivity

TI = np.radians([0.0, 30.0, 60.0, 85.0])


def _diag(s):
    z = np.zeros_like(s)
    return np.array([[s, z], [z, s]])


def test_lambertian_surface_gives_its_albedo():
    # σ⁰ = 4 ρ cosθi cosθs  ⇒  r = ρ exactly (2-D normalization 1/(4π cosθi) ∫ dΩ).
    rho = 0.3
    r, err, _ = hemispherical_reflectivity(
        lambda ts, ps: _diag(4 * rho * np.cos(TI[:, None, None]) * np.cos(ts)), TI
    )
    np.testing.assert_allclose(r, rho, rtol=1e-12)
    assert np.all(err < 1e-10)


def test_lambertian_profile_gives_its_albedo():
    # 1-D: σ⁰ = π ρ cosθi cosθs  ⇒  r = 1/(2π cosθi) ∫ σ⁰ dθs = ρ.
    rho = 0.7
    r, _, _ = hemispherical_reflectivity(
        lambda ts, ps: _diag(math.pi * rho * np.cos(TI[:, None]) * np.cos(ts)), TI, dimension=1
    )
    np.testing.assert_allclose(r, rho, rtol=1e-12)


def test_isotropic_emitter_needs_edge_map():
    # σ⁰ = 4π cosθi ρ/(2π)·… : constant radiance per solid angle (no cosθs factor):
    # ∫ dΩ = 2π  ⇒ σ⁰ = 2 ρ cosθi gives r = ρ. The 1/cosθs Jacobian is singular at the edge.
    r, err, _ = hemispherical_reflectivity(
        lambda ts, ps: _diag(2 * 0.5 * np.cos(TI[:, None, None]) + 0 * ts), TI, tol=1e-9
    )
    np.testing.assert_allclose(r, 0.5, rtol=1e-8)


@pytest.mark.parametrize("width", [0.1, 0.02, 0.002])
def test_narrow_specular_lobe(width):
    # A Gaussian lobe of width w around the specular direction in transverse-vector space,
    # normalized so that its integral is 1 when it lies inside the unit disk.
    ti = np.radians([0.0, 10.0, 30.0])  # lobe ≥ 5 widths inside the unit disk

    def lobe(ts, ps):
        t = ti[:, None, None]
        px, py = np.sin(ts) * np.cos(ps), np.sin(ts) * np.sin(ps)
        d2 = (px - np.sin(t)) ** 2 + py**2
        s = 4 * np.cos(t) * np.cos(ts) * np.exp(-d2 / width**2) / width**2
        return _diag(s)

    r, err, n = hemispherical_reflectivity(lobe, ti, finest=width, tol=1e-7)
    np.testing.assert_allclose(r, 1.0, rtol=1e-5)
    assert np.all(err < 1e-6)
