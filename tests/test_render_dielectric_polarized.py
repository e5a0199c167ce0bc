"""The emscatter_dielectric plugin in polarized variants (render/dielectric/polarized.py),
through tests/dielectric_polarized_worker.py (Dr.Jit variants are per process)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("mitsuba")
HERE = Path(__file__).parent
V = [[0.3, 0.2, -0.93], [0.5, -0.1, 0.86], [-0.6, 0.3, -0.74], [0.1, 0.7, 0.7]]
L = [[-0.4, 0.1, 0.91], [0.2, 0.3, -0.93], [0.5, -0.2, 0.84], [0.3, 0.1, 0.95]]


def _worker(**args):
    r = subprocess.run(
        [sys.executable, str(HERE / "dielectric_polarized_worker.py"), json.dumps(args)],
        capture_output=True, text=True, timeout=600, check=False,
    )  # fmt: skip
    assert r.returncode == 0, r.stderr[-3000:]
    return json.loads(r.stdout.strip().splitlines()[-1])


def _n(v):
    v = np.asarray(v, float)
    return (v / np.linalg.norm(v, axis=1, keepdims=True)).tolist()


@pytest.fixture(scope="module")
def pol():
    return _worker(variant="llvm_ad_spectral_polarized", n_theta=16, alpha=0.3, v=_n(V), l=_n(L))


def test_s0_equals_unpolarized_plugin(pol):
    """M₀₀ of the polarized plugin is the unpolarized plugin's value (both sides, all lobes)."""
    unp = _worker(variant="llvm_ad_spectral", n_theta=16, alpha=0.3, v=_n(V), l=_n(L))
    s0 = np.asarray(pol["em"], float).reshape(4, 4, -1, len(V))[0, 0, 0]
    ref = np.asarray(unp["em"], float).reshape(-1, len(V))[0]
    assert np.all(ref > 0)
    np.testing.assert_allclose(s0, ref, rtol=1e-6, atol=1e-9)


def test_transmission_matches_numpy_table(pol):
    """Light outside, viewer inside: eval = BtdfTable.evaluate_mueller(frame='mitsuba')·cosθl."""
    em = np.asarray(pol["em"], float).reshape(4, 4, -1, len(V))[:, :, 0]  # first slot
    ref = np.asarray(pol["np"], float)
    below = np.asarray(V)[:, 2] < 0
    np.testing.assert_allclose(em[..., below], ref[..., below], rtol=2e-4, atol=1e-6)


def test_smooth_limit_against_mitsuba_dielectric():
    """Small α: the normalized transmitted Mueller matrix at the refracted direction is Mitsuba's
    smooth, polarized ``dielectric`` (closed-form Fresnel transmission in Mitsuba's frames), for
    light from outside and from inside, within 1 % of M₀₀."""
    r = _worker(variant="llvm_ad_mono_polarized", n_theta=46, alpha=0.05, v=_n(V), l=_n(L),
                smooth=True)  # fmt: skip
    t = np.asarray(r["wo"])[:, 2] * np.asarray(V)[:, 2] < 0  # transmitted (not TIR) samples
    assert t.sum() >= 3
    ref = np.asarray(r["ref"], float)[..., t]
    em = np.asarray(r["em_t"], float)[..., t]
    assert np.all(em[0, 0] > 0)
    # off-diagonal polarization elements are visible (not a trivially diagonal check)
    assert np.max(np.abs(ref[0, 2] / ref[0, 0])) > 5e-3
    np.testing.assert_allclose(em / em[0, 0], ref / ref[0, 0], atol=1e-2)
