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
def transition_lin(Q, K2, spec, dim, rtol_t, wbuf):
    """Linear-space :func:`transition_sums`: ``(ok, S(2Q)/S(Q) e^{−Q}, S(4Q)/S(Q) e^{−2Q},
    orders stored in wbuf)`` with ``S(βQ) = Σ_{n≥1} (βQ)ⁿ/n! Ŵₙ``; ``wbuf[n] = Ŵₙ``. Stops
    when the geometric tail of each of the three series (term ratios non-increasing from n = 3
    on for these spectra) is below ``rtol_t`` of its sum; ``ok`` False when the sums leave the
    safe range (the caller then takes the log-space path)."""
    s1 = s2 = s4 = 0.0
    qn, p2, p4, prev = 1.0, 1.0, 1.0, 0.0
    nw = wbuf.shape[0]
    n = 1.0
    while True:
        qn *= Q / n
        p2 *= 2.0
        p4 *= 4.0
        w = w_lin(n, K2, spec, dim)
        i = int(n)
        if i < nw:
            wbuf[i] = w
        t1 = qn * w
        s1 += t1
        s2 += t1 * p2
        s4 += t1 * p4
        if n >= 3.0 and i & 1 and prev > 0.0:  # tail test at odd orders
            r1 = t1 / prev
            r4 = 4.0 * r1
            if r4 < 1.0:
                r2 = 2.0 * r1
                if (t1 * r1 / (1.0 - r1) <= rtol_t * s1
                        and t1 * p2 * r2 / (1.0 - r2) <= rtol_t * s2
                        and t1 * p4 * r4 / (1.0 - r4) <= rtol_t * s4):  # fmt: skip
                    break
        prev = t1
        n += 1.0
        if n > FAST_MAX_ORDER:
            return False, 0.0, 0.0, 0
    if not (TINY <= s1 < HUGE and s4 < HUGE):
        return False, 0.0, 0.0, 0
    eq = math.exp(-Q)
    return True, s2 / s1 * eq, s4 / s1 * eq * eq, min(int(n) + 1, nw)


@inline
def fast_pair(amp, x, att, e_log, dd, J, ks2, K2, spec, dim, rtol, max_terms, wbuf, nw, z, msk,
              co, xx):  # fmt: skip
    """Both co-pol series of one backscatter geometry in linear space (the log-space
    :func:`row_series` rewritten as recurrences): ``(ok, S_hh, S_vv, precision ratio)``
    without the prefactor ``e^{pref}``.

    ``amp`` (2, J) complex amplitudes, ``x`` (J) real bases, ``att`` (J) = ``e^{e_log}`` their
    attenuations, ``dd`` (2) the n = 1 extra amplitudes (attenuation included). Terms
    ``Tₙ = (kσ)^{2n}/n! Ŵₙ |Σ_j amp_j att_j x_j^(n−1) + δ_{n1} d|²`` with
    ``z_j(n) = att_j x_j^(n−1) √((kσ)^{2n}/n!)`` by one multiplication per order, scaled by the
    largest start magnitude so every term is ≤ 1-ish. Stopping rule as :func:`row_series`:
    per component the geometric tail ``T r/(1 − r)`` with ``r = x_j² (kσ)²/n Ŵₙ/Ŵₙ₋₁`` (term
    ratios are non-increasing from n = 3 on for the Gaussian and exponential closed forms),
    its whole-series bound ``|amp|² e^{2e + Q}/x²`` where it still rises; times J
    (Cauchy–Schwarz); below ``rtol`` of the sum for both polarizations. ``ok`` False (the
    caller takes the log-space path) when a term could leave the range of doubles: a
    component that starts below 1e-140 of the largest is left out and its whole-series
    bound must be negligible (≤ 1e-3 rtol of the sum) at the end; a walk
    longer than :data:`FAST_MAX_ORDER`, sums outside [1e-250, 1e300]."""
    sks = math.sqrt(ks2)
    # n = 1
    w1 = wbuf[1] if nw > 1 else w_lin(1.0, K2, spec, dim)
    i1h = dd[0] * sks
    i1v = dd[1] * sks
    e1h = cabs(dd[0]) * sks
    e1v = cabs(dd[1]) * sks
    m2 = 0.0  # largest squared start magnitude
    for j in range(J):  # real work copies: rows re/im hh, re/im vv, |hh|, |vv|, |hh|², |vv|²
        co[0, j], co[1, j] = amp[0, j].real, amp[0, j].imag
        co[2, j], co[3, j] = amp[1, j].real, amp[1, j].imag
        co[6, j] = co[0, j] ** 2 + co[1, j] ** 2
        co[7, j] = co[2, j] ** 2 + co[3, j] ** 2
        co[4, j], co[5, j] = math.sqrt(co[6, j]), math.sqrt(co[7, j])
        xx[j] = x[j] * x[j]
        if e_log[j] < -700.0 and (co[6, j] > 0.0 or co[7, j] > 0.0):  # att not normal
            return False, 0.0, 0.0, 0.0
        z1 = att[j] * sks
        i1h += amp[0, j] * z1
        i1v += amp[1, j] * z1
        e1h += co[4, j] * z1
        e1v += co[5, j] * z1
        z[j] = z1 * x[j] * sks * ISQ[2]  # n = 2
        m2 = max(m2, max(co[6, j], co[7, j]) * z[j] * z[j])
    a1h = i1h.real * i1h.real + i1h.imag * i1h.imag
    a1v = i1v.real * i1v.real + i1v.imag * i1v.imag
    m2 = max(m2, a1h, a1v)
    if not (0.0 < m2 < HUGE):
        return False, 0.0, 0.0, 0.0
    m0 = math.sqrt(m2)
    inv = 1.0 / m0
    nh = nv = nd = 0
    drop = 0.0  # bound on the left-out components' whole series (scaled)
    for j in range(J):
        z[j] *= inv
        big = max(co[6, j], co[7, j])
        mj = big * z[j] * z[j]
        msk[j] = -1.0  # whole-series bound, computed when needed (-1: not yet)
        if mj == 0.0:
            z[j] = 0.0
            continue
        if mj < 1e-280:  # may rise from below the precise range: left out, bounded below
            drop += big * math.exp(2.0 * e_log[j] + ks2 * xx[j]) / xx[j] * inv * inv
            nd += 1
            z[j] = 0.0
            continue
        if co[6, j] > 0.0:
            nh += 1
        if co[7, j] > 0.0:
            nv += 1
    sh = a1h * inv * inv * w1
    sv = a1v * inv * inv * w1
    eh = (e1h * inv) ** 2 * w1
    ev = (e1v * inv) ** 2 * w1
    w_prev = w1
    n = 2.0
    while True:
        i = int(n)
        w = wbuf[i] if i < nw else w_lin(n, K2, spec, dim)
        hr = hi = vr = vi = 0.0
        enh = 0.0
        env = 0.0
        for j in range(J):
            zj = z[j]
            hr += co[0, j] * zj
            hi += co[1, j] * zj
            vr += co[2, j] * zj
            vi += co[3, j] * zj
            az = abs(zj)
            enh += co[4, j] * az
            env += co[5, j] * az
        sh += (hr * hr + hi * hi) * w
        sv += (vr * vr + vi * vi) * w
        eh += enh * enh * w
        ev += env * env * w
        if n >= 3.0 and i & 3 == 3:  # tail test at orders 3, 7, 11, ...
            rho = ks2 / n * w / w_prev if w_prev > 0.0 else np.inf
            th = 0.0
            tv = 0.0
            for j in range(J):
                zj = z[j]
                if zj == 0.0:
                    continue
                r = xx[j] * rho
                if r < 1.0:
                    g = zj * zj * w * r / (1.0 - r)
                else:
                    if msk[j] < 0.0:
                        q = ks2 * xx[j]
                        msk[j] = math.exp(2.0 * e_log[j] + q) / xx[j] * inv * inv
                    g = msk[j]
                th += co[6, j] * g
                tv += co[7, j] * g
            if nh * th <= rtol * sh and nv * tv <= rtol * sv:
                break
        if n >= FAST_MAX_ORDER or n > max_terms:
            return False, 0.0, 0.0, 0.0
        w_prev = w
        n += 1.0
        f = sks * isqrt(n)
        for j in range(J):
            z[j] *= x[j] * f
    if not (TINY <= sh < HUGE and TINY <= sv < HUGE):
        return False, 0.0, 0.0, 0.0
    # left-out components change √S by at most √(nd·drop) (Minkowski, Cauchy–Schwarz): keep
    # that below 5e-4 rtol of √S (a relative change ≤ 1e-3 rtol), else the log-space path
    if nd and not nd * drop <= (5e-4 * rtol) ** 2 * min(sh, sv):
        return False, 0.0, 0.0, 0.0
    return True, sh * m0 * m0, sv * m0 * m0, max(eh / sh, ev / sv)


@inline
def back_shadowing(s, c, den1, code, psi):
    """:func:`emscatter.solvers.iem._shadowing` at backscatter, one direction: Smith's Λ
    (:func:`emscatter.solvers.kirchhoff_common.smith_lambda`) at ``a = cosθ/(sinθ √2 s)``
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
    """(hh, 0, 0, vv) of :func:`.iem_kernels._combine` for the lower medium, co-pol only,
    with ``iq = 1/q₂``, ``ieps = 1/ε`` (multiplications instead of its divisions)."""
    c1, c2, c3, c4, c5 = C
    hp, hm = 1.0 + rh, 1.0 - rh
    hh = hp * iq * (hp * (c3 - c1 * eps) + hm * c2) + hm * iq * (hm * c4 + hp * c5)
    vp, vm = 1.0 + rv, 1.0 - rv
    vv = vp * iq * (vp * (c1 - c3 * ieps) - vm * c2) - vm * iq * (vm * c4 * eps + vp * c5)
    return hh, 0j, 0j, vv


@jit
def back_kernel(si, cs, eps, pec, ks, K, pref, spec, dim, transition, log_rtol,
                max_terms, use_fast, sh_code, sh_slope, psi, out_hh, out_vv, out_e,
                out_fast):  # fmt: skip
    """Exact-backscatter hh, vv per geometry: the linear-space walk (:func:`fast_pair`,
    :func:`transition_lin`) where it is safe and ``use_fast``, else the log-space
    :func:`row_series` / :func:`transition_sums`. Outputs σ⁰_hh, σ⁰_vv, the precision ratio
    (sum of the envelopes over the sum, ≥ 1; :mod:`.iem_series`) and ``out_fast[r]``: the
    fast path was taken."""
    ks2 = ks * ks
    log_ks2 = math.log(ks2)
    rtol = math.exp(log_rtol)
    status = 0
    la = np.empty(3)
    lx = np.empty(3)
    sx = np.ones(3)
    ph = np.ones(3, dtype=np.complex128)
    sq = root(eps)
    r0 = (sq - 1.0) / (sq + 1.0)
    ieps = 1.0 / eps
    zero = (0j, 0j, 0j, 0j)
    wok, wmass, wprev, wcur = np.empty(3, np.bool_), np.empty(3), np.empty(3), np.empty(3)
    wbuf = np.empty(256)
    famp = np.empty((2, 3), dtype=np.complex128)
    fx, fatt, felog, fz, fmsk = np.empty(3), np.empty(3), np.empty(3), np.empty(3), np.empty(3)
    fdd = np.empty(2, dtype=np.complex128)
    fco, fxx = np.empty((8, 3)), np.empty(3)
    sh_den = math.sqrt(2.0 * sh_slope * sh_slope)
    for r in range(si.shape[0]):
        s, c = si[r], cs[r]
        s2 = s * s
        K2 = K[r] * K[r]
        shf = 1.0
        if sh_code != 0:
            shf = back_shadowing(s, c, sh_den, sh_code, psi[r] if sh_code == 1 else 0.0)
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
        fast = use_fast
        nw = 0
        if transition and not pec:
            Q = ks2 * c * c
            e2, e4 = 2.0, 4.0
            if c > 0:
                if fast:
                    fast, e2, e4, nw = transition_lin(Q, K2, spec, dim, rtol * 1e-2, wbuf)
                if not fast:
                    lq = math.log(Q)
                    l1, l2, l4 = transition_sums(lq, K[r], spec, dim, log_rtol - 4.6)
                    e2 = math.exp(min(l2 - l1 - Q, 700.0))
                    e4 = math.exp(min(l4 - l1 - 2.0 * Q, 700.0))
            ftc = 8.0 * r0 * r0 * s2 * (c + q2) / q2
            a0 = 16.0 * abs(r0) ** 2
            gh, gv = 0.0, 0.0
            for i in range(2):
                f = -ftc if i == 0 else ftc
                num = abs(f + 8.0 * r0) ** 2
                den = abs(f) ** 2 + 8.0 * (f * np.conj(r0)).real * e2 + a0 * e4
                ratio = num / den if den > 0 else 1.0
                if i == 0:
                    gh = min(max(1.0 - ratio, 0.0), 1.0)
                else:
                    gv = min(max(1.0 - ratio, 0.0), 1.0)
            rh_t = rh + (-r0 - rh) * gh
            rv_t = rv + (r0 - rv) * gv
        e_k = -2.0 * ks2 * c * c
        lx[0] = math.log(2.0 * c) if c > 0 else -np.inf
        J = 1
        a = 0.0
        if not pec:
            a = q2.real
            Ci, _ = reduced_i(s, c, s, c, 0.0, -1.0, -q2, c + a)
            Cs, _ = reduced_s(s, c, s, c, 0.0, -1.0, q2, c + a)
            Cm, _ = reduced_s(s, c, s, c, 0.0, -1.0, -q2, c - a)
            iq = 1.0 / q2
            p1 = lower_co(Ci, rh, rv, iq, eps, ieps)
            p2 = lower_co(Cs, rh, rv, iq, eps, ieps)
            mm = lower_co(Cm, rh, rv, iq, eps, ieps)
            e_g = -ks2 * (a * a + c * c)
            J = 3
        # linear-space walk of both polarizations (fast path)
        if fast:
            fx[0], felog[0] = 2.0 * c, e_k
            famp[0, 0], famp[1, 0] = -4.0 * rh_t, 4.0 * rv_t
            if J == 3:
                fx[1], fx[2] = c + a, c - a
                felog[1] = felog[2] = e_g
                famp[0, 1], famp[1, 1] = 0.25 * (p1[0] + p2[0]), 0.25 * (p1[3] + p2[3])
                famp[0, 2], famp[1, 2] = 0.25 * mm[0], 0.25 * mm[3]
            ek_lin = math.exp(e_k)
            fatt[0] = ek_lin
            if J == 3:
                fatt[1] = fatt[2] = math.exp(e_g)
            fdd[0] = -4.0 * s2 * rh * rh * ek_lin
            fdd[1] = 4.0 * s2 * rv * rv * ek_lin
            if nw < 3:
                nw = 0
            fast, shh, svv, prec = fast_pair(
                famp, fx, fatt, felog, fdd, J, ks2, K2, spec, dim, rtol, max_terms, wbuf, nw,
                fz, fmsk, fco, fxx,
            )  # fmt: skip
            if fast:
                ep = math.exp(pref[r]) * shf
                out_hh[r] = shh * ep
                out_vv[r] = svv * ep
                out_e[r] = prec
                out_fast[r] = True
                continue
        out_fast[r] = False
        # log-space path (any kσ, |ε|)
        if not pec:
            lx[1] = math.log(abs(c + a)) if c + a != 0 else -np.inf
            lx[2] = math.log(abs(c - a)) if c - a != 0 else -np.inf
            sx[1] = -1.0 if c + a < 0 else 1.0
            sx[2] = -1.0 if c - a < 0 else 1.0
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
                pref[r] + math.log(shf),
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
                out_hh[r] = math.exp(sres)
            else:
                out_vv[r] = math.exp(sres)
            out_e[r] = max(out_e[r], math.exp(min(eres - sres, 700.0)))
    return status
