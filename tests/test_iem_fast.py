"""The linear-space backscatter walk of the compiled IEM kernel (iem_numba.fast_pair,
transition_lin) against the log-space walk it replaces where safe, and against numpy."""

from __future__ import annotations

import math

import numpy as np
import pytest

from emscatter.solvers import iem, iem_jit
from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation

pytestmark = pytest.mark.skipif(
    not iem_jit.enabled(),
    reason="numba kernels off (EMSCATTER_KERNELS=numpy) or numba not installed",
)

THETA = np.radians(np.linspace(0.0, 89.0, 37))
EPS = (15 + 2j, 3.0, 80 + 20j, "pec")


def _both(spec, dim, ks, kl, eps, *, transition=True, rtol=1e-12):
    si, cs = np.sin(THETA), np.cos(THETA)
    K = 2.0 * kl * si
    pref = math.log(math.pi * kl * kl) if dim == 2 else math.log(0.5 * math.pi * kl)
    kw = dict(transition=transition, rtol=rtol, max_terms=10**6)
    fast = iem_jit.backscatter(si, cs, eps, ks, K, pref, spec, dim, report=True, **kw)
    slow = iem_jit.backscatter(si, cs, eps, ks, K, pref, spec, dim, fast=False, **kw)
    return fast, slow


def _rel(a, b):
    return float(np.max(np.abs(a - b) / (np.abs(b) + 1e-300)))


@pytest.mark.parametrize("spec", [iem_jit.GAUSSIAN, iem_jit.EXPONENTIAL], ids=["gauss", "exp"])
@pytest.mark.parametrize("ks", [0.05, 0.3, 1.1, 2.0, 3.0])
def test_fast_walk_equals_log_space_walk(spec, ks):
    """hh, vv to 1e-10 relative (rtol 1e-12) over kℓ, ε (dielectrics, PEC), 0–89°, with and
    without the Fresnel transition, surfaces and profiles; the fast path is taken for every
    angle inside the model's range except a very lossy high-ε medium at kσ = 3."""
    for dim in (2, 1):
        for kl in (0.5, 3.0, 20.0) if dim == 2 else (6.0,):
            for eps in EPS:
                for transition in (True, False) if dim == 2 else (True,):
                    fast, slow = _both(spec, dim, ks, kl, eps, transition=transition)
                    assert fast[3] == slow[3] == 0
                    assert _rel(fast[0], slow[0]) < 1e-10, (dim, kl, eps, transition)
                    assert _rel(fast[1], slow[1]) < 1e-10, (dim, kl, eps, transition)
                    if not (ks == 3.0 and eps == 80 + 20j):
                        assert np.all(fast[4]), (dim, kl, eps, transition)


@pytest.mark.parametrize("spec", [iem_jit.GAUSSIAN, iem_jit.EXPONENTIAL], ids=["gauss", "exp"])
def test_large_roughness_takes_the_log_space_path(spec):
    """Outside the double range of the linear walk (kσ ≫ 3) every angle of a dielectric falls
    back, and the answer is the log-space one."""
    for ks in (12.0, 30.0):
        fast, slow = _both(spec, 2, ks, 10.0, 15 + 2j)
        assert not np.any(fast[4])
        assert _rel(fast[0], slow[0]) < 1e-10 and _rel(fast[1], slow[1]) < 1e-10
    fast, slow = _both(spec, 2, 12.0, 3.0, 3.0)  # mixed: some angles each way
    assert 0 < np.sum(fast[4]) < fast[4].size
    assert _rel(fast[0], slow[0]) < 1e-10 and _rel(fast[1], slow[1]) < 1e-10


def test_default_tolerance_is_met():
    """At the default rtol = 1e-8 the fast walk is within rtol of a 1e-14 reference (its tail
    test bounds every series; the transition sums at rtol·1e-2)."""
    for spec in (iem_jit.GAUSSIAN, iem_jit.EXPONENTIAL):
        for ks, kl, eps in ((0.05, 0.5, 80 + 20j), (0.44, 3.3, 15 + 2j), (1.1, 6.0, 3.0),
                            (2.5, 10.0, "pec")):  # fmt: skip
            fast, _ = _both(spec, 2, ks, kl, eps, rtol=1e-8)
            ref, _ = _both(spec, 2, ks, kl, eps, rtol=1e-14)
            assert np.all(fast[4])
            assert _rel(fast[0], ref[0]) < 1e-8 and _rel(fast[1], ref[1]) < 1e-8


@pytest.mark.parametrize(
    "rough",
    [GaussianCorrelation(0.3, 1.5), ExponentialCorrelation(1.1, 6.0),
     GaussianCorrelation(2.0, 8.0, dimension=1), ExponentialCorrelation(0.05, 10.0)],
    ids=["gauss", "exp", "gauss-profile", "exp-small"],
)  # fmt: skip
def test_backscatter_equals_numpy_reference(rough, monkeypatch):
    """iem.bistatic at exact backscatter (default options, k = 1): compiled = numpy to 1e-10."""
    out = {}
    for mode in ("numba", "numpy"):
        monkeypatch.setenv("EMSCATTER_KERNELS", mode)
        out[mode] = [
            iem.bistatic(rough, eps, 1.0, THETA, THETA, math.pi, coherent=False,
                         crosspol=False, rtol=1e-12).sigma0
            for eps in EPS
        ]  # fmt: skip
    for a, b in zip(out["numba"], out["numpy"], strict=True):
        assert _rel(a[0, 0], b[0, 0]) < 1e-10 and _rel(a[1, 1], b[1, 1]) < 1e-10
