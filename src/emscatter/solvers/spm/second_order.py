"""Second-order small-perturbation coherent field: the transverse-spectrum quadrature and the
boundary-value kernel behind :func:`emscatter.solvers.spm.coherent_reflectivity` (derivation in
:mod:`emscatter.solvers.spm.model`'s docstring).

Spectral cutoff. The kernel grows like ``|k⊥|`` at large transverse wavenumbers (evanescent
waves), so for algebraic (exponential, power-law) spectra the integral over ``w(k⊥ − k_i⊥)``
converges only logarithmically over a lossy medium: the coherent reflectivity depends on how
far the roughness spectrum extends. :func:`_nodes_2d` / :func:`_nodes_1d` therefore integrate
over the disc ``|k⊥ − k_i⊥| ≤ k_max`` exactly (per-radius azimuth limits on the boundary
annulus, so the cut is an end point of every 1-D rule, never a jump inside one); ``k_max`` is
the explicit cutoff of :func:`emscatter.solvers.spm.model.bistatic` (validation/spm2_cutoff).
"""

from __future__ import annotations

import functools
import math

import numpy as np

from emscatter.fresnel import PEC, check_eps, is_pec
from emscatter.solvers.quadrature import _segment_nodes
from emscatter.spectra import GaussianCorrelation, Roughness


def _root(eps, s2):
    """√(ε − sin²θ) with Im ≥ 0 (decaying branch)."""
    r = np.sqrt(np.asarray(eps - s2, dtype=complex))
    return np.where(r.imag < 0, -r, r)


def _eps_array(eps):
    eps = check_eps(eps)
    if is_pec(eps):
        return PEC
    return np.asarray(eps, dtype=complex)


def _spectral_scales(rough: Roughness) -> tuple[float, tuple[float, ...]]:
    """(support radius, interior breakpoints), both in units of 1/ℓ: beyond the support
    ``w`` is negligible (Gaussian: e^(−q²/4) < 1e-18; algebraic tails: relative mass
    ≲ 1e-4 left out); the breakpoints resolve the peak of ``w`` at k_i⊥. A roughness with a
    ``spectral_support`` attribute (a band-limited spectrum) gives its own."""
    own = getattr(rough, "spectral_support", None)
    if own is not None:
        return own
    if isinstance(rough, GaussianCorrelation):
        return 13.0, (1.5, 4.0)
    return 2.0e4, (1.0, 8.0, 64.0, 512.0)


def _breaks(lo: float, hi: float, pts) -> list[float]:
    """Sorted breakpoints in [lo, hi]; points closer than 1e-9 of the range are merged
    (no degenerate segment whose nodes would sit on a branch point)."""
    tol = 1e-9 * max(hi - lo, abs(hi), abs(lo), 1e-300)
    out = [lo]
    for p in sorted(float(p) for p in pts if lo < p < hi):
        if p - out[-1] > tol and hi - p > tol:
            out.append(p)
    out.append(hi)
    return out


def _nodes_on(br, n, log=False):
    xs, ws = [], []
    for a, b in zip(br[:-1], br[1:], strict=True):
        x, wx = _segment_nodes(a, b, n, log=log)
        xs.append(x)
        ws.append(wx)
    return np.concatenate(xs), np.concatenate(ws)


def _branch_points(k, eps):
    """Radii |k⊥| where the integrand is not smooth: the branch circles ``k`` and
    ``Re√ε k``, and for a metal (``Re ε < −1``) the surface-plasmon pole of the TM kernel,
    ``k_sp = k √(ε/(ε + 1))`` (zero of ``ε k_z1 + k_z2``; Raether 1988, *Surface Plasmons*,
    eq. 2.2), with breaks a few pole widths ``Im k_sp`` on either side so that the peak
    sits between dense nodes (gold at 650 nm: 0.65 % → 1e-5 with 16 nodes per segment)."""
    pts = [k]
    if not is_pec(eps):
        pts.append(float(np.sqrt(eps).real * k))
        e = complex(eps)  # one medium per call (spm groups the permittivities)
        if e.real < -1.0:
            ksp = k * np.sqrt(e / (e + 1.0))
            width = max(abs(ksp.imag), 1e-6 * k)
            pts += [float(ksp.real + f * width) for f in (-4.0, -1.0, 0.0, 1.0, 4.0)]
    return pts


def _nodes_2d(rough, eps, k, kix, kiy, nr, npsi, phi_i=0.0, k_max=None):
    """Polar (origin-centred) nodes over the support of w(k⊥ − k_i⊥): (kx, ky, weight).
    Radial segments split at the branch circles |k⊥| = k, Re√ε k and around |k_i⊥|;
    azimuth restricted to the sector holding the support, split around ψ_i. With a cutoff
    ``k_max`` [rad/m] below the support the domain is the disc ``|k⊥ − k_i⊥| ≤ k_max``:
    full circles inside ``|k⊥| ≤ k_max − |k_i⊥|``, per-radius azimuth limits beyond."""
    inv_len = 1.0 / min(rough.length, rough.length_y)
    q, dq = _spectral_scales(rough)
    heavy = not isinstance(rough, GaussianCorrelation)
    kabs = math.hypot(kix, kiy)
    extent = q * inv_len
    cut = k_max is not None and k_max < extent
    if cut:
        extent = float(k_max)
    lo, hi = max(0.0, kabs - extent), kabs + extent
    pts = _branch_points(k, eps) + [kabs + s * d * inv_len for d in dq for s in (-1, 1)]
    psi_i = math.atan2(kiy, kix)
    angs = [d * inv_len / kabs for d in dq] if kabs > 0 else []
    full_to = (extent - kabs) if cut else hi  # radii below: whole circles (or the sector)
    blocks = []
    if full_to > lo:
        kr, wr = _nodes_on(_breaks(lo, full_to, pts), nr, log=heavy)
        half = math.asin(extent / kabs) if extent < kabs and not cut else math.pi
        pb = _breaks(-half, half, [s * a for a in angs for s in (-1, 1)] + [0.0])
        psi, wpsi = _nodes_on(pb, npsi)
        blocks.append(
            (np.repeat(kr, psi.size), np.tile(psi, kr.size), np.multiply.outer(wr * kr, wpsi))
        )
    if cut:  # the boundary annulus: |ψ| ≤ ψmax(r), the disc's edge an end point in ψ
        kr, wr = _nodes_on(_breaks(max(lo, abs(extent - kabs)), hi, pts), nr, log=heavy)
        with np.errstate(divide="ignore", invalid="ignore"):
            cosm = (kr * kr + kabs * kabs - extent * extent) / (2 * kr * kabs)
        psm = np.arccos(np.clip(np.nan_to_num(cosm, nan=1.0), -1.0, 1.0))
        # the spectrum's peak sits at ψ = 0 near |k⊥| = |k_i⊥| ≈ the inner radius (grazing):
        # the full circle's breakpoints, as fractions of ψmax ≈ π there
        fr = [s * a / math.pi for a in angs if a < math.pi for s in (-1, 1)]
        t, wt_ = _nodes_on(_breaks(-1.0, 1.0, [*fr, 0.0]), npsi)
        blocks.append(
            (
                np.repeat(kr, t.size),
                np.multiply.outer(psm, t).ravel(),
                np.multiply.outer(wr * kr * psm, wt_),
            )
        )
    kr = np.concatenate([b[0] for b in blocks])
    psi = np.concatenate([b[1] for b in blocks]) + psi_i
    weight = np.concatenate([b[2].ravel() for b in blocks])
    kx, ky = kr * np.cos(psi), kr * np.sin(psi)
    dx, dy = kx - kix, ky - kiy
    if phi_i != 0.0 and not rough.is_isotropic:  # frame with k_i⊥ along x → surface axes
        c, s_ = math.cos(phi_i), math.sin(phi_i)
        dx, dy = c * dx - s_ * dy, s_ * dx + c * dy
    return kx, ky, weight * rough.spectrum(dx, dy)


def _nodes_1d(rough, eps, k, kix, nr, k_max=None):
    inv_len = 1.0 / rough.length
    q, dq = _spectral_scales(rough)
    extent = q * inv_len if k_max is None else min(q * inv_len, float(k_max))
    lo, hi = kix - extent, kix + extent
    pts = [s * b for b in _branch_points(k, eps) for s in (-1, 1)]
    pts += [kix + s * d * inv_len for d in dq for s in (-1, 1)]
    heavy = not isinstance(rough, GaussianCorrelation)  # log-stretch the algebraic tails
    kx, w = _nodes_on(_breaks(lo, hi, pts), nr, log=heavy)
    wt = w * rough.spectrum(kx - kix)
    return kx, np.zeros_like(kx), wt


def _kz(k2, kperp2):
    return _root(k2, kperp2)  # √(k² − k⊥²), Im ≥ 0


def _solve_up(eps, k, k1z, k2z, se_c, se_h, sh_c, sh_h):
    """Amplitudes (a_h, a_v, b_h, b_v) of the up-going (medium 1) and down-going (medium 2)
    waves whose tangential jump cancels the source S (components along ĉ = k̂⊥, ĥ = ẑ×ĉ)."""
    if is_pec(eps):
        a_h = -se_h
        a_v = -k * se_c / k1z
        return a_h, a_v, 0.0 * a_h, 0.0 * a_v
    a_h = (sh_c - k2z * se_h) / (k1z + k2z)
    b_h = a_h + se_h
    a_v = -(eps * k * se_c + k2z * sh_h / k) / (eps * k1z + k2z)
    k2 = np.sqrt(eps) * k
    b_v = (k * a_v + sh_h) / k2
    return a_h, a_v, b_h, b_v


def _wave_fields(eps, k, c, K, amp_h, amp_v, qz, medium2):
    """Cartesian E and H̃ (= q × E) of a plane wave with transverse direction c=(cx, cy),
    |k⊥| = K, vertical wavenumber qz and amplitudes on ĥ and v̂ = ĥ × q / k_m."""
    cx, cy = c
    km = np.sqrt(eps) * k if medium2 else k
    hx, hy = -cy, cx
    vx, vy, vz = cx * qz / km, cy * qz / km, -K / km
    ex = amp_h * hx + amp_v * vx
    ey = amp_h * hy + amp_v * vy
    ez = amp_v * vz
    # q × ĥ = −k_m v̂,  q × v̂ = k_m ĥ
    hx_ = -km * amp_h * vx + km * amp_v * hx
    hy_ = -km * amp_h * vy + km * amp_v * hy
    hz_ = -km * amp_h * vz
    return (ex, ey, ez), (hx_, hy_, hz_)


#: One coherent angle counted as this many geometries by the compiled gate
#: (:func:`emscatter.kernels.gate.worth_it`): ~1000–5000 nodes, 2–8 ms in numpy, so a call
#: of ≥ 64 angles (or any call once the kernels are loaded) pays for loading numba.
ANGLE_WEIGHT = 64


def _second_order_R(rough, eps, k, theta_i, nr, npsi, transmitted=False, phi_i=None, k_max=None):
    """(R0, R2/σ²) for incident h and v at each θi (flat array [rad]), φi = 0 frame; with
    ``transmitted=True`` also the down-going (T0, T2/σ²) amplitudes (energy checks).

    The compiled node loop (:mod:`.kernel_coherent`) runs when the numba backend is selected
    and the call is worth it (:data:`ANGLE_WEIGHT`), else the numpy reference
    :func:`_second_order_R_numpy` (the same values to ≤ 1e-13 relative)."""
    theta_i = np.asarray(theta_i, dtype=float).ravel()
    out = _compiled_R(rough, eps, k, theta_i, nr, npsi, phi_i, k_max)
    if out is None:
        return _second_order_R_numpy(rough, eps, k, theta_i, nr, npsi, transmitted, phi_i, k_max)
    return out if transmitted else out[:2]


def _compiled_R(rough, eps, k, theta_i, nr, npsi, phi_i, k_max):
    """``(R0, R2, T0, T2)`` from :mod:`.kernel_coherent`, or None (numpy backend, a small
    call before numba is loaded, no angles)."""
    from emscatter.kernels import backend
    from emscatter.kernels.gate import worth_it

    n = theta_i.size
    if n == 0 or backend() != "numba" or not worth_it(n * ANGLE_WEIGHT):
        return None
    from emscatter.solvers.spm.kernel_coherent import second_order_amplitudes

    pec = is_pec(eps)
    e = PEC if pec else complex(eps)
    phis = np.zeros(n) if phi_i is None else np.broadcast_to(phi_i, theta_i.shape)
    cut = None if k_max is None else float(k_max)
    try:
        hash(rough)
        nodes = _angle_nodes
    except TypeError:  # a roughness that cannot key a cache: nodes built afresh
        nodes = _angle_nodes.__wrapped__
    parts = [
        nodes(rough, e, float(k), float(th), int(nr), int(npsi), float(ph), cut)
        for th, ph in zip(theta_i, phis, strict=True)
    ]  # the nodes' layout differs per angle (breakpoints); memoized across calls
    offsets = np.zeros(n + 1, dtype=np.int64)
    np.cumsum([p[0].size for p in parts], out=offsets[1:])
    kx, ky, wt = (np.concatenate([p[i] for p in parts]) for i in range(3))
    return second_order_amplitudes(theta_i, kx, ky, wt, offsets, float(k), e, pec)


@functools.lru_cache(maxsize=256)
def _angle_nodes(rough, eps, k, theta, nr, npsi, phi, k_max):
    """``(kx, ky, weight)`` of one incidence angle (read-only; :func:`_nodes_2d` /
    :func:`_nodes_1d`), kept for the next call with the same surface, ε, k and angle (an
    emissivity curve recomputed with the result cache off; ~0.3 ms and ≤ 0.2 MB each)."""
    kix = k * math.sin(theta)
    if rough.dimension == 2:
        nodes = _nodes_2d(rough, eps, k, kix, 0.0, nr, npsi, phi, k_max)
    else:
        nodes = _nodes_1d(rough, eps, k, kix, nr, k_max)
    out = tuple(np.ascontiguousarray(a, dtype=float) for a in nodes)
    for a in out:
        a.flags.writeable = False
    return out


def _second_order_R_numpy(
    rough, eps, k, theta_i, nr, npsi, transmitted=False, phi_i=None, k_max=None
):
    """The numpy reference of :func:`_second_order_R` (one vectorized pass over the nodes
    per angle and polarization)."""
    pec = is_pec(eps)
    out0 = np.empty((2, theta_i.size), dtype=complex)
    out2 = np.empty((2, theta_i.size), dtype=complex)
    tr0 = np.zeros((2, theta_i.size), dtype=complex)
    tr2 = np.zeros((2, theta_i.size), dtype=complex)
    k2 = None if pec else eps * k * k
    phis = np.zeros(theta_i.size) if phi_i is None else np.broadcast_to(phi_i, theta_i.shape)
    for j, th in enumerate(theta_i):  # nodes depend on θi; the work per θi is vectorized
        si, ci = math.sin(th), math.cos(th)
        kix, kiy = k * si, 0.0
        K_i = kix
        cvec_i = (1.0, 0.0)  # ĉ_i along x (φi = 0 frame; also fixes ĥ at θi = 0)
        k1zi = k * ci
        if pec:
            rh0, rv0 = -1.0 + 0j, 1.0 + 0j
            k2zi = None
        else:
            k2zi = complex(_kz(k2, K_i * K_i))
            rh0 = (k1zi - k2zi) / (k1zi + k2zi)
            rv0 = (eps * k1zi - k2zi) / (eps * k1zi + k2zi)
        out0[:, j] = rh0, rv0
        if rough.dimension == 2:
            kx, ky, wt = _nodes_2d(rough, eps, k, kix, kiy, nr, npsi, float(phis[j]), k_max)
        else:
            kx, ky, wt = _nodes_1d(rough, eps, k, kix, nr, k_max)
        Kn = np.hypot(kx, ky)
        Kn = np.where(Kn == 0, 1e-300, Kn)
        cxn, cyn = kx / Kn, ky / Kn
        kap_x, kap_y = kx - kix, ky - kiy
        k1zn = _kz(k * k, Kn * Kn)
        k2zn = None if pec else _kz(k2, Kn * Kn)
        for p in (0, 1):
            amp_inc = (1.0, 0.0) if p == 0 else (0.0, 1.0)
            # zeroth-order waves: (E, H, qz, sign in jump)
            waves = []
            Ei, Hi = _wave_fields(1.0, k, cvec_i, K_i, *amp_inc, -k1zi, False)
            waves.append((Ei, Hi, -k1zi, 1.0))
            r0 = rh0 if p == 0 else rv0
            amp_r = (r0, 0.0) if p == 0 else (0.0, r0)
            Er, Hr = _wave_fields(1.0, k, cvec_i, K_i, *amp_r, k1zi, False)
            waves.append((Er, Hr, k1zi, 1.0))
            if not pec:
                if p == 0:
                    amp_t = (1.0 + rh0, 0.0)
                else:
                    amp_t = (0.0, k * (1.0 + rv0) / (np.sqrt(eps) * k))
                Et, Ht = _wave_fields(eps, k, cvec_i, K_i, *amp_t, -k2zi, True)
                waves.append((Et, Ht, -k2zi, -1.0))
            # first-order source at nodes: S1 = ∂z J0_t + i κ J0_z
            se = [0.0, 0.0]
            sh = [0.0, 0.0]
            s2e = [0.0, 0.0]
            s2h = [0.0, 0.0]
            for E, H, qz, sg in waves:
                se[0] = se[0] + sg * (1j * qz * E[0] + 1j * kap_x * E[2])
                se[1] = se[1] + sg * (1j * qz * E[1] + 1j * kap_y * E[2])
                sh[0] = sh[0] + sg * (1j * qz * H[0] + 1j * kap_x * H[2])
                sh[1] = sh[1] + sg * (1j * qz * H[1] + 1j * kap_y * H[2])
                # ½ ∂z² J0_t (coefficient of σ²)
                s2e[0] = s2e[0] - 0.5 * sg * qz * qz * E[0]
                s2e[1] = s2e[1] - 0.5 * sg * qz * qz * E[1]
                s2h[0] = s2h[0] - 0.5 * sg * qz * qz * H[0]
                s2h[1] = s2h[1] - 0.5 * sg * qz * qz * H[1]
            # project on the node basis ĉ = (cx, cy), ĥ = (−cy, cx)
            se_c = se[0] * cxn + se[1] * cyn
            se_h = -se[0] * cyn + se[1] * cxn
            sh_c = sh[0] * cxn + sh[1] * cyn
            sh_h = -sh[0] * cyn + sh[1] * cxn
            a_h, a_v, b_h, b_v = _solve_up(eps, k, k1zn, k2zn, se_c, se_h, sh_c, sh_h)
            # first-order fields (per unit H(κ)), then T = ∂z J1_t + i(k_i⊥ − k⊥) J1_z
            Eu, Hu = _wave_fields(1.0, k, (cxn, cyn), Kn, a_h, a_v, k1zn, False)
            tex = 1j * k1zn * Eu[0] - 1j * kap_x * Eu[2]
            tey = 1j * k1zn * Eu[1] - 1j * kap_y * Eu[2]
            thx = 1j * k1zn * Hu[0] - 1j * kap_x * Hu[2]
            thy = 1j * k1zn * Hu[1] - 1j * kap_y * Hu[2]
            if not pec:
                Ed, Hd = _wave_fields(eps, k, (cxn, cyn), Kn, b_h, b_v, -k2zn, True)
                tex = tex - (-1j * k2zn * Ed[0] - 1j * kap_x * Ed[2])
                tey = tey - (-1j * k2zn * Ed[1] - 1j * kap_y * Ed[2])
                thx = thx - (-1j * k2zn * Hd[0] - 1j * kap_x * Hd[2])
                thy = thy - (-1j * k2zn * Hd[1] - 1j * kap_y * Hd[2])
            S2 = [
                s2e[0] + np.dot(wt, tex),
                s2e[1] + np.dot(wt, tey),
                s2h[0] + np.dot(wt, thx),
                s2h[1] + np.dot(wt, thy),
            ]
            # solve at k_i⊥ in its basis ĉ_i = x̂, ĥ_i = ŷ
            a2h, a2v, b2h, b2v = _solve_up(eps, k, k1zi, k2zi, S2[0], S2[1], S2[2], S2[3])
            out2[p, j] = a2h if p == 0 else a2v
            if not pec:
                tr0[p, j] = amp_t[p]
                tr2[p, j] = b2h if p == 0 else b2v
    if transmitted:
        return out0, out2, tr0, tr2
    return out0, out2


def _first_order_amplitudes(rough, eps, k, theta_i, kx, ky):
    """Up-going first-order amplitudes (a_h, a_v) per unit H(κ) at transverse wavenumbers
    (kx, ky) for incident h and v (φi = 0). Internal; used by the tests to check the closed
    forms of ``f_pq`` (``|a_p|² = 4 k² cos²θi |α|²``)."""
    eps = _eps_array(eps) if not is_pec(eps) else PEC
    pec = is_pec(eps)
    si, ci = math.sin(theta_i), math.cos(theta_i)
    kix, K_i, k1zi = k * si, k * si, k * ci
    cvec_i = (1.0, 0.0)
    kx, ky = np.asarray(kx, float), np.asarray(ky, float)
    Kn = np.hypot(kx, ky)
    cxn, cyn = kx / Kn, ky / Kn
    kap_x, kap_y = kx - kix, ky
    k1zn = _kz(k * k, Kn * Kn)
    if pec:
        rh0, rv0, k2zi, k2zn = -1.0, 1.0, None, None
    else:
        k2zi = complex(_kz(eps * k * k, K_i**2))
        k2zn = _kz(eps * k * k, Kn * Kn)
        rh0 = (k1zi - k2zi) / (k1zi + k2zi)
        rv0 = (eps * k1zi - k2zi) / (eps * k1zi + k2zi)
    res = []
    for p in (0, 1):
        amp_inc = (1.0, 0.0) if p == 0 else (0.0, 1.0)
        r0 = rh0 if p == 0 else rv0
        waves = [
            (*_wave_fields(1.0, k, cvec_i, K_i, *amp_inc, -k1zi, False), -k1zi, 1.0),
            (
                *_wave_fields(
                    1.0, k, cvec_i, K_i, *((r0, 0.0) if p == 0 else (0.0, r0)), k1zi, False
                ),
                k1zi,
                1.0,
            ),
        ]
        if not pec:
            amp_t = (1.0 + rh0, 0.0) if p == 0 else (0.0, (1.0 + rv0) / np.sqrt(eps))
            waves.append((*_wave_fields(eps, k, cvec_i, K_i, *amp_t, -k2zi, True), -k2zi, -1.0))
        se = [0.0, 0.0]
        sh = [0.0, 0.0]
        for E, H, qz, sg in waves:
            se[0] = se[0] + sg * (1j * qz * E[0] + 1j * kap_x * E[2])
            se[1] = se[1] + sg * (1j * qz * E[1] + 1j * kap_y * E[2])
            sh[0] = sh[0] + sg * (1j * qz * H[0] + 1j * kap_x * H[2])
            sh[1] = sh[1] + sg * (1j * qz * H[1] + 1j * kap_y * H[2])
        se_c = se[0] * cxn + se[1] * cyn
        se_h = -se[0] * cyn + se[1] * cxn
        sh_c = sh[0] * cxn + sh[1] * cyn
        sh_h = -sh[0] * cyn + sh[1] * cxn
        a_h, a_v, b_h, b_v = _solve_up(eps, k, k1zn, k2zn, se_c, se_h, sh_c, sh_h)
        res.append((a_h, a_v, b_h, b_v))
    return res
