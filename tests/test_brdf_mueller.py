"""Polarized (Mueller) BRDF tables (emscatter.brdf.mueller): agreement with the unpolarized and
per-pair tables, physical realizability, the flat-mirror limit, the SPM phases against the
boundary-value solution, refusal where no phase exists, and Mitsuba's own frames."""

from __future__ import annotations

import importlib.util
import json
import math
import subprocess
import sys
import warnings

import numpy as np
import pytest

from emscatter.brdf import frames
from emscatter.brdf.mueller import (
    MuellerUnavailable,
    build_mueller_table,
    go_jones,
    jones_to_mueller,
    mueller_at,
    spm_jones,
    stokes_basis,
    to_mitsuba,
)
from emscatter.fresnel import fresnel_cos
from emscatter.solvers.spm import model as spm
from emscatter.spectra import GaussianCorrelation

LAM = 550e-9
EPS_AU = (0.2 + 3.0j) ** 2  # n + ik = 0.2 + 3i (Mitsuba's eta, k)
THETA = np.radians(np.arange(0.0, 90.0, 10.0))
PHI = np.linspace(0.0, math.pi, 13)


def go_surface():
    return GaussianCorrelation(sigma=1e-6, length=6e-6, dimension=2)  # m = 2σ/T ≈ 0.33


def spm_surface():
    return GaussianCorrelation(sigma=5e-9, length=2e-7, dimension=2)  # kσ = 0.057


def _build(method, surface, eps, energy="off"):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return build_mueller_table(
            surface, eps, [LAM, 650e-9], method=method, theta=THETA, phi=PHI, energy=energy
        )


# ------------------------------------------------------------------ the Jones → Mueller map
def test_flat_mirror_closed_form():
    """GO facet at the specular direction is a flat mirror: J = diag(R_h, R_v) and M the
    Fresnel Mueller matrix ½[[Rs+Rp, Rs−Rp,0,0],[Rs−Rp,Rs+Rp,0,0],[0,0,2Re z,2Im z],
    [0,0,−2Im z,2Re z]], z = r_s r_p* (Chipman 2018 §6.10; Mitsuba's specular_reflection)."""
    th = np.radians([0.0, 20.0, 45.0, 70.0, 85.0])
    phi = np.radians([0.0, 30.0, 100.0, 200.0, 300.0])
    j = go_jones(EPS_AU, th, phi, th, phi + math.pi)
    rs, rp = fresnel_cos(EPS_AU, np.cos(th))
    np.testing.assert_allclose(j[0, 0], rs, atol=1e-12)
    np.testing.assert_allclose(j[1, 1], rp, atol=1e-12)
    np.testing.assert_allclose(j[0, 1], 0, atol=1e-12)
    np.testing.assert_allclose(j[1, 0], 0, atol=1e-12)
    m = jones_to_mueller(j)
    Rs, Rp, z = abs(rs) ** 2, abs(rp) ** 2, rs * np.conj(rp)
    zero = np.zeros_like(Rs)
    ref = 0.5 * np.array(
        [
            [Rs + Rp, Rs - Rp, zero, zero],
            [Rs - Rp, Rs + Rp, zero, zero],
            [zero, zero, 2 * z.real, 2 * z.imag],
            [zero, zero, -2 * z.imag, 2 * z.real],
        ]
    )
    np.testing.assert_allclose(m, ref, atol=1e-12)


def test_jones_to_mueller_rejects_bad_shape():
    with pytest.raises(ValueError, match=r"jones must have shape \(2, 2, ...\), got \(3,\)"):
        jones_to_mueller(np.zeros(3))


# ------------------------------------------------------------------ agreement with build_table
def _check_against_table(mt, skip_normal_pair):
    t = mt.table
    peak = float(t.values.max())
    # M00 is the unpolarized table
    np.testing.assert_allclose(mt.mueller[:, 0, 0], t.values, rtol=1e-9, atol=1e-12 * peak)
    powers = mt.polarized_powers()
    table_pol = np.moveaxis(t.polarized, 2, 0)  # (n_wl, 2, 2, grid)
    if skip_normal_pair:
        # both directions on the normal: h/v are fixed by φ here (ĥ = (−sinφ, cosφ, 0)),
        # the power solver takes ĥ_s = −ĥ_i whatever Δφ (its degenerate branch): unpolarized
        # values agree (above), the split between pairs depends on that basis choice
        powers, table_pol = powers[..., 1:, :, :], table_pol[..., 1:, :, :]
    np.testing.assert_allclose(powers, table_pol, rtol=1e-9, atol=1e-12 * peak)


def test_go_mueller_equals_unpolarized_and_pair_tables():
    mt = _build("go", go_surface(), EPS_AU)
    _check_against_table(mt, skip_normal_pair=True)
    # out of the plane of incidence the GO Mueller matrix couples linear and circular
    # polarization (nonzero M_23 etc.): the phase matters, not only the powers
    assert np.abs(mt.mueller[:, 2, 3]).max() > 1e-3 * mt.mueller[:, 0, 0].max()


def test_go_mueller_energy_remedy_follows_table():
    """At grazing incidence the remedy rescales the table; the Mueller table follows it."""
    rough = GaussianCorrelation(sigma=1e-6, length=2e-6, dimension=2)  # m ≈ 1: albedo > 1
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        mt = build_mueller_table(
            rough, "pec", [LAM], method="go", theta=THETA, phi=PHI, shadowing=False
        )
    assert mt.table.metadata["energy"]["remedy_applied"]
    _check_against_table(mt, skip_normal_pair=True)


@pytest.mark.parametrize("eps", [2.25 + 0.01j, 17 + 2j, "pec"])
def test_spm_mueller_equals_unpolarized_and_pair_tables(eps):
    mt = _build("spm", spm_surface(), eps)
    _check_against_table(mt, skip_normal_pair=False)


@pytest.mark.parametrize("eps", [5 + 1j, 17 + 2j, -10 + 1j])
def test_spm_relative_phases_against_boundary_value_solution(eps):
    """The Mueller matrix needs the *phases* of f_pq relative to each other: the closed-form
    f_pq must equal the numerically solved boundary-value amplitudes (Tsang's h/v basis, the
    same as emscatter's) up to one complex factor common to all four pairs."""
    rng = np.random.default_rng(3)
    k = 2 * math.pi / LAM
    ti = 0.6
    ts = rng.uniform(0.05, 1.5, 15)
    ps = rng.uniform(0, 2 * np.pi, 15)
    kx, ky = k * np.sin(ts) * np.cos(ps), k * np.sin(ts) * np.sin(ps)
    (ah_h, av_h, *_), (ah_v, av_v, *_) = spm._first_order_amplitudes(
        spm_surface(), eps, k, ti, kx, ky
    )
    # renderer angles of the emscatter geometry (φi = 0, φs = ps)
    j = spm_jones(eps, ti, math.pi, ts, ps)
    ratio = [ah_h / j[0, 0], ah_v / j[0, 1], av_h / j[1, 0], av_v / j[1, 1]]
    for r in ratio[1:]:
        np.testing.assert_allclose(r, ratio[0], rtol=1e-8)


# ------------------------------------------------------------------ physical realizability
@pytest.mark.parametrize("method", ["go", "spm"])
def test_physically_realizable(method):
    surface, eps = (go_surface(), EPS_AU) if method == "go" else (spm_surface(), 17 + 2j)
    mt = _build(method, surface, eps)
    m = np.moveaxis(mt.mueller, (1, 2), (0, 1)).reshape(4, 4, -1)
    m00 = m[0, 0]
    tol = 1e-12 * m00.max()
    assert np.all(m00 >= 0)
    # unpolarized input (1, 0, 0, 0) gives the Stokes vector M[:, 0]: degree of polarization ≤ 1
    assert np.all(np.sqrt((m[1:, 0] ** 2).sum(axis=0)) <= m00 + tol)
    # |M_0j| ≤ M00 (a fully polarized input never gives negative power)
    assert np.all(np.abs(m[0, 1:]) <= m00 + tol)
    assert np.all(np.sqrt((m[0, 1:] ** 2).sum(axis=0)) <= m00 + tol)
    # one amplitude matrix per node: a pure (non-depolarizing) Mueller matrix,
    # tr(MᵀM) = 4 M00² (Gil & Bernabeu 1985)
    np.testing.assert_allclose((m * m).sum(axis=(0, 1)), 4 * m00**2, rtol=1e-9, atol=tol**2)


def test_mueller_table_reciprocity():
    """σ⁰ reciprocity carried to the Mueller table on the symmetric grid: M₀₀(ωi, ωo) =
    M₀₀(ωo, ωi) exactly for GO (equal node axes)."""
    mt = _build("go", go_surface(), EPS_AU)
    m00 = mt.mueller[:, 0, 0]
    np.testing.assert_allclose(m00, np.swapaxes(m00, 1, 2), rtol=1e-10, atol=1e-14)


# ------------------------------------------------------------------ refusals
@pytest.mark.parametrize("method", ["po", "iem", "mom", "nonsense"])
def test_refuses_formulations_without_cross_products(method):
    with pytest.raises(MuellerUnavailable, match=rf"method='{method}' gives no Mueller matrix"):
        build_mueller_table(go_surface(), EPS_AU, [LAM], method=method, theta=THETA, phi=PHI)


def test_refuses_unknown_option_and_bad_wavelength():
    with pytest.raises(ValueError, match=r"option\(s\) \['order'\] not accepted by the 'go'"):
        mueller_at(go_surface(), EPS_AU, LAM, 0.3, 0, 0.3, math.pi, method="go", order=1)
    with pytest.raises(ValueError, match="wavelength must be a positive finite number"):
        mueller_at(go_surface(), EPS_AU, -1.0, 0.3, 0, 0.3, math.pi, method="go")


# ------------------------------------------------------------------ Mitsuba's frames
_MI_SCRIPT = r"""
import json, sys
import numpy as np
import mitsuba as mi
mi.set_variant("scalar_spectral_polarized")
args = json.loads(sys.argv[1])
b = mi.load_dict({"type": "roughconductor", "distribution": "beckmann",
                  "alpha": args["alpha"], "eta": args["eta"], "k": args["k"]})
out = []
for wi, wo in zip(args["wi"], args["wo"]):
    si = mi.SurfaceInteraction3f()
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    si.n = mi.Vector3f(0, 0, 1)
    si.wi = mi.Vector3f(wo)        # Mitsuba's si.wi: towards the viewer (emscatter's wo)
    si.wavelengths = [550.0] * 4
    a = np.array(b.eval(mi.BSDFContext(), si, mi.Vector3f(wi)))  # Mitsuba's wo: the light
    out.append((a if a.ndim == 2 else a[..., 0]).tolist())
basis = [np.array(mi.mueller.stokes_basis(mi.Vector3f(w))).tolist() for w in args["probe"]]
print(json.dumps({"m": out, "basis": basis}))
"""


def _mitsuba_polarized():
    if importlib.util.find_spec("mitsuba") is None:
        return False
    try:
        out = subprocess.run(
            [sys.executable, "-c", "import mitsuba as mi; print(mi.variants())"],
            capture_output=True, text=True, timeout=120,
        )  # fmt: skip
    except subprocess.TimeoutExpired:
        return False
    return "scalar_spectral_polarized" in out.stdout


@pytest.mark.skipif(not _mitsuba_polarized(), reason="needs Mitsuba's scalar_spectral_polarized")
def test_go_mueller_in_mitsuba_frames_equals_roughconductor():
    """The GO Mueller matrix, converted by to_mitsuba, against Mitsuba 3's own polarized
    ``roughconductor`` (Beckmann, α = m, separable Smith shadowing, its Fresnel Mueller
    matrix rotated with mi.mueller.rotate_mueller_basis): all 16 elements within 1 % of M00
    up to 80°, and our numpy stokes_basis equal to mi.mueller.stokes_basis."""
    rng = np.random.default_rng(7)
    n = 40
    ti = rng.uniform(0.05, math.radians(80), n)
    to = rng.uniform(0.05, math.radians(80), n)
    pi_ = rng.uniform(0, 2 * math.pi, n)
    po = pi_ + math.pi + rng.uniform(-0.6, 0.6, n)
    wi, wo = frames.directions(ti, pi_), frames.directions(to, po)
    probe = np.concatenate([-wi, wo, [[0, 0, 1.0], [0, 0, -1.0], [0.6, 0, -0.8]]])
    m_slope = 0.3
    args = {"alpha": m_slope, "eta": 0.2, "k": 3.0, "wi": wi.tolist(), "wo": wo.tolist(),
            "probe": probe.tolist()}  # fmt: skip
    res = subprocess.run(
        [sys.executable, "-c", _MI_SCRIPT, json.dumps(args)],
        capture_output=True, text=True, timeout=300, check=True,
    )  # fmt: skip
    data = json.loads(res.stdout)
    np.testing.assert_allclose(np.array(data["basis"]), stokes_basis(probe.T).T, atol=1e-6)
    ref = np.moveaxis(np.array(data["m"]), 0, -1) / np.cos(ti)  # eval includes cosθ(light)
    s2 = m_slope**2 / 2
    mine = mueller_at(
        go_surface(), EPS_AU, LAM, ti, pi_, to, po, method="go", shadowing="separable",
        slope_variance=(s2, s2),
    )  # fmt: skip
    conv = to_mitsuba(mine, ti, pi_, to, po)
    err = np.abs(conv - ref).max(axis=(0, 1)) / ref[0, 0]
    assert err.max() < 0.01, f"max error {err.max():.3g} (median {np.median(err):.3g})"
    # and without the conversion the V-coupling elements would have the wrong sign
    flip = np.diag([1.0, 1, -1, -1])
    wrong = np.einsum("ij,jk...,kl->il...", flip, mine, flip)
    assert np.abs(to_mitsuba(wrong, ti, pi_, to, po) - ref).max() > 0.01 * ref[0, 0].max()
