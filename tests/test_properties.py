"""Property-based stress tests (hypothesis) over the whole box of issue 11.

θ ∈ [0, 89.99°], φ ∈ [0, 2π), kσ ∈ [1e-6, 1e3], kℓ ∈ [1e-3, 1e6], |ε| up to 1e9 with
Re ε < 0 allowed, PEC, Gaussian / exponential / power-law (H ∈ [0.01, 0.99]) correlations;
every method (``auto``, ``spm``, ``go``, ``po``) through the public API. Laws:

* bistatic: no NaN/inf, σ⁰ ≥ 0, reciprocity, a warning exactly when the report says invalid;
* emissivity: finite; ``e ∈ [0, 1]`` and ``r_coh + r_incoh ≤ 1`` (within the quadrature error)
  wherever the result is reported valid; wherever not, a flag (``energy_ok``/``angle_valid``)
  and a warning naming the angle in degrees;
* ``auto`` is continuous across a method switch: on both sides of a validity limit the σ⁰
  lobe (angles within 20 dB of its peak, the validity maps' metric) and the backscatter σ⁰
  (all four polarizations) differ by at most :data:`MAX_JUMP_DB` (0.5 dB; issue 20), also at
  random roughness (measured-map edges included);
* ``auto`` in backscatter on a rough dielectric: ``hv = vh > 0``; ``σhh ≤ σvv`` over the
  Oh et al. (1992) box (xfail while the IEM's co-pol ratio is inverted);
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
from emscatter import method_resolution as dispatch
from emscatter.emissivity import ENERGY_ATOL, time_budget
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
    """``(result, warnings)``; fails if the call takes longer than the bound. The library's
    time budget (emscatter.emissivity.time_budget) is the same bound: an integral that would
    exceed it stops refining (its error says so) or is refused early, not after the bound."""
    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as rec, time_budget(0.9 * time_bound()):
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


#: Largest σ⁰ change [dB] allowed across a switch (issue 20): auto blends the methods over a
#: transition band with weights continuous by construction (emscatter.solvers.blend).
MAX_JUMP_DB = 0.5


def _sides(param, limit, other):
    for side in (1 - 1e-6, 1 + 1e-6):
        ks, kl = (limit * side, other) if param == "k_sigma" else (other / 30, limit * side)
        yield em.GaussianCorrelation(ks / K, kl / K)


@settings(max_examples=examples("continuity"))
@given(
    switch=st.sampled_from(SWITCHES),
    other=log_uniform(1.0, 300.0),
    eps=st.sampled_from(["pec", 3.0, 17 + 2j]),
    theta_i=st.floats(math.radians(5), math.radians(50)),
)
# issue 20/23: auto jumped 2.86 dB (VV) / 0.93 dB (HH) from iem to go here
@example(switch=("k_sigma", math.sqrt(10) / 2), other=7.5, eps=3.0, theta_i=0.8125)
def test_auto_is_continuous_across_method_switches(switch, other, eps, theta_i):
    ts = np.clip(theta_i + np.radians(np.linspace(-20, 20, 17)), 0, math.radians(89))
    out = []
    for rough in _sides(*switch, other):
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
    for p in ("hh", "vv"):
        jump = _lobe_rms_db(a.pol(p), b.pol(p))
        note(f"{a.method} -> {b.method} {p}: {jump:.3f} dB")
        assert jump <= MAX_JUMP_DB


def _backscatter_switch_cases(test):
    """The backscatter continuity cases: any switch of :data:`SWITCHES` (random other
    parameter, medium, angle) and the examples found so far."""
    for ex in (
        dict(switch=("k_sigma", math.sqrt(10) / 2), other=7.5, eps=3.0, theta_i=0.8125),
        dict(switch=("k_sigma", 0.3), other=5.0, eps=17 + 2j, theta_i=0.7),  # spm ↔ po/iem: hv
        dict(switch=("k_sigma", 0.3), other=17.8, eps=3.0, theta_i=1.0),  # was xfail (issue 20)
        # a corner: above SPM's kσ = 0.3 the IEM for kℓ < 4, PO beyond (0.53 dB hh step
        # before the blend's weights were continuous)
        dict(switch=("k_l", 4.0), other=10**0.875, eps="pec", theta_i=1.0),
        # a fresh-example find: SPM's slope and kσ limits meet (cross-pol stepped 1.9 dB with
        # the probing blend: weights 0.53/0.47 → 0.77/0.23 between IEM and SPM)
        dict(switch=("k_sigma", 0.3), other=10**0.125, eps=3.0, theta_i=1.0),
    ):
        test = example(**ex)(test)
    test = given(
        switch=st.sampled_from(SWITCHES),
        other=log_uniform(1.0, 300.0),
        eps=st.sampled_from(["pec", 3.0, 17 + 2j]),
        theta_i=st.floats(math.radians(5), math.radians(60)),
    )(test)
    return settings(max_examples=examples("continuity"))(test)


# a fresh-example find: a co-pol step at GO's switch where the probing blend (before the
# continuous weights of emscatter.solvers.blend) changed its set of methods
@example(switch=("k_sigma", math.sqrt(10) / 2), other=10**0.75, eps="pec", theta_i=1.0)
@_backscatter_switch_cases
def test_auto_backscatter_is_continuous_with_crosspol(switch, other, eps, theta_i):
    """Backscatter co-pol (hh, vv) with the cross-pol terms on: continuous at every switch. The
    first example stepped 0.69 dB (hh) while an earlier, probing blend skipped the IEM region
    (kσ 1.50–1.58) between PO and GO on the GO side."""
    a, b = _backscatter_sides(switch, other, eps, theta_i)
    jump = np.abs(10 * np.log10(a / b))[[0, 1], [0, 1]]
    note(f"co-pol jumps [dB] {jump}")
    assert np.all(jump <= MAX_JUMP_DB)


def _backscatter_sides(switch, other, eps, theta_i):
    out = []
    for rough in _sides(*switch, other):
        res, _ = timed(
            em.backscatter, rough, eps, wavelength=1.0, theta_i=theta_i, out_of_range="ignore"
        )
        out.append(res.sigma0)
    a, b = out
    assume(np.all(a > 1e-30) and np.all(b > 1e-30))  # (Gaussian at large kℓ: underflow)
    return a, b


@_backscatter_switch_cases
def test_auto_backscatter_crosspol_is_continuous(switch, other, eps, theta_i):
    """The same, cross-pol (hv, vh: SPM2 / IEM multiple scattering by branch)."""
    a, b = _backscatter_sides(switch, other, eps, theta_i)
    jump = np.abs(10 * np.log10(a / b))[[0, 1], [1, 0]]
    note(f"cross-pol jumps [dB] {jump}")
    assert np.all(jump <= MAX_JUMP_DB)


@settings(max_examples=examples("continuity"))
@given(
    kind=st.sampled_from(["gaussian", "exponential"]),
    ks=log_uniform(0.02, 30.0),
    kl=log_uniform(0.5, 300.0),
    eps=st.sampled_from(["pec", 3.0, 17 + 2j]),
    axis=st.sampled_from([0, 1]),
)
def test_auto_backscatter_is_continuous_anywhere(kind, ks, kl, eps, axis):
    """No switch is listed here: any roughness, a relative step of 1e-6 in kσ or kℓ (the
    measured-map cell edges and tolerance switches included)."""
    out = []
    for side in (1 - 1e-6, 1 + 1e-6):
        s, l_ = (ks * side, kl) if axis == 0 else (ks, kl * side)
        rough = em.roughness(kind, sigma=s / K, length=l_ / K)
        res, _ = timed(
            em.backscatter, rough, eps, wavelength=1.0, theta_i=0.6, out_of_range="ignore"
        )
        out.append(res.sigma0)
    a, b = out
    assume(np.all(a > 1e-30) and np.all(b > 1e-30))
    assert np.all(np.abs(10 * np.log10(a / b)) <= MAX_JUMP_DB)


@settings(max_examples=examples("continuity"))
@given(
    kind=st.sampled_from(["gaussian", "exponential"]),
    ks=log_uniform(0.01, 5.0),
    kl=log_uniform(0.5, 20.0),
    eps=st.tuples(st.floats(1.5, 80.0), st.floats(0.0, 10.0)).map(lambda t: complex(*t)),
    theta=st.lists(st.floats(math.radians(5), math.radians(70)), min_size=1, max_size=3),
)
@example(kind="exponential", ks=0.13, kl=5.0, eps=15 + 2j, theta=[math.radians(40)])  # spm
@example(kind="exponential", ks=0.5, kl=10.0, eps=15 + 2j, theta=[math.radians(40)])  # po
def test_auto_backscatter_crosspol_of_rough_dielectrics(kind, ks, kl, eps, theta):
    """Issue 20: auto gave hv = 0 in backscatter on the spm and po branches. A rough
    dielectric depolarizes (second order): hv = vh > 0 on every branch."""
    rough = em.roughness(kind, sigma=ks / K, length=kl / K)
    res, _ = timed(
        em.backscatter, rough, eps, wavelength=1.0, theta_i=np.array(theta), out_of_range="ignore"
    )
    hv, vh = res.sigma0[0, 1], res.sigma0[1, 0]
    note(f"{res.method}: hv {10 * np.log10(hv)} dB")
    np.testing.assert_allclose(hv, vh, rtol=1e-12)
    assert np.all(hv > 0), (res.method, hv)


@settings(max_examples=examples("continuity"))
@given(
    kind=st.sampled_from(["gaussian", "exponential"]),
    ks=st.floats(0.1, 6.0),
    kl=st.floats(2.6, 19.7),
    eps=st.tuples(st.floats(4.0, 25.0), st.floats(0.5, 5.0)).map(lambda t: complex(*t)),
    theta=st.floats(math.radians(10), math.radians(70)),
)
def test_auto_backscatter_hh_below_vv_in_the_oh_box(kind, ks, kl, eps, theta):
    """Oh, Sarabandi & Ulaby (IEEE TGRS 30, 370, 1992): over bare soils with kσ 0.1–6,
    kℓ 2.6–19.7, moisture 0.09–0.31 (ε ≈ 4–25), θ 10–70°, p = σhh/σvv ≤ 1: the whole box,
    its 70° edge included since the IEM's transition takes kσ (not kσ cosθ) as its phase
    variable (solvers/iem/terms.py)."""
    rough = em.roughness(kind, sigma=ks / K, length=kl / K)
    res, _ = timed(em.backscatter, rough, eps, wavelength=1.0, theta_i=theta, out_of_range="ignore")
    note(res.method)
    assert res.pol("hh") <= res.pol("vv") * (1 + 1e-9)


@pytest.mark.parametrize(("ks", "kl"), [(3.0, 3.0), (2.0, 6.0)])
def test_auto_backscatter_hh_below_vv_at_the_70_degree_edge(ks, kl):
    """The edge that failed with the published transition variable (kσ cosθ)²: exponential,
    ε = 4 + 0.5i (Brewster ≈ 63°), 70°: hh − vv was +1.22 / +1.28 dB (γ_v ≈ 0.2 put R_vT
    near zero). Oh et al. (1992)'s p = [1 − (2θ/π)^{1/(3Γ₀)} e^{−kσ}]² gives −0.2 / −0.6 dB
    here; the answer must at least have hh ≤ vv."""
    rough = em.roughness("exponential", sigma=ks / K, length=kl / K)
    res = em.backscatter(rough, 4 + 0.5j, wavelength=1.0, theta_i=math.radians(70),
                         out_of_range="ignore")  # fmt: skip
    assert res.pol("hh") <= res.pol("vv") * (1 + 1e-9)


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
