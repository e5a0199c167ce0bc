"""The linear-space bistatic series walk (``kernels.linseries.series_kernel_lin``) against the
log-space one (``kernels.series.series_kernel``) on the rows the IEM itself builds (bistatic
grids: Gaussian, exponential, profile; kσ 0.1–3; PEC and dielectric), its per-row fallback
where the linear sums would leave the doubles, and emissivity through it."""

from __future__ import annotations

import math

import numpy as np
import pytest

import emscatter as em
from emscatter.solvers.iem import compiled as iem_jit
from emscatter.solvers.iem import model as iem
from emscatter.solvers.iem.kernels import linseries
from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation

pytestmark = pytest.mark.skipif(
    not iem_jit.enabled(),
    reason="numba kernels off (EMSCATTER_KERNELS=numpy) or numba not installed",
)

K0 = 2 * math.pi  # wavenumber [1/m] at λ = 1 m


def _rows(rough, eps, rtol, monkeypatch):
    """The series rows (``series_rows``' arguments) of one bistatic IEM call on a grid of
    θi, θs, φs, recorded on their way to the compiled kernel."""
    seen = []
    real = iem_jit.series_rows

    def record(*args, **kw):
        seen.append((args, kw))
        return real(*args, **kw)

    monkeypatch.setattr(iem_jit, "series_rows", record)
    ti = np.radians([0.0, 10.0, 30.0, 50.0, 70.0, 85.0])
    ts = np.radians([0.0, 20.0, 40.0, 60.0, 80.0])
    ps = np.radians([0.0, 45.0, 120.0, 180.0]) if rough.dimension == 2 else np.array([0.0, np.pi])
    T, S, P = np.meshgrid(ti, ts, ps, indexing="ij")
    iem.bistatic(rough, eps, K0, T.ravel(), S.ravel(), P.ravel(), coherent=False, rtol=rtol)
    monkeypatch.setattr(iem_jit, "series_rows", real)
    assert seen, "the IEM did not reach the compiled series"
    return seen


CASES = [
    (GaussianCorrelation(sigma, 4.0 * sigma + 0.3), eps)
    for sigma in (0.1 / K0, 0.5 / K0, 1.0 / K0, 3.0 / K0)
    for eps in (15 + 2j, "pec")
] + [
    (ExponentialCorrelation(0.5 / K0, 2.0 / K0), 5 + 0.5j),
    (ExponentialCorrelation(2.0 / K0, 6.0 / K0), "pec"),
    (GaussianCorrelation(1.5 / K0, 6.0 / K0, dimension=1), 15 + 2j),
]  # fmt: skip


@pytest.mark.parametrize("rtol", [1e-8, 1e-12])
@pytest.mark.parametrize(("rough", "eps"), CASES, ids=lambda v: repr(v)[:30])
def test_linear_walk_equals_the_log_space_walk(rough, eps, rtol, monkeypatch):
    """Same log σ⁰ and precision ratio to ≤ rtol (relative; both are within rtol of the
    series' value) on every row, and the linear path taken on every row of these grids
    (kσ ≤ 3: every term inside the doubles)."""
    for args, kw in _rows(rough, eps, rtol, monkeypatch):
        s_lin, p_lin, st_lin, fast = iem_jit.series_rows(*args, **kw, fast=True, report=True)
        s_log, p_log, st_log = iem_jit.series_rows(*args, **kw, fast=False)
        assert st_lin == st_log == 0
        np.testing.assert_array_equal(np.isfinite(s_lin), np.isfinite(s_log))
        fin = np.isfinite(s_log)
        assert fin.any()
        err = np.max(np.abs(np.expm1(s_lin[fin] - s_log[fin])))
        assert err <= max(rtol, 1e-13), f"σ⁰ differs by {err:.3g} (rtol {rtol:g})"
        perr = np.max(np.abs(np.expm1(p_lin[fin] - p_log[fin])))
        assert perr <= max(rtol, 1e-13), f"precision ratio differs by {perr:.3g}"
        assert fast.all(), f"{np.sum(~fast)} of {fast.size} rows fell back"


def _series(la, lx, d, log_ks2, rtol=1e-10):
    """Both kernels on hand-made rows (phases 1, signs +, K = 1, pref 0, Gaussian 2-D)."""
    la, lx = np.atleast_2d(la).astype(float), np.atleast_2d(lx).astype(float)
    n = la.shape[0]
    ph, sx = np.ones(la.shape, complex), np.ones(la.shape)
    args = (la, lx, ph, sx, np.asarray(d, complex), log_ks2, iem_jit.GAUSSIAN, 2, np.ones(n),
            np.zeros(n))  # fmt: skip
    lin = iem_jit.series_rows(*args, rtol=rtol, max_terms=10**6, fast=True, report=True)
    log = iem_jit.series_rows(*args, rtol=rtol, max_terms=10**6, fast=False)
    return lin, log


def test_fallback_per_row_where_the_linear_sums_leave_the_doubles():
    """Rows 1 and 2 go to the log-space walk (a component e^-400 below the largest; a Poisson
    argument q = (kσ)² x² = 900 > LIN_MAX_Q, terms up to e^900), rows 0 and 3 in the same call
    stay linear, and every row equals the log-space result (the fallback rows exactly)."""
    assert linseries.LIN_MAX_Q < 900.0 and linseries.LIN_SPAN < 400.0
    log_ks2 = math.log(400.0)
    la = [[0.0, -1.0], [0.0, -400.0], [0.0, -1.0], [0.0, -2.0]]
    lx = [[math.log(0.3), math.log(0.2)], [math.log(0.3), math.log(0.2)],
          [math.log(1.5), math.log(0.2)], [math.log(0.1), math.log(0.05)]]  # fmt: skip
    (s_lin, p_lin, st, fast), (s_log, p_log, _) = _series(la, lx, np.zeros(4), log_ks2)
    assert st == 0
    assert fast.tolist() == [True, False, False, True]
    np.testing.assert_array_equal(s_lin[~fast], s_log[~fast])
    np.testing.assert_array_equal(p_lin[~fast], p_log[~fast])
    np.testing.assert_allclose(s_lin, s_log, rtol=0, atol=1e-10)
    assert s_log[2] > 800.0  # the row really is beyond the doubles in linear space


def test_zero_row_and_first_order_only_rows():
    """An all-zero row gives σ⁰ = 0 (log −inf) on both paths without a fallback; a row with
    only n = 1 terms (no walked component: bases zero) is |Σ a + d|² (kσ)² Ŵ₁ exactly."""
    inf = -np.inf
    la = [[inf, inf], [0.0, math.log(0.5)]]
    lx = [[0.0, 0.0], [inf, inf]]
    d = np.array([0.0, 0.25])
    log_ks2 = math.log(0.3)
    (s_lin, p_lin, st, fast), (s_log, p_log, _) = _series(la, lx, d, log_ks2)
    assert fast.all() and st == 0
    assert s_lin[0] == s_log[0] == -np.inf
    w1 = math.exp(-1.0 / 4.0) / (4.0 * math.pi)  # Gaussian Ŵ₁(K = 1), 2-D: e^{−K²/4}/(4π)
    np.testing.assert_allclose(s_lin[1], math.log(0.3 * w1 * 1.75**2), rtol=1e-14)
    np.testing.assert_allclose(s_lin[1], s_log[1], rtol=1e-14)


def test_emissivity_through_the_linear_walk_matches_the_log_space_walk(monkeypatch):
    """IEM emissivity (pyi2em's README case, 5.3 GHz, σ = 2.5 mm, ℓ = 10 cm, ε = 11.3 + 1.5j)
    with the linear walk equals the all-log-space one within its stated error."""
    monkeypatch.setenv("EMSCATTER_CACHE", "0")  # every call integrates
    surf = em.GaussianCorrelation(0.0025, 0.10)
    real = iem_jit.series_rows
    out = {}
    for fast in (True, False):
        monkeypatch.setattr(
            iem_jit, "series_rows", lambda *a, _f=fast, **kw: real(*a, **kw, fast=_f)
        )
        out[fast] = em.emissivity(
            surf, 11.3 + 1.5j, frequency=5.3e9, theta_i=np.radians([30.0, 60.0]), method="iem",
            tol=1e-4, crosspol=False, out_of_range="ignore",
        )  # fmt: skip
    monkeypatch.setattr(iem_jit, "series_rows", real)
    a, b = np.asarray(out[True].emissivity), np.asarray(out[False].emissivity)
    assert np.all((a > 0) & (a < 1))
    np.testing.assert_allclose(a, b, rtol=0, atol=2e-4)
