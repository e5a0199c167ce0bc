"""The numba kernels behind :mod:`emscatter.solvers.iem.compiled` (module-level, so numba's on-disk
cache reuses
them across processes), decorated with the package's runtime (:mod:`emscatter.kernels._runtime`:
cache directory, numba options). Only :mod:`emscatter.solvers.iem.compiled` imports this module, on
first use."""

from __future__ import annotations

import math

import numpy as np

from emscatter.kernels._runtime import inline, jit
from emscatter.solvers.iem import terms as kern

reduced_i = jit(kern._reduced_i)
reduced_s = jit(kern._reduced_s)
combine = jit(kern._combine)
l4pi, l2pi, lpi = math.log(4 * math.pi), math.log(2 * math.pi), math.log(math.pi)
LOG_FACT = np.array([math.lgamma(n + 1.0) for n in range(2048)])  # log n!, looked up


@inline
def log_fact(n):
    i = int(n)
    return LOG_FACT[i] if i < 2048 and i == n else math.lgamma(n + 1.0)


l2spi = math.log(2 * math.sqrt(math.pi))


@inline
def log_w(n, K, spec, dim):  # kirchhoff_po.log_nfold (closed forms)
    if spec == 0:
        if dim == 2:
            return -l4pi - math.log(n) - K * K / (4.0 * n)
        return -l2spi - 0.5 * math.log(n) - K * K / (4.0 * n)
    if dim == 2:
        return -l2pi - 2.0 * math.log(n) - 1.5 * math.log1p((K / n) ** 2)
    return -lpi - math.log(n) - math.log1p((K / n) ** 2)


@inline
def logadd(a, b):
    if a == -np.inf:
        return b
    if b == -np.inf:
        return a
    m = max(a, b)
    return m + math.log1p(math.exp(-abs(a - b)))


@inline
def log_expm1(x):
    if x > 1.0:
        return x + math.log1p(-math.exp(-x))
    if x <= 0.0:
        return -np.inf
    return math.log(math.expm1(x))


@inline
def w_max(K, spec, dim):
    """max over real n ≥ 1 of log_w(n, K) (closed forms: the stationary point or n = 1)."""
    if spec == 0:
        n = K * K / 4.0 if dim == 2 else K * K / 2.0
    else:
        n = K / math.sqrt(2.0) if dim == 2 else K
    return log_w(max(n, 1.0), K, spec, dim)


@inline
def lnorm(n, pref, log_ks2, K, spec, dim):
    return pref + n * log_ks2 - log_fact(n) + log_w(n, K, spec, dim)


@inline
def term_log(n, pref, log_ks2, K, spec, dim, la_j, lx_j):
    return lnorm(n, pref, log_ks2, K, spec, dim) + 2.0 * (la_j + (n - 1.0) * lx_j)


@inline
def peak_order(pref, log_ks2, K, spec, dim, la_j, lx_j, qs):
    """Peak of one component's log-terms (log-concave in n): n = 2 if it already falls from
    2 to 3, else a golden-section search on log n."""
    f2 = term_log(2.0, pref, log_ks2, K, spec, dim, la_j, lx_j)
    f3 = term_log(3.0, pref, log_ks2, K, spec, dim, la_j, lx_j)
    if f3 <= f2:
        return 2.0
    a, b = math.log(2.0), math.log(2.0 * qs + 2.0 * K + 40.0)
    g = 0.6180339887498949
    c, e = b - g * (b - a), a + g * (b - a)
    fc = term_log(math.exp(c), pref, log_ks2, K, spec, dim, la_j, lx_j)
    fe = term_log(math.exp(e), pref, log_ks2, K, spec, dim, la_j, lx_j)
    for _ in range(30):
        if b - a < 0.01:
            break
        if fc > fe:
            b, e, fe = e, c, fc
            c = b - g * (b - a)
            fc = term_log(math.exp(c), pref, log_ks2, K, spec, dim, la_j, lx_j)
        else:
            a, c, fc = c, e, fe
            e = a + g * (b - a)
            fe = term_log(math.exp(e), pref, log_ks2, K, spec, dim, la_j, lx_j)
    return max(2.0, float(round(math.exp(0.5 * (a + b)))))


@jit
def row_series(la, lx, ph, sx, d, pref, K, log_ks2, spec, dim, log_rtol, max_terms,
               ok, lmass, prev, cur):  # fmt: skip
    """(log σ⁰, log envelope sum, status) of one geometry (see iem_series); ``ok, lmass,
    prev, cur``: work arrays of the components' length."""
    J = la.shape[0]
    # n = 1 (all components and d)
    big = -np.inf
    for j in range(J):
        big = max(big, la[j])
    ad = abs(d)
    ld = math.log(ad) if ad > 0 else -np.inf
    big = max(big, ld)
    ref = -np.inf  # sums are kept as ref + log(acc)
    acc = 0.0
    acc_e = 0.0
    if big > -np.inf:
        amp = 0j
        env = 0.0
        for j in range(J):
            m = math.exp(la[j] - big)
            amp += m * ph[j]
            env += m
        if ad > 0:
            amp += d * math.exp(-big)
            env += ad * math.exp(-big)
        ref = lnorm(1.0, pref, log_ks2, K, spec, dim) + 2.0 * big + 2.0 * math.log(env)
        acc = (amp.real * amp.real + amp.imag * amp.imag) / (env * env)
        acc_e = 1.0
    # components beyond n = 1
    wm = w_max(K, spec, dim)
    jstar, best, nok = -1, -np.inf, 0
    for j in range(J):
        ok[j] = lx[j] > -np.inf and la[j] > -np.inf
        lmass[j] = -np.inf
        if ok[j]:
            nok += 1
            q = math.exp(log_ks2 + 2.0 * lx[j])
            lmass[j] = pref + 2.0 * la[j] + log_expm1(q) - 2.0 * lx[j] + wm
            if 2.0 * la[j] + q > best:
                best, jstar = 2.0 * la[j] + q, j
    if nok == 0:
        return ref + math.log(acc) if acc > 0 else -np.inf, ref + math.log(acc_e), 0
    qs = math.exp(log_ks2 + 2.0 * lx[jstar])
    n0 = peak_order(pref, log_ks2, K, spec, dim, la[jstar], lx[jstar], qs)
    count = 0
    for direction in (1, -1):
        n = n0 if direction > 0 else n0 - 1.0
        first = True
        ln_prev = 0.0
        lg = log_fact(n)
        while n >= 2.0:
            ln = pref + n * log_ks2 - lg + log_w(n, K, spec, dim)
            big = -np.inf
            for j in range(J):
                if ok[j]:
                    cur[j] = la[j] + (n - 1.0) * lx[j]
                    big = max(big, cur[j])
                else:
                    cur[j] = -np.inf
            if big > -np.inf:
                amp = 0j
                env = 0.0
                odd = (int(n) - 1) % 2 == 1
                for j in range(J):
                    if ok[j]:
                        m = math.exp(cur[j] - big)
                        env += m
                        amp += (m * sx[j] if odd else m) * ph[j]
                te = ln + 2.0 * big + 2.0 * math.log(env)
                if te > ref:  # rescale the sums to the new largest envelope
                    sc = math.exp(ref - te) if ref > -np.inf else 0.0
                    acc *= sc
                    acc_e *= sc
                    ref = te
                w = math.exp(te - ref)
                acc += w * (amp.real * amp.real + amp.imag * amp.imag) / (env * env)
                acc_e += w
            # tail test every 4 orders (per component: geometric tail where it decreases in
            # the walk direction, its whole-series bound otherwise)
            if not first and count % 4 == 3:
                S = ref + math.log(acc) if acc > 0 else -np.inf
                dln = ln - ln_prev
                tmax = -np.inf
                for j in range(J):
                    if not ok[j]:
                        continue
                    c = ln + 2.0 * cur[j]
                    lr = dln + 2.0 * direction * lx[j]
                    t = lmass[j]
                    if lr < 0:
                        g = c + lr - math.log(-math.expm1(lr))
                        if direction < 0:
                            g = min(g, c + math.log(max(n - 2.0, 1e-300)))
                        t = min(t, g)
                    prev[j] = t
                    tmax = max(tmax, t)
                tail = -np.inf
                if tmax > -np.inf:
                    tot = 0.0
                    for j in range(J):
                        if ok[j]:
                            tot += math.exp(prev[j] - tmax)
                    tail = tmax + math.log(tot * nok)
                if tail <= log_rtol + S or logadd(S, tail) < -760.0:
                    break
            ln_prev = ln
            first = False
            if direction > 0:
                n += 1.0
                lg += math.log(n)
            else:
                lg -= math.log(n)
                n -= 1.0
            count += 1
            if count > max_terms:
                return ref + math.log(acc) if acc > 0 else -np.inf, ref + math.log(acc_e), 1
    return ref + math.log(acc) if acc > 0 else -np.inf, ref + math.log(acc_e), 0


@jit
def series_kernel(la, lx, ph, sx, d, pref, K, log_ks2, spec, dim, log_rtol, max_terms,
                  out_s, out_e):  # fmt: skip
    status = 0
    J = la.shape[1]
    ok, lmass, prev, cur = np.empty(J, np.bool_), np.empty(J), np.empty(J), np.empty(J)
    for r in range(la.shape[0]):
        s, e, st = row_series(la[r], lx[r], ph[r], sx[r], d[r], pref[r], K[r], log_ks2,
                              spec, dim, log_rtol, max_terms, ok, lmass, prev, cur)  # fmt: skip
        out_s[r], out_e[r] = s, e
        status = max(status, st)
    return status


#: From this q = e^logq on the Poisson-type sums start at their peak n ≈ q (walking from
#: n = 1 costs ~q orders; from the peak, ~15 √q at rtol 1e-10)
PEAK_START_Q = 64.0


@inline
def _increment(n, logq, K, spec, dim):
    """``t(n + 1) − t(n)`` for the terms ``t(n) = n log q − log n! + log Ŵₙ``."""
    return logq - math.log(n + 1.0) + log_w(n + 1.0, K, spec, dim) - log_w(n, K, spec, dim)


@inline
def _peak(logq, K, spec, dim):
    """The largest term's order: the first n ≥ 1 with ``t(n + 1) ≤ t(n)``. The increments
    decrease with n for the Gaussian and exponential closed forms (the terms are log-concave:
    ``−log n!`` and ``log Ŵₙ`` each have decreasing increments from n = 2), so bisection finds
    it; the bracket doubles until it holds the sign change."""
    if _increment(1.0, logq, K, spec, dim) <= 0.0:
        return 1.0
    lo, hi = 1.0, max(2.0, float(math.ceil(math.exp(logq))))  # integers: bisection ends
    while _increment(hi, logq, K, spec, dim) > 0.0:
        lo, hi = hi, 2.0 * hi
    while hi - lo > 1.0:
        mid = math.floor(0.5 * (lo + hi))
        if _increment(mid, logq, K, spec, dim) > 0.0:
            lo = mid
        else:
            hi = mid
    return hi


@jit
def poisson_sum(logq, K, spec, dim, log_rtol):
    """log Σ_{n≥1} qⁿ/n! Ŵₙ(K) (log-concave terms). From :data:`PEAK_START_Q` on the walk
    starts at the largest term and goes both ways; each way stops when the geometric bound of
    what is left (the current term ratio holds or improves: log-concavity) is below ``rtol`` of
    the sum."""
    if logq < math.log(PEAK_START_Q):
        ref, acc, prev = -np.inf, 0.0, -np.inf
        n = 1.0
        while True:
            t = n * logq - log_fact(n) + log_w(n, K, spec, dim)
            if t > ref:
                acc = acc * math.exp(ref - t) + 1.0 if ref > -np.inf else 1.0
                ref = t
            else:
                acc += math.exp(t - ref)
            S = ref + math.log(acc)
            lr = t - prev
            if n > 1.0 and lr < 0:
                if t + lr - math.log(-math.expm1(lr)) <= S + log_rtol or S < -760.0:
                    return S
            prev = t
            n += 1.0
            if n > 1e7:
                return S
    n0 = _peak(logq, K, spec, dim)
    ref = n0 * logq - log_fact(n0) + log_w(n0, K, spec, dim)  # the largest term
    acc = 1.0
    for step in (1.0, -1.0):  # up from the peak, then down to n = 1
        prev = ref
        n = n0 + step
        while n >= 1.0:
            t = n * logq - log_fact(n) + log_w(n, K, spec, dim)
            acc += math.exp(t - ref)
            lr = t - prev  # < 0 away from the peak
            if lr < 0.0 and t + lr - math.log(-math.expm1(lr)) <= ref + math.log(acc) + log_rtol:
                break
            prev = t
            n += step
            if abs(n - n0) > 1e7:
                break
    return ref + math.log(acc)


@jit
def transition_sums(logq, K, spec, dim, log_rtol):
    """log S(βQ) for β = 1, 2, 4 in one pass (the β = 4 series is the longest); three
    peak-started :func:`poisson_sum` calls where Q is large."""
    if logq >= math.log(PEAK_START_Q):
        return (poisson_sum(logq, K, spec, dim, log_rtol),
                poisson_sum(logq + math.log(2.0), K, spec, dim, log_rtol),
                poisson_sum(logq + math.log(4.0), K, spec, dim, log_rtol))  # fmt: skip
    r1 = r2 = r4 = -np.inf
    a1 = a2 = a4 = 0.0
    prev = -np.inf
    l2, l4 = math.log(2.0), math.log(4.0)
    n = 1.0
    while True:
        t = n * logq - log_fact(n) + log_w(n, K, spec, dim)
        for which in range(3):
            tb = t + n * (0.0 if which == 0 else (l2 if which == 1 else l4))
            rr = r1 if which == 0 else (r2 if which == 1 else r4)
            aa = a1 if which == 0 else (a2 if which == 1 else a4)
            if tb > rr:
                aa = aa * math.exp(rr - tb) + 1.0 if rr > -np.inf else 1.0
                rr = tb
            else:
                aa += math.exp(tb - rr)
            if which == 0:
                r1, a1 = rr, aa
            elif which == 1:
                r2, a2 = rr, aa
            else:
                r4, a4 = rr, aa
        t4 = t + n * l4
        S4 = r4 + math.log(a4)
        lr = t4 - prev
        if n > 1.0 and lr < 0:
            if t4 + lr - math.log(-math.expm1(lr)) <= S4 + log_rtol or S4 < -760.0:
                break
        prev = t4
        n += 1.0
        if n > 1e7:
            break
    return r1 + math.log(a1), r2 + math.log(a2), r4 + math.log(a4)


@jit
def poisson_kernel(logq, K, spec, dim, log_rtol, out):
    for r in range(logq.shape[0]):
        out[r] = poisson_sum(logq[r], K[r], spec, dim, log_rtol) if logq[r] > -np.inf \
            else -np.inf  # fmt: skip


@inline
def root(z):
    r = np.sqrt(z + 0j)
    return -r if r.imag < 0 else r


ISQ = np.array([0.0] + [1.0 / math.sqrt(n) for n in range(1, 4096)])  # 1/√n, looked up
FAST_MAX_ORDER = 4000  # a linear-space walk longer than this goes to the log-space path
TINY, HUGE = 1e-250, 1e300  # sums outside [TINY, HUGE] (scaled): log-space path


@inline
def w_lin(n, K2, spec, dim):
    """Ŵₙ(K) (exp of :func:`log_w`), ≤ 1 for every n ≥ 1, K; ``K2 = K²``."""
    if spec == 0:
        if dim == 2:
            return math.exp(-K2 / (4.0 * n)) / (4.0 * math.pi * n)
        return math.exp(-K2 / (4.0 * n)) / (2.0 * math.sqrt(math.pi * n))
    t = n * n + K2
    if dim == 2:
        return n / (2.0 * math.pi * t * math.sqrt(t))
    return n / (math.pi * t)


@inline
def cabs(z):
    return math.sqrt(z.real * z.real + z.imag * z.imag)


@inline
def isqrt(n):
    i = int(n)
    return ISQ[i] if i < 4096 else 1.0 / math.sqrt(n)


@inline
def back_shadowing(s, c, den1, code, psi):
    """:func:`emscatter.solvers.iem.model._shadowing` at backscatter, one direction: Smith's Λ
    (:func:`emscatter.solvers.kirchhoff.common.smith_lambda`) at ``a = cosθ/(sinθ √2 s)``
    (``den1 = √2 s``), then ``1/(1 + Λ + λ(ψ) Λ)`` (code 1) or ``1/(1 + 2Λ)`` (code 2)."""
    den = s * den1
    a = c / (den if den > 0 else 1.0) if den > c * 1e-300 else 1e300
    lam = 0.0
    if a < 6.0:
        an = max(a, 1e-300)
        lam = max(0.5 * (math.exp(-an * an) / (an * SQRT_PI) - math.erfc(an)), 0.0)
    if code == 2:
        return 1.0 / (1.0 + lam + lam)
    corr = 4.41 * psi / (4.41 * psi + 1.0)
    return 1.0 / (1.0 + lam + corr * lam)


SQRT_PI = math.sqrt(math.pi)


@inline
def lower_co(C, rh, rv, iq, eps, ieps):
    """(hh, 0, 0, vv) of :func:`emscatter.solvers.iem.terms._combine` for the lower medium, co-pol
    only,
    with ``iq = 1/q₂``, ``ieps = 1/ε`` (multiplications instead of its divisions)."""
    c1, c2, c3, c4, c5 = C
    hp, hm = 1.0 + rh, 1.0 - rh
    hh = hp * iq * (hp * (c3 - c1 * eps) + hm * c2) + hm * iq * (hm * c4 + hp * c5)
    vp, vm = 1.0 + rv, 1.0 - rv
    vv = vp * iq * (vp * (c1 - c3 * ieps) - vm * c2) - vm * iq * (vm * c4 * eps + vp * c5)
    return hh, 0j, 0j, vv
