"""Property-based stress tests (hypothesis) over the whole box of issue 11.

θ ∈ [0, 89.99°], φ ∈ [0, 2π), kσ ∈ [1e-6, 1e3], kℓ ∈ [1e-3, 1e6], |ε| up to 1e9 with
Re ε < 0 allowed, PEC, Gaussian / exponential / power-law (H ∈ [0.01, 0.99]) correlations;
every method (``auto``, ``spm``, ``go``, ``po``) through the public API. Laws:

* bistatic: no NaN/inf, σ⁰ ≥ 0, reciprocity, a warning exactly when the report says invalid;
* emissivity: finite; ``e ∈ [0, 1]`` and ``r_coh + r_incoh ≤ 1`` (within the quadrature error)
  wherever the result is reported valid; wherever not, a flag (``energy_ok``/``angle_valid``)
  and a warning naming the angle in degrees;
* ``auto`` is continuous across a method switch: on both sides of a validity limit the σ⁰
  lobe (angles within 20 dB of its peak, the validity maps' metric) differs by no more than
  the two methods' documented errors against the method of moments added
  (validation/validity_maps/validity_pec.csv, largest error where each is valid);
* every call answers within :data:`CALL_TIME_BOUND` seconds.

Profiles (registered in ``tests/conftest.py``): ``dev`` (the default) runs the example counts
in :data:`EXAMPLES` with fresh examples and a local database of failures; ``ci`` (where ``CI``
is set) the same counts derandomized, without a database; ``long``
(``HYPOTHESIS_PROFILE=long``) 20× as many:
``HYPOTHESIS_PROFILE=long python -m pytest -q tests/test_properties.py``. Failures found are
kept below as explicit ``@example`` regressions.
"""

from __future__ import annotations

import csv
import math
import os
import time
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import assume, example, given, note, settings
from hypothesis import strategies as st

import emscatter as em
from emscatter import dispatch
from emscatter.emissivity import ENERGY_ATOL
from emscatter.solvers.select import ValidityWarning

K = 2 * math.pi  # λ = 1 m: kσ and kℓ are the parameters
#: Seconds any single call may take on an idle 2-core machine (the slowest seen is ~9 s),
#: scaled up by the load when the machine is shared (load average / cores).
CALL_TIME_BOUND = 60.0


def time_bound() -> float:
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else 0.0
    return CALL_TIME_BOUND * max(1.0, load / (os.cpu_count() or 1))


EXAMPLES = {"bistatic": 40, "emissivity": 16, "continuity": 12}
PROFILE = settings.get_current_profile_name()  # loaded by tests/conftest.py
SCALE = 20 if PROFILE == "long" else 1


def examples(name: str) -> int:
    return EXAMPLES[name] * SCALE


# ----------------------------------------------------------------------------- strategies
def log_uniform(lo: float, hi: float):
    return st.floats(math.log10(lo), math.log10(hi)).map(lambda x: 10.0**x)


angles = st.floats(0.0, math.radians(89.99))
azimuths = st.floats(0.0, 2 * math.pi, exclude_max=True)
methods = st.sampled_from(["auto", "spm", "go", "po"])


@st.composite
def permittivities(draw):
    if draw(st.integers(0, 5)) == 0:
        return "pec"
    re = draw(st.sampled_from([-1.0, 1.0])) * draw(log_uniform(1.01, 1e9))
    im = draw(st.one_of(st.just(0.0), log_uniform(1e-6, 1e9)))
    return complex(re, im)


@st.composite
def roughnesses(draw, dimension=2):
    kind = draw(st.sampled_from(["gaussian", "exponential", "power-law"]))
    ks = draw(log_uniform(1e-6, 1e3))
    kl = draw(log_uniform(1e-3, 1e6))
    extra = {"hurst": draw(st.floats(0.01, 0.99))} if kind == "power-law" else {}
    return em.roughness(kind, sigma=ks / K, length=kl / K, dimension=dimension, **extra)


def timed(fn, *args, **kwargs):
    """``(result, warnings)``; fails if the call takes longer than the bound."""
    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        out = fn(*args, **kwargs)
    dt = time.perf_counter() - t0
    assert dt < time_bound(), f"{fn.__name__} took {dt:.1f} s (bound {time_bound():.0f} s)"
    note(f"{fn.__name__}: {dt:.2f} s")
    return out, [w for w in rec if issubclass(w.category, ValidityWarning)]


def _describe(rough, eps) -> str:
    return f"{rough!r}, kσ={K * rough.sigma:.3g}, kℓ={K * rough.length:.3g}, eps={eps}"


# ----------------------------------------------------------------------------- bistatic
@settings(max_examples=examples("bistatic"))
@given(
    rough=roughnesses(),
    eps=permittivities(),
    method=methods,
    geometry=st.lists(st.tuples(angles, angles, azimuths, azimuths), min_size=1, max_size=4),
)
def test_bistatic_is_physical_reciprocal_and_warns_when_invalid(rough, eps, method, geometry):
    note(_describe(rough, eps))
    ti, ts, ps, pi_ = (np.array(v) for v in zip(*geometry, strict=True))
    fwd, warned = timed(
        em.bistatic,
        rough,
        eps,
        wavelength=1.0,
        theta_i=ti,
        theta_s=ts,
        phi_s=ps,
        phi_i=pi_,
        method=method,
    )
    s = fwd.sigma0
    assert np.all(np.isfinite(s)) and np.all(s >= 0), s
    report = fwd.info["validity"]
    assert bool(warned) == (not report["valid"]), (report, [str(w.message) for w in warned])
    rev, _ = timed(
        em.bistatic,
        rough,
        eps,
        wavelength=1.0,
        theta_i=ts,
        theta_s=ti,
        phi_s=pi_ + math.pi,
        phi_i=ps + math.pi,
        method=fwd.method if method != "auto" else "auto",
        out_of_range="ignore",
    )
    assert rev.method == fwd.method
    r = np.swapaxes(rev.sigma0, 0, 1)
    scale = np.maximum(np.abs(s), np.abs(r)).max(axis=(0, 1), keepdims=True) + 1e-300
    assert np.max(np.abs(s - r) / scale) < 1e-8


# ----------------------------------------------------------------------------- emissivity
@settings(max_examples=examples("emissivity"))
@given(
    rough=roughnesses(),
    eps=permittivities(),
    method=methods,
    theta=st.lists(angles, min_size=1, max_size=3, unique=True),
)
# found by HYPOTHESIS_PROFILE=long (issue 23): kσ = 1, kℓ = 1.15e4, a lossless plasma-like
# ε, one angle near grazing; took 86 s (the power-law spectrum's large-s series per element)
@example(
    rough=em.roughness("power-law", sigma=0.159, length=1825.7, hurst=0.1945, dimension=2),
    eps=complex(-11471.49, 0.0),
    method="auto",
    theta=[0.71199, 1.55892, 1.13e-97],
)
def test_emissivity_in_0_1_wherever_valid_else_flagged_and_warned(rough, eps, method, theta):
    note(_describe(rough, eps))
    ti = np.array(sorted(theta))
    res, warned = timed(
        em.emissivity, rough, eps, wavelength=1.0, theta_i=ti, method=method, tol=1e-3
    )
    e, err = res.emissivity, res.error
    assert np.all(np.isfinite(e)) and np.all(np.isfinite(err))
    margin = np.maximum(err, 1e-3) + ENERGY_ATOL  # the quadrature's accuracy: tol or its estimate
    inside = np.all((e >= -margin) & (e <= 1 + margin), axis=0)
    inside &= np.all((res.coherent >= -margin) & (res.incoherent >= -margin), axis=0)
    np.testing.assert_array_equal(res.energy_ok, inside)
    # where the method used at an angle reports itself valid but breaks energy, the API's
    # check is what catches it (a gap in that method's validity conditions; noted, and
    # listed in validation/extreme_cases): the result is flagged and warned like any other.
    for j, name in enumerate(res.info["methods"]):
        own = dispatch.validity_report(name, rough, res.k, eps=eps, theta_i=ti[j : j + 1])
        if own["valid"] and not inside[j]:
            note(f"{name} valid by its own report at {math.degrees(ti[j]):.4g}°: e = {e[:, j]}")
    report = res.info["validity"]
    final_ok = np.asarray(report["angle_valid"]) & report["roughness_valid"]
    # emissivity in [0, 1] (and r ≤ 1) wherever the result is reported valid
    assert np.all(inside[final_ok]), (e, report)
    assert not np.any(res.energy_ok < inside) and not np.any(res.info["energy"]["ok"] != inside)
    if not res.info["validity"]["valid"]:
        assert warned, res.info["validity"]
    text = " ".join(str(w.message) for w in warned)
    for j in np.flatnonzero(~inside):
        assert f"{math.degrees(ti[j]):.4g}°" in text, text


# ----------------------------------------------------------------------------- continuity
def _documented_errors() -> dict[str, float]:
    """Largest σ⁰ error [dB] against the method of moments where each method is valid."""
    path = Path(__file__).parents[1] / "validation" / "validity_maps" / "validity_pec.csv"
    worst: dict[str, float] = {}
    with open(path, newline="") as fh:
        for row in csv.DictReader(fh):
            if row["valid"] == "True" and row["error_dB"] not in ("", "nan"):
                name = {"spm1": "spm"}.get(row["method"], row["method"])
                worst[name] = max(worst.get(name, 0.0), float(row["error_dB"]))
    return worst


DOCUMENTED = _documented_errors()
#: (parameter, limit) pairs where auto switches between methods: SPM's kσ ≤ 0.3, GO's
#: stationary phase (2kσ)² ≥ 10, PO's kℓ > 4, and the slope limits of SPM (0.3) and PO (0.4).
SWITCHES = [("k_sigma", 0.3), ("k_sigma", math.sqrt(10) / 2), ("k_l", 4.0), ("k_l", 6.0)]


def _lobe_rms_db(a: np.ndarray, b: np.ndarray) -> float:
    keep = (a > 1e-2 * a.max()) & (b > 1e-2 * b.max())
    return float(np.sqrt(np.mean((10 * np.log10(a[keep] / b[keep])) ** 2)))


@settings(max_examples=examples("continuity"))
@given(
    switch=st.sampled_from(SWITCHES),
    other=log_uniform(1.0, 300.0),
    eps=st.sampled_from(["pec", 3.0, 17 + 2j]),
    theta_i=st.floats(math.radians(5), math.radians(50)),
)
def test_auto_is_continuous_across_method_switches(switch, other, eps, theta_i):
    param, limit = switch
    ts = np.clip(theta_i + np.radians(np.linspace(-20, 20, 17)), 0, math.radians(89))
    out = []
    for side in (1 - 1e-6, 1 + 1e-6):
        ks, kl = (limit * side, other) if param == "k_sigma" else (other / 30, limit * side)
        rough = em.GaussianCorrelation(ks / K, kl / K)
        res, _ = timed(
            em.bistatic,
            rough,
            eps,
            wavelength=1.0,
            theta_i=theta_i,
            theta_s=ts,
            phi_s=0.0,
            out_of_range="ignore",
        )
        out.append(res)
    a, b = out
    assume(a.method != b.method)
    assume(a.info["validity"]["roughness_valid"] and b.info["validity"]["roughness_valid"])
    allowed = DOCUMENTED[a.method] + DOCUMENTED[b.method]
    for p in ("hh", "vv"):
        jump = _lobe_rms_db(a.pol(p), b.pol(p))
        note(f"{a.method} -> {b.method} {p}: {jump:.3f} dB (allowed {allowed:.3f})")
        assert jump <= allowed


def test_the_documented_errors_are_read():
    assert {"spm", "po", "go"} <= set(DOCUMENTED) and all(0 < v < 3 for v in DOCUMENTED.values())


@pytest.mark.parametrize("profile", ["ci", "dev", "long"])
def test_profiles_exist(profile):
    settings.get_profile(profile)


def test_ci_is_derandomized_and_local_runs_explore():
    assert settings.get_profile("ci").derandomize and settings.get_profile("ci").database is None
    for name in ("dev", "long"):
        assert not settings.get_profile(name).derandomize
        assert settings.get_profile(name).database is not None
