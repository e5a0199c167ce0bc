"""The coherent (delta) lobes of the ``emscatter_dielectric`` plugin (render/dielectric/delta.py):
SPM glass (ε = 2.25, ℓ = 1 µm, 550 nm) against Mitsuba's smooth ``dielectric`` in the limit
kσ → 0, energy against the tables, GO tables unchanged. Real Mitsuba in subprocesses
(tests/dielectric_delta_worker.py): Dr.Jit variants are per process."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("mitsuba")
HERE = Path(__file__).parent
ANGLES = [0, 9, 27, 40, 41.5, 45, 63, 80, 85]  # nodes, off-node, both sides of the critical 41.8°


def _worker(**args):
    args = {"variant": "llvm_ad_rgb", "method": "spm", "n_theta": 10, "n": 64, **args}
    r = subprocess.run(
        [sys.executable, str(HERE / "dielectric_delta_worker.py"), json.dumps(args)],
        capture_output=True, text=True, timeout=600, check=False,
    )  # fmt: skip
    assert r.returncode == 0, r.stderr[-3000:]
    return json.loads(r.stdout.strip().splitlines()[-1])


class _Flags:
    """Mitsuba's BSDFFlags values as the worker reports them (no variant in this process)."""

    def __init__(self, r):
        self.__dict__.update(r["flag_values"])


@pytest.fixture(scope="module")
def smooth_rgb():
    """kσ = 0.01: the coherent parts are R_F, T_F times 1 − O((kσ)²) = 0.9996."""
    return _worker(k_sigma=0.01, theta_deg=ANGLES, render=32, spp=64)


@pytest.mark.parametrize("variant", ["llvm_ad_rgb", "llvm_ad_spectral"])
def test_delta_lobes_equal_smooth_dielectric(variant, smooth_rgb):
    """Each delta component alone (weight = its coherent part, radiance scale 1/ε outside and ε
    inside included) equals Mitsuba's ``dielectric`` within 1 % (outside and inside viewers,
    total internal reflection included: T = 0, R = 1), and the full sampler's mean reflected
    and transmitted weights agree with ``dielectric``'s under the same random numbers."""
    r = smooth_rgb if variant == "llvm_ad_rgb" else _worker(variant=variant, k_sigma=0.01,
                                                             theta_deg=ANGLES)  # fmt: skip
    for lobe in ("R", "T"):
        got, ref = np.array(r["d" + lobe]), np.array(r["d_ref" + lobe])
        assert np.all(np.abs(got - ref) <= 0.01 * np.abs(ref) + 1e-6), (lobe, got, ref)
        mean, mean_ref = np.array(r[lobe]), np.array(r[lobe + "_ref"])
        assert np.all(np.abs(mean - mean_ref) <= 0.05 * mean_ref + 4 * np.array(r["se"]))
    assert r["delta_fraction"] > 0.99


def test_smooth_sphere_render_equals_dielectric(smooth_rgb):
    """A kσ = 0.01 glass sphere over a checkerboard renders as Mitsuba's smooth ``dielectric``:
    mean within 1 %, pixel differences below the dielectric's own seed-to-seed noise."""
    m = smooth_rgb["render_mean"]
    assert abs(m["em"] / m["ref"] - 1) < 0.01, m
    assert smooth_rgb["render_mean_abs_diff"] < smooth_rgb["render_noise_floor"]


def test_flags_and_components(smooth_rgb):
    f = _Flags(smooth_rgb)
    flags = smooth_rgb["flags"]
    assert flags & f.DeltaReflection and flags & f.DeltaTransmission
    assert flags & f.GlossyReflection and flags & f.GlossyTransmission
    assert smooth_rgb["components"] == 6  # 3 glossy, delta R outside, delta T, delta R inside


def test_polarized_delta_equals_dielectric_mueller():
    """``*_spectral_polarized``: each delta component's Mueller matrix equals Mitsuba's
    polarized ``dielectric`` (Fresnel matrices in its Stokes frames) within 1 % of M₀₀."""
    r = _worker(variant="llvm_ad_spectral_polarized", k_sigma=0.01, theta_deg=ANGLES, n=4)
    got, ref = np.array(r["dM"]), np.array(r["d_refM"])  # (component, 4, 4, viewer)
    half = len(ANGLES)
    pairs = [(got[0][..., :half], ref[0][..., :half]), (got[2][..., half:], ref[2][..., half:]),
             (got[1], ref[1])]  # fmt: skip
    for g, rf in pairs:
        assert np.all(np.abs(g - rf) <= 0.01 * np.abs(rf[0, 0]) + 1e-6), (g, rf)
    assert np.abs(ref[1][2, 2]).max() > 0.1  # the matrices are not trivially zero


@pytest.fixture(scope="module")
def rough_spm():
    """kσ = 0.13 (a fine polish): glossy lobes ~1 %, coherent transmission ~96 %."""
    kw = dict(k_sigma=0.13, theta_deg=[0, 27, 54, 72], n=20000, mode="importance")
    return _worker(**kw), _worker(coherent=False, **kw)


def test_energy_equals_tables(rough_spm):
    """Importance transport (no radiance scale): the mean sampled weight from outside equals the
    tables' R_coh + R_inc + T_coh + T_inc within Monte-Carlo error, and is ≤ 1 + noise on
    both sides; the glossy samples' pdf equals pdf(wo)."""
    r, _ = rough_spm
    total = np.array(r["R"]) + np.array(r["T"])
    se = np.array(r["se"])
    k = len(r["table_sum"])
    assert np.all(np.abs(total[:k] - r["table_sum"]) <= 4 * se[:k] + 2e-3), (total, r)
    assert np.all(total <= 1 + 4 * se + 2e-3)
    assert r["pdf_bad_fraction"] < 1e-3


def test_coherent_false_is_glossy_only(rough_spm):
    """``coherent=false``: no delta flags, the sampled energy is the glossy lobes' alone
    (tables' sum minus the coherent parts)."""
    r_on, r = rough_spm
    assert not r["flags"] & _Flags(r).Delta and r["components"] == 3
    assert r["delta_fraction"] == 0.0
    total = np.array(r["R"]) + np.array(r["T"])
    k = len(r["table_sum"])
    want = np.array(r["table_sum"]) - np.array(r["table_coherent"])
    assert np.all(np.abs(total[:k] - want) <= 4 * np.array(r["se"][:k]) + 3e-4), (total, want)
    assert np.all(want < 0.02) and np.all(np.array(r_on["table_coherent"]) > 0.9)


def test_go_tables_unchanged():
    """A GO table set has no coherent part: ``coherent`` true or false give the same BSDF bit
    for bit (sample weights, directions, pdfs, evals), three glossy components, no delta flag."""
    kw = dict(method="go", theta_deg=[0, 30, 60, 80], n=500)
    a, b = _worker(**kw), _worker(coherent=False, **kw)
    assert a["digest"] == b["digest"] and a["flags"] == b["flags"]
    assert a["components"] == 3 and not a["flags"] & _Flags(a).Delta
    assert a["delta_fraction"] == 0.0


def test_bsdf_dict_coherent_must_be_bool():
    from emscatter.render import dielectric as em_d

    with pytest.raises(ValueError, match="coherent must be True or False, got 'yes'"):
        em_d.bsdf_dict(None, None, coherent="yes")
