"""Emissivity speed contracts: σ⁰ evaluated in growing chunks (not one direction per call),
the multiple-scattering hv integrated to the accuracy the tolerance needs, the quadrature's
tolerance met or a warning naming the error reached."""

import math

import numpy as np

from emscatter.emissivity import hemispherical_reflectivity

TI = np.radians([0.0, 30.0, 60.0])


def _diag(s):
    z = np.zeros_like(s)
    return np.array([[s, z], [z, s]])


def test_sigma0_chunks_grow_geometrically():
    # Each solver call has a fixed cost (checks, dispatch): one call per direction made the
    # IEM emissivity 50× slower. Chunks grow ×8 up to ~1 s of work, so a fast σ⁰ over a
    # few thousand directions is a handful of calls per estimate.
    calls = []

    def lambert(ts, ps):
        calls.append(ts.shape)
        return _diag(4 * 0.3 * np.cos(TI[:, None, None]) * np.cos(ts))

    r, err, n = hemispherical_reflectivity(lambert, TI, tol=1e-6, budget_s=None)
    np.testing.assert_allclose(r, 0.3, rtol=1e-12)
    per_angle = n // TI.size
    # 1, 8, 64, 512, ... directions per call: ≤ log8(directions) + 2 calls per estimate
    bound = 2 * (math.ceil(math.log(per_angle, 8)) + 2)
    assert len(calls) <= bound, (len(calls), bound, per_angle)
    assert sum(math.prod(s[1:]) for s in calls) == per_angle
