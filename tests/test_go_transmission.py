"""GO transmission (rough-dielectric BTDF, :mod:`emscatter.solvers.kirchhoff.transmission.go`):
against Mitsuba 3's own ``roughdielectric`` (Beckmann, run for real in a worker process), the
energy balance R + T with GO's reflection, Smith's normalization, reciprocity, the smooth
limit and the bad inputs."""

from __future__ import annotations

import importlib.util
import json
import math
import subprocess
import sys
from functools import lru_cache
from pathlib import Path

import numpy as np
import pytest

from emscatter.fresnel import fresnel_cos
from emscatter.solvers.kirchhoff import go
from emscatter.solvers.kirchhoff.common import illuminated_fraction
from emscatter.solvers.kirchhoff.transmission import go as gt
from emscatter.spectra import GaussianCorrelation

HERE = Path(__file__).parent
K0 = 2 * math.pi  # λ = 1 (GO's σ⁰ does not depend on k for a Gaussian correlation)


def _rough(alpha, alpha_y=None):
    """Gaussian correlation with Beckmann α = 2σ/ℓ (α² = 2⟨ζx²⟩, Mitsuba's alpha)."""
    ly = None if alpha_y is None else 2 * 0.1 / alpha_y
    return GaussianCorrelation(0.1, 2 * 0.1 / alpha, length_y=ly)


@lru_cache(maxsize=1)
def _llvm() -> str | None:
    if importlib.util.find_spec("mitsuba") is None:
        return None
    for variant in ("llvm_ad_rgb", "scalar_rgb"):
        code = (
            f"import mitsuba as mi; mi.set_variant('{variant}'); "
            "mi.load_dict({'type': 'diffuse'})"
        )
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, timeout=120)
        if out.returncode == 0:
            return variant
    return None


def _mitsuba(bsdf: dict, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
    args = {"variant": _llvm(), "bsdf": bsdf, "wi": wi.tolist(), "wo": wo.tolist()}
    res = subprocess.run(
        [sys.executable, str(HERE / "btdf_worker.py")], input=json.dumps(args),
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert res.returncode == 0, res.stderr[-3000:]
    return np.array(json.loads(res.stdout.splitlines()[-1])["eval"])


needs_mitsuba = pytest.mark.skipif(_llvm() is None, reason="needs Mitsuba 3")


def _light(ti, pi_):
    """Renderer direction towards the light of emscatter's incidence (θi, φi): −k̂_i."""
    return np.stack([-np.sin(ti) * np.cos(pi_), -np.sin(ti) * np.sin(pi_), np.cos(ti)], -1)


def _below(tt, pt):
    """Renderer direction of emscatter's transmitted k̂_t (below the surface)."""
    return np.stack([np.sin(tt) * np.cos(pt), np.sin(tt) * np.sin(pt), -np.cos(tt)], -1)


def _pairs(n=600, seed=3, eps=2.25, spread=0.6):
    """Random pairs, θi ≤ 80°, the transmitted direction scattered around the refracted one
    (θt by ``spread`` rad, φt by ``spread`` rad about φi), θt < 87°."""
    rng = np.random.default_rng(seed)
    ti = np.arccos(rng.uniform(math.cos(math.radians(80)), 1.0, n))
    pi_ = rng.uniform(-math.pi, math.pi, n)
    refr = np.arcsin(np.minimum(np.sin(ti) / math.sqrt(eps), 1.0))
    tt = np.clip(refr + rng.normal(0.0, spread, n), 0.0, math.radians(87))
    tt = np.abs(tt)
    pt = pi_ + rng.normal(0.0, spread, n)  # around the forward (refracted) azimuth
    return ti, pi_, tt, pt


CASES = {
    # name: (Mitsuba parameters, ε, α, α_y)
    "glass": ({"int_ior": 1.5, "ext_ior": 1.0}, 2.25, 0.3, None),
    "water-rough": ({"int_ior": 1.33, "ext_ior": 1.0}, 1.33**2, 0.5, None),
    "from-inside": ({"int_ior": 1.0, "ext_ior": 1.5}, 1 / 2.25, 0.2, None),
    "aniso": ({"int_ior": 1.5, "ext_ior": 1.0}, 2.25, 0.15, 0.4),
}


@needs_mitsuba
@pytest.mark.parametrize("name", list(CASES))
def test_btdf_matches_mitsuba_roughdielectric(name):
    """Transmitted pairs (viewer below the surface): Mitsuba's ``eval`` = ``f_t · cosθ_light``
    = ``σ⁰_t / (4π cosθt)``. Walter's rational G1 in Mitsuba against our exact Smith G1 is the
    only difference. Measured (600 random pairs, θi ≤ 80°): glass median 0.012 %, p90 0.29 %;
    the issue asks median ≤ 0.5 %, p90 ≤ 3 %."""
    params, eps, ax, ay = CASES[name]
    bsdf = {"type": "roughdielectric", "distribution": "beckmann", **params}
    if ay is None:
        bsdf["alpha"] = ax
    else:
        bsdf["alpha_u"], bsdf["alpha_v"] = ax, ay
    ti, pi_, tt, pt = _pairs(eps=eps, spread=max(ax, ay or ax))
    res = gt.bistatic_transmission(_rough(ax, ay), eps, K0, ti, tt, pt, pi_, shadowing="separable")
    ours = res.unpolarized() / (4 * math.pi * np.cos(tt))
    theirs = _mitsuba(bsdf, _light(ti, pi_), _below(tt, pt))
    big = np.maximum(ours, theirs) > 1e-4 * theirs.max()
    assert big.sum() > 200, f"only {big.sum()} significant pairs"
    rel = np.abs(ours - theirs)[big] / theirs[big]
    med, p90 = np.median(rel), np.percentile(rel, 90)
    print(f"{name}: median {med:.3g}, p90 {p90:.3g}, max {rel.max():.3g} over {big.sum()}")
    assert med <= 5e-3 and p90 <= 3e-2
    # negligible where Mitsuba has zero (no facet refracts i into o, total internal
    # reflection, or float32 underflow there)
    assert np.all(ours[theirs == 0] < 1e-6 * ours.max())


# --- energy -------------------------------------------------------------------------------


def _sphere(n_mu, n_phi):
    x, w = np.polynomial.legendre.leggauss(n_mu)
    mu = 0.5 * (x + 1.0)
    wmu = 0.5 * w
    phi = (np.arange(n_phi) + 0.5) * (2 * math.pi / n_phi)
    return np.arccos(mu)[:, None], phi[None, :], (wmu[:, None] * (2 * math.pi / n_phi))


def _r_t(rough, eps, ti, shadow_r, shadow_t, n_mu=192, n_phi=256):
    """Hemispherical reflectance (GO) and transmittance (this BTDF) for unpolarized light at θi."""
    th, ph, w = _sphere(n_mu, n_phi)
    r = go.bistatic(rough, eps, K0, ti, th, ph, 0.0, shadowing=shadow_r, coherent=False)
    t = gt.bistatic_transmission(rough, eps, K0, ti, th, ph, 0.0, shadowing=shadow_t)
    norm = 1.0 / (4 * math.pi * math.cos(ti))
    return float(np.sum(r.unpolarized() * w) * norm), float(np.sum(t.unpolarized() * w) * norm)


def _r_t_err(*args):
    """(R, T, quadrature error of R + T: the change from doubling the grid)."""
    r1, t1 = _r_t(*args, n_mu=128, n_phi=192)
    r2, t2 = _r_t(*args, n_mu=256, n_phi=384)
    return r2, t2, abs(r2 + t2 - r1 - t1)


ANGLES = [0.0, 30.0, 60.0, 75.0]


def _escapes_slope_space(eps, ti, s2, n=1201):
    """Independent of the solvers: ``∫ p(ζ) max(0, i·ĥ)/(cosθh cosθi) [F·1(r_z > 0) +
    (1 − F)·1(t_z < 0)] d²ζ`` on a slope grid (``D dΩ_h = p d²ζ / cosθh``), the facet's flat
    Fresnel F, mirror r and Snell refraction t: what single scattering without shadowing
    sends into the right hemispheres, and ``1 + Λ(θi)`` with the wrong-hemisphere part."""
    z = np.linspace(-9, 9, n) * math.sqrt(s2)
    zx, zy = np.meshgrid(z, z, indexing="ij")
    p = np.exp(-(zx**2 + zy**2) / (2 * s2)) / (2 * math.pi * s2)
    hz = 1 / np.sqrt(1 + zx**2 + zy**2)
    h = np.stack([-zx * hz, -zy * hz, hz])
    i = np.array([-math.sin(ti), 0.0, math.cos(ti)])[:, None, None]
    c = np.einsum("i...,i...->...", i, h)
    lit = c > 0
    cc = np.clip(c, 0, 1)
    rh, rv = fresnel_cos(eps, cc)
    f = 0.5 * (np.abs(rh) ** 2 + np.abs(rv) ** 2)
    eta = math.sqrt(eps)
    r = 2 * cc * h - i
    root = 1 - (1 - cc**2) / eps
    t = -i / eta + (cc / eta - np.sqrt(np.maximum(root, 0))) * h
    out = f * (r[2] > 0) + (1 - f) * ((t[2] < 0) & (root > 0))
    w = p * cc / (hz * math.cos(ti)) * lit * (z[1] - z[0]) ** 2
    return float(np.sum(w * out)), float(np.sum(w))


@pytest.mark.parametrize("eps", [2.25, 1 / 1.33**2])
def test_r_plus_t_against_slope_space(eps):
    """Without shadowing: R + T (direction-space quadrature of GO reflection + this BTDF)
    equals the same energy computed in slope space by independent code (half-vector Jacobian,
    W07 eq. 17, D, the facet Fresnel transmission all checked together), and the slope-space
    total ``∫ D max(0, i·ĥ) dΩ_h / cosθi`` is Smith's ``1/G1(θi) = 1 + Λ(θi)`` (Heitz 2014
    eq. 13). ``ε < 1``: incidence from the denser side, total internal reflection included."""
    rough = _rough(0.3)
    s2 = 0.3**2 / 2
    for deg in ANGLES:
        ti = math.radians(deg)
        r, t, err = _r_t_err(rough, eps, ti, False, False)
        escapes, total = _escapes_slope_space(eps, ti, s2)
        assert total == pytest.approx(1.0 / float(illuminated_fraction(ti, s2)), abs=1e-6)
        assert abs(r + t - escapes) <= max(5 * err, 1e-4), (deg, r, t, escapes, err)


def test_smooth_limit_transmittance():
    """Small slope (α = 0.08): T(θi) → 1 − F(θi), the flat interface's unpolarized Fresnel
    transmittance (Born & Wolf §1.5.3), and R + T → 1."""
    rough = _rough(0.08)
    for deg in (0.0, 40.0, 60.0):
        ti = math.radians(deg)
        r, t = _r_t(rough, 2.25, ti, "separable", "separable", n_mu=512, n_phi=512)
        rh, rv = fresnel_cos(2.25, math.cos(ti))
        flat_t = 1 - 0.5 * (abs(rh) ** 2 + abs(rv) ** 2)
        assert t == pytest.approx(flat_t, abs=3e-3), (deg, t, flat_t)
        assert r + t == pytest.approx(1.0, abs=3e-3), (deg, r, t)


@pytest.mark.parametrize("mode", ["separable", "correlated"])
def test_energy_deficit_single_scattering(mode):
    """With shadowing, R + T < 1 (single scattering loses the masked light) and the deficit
    grows towards grazing incidence (at small slopes light leaving below the horizon adds to
    it, so the deficit is not monotonic in the slope). Measured deficits in the module
    docstring's table."""
    prev = None
    for alpha in (0.1, 0.3, 0.5):
        rough = _rough(alpha)
        row = []
        for deg in ANGLES:
            r, t, err = _r_t_err(rough, 2.25, math.radians(deg), mode, mode)
            assert r + t <= 1 + max(5 * err, 2e-4)
            row.append(1 - (r + t))
        row = np.array(row)
        assert np.all(np.diff(row) >= -2e-4), (alpha, row)  # grows towards grazing
        print(mode, alpha, np.round(row, 5))
        prev = row
    assert prev[0] < 0.05 and prev[-1] < 0.4


@needs_mitsuba
def test_albedo_equals_mitsuba_roughdielectric():
    """R + T of GO reflection + this BTDF (separable Smith) equals Mitsuba's roughdielectric
    albedo, integrated on the same grid from its own ``eval`` (both hemispheres): the same
    single-scattering deficit, to Walter's G1 approximation."""
    alpha, eps = 0.4, 2.25
    rough = _rough(alpha)
    th, ph, w = _sphere(128, 192)
    th, ph = np.broadcast_arrays(th, ph)
    w = np.broadcast_to(w, th.shape).ravel()
    bsdf = {"type": "roughdielectric", "distribution": "beckmann", "alpha": alpha,
            "int_ior": 1.5, "ext_ior": 1.0}  # fmt: skip
    up = np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], -1)
    up = up.reshape(-1, 3)
    down = up * np.array([1.0, 1.0, -1.0])
    for deg in (0.0, 45.0, 70.0):
        ti = math.radians(deg)
        light = np.broadcast_to(_light(ti, 0.0), up.shape)
        ev = _mitsuba(bsdf, np.concatenate([light, light]), np.concatenate([up, down]))
        theirs = float(np.sum(ev * np.concatenate([w, w]) * np.abs(np.concatenate(
            [up[:, 2], down[:, 2]]))) / math.cos(ti))  # fmt: skip
        r, t = _r_t(rough, eps, ti, "separable", "separable", n_mu=128, n_phi=192)
        print(f"θi = {deg}: ours R + T = {r + t:.5f}, Mitsuba {theirs:.5f}")
        assert r + t == pytest.approx(theirs, abs=4e-3)


def test_reciprocity():
    """``f_t(i → o) / η_o² = f_t(o → i) / η_i²`` (W07 §5.2; Veach 1997 §5.2): with emscatter's
    angles ``σ⁰_t(θi, φi → θt, φt; ε) = ε σ⁰_t(θt, φt + π → θi, φi + π; 1/ε)``; the power
    matrix is transposed (incident and transmitted polarizations exchange)."""
    rough = _rough(0.3)
    ti, pi_, tt, pt = _pairs(400, seed=5)
    a = gt.bistatic_transmission(rough, 2.25, K0, ti, tt, pt, pi_).sigma0
    b = gt.bistatic_transmission(rough, 1 / 2.25, K0, tt, ti, pi_ + math.pi, pt + math.pi).sigma0
    scale = a.max()
    np.testing.assert_allclose(a.sum(axis=(0, 1)), 2.25 * b.sum(axis=(0, 1)), atol=1e-12 * scale)
    np.testing.assert_allclose(a, 2.25 * np.swapaxes(b, 0, 1), atol=1e-10 * scale)


def test_polarization_sum_and_plane():
    """Σ_pq |J_pq|² = T_h + T_v (rotations), and in the plane of incidence (φt = φi) the
    cross terms vanish and hh, vv are the facet's T_h, T_v."""
    ti = np.radians([10.0, 40.0, 70.0])
    tt = np.radians([5.0, 30.0, 35.0])
    j = gt.transmission_jones(2.25, ti, tt, 0.0, 0.0)
    assert np.all(np.abs(j[0, 1]) < 1e-12) and np.all(np.abs(j[1, 0]) < 1e-12)
    j2 = gt.transmission_jones(2.25, ti, tt, 1.0, 0.3)
    total = (j2**2).sum(axis=(0, 1))
    assert np.all(total > 0) and np.all(total <= 2 + 1e-12)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"eps": "pec"}, "perfect conductor"),
        ({"eps": 2.25 + 0.1j}, "eps must be real"),
        ({"eps": 1.0}, "eps must be > 0 and != 1"),
        ({"eps": -2.0}, "eps must be > 0"),
        ({"shadowing": "direction-correlated"}, "shadowing must be"),
        ({"theta_t": 2.0}, "theta_t"),
    ],
)
def test_bad_inputs(kwargs, match):
    args = {"eps": 2.25, "theta_t": 0.2, "shadowing": True}
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        gt.bistatic_transmission(
            _rough(0.3), args["eps"], K0, 0.3, args["theta_t"], 0.0,
            shadowing=args["shadowing"],
        )  # fmt: skip
