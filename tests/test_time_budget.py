"""Time budget and interrupts of the hemispherical integral (issue 23, item 5).

σ⁰ is evaluated in chunks: the answer does not depend on the chunking, a call that would
exceed its budget says so after a few chunks (an estimate from the measured cost, before the
work), a refinement that would end past the budget is not started, and a signal handler
(SIGALRM, Ctrl-C) runs within about a chunk even inside a compiled solver."""

from __future__ import annotations

import importlib
import math
import signal
import time

import numpy as np
import pytest

import emscatter as em

# the module (``emscatter.emissivity`` the attribute is the API function)
emi = importlib.import_module("emscatter.emissivity")

K = 2 * math.pi


class FakeClock:
    """The integral's clock (``emissivity.time``), advanced by the synthetic solver below:
    timings that do not depend on the machine's load."""

    def __init__(self):
        self.now = 0.0

    def perf_counter(self):
        return self.now


def _lobe(theta_i, width=0.05, delay=0.0, clock=None):
    """A synthetic σ⁰ (2, 2, ...): a Gaussian lobe around the specular direction that costs
    ``delay`` seconds of ``clock`` per evaluated direction (a stand-in for a slow solver)."""
    ti = np.asarray(theta_i)[..., None, None]

    def fn(theta_s, phi_s):
        if delay:
            clock.now += delay * math.prod(np.broadcast_shapes(np.shape(theta_s), ti.shape))
        px = np.sin(theta_s) * np.cos(phi_s) - np.sin(ti)
        py = np.sin(theta_s) * np.sin(phi_s)
        g = np.exp(-(px**2 + py**2) / width**2) * np.cos(theta_s)
        return np.stack([np.stack([g, 0 * g]), np.stack([0 * g, g])])

    return fn


def test_chunking_does_not_change_the_integral(monkeypatch):
    ti = np.radians([0.0, 30.0, 60.0])
    a = emi.hemispherical_reflectivity(_lobe(ti), ti, tol=1e-4, budget_s=None)
    monkeypatch.setattr(emi, "CHUNK_SECONDS", 1e-9)  # one index per chunk: thousands of calls
    b = emi.hemispherical_reflectivity(_lobe(ti), ti, tol=1e-4, budget_s=None)
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])
    assert a[2] == b[2]


def test_a_call_over_budget_is_refused_early_with_the_estimate(monkeypatch):
    clock = FakeClock()
    monkeypatch.setattr(emi, "time", clock)
    ti = np.radians([10.0, 40.0])
    with pytest.raises(emi.TimeBudgetError) as info:
        # 5 ms per direction: the first estimate (2 angles × 16 × 12 directions) takes ~2 s
        fn = _lobe(ti, delay=5e-3, clock=clock)
        emi.hemispherical_reflectivity(fn, ti, tol=1e-3, budget_s=0.5)
    assert clock.now < 0.5  # refused from the first chunks' measured rate, not after the work
    text = str(info.value)
    for words in ("would take about", "time budget of 0.5 s", "σ⁰ evaluations", "ways out"):
        assert words in text, text


def test_a_refinement_past_the_budget_is_not_started(monkeypatch):
    clock = FakeClock()
    monkeypatch.setattr(emi, "time", clock)
    ti = np.radians([20.0])
    fn = _lobe(ti, width=0.01, delay=2e-5, clock=clock)  # estimates of 15, 61, 246, 983 ms
    r, err, n = emi.hemispherical_reflectivity(fn, ti, tol=1e-12, budget_s=0.2)
    full = emi.hemispherical_reflectivity(_lobe(ti, width=0.01), ti, tol=1e-12, budget_s=None)
    assert n < full[2]  # stopped early ...
    assert np.all(np.isfinite(err)) and np.all(err > 0)  # ... with the error it reached
    assert clock.now <= 0.2  # and within the budget
    assert abs(r - full[0]).max() <= 10 * err.max() + 1e-12


def test_budget_settings_are_checked(monkeypatch):
    with pytest.raises(ValueError, match="time_budget must be a positive number.*-1"):
        with emi.time_budget(-1):
            pass
    monkeypatch.setenv("EMSCATTER_TIME_BUDGET_S", "abc")
    with pytest.raises(ValueError, match="EMSCATTER_TIME_BUDGET_S must be a positive.*'abc'"):
        emi.current_time_budget()
    monkeypatch.setenv("EMSCATTER_TIME_BUDGET_S", "none")
    assert emi.current_time_budget() is None
    with emi.time_budget(7.5):
        assert emi.current_time_budget() == 7.5
    monkeypatch.delenv("EMSCATTER_TIME_BUDGET_S")
    assert emi.current_time_budget() == emi.TIME_BUDGET_S


# issue 23 item 5: Gaussian kσ = 1e3, kℓ = 3e3, ε = 17 + 2i, θ = [0, 90°], method="iem" ran
# over 240 s and SIGALRM could not interrupt it
BIG = em.GaussianCorrelation(1e3 / K, 3e3 / K)
BIG_ANGLES = np.radians([0.0, 90.0])


def _warm_up():
    """Compile/build what the IEM needs at this kσ (one direction), outside the timings."""
    with pytest.warns(Warning):
        em.bistatic(BIG, 17 + 2j, wavelength=1.0, theta_i=0.0, theta_s=0.1, phi_s=0.0,
                    method="iem")  # fmt: skip


def test_the_issue_case_is_refused_within_seconds():
    _warm_up()
    t0 = time.perf_counter()
    with emi.time_budget(20.0), pytest.raises(emi.TimeBudgetError, match="would take about"):
        with pytest.warns(Warning):
            em.emissivity(BIG, 17 + 2j, wavelength=1.0, theta_i=BIG_ANGLES, method="iem")
    assert time.perf_counter() - t0 < 20.0


class _Alarm(Exception):
    pass


@pytest.mark.skipif(not hasattr(signal, "setitimer"), reason="needs POSIX interval timers")
def test_sigalrm_interrupts_the_issue_case_inside_the_solver():
    _warm_up()

    def handler(signum, frame):
        raise _Alarm

    old = signal.signal(signal.SIGALRM, handler)
    t0 = time.perf_counter()
    try:
        signal.setitimer(signal.ITIMER_REAL, 1.0)
        with emi.time_budget(None), pytest.raises(_Alarm), pytest.warns(Warning):
            em.emissivity(BIG, 17 + 2j, wavelength=1.0, theta_i=BIG_ANGLES, method="iem")
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, old)
    # one chunk (two directions here) at most after the alarm; the whole call takes minutes
    assert time.perf_counter() - t0 < 1.0 + 15.0
