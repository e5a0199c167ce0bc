"""The linear-space backscatter walk of the compiled IEM kernel (iem_numba.walk_lanes,
walk_transition) against the log-space walk it replaces where safe, and against numpy."""

from __future__ import annotations

import math

import numpy as np
import pytest

from emscatter.solvers.iem import compiled as iem_jit
from emscatter.solvers.iem import model as iem
from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation

pytestmark = pytest.mark.skipif(
    not iem_jit.enabled(),
    reason="numba kernels off (EMSCATTER_KERNELS=numpy) or numba not installed",
)

THETA = np.radians(np.linspace(0.0, 89.0, 37))
EPS = (15 + 2j, 3.0, 80 + 20j, "pec")


def _both(spec, dim, ks, kl, eps, *, transition=True, rtol=1e-12, lower_q2=True):
    si, cs = np.sin(THETA), np.cos(THETA)
    K = 2.0 * kl * si
    pref = math.log(math.pi * kl * kl) if dim == 2 else math.log(0.5 * math.pi * kl)
    kw = dict(transition=transition, rtol=rtol, max_terms=10**6, lower_q2=lower_q2)
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
    # the lower-medium terms with the upper-medium phase (complementary="aiem-upper"):
    # bases 2kz and 0 instead of kz ± Re q₂
    for eps in EPS:
        fast, slow = _both(spec, 2, ks, 3.0, eps, lower_q2=False)
        assert fast[3] == slow[3] == 0
        assert _rel(fast[0], slow[0]) < 1e-10 and _rel(fast[1], slow[1]) < 1e-10, eps


@pytest.mark.parametrize("spec", [iem_jit.GAUSSIAN, iem_jit.EXPONENTIAL], ids=["gauss", "exp"])
def test_large_roughness_takes_the_log_space_path(spec):
    """Outside the double range of the linear walk (kσ ≫ 3) every angle of a dielectric falls
    back, and the answer is the log-space one: with the lower-medium phase ``Re q₂`` (bases
    kz ± Re q₂) at kσ = 12 and 30; with the upper-medium phase (``lower_q2=False``, bases
    2kz, 0) the walk stays in range longer — wherever it is taken it equals the log-space
    walk."""
    for ks in (12.0, 30.0):
        fast, slow = _both(spec, 2, ks, 10.0, 15 + 2j)
        assert not np.any(fast[4])
        assert _rel(fast[0], slow[0]) < 1e-10 and _rel(fast[1], slow[1]) < 1e-10
        fast, slow = _both(spec, 2, ks, 10.0, 15 + 2j, lower_q2=False)
        assert _rel(fast[0], slow[0]) < 1e-10 and _rel(fast[1], slow[1]) < 1e-10
    # mixed: some angles each way (kσ = 15; at 12 all angles now stay linear: the transition's
    # sums at Q = (kσ)² leave the linear range alone and are then summed in log space without
    # sending the angle's series there)
    fast, slow = _both(spec, 2, 15.0, 3.0, 3.0)
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


@pytest.mark.parametrize(
    "rough, eps",
    [(ExponentialCorrelation(0.44, 3.3), 15 + 2j), (GaussianCorrelation(1.1, 6.0), "pec"),
     (GaussianCorrelation(12.0, 3.0), 3.0)],
    ids=["exp-soil", "gauss-pec", "mixed-fallback"],
)  # fmt: skip
def test_lanes_and_threads_leave_every_geometry_alone(rough, eps):
    """The kernel walks blocks of LANES geometries in lockstep and splits large calls over
    threads: each geometry's σ⁰ is bit for bit what a call with that geometry alone gives
    (2 × BACK_MIN_CHUNK + 37 angles: blocks and thread chunks of odd sizes; the last case
    mixes fast and log-space lanes within blocks)."""
    from emscatter.solvers.iem.compiled import BACK_MIN_CHUNK

    th = np.radians(np.linspace(0.0, 80.0, 2 * BACK_MIN_CHUNK + 37))
    one = iem.bistatic(rough, eps, 1.0, th, th, math.pi, coherent=False, crosspol=False,
                       threads=1).sigma0  # fmt: skip
    two = iem.bistatic(rough, eps, 1.0, th, th, math.pi, coherent=False, crosspol=False,
                       threads=2).sigma0  # fmt: skip
    assert np.array_equal(one, two)
    for t in th[::397]:
        alone = iem.bistatic(rough, eps, 1.0, t, t, math.pi, coherent=False, crosspol=False)
        i = int(np.flatnonzero(th == t)[0])
        assert np.array_equal(alone.sigma0[..., 0] if alone.sigma0.ndim == 3 else alone.sigma0,
                              one[..., i])  # fmt: skip


@pytest.mark.parametrize("bad", [0, -2, 1.5, "2", True])
def test_threads_option_is_checked(bad):
    with pytest.raises(ValueError, match=r"threads must be a positive integer or None, got"):
        iem.bistatic(GaussianCorrelation(0.3, 1.5), 3.0, 1.0, 0.3, 0.3, math.pi, threads=bad)


def test_run_split_reraises_a_chunk_error_after_every_chunk_ends():
    """The persistent pool of the short kernels: an error in a worker chunk or in the
    caller's own chunk reaches the caller; every chunk has run by then."""
    from emscatter.kernels._runtime import run_split

    for bad_start in (0, 600):  # a worker's chunk, the caller's (last) chunk
        seen = []

        def part(a, b, bad_start=bad_start, seen=seen):
            seen.append(a)
            if a == bad_start:
                raise ArithmeticError(f"chunk {a}")

        with pytest.raises(ArithmeticError, match=f"chunk {bad_start}"):
            run_split(part, 1200, 2, 256)
        assert sorted(seen) == [0, 600]


def _poisson_reference(logq, K, spec, dim):
    """log Σ_{n≥1} qⁿ/n! Ŵₙ(K) by brute force over every order that matters."""
    from scipy.special import gammaln, logsumexp

    q = math.exp(logq)
    n = np.arange(1, int(q + 60 * math.sqrt(q) + 200 + 2 * K) + 1, dtype=float)
    if spec == iem_jit.GAUSSIAN:
        c = -math.log(4 * math.pi) if dim == 2 else -math.log(2 * math.sqrt(math.pi))
        lw = c - (1.0 if dim == 2 else 0.5) * np.log(n) - K * K / (4 * n)
    elif dim == 2:
        lw = -math.log(2 * math.pi) - 2 * np.log(n) - 1.5 * np.log1p((K / n) ** 2)
    else:
        lw = -math.log(math.pi) - np.log(n) - np.log1p((K / n) ** 2)
    return float(logsumexp(n * logq - gammaln(n + 1) + lw))


@pytest.mark.parametrize("spec", [iem_jit.GAUSSIAN, iem_jit.EXPONENTIAL], ids=["gauss", "exp"])
def test_poisson_sums_started_at_their_peak_equal_brute_force(spec):
    """From q = 64 on the Poisson-type sums (cross-pol T table, transition sums) walk both
    ways from their largest term instead of from n = 1 (~15 √q orders instead of ~q; a
    hypothesis case at kσ ≈ 950 took 7 minutes): the same sums to 1e-9 relative, both sides
    of the switch, narrow and wide spectra, surfaces and profiles."""
    for dim in (2, 1):
        for q in (50.0, 64.0, 65.0, 1e3, 1e5):
            for K in (0.0, 1.0, 30.0, 1e3):
                got = iem_jit.poisson_sums(np.array([math.log(q)]), K, spec, dim, rtol=1e-10)
                ref = _poisson_reference(math.log(q), K, spec, dim)
                if ref > -700.0:  # below: zero for every caller (the n = 1 walk stops there)
                    assert abs(math.expm1(got[0] - ref)) < 1e-9, (dim, q, K)
    big = iem_jit.poisson_sums(np.array([math.log(3.7e6)]), 10.0, spec, 2, rtol=1e-10)
    assert np.isfinite(big[0]) and abs(big[0] - 3.7e6) < 50.0  # ≈ q + log Ŵ_q


@pytest.mark.parametrize("kernels", ["numba", "numpy"])
@pytest.mark.parametrize(
    "corr", [GaussianCorrelation, ExponentialCorrelation], ids=["gauss", "exp"]
)
def test_fung92_backscatter_fast_path_equals_the_general_terms(corr, kernels, monkeypatch):
    """``complementary="fung92"`` in exact backscatter takes the closed-form path (one
    complementary component of base cosθ, :func:`terms.fung92_backscatter_terms`); it must
    give the general eight-term path's σ⁰ (reached just off backscatter, φ = π + 1e-7, where
    an unshadowed σ⁰ is even in φ − π) to 1e-9, compiled and numpy, over kσ 0.05–2.5,
    dielectrics and a PEC, both Fresnel options and first-order forms."""
    monkeypatch.setenv("EMSCATTER_KERNELS", kernels)
    for ks in (0.05, 0.3, 1.1, 2.5):
        for eps in EPS:
            for kw in (
                dict(fresnel="incident", first_order="model"),
                dict(),
                dict(shadowing="height-correlated"),
            ):
                kw = {"shadowing": False, **kw}
                r = corr(ks, 1.5)
                common = dict(coherent=False, crosspol=False, complementary="fung92", rtol=1e-12)
                fast = iem.bistatic(r, eps, 1.0, THETA, THETA, math.pi, **common, **kw)
                gen = iem.bistatic(r, eps, 1.0, THETA, THETA, math.pi + 1e-7, **common, **kw)
                for p in (0, 1):
                    assert _rel(fast.sigma0[p, p], gen.sigma0[p, p]) < 1e-9, (ks, eps, kw, p)
                assert np.all(fast.sigma0[0, 1] == 0) and np.all(fast.sigma0[1, 0] == 0)


def test_fung92_closed_form_is_the_sum_of_the_general_terms():
    """``fung92_backscatter_terms`` = Σ ¼ F̃ of ``complementary_terms(phase="fung92")`` in
    backscatter (0–89.9°, ε from a dry soil to a metal-like 1e6 i), to 1e-9 relative."""
    from emscatter.fresnel import fresnel_cos
    from emscatter.solvers.iem import terms

    th = np.radians(np.linspace(0.5, 89.9, 60))
    si, cs = np.sin(th), np.cos(th)
    for eps in (15 + 2j, 3.2 + 0.01j, 80 + 70j, 1e6j):
        rh, rv = fresnel_cos(eps, cs)
        T = terms.complementary_terms(si, cs, si, cs, 0 * si, -1 + 0 * si, eps, rh, rv,
                                      phase="fung92")  # fmt: skip
        G = sum(0.25 * np.asarray(F) for _, F, _, _ in T)
        gh, gv = terms.fung92_backscatter_terms(si, cs, eps)
        assert _rel(gh, G[0]) < 1e-9 and _rel(gv, G[3]) < 1e-9, eps
    T = terms.complementary_terms(si, cs, si, cs, 0 * si, -1 + 0 * si, 1.0, -1 + 0 * cs,
                                  1 + 0 * cs, lower=False, phase="fung92")  # fmt: skip
    G = sum(0.25 * np.asarray(F) for _, F, _, _ in T)
    gh, gv = terms.fung92_backscatter_terms(si, cs, "pec")
    assert _rel(gh, G[0]) < 1e-12 and _rel(gv, G[3]) < 1e-12


def test_fung92_compiled_fast_walk_equals_log_space_walk():
    """The kernel's fung92 lanes against its own log-space walk (rtol 1e-12)."""
    for spec in (iem_jit.GAUSSIAN, iem_jit.EXPONENTIAL):
        for ks in (0.05, 0.3, 1.1, 2.5):
            for eps in EPS:
                for transition in (True, False):
                    si, cs = np.sin(THETA), np.cos(THETA)
                    K, pref = 2.0 * 3.0 * si, math.log(math.pi * 9.0)
                    kw = dict(transition=transition, rtol=1e-12, max_terms=10**6, fung92=True)
                    fast = iem_jit.backscatter(si, cs, eps, ks, K, pref, spec, 2, report=True,
                                               **kw)  # fmt: skip
                    slow = iem_jit.backscatter(si, cs, eps, ks, K, pref, spec, 2, fast=False, **kw)
                    assert fast[3] == slow[3] == 0
                    assert np.all(fast[4]), (spec, ks, eps, transition)
                    assert _rel(fast[0], slow[0]) < 1e-10 and _rel(fast[1], slow[1]) < 1e-10


def test_closed_form_lower_medium_amplitudes_equal_the_reduced_coefficients():
    """``lanes.lower_back`` (the fast walk's lower-medium amplitudes in closed form at exact
    backscatter, used with the upper-medium phase: the default ``"aiem-faded"`` and
    ``"aiem-upper"``) equals ``lanes.lower_setup`` (the general reduced coefficients
    ``terms._reduced_i``, ``_reduced_s`` combined by ``lower_co``, which the log-space path
    keeps) to rounding: within 4e-15 of the amplitude scale (the Kirchhoff ``4|R|``) over
    0–89°, ε (lossless, lossy, very lossy), both height phases and a fade factor."""
    from emscatter.solvers.iem.kernels import lanes

    for eps in (3.0 + 0j, 15 + 2j, 80 + 20j, 5 + 40j):
        for th in np.radians(np.linspace(0.0, 89.0, 90)):
            s, c = math.sin(th), math.cos(th)
            q2, iq, rh, rv = lanes.fresnel_setup(s, c, eps, False)
            for lower_q2, f in ((True, 1.0), (False, 1.0), (False, 0.37)):
                a, _, p1, p2, mm = lanes.lower_setup(s, c, q2, iq, rh, rv, eps, 1 / eps, 1.0,
                                                     lower_q2, f, f)  # fmt: skip
                ref = np.array([p1[0] + p2[0], p1[3] + p2[3], mm[0], mm[3]]) * 0.25
                new = lanes.lower_back(s * s, c, q2, iq, rh, rv, eps, 1 / eps, a, 0.25 * f)
                new = np.array(new)
                scale = max(np.max(np.abs(ref)), 4 * abs(rh), 4 * abs(rv))
                assert np.max(np.abs(new - ref)) <= 4e-15 * scale, (eps, th, lower_q2)


@pytest.mark.parametrize("spec", [iem_jit.GAUSSIAN, iem_jit.EXPONENTIAL], ids=["gauss", "exp"])
@pytest.mark.parametrize("ks", [0.1, 0.5, 1.5, 2.5])
def test_default_configuration_fast_walk_equals_log_space_walk(spec, ks):
    """The default configuration (``"aiem-faded"``: faded lower-medium terms in closed form,
    ``lanes.lower_back``; the transition sums with one ``Qⁿ/n!`` per order for every lane;
    shadowing in the kernel) — fast walk = log-space walk (the general reduced coefficients)
    to 1e-10 at rtol 1e-12, and to rtol at the default 1e-8, over kℓ, ε (dielectrics, PEC),
    both shadowing modes, surfaces and profiles."""
    si, cs = np.sin(THETA), np.cos(THETA)
    for dim, kl in ((2, 0.5), (2, 3.3), (2, 20.0), (1, 6.0)):
        K = 2.0 * kl * si
        pref = math.log(math.pi * kl * kl) if dim == 2 else math.log(0.5 * math.pi * kl)
        for eps in EPS:
            psi = np.linspace(0, 3, THETA.size)
            for shadow, rtol in (((1, 0.2, psi), 1e-12), ((2, 0.3, None), 1e-12),
                                 ((1, 0.2, 0.5 + 0 * psi), 1e-8)):  # fmt: skip
                kw = dict(transition=True, rtol=rtol, max_terms=10**6, lower_q2=False,
                          fade=True, shadow=shadow)  # fmt: skip
                fast = iem_jit.backscatter(si, cs, eps, ks, K, pref, spec, dim, report=True, **kw)
                slow = iem_jit.backscatter(si, cs, eps, ks, K, pref, spec, dim, fast=False, **kw)
                assert fast[3] == slow[3] == 0 and np.all(fast[4])
                tol = 1e-10 if rtol < 1e-10 else 2 * rtol
                assert _rel(fast[0], slow[0]) < tol and _rel(fast[1], slow[1]) < tol, (dim, kl, eps)


@pytest.mark.skipif(not iem_jit.enabled(), reason="numba kernels off")
def test_real_arithmetic_root_and_division_equal_numpy():
    """``mono.fast_root`` (√z with Im ≥ 0, the branch of ``series.root``: decaying
    transmitted wave for Im ε ≥ 0) and ``mono.cdiv`` (``a b* / |b|²``), which the Fresnel
    setup of the backscatter lanes uses instead of the complex library calls, equal numpy's
    complex sqrt (flipped to Im ≥ 0) and division to a few ulp — over lossless, lossy,
    metallic (Re z < 0, on the negative real axis with ±0 imaginary part), tiny and huge
    arguments; and the setup's ``R_h, R_v`` are :func:`emscatter.fresnel.fresnel_cos`'s."""
    from emscatter.fresnel import fresnel_cos
    from emscatter.solvers.iem.kernels import lanes, mono

    zs = [complex(x, y) for x in (-1e6, -50.0, -1.0, -1e-9, 0.0, 1e-9, 0.3, 3.0, 80.0, 1e6)
          for y in (-0.0, 0.0, 1e-12, 2.0, 40.0, 1e5, -3.0)]  # fmt: skip
    for z in zs:
        ref = np.sqrt(complex(z))
        ref = -ref if ref.imag < 0 else ref
        got = mono.fast_root(z)
        assert got.imag >= 0.0, z
        assert abs(got - ref) <= 4e-16 * abs(ref), (z, got, ref)
        for b in (z, 1.0 + 0j, -2.5 + 7j, 1e-3 - 2e-3j):
            if b != 0:
                q = mono.cdiv(z + 1.5j, b)
                assert abs(q - (z + 1.5j) / b) <= 5e-16 * abs((z + 1.5j) / b), (z, b)
    assert mono.cdiv(1.0 + 2j, 0j) == 0j  # the setup's "0 where the denominator vanishes"
    for eps in (3.0 + 0j, 15 + 2j, 80 + 40j, -50 + 3j, 1e5 + 1e6j):
        for th in np.radians([0.0, 10.0, 45.0, 70.0, 89.0]):
            s, c = math.sin(th), math.cos(th)
            _, _, rh, rv = lanes.fresnel_setup(s, c, eps, False)
            ref_h, ref_v = fresnel_cos(eps, np.array([c]))
            assert abs(rh - ref_h[0]) <= 2e-15 and abs(rv - ref_v[0]) <= 2e-15, (eps, th)


@pytest.mark.skipif(not iem_jit.enabled(), reason="numba kernels off")
def test_transition_walk_hands_its_spectrum_weights_to_the_series_walk():
    """``lanes.walk_transition`` keeps Ŵₙ(K) of every order it walked in the table the
    series walk reads (``WT[(n − 1) LANES + l]``, orders 1 … nw): they are the exponential
    surface spectrum ``Ŵₙ = n / (2π (n² + K²)^{3/2})`` (``series.w_lin``), so the series walk
    gets the numbers it would have evaluated; a table with no room keeps none (nw = 0)."""
    from emscatter.solvers.iem.kernels import lanes

    m = 5
    K = np.array([0.0, 0.3, 1.7, 6.0, 25.0])
    T = np.zeros(lanes.T_ROWS * lanes.LANES)
    T[lanes.TK2 : lanes.TK2 + m] = K * K
    T[lanes.TACT : lanes.TACT + m] = 1.0
    ok = np.empty(lanes.LANES, dtype=np.bool_)
    WT = np.full(lanes.WT_ORDERS * lanes.LANES, np.nan)
    nw = lanes.walk_transition(T, m, 0.25, iem_jit.EXPONENTIAL, 2, 1e-10, ok, WT)
    assert 3 <= nw <= lanes.WT_ORDERS and ok[:m].all()
    for n in range(1, nw + 1):
        t = n * n + K * K
        ref = n / (2 * math.pi * t * np.sqrt(t))
        got = WT[(n - 1) * lanes.LANES : (n - 1) * lanes.LANES + m]
        np.testing.assert_allclose(got, ref, rtol=1e-15, atol=0)
    assert lanes.walk_transition(T, m, 0.25, iem_jit.EXPONENTIAL, 2, 1e-10, ok, WT[:0]) == 0
