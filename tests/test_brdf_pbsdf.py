"""``.pbsdf`` export for Mitsuba 3's ``measured_polarized`` (emscatter.brdf.export_pbsdf): the
Rusinkiewicz node geometry against the plugin's own mapping, s0 equal to the unpolarized table,
Mueller reciprocity of the file, the real plugin against ``roughconductor`` in
``scalar_spectral_polarized``, and the writer's and reader's errors."""

from __future__ import annotations

import importlib.util
import json
import math
import subprocess
import sys
import warnings
from functools import lru_cache
from pathlib import Path

import numpy as np
import pytest

from emscatter.brdf import frames
from emscatter.brdf.export_pbsdf import (
    PbsdfFormatError,
    default_axes,
    node_directions,
    read_pbsdf,
    write_pbsdf,
)
from emscatter.brdf.export_rgl import _write_tensor_file
from emscatter.brdf.mueller import build_mueller_table
from emscatter.spectra import GaussianCorrelation

HERE = Path(__file__).parent
EPS_AU = (0.2 + 3.0j) ** 2  # n + ik = 0.2 + 3i (Mitsuba's eta, k)
M_SLOPE = 0.3
WL_NM = [450, 500, 550, 600, 650]


@lru_cache(maxsize=2)
def go_table(step_deg: float = 2.0):
    """GO gold, Beckmann m = 0.3 with separable Smith shadowing: Mitsuba's roughconductor
    (Beckmann, α = m) within GO; two wavelengths, interpolated onto the file's five."""
    s2 = M_SLOPE**2 / 2
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return build_mueller_table(
            GaussianCorrelation(sigma=1e-6, length=6e-6, dimension=2), EPS_AU,
            [450e-9, 650e-9], method="go", theta=np.radians(np.arange(0, 90, step_deg)),
            phi=np.radians(np.arange(0, 180.01, step_deg)), energy="off",
            shadowing="separable", slope_variance=(s2, s2),
        )  # fmt: skip


def _rusinkiewicz(i, o):
    """Mitsuba's measured_polarized::directions_to_rusinkiewicz (numpy transcription):
    i = light, o = view → (φd, θh, θd)."""
    h = (i + o) / np.linalg.norm(i + o, axis=-1, keepdims=True)
    n = np.array([0.0, 0, 1])
    b = np.cross(n, h)
    b /= np.linalg.norm(b, axis=-1, keepdims=True)
    t = np.cross(b, h)
    t /= np.linalg.norm(t, axis=-1, keepdims=True)
    td = np.arccos(np.clip((h * i).sum(-1), -1, 1))
    th = np.arccos(np.clip(h[..., 2], -1, 1))
    ip = i - (i * h).sum(-1, keepdims=True) * h
    ip /= np.linalg.norm(ip, axis=-1, keepdims=True)
    return np.arctan2((b * ip).sum(-1), (t * ip).sum(-1)), th, td


def test_node_directions_invert_the_plugins_mapping():
    rng = np.random.default_rng(1)
    pd = rng.uniform(-math.pi, math.pi, 500)
    td, th = rng.uniform(0.01, 1.5, 500), rng.uniform(0.01, 1.5, 500)
    L, V, x = node_directions(pd, td, th)
    p2, h2, d2 = _rusinkiewicz(L, V)
    np.testing.assert_allclose(np.c_[p2, h2, d2], np.c_[pd, th, td], atol=1e-9)
    # the plugin's Stokes x axis: normalize(cross(L − V, −L)) (both sides), ∝ h × d
    xo = np.cross(L - V, -L)
    xo /= np.linalg.norm(xo, axis=-1, keepdims=True)
    np.testing.assert_allclose(np.abs((xo * x).sum(-1)), 1.0, atol=1e-9)


@pytest.fixture(scope="module")
def small_file(tmp_path_factory):
    ax = default_axes(24, 23, 37)
    path = tmp_path_factory.mktemp("pbsdf") / "go.pbsdf"
    write_pbsdf(go_table(3.0), path, phi_d=ax[0], theta_d=ax[1], theta_h=ax[2],
                wavelengths_nm=WL_NM)  # fmt: skip
    return path


def test_s0_is_the_unpolarized_table(small_file):
    """M00 at every node with both directions above the horizon equals the unpolarized
    table's interpolant at that direction pair (float32 storage: 1e-6)."""
    f = read_pbsdf(small_file)
    assert f["wvls"].tolist() == WL_NM and f["M"].shape == (37, 23, 24, 5, 4, 4)
    P, T, H = np.meshgrid(f["phi_d"][0], f["theta_d"][0], f["theta_h"][0], indexing="ij")
    L, V, _ = node_directions(P, T, H)
    ok = (L[..., 2] > 1e-6) & (V[..., 2] > 1e-6)
    tab = go_table(3.0).table.evaluate(L[ok], V[ok], np.array(WL_NM) * 1e-9)  # (5, N)
    m00 = f["M"][..., 0, 0][ok].T.astype(float)
    np.testing.assert_allclose(m00, tab, rtol=1e-6, atol=1e-6 * tab.max())


def test_file_mueller_reciprocity(small_file):
    """Swapping light and view (φd → φd + π at equal θh, θd) transposes the Mueller matrix as
    M' = Q Mᵀ Q, Q = diag(1, 1, −1, 1) (reciprocity of Mueller matrices, van de Hulst,
    *Light Scattering by Small Particles*, 1957, §5.3; Jones J' = Jᵀ in mirrored frames):
    the GO table is reciprocal on its symmetric grid, so the file is too, to float32."""
    f = read_pbsdf(small_file)
    m = f["M"].astype(float)
    a, b = m[:18], m[18:36]  # φd and φd + π (37 nodes on [−π, π])
    np.testing.assert_allclose(f["phi_d"][0][18:36] - f["phi_d"][0][:18], math.pi, atol=1e-6)
    q = np.diag([1.0, 1, -1, 1])
    rev = np.einsum("ij,...kj,kl->...il", q, b, q)
    scale = m[..., 0, 0].max()
    np.testing.assert_allclose(rev, a, atol=1e-6 * scale, rtol=1e-5)
    # and not with Q = 1 (the sign of the U rows and columns is what reciprocity fixes)
    assert np.abs(np.einsum("...kj->...jk", b) - a).max() > 1e-2 * scale


def test_writer_errors(tmp_path):
    mt = go_table(3.0)
    with pytest.raises(ValueError, match="reads exactly 5 wavelengths in whole nanometres"):
        write_pbsdf(mt, tmp_path / "a.pbsdf")
    with pytest.raises(ValueError, match=r"wavelengths_nm must be 5 rising whole numbers"):
        write_pbsdf(mt, tmp_path / "a.pbsdf", wavelengths_nm=[450, 500, 550, 600])
    with pytest.raises(ValueError, match=r"must lie within the table's wavelengths"):
        write_pbsdf(mt, tmp_path / "a.pbsdf", wavelengths_nm=[400, 500, 550, 600, 650])
    with pytest.raises(ValueError, match=r"theta_h must lie within \[0, 1.5708\] rad"):
        write_pbsdf(mt, tmp_path / "a.pbsdf", theta_h=[0, 2.0], wavelengths_nm=WL_NM)
    with pytest.raises(ValueError, match="n_phi_d must be an integer >= 2, got 1"):
        default_axes(n_phi_d=1)
    with pytest.raises(TypeError, match="mt must be a MuellerTable"):
        write_pbsdf(mt.table, tmp_path / "a.pbsdf")
    assert not list(tmp_path.iterdir())  # nothing half-written


def test_reader_rejects_damaged_files(tmp_path, small_file):
    f = read_pbsdf(small_file)
    bad = dict(f, wvls=f["wvls"][:4].copy())
    _write_tensor_file(tmp_path / "w.pbsdf", bad)
    with pytest.raises(PbsdfFormatError, match=r"'wvls' must be uint16 of shape \(5,\)"):
        read_pbsdf(tmp_path / "w.pbsdf")
    m = f["M"].copy()
    m[3, 2, 1, 0, 0, 0] = -1.0
    _write_tensor_file(tmp_path / "n.pbsdf", dict(f, M=m))
    with pytest.raises(PbsdfFormatError, match="'M00' is negative at 1 nodes"):
        read_pbsdf(tmp_path / "n.pbsdf")
    m = f["M"].copy()
    m[3, 2, 1, 0, 0, 1] = 10 * m[3, 2, 1, 0, 0, 0] + 1
    _write_tensor_file(tmp_path / "r.pbsdf", dict(f, M=m))
    with pytest.raises(PbsdfFormatError, match="1 nodes are not realizable"):
        read_pbsdf(tmp_path / "r.pbsdf")
    (tmp_path / "x.pbsdf").write_bytes(b"hello")
    with pytest.raises(PbsdfFormatError, match="not a Mitsuba tensor file"):
        read_pbsdf(tmp_path / "x.pbsdf")


# ------------------------------------------------------------------ the real plugin
def _mitsuba_polarized():
    if importlib.util.find_spec("mitsuba") is None:
        return False
    out = subprocess.run(
        [sys.executable, "-c", "import mitsuba as mi; print(mi.variants())"],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    return "scalar_spectral_polarized" in out.stdout


def _worker(variant, bsdfs, wi, wo):
    args = {"variant": variant, "bsdfs": bsdfs, "wi": wi.tolist(), "wo": wo.tolist(),
            "wavelength": 550.0}  # fmt: skip
    res = subprocess.run(
        [sys.executable, str(HERE / "pbsdf_worker.py"), json.dumps(args)],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert res.returncode == 0, res.stderr[-3000:]
    data = json.loads(res.stdout.splitlines()[-1])
    return {k: np.moveaxis(np.array(v), 0, -1) for k, v in data.items()}


@pytest.mark.skipif(not _mitsuba_polarized(), reason="needs Mitsuba's scalar_spectral_polarized")
def test_measured_polarized_equals_roughconductor(tmp_path):
    """The file loaded into Mitsuba's own measured_polarized, evaluated at 200 direction pairs
    in the lobe (θi, θo ≤ 80°, |θo − θi| ≤ 14°, Δφ within 17° of the mirror) against
    roughconductor (Beckmann α = m, its Fresnel Mueller matrix): all 16 elements relative to
    M00. Measured (2° source table, default axes): median 0.15 %, p90 0.95 %, max 3.9 %; the
    max is the source table's 2° Δφ grid at grazing pairs (the table's own s0 alone: 5 %),
    the file adds ≤ 0.05 % median. And the same file in scalar_spectral (unpolarized) gives
    the polarized s0 to 1e-6."""
    path = write_pbsdf(go_table(2.0), tmp_path / "go.pbsdf", wavelengths_nm=WL_NM)
    rng = np.random.default_rng(7)
    n = 200
    ti = rng.uniform(0.05, math.radians(80), n)
    to = np.clip(ti + rng.uniform(-0.25, 0.25, n), 0.02, math.radians(80))
    pi_ = rng.uniform(0, 2 * math.pi, n)
    po = pi_ + math.pi + rng.uniform(-0.3, 0.3, n)
    wi, wo = frames.directions(ti, pi_), frames.directions(to, po)
    rc = {"type": "roughconductor", "distribution": "beckmann", "alpha": M_SLOPE,
          "eta": 0.2, "k": 3.0}  # fmt: skip
    pb = {"type": "measured_polarized", "filename": str(path), "alpha_sample": M_SLOPE}
    pol = _worker("scalar_spectral_polarized", {"rc": rc, "pb": pb}, wi, wo)
    err = np.abs(pol["pb"] - pol["rc"]).max(axis=(0, 1)) / pol["rc"][0, 0]
    summary = f"median {np.median(err):.3g}, p90 {np.percentile(err, 90):.3g}, max {err.max():.3g}"
    assert np.median(err) < 0.003 and np.percentile(err, 90) < 0.012, summary
    assert err.max() < 0.05, summary
    # the V (circular) coupling is really there and matched: M23 ≠ 0 out of the plane
    assert np.abs(pol["rc"][2, 3]).max() > 0.05 * pol["rc"][0, 0].max()
    unpol = _worker("scalar_spectral", {"pb": pb}, wi, wo)["pb"]
    np.testing.assert_allclose(unpol, pol["pb"][0, 0], rtol=1e-6, atol=1e-9)
