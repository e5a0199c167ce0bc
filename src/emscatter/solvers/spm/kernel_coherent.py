"""Compiled second-order coherent amplitudes: the node loop of
:func:`emscatter.solvers.spm.second_order._second_order_R` (the mean-field ``R⁽²⁾`` from the
tangential boundary conditions ``n × [E] = n × [H] = 0``; structure of Tsang, Kong, Ding & Ao
2001, *Scattering of Electromagnetic Waves* vol. III ch. 4; Johnson 1999, JOSA A 16, 2720 —
derivation in :mod:`emscatter.solvers.spm.model`).

Same arithmetic, in the same order, as the numpy reference (``_wave_fields``, ``_solve_up``,
the first-order sources ``∂z J₀ + iκ J₀z`` and the second-order source at ``k_i⊥``), one pass
over the quadrature nodes per incidence angle with both incident polarizations at once, so no
complex temporary array is written; only the sum over nodes is in a different order (a running
sum instead of BLAS ``dot``: ≤ 1e-13 relative in tests/test_spm_coherent_kernel.py). The nodes
``(k_x, k_y, weight)`` come from the numpy node builders (``second_order._nodes_2d`` /
``_nodes_1d``), concatenated over angles with ``offsets``.

Units: ``k`` [rad/m], node wavenumbers [rad/m], angles [rad]; ``R⁽²⁾/σ²`` [1/m²].
"""

from __future__ import annotations

import math

import numpy as np

from emscatter.kernels import default_threads
from emscatter.kernels._runtime import inline, jit, run_split

__all__ = ["second_order_amplitudes"]


@inline
def _root(z):
    """√z with Im ≥ 0 (``second_order._root``)."""
    r = np.sqrt(z)
    return -r if r.imag < 0 else r


@inline
def _fields(km, inv_km, cx, cy, K, amp_h, amp_v, qz):
    """``second_order._wave_fields``: Cartesian E and H̃ = q × E of a plane wave with transverse
    direction (cx, cy), |k⊥| = K, vertical wavenumber qz, amplitudes on ĥ and v̂ = ĥ × q / k_m
    (``inv_km = 1/k_m``: a product instead of the reference's division, equal to rounding)."""
    hx, hy = -cy, cx
    r = qz * inv_km
    vx, vy, vz = cx * r, cy * r, -K * inv_km
    ex = amp_h * hx + amp_v * vx
    ey = amp_h * hy + amp_v * vy
    ez = amp_v * vz
    hx_ = -km * amp_h * vx + km * amp_v * hx
    hy_ = -km * amp_h * vy + km * amp_v * hy
    hz_ = -km * amp_h * vz
    return ex, ey, ez, hx_, hy_, hz_


@inline
def _ikb(kap, b):
    """``i κ b``: the node-dependent part of the first-order source."""
    return 1j * kap * b


@jit
def _amplitudes(theta, kx, ky, wt, offsets, k, eps, pec, j0, j1, out0, out2, tr0, tr2):  # noqa: C901
    """Fill ``out0, out2, tr0, tr2`` (2, n) for the angles ``theta[j0:j1]`` (φi = 0 frame);
    the nodes of angle ``j`` are ``offsets[j]:offsets[j + 1]``."""
    k2 = eps * k * k
    sq = np.sqrt(eps)
    km2 = sq * k
    inv_k2 = 1.0 / km2
    inv_k = 1.0 / k
    for j in range(j0, j1):
        si, ci = math.sin(theta[j]), math.cos(theta[j])
        kix = k * si
        K_i = kix
        k1zi = complex(k * ci, 0.0)
        if pec:
            rh0, rv0 = -1.0 + 0j, 1.0 + 0j
            k2zi = 0j
        else:
            k2zi = _root(k2 - complex(K_i * K_i, 0.0))
            rh0 = (k1zi - k2zi) / (k1zi + k2zi)
            rv0 = (eps * k1zi - k2zi) / (eps * k1zi + k2zi)
        out0[0, j] = rh0
        out0[1, j] = rv0
        # node-independent parts of the first-order source (per polarization p):
        # se_x = ax + i κx bz, se_y = ay + i κy bz (E); the same for H̃; s2: the σ² source
        ae = np.zeros((2, 2), dtype=np.complex128)
        ah = np.zeros((2, 2), dtype=np.complex128)
        be = np.zeros(2, dtype=np.complex128)
        bh = np.zeros(2, dtype=np.complex128)
        s2 = np.zeros((2, 4), dtype=np.complex128)
        amp_t = np.zeros(2, dtype=np.complex128)
        nw = 2 if pec else 3
        for p in range(2):
            r0 = rh0 if p == 0 else rv0
            if p == 0:
                amp_t[p] = 1.0 + rh0
            else:
                amp_t[p] = k * (1.0 + rv0) / km2
            for w in range(nw):
                if w == 0:  # incident
                    km, ikm, qz, sg = k + 0j, inv_k + 0j, -k1zi, 1.0
                    a_h, a_v = (1.0 + 0j, 0j) if p == 0 else (0j, 1.0 + 0j)
                elif w == 1:  # reflected
                    km, ikm, qz, sg = k + 0j, inv_k + 0j, k1zi, 1.0
                    a_h, a_v = (r0, 0j) if p == 0 else (0j, r0)
                else:  # transmitted
                    km, ikm, qz, sg = km2, inv_k2, -k2zi, -1.0
                    a_h, a_v = (amp_t[p], 0j) if p == 0 else (0j, amp_t[p])
                ex, ey, ez, hx, hy, hz = _fields(km, ikm, 1.0, 0.0, K_i, a_h, a_v, qz)
                ae[p, 0] += sg * (1j * qz * ex)
                ae[p, 1] += sg * (1j * qz * ey)
                be[p] += sg * ez
                ah[p, 0] += sg * (1j * qz * hx)
                ah[p, 1] += sg * (1j * qz * hy)
                bh[p] += sg * hz
                s2[p, 0] -= 0.5 * sg * qz * qz * ex
                s2[p, 1] -= 0.5 * sg * qz * qz * ey
                s2[p, 2] -= 0.5 * sg * qz * qz * hx
                s2[p, 3] -= 0.5 * sg * qz * qz * hy
        acc = np.zeros((2, 4), dtype=np.complex128)
        for n in range(offsets[j], offsets[j + 1]):
            x, y = kx[n], ky[n]
            Kn = math.hypot(x, y)
            if Kn == 0.0:
                Kn = 1e-300
            cxn, cyn = x / Kn, y / Kn
            kap_x, kap_y = x - kix, y
            d1 = k * k - Kn * Kn
            k1zn = complex(math.sqrt(d1), 0.0) if d1 >= 0.0 else complex(0.0, math.sqrt(-d1))
            if pec:
                k2zn, inv_d1, inv_d2 = 0j, 0j, 1.0 / k1zn
            else:
                k2zn = _root(k2 - complex(Kn * Kn, 0.0))
                inv_d1 = 1.0 / (k1zn + k2zn)
                inv_d2 = 1.0 / (eps * k1zn + k2zn)
            for p in range(2):
                se0 = ae[p, 0] + _ikb(kap_x, be[p])
                se1 = ae[p, 1] + _ikb(kap_y, be[p])
                sh0 = ah[p, 0] + _ikb(kap_x, bh[p])
                sh1 = ah[p, 1] + _ikb(kap_y, bh[p])
                se_c = se0 * cxn + se1 * cyn
                se_h = -se0 * cyn + se1 * cxn
                sh_c = sh0 * cxn + sh1 * cyn
                sh_h = -sh0 * cyn + sh1 * cxn
                if pec:
                    a_h = -se_h
                    a_v = -k * se_c * inv_d2
                    b_h, b_v = 0j, 0j
                else:
                    a_h = (sh_c - k2zn * se_h) * inv_d1
                    b_h = a_h + se_h
                    a_v = -(eps * k * se_c + k2zn * sh_h * inv_k) * inv_d2
                    b_v = (k * a_v + sh_h) * inv_k2
                ex, ey, ez, hx, hy, hz = _fields(k, inv_k, cxn, cyn, Kn, a_h, a_v, k1zn)
                tex = 1j * k1zn * ex - 1j * kap_x * ez
                tey = 1j * k1zn * ey - 1j * kap_y * ez
                thx = 1j * k1zn * hx - 1j * kap_x * hz
                thy = 1j * k1zn * hy - 1j * kap_y * hz
                if not pec:
                    ex, ey, ez, hx, hy, hz = _fields(km2, inv_k2, cxn, cyn, Kn, b_h, b_v, -k2zn)
                    tex = tex - (-1j * k2zn * ex - 1j * kap_x * ez)
                    tey = tey - (-1j * k2zn * ey - 1j * kap_y * ez)
                    thx = thx - (-1j * k2zn * hx - 1j * kap_x * hz)
                    thy = thy - (-1j * k2zn * hy - 1j * kap_y * hz)
                w_ = wt[n]
                acc[p, 0] += w_ * tex
                acc[p, 1] += w_ * tey
                acc[p, 2] += w_ * thx
                acc[p, 3] += w_ * thy
        for p in range(2):  # the second-order wave at k_i⊥ (basis ĉ_i = x̂, ĥ_i = ŷ)
            S0 = s2[p, 0] + acc[p, 0]
            S1 = s2[p, 1] + acc[p, 1]
            S2 = s2[p, 2] + acc[p, 2]
            S3 = s2[p, 3] + acc[p, 3]
            if pec:
                a_h = -S1
                a_v = -k * S0 / k1zi
                b_h, b_v = 0j, 0j
            else:
                a_h = (S2 - k2zi * S1) / (k1zi + k2zi)
                b_h = a_h + S1
                a_v = -(eps * k * S0 + k2zi * S3 / k) / (eps * k1zi + k2zi)
                b_v = (k * a_v + S3) / km2
                tr0[p, j] = amp_t[p]
                tr2[p, j] = b_h if p == 0 else b_v
            out2[p, j] = a_h if p == 0 else a_v


def second_order_amplitudes(theta, kx, ky, wt, offsets, k: float, eps, pec: bool, threads=None):
    """``(R0, R2/σ², T0, T2/σ²)``, each complex (2, n) for incident h, v at the angles
    ``theta`` [rad] (flat), from the concatenated nodes (``offsets``: n + 1 indices); the
    angles are split over ``threads`` (default :func:`emscatter.kernels.default_threads`)."""
    n = theta.size
    out0 = np.empty((2, n), dtype=np.complex128)
    out2 = np.empty((2, n), dtype=np.complex128)
    tr0 = np.zeros((2, n), dtype=np.complex128)
    tr2 = np.zeros((2, n), dtype=np.complex128)
    args = [np.ascontiguousarray(a, dtype=np.float64) for a in (theta, kx, ky, wt)]
    args += [np.ascontiguousarray(offsets, dtype=np.int64), float(k)]
    args += [complex(1.0 if pec else eps), bool(pec)]

    def part(start, stop):
        _amplitudes(*args, start, stop, out0, out2, tr0, tr2)

    run_split(part, n, min(threads or default_threads(), n), 1)  # angles are independent
    return out0, out2, tr0, tr2
