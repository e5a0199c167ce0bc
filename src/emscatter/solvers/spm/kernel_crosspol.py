"""Compiled (numba) backscatter cross-pol of second-order SPM, ``σ⁰⁽²²⁾_hv = σ⁰⁽²²⁾_vh`` [-]:
every angle of a call in one jitted loop.

The same quadrature and the same arithmetic as the numpy reference
:func:`emscatter.solvers.spm.crosspol.backscatter_hv` (equations and sources in
:mod:`emscatter.solvers.spm.crosspol`: Rice 1951; Tsang, Kong, Ding & Ao 2001 vol. III ch. 4;
Johnson, JOSA A 16, 1999), per angle:

* the polar nodes of ``crosspol._polar_nodes`` — radial breaks at ``k``, ``Re√ε k`` and
  ``k sinθ ± (0.5, 1.5, 4)/ℓ``, azimuth breaks around the two spectral peaks, merged as
  ``second_order._breaks`` does, cosine-mapped Gauss–Legendre segments
  (``quadrature._segment_nodes``, log-stretched radially for the exponential spectrum) — built
  here from the unit rule ``(s, ds)`` the caller passes (:func:`unit_rule`), because building
  them in numpy costs ~0.3 ms per angle, more than the kernel itself;
* the azimuth partners ``ψ + π`` and ``−ψ`` (``crosspol._partner``, the same 1e-9 rad test)
  and the same choice between the upper half plane (point and mirror symmetry, the weights
  mirror-even to 1e-12 relative), the whole plane (point symmetry only) or neither: then the
  angle's flag is 0 and the caller runs the numpy reference for it;
* the incident-v kernel ``g_hv(p)`` of ``crosspol._kernel`` (zeroth-order waves, first-order
  amplitudes from ``second_order._solve_up``, the second-order source at ``k_s``, the ``h``
  amplitude of the solve there) in scalar complex arithmetic, and the weighted ladder + crossed
  sums.

Covered: 2-D Gaussian and exponential spectra (any ``ℓ_x, ℓ_y`` and azimuth), one dielectric
``ε``. Agreement with numpy: rounding (``tests/test_spm_crosspol_kernel.py``: ≤ 1e-10 relative).
"""

from __future__ import annotations

import functools
import math

import numpy as np

from emscatter.kernels._runtime import inline, jit, run_split
from emscatter.solvers.quadrature import _gl

__all__ = ["unit_rule", "backscatter_hv", "GAUSSIAN", "EXPONENTIAL"]

GAUSSIAN, EXPONENTIAL = 0, 1
_DISTANCES = (0.5, 1.5, 4.0)  # breaks around the spectral peaks, in units of 1/ℓ
_MAX_RADIAL_SEGMENTS = 15  # 2 branch circles + 12 peak breaks → at most 15 segments
_MAX_AZIMUTH_SEGMENTS = 17  # 16 azimuth breaks → at most 17 segments


@functools.lru_cache(maxsize=16)
def unit_rule(n: int):
    """``(s, ds)`` of ``quadrature._segment_nodes`` on [0, 1]: the cosine map of the
    ``n``-point Gauss–Legendre rule (same expressions, so the same doubles)."""
    t, wt = _gl(n)
    s = 0.5 * (1.0 - np.cos(math.pi * t))
    ds = 0.5 * math.pi * np.sin(math.pi * t) * wt
    s, ds = np.ascontiguousarray(s), np.ascontiguousarray(ds)
    s.flags.writeable = ds.flags.writeable = False
    return s, ds


@inline
def _breaks(lo, hi, pts, npts, out):
    """``second_order._breaks``: sorted points strictly inside (lo, hi), merged within 1e-9 of
    the range, with the ends; written into ``out``, count returned. ``pts[:npts]`` is sorted
    in place."""
    tol = 1e-9 * max(hi - lo, abs(hi), abs(lo), 1e-300)
    for i in range(1, npts):  # insertion sort (≤ 16 points)
        v = pts[i]
        j = i - 1
        while j >= 0 and pts[j] > v:
            pts[j + 1] = pts[j]
            j -= 1
        pts[j + 1] = v
    m = 1
    out[0] = lo
    for i in range(npts):
        p = pts[i]
        if lo < p < hi and p - out[m - 1] > tol and hi - p > tol:
            out[m] = p
            m += 1
    out[m] = hi
    return m + 1


@inline
def _nodes_on(br, nb, s, ds, log, x, w):
    """``second_order._nodes_on`` (``quadrature._segment_nodes`` per segment, ``a ≥ 0`` or
    azimuth: the mirrored log branch never occurs here); count returned."""
    n = s.size
    m = 0
    for seg in range(nb - 1):
        a, b = br[seg], br[seg + 1]
        if log and a > 0 and b > 8.0 * a:
            lr = math.log(b / a)
            for j in range(n):
                xv = a * math.exp(lr * s[j])
                x[m + j] = xv
                w[m + j] = xv * lr * ds[j]
        else:
            for j in range(n):
                x[m + j] = a + (b - a) * s[j]
                w[m + j] = (b - a) * ds[j]
        m += n
    return m


@inline
def _partner(psi, npsi, shift_const, mirror, out):
    """``crosspol._partner`` for the shift ``π`` (``mirror`` False) or ``−2ψ`` (True) on the
    sorted rule ``psi[:npsi]``: index map into ``out``; False where a node has no partner."""
    two_pi = 2.0 * math.pi
    for i in range(npsi):
        shift = -2.0 * psi[i] if mirror else shift_const
        target = np.remainder(psi[i] + shift + math.pi, two_pi) - math.pi
        # np.searchsorted(psi, target) (side="left"), clipped to [1, npsi - 1]
        lo_, hi_ = 0, npsi
        while lo_ < hi_:
            mid = (lo_ + hi_) // 2
            if psi[mid] < target:
                lo_ = mid + 1
            else:
                hi_ = mid
        pos = min(max(lo_, 1), npsi - 1)
        left, right = pos - 1, pos
        idx = left if abs(psi[left] - target) <= abs(psi[right] - target) else right
        gap = abs(np.remainder(psi[idx] - target + math.pi, two_pi) - math.pi)
        if not gap <= 1e-9:
            return False
        out[i] = idx
    return True


@inline
def _remainder_2pi(x):
    """``math.remainder(x, 2π)`` (nearest multiple, ties to even) for ``|x| < 3π`` (the
    multiple, 0 or ±2π, is exact; a quotient rounded onto a tie differs only within a few ulps
    of ±π, which ``_breaks`` drops as the range's ends)."""
    two_pi = 2.0 * math.pi
    q = x / two_pi
    n = math.floor(q)
    f = q - n
    if f > 0.5 or (f == 0.5 and n % 2 != 0):
        n += 1
    return x - n * two_pi


@inline
def _zeroth(zc, amp, qz, sg, km, K_i):
    """Add one zeroth-order wave (``second_order._wave_fields(c = x̂, K_i, amp_h = 0,
    amp_v = amp)``: ``E = amp v̂``, ``H̃ = k_m amp ĥ``, ``ĥ = ŷ``; vertical wavenumber ``qz``,
    sign ``sg`` in the jump) to the node-independent parts of the sources (:func:`_g_hv`)."""
    ex, ez = amp * (qz / km), amp * (-K_i / km)
    hy = km * amp
    zc[0] += sg * 1j * qz * ex  # first-order source ∂z J₀ + iκ₁ J₀z: e_x part,
    zc[1] += sg * 1j * ez  # × κ₁ (both components),
    zc[2] += sg * 1j * qz * hy  # h̃_y part
    zc[3] += -sg * qz * (0.5 * qz * ex)  # second-order h², h∇h source: e_x part,
    zc[4] += -sg * qz * ez  # × κ₂,
    zc[5] += -sg * qz * (0.5 * qz * hy)  # h̃_y part


@inline
def _root(z):
    """√z with Im ≥ 0 (``second_order._root``)."""
    r = np.sqrt(z)
    return -r if r.imag < 0 else r


@inline
def _q2(x, y, cr, sr, lx, ly):
    """``(Kℓ)²`` of the surface-frame wavevector of ``(x, y)`` (``rough.spectrum``'s ``q²``)."""
    X, Y = cr * x - sr * y, sr * x + cr * y
    return (X * lx) ** 2 + (Y * ly) ** 2


@inline
def _weights(kr, wr, nr, cpsi, spsi, wpsi, na, k_s, k_i, cr, sr, lx, ly, spec, wt):
    """``wt[ir, ia] = wr kr wpsi w(k_s − p) w(p − k_i)`` (``w`` = ``rough.spectrum``,
    :mod:`emscatter.spectra`: Gaussian ``ℓxℓy e^{−q²/4}/(4π)``, exponential
    ``ℓxℓy (1 + q²)^{−3/2}/(2π)``), the two spectra's product in one ``exp`` or one root."""
    if spec == GAUSSIAN:
        area = (lx * ly / (4.0 * math.pi)) ** 2
        for ir in range(nr):
            base = area * wr[ir] * kr[ir]
            for ia in range(na):
                px, py = kr[ir] * cpsi[ia], kr[ir] * spsi[ia]
                q2 = _q2(k_s[0] - px, k_s[1] - py, cr, sr, lx, ly)
                q2 += _q2(px - k_i[0], py - k_i[1], cr, sr, lx, ly)
                wt[ir, ia] = base * wpsi[ia] * math.exp(-0.25 * q2)
    else:
        area = (lx * ly / (2.0 * math.pi)) ** 2
        for ir in range(nr):
            base = area * wr[ir] * kr[ir]
            for ia in range(na):
                px, py = kr[ir] * cpsi[ia], kr[ir] * spsi[ia]
                t = 1.0 + _q2(k_s[0] - px, k_s[1] - py, cr, sr, lx, ly)
                t *= 1.0 + _q2(px - k_i[0], py - k_i[1], cr, sr, lx, ly)
                wt[ir, ia] = base * wpsi[ia] / (t * math.sqrt(t))


@inline
def _radial(eps, k, rho):
    """The node-radius parts of :func:`_g_hv`: ``(k_z1, k_z2, 1/(k_z1 + k_z2),
    1/(ε k_z1 + k_z2))`` at ``|p| = rho`` (``second_order._kz``: Im ≥ 0)."""
    d1 = k * k - rho * rho
    k1z = complex(math.sqrt(d1), 0.0) if d1 >= 0.0 else complex(0.0, math.sqrt(-d1))
    k2z = _root(eps * k * k - rho * rho)
    return k1z, k2z, 1.0 / (k1z + k2z), 1.0 / (eps * k1z + k2z)


@inline
def _g_hv(eps, k, inv_k2, k2zs, inv_den, cphi, sphi, ksx, ksy, K_i, zc, rho, rad, cx, cy, px,
          py):  # fmt: skip
    """``crosspol._kernel(..., pols=(1,))[0, 0]`` at the node ``p = (px, py) = rho (cx, cy)``:
    the h amplitude of the second-order wave at ``k_s`` for incident v. ``zc``: the
    zeroth-order waves' parts of the sources (:func:`_zeroth`; their ``E_y``, ``H̃_x``, ``H̃_z``
    vanish); ``rad`` :func:`_radial` at ``rho``; ``inv_k2 = 1/(√ε k)``,
    ``inv_den = 1/(k_z1(k_s) + k_z2(k_s))``. (The numpy kernel takes ``|p|`` and ``p/|p|``
    from ``(px, py)``: the same to rounding.)"""
    k1z, k2z, inv_d1, inv_d2 = rad
    inv_k = 1.0 / k
    k1x, k1y = px - K_i, py  # κ₁ = p − k_i
    k2x, k2y = ksx - px, ksy - py  # κ₂ = k_s − p
    sex, sey, shy = zc[0] + k1x * zc[1], k1y * zc[1], zc[2]
    tex, tey, thx, thy = zc[3] + k2x * zc[4], k2y * zc[4], 0j, zc[5]
    # first-order amplitudes (second_order._solve_up on the node basis ĉ, ĥ = ẑ × ĉ)
    se_c, se_h = sex * cx + sey * cy, -sex * cy + sey * cx
    sh_c, sh_h = shy * cy, shy * cx
    a_h = (sh_c - k2z * se_h) * inv_d1
    b_h = a_h + se_h
    a_v = -(eps * k * se_c + k2z * sh_h * inv_k) * inv_d2
    b_v = (k * a_v + sh_h) * inv_k2
    # their waves (second_order._wave_fields), ĥ = (−c_y, c_x), and their source at k_s
    for medium in range(2):
        if medium == 0:  # up-going, k_m = k
            km, amp_h, amp_v, qz, sg = k + 0j, a_h, a_v, k1z, 1.0
            r, vz = k1z * inv_k, complex(-rho * inv_k, 0.0)
        else:  # down-going, k_m = √ε k
            km, amp_h, amp_v, qz, sg = 1.0 / inv_k2, b_h, b_v, -k2z, -1.0
            r, vz = qz * inv_k2, -rho * inv_k2
        vx, vy = cx * r, cy * r
        ex = -amp_h * cy + amp_v * vx
        ey = amp_h * cx + amp_v * vy
        ez = amp_v * vz
        hx = -km * amp_h * vx - km * amp_v * cy
        hy = -km * amp_h * vy + km * amp_v * cx
        hz = -km * amp_h * vz
        tex = tex + sg * 1j * (qz * ex + k2x * ez)
        tey = tey + sg * 1j * (qz * ey + k2y * ez)
        thx = thx + sg * 1j * (qz * hx + k2x * hz)
        thy = thy + sg * 1j * (qz * hy + k2y * hz)
    te_h = -tex * sphi + tey * cphi
    th_c = thx * cphi + thy * sphi
    return (th_c - k2zs * te_h) * inv_den


@inline
def _node_rules(k, kis0, kis1, ksv0, ksv1, sq_eps, inv_len, extent, log, s_r, ds_r, s_a, ds_a,
                pts, br, kr, wr, psi, wpsi):  # fmt: skip
    """The radial and azimuth node rules of one backscatter angle (``crosspol._polar_nodes``):
    ``(nr, na)``, the nodes and weights written into ``kr, wr`` and ``psi, wpsi``; ``k_i⊥ =
    (kis0, kis1)``, ``k_s⊥ = (ksv0, ksv1)`` [rad/m]. Shared with the resummed cross-pol kernel
    (:mod:`emscatter.solvers.iem.kernels.crosspol_resummed`)."""
    # radial rule
    p0, p1 = math.hypot(kis0, kis1), math.hypot(ksv0, ksv1)
    pts[0], pts[1] = k, sq_eps.real * k
    m = 2
    for c in (p0, p1):
        for d in _DISTANCES:
            pts[m] = c - d * inv_len
            pts[m + 1] = c + d * inv_len
            m += 2
    nb = _breaks(0.0, max(p0, p1) + extent, pts, m, br)
    nr = _nodes_on(br, nb, s_r, ds_r, log, kr, wr)
    # azimuth rule
    m = 0
    for c, ang in ((p0, math.atan2(kis1, kis0)), (p1, math.atan2(ksv1, ksv0))):
        for d in (0.0, 0.5, 1.5, 4.0):
            off = d * inv_len / max(c, inv_len)
            if off < math.pi:
                pts[m] = _remainder_2pi(ang - off)
                pts[m + 1] = _remainder_2pi(ang + off)
                m += 2
    nb = _breaks(-math.pi, math.pi, pts, m, br)
    na = _nodes_on(br, nb, s_a, ds_a, False, psi, wpsi)
    return nr, na


@inline
def _fill_g(g, eps, k, si, ci, sq_eps, inv_k2, cphi, sphi, ksv0, ksv1, zc, kr, nr, cpsi, spsi,
            first, na):  # fmt: skip
    """The second-order kernel ``g_hv`` at the nodes ``(ir < nr, first ≤ ia < na)`` into ``g``,
    after the zeroth-order waves of an incident v wave (``crosspol._zeroth_order_waves``,
    pol = 1) into ``zc``. Shared with the resummed cross-pol kernel."""
    K_i, k1z = k * si, k * ci
    k2z = _root(eps * k * k - K_i * K_i)
    rv = (eps * k1z - k2z) / (eps * k1z + k2z)
    zc[:] = 0j
    _zeroth(zc, 1.0 + 0j, -k1z + 0j, 1.0, k + 0j, K_i)  # incident
    _zeroth(zc, rv, k1z + 0j, 1.0, k + 0j, K_i)  # reflected
    _zeroth(zc, (1.0 + rv) / sq_eps, -k2z, -1.0, sq_eps * k, K_i)  # transmitted
    k2zs = _root(eps * k * k - (k * si) ** 2)
    inv_den = 1.0 / (k * ci + k2zs)
    for ir in range(nr):
        rho = kr[ir]
        rad = _radial(eps, k, rho)
        for ia in range(first, na):
            g[ir, ia] = _g_hv(eps, k, inv_k2, k2zs, inv_den, cphi, sphi, ksv0, ksv1, K_i, zc,
                              rho, rad, cpsi[ia], spsi[ia], rho * cpsi[ia],
                              rho * spsi[ia])  # fmt: skip


@inline
def _rule_constants(spec, lx, ly, eps):
    """The backscatter node rule's constants: ``(log, 1/ℓ_min, extent, √ε, cos Δφ, sin Δφ)``
    — a log-graded radial rule for spectra other than the Gaussian, the radial extent
    (12/ℓ Gaussian, 400/ℓ otherwise), ``Δφ = φs − φi = π`` (as ``sigma0_22`` has it)."""
    inv_len = 1.0 / min(lx, ly)
    extent = (12.0 if spec == GAUSSIAN else 400.0) * inv_len
    return spec != GAUSSIAN, inv_len, extent, np.sqrt(eps), math.cos(math.pi), math.sin(math.pi)


@inline
def _rule_scratch(nr_, na_):
    """Scratch of :func:`_node_rules` and the partners for ``nr_`` radial and ``na_`` azimuth
    nodes per segment: ``(pts, br, kr, wr, psi, wpsi, neg, mir, cos ψ, sin ψ)``."""
    psi = np.empty(_MAX_AZIMUTH_SEGMENTS * na_)
    return (np.empty(16), np.empty(18), np.empty(_MAX_RADIAL_SEGMENTS * nr_),
            np.empty(_MAX_RADIAL_SEGMENTS * nr_), psi, np.empty(psi.size),
            np.empty(psi.size, dtype=np.int64), np.empty(psi.size, dtype=np.int64),
            np.empty(psi.size), np.empty(psi.size))  # fmt: skip


@jit
def _hv_kernel(theta, eps, k, sigma4, lx, ly, cr, sr, spec, s_r, ds_r, s_a, ds_a, start, stop,
               out, flag):  # fmt: skip
    """σ⁰⁽²²⁾_hv into ``out[j]`` for ``theta[start:stop]`` [rad]; ``flag[j]`` 1 where computed,
    0 where the azimuth rule lacks the point symmetry (the caller's numpy fallback)."""
    log, inv_len, extent, sq_eps, cphi, sphi = _rule_constants(spec, lx, ly, eps)
    pts, br, kr, wr, psi, wpsi, neg, mir, cpsi, spsi = _rule_scratch(s_r.size, s_a.size)
    g = np.empty((kr.size, psi.size), dtype=np.complex128)
    wt = np.empty((kr.size, psi.size))
    zc = np.empty(6, dtype=np.complex128)
    inv_k2 = 1.0 / (sq_eps * k)
    for j in range(start, stop):
        a = theta[j]
        si, ci = math.sin(a), math.cos(a)
        kis0, kis1 = k * si, 0.0
        ksv0, ksv1 = k * si * cphi, k * si * sphi
        nr, na = _node_rules(k, kis0, kis1, ksv0, ksv1, sq_eps, inv_len, extent, log, s_r, ds_r,
                             s_a, ds_a, pts, br, kr, wr, psi, wpsi)  # fmt: skip
        flag[j] = 0
        out[j] = 0.0
        if not _partner(psi, na, math.pi, False, neg):
            continue  # (no point symmetry: numpy's sigma0_22 branch)
        has_mirror = _partner(psi, na, 0.0, True, mir)
        for ia in range(na):
            cpsi[ia], spsi[ia] = math.cos(psi[ia]), math.sin(psi[ia])
        half = has_mirror
        _weights(kr, wr, nr, cpsi, spsi, wpsi, na, (ksv0, ksv1), (kis0, kis1), cr, sr, lx, ly,
                 spec, wt)  # fmt: skip
        if half:  # np.allclose(wt, wt[:, mirror], rtol=1e-12, atol=0)
            for ir in range(nr):
                for ia in range(na):
                    b = wt[ir, mir[ia]]
                    if not abs(wt[ir, ia] - b) <= 1e-12 * abs(b):
                        half = False
        first = 0
        if half:  # the upper half plane: g(−p) = −g(ρ, π − ψ), the mirror of −p
            while first < na and not psi[first] > 0.0:
                first += 1
        _fill_g(g, eps, k, si, ci, sq_eps, inv_k2, cphi, sphi, ksv0, ksv1, zc, kr, nr, cpsi, spsi,
                first, na)  # fmt: skip
        val = 0.0
        for ir in range(nr):
            for ia in range(first, na):
                ga = g[ir, ia]
                if half:
                    pos = max(mir[neg[ia]] - first, 0) + first
                    d = ga - g[ir, pos]
                    val += wt[ir, ia] * (ga.real * d.real + ga.imag * d.imag)
                else:
                    d = ga + g[ir, neg[ia]]
                    val += wt[ir, ia] * (ga.real * d.real + ga.imag * d.imag)
        if half:
            val *= 2.0
        out[j] = 4.0 * math.pi * k * k * ci * ci * sigma4 * val
        flag[j] = 1


def backscatter_hv(theta, eps: complex, k: float, sigma: float, length: float, length_y: float,
                   phi_i: float, spectrum: int, n_radial: int, n_azimuth: int,
                   threads: int = 1):  # fmt: skip
    """``(σ⁰⁽²²⁾_hv, computed)`` at the flat angles ``theta`` [rad] (checked by the caller):
    values [-] and a bool mask (False: the caller's numpy reference runs that angle)."""
    theta = np.ascontiguousarray(theta, dtype=np.float64)
    n = theta.size
    out, flag = np.zeros(n), np.zeros(n, dtype=np.int64)
    s_r, ds_r = unit_rule(int(n_radial))
    s_a, ds_a = unit_rule(int(n_azimuth))
    args = (complex(eps), float(k), float(sigma) ** 4, float(length), float(length_y),
            math.cos(phi_i), math.sin(phi_i), int(spectrum), s_r, ds_r, s_a, ds_a)  # fmt: skip

    def part(a: int, b: int) -> None:
        _hv_kernel(theta, *args, a, b, out, flag)

    run_split(part, n, threads, 2)
    return out, flag.astype(bool)
