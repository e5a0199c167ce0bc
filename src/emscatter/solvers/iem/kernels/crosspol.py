"""Compiled (numba) integral of the multiple-scattering cross-polarization of
:mod:`emscatter.solvers.iem.crosspol`: the same nodes, kernel, tables and interpolation as its
numpy reference
(``_integrate_numpy``), one geometry at a time, threads over contiguous chunks of geometries.

Per geometry: the three ``log T`` rows (last point, first point, crossed pairing) are
interpolated in ``log Q`` from the per-roughness table once, then each node costs two kernel
evaluations (the forward and the reversed path), four 1-D Catmull–Rom look-ups and one Smith
shadowing. Agreement with the numpy reference: rounding (tests/test_iem_crosspol.py).
"""

from __future__ import annotations

import math
import os
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from emscatter.kernels._runtime import inline, jit
from emscatter.solvers.iem.crosspol_terms import slope_coefficients

__all__ = ["integrate"]

_SQRT_PI = math.sqrt(math.pi)


@inline
def _graded(c, e, w, tau, wtau, xs, ws, off):
    """:func:`emscatter.solvers.iem.crosspol.graded` for one segment, written into ``xs, ws`` at
    ``off``."""
    L = abs(e - c)
    lam = L / w
    flat = lam < 1e-8
    ll = math.log1p(lam) if not flat else 0.0
    for j in range(tau.size):
        if flat:
            g, dg = tau[j], 1.0
        else:
            g = math.expm1(tau[j] * ll) / lam
            dg = ll * math.exp(tau[j] * ll) / lam
        xs[off + j] = c + (e - c) * g
        ws[off + j] = L * dg * wtau[j]


@inline
def _cr(f):
    f2 = f * f
    f3 = f2 * f
    return (-0.5 * f3 + f2 - 0.5 * f, 1.5 * f3 - 2.5 * f2 + 1.0, -1.5 * f3 + 2.0 * f2 + 0.5 * f,
            0.5 * f3 - 0.5 * f2)  # fmt: skip


@inline
def _row(values, s0, hs, ns, Q, out):
    """``log T(Q, ·)`` on the x grid (Catmull–Rom in ``log Q``, clamped)."""
    p = (math.log(Q) - s0) / hs if Q > 0 else 0.0
    p = min(max(p, 0.0), ns - 1.0)
    i = min(int(math.floor(p)), ns - 2)
    w0, w1, w2, w3 = _cr(p - i)
    for j in range(out.size):
        out[j] = (w0 * values[i, j] + w1 * values[i + 1, j] + w2 * values[i + 2, j]
                  + w3 * values[i + 3, j])  # fmt: skip


@inline
def _position(hx, nx, K):
    p = min(math.log1p(K) / hx, nx - 1.0)
    j = min(int(math.floor(p)), nx - 2)
    return j, _cr(p - j)


@inline
def _look(row, j, w):
    return w[0] * row[j] + w[1] * row[j + 1] + w[2] * row[j + 2] + w[3] * row[j + 3]


@inline
def _shadow(r, q, s2):
    """Smith ``1/(1 + Λ)`` of the intermediate wave, ``a = q/(r √(2 s²))``."""
    lam = 0.0
    if r > 0:
        aa = q / (r * math.sqrt(2.0 * s2))
        if aa < 6.0:
            aa = max(aa, 1e-300)
            lam = max(0.5 * (math.exp(-aa * aa) / (aa * _SQRT_PI) - math.erfc(aa)), 0.0)
    return 1.0 / (1.0 + lam)


# the numpy reference's own polynomial, compiled (one source: edit it there)
_slope_coefficients = inline(slope_coefficients)


@inline
def _amplitude(gam, g, pol, b, inv_q, inv_qt, pec):
    up = 0j
    lo = 0j
    for j in range(6):
        up += gam[0, pol, j, g] * b[j]
        lo += gam[1, pol, j, g] * b[j]
    return up * inv_q + (0j if pec else lo * inv_qt)


@jit
def _kernel(ti, ts, si, cs, ss, css, sf, cf, dp, pi_, eps, pec, gam, gam_r, q_s, q_i, q_c,
            decor, values, s0, hs, ns, hx, nx, klx, kly, sx, sy, w, w_rim, tau, wtau, start,
            stop, out_hv, out_vh):  # fmt: skip
    n = tau.size
    tr, wr = np.empty(5 * n), np.empty(5 * n)
    ta, wa = np.empty(4 * n), np.empty(4 * n)
    row_s, row_i, row_c = np.empty(nx + 3), np.empty(nx + 3), np.empty(nx + 3)
    ca, sa, s2a = np.empty(4 * n), np.empty(4 * n), np.empty(4 * n)
    iso = sx == sy
    half_pi, two_pi = 0.5 * math.pi, 2.0 * math.pi
    for g in range(start, stop):
        a_i, a_s = si[g], ss[g]
        lo, hi = min(ti[g], ts[g]), max(ti[g], ts[g])
        w_lo = min(w / max(math.cos(lo), w), 1.0)
        w_hi = min(w / max(math.cos(hi), w), 1.0)
        mid, top = 0.5 * (lo + hi), 0.5 * (hi + half_pi)
        _graded(lo, 0.0, w_lo, tau, wtau, tr, wr, 0)
        _graded(lo, mid, w_lo, tau, wtau, tr, wr, n)
        _graded(hi, mid, w_hi, tau, wtau, tr, wr, 2 * n)
        _graded(hi, top, w_hi, tau, wtau, tr, wr, 3 * n)
        _graded(half_pi, top, w_rim, tau, wtau, tr, wr, 4 * n)
        d = dp[g] % two_pi
        a1, a2 = math.pi, math.pi + d
        m1, m2 = a1 + 0.5 * d, a2 + 0.5 * (two_pi - d)
        wi = min(w / max(a_i, w), 1.0)
        ws_ = min(w / max(a_s, w), 1.0)
        _graded(a1, m1, wi, tau, wtau, ta, wa, 0)
        _graded(a2, m1, ws_, tau, wtau, ta, wa, n)
        _graded(a2, m2, ws_, tau, wtau, ta, wa, 2 * n)
        _graded(a1 + two_pi, m2, wi, tau, wtau, ta, wa, 3 * n)
        for ia in range(4 * n):
            ca[ia], sa[ia] = math.cos(ta[ia]), math.sin(ta[ia])
            alpha = ta[ia] + pi_[g]  # intermediate-wave azimuth, surface frame
            s2a[ia] = (sx * math.cos(alpha)) ** 2 + (sy * math.sin(alpha)) ** 2
        _row(values, s0, hs, ns, q_s[g], row_s)
        _row(values, s0, hs, ns, q_i[g], row_i)
        _row(values, s0, hs, ns, q_c[g], row_c)
        c_i, c_s, s_f, c_f = cs[g], css[g], sf[g], cf[g]
        cp, sp = math.cos(pi_[g]), math.sin(pi_[g])
        e = 1.0 + 0j if pec else eps[g]
        dec = decor[g]
        acc_hv, acc_vh = 0.0, 0.0
        for it in range(5 * n):
            r = math.sin(tr[it])
            q = math.cos(tr[it])
            jr = wr[it] * r * q
            inv_q = 1.0 / math.sqrt(max(q * q, 1e-24))
            inv_qt = 0j
            if not pec:
                qt = np.sqrt(e - r * r)
                if qt.imag < 0:
                    qt = -qt
                inv_qt = 1.0 / qt if abs(qt) > 1e-12 else 1e12 + 0j
            sh_r = _shadow(r, q, sx * sx) if iso else 0.0
            for ia in range(4 * n):
                u, v = r * ca[ia], r * sa[ia]
                b = _slope_coefficients(a_i, c_i, a_s, c_s, s_f, c_f, u, v)
                f_hv = _amplitude(gam, g, 0, b, inv_q, inv_qt, pec)
                f_vh = _amplitude(gam, g, 1, b, inv_q, inv_qt, pec)
                ur, vr = u * c_f + v * s_f, v * c_f - u * s_f
                b = _slope_coefficients(a_s, c_s, a_i, c_i, -s_f, c_f, ur, vr)
                r_hv = _amplitude(gam_r, g, 0, b, inv_q, inv_qt, pec)
                r_vh = _amplitude(gam_r, g, 1, b, inv_q, inv_qt, pec)
                dx, dy = a_i + u, v
                X, Y = cp * dx - sp * dy, sp * dx + cp * dy
                k_i = math.sqrt((X * klx) ** 2 + (Y * kly) ** 2)
                dx, dy = a_s * c_f + u, a_s * s_f + v
                X, Y = cp * dx - sp * dy, sp * dx + cp * dy
                k_s = math.sqrt((X * klx) ** 2 + (Y * kly) ** 2)
                js, cs_w = _position(hx, nx, k_s)
                ji, ci_w = _position(hx, nx, k_i)
                t_si = _look(row_s, js, cs_w) + _look(row_i, ji, ci_w)
                t_c = _look(row_c, js, cs_w) + _look(row_c, ji, ci_w)
                weight = math.exp(t_si) + dec * math.exp(t_c)
                shade = sh_r if iso else _shadow(r, q, s2a[ia])
                weight *= jr * wa[ia] * shade
                acc_hv += weight * (abs(f_hv) ** 2 + abs(r_vh) ** 2)
                acc_vh += weight * (abs(f_vh) ** 2 + abs(r_hv) ** 2)
        out_hv[g] = 0.5 * acc_hv
        out_vh[g] = 0.5 * acc_vh


def integrate(rough, k, table, args, slope, w, w_rim, order, pec):
    """Compiled counterpart of ``iem_crosspol._integrate_numpy`` (same arguments)."""
    from emscatter.solvers.iem.crosspol_terms import gauss_legendre

    ti, ts, si, cs, ss, css, sf, cf, dp, pi_, eps_g, gam, gam_r, Qs, decor = args
    G = si.size
    tau, wtau = gauss_legendre(order)

    def c(x, dtype=None):  # C-contiguous and writeable: one compiled signature for all calls
        if (
            type(x) is np.ndarray
            and (dtype is None or x.dtype == dtype)
            and x.flags.c_contiguous
            and x.flags.writeable
        ):
            return x  # (np.require's answer, without its ~3 µs per array)
        return np.require(x, dtype=dtype, requirements=("C", "W"))

    flat = [c(x, dtype=float) for x in (ti, ts, si, cs, ss, css, sf, cf, dp, pi_)]
    eps_a = c(np.zeros(1, complex) if pec else eps_g, dtype=complex)
    out_hv, out_vh = np.zeros(G), np.zeros(G)
    consts = (
        eps_a, bool(pec), c(gam), c(gam_r), *(c(q, dtype=float) for q in Qs), c(decor, float),
        table.values, float(table.s0), float(table.hs), int(table.ns), float(table.hx),
        int(table.nx), float(k * rough.length), float(k * rough.length_y), float(slope[0]),
        float(slope[1]), float(w), float(w_rim), c(tau), c(wtau),
    )  # fmt: skip

    def part(a: int, b: int) -> None:
        _kernel(*flat, *consts, a, b, out_hv, out_vh)

    threads = min(os.cpu_count() or 1, 8)
    parts = max(1, min(threads, G // 4))
    if parts == 1:
        part(0, G)
    else:
        edges = np.linspace(0, G, parts + 1).astype(np.int64)
        with ThreadPoolExecutor(max_workers=parts) as pool:
            futs = [pool.submit(part, int(a), int(b)) for a, b in zip(edges[:-1], edges[1:],
                                                                      strict=True)]  # fmt: skip
            for f in futs:
                f.result()
    return out_hv, out_vh
