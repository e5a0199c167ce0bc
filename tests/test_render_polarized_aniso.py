"""Anisotropic Mueller tables through the polarized plugin (emscatter.render.polarized): GO
gold with anisotropic Beckmann slopes (m_x = 0.2, m_y = 0.4, separable Smith) against
Mitsuba's anisotropic ``roughconductor`` (alpha_u, alpha_v) in ``llvm_ad_spectral_polarized``,
the plugin equal to the table's own Mueller matrices at its nodes (frames exact), and s0 equal
to the unpolarized plugin. Mitsuba runs in subprocesses (tests/plugin_polarized_worker.py)."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from emscatter.brdf import frames

sys.path.insert(0, str(Path(__file__).parent))
from test_render_polarized import STOKES_IN, _llvm_polarized  # noqa: E402

HERE = Path(__file__).parent
POL, UNPOL = "llvm_ad_spectral_polarized", "llvm_ad_spectral"
needs_mitsuba = pytest.mark.skipif(not _llvm_polarized(), reason=f"needs Mitsuba's {POL}")


def _pairs(n=60, seed=5):
    """Pairs around the mirror direction, θ ≤ 70°, all azimuths (the lobe turns with φi)."""
    rng = np.random.default_rng(seed)
    ti = rng.uniform(0.05, math.radians(70), n)
    to = np.clip(ti + rng.uniform(-0.2, 0.2, n), 0.02, math.radians(70))
    pi_ = rng.uniform(0, 2 * math.pi, n)
    po = pi_ + math.pi + rng.uniform(-0.25, 0.25, n)
    return frames.directions(ti, pi_), frames.directions(to, po)


def _worker(variant, n_theta):
    wi, wo = _pairs()
    args = {"table": "aniso", "variant": variant, "n_theta": n_theta, "n_phi": 4 * n_theta,
            "m_x": 0.2, "m_y": 0.4, "wi": wi.tolist(), "wo": wo.tolist(), "n_nodes": 30,
            "seed": 1}  # fmt: skip
    res = subprocess.run(
        [sys.executable, str(HERE / "plugin_polarized_worker.py"), json.dumps(args)],
        capture_output=True, text=True, timeout=900,
    )  # fmt: skip
    assert res.returncode == 0, res.stderr[-3000:]
    return {k: np.array(v) for k, v in json.loads(res.stdout.splitlines()[-1]).items()}


def _lobe_error(out):
    em, rc = out["em"], out["rc"]
    lobe = rc[:, 0, 0] >= 0.05 * rc[:, 0, 0].max()
    s_em = np.einsum("nij,sj->nsi", em, STOKES_IN)
    s_rc = np.einsum("nij,sj->nsi", rc, STOKES_IN)
    return (np.abs(s_em - s_rc).max(axis=(1, 2)) / rc[:, 0, 0])[lobe], lobe


@needs_mitsuba
def test_anisotropic_mueller_plugin():
    """At the table's nodes the plugin returns the table's Mueller matrices in Mitsuba's
    frames (numpy ``to_mitsuba``) to float32: 1e-4 of max(s0, 0.1 % of the peak) at 30 nodes
    in and around the lobe (measured 2e-5).
    Against ``roughconductor`` (alpha_u = 0.2, alpha_v = 0.4) the Stokes error in the lobe is
    the table's interpolation error, converging as h²: 12 × 48 nodes (7.5°) median 3.9 %,
    p90 11 %; 22 × 88 (4.1°) median 1.1 %, p90 3.3 % (ratio 3.6 ≈ (7.5/4.1)²). s0 equals
    the unpolarized plugin's value to 5e-6 (float32)."""
    coarse = _worker(POL, 12)
    en, rn = coarse["em_nodes"], coarse["ref_nodes"]
    floor = 1e-3 * rn[:, 0, 0].max()  # far tail (1e-8 … 1e-62: float32 rounding of w)
    node_err = np.abs(en - rn).max(axis=(1, 2)) / np.maximum(rn[:, 0, 0], floor)
    assert node_err.max() < 1e-4, node_err
    # the matrices are not trivially diagonal: the frames are really tested
    assert np.abs(rn[:, 2, 3]).max() > 0.05 * rn[:, 0, 0].max()
    unpol = _worker(UNPOL, 12)
    np.testing.assert_allclose(coarse["em"][:, 0, 0], unpol["em"], rtol=5e-6, atol=1e-9)
    np.testing.assert_allclose(coarse["em_nodes"][:, 0, 0], unpol["em_nodes"], rtol=5e-6,
                               atol=1e-9)  # fmt: skip
    e12, lobe = _lobe_error(coarse)
    fine = _worker(POL, 22)
    e22, _ = _lobe_error(fine)
    assert lobe.sum() >= 40
    summary = (
        f"12: median {np.median(e12):.3g} p90 {np.percentile(e12, 90):.3g}; 22: median "
        f"{np.median(e22):.3g} p90 {np.percentile(e22, 90):.3g} max {e22.max():.3g}"
    )
    print("anisotropic polarized plugin vs roughconductor:", summary)
    assert np.median(e22) < 0.015 and np.percentile(e22, 90) < 0.045, summary
    assert np.median(e12) > 2.5 * np.median(e22), summary  # interpolation, converging
