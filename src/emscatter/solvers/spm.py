"""Small-perturbation method (SPM, Rice 1951): first-order bistatic σ⁰ and the
second-order coherent reflectivity.

Geometry, time convention (``exp(-iωt)``, ``Im ε ≥ 0``) and result layout
(``sigma0[pol_s, pol_i]``, 0 = h, 1 = v) follow :mod:`emscatter.conventions`.
Spectrum normalization follows :mod:`emscatter.spectra`: ``w`` integrates to one, the
height PSD is ``σ² w`` and Ulaby's ``W = 2π w``.

First order (Rice 1951; Ulaby, Moore & Fung 1982 vol. II ch. 12, small-perturbation model and
its bistatic form; Tsang, Kong & Ding 2000 vol. I ch. 6)::

    σ⁰_pq = 16π k⁴ σ² |f_pq|² w(k_sx − k_ix, k_sy − k_iy)        (2-D surface, per unit area)
    σ⁰_pq =  8π k³ σ² |f_pq|² w(k_sx − k_ix)                      (1-D profile, per unit length)

with ``f_pq = cosθi cosθs α_pq``, ``φ = φs − φi``, ``r = √(ε − sin²θ)`` (Im ≥ 0)::

    α_hh = (ε−1) cosφ / ((cosθi + r_i)(cosθs + r_s))
    α_vv = (ε−1) (ε sinθi sinθs − r_i r_s cosφ) / ((ε cosθi + r_i)(ε cosθs + r_s))
    α_hv = (ε−1) r_i sinφ / ((ε cosθi + r_i)(cosθs + r_s))      (scattered h, incident v)
    α_vh = (ε−1) r_s sinφ / ((cosθi + r_i)(ε cosθs + r_s))      (scattered v, incident h)

In backscatter (``φ = π``, ``θs = θi``) this is Ulaby's ``σ⁰ = 8k⁴σ²cos⁴θ |α_pp|² W(2k sinθ)``
with ``α_hh = R_h`` and ``α_vv = (ε−1)[sin²θ − ε(1+sin²θ)]/(ε cosθ + r)²``. The perfect
conductor is the ``ε → ∞`` limit: ``f_hh = cosθi cosθs cosφ``,
``f_vv = sinθi sinθs − cosφ``, ``f_hv = cosθs sinφ``, ``f_vh = cosθi sinφ``.
The 1-D profile (2-D problem) is the in-plane case with a signed scattering angle
(``φs = φi + π`` ↦ ``θs → −θs``); its prefactor follows from
``r = 1/(2π cosθi) ∫ σ⁰ dθs`` (see :class:`emscatter.scattering.Scattering`).

Second order (coherent field). The mean reflected amplitude is
``R_p = R_p⁽⁰⁾ + σ² [ ½ ∂²_z-term + ∫ w(k⊥ − k_i⊥) K_p(k⊥) d²k⊥ ]`` (the structure of Tsang,
Kong, Ding & Ao 2001 vol. III ch. 4; Johnson, JOSA A 16 (1999) 2720; Thorsos & Jackson 1989
for 1-D Dirichlet: ``R = −1 + 2k_zσ² ∫ w(k_x − k_ix) k_1z(k_x) dk_x``). Rather than transcribe
a printed kernel, it is derived here: the exact tangential boundary conditions
``n × [E] = n × [H] = 0`` on ``z = h`` (``n ∝ (−h_x, −h_y, 1)``), Taylor-expanded about
``z = 0``, are carried to second order, node by node, in the local
``(k̂⊥, ĥ)`` basis where the flat-interface system is two 2×2 blocks with closed-form
inverses (TE: ``a_h = (S_H − k2z S_E)/(k1z + k2z)``; TM:
``a_v = −(ε k S_E + k2z S_H / k)/(ε k1z + k2z)``; PEC: ``a_h = −S_E``,
``a_v = −k S_E / k1z``). The transverse integral runs over the whole plane, the evanescent
part ``|k⊥| > k`` included (``k1z = i√(k⊥² − k²)``, and the lossy lower medium's
``k2z = √(εk² − k⊥²)``, Im ≥ 0), with Gauss–Legendre on radial segments split at ``k`` and
``Re√ε k`` (cosine-mapped so the square-root branch points are smooth) × Gauss–Legendre in
azimuth. The kernel is checked by the laws it must obey (tests): the first-order amplitudes of
the same solution reproduce the closed-form ``f_pq`` to 1e-10; a perfect conductor conserves
energy, ``r_coh + r_incoh = 1``, to 1e-8 and a lossless dielectric
``r_coh + t_coh + r_incoh + t_incoh = 1`` to 1e-9 (2-D and 1-D). The coherent
*reflectivity* is the consistent second-order expansion ``|R⁽⁰⁾|² + 2 Re(R⁽⁰⁾* R⁽²⁾)``:
with the first-order incoherent reflectivity it conserves energy to ``O((kσ)⁴)`` (exactly at
order ``(kσ)²``). Far outside validity
(``kσ ≳ 0.5`` or rms slope ≫ 1) this expansion can leave ``[0, 1]``; it is then clipped
and ``info["coherent_clipped"]`` (in :func:`bistatic`) counts the clipped points.

Validity (:data:`VALIDITY`, :func:`check_validity`, in :mod:`.spm_validity`): ``kσ ≤ 0.3`` and
rms slope ``≤ 0.3`` (Ulaby, Moore & Fung 1982, vol. II ch. 12; Thorsos & Jackson, JASA 86 (1989)
261), and per incidence angle a first-order scattered fraction ``r₁(θi) ≤ 0.36`` (which fails
near grazing for a conductor in TM).
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from .. import cache
from ..conventions import broadcast_angles, check_angle, check_positive
from ..fresnel import PEC, check_eps, fresnel_cos, is_pec
from ..kernels import dispatch
from ..scattering import Scattering
from ..spectra import GaussianCorrelation, Roughness, check_roughness
from .spm_validity import OPTIONS, VALIDITY, check_validity  # noqa: F401 (re-exported)

__all__ = ["VALIDITY", "bistatic", "coherent_reflectivity", "check_validity"]


_CHUNK = 1 << 15  # geometries per vectorized block (cache-friendly)


# ----------------------------------------------------------------------------- helpers
def _root(eps, s2):
    """√(ε − sin²θ) with Im ≥ 0 (decaying branch)."""
    r = np.sqrt(np.asarray(eps - s2, dtype=complex))
    return np.where(r.imag < 0, -r, r)


_check_roughness = check_roughness


def _check_order(order) -> int:
    if isinstance(order, bool) or order not in (0, 1, 2):
        raise ValueError(f"order must be 0, 1 or 2, got {order!r}")
    return int(order)


def _eps_array(eps):
    eps = check_eps(eps)
    if is_pec(eps):
        return PEC
    return np.asarray(eps, dtype=complex)


def _in_plane_sign(dphi: np.ndarray) -> np.ndarray:
    """+1 where φs − φi ≡ 0, −1 where ≡ π (mod 2π); raise otherwise (1-D profiles)."""
    d = np.mod(dphi, 2 * math.pi)
    fwd = (np.abs(d) < 1e-9) | (np.abs(d - 2 * math.pi) < 1e-9)
    back = np.abs(d - math.pi) < 1e-9
    if not np.all(fwd | back):
        bad = np.asarray(dphi)[~(fwd | back)].ravel()[0]
        raise ValueError(
            "for a 1-D profile (dimension=1, 2-D problem) phi_s must equal phi_i or phi_i + pi "
            f"(the plane of incidence), got phi_s - phi_i = {bad!r} rad"
        )
    return np.where(fwd, 1.0, -1.0)


# ----------------------------------------------------------------------------- first order
def _f_factors(eps, ci, si, cs, ss, cphi, sphi):
    """``f_pq = cosθi cosθs α_pq`` (module docstring); returns (f_hh, f_hv, f_vh, f_vv)."""
    if is_pec(eps):
        z = np.zeros(np.broadcast(ci, cs, cphi).shape)
        fhh = ci * cs * cphi + z
        fvv = si * ss - cphi + z
        fhv = cs * sphi + z
        fvh = ci * sphi + z
        return fhh, fhv, fvh, fvv
    ri = _root(eps, si * si)
    rs = _root(eps, ss * ss)
    em1 = eps - 1.0
    dhi = ci + ri
    dhs = cs + rs
    dvi = eps * ci + ri
    dvs = eps * cs + rs
    cc = ci * cs
    fhh = em1 * cc * cphi / (dhi * dhs)
    fvv = em1 * cc * (eps * si * ss - ri * rs * cphi) / (dvi * dvs)
    fhv = em1 * cc * ri * sphi / (dvi * dhs)
    fvh = em1 * cc * rs * sphi / (dhi * dvs)
    return fhh, fhv, fvh, fvv


def _abs2(z):
    return z.real * z.real + z.imag * z.imag


def _sqrt_upper(x, y):
    """√(x + iy) for y ≥ 0 on the branch Im ≥ 0, in real arithmetic (no cancellation):
    returns (Re, Im)."""
    if np.ndim(y) == 0 and np.min(x) > 0:  # common case (Re ε > 1): no branch selection
        a = np.sqrt(0.5 * (np.sqrt(x * x + y * y) + x))  # np.hypot is ~20× slower
        return a, (0.5 * y) / a
    a = np.sqrt(0.5 * (np.sqrt(x * x + y * y) + np.abs(x)))
    b = 0.5 * y / np.where(a > 0, a, 1.0)
    pos = x >= 0
    return np.where(pos, a, b), np.where(pos, b, a)


def _fresnel_power(eps, theta) -> np.ndarray:
    """``(|R_h|², |R_v|²)`` stacked on axis 0, in real arithmetic (same values as
    :func:`emscatter.fresnel.fresnel`; cheaper on large geometry arrays)."""
    theta = np.asarray(theta, dtype=float)
    if is_pec(eps):
        return np.ones((2, *theta.shape))
    c = np.cos(theta)
    er, ei = np.real(eps), np.imag(eps)
    rr, ri = _sqrt_upper(er - (1.0 - c * c), ei)
    rh = ((c - rr) ** 2 + ri * ri) / ((c + rr) ** 2 + ri * ri)
    rv = ((er * c - rr) ** 2 + (ei * c - ri) ** 2) / ((er * c + rr) ** 2 + (ei * c + ri) ** 2)
    return np.stack(np.broadcast_arrays(rh, rv))


def _f2_factors(eps, ci, si, cs, ss, cphi, s2):
    """``|f_pq|²`` (hh, hv, vh, vv) in real arithmetic — every ``|a/b|²`` as
    ``|a|²/|b|²`` (the hot path of :func:`bistatic`); same values as :func:`_f_factors`.
    ``s2`` is ``sin²φ``: only the square of ``sin φ`` enters (saves a transcendental)."""
    if is_pec(eps):
        fhh = (ci * cs * cphi) ** 2
        fvv = (si * ss - cphi) ** 2
        fhv = cs * cs * s2
        fvh = ci * ci * s2
        return fhh, fhv, fvh, fvv
    er, ei = np.real(eps), np.imag(eps)
    rir, rii = _sqrt_upper(er - si * si, ei)
    rsr, rsi = _sqrt_upper(er - ss * ss, ei)
    cc2 = ((er - 1.0) ** 2 + ei * ei) * (ci * cs) ** 2
    dhi = (ci + rir) ** 2 + rii * rii
    dhs = (cs + rsr) ** 2 + rsi * rsi
    dvi = (er * ci + rir) ** 2 + (ei * ci + rii) ** 2
    dvs = (er * cs + rsr) ** 2 + (ei * cs + rsi) ** 2
    sss = si * ss
    nr = er * sss - (rir * rsr - rii * rsi) * cphi
    ni = ei * sss - (rir * rsi + rii * rsr) * cphi
    fhh = cc2 * cphi * cphi / (dhi * dhs)
    fvv = cc2 * (nr * nr + ni * ni) / (dvi * dvs)
    fhv = cc2 * (rir * rir + rii * rii) * s2 / (dvi * dhs)
    fvh = cc2 * (rsr * rsr + rsi * rsi) * s2 / (dhi * dvs)
    return fhh, fhv, fvh, fvv


def _sigma0_first(rough: Roughness, eps, k, ti, ts, dphi, phi_i, out):
    """Fill ``out`` (2, 2, n) with first-order σ⁰ for flat 1-D inputs."""
    si, ss = np.sin(ti), np.sin(ts)
    ci = np.sqrt(np.maximum(1.0 - si * si, 0.0))  # θ ∈ [0, π/2]: cos ≥ 0, cheaper than cos
    cs = np.sqrt(np.maximum(1.0 - ss * ss, 0.0))
    if rough.dimension == 1:
        sgn = _in_plane_sign(dphi)
        ss = ss * sgn
        cphi, s2 = 1.0, 0.0
        w = rough.spectrum(k * (ss - si))
        pref = 8.0 * math.pi * k**3 * rough.sigma**2
    else:
        cphi = np.cos(dphi)
        s2 = np.maximum(1.0 - cphi * cphi, 0.0)  # only sin²φ enters |f|²
        if rough.is_isotropic:  # w depends on |Δk⊥|² = k²(sin²θs + sin²θi − 2 sinθs sinθi cosφ)
            # (the subclass hook _w2_unit avoids spectrum()'s slow np.hypot on this hot path)
            dk2 = ss * ss + si * si - 2.0 * ss * si * cphi
            q = (k * rough.length) * np.sqrt(np.maximum(dk2, 0.0))
            w = rough.length * rough.length_y * rough._w2_unit(q)
        else:
            phs = dphi + phi_i
            dkx = k * (ss * np.cos(phs) - si * np.cos(phi_i))
            dky = k * (ss * np.sin(phs) - si * np.sin(phi_i))
            w = rough.spectrum(dkx, dky)
        pref = 16.0 * math.pi * k**4 * rough.sigma**2
    fhh, fhv, fvh, fvv = _f2_factors(eps, ci, si, cs, ss, cphi, s2)
    pw = pref * w
    out[0, 0] = pw * fhh
    out[0, 1] = pw * fhv
    out[1, 0] = pw * fvh
    out[1, 1] = pw * fvv
    return out


# ----------------------------------------------------------------------------- second order
@lru_cache(maxsize=64)
def _gl(n: int):
    x, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * (x + 1.0), 0.5 * w


def _segment_nodes(a: float, b: float, n: int, log: bool = False):
    """Nodes/weights on [a, b] with a cosine map that clusters at both ends, so
    ``√(x − a)`` and ``√(b − x)`` branch points become smooth; optional log stretch."""
    t, wt = _gl(n)
    s = 0.5 * (1.0 - np.cos(math.pi * t))
    ds = 0.5 * math.pi * np.sin(math.pi * t) * wt
    if log and a > 0 and b > 8.0 * a:
        lr = math.log(b / a)
        x = a * np.exp(lr * s)
        return x, x * lr * ds
    if log and b < 0 and a < 8.0 * b:  # mirrored: log stretch towards −∞
        x, wx = _segment_nodes(-b, -a, n, log=True)
        return -x[::-1], wx[::-1]
    return a + (b - a) * s, (b - a) * ds


def _spectral_scales(rough: Roughness) -> tuple[float, tuple[float, ...]]:
    """(support radius, interior breakpoints), both in units of 1/ℓ: beyond the support
    ``w`` is negligible (Gaussian: e^(−q²/4) < 1e-18; algebraic tails: relative mass
    ≲ 1e-4 left out); the breakpoints resolve the peak of ``w`` at k_i⊥."""
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
    pts = [k]
    if not is_pec(eps):
        pts.append(float(np.sqrt(eps).real * k))
    return pts


def _nodes_2d(rough, eps, k, kix, kiy, nr, npsi, phi_i=0.0):
    """Polar (origin-centred) nodes over the support of w(k⊥ − k_i⊥): (kx, ky, weight).
    Radial segments split at the branch circles |k⊥| = k, Re√ε k and around |k_i⊥|;
    azimuth restricted to the sector holding the support, split around ψ_i."""
    inv_len = 1.0 / min(rough.length, rough.length_y)
    q, dq = _spectral_scales(rough)
    heavy = not isinstance(rough, GaussianCorrelation)
    kabs = math.hypot(kix, kiy)
    extent = q * inv_len
    lo, hi = max(0.0, kabs - extent), kabs + extent
    pts = _branch_points(k, eps) + [kabs + s * d * inv_len for d in dq for s in (-1, 1)]
    kr, wr = _nodes_on(_breaks(lo, hi, pts), nr, log=heavy)
    psi_i = math.atan2(kiy, kix)
    half = math.asin(extent / kabs) if extent < kabs else math.pi
    angs = [d * inv_len / kabs for d in dq] if kabs > 0 else []
    pb = _breaks(-half, half, [s * a for a in angs for s in (-1, 1)] + [0.0])
    psi, wpsi = _nodes_on(pb, npsi)
    psi = psi + psi_i
    kx = np.multiply.outer(kr, np.cos(psi)).ravel()
    ky = np.multiply.outer(kr, np.sin(psi)).ravel()
    dx, dy = kx - kix, ky - kiy
    if phi_i != 0.0 and not rough.is_isotropic:  # frame with k_i⊥ along x → surface axes
        c, s_ = math.cos(phi_i), math.sin(phi_i)
        dx, dy = c * dx - s_ * dy, s_ * dx + c * dy
    wt = np.multiply.outer(wr * kr, wpsi).ravel() * rough.spectrum(dx, dy)
    return kx, ky, wt


def _nodes_1d(rough, eps, k, kix, nr):
    inv_len = 1.0 / rough.length
    q, dq = _spectral_scales(rough)
    lo, hi = kix - q * inv_len, kix + q * inv_len
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


def _second_order_R(rough, eps, k, theta_i, nr, npsi, transmitted=False, phi_i=None):
    """(R0, R2/σ²) for incident h and v at each θi (flat array), φi = 0 frame; with
    ``transmitted=True`` also the down-going (T0, T2/σ²) amplitudes (energy checks)."""
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
            kx, ky, wt = _nodes_2d(rough, eps, k, kix, kiy, nr, npsi, float(phis[j]))
        else:
            kx, ky, wt = _nodes_1d(rough, eps, k, kix, nr)
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


# ----------------------------------------------------------------------------- public API
def coherent_reflectivity(
    roughness: Roughness,
    eps,
    k: float,
    theta_i,
    *,
    order: int = 2,
    phi_i=0.0,
    n_radial: int = 16,
    n_azimuth: int = 16,
) -> np.ndarray:
    """Coherent (specular) power reflectivity of the rough interface, shape ``(2, *shape)``
    for incident h and v [-].

    Parameters
    ----------
    roughness : :class:`~emscatter.spectra.Roughness` (dimension 1 or 2).
    eps : relative permittivity of the lower medium (``Im ε ≥ 0``, broadcasts with
        ``theta_i``) or ``"pec"``.
    k : free-space wavenumber [rad/m].
    theta_i : incidence angle(s) [rad] in ``[0, π/2]``.
    order : 0 or 1 → flat-interface Fresnel ``|R|²`` (first order has no coherent
        correction); 2 → ``|R⁽⁰⁾|² + 2 Re(R⁽⁰⁾* R⁽²⁾)`` (module docstring), clipped to
        ``[0, 1]`` (the clip acts only far outside SPM validity, e.g. rms slope ≫ 1).
    phi_i : incidence azimuth [rad] (broadcasts with ``theta_i``); matters only for
        anisotropic 2-D roughness.
    n_radial, n_azimuth : Gauss–Legendre nodes per radial / azimuthal segment (16 gives
        ~1e-7 relative accuracy on ``R⁽²⁾`` for Gaussian and exponential spectra).

    Cost: ~2–10 ms per distinct ``theta_i`` (2-D surface), < 2 ms (1-D profile).
    """
    rough = _check_roughness(roughness)
    k = check_positive("k", k, unit="rad/m")
    order = _check_order(order)
    eps_c = _eps_array(eps)
    ti = check_angle("theta_i", theta_i)
    pi_ = check_angle("phi_i", phi_i, low=-1e6, high=1e6)
    shapes = [ti.shape, pi_.shape] + ([] if is_pec(eps_c) else [eps_c.shape])
    try:
        shape = np.broadcast_shapes(*shapes)
    except ValueError:
        raise ValueError(
            f"eps, theta_i{ti.shape} and phi_i{pi_.shape} do not broadcast together"
            + ("" if is_pec(eps_c) else f" (eps{eps_c.shape})")
        ) from None
    if order < 2:
        rh, rv = fresnel_cos(eps_c, np.cos(ti))
        return np.broadcast_to(np.stack([np.abs(rh) ** 2, np.abs(rv) ** 2]), (2, *shape)).copy()
    return _coherent(rough, eps_c, k, ti, shape, n_radial, n_azimuth, pi_)[0]


def _coherent(rough, eps_c, k, ti, shape, n_radial, n_azimuth, phi_i=0.0):
    """(second-order coherent reflectivity (2, *shape), number of clipped points)."""
    clipped = 0
    ti_b = np.broadcast_to(ti, shape).ravel()
    aniso = rough.dimension == 2 and not rough.is_isotropic
    pi_b = np.broadcast_to(phi_i, shape).ravel() if aniso else np.zeros(ti_b.size)
    out = np.empty((2, ti_b.size))
    if is_pec(eps_c):
        groups = [(PEC, np.ones(ti_b.size, bool))]
    else:
        eb = np.broadcast_to(eps_c, shape).ravel()
        groups = [(complex(e), eb == e) for e in np.unique(eb)]
    for e, mask in groups:
        pairs = np.stack([ti_b[mask], np.mod(pi_b[mask], 2 * math.pi)], axis=1)
        uniq, inv = np.unique(pairs, axis=0, return_inverse=True)
        key = {"surface": rough, "eps": e, "k": k, "angles": uniq, "nodes": (n_radial, n_azimuth)}
        r0, r2 = cache.cached(  # the quadrature costs ms per angle: kept on disk (emscatter.cache)
            "spm2-coherent",
            key,
            lambda e=e, u=uniq: _second_order_R(
                rough, e, k, u[:, 0], n_radial, n_azimuth, phi_i=u[:, 1]
            ),
        )
        r2 = r2 * rough.sigma**2
        refl = np.abs(r0) ** 2 + 2.0 * (np.conj(r0) * r2).real
        clipped += int(np.count_nonzero((refl < 0) | (refl > 1)))
        refl = np.clip(refl, 0.0, 1.0)
        out[:, mask] = refl[:, inv.ravel()]
    return out.reshape(2, *shape), clipped


def bistatic(
    roughness: Roughness,
    eps,
    k: float,
    theta_i,
    theta_s,
    phi_s,
    phi_i=0.0,
    *,
    order: int = 2,
    coherent: bool = True,
) -> Scattering:
    """First-order SPM bistatic scattering coefficients σ⁰ (all four polarizations) and the
    coherent reflectivity to ``order``.

    Parameters
    ----------
    roughness : :class:`~emscatter.spectra.Roughness`; ``dimension=2`` (surface, 3-D problem)
        or ``dimension=1`` (profile, 2-D problem: hh and vv only, ``phi_s ∈ {phi_i,
        phi_i + π}``).
    eps : complex relative permittivity (``Im ε ≥ 0``; array broadcasting with the angles)
        or ``"pec"``.
    k : free-space wavenumber [rad/m].
    theta_i, theta_s : incidence / scattering angles [rad] in ``[0, π/2]``.
    phi_s, phi_i : azimuths [rad] (finite; only ``phi_s − phi_i`` and ``phi_i`` enter).
    order : coherent part: 0/1 → Fresnel ``|R|²``; 2 → with the second-order correction.
    coherent : ``False`` skips the coherent part (its quadrature dominates the cost when only
        σ⁰ is needed, e.g. inside the hemispherical integral); ``coherent`` is then NaN and
        ``info["coherent"]`` says so.

    Returns
    -------
    :class:`~emscatter.scattering.Scattering` with ``sigma0`` (2, 2, *shape) — per unit area
    (2-D) or length (1-D), eq. in the module docstring — and ``coherent`` (2, *shape).
    """
    rough = _check_roughness(roughness)
    k = check_positive("k", k, unit="rad/m")
    order = _check_order(order)
    eps_c = _eps_array(eps)
    ti = check_angle("theta_i", theta_i)
    ts = check_angle("theta_s", theta_s)
    big = 1e6
    ps = check_angle("phi_s", phi_s, low=-big, high=big)
    pi_ = check_angle("phi_i", phi_i, low=-big, high=big)
    arrays = {"theta_i": ti, "theta_s": ts, "phi_s": ps, "phi_i": pi_}
    scalar_eps = is_pec(eps_c) or eps_c.ndim == 0
    if not scalar_eps:
        arrays["eps"] = eps_c
    b = broadcast_angles(**arrays)
    ti_b, ts_b, ps_b, pi_b = b[:4]
    eps_b = eps_c if scalar_eps else b[4]
    shape = ti_b.shape
    n = int(np.prod(shape))
    sig = np.empty((2, 2, n))
    fi, fs = ti_b.ravel(), ts_b.ravel()
    dphi = (ps_b - pi_b).ravel()
    fpi = pi_b.ravel()
    fe = eps_c if scalar_eps else eps_b.ravel()
    coh = np.empty((2, n)) if order < 2 else None
    compiled = scalar_eps and dispatch.spm1_sigma0(rough, eps_c, k, fi, fs, dphi, sig)
    for s in range(0, n, _CHUNK):
        sl = slice(s, s + _CHUNK)
        e = fe if scalar_eps else fe[sl]
        if not compiled:  # numpy reference path (emscatter.kernels covers the common cases)
            _sigma0_first(rough, e, k, fi[sl], fs[sl], dphi[sl], fpi[sl], sig[:, :, sl])
        if coh is not None:
            coh[:, sl] = _fresnel_power(e, fi[sl])
    if rough.dimension == 1:
        sig[0, 1] = 0.0
        sig[1, 0] = 0.0
    sig = sig.reshape(2, 2, *shape)
    if not coherent:
        coh, clipped = np.full((2, *shape), np.nan), 0
    elif order < 2:
        coh, clipped = coh.reshape(2, *shape), 0
    else:
        coh, clipped = _coherent(rough, eps_b, k, ti_b, shape, 16, 16, pi_b)
    coh = np.broadcast_to(coh, (2, *shape))
    info = {"validity": check_validity(rough, k), "order": order, "coherent_clipped": clipped}
    if not coherent:
        info["coherent"] = "not computed (coherent=False)"
    return Scattering(
        sigma0=sig,
        coherent=np.array(coh),
        method="spm",
        theta_i=ti_b,
        theta_s=ts_b,
        phi_s=ps_b,
        phi_i=pi_b,
        k=k,
        dimension=rough.dimension,
        info=info,
    )
