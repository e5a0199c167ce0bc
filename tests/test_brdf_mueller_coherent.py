"""Numpy side of the coherent (delta) lobe's Mueller matrix (emscatter.brdf.mueller:
coherent_amplitudes, coherent_mueller, MuellerTable.coherent) and the reciprocity of SPM
Mueller tables through the ``measured_polarized`` export."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from emscatter.brdf.export_pbsdf import default_axes, read_pbsdf, write_pbsdf
from emscatter.brdf.mueller import build_mueller_table, coherent_amplitudes, coherent_mueller
from emscatter.fresnel import fresnel_cos
from emscatter.spectra import GaussianCorrelation

EPS_AU = (0.2 + 3.0j) ** 2
WL_NM = [450, 500, 550, 600, 650]


def _surface():
    return GaussianCorrelation(sigma=5e-9, length=1e-7, dimension=2)


def _spm(wl_nm=(550,), step_deg=6.0, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return build_mueller_table(
            _surface(), EPS_AU, np.array(wl_nm) * 1e-9, method="spm",
            theta=np.radians(np.arange(0, 90, step_deg)),
            phi=np.radians(np.arange(0, 180.01, step_deg)), energy="off", **kw,
        )  # fmt: skip


@pytest.mark.parametrize("order", [1, 2])
def test_coherent_mueller_is_the_tables_delta_lobe(order):
    """M₀₀ is the table's R_coh, M₀₀ ± M₀₁ its h/v coherent powers, and the matrix is pure
    (one mean-field Jones matrix: tr(MᵀM) = 4 M₀₀², Gil & Bernabeu 1985), block-diagonal
    (no h↔v mean field on an isotropic surface)."""
    mt = _spm(order=order)
    c, t = mt.coherent, mt.table
    assert c.shape == (1, 4, 4, t.theta_i.size)
    np.testing.assert_allclose(c[:, 0, 0], t.coherent, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(c[:, 0, 0] + c[:, 0, 1], t.coherent_polarized[0], rtol=1e-12)
    np.testing.assert_allclose(c[:, 0, 0] - c[:, 0, 1], t.coherent_polarized[1], rtol=1e-12)
    np.testing.assert_allclose((c * c).sum(axis=(1, 2)), 4 * c[:, 0, 0] ** 2, rtol=1e-10)
    assert np.abs(c[:, :2, 2:]).max() < 1e-12 and np.abs(c[:, 2:, :2]).max() < 1e-12


def test_coherent_phase_fresnel_and_second_order():
    """Order 1: the phase between h and v is the Fresnel one, arg(r_h r_v*), exactly. Order 2:
    the mean field R⁽⁰⁾ + σ²R⁽²⁾ shifts it by O((kσ)²) (kσ = 0.057: between 1e-4 and 0.05
    rad here), with the same powers."""
    th = np.radians([10.0, 40, 70])
    rh, rv = fresnel_cos(EPS_AU, np.cos(th))
    pw = np.stack([np.abs(rh) ** 2, np.abs(rv) ** 2])
    a1 = coherent_amplitudes(_surface(), EPS_AU, 550e-9, th, pw, method="spm", order=1)
    np.testing.assert_allclose(a1, np.stack([rh, rv]), rtol=1e-12)
    a2 = coherent_amplitudes(_surface(), EPS_AU, 550e-9, th, pw, method="spm", order=2)
    np.testing.assert_allclose(np.abs(a2), np.abs(a1), rtol=1e-12)
    shift = np.abs(np.angle(a2[0] * np.conj(a2[1])) - np.angle(rh * np.conj(rv)))
    assert np.all((shift > 1e-4) & (shift < 0.05)), shift
    # closed form of a flat mirror in h/v frames (x = s, y = p): M₂₂ = Re(a_h a_v*) etc. up
    # to the frames' signs; the magnitudes are frame-free
    m = coherent_mueller(a1, th)
    np.testing.assert_allclose(np.hypot(m[2, 2], m[2, 3]), np.abs(rh * rv), rtol=1e-12)
    np.testing.assert_allclose(m[0, 0], 0.5 * (pw[0] + pw[1]), rtol=1e-12)


def test_go_tables_have_no_coherent_matrix():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        mt = build_mueller_table(
            GaussianCorrelation(sigma=1e-6, length=6e-6, dimension=2), EPS_AU, [550e-9],
            method="go", resolution=(8, 9),
        )  # fmt: skip
    assert mt.coherent is None


def test_spm_mueller_file_reciprocity(tmp_path):
    """The SPM Mueller table exported to ``measured_polarized``: swapping light and view
    (φd → φd + π) gives M' = Q Mᵀ Q, Q = diag(1, 1, −1, 1) (van de Hulst 1957 §5.3; as
    tests/test_brdf_pbsdf.py for GO). The table is reciprocal at its nodes (first-order SPM
    amplitudes obey f_pq(i→s) ↔ f_qp(s→i)); between them the file's nodes see the
    interpolant, symmetric too: measured max 5e-12 of the largest M₀₀ (3° table)."""
    mt = _spm(WL_NM, step_deg=3.0)
    ax = default_axes(24, 23, 37)
    path = tmp_path / "spm.pbsdf"
    write_pbsdf(mt, path, phi_d=ax[0], theta_d=ax[1], theta_h=ax[2], wavelengths_nm=WL_NM)
    f = read_pbsdf(path)
    m = f["M"].astype(float)
    a, b = m[:18], m[18:36]
    np.testing.assert_allclose(f["phi_d"][0][18:36] - f["phi_d"][0][:18], math.pi, atol=1e-6)
    q = np.diag([1.0, 1, -1, 1])
    rev = np.einsum("ij,...kj,kl->...il", q, b, q)
    scale = m[..., 0, 0].max()
    err = np.abs(rev - a).max() / scale
    print(f"SPM Mueller file reciprocity: max {err:.3g} of the largest M00")
    assert err < 1e-6
    assert np.abs(np.einsum("...kj->...jk", b) - a).max() > 1e-3 * scale
