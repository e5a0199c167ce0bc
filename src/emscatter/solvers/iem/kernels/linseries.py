"""The compiled linear-space walk of the bistatic IEM series (:func:`series_kernel_lin`): the
terms of :func:`.series.row_series` by recurrences (one multiplication per component and order,
one ``Ŵₙ``), used per geometry where the scaled sums stay in the range of doubles, with the
log-space :func:`.series.row_series` as the per-row fallback. Numpy reference:
:func:`emscatter.solvers.iem.series.iem_series`."""

from __future__ import annotations

import math

import numpy as np

from emscatter.kernels._runtime import inline, jit
from emscatter.solvers.iem.kernels.series import (
    FAST_MAX_ORDER,
    HUGE,
    TINY,
    isqrt,
    row_series,
    w_lin,
    w_max,
)

#: A walked component whose start magnitude is below e^{−LIN_SPAN} of the largest sends the row
#: to the log-space path (its squares would leave the normal doubles before it decays)
LIN_SPAN = 300.0
#: Largest Poisson argument ``q_j = (kσ)² x_j²`` of the linear path: the scaled terms grow at
#: most as ``e^{q_j}``, kept well inside the doubles (HUGE = 1e300)
LIN_MAX_Q = 600.0


@inline
def row_lin(la, lx, ph, sx, d, pref, K, ks2, spec, dim, rtol, max_terms, z, xs, mass):
    """``(ok, log σ⁰, log envelope sum)`` of one geometry (:func:`.series.row_series`'s terms
    and outputs) in linear space; ``ok`` False: not safe here, take :func:`.series.row_series`.
    ``z, xs, mass``: work arrays of the components' length.

    Terms (the series of :mod:`emscatter.solvers.iem.series`, from the IEM of Fung, Li & Chen
    1992 and Chen et al. 2003 as :mod:`emscatter.solvers.iem.model` writes it):
    ``Tₙ = e^{pref} (kσ)^{2n}/n! Ŵₙ(K) |Σ_j e^{la_j} ph_j (sx_j e^{lx_j})^{n−1} + δ_{n1} d|²``,
    summed from n = 1 with everything scaled by
    ``e^{−big}``, ``big = max(la_j, log|d|)``: ``z_j(n) = e^{la_j − big} (sx_j x_j)^{n−1}
    √((kσ)^{2n}/n!)`` by ``z_j(n+1) = z_j(n) sx_j x_j kσ/√(n+1)``. Stopping rule (as
    ``row_series``, tested at orders 3, 7, 11, …): per component the geometric tail
    ``z_j² Ŵₙ r/(1 − r)`` with ``r = x_j² (kσ)²/(n+1) Ŵₙ₊₁/Ŵₙ`` bounded by the current
    ``x_j² (kσ)²/n Ŵₙ/Ŵₙ₋₁`` (term ratios non-increasing from n = 3 for the Gaussian and
    exponential closed forms), its whole-series bound ``e^{2(la_j − big)} (e^{q_j} − 1)/x_j²
    max Ŵ`` where that ratio is ≥ 1; the bounds' sum times the number of walked components
    (Cauchy–Schwarz) below ``rtol`` of the sum. Not safe: a walked component starting below
    ``e^{−LIN_SPAN}`` of the largest, ``q_j > LIN_MAX_Q``, a walk past
    :data:`.series.FAST_MAX_ORDER` or ``max_terms``, final sums outside [1e-250, 1e300]."""
    J = la.shape[0]
    big = -np.inf
    for j in range(J):
        big = max(big, la[j])
    ad = abs(d)
    ld = math.log(ad) if ad > 0 else -np.inf
    big = max(big, ld)
    if big == -np.inf:  # every amplitude zero: σ⁰ = 0 (row_series' −inf, −inf)
        return True, -np.inf, -np.inf
    sks = math.sqrt(ks2)
    wm = math.exp(w_max(K, spec, dim))
    K2 = K * K
    # n = 1: every component with a finite amplitude, and d
    amp = d * math.exp(-big) * sks
    env = ad * math.exp(-big) * sks
    nok = 0
    for j in range(J):
        m = math.exp(la[j] - big) * sks if la[j] > -np.inf else 0.0
        amp += m * ph[j]
        env += m
        z[j] = 0.0
        xs[j] = 0.0
        mass[j] = 0.0
        if m > 0.0 and lx[j] > -np.inf:
            if la[j] - big < -LIN_SPAN:
                return False, 0.0, 0.0
            x = math.exp(lx[j])
            q = ks2 * x * x
            if q > LIN_MAX_Q:
                return False, 0.0, 0.0
            z[j] = m
            xs[j] = sx[j] * x
            mass[j] = math.exp(2.0 * (la[j] - big)) * math.expm1(q) / (x * x) * wm
            nok += 1
    w = w_lin(1.0, K2, spec, dim)
    acc = (amp.real * amp.real + amp.imag * amp.imag) * w
    acc_e = env * env * w
    lscale = pref + 2.0 * big
    if nok > 0:
        lim = -760.0 - lscale  # the log-space walk's absolute floor, e^-760, scaled
        floor = math.exp(lim) if lim > -745.0 else 0.0
        n = 1.0
        while True:
            n += 1.0
            wp = w
            w = w_lin(n, K2, spec, dim)
            f = sks * isqrt(n)
            amp = 0j
            env = 0.0
            for j in range(J):
                zj = z[j] * xs[j] * f
                z[j] = zj
                amp += zj * ph[j]
                env += abs(zj)
            acc += (amp.real * amp.real + amp.imag * amp.imag) * w
            acc_e += env * env * w
            if int(n) & 3 == 3:
                rho = ks2 / n * w / wp
                tail = 0.0
                for j in range(J):
                    zj = z[j]
                    if zj == 0.0:
                        continue
                    r = xs[j] * xs[j] * rho
                    if r < 1.0:
                        tail += min(zj * zj * w * r / (1.0 - r), mass[j])
                    else:
                        tail += mass[j]
                if nok * tail <= rtol * acc or acc + nok * tail < floor:
                    break
            if n >= FAST_MAX_ORDER or n > max_terms:
                return False, 0.0, 0.0
    if not (TINY <= acc < HUGE and acc_e < HUGE):
        return False, 0.0, 0.0
    return True, lscale + math.log(acc), lscale + math.log(acc_e)


@jit
def series_kernel_lin(la, lx, ph, sx, d, pref, K, log_ks2, spec, dim, log_rtol, max_terms,
                      out_s, out_e, out_fast):  # fmt: skip
    """:func:`.series.series_kernel` (same arguments and outputs: log σ⁰, log envelope sum;
    returns the status) with the linear-space :func:`row_lin` where it is safe, else the
    log-space :func:`.series.row_series` for that row; ``out_fast[r]``: the linear path was
    taken."""
    status = 0
    J = la.shape[1]
    ks2 = math.exp(log_ks2)
    rtol = math.exp(log_rtol)
    z, xs, mass = np.empty(J), np.empty(J), np.empty(J)
    ok, lmass, prev, cur = np.empty(J, np.bool_), np.empty(J), np.empty(J), np.empty(J)
    for r in range(la.shape[0]):
        fast, s, e = row_lin(la[r], lx[r], ph[r], sx[r], d[r], pref[r], K[r], ks2, spec, dim,
                             rtol, max_terms, z, xs, mass)  # fmt: skip
        out_fast[r] = fast
        if not fast:
            s, e, st = row_series(la[r], lx[r], ph[r], sx[r], d[r], pref[r], K[r], log_ks2,
                                  spec, dim, log_rtol, max_terms, ok, lmass, prev, cur)  # fmt: skip
            status = max(status, st)
        out_s[r], out_e[r] = s, e
    return status
