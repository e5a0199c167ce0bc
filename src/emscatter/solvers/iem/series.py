"""The integral-equation series, summed in log space to a relative tolerance.

For each geometry the single-scattering coefficient is (module :mod:`emscatter.solvers.iem.model`)::

    σ⁰ = Σ_{n≥1} exp(pref) · (kσ)^{2n}/n! · Ŵₙ(K) · |Iₙ|²,   Iₙ = Σ_j a_j x_j^(n−1) + δ_{n1} d

with complex amplitudes ``a_j`` (attenuation factors included), real bases ``x_j`` and
``Ŵₙ = exp(log_w(n, K))`` the n-fold spectrum. Every summand is ``≥ 0``; the only cancellation
is inside ``Iₙ`` (a handful of terms at fixed ``n``), evaluated after scaling by the largest
``|a_j x_j^(n−1)|`` so nothing overflows for any ``kσ`` (checked to 100) or ``|ε|``.

Stopping rule (no fixed term count): by Cauchy–Schwarz ``|Iₙ|² ≤ J Σ_j |a_j x_j^(n−1)|²``, and
each component series ``(kσ x_j)^{2n}/n! Ŵₙ`` is log-concave in ``n`` past its peak (Poisson
weights times a log-concave spectrum), so past a block end where every component decreases,
its tail is at most the last term times ``r/(1 − r)`` (``r`` the last ratio). Summation stops
when that bound is below ``rtol`` of the sum.

Order of work: geometries whose largest component parameter ``Q = (kσ x_j)²`` is moderate
(``≤ 600``, which covers the model's whole validity range) are summed from ``n = 2`` in one
vectorized block sized from ``Q`` (``Q + 8√Q + 24`` orders, grouped in powers of two), then
extended if the bound is not yet met; larger ``Q`` walk outward from the peak of the dominant
component in doubling blocks (like :func:`emscatter.solvers.kirchhoff.po.series_sum`). The
``n = 1`` term is computed apart (it holds ``d`` and the components with ``x_j = 0``).

Precision: the sum of the envelopes ``Σₙ (Σ_j |a_j x_j^(n−1)|)² …`` over the sum itself is
returned too; ``1e-16`` times it bounds the relative rounding error of the result.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import special

__all__ = ["iem_series"]

_Q_DIRECT = 600.0
_UNDERFLOW = -760.0  # log of a value that exp() returns as 0.0
_CHUNK = 1 << 16  # elements per (rows, orders, components) block: stays in cache


def _log_w_max(log_w, K):
    """``max_n log Ŵₙ(K)`` per row (log grid of n over [1, 1e8], +1 margin)."""
    n = np.geomspace(1.0, 1e8, 41)
    return np.max(log_w(n[None, :], np.asarray(K, dtype=float)[:, None]), axis=1) + 1.0


def _too_many(rtol, max_terms, needed, log_ks2):
    return (
        f"integral-equation series does not converge to rtol={rtol:g} within "
        f"max_terms={max_terms} terms (needs ~{needed:.0f}; kσ = "
        f"{math.exp(0.5 * log_ks2):.3g}); raise max_terms or rtol"
    )


def _log_expm1(x):
    """``log(eˣ − 1)`` for ``x ≥ 0`` without overflow (``-inf`` at 0)."""
    x = np.asarray(x, dtype=float)
    big = x > 1.0
    with np.errstate(divide="ignore"):
        small = np.log(np.expm1(np.where(big, 1.0, x)))
    return np.where(big, x + np.log1p(-np.exp(-np.where(big, x, 1.0))), small)


def _orders_needed(Q, log_rtol):
    """Orders n ≥ 2 to sum so that the Poisson tail ``Σ_{m>n} Qᵐ/m! e^{−Q}`` is below
    ``rtol·e⁻³``: Bernstein's bound ``exp(−t²/(2(Q + t/3)))`` at ``n = Q + t`` for large Q, the
    first omitted term for small Q; the stopping test still decides."""
    L = 3.0 - log_rtol
    out = Q + L / 3.0 + np.sqrt(L * L / 9.0 + 2.0 * L * Q)
    sm = Q < 8.0
    if np.any(sm):
        n = np.arange(1.0, 65.0)
        lq = np.log(np.maximum(Q[sm], 1e-300))[:, None]
        f = n[None, :] * lq - special.gammaln(n + 1.0)[None, :] - Q[sm][:, None]
        small = np.argmax(f < -L, axis=1) + 1.0
        out[sm] = np.minimum(small, out[sm])
    return out


def _block(n, la, lx, ph, sx, lnorm):
    """Summands, envelopes and the last two per-component log-terms for orders ``n`` (m, c).
    Loops over the (few) components on (m, c) arrays: no strided reductions."""
    J = la.shape[1]
    nm1 = n - 1.0
    e = [la[:, j, None] + nm1 * lx[:, j, None] for j in range(J)]
    big = e[0].copy()
    for j in range(1, J):
        np.maximum(big, e[j], out=big)
    finite = np.isfinite(big)
    ref = np.where(finite, big, 0.0)
    odd = ((n.astype(np.int64) - 1) & 1).astype(bool)
    re = np.zeros(n.shape)
    im = np.zeros(n.shape)
    env = np.zeros(n.shape)
    for j in range(J):
        mag = np.exp(e[j] - ref)
        env += mag
        w = np.where(odd, sx[:, j, None] * mag, mag)
        re += w * ph[:, j, None].real
        im += w * ph[:, j, None].imag
    base = lnorm + 2.0 * ref
    with np.errstate(divide="ignore"):
        t = np.where(finite, base + np.log(re * re + im * im), -np.inf)
        te = np.where(finite, base + 2.0 * np.log(env), -np.inf)
    last = lnorm[:, -1, None] + 2.0 * np.stack([ej[:, -1] for ej in e], axis=1)
    if n.shape[1] > 1:
        prev = lnorm[:, -2, None] + 2.0 * np.stack([ej[:, -2] for ej in e], axis=1)
    else:
        prev = last
    return t, te, last, prev


def _tail_ok(last, prev, nn_last, direction, J_eff, acc, ref, log_rtol, lmass):
    """Per row: the bound on what is left is below ``rtol`` of the sum. Per component the
    bound is the geometric tail where the component decreases in the walk direction, and its
    whole mass ``lmass`` otherwise (a component still rising toward a far peak but negligible
    in total does not hold the sum back)."""
    with np.errstate(invalid="ignore"):
        lr = last - prev
    dec = (lr < 0) | ~np.isfinite(last)
    lr_safe = np.where(lr < 0, lr, -1.0)
    geo = np.where(np.isfinite(last), last + lr_safe - np.log(-np.expm1(lr_safe)), -np.inf)
    if direction < 0:  # at most (n_last − 2) terms remain below
        with np.errstate(divide="ignore"):
            geo = np.minimum(geo, last + np.log(np.maximum(nn_last - 2.0, 0.0))[:, None])
    tail = np.minimum(np.where(dec, geo, np.inf), lmass)
    tail_tot = np.log(J_eff) + np.logaddexp.reduce(tail, axis=1) - ref
    with np.errstate(divide="ignore"):
        log_acc = np.log(acc)
    # below the smallest double (sum and tail): the result is 0.0 whatever else is added
    gone = np.logaddexp(log_acc, tail_tot) + ref < _UNDERFLOW
    return (tail_tot <= log_rtol + np.log(np.maximum(acc, 1e-300))) | gone


def iem_series(la, lx, ph, sx, d, log_ks2: float, log_w, K, pref, *, rtol=1e-8,
               max_terms: int = 10**6, prune: bool = True):  # fmt: skip
    """``(log σ⁰, log precision ratio)`` for flat arrays of geometries.

    Parameters
    ----------
    la, lx : (N, J) real — ``log|a_j|`` and ``log|x_j|`` (``-inf`` allowed).
    ph, sx : (N, J) — unit phase of ``a_j`` (complex) and sign of ``x_j`` (±1).
    d : (N,) complex — extra first-order amplitude.
    log_ks2 : ``log (kσ)²``. ``log_w(n, K)``: log n-fold spectrum; ``K`` (N,).
    pref : (N,) — log of the prefactor (normalization of the spectrum, ½, shadowing).
    """
    la = np.asarray(la, dtype=float)
    N, J = la.shape
    K = np.asarray(K, dtype=float)
    pref = np.broadcast_to(np.asarray(pref, dtype=float), (N,))
    log_rtol = math.log(rtol)
    if N == 0:
        return np.zeros(0), np.zeros(0)

    def lnorm_of(n, idx):
        return pref[idx, None] + n * log_ks2 - special.gammaln(n + 1.0) + log_w(n, K[idx, None])

    # n = 1: all components plus d
    with np.errstate(divide="ignore"):
        ld = np.log(np.abs(d))
    L1 = np.maximum(np.max(la, axis=1), ld)
    L1f = np.where(np.isfinite(L1), L1, 0.0)
    m1 = np.exp(la - L1f[:, None])
    md = np.where(np.isfinite(ld), np.exp(np.minimum(ld - L1f, 700.0)), 0.0)
    a1 = np.sum(m1 * ph, axis=1) + md * np.exp(1j * np.angle(d))
    e1 = np.sum(m1, axis=1) + md
    ln1 = lnorm_of(np.ones((N, 1)), np.arange(N))[:, 0]
    with np.errstate(divide="ignore"):
        t1 = np.where(np.isfinite(L1), ln1 + 2 * L1f + np.log(np.abs(a1) ** 2), -np.inf)
        te1 = np.where(np.isfinite(L1), ln1 + 2 * L1f + 2 * np.log(e1), -np.inf)

    # components that live beyond n = 1
    lx_ok = np.isfinite(lx) & np.isfinite(la)
    lxm = np.where(lx_ok, lx, -np.inf)
    lam = np.where(lx_ok, la, -np.inf)
    Qj = np.where(lx_ok, np.exp(log_ks2 + 2.0 * np.where(lx_ok, lx, 0.0)), 0.0)
    mass = np.where(lx_ok, 2.0 * lam + Qj, -np.inf)
    # bound on each component's whole series: e^{pref} |a|² max_n Ŵₙ(K) (e^Q − 1)/x², the
    # maximum over n from a log grid (+1: the grid's worst miss of a smooth peak is ≪ 1)
    lw_max = _log_w_max(log_w, K)
    with np.errstate(divide="ignore", invalid="ignore"):
        lmass = np.where(
            lx_ok,
            pref[:, None] + 2.0 * lam + _log_expm1(Qj) - 2.0 * lxm + lw_max[:, None],
            -np.inf,
        )
    # components negligible beside the largest bound are left out of the n ≥ 2 sums; the
    # result is checked against their bound below (Minkowski: relative change ≤ 2√(B/S))
    pruned = lx_ok & (lmass < np.max(lmass, axis=1, keepdims=True) + 2.0 * (log_rtol - 3.0))
    lmass_all, ph_all, sx_all = lmass, ph, sx
    if prune and np.any(pruned):
        cols = np.nonzero(np.any(lx_ok & ~pruned, axis=0))[0]
        lx_ok = lx_ok & ~pruned
        lam, lxm, lmass = (np.where(lx_ok, a, -np.inf)[:, cols] for a in (lam, lxm, lmass))
        ph, sx = ph[:, cols], sx[:, cols]
        Qj = np.where(lx_ok, Qj, 0.0)[:, cols]
        mass = np.where(lx_ok, mass, -np.inf)[:, cols]
        lx_ok = lx_ok[:, cols]
        J = cols.size
    else:
        pruned = np.zeros_like(lx_ok)
    jstar = np.argmax(mass, axis=1)
    q_star = np.take_along_axis(Qj, jstar[:, None], 1)[:, 0]
    q_max = np.max(Qj, axis=1)
    has = np.any(lx_ok, axis=1)
    J_eff = np.maximum(np.sum(lx_ok, axis=1), 1).astype(float)

    ref = np.where(np.isfinite(te1), te1, 0.0)
    acc = np.where(np.isfinite(t1), np.exp(t1 - ref), 0.0)
    acc_env = np.where(np.isfinite(te1), np.exp(te1 - ref), 0.0)

    def add(rows, t, te):
        top = np.max(te, axis=1)  # envelope ≥ summand: keeps both sums finite
        new = np.where(np.isfinite(top), np.maximum(ref[rows], top), ref[rows])
        scale = np.exp(ref[rows] - new)
        acc[rows] *= scale
        acc_env[rows] *= scale
        ref[rows] = new
        acc[rows] += np.exp(t - new[:, None]).sum(axis=1)
        acc_env[rows] += np.exp(te - new[:, None]).sum(axis=1)

    # peak of the dominant component (its Poisson weight times Ŵₙ(K), which moves the peak
    # far beyond Q for a Gaussian spectrum at large K): coarse search on a log grid of n
    lx_star = np.take_along_axis(lxm, jstar[:, None], 1)[:, 0]
    la_star = np.take_along_axis(lam, jstar[:, None], 1)[:, 0]
    hi = np.log(2.0 * q_star + 2.0 * K + 40.0)
    grid = np.exp(np.linspace(0.0, 1.0, 24)[None, :] * hi[:, None])
    with np.errstate(invalid="ignore"):
        g = lnorm_of(grid, np.arange(N)) + 2.0 * (
            la_star[:, None] + (grid - 1.0) * lx_star[:, None]
        )
    g = np.where(np.isnan(g), -np.inf, g)
    ib = np.argmax(g, axis=1)
    # refine between the neighbours of the coarse maximum
    lo = np.log(grid[np.arange(N), np.maximum(ib - 1, 0)])
    up = np.log(grid[np.arange(N), np.minimum(ib + 1, grid.shape[1] - 1)])
    grid = np.exp(lo[:, None] + np.linspace(0.0, 1.0, 33)[None, :] * (up - lo)[:, None])
    with np.errstate(invalid="ignore"):
        g = lnorm_of(grid, np.arange(N)) + 2.0 * (
            la_star[:, None] + (grid - 1.0) * lx_star[:, None]
        )
    g = np.where(np.isnan(g), -np.inf, g)
    n_pk = np.maximum(np.round(grid[np.arange(N), np.argmax(g, axis=1)]), 2.0)

    # direct blocks from n = 2 (moderate Q, peak inside the block), grouped by their size
    # (size the block by the components whose mass is within rtol·e⁻¹⁰ of the largest)
    relevant = lx_ok & (mass >= np.max(mass, axis=1, keepdims=True) + log_rtol - 10.0)
    q_size = np.max(np.where(relevant, Qj, 0.0), axis=1)
    need = _orders_needed(q_size, log_rtol)
    direct = has & (q_max <= _Q_DIRECT) & (n_pk <= need)
    if np.any(direct & (need > max_terms)):
        raise RuntimeError(_too_many(rtol, max_terms, float(np.max(need[direct])), log_ks2))
    width = np.maximum(8.0 * np.ceil(need / 8.0), 8.0)
    walk_from = np.full(N, 2.0)  # where the upward walk continues
    groups = []
    for wd in np.unique(width[direct]):
        rows = np.nonzero(direct & (width == wd))[0]
        step = max(1, _CHUNK // int(wd * J))
        groups += [(wd, rows[i : i + step]) for i in range(0, rows.size, step)]
    for wd, rows in groups:
        nn = np.broadcast_to(np.arange(2.0, 2.0 + wd)[None, :], (rows.size, int(wd)))
        t, te, last, prev = _block(nn, lam[rows], lxm[rows], ph[rows], sx[rows],
                                   lnorm_of(nn, rows))  # fmt: skip
        add(rows, t, te)
        walk_from[rows] = 2.0 + wd
        ok = _tail_ok(last, prev, nn[:, -1], +1, J_eff[rows], acc[rows], ref[rows], log_rtol,
                      lmass[rows])  # fmt: skip
        direct[rows[ok]] = False  # converged: no further walk
        has[rows[ok]] = False
    # outward walk: from the peak (rows not summed directly), or onward (direct rows that are
    # not converged yet)
    down = has & (walk_from == 2.0)
    start_up = np.where(down, n_pk, walk_from)
    if np.any(down):
        rows = np.nonzero(down)[0]
        n0 = start_up[rows, None]
        _, te0, _, _ = _block(n0, lam[rows], lxm[rows], ph[rows], sx[rows], lnorm_of(n0, rows))
        new_ref = np.maximum(ref[rows], te0[:, 0])
        scale = np.exp(ref[rows] - new_ref)
        acc[rows] *= scale
        acc_env[rows] *= scale
        ref[rows] = new_ref
    count = np.zeros(N)
    for direction in (+1, -1):
        if direction > 0:
            active = has.copy()
            nxt = start_up.copy()
        else:
            active = down & (start_up - 1 >= 2)
            nxt = start_up - 1
        c = 16
        while np.any(active):
            a = np.nonzero(active)[0]
            c = int(min(c, max(8, (1 << 21) // (a.size * J))))
            a = a[: max(1, _CHUNK // (c * J))]
            nn = nxt[a, None] + direction * np.arange(c)[None, :]
            valid = nn >= 2
            nn_eval = np.maximum(nn, 2.0)
            t, te, last, prev = _block(nn_eval, lam[a], lxm[a], ph[a], sx[a], lnorm_of(nn_eval, a))
            add(a, np.where(valid, t, -np.inf), np.where(valid, te, -np.inf))
            count[a] += valid.sum(axis=1)
            done = _tail_ok(last, prev, nn[:, -1], direction, J_eff[a], acc[a], ref[a], log_rtol,
                            lmass[a])  # fmt: skip
            if direction < 0:
                done |= ~valid[:, -1] | (nn[:, -1] <= 2)
            if np.any(count[a] > max_terms):
                raise RuntimeError(_too_many(rtol, max_terms, float(np.max(count[a])), log_ks2))
            active[a[done]] = False
            nxt[a] += direction * c
            c = min(2 * c, 4096, int(4.0 * math.sqrt(float(np.max(q_star[a]))) + 16.0))
    with np.errstate(divide="ignore"):
        log_s = ref + np.log(acc)
        log_prec = np.log(np.maximum(acc_env, 1e-300)) - np.log(np.maximum(acc, 1e-300))
    if np.any(pruned):
        n_p = np.maximum(np.sum(pruned, axis=1), 1)
        with np.errstate(divide="ignore"):
            bound = np.log(n_p) + np.logaddexp.reduce(np.where(pruned, lmass_all, -np.inf), axis=1)
        redo = np.nonzero(np.any(pruned, axis=1) & (bound > 2.0 * (log_rtol - math.log(3.0))
                                                    + log_s) & (log_s > _UNDERFLOW))[0]  # fmt: skip
        if redo.size:
            log_s[redo], log_prec[redo] = iem_series(
                la[redo], lx[redo], ph_all[redo], sx_all[redo], d[redo], log_ks2, log_w, K[redo],
                pref[redo], rtol=rtol, max_terms=max_terms, prune=False,
            )  # fmt: skip
    return log_s, log_prec


def orders_table(log_ks2: float, log_w, K, N: int):
    """``n log(kσ)² − log n! + log Ŵₙ(K)`` for ``n = 1 … N``, shape (len(K), N): the part of
    every summand shared by the polarizations and by the transition sums."""
    n = np.arange(1.0, N + 1.0)
    return n * log_ks2 - special.gammaln(n + 1.0) + log_w(n[None, :], np.asarray(K)[:, None])


def direct_sum(table, la, lx, ph, sx, d, pref, log_rtol: float, log_ks2: float, lw_max: float):
    """Lean single-block version of :func:`iem_series` over the orders of ``table``
    (``n = 1 … N``): ``(log σ⁰, converged, log precision ratio)``; rows that are not
    converged by the same tail test must be redone with :func:`iem_series`."""
    m, N = table.shape
    n = np.arange(1.0, N + 1.0)
    with np.errstate(invalid="ignore"):
        e = la[:, None, :] + (n[None, :, None] - 1.0) * lx[:, None, :]
    e[:, 0, :] = la  # n = 1 (0 · −inf)
    with np.errstate(divide="ignore"):
        ld = np.log(np.abs(d))
    big = np.maximum(np.max(e, axis=2), np.where(n[None, :] == 1.0, ld[:, None], -np.inf))
    finite = np.isfinite(big)
    ref = np.where(finite, big, 0.0)
    mag = np.exp(e - ref[:, :, None])
    odd = (np.arange(N) & 1).astype(bool)
    w = np.where(odd[None, :, None], sx[:, None, :] * mag, mag)
    amp = np.einsum("mcj,mj->mc", w, ph)
    md = np.exp(np.minimum(ld - ref[:, 0], 700.0))
    amp[:, 0] += np.where(np.isfinite(ld), md, 0.0) * np.exp(1j * np.angle(d))
    env = np.sum(mag, axis=2)
    env[:, 0] += np.where(np.isfinite(ld), md, 0.0)
    base = pref[:, None] + table + 2.0 * ref
    with np.errstate(divide="ignore"):
        t = np.where(finite, base + np.log(amp.real**2 + amp.imag**2), -np.inf)
        te = np.where(finite, base + 2.0 * np.log(env), -np.inf)
    top = np.max(te, axis=1)
    top = np.where(np.isfinite(top), top, 0.0)
    acc = np.exp(t - top[:, None]).sum(axis=1)
    acc_env = np.exp(te - top[:, None]).sum(axis=1)
    lx_ok = np.isfinite(lx) & np.isfinite(la)
    if N > 1:
        last = np.where(lx_ok, pref[:, None] + table[:, -1, None] + 2.0 * e[:, -1, :], -np.inf)
        prev = np.where(lx_ok, pref[:, None] + table[:, -2, None] + 2.0 * e[:, -2, :], -np.inf)
        J_eff = np.maximum(np.sum(lx_ok, axis=1), 1).astype(float)
        lxm = np.where(lx_ok, lx, 0.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            lmass = np.where(lx_ok, pref[:, None] + 2.0 * la + _log_expm1(
                np.exp(log_ks2 + 2.0 * lxm)) - 2.0 * lxm + lw_max, -np.inf)  # fmt: skip
        ok = _tail_ok(last, prev, np.full(m, float(N)), +1, J_eff, acc, top, log_rtol, lmass)
        ok |= ~np.any(lx_ok, axis=1)
    else:
        ok = ~np.any(lx_ok, axis=1)
    with np.errstate(divide="ignore"):
        log_s = top + np.log(acc)
        log_prec = np.log(np.maximum(acc_env, 1e-300)) - np.log(np.maximum(acc, 1e-300))
    return log_s, ok, log_prec
