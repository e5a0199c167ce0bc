"""The numba kernels behind :mod:`.iem_jit` (module-level, so numba's on-disk cache reuses
them across processes), decorated with the package's runtime (:mod:`emscatter.kernels._runtime`:
cache directory, numba options). Only :mod:`.iem_jit` imports this module, on first use."""

from __future__ import annotations

import math

import numpy as np

from ..kernels._runtime import inline, jit
from . import iem_kernels as kern

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


@jit
def poisson_sum(logq, K, spec, dim, log_rtol):
    """log Σ_{n≥1} qⁿ/n! Ŵₙ(K) (log-concave past its peak)."""
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


@jit
def transition_sums(logq, K, spec, dim, log_rtol):
    """log S(βQ) for β = 1, 2, 4 in one pass (the β = 4 series is the longest)."""
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
def to_c4(t):
    return (t[0] + 0j, t[1] + 0j, t[2] + 0j, t[3] + 0j)


@inline
def root(z):
    r = np.sqrt(z + 0j)
    return -r if r.imag < 0 else r


@jit
def back_kernel(si, cs, eps, pec, ks, K, pref, spec, dim, transition, log_rtol,
                max_terms, out_hh, out_vv, out_e):  # fmt: skip
    ks2 = ks * ks
    log_ks2 = math.log(ks2)
    status = 0
    la = np.empty(3)
    lx = np.empty(3)
    sx = np.ones(3)
    ph = np.ones(3, dtype=np.complex128)
    sq = root(eps)
    r0 = (sq - 1.0) / (sq + 1.0)
    zero = (0j, 0j, 0j, 0j)
    wok, wmass, wprev, wcur = np.empty(3, np.bool_), np.empty(3), np.empty(3), np.empty(3)
    for r in range(si.shape[0]):
        s, c = si[r], cs[r]
        s2 = s * s
        q2 = 0j
        p1, p2, mm = zero, zero, zero
        e_g = 0.0
        if pec:
            rh, rv = -1.0 + 0j, 1.0 + 0j
        else:
            q2 = root(eps - s2)
            rh = (c - q2) / (c + q2) if c + q2 != 0 else 0j
            rv = (eps * c - q2) / (eps * c + q2) if eps * c + q2 != 0 else 0j
        rh_t, rv_t = rh, rv
        if transition and not pec:
            lq = math.log(ks2 * c * c) if c > 0 else -np.inf
            l1 = l2 = l4 = 0.0
            if c > 0:
                l1, l2, l4 = transition_sums(lq, K[r], spec, dim, log_rtol - 4.6)
            Q = ks2 * c * c
            e2 = math.exp(min(l2 - l1 - Q, 700.0)) if c > 0 else 2.0
            e4 = math.exp(min(l4 - l1 - 2.0 * Q, 700.0)) if c > 0 else 4.0
            ftc = 8.0 * r0 * r0 * s2 * (c + q2) / q2
            a0 = 16.0 * abs(r0) ** 2
            gam = np.empty(2)
            for i, f in enumerate((-ftc, ftc)):
                num = abs(f + 8.0 * r0) ** 2
                den = abs(f) ** 2 + 8.0 * (f * np.conj(r0)).real * e2 + a0 * e4
                ratio = num / den if den > 0 else 1.0
                gam[i] = min(max(1.0 - ratio, 0.0), 1.0)
            rh_t = rh + (-r0 - rh) * gam[0]
            rv_t = rv + (r0 - rv) * gam[1]
        e_k = -2.0 * ks2 * c * c
        lx[0] = math.log(2.0 * c) if c > 0 else -np.inf
        J = 1
        if not pec:
            a = q2.real
            Rx = 0.5 * (rv - rh)
            Ci, Bi = reduced_i(s, c, s, c, 0.0, -1.0, -q2, c + a)
            Cs, Bs = reduced_s(s, c, s, c, 0.0, -1.0, q2, c + a)
            Cm, Bm = reduced_s(s, c, s, c, 0.0, -1.0, -q2, c - a)
            p1 = to_c4(combine(Ci, Bi, (rh, rv), Rx, q2, eps, True, True))
            p2 = to_c4(combine(Cs, Bs, (rh, rv), Rx, q2, eps, True, True))
            mm = to_c4(combine(Cm, Bm, (rh, rv), Rx, q2, eps, True, True))
            e_g = -ks2 * (a * a + c * c)
            lx[1] = math.log(abs(c + a)) if c + a != 0 else -np.inf
            lx[2] = math.log(abs(c - a)) if c - a != 0 else -np.inf
            sx[1] = -1.0 if c + a < 0 else 1.0
            sx[2] = -1.0 if c - a < 0 else 1.0
            J = 3
        for p in range(2):
            ak = -4.0 * rh_t if p == 0 else 4.0 * rv_t
            u = (-4.0 * s2 * rh * rh) if p == 0 else (4.0 * s2 * rv * rv)
            amps = (
                (
                    ak,
                    0.25 * (p1[0] + p2[0]) if p == 0 else 0.25 * (p1[3] + p2[3]),
                    0.25 * mm[0] if p == 0 else 0.25 * mm[3],
                )
                if J == 3
                else (ak, 0j, 0j)
            )
            for j in range(J):
                m = abs(amps[j])
                la[j] = (math.log(m) if m > 0 else -np.inf) + (e_k if j == 0 else e_g)
                ph[j] = amps[j] / m if m > 0 else 1.0 + 0j
            d = u * math.exp(e_k)
            sres, eres, st = row_series(
                la[:J],
                lx[:J],
                ph[:J],
                sx[:J],
                d,
                pref[r],
                K[r],
                log_ks2,
                spec,
                dim,
                log_rtol,
                max_terms,
                wok[:J],
                wmass[:J],
                wprev[:J],
                wcur[:J],
            )
            status = max(status, st)
            if p == 0:
                out_hh[r] = sres
            else:
                out_vv[r] = sres
            out_e[r] = max(out_e[r], eres - sres)
    return status
