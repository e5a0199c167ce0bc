"""The renderer ↔ emscatter frame conversion, checked against Mitsuba 3's own
``roughconductor`` (run for real): the GO σ⁰ at the converted angles is Mitsuba's BRDF.

Tolerance 1e-2 relative: Mitsuba's Smith G1 is Walter et al.'s (2007, eq. 27) rational
approximation, emscatter's the exact Smith (see tests/test_mitsuba_go.py).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from brdf_helpers import go_fr, mitsuba_fr, mitsuba_variant, random_directions
from emscatter.brdf import frames
from emscatter.spectra import GaussianCorrelation

ETA, KAPPA = 0.2, 3.0
EPS = (ETA + 1j * KAPPA) ** 2


def test_round_trip_and_mirror():
    rng = np.random.default_rng(1)
    ti, to = rng.uniform(0, 1.5, (2, 50))
    pi_, po = rng.uniform(-4, 4, (2, 50))
    back = frames.from_emscatter(*frames.to_emscatter(ti, pi_, to, po))
    for a, b in zip(back, (ti, pi_, to, po), strict=True):
        np.testing.assert_allclose(a, b, atol=1e-15)
    # the renderer's mirror direction is emscatter's specular direction
    wi = frames.directions(ti, pi_)
    t_o, p_o = frames.angles(frames.mirror(wi))
    et, es, ps, ei = frames.to_emscatter(ti, pi_, t_o, p_o)
    np.testing.assert_allclose(es, et, atol=1e-12)
    np.testing.assert_allclose(np.cos(ps - ei), 1.0, atol=1e-12)
    np.testing.assert_allclose(frames.fold_dphi(p_o - pi_), math.pi, atol=1e-12)


def test_angles_rejects_bad_vectors():
    with pytest.raises(ValueError, match="shape"):
        frames.angles(np.zeros((4, 2)))
    with pytest.raises(ValueError, match="zero vector"):
        frames.angles(np.zeros((1, 3)))


def _significant_rel(ours, theirs):
    sig = np.maximum(ours, theirs) > 1e-4 * theirs.max()
    return np.abs(ours - theirs)[sig] / np.maximum(ours, theirs)[sig], sig


def test_conversion_matches_mitsuba_anisotropic():
    mi = pytest.importorskip("mitsuba")
    if mitsuba_variant(mi) is None:
        pytest.skip("no Mitsuba variant loads here")
    rng = np.random.default_rng(7)
    # anisotropic roughness: a lobe rotated by π or with swapped axes fails loudly
    rough = GaussianCorrelation(0.1, 0.5, length_y=1.5)  # α_x = 0.4, α_y = 0.133
    bsdf = {
        "type": "roughconductor",
        "distribution": "beckmann",
        "eta": ETA,
        "k": KAPPA,
        "alpha_u": 2 * 0.1 / 0.5,
        "alpha_v": 2 * 0.1 / 1.5,
    }
    wi = random_directions(rng, 400, math.radians(80))
    # half the outgoing directions near the mirror, where the lobe is
    near = frames.mirror(wi[:200]) + rng.normal(0, 0.15, (200, 3)) * [1, 1, 0]
    near[:, 2] = np.abs(near[:, 2]) + 0.05
    wo = np.concatenate(
        [
            near / np.linalg.norm(near, axis=1)[:, None],
            random_directions(rng, 200, math.radians(80)),
        ]
    )
    theirs = mitsuba_fr(mi, bsdf, wi, wo)
    ours = go_fr(rough, EPS, wi, wo)
    rel, sig = _significant_rel(ours, theirs)
    assert sig.sum() > 150
    assert rel.max() < 1e-2, f"max relative difference {rel.max():.3g}"
    # the tempting mistake (φi taken as is, without + π) is far off
    wrong = go_fr(rough, EPS, wi, wo, convert=lambda ti, pi_, to, po: (ti, to, po, pi_))
    rel_wrong, _ = _significant_rel(wrong, theirs)
    assert rel_wrong.max() > 0.5
