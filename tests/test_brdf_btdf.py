"""The BTDF at renderer direction pairs (:mod:`emscatter.brdf.btdf`): unpolarized and Mueller
against Mitsuba 3's own polarized ``roughdielectric`` (Beckmann, run in a worker process),
s0 equal to the unpolarized BTDF, and the bad inputs."""

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

from emscatter.brdf import btdf
from emscatter.spectra import GaussianCorrelation

HERE = Path(__file__).parent
ALPHA = 0.3
WL = 550e-9
# Beckmann α = 2σ/ℓ = 0.3 (Mitsuba's alpha; α² = 2⟨ζx²⟩)
ROUGH = GaussianCorrelation(sigma=1.5e-6, length=1e-5)


@lru_cache(maxsize=1)
def _polarized() -> bool:
    if importlib.util.find_spec("mitsuba") is None:
        return False
    code = "import mitsuba as mi; mi.set_variant('llvm_ad_spectral_polarized')"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, timeout=120)
    return out.returncode == 0


def _mitsuba(variant, bsdf, wi, wo):
    args = {"variant": variant, "bsdf": bsdf, "wi": wi.tolist(), "wo": wo.tolist(),
            "wavelength": WL * 1e9}  # fmt: skip
    res = subprocess.run(
        [sys.executable, str(HERE / "btdf_worker.py")], input=json.dumps(args),
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert res.returncode == 0, res.stderr[-3000:]
    return np.array(json.loads(res.stdout.splitlines()[-1])["eval"])


def _pairs(n=500, seed=11, eta=1.5):
    """Light above (θi ≤ 80°), viewer below around the refracted direction."""
    rng = np.random.default_rng(seed)
    ti = np.arccos(rng.uniform(math.cos(math.radians(80)), 1.0, n))
    pi_ = rng.uniform(-math.pi, math.pi, n)
    tt = np.abs(np.arcsin(np.sin(ti) / eta) + rng.normal(0, ALPHA, n))
    tt = np.minimum(tt, math.radians(85))
    pt = pi_ + math.pi + rng.normal(0, ALPHA, n)  # viewer opposite the light's azimuth
    wi = np.stack([np.sin(ti) * np.cos(pi_), np.sin(ti) * np.sin(pi_), np.cos(ti)], -1)
    wo = np.stack([np.sin(tt) * np.cos(pt), np.sin(tt) * np.sin(pt), -np.cos(tt)], -1)
    return wi, wo


@pytest.mark.skipif(not _polarized(), reason="needs Mitsuba's llvm_ad_spectral_polarized")
def test_mueller_btdf_against_polarized_roughdielectric():
    """M00 against ``roughdielectric`` in ``llvm_ad_spectral_polarized`` (its eval / cosθi):
    the issue asks median ≤ 0.5 %, p90 ≤ 3 %; measured median 2.5e-5, p90 0.26 % (Walter's
    rational G1 in Mitsuba). Mitsuba 3.9's ``roughdielectric`` is a *depolarizer* in the
    polarized variants (reflection and transmission alike, unlike ``roughconductor``): its
    other 15 elements are exactly 0, so it is no reference for them (asserted, so that a
    Mitsuba that polarizes it shows up here); ours are checked against the closed-form
    Fresnel transmission in :func:`test_mueller_in_plane_is_fresnel_transmission`."""
    wi, wo = _pairs()
    ours = btdf.mueller_btdf_at(ROUGH, 2.25, WL, wi, wo, shadowing="separable")
    bsdf = {"type": "roughdielectric", "distribution": "beckmann", "alpha": ALPHA,
            "int_ior": 1.5, "ext_ior": 1.0}  # fmt: skip
    theirs = np.moveaxis(_mitsuba("llvm_ad_spectral_polarized", bsdf, wi, wo), 0, -1)
    theirs = theirs / wi[:, 2]
    m00 = theirs[0, 0]
    big = m00 > 1e-3 * m00.max()
    assert big.sum() > 200
    rel00 = np.abs(ours[0, 0] - m00)[big] / m00[big]
    med, p90 = np.median(rel00), np.percentile(rel00, 90)
    print(f"M00: median {med:.3g}, p90 {p90:.3g}, max {rel00.max():.3g} over {big.sum()}")
    assert med <= 5e-3 and p90 <= 3e-2
    rest = theirs.reshape(16, -1)[1:]
    assert np.all(rest == 0), "Mitsuba's roughdielectric now polarizes: compare all 16"
    # ours is polarized: the transmitted light is partly polarized (Brewster-like)
    assert np.max(np.abs(ours[1, 0, big] / ours[0, 0, big])) > 0.02


def test_mueller_in_plane_is_fresnel_transmission():
    """In the plane of incidence the facet is the one refracting wi into wo, and the Mueller
    matrix (emscatter's h/v frames) over M00 is the Fresnel transmission's closed form at the
    local angle ``cosθl = i·ĥ`` (Born & Wolf §1.5.3; Chipman 2018 §6.10):
    ``[[1, d, 0, 0], [d, 1, 0, 0], [0, 0, c, 0], [0, 0, 0, c]]``, ``d = (T_s − T_p)/(T_s + T_p)``,
    ``c = 2√(T_s T_p)/(T_s + T_p)`` (real, positive transmission amplitudes)."""
    from emscatter.fresnel import fresnel_cos

    ti = np.radians([5.0, 30.0, 50.0, 70.0])
    tt = np.radians([10.0, 15.0, 40.0, 30.0])
    wi = np.stack([np.sin(ti), 0 * ti, np.cos(ti)], -1)
    wo = np.stack([-np.sin(tt), 0 * tt, -np.cos(tt)], -1)  # forward, below
    m = btdf.mueller_btdf_at(ROUGH, 2.25, WL, wi, wo, frame="emscatter")
    w = wi + 1.5 * wo
    h = -w / np.linalg.norm(w, axis=-1, keepdims=True)
    c = np.sum(wi * h, axis=-1)
    rs, rp = fresnel_cos(2.25, c)
    ts, tp = 1 - np.abs(rs) ** 2, 1 - np.abs(rp) ** 2
    d, cc = (ts - tp) / (ts + tp), 2 * np.sqrt(ts * tp) / (ts + tp)
    z = np.zeros_like(d)
    one = np.ones_like(d)
    want = np.array([[one, d, z, z], [d, one, z, z], [z, z, cc, z], [z, z, z, cc]])
    np.testing.assert_allclose(m / m[0, 0], want, atol=1e-12)


def test_s0_equals_unpolarized_and_frames():
    """M00 (either frame) equals the unpolarized BTDF to 1e-12; the frame rotation keeps
    M00 and the total polarized power."""
    wi, wo = _pairs(200, seed=2)
    f = btdf.btdf_at(ROUGH, 2.25, WL, wi, wo)
    m_em = btdf.mueller_btdf_at(ROUGH, 2.25, WL, wi, wo, frame="emscatter")
    m_mi = btdf.mueller_btdf_at(ROUGH, 2.25, WL, wi, wo)
    scale = f.max()
    np.testing.assert_allclose(m_em[0, 0], f, atol=1e-12 * scale)
    np.testing.assert_allclose(m_mi[0, 0], f, atol=1e-12 * scale)
    dop_em = np.hypot(np.hypot(m_em[1, 0], m_em[2, 0]), m_em[3, 0])
    dop_mi = np.hypot(np.hypot(m_mi[1, 0], m_mi[2, 0]), m_mi[3, 0])
    np.testing.assert_allclose(dop_em, dop_mi, atol=1e-12 * scale)
    assert np.all(f >= 0) and np.all(dop_em <= f * (1 + 1e-12))


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"material": "pec"}, "perfect conductor"),
        ({"material": "Au"}, "material 'Au'.*eps must be real"),
        ({"wi": np.array([0.0, 0.3, -1.0])}, "wi must point above"),
        ({"wo": np.array([0.0, 0.3, 1.0])}, "wo must point below"),
        ({"wavelength": -1.0}, "wavelength"),
        ({"frame": "pbrt"}, "frame must be"),
        ({"sample": 3}, "unknown option"),
    ],
)
def test_bad_inputs(kwargs, match):
    args = {"material": 2.25, "wavelength": WL, "wi": np.array([0.0, 0.3, 1.0]),
            "wo": np.array([0.0, -0.2, -1.0])}  # fmt: skip
    extra = {k: v for k, v in kwargs.items() if k not in args}
    args.update({k: v for k, v in kwargs.items() if k in args})
    with pytest.raises(ValueError, match=match):
        btdf.mueller_btdf_at(
            ROUGH, args["material"], args["wavelength"], args["wi"], args["wo"], **extra
        )
