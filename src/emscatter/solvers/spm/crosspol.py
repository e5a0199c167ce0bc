"""Second-order small-perturbation incoherent scattering (the (2,2) term, fourth order in σ) at
any bistatic geometry: the small-roughness reference for the multiple-scattering
cross-polarization of :mod:`emscatter.solvers.iem.crosspol`.

The perturbation series of the scattered plane-wave amplitudes (Rice 1951; the vector form of
Tsang, Kong, Ding & Ao 2001, *Scattering of Electromagnetic Waves* vol. III, ch. 4, and Johnson,
JOSA A 16, 2720, 1999) is carried to second order with the boundary-value kernel of
:mod:`emscatter.solvers.spm.second_order` (exact tangential conditions ``n × [E] = n × [H] = 0`` on
``z = h``,
Taylor-expanded about ``z = 0``; its closed-form 2×2 solves per transverse wavevector)::

    a⁽²⁾(k_s) = ∫ g₂(k_s, p, k_i) ĥ(k_s − p) ĥ(p − k_i) d²p

with the source at ``k_s`` from (i) the zeroth-order waves (incident, reflected, transmitted;
vertical wavenumber ``q_z``): ``−½ q_z² J₀,t − q_z κ₂ J₀,z`` (the ``h²`` and ``h ∇h`` terms,
``κ₂ = k_s − p``), and (ii) the first-order waves at ``p`` (amplitudes per unit ``ĥ(p − k_i)``):
``i q_z J₁,t + i κ₂ J₁,z``. (In the coherent case ``k_s = k_i`` the ``h∇h`` term integrates to
zero and this is :func:`emscatter.solvers.spm.second_order._second_order_R`; tested.) For Gaussian
heights the
incoherent power of ``a⁽²⁾`` pairs the four spectral amplitudes in two ways — the "ladder"
(``p' = p``) and the "crossed" (``p' = k_s + k_i − p``) pairing::

    σ⁰⁽²²⁾_qp = 4π k² cos²θs σ⁴ ∫ w(k_s − p) w(p − k_i) g₂(p) [g₂*(p) + g₂*(k_s + k_i − p)] d²p

(``w`` the normalized spectrum of :mod:`emscatter.spectra`; the same normalization gives the
first-order ``σ⁰ = 4πk² cos²θs σ² |g₁|² w = 16πk⁴σ²|f|² w`` of :mod:`emscatter.solvers.spm`,
tested). In the
plane of incidence the first-order cross-polarized amplitude vanishes, so there (backscatter
included) this is the whole fourth-order cross-polarized σ⁰; out of the plane the
``2 Re⟨a⁽¹⁾ a⁽³⁾*⟩`` term (a correction to single scattering) is not included.

The integral runs over the whole plane (evanescent ``|p| > k`` included), on polar nodes split
at the branch circles ``|p| = k``, ``Re√ε k`` and around the two spectral peaks ``p = k_i⊥,
k_s⊥`` (cosine-mapped Gauss–Legendre segments,
:func:`emscatter.solvers.spm.second_order._nodes_on`). A
reference, not a fast path: one vectorized evaluation (~10⁴ nodes) per geometry. A perfect
conductor's kernel carries ``1/k_z(p)`` (TM), which makes the integral diverge logarithmically
at the horizon ``|p| = k``; use dielectrics (``eps`` complex) here.
"""

from __future__ import annotations

import math

import numpy as np

from emscatter.conventions import broadcast_angles, check_angle, check_positive
from emscatter.fresnel import check_eps, is_pec
from emscatter.solvers.spm.second_order import _breaks, _kz, _nodes_on, _solve_up, _wave_fields
from emscatter.spectra import GaussianCorrelation, check_roughness

__all__ = ["sigma0_22", "backscatter_hv"]


def _zeroth_order_waves(eps, k, si, ci, pol):
    """(E, H, q_z, sign in the jump) of the incident (``pol`` 0 = h, 1 = v), reflected and
    transmitted waves (transverse direction x̂, φi = 0 frame)."""
    K_i, k1z = k * si, k * ci
    k2z = complex(_kz(eps * k * k, K_i * K_i))
    rh = (k1z - k2z) / (k1z + k2z)
    rv = (eps * k1z - k2z) / (eps * k1z + k2z)
    c = (1.0, 0.0)
    inc = (1.0, 0.0) if pol == 0 else (0.0, 1.0)
    ref = (rh, 0.0) if pol == 0 else (0.0, rv)
    tra = (1.0 + rh, 0.0) if pol == 0 else (0.0, (1.0 + rv) / np.sqrt(eps))
    return [
        (*_wave_fields(1.0, k, c, K_i, *inc, -k1z, False), -k1z, 1.0),
        (*_wave_fields(1.0, k, c, K_i, *ref, k1z, False), k1z, 1.0),
        (*_wave_fields(eps, k, c, K_i, *tra, -k2z, True), -k2z, -1.0),
    ]


def _project(vx, vy, cx, cy):
    """Components along ĉ = (cx, cy) and ĥ = ẑ × ĉ."""
    return vx * cx + vy * cy, -vx * cy + vy * cx


def _first_order(eps, k, si, ci, px, py, pols=(0, 1)):
    """First-order amplitudes per unit ``ĥ(p − k_i)`` at transverse wavevectors ``(px, py)``
    [rad/m] (φi = 0 frame), for the incident polarizations ``pols`` (0 = h, 1 = v): list of
    ``(a_h, a_v, b_h, b_v)`` on the node basis ``ĉ = p/|p|``, ``ĥ = ẑ × ĉ``; and
    ``(ĉ, |p|, k1z, k2z)``."""
    rho = np.hypot(px, py)
    safe = np.where(rho > 0, rho, 1.0)
    cx, cy = np.where(rho > 0, px / safe, 1.0), np.where(rho > 0, py / safe, 0.0)
    k1z, k2z = _kz(k * k, rho * rho), _kz(eps * k * k, rho * rho)
    k1x, k1y = px - k * si, py  # κ₁ = p − k_i
    amps = []
    for pol in pols:
        se, sh = [0.0, 0.0], [0.0, 0.0]
        for E, H, qz, sg in _zeroth_order_waves(eps, k, si, ci, pol):
            for comp, kap in ((0, k1x), (1, k1y)):
                se[comp] = se[comp] + sg * 1j * (qz * E[comp] + kap * E[2])
                sh[comp] = sh[comp] + sg * 1j * (qz * H[comp] + kap * H[2])
        amps.append(_solve_up(eps, k, k1z, k2z, *_project(*se, cx, cy), *_project(*sh, cx, cy)))
    return amps, ((cx, cy), rho, k1z, k2z)


def _kernel(eps, k, si, ci, ss, cs, cphi, sphi, px, py, pols=(0, 1)):
    """``g₂[pol_s, pol_i]`` at transverse wavevectors ``(px, py)`` [rad/m] (φi = 0 frame) for
    the incident polarizations ``pols``: complex array (2, len(pols), N)."""
    ksx, ksy = k * ss * cphi, k * ss * sphi
    amps, (c, rho, k1z, k2z) = _first_order(eps, k, si, ci, px, py, pols)
    k1zs = k * cs
    k2zs = complex(_kz(eps * k * k, (k * ss) ** 2))
    k2x, k2y = ksx - px, ksy - py  # κ₂ = k_s − p
    out = np.empty((2, len(pols), px.size), dtype=complex)
    for j, pol in enumerate(pols):
        te, th = [0.0, 0.0], [0.0, 0.0]
        for E, H, qz, sg in _zeroth_order_waves(eps, k, si, ci, pol):  # h² and h∇h terms
            for comp, kap in ((0, k2x), (1, k2y)):
                te[comp] = te[comp] - sg * qz * (0.5 * qz * E[comp] + kap * E[2])
                th[comp] = th[comp] - sg * qz * (0.5 * qz * H[comp] + kap * H[2])
        a_h, a_v, b_h, b_v = amps[j]
        for (E, H), qz, sg in (
            (_wave_fields(1.0, k, c, rho, a_h, a_v, k1z, False), k1z, 1.0),
            (_wave_fields(eps, k, c, rho, b_h, b_v, -k2z, True), -k2z, -1.0),
        ):
            for comp, kap in ((0, k2x), (1, k2y)):  # first-order waves' source at k_s
                te[comp] = te[comp] + sg * 1j * (qz * E[comp] + kap * E[2])
                th[comp] = th[comp] + sg * 1j * (qz * H[comp] + kap * H[2])
        a2h, a2v, _, _ = _solve_up(eps, k, k1zs, k2zs, *_project(*te, cphi, sphi),
                                   *_project(*th, cphi, sphi))  # fmt: skip
        out[0, j], out[1, j] = a2h, a2v
    return out


def _nodes(rough, eps, k, kis, ksv, n_radial, n_azimuth):
    """Polar nodes (px, py, weight with the polar Jacobian) over the support of
    ``w(k_s − p) w(p − k_i)``."""
    kr, wr, psi, wpsi = _polar_nodes(rough, eps, k, kis, ksv, n_radial, n_azimuth)
    px = np.multiply.outer(kr, np.cos(psi)).ravel()
    py = np.multiply.outer(kr, np.sin(psi)).ravel()
    return px, py, np.multiply.outer(wr * kr, wpsi).ravel()


def _polar_nodes(rough, eps, k, kis, ksv, n_radial, n_azimuth):
    """The radial ``(|p|, weight)`` and azimuthal ``(ψ, weight)`` rules of :func:`_nodes`."""
    inv_len = 1.0 / min(rough.length, rough.length_y)
    gauss = isinstance(rough, GaussianCorrelation)
    extent = (12.0 if gauss else 400.0) * inv_len
    peaks = [math.hypot(*kis), math.hypot(*ksv)]
    pts = [k, float(np.sqrt(eps).real) * k]
    pts += [c + s * d * inv_len for c in peaks for d in (0.5, 1.5, 4.0) for s in (-1, 1)]
    hi = max(peaks) + extent
    kr, wr = _nodes_on(_breaks(0.0, hi, pts), n_radial, log=not gauss)
    angs = [math.atan2(kis[1], kis[0]), math.atan2(ksv[1], ksv[0])]
    apts = []
    for a, c in zip(angs, peaks, strict=True):
        for d in (0.0, 0.5, 1.5, 4.0):
            off = d * inv_len / max(c, inv_len)
            if off < math.pi:
                apts += [a - off, a + off]
    apts = [math.remainder(a, 2 * math.pi) for a in apts]
    psi, wpsi = _nodes_on(_breaks(-math.pi, math.pi, apts), n_azimuth)
    return kr, wr, psi, wpsi


def sigma0_22(roughness, eps, k: float, theta_i, theta_s, phi_s, phi_i=0.0, *,
              n_radial: int = 16, n_azimuth: int = 16, parts: bool = False,
              propagating: bool = False) -> np.ndarray:  # fmt: skip
    """Second-order SPM incoherent σ⁰⁽²²⁾ [-], all four polarizations, shape
    ``(2, 2, *broadcast shape)`` indexed ``[pol_s, pol_i]`` (module docstring).

    ``roughness`` a 2-D Gaussian or exponential surface, ``eps`` a (complex) permittivity
    (dielectrics only: a conductor's kernel is singular at the horizon), ``k`` [rad/m], angles
    [rad]; ``n_radial`` / ``n_azimuth`` Gauss–Legendre nodes per segment."""
    rough = check_roughness(roughness)
    if rough.dimension != 2:
        raise ValueError(f"sigma0_22 needs a 2-D surface (dimension=2), got {rough.dimension}")
    eps = check_eps(eps)
    if is_pec(eps) or np.ndim(eps) != 0:
        raise ValueError(f"eps must be one dielectric permittivity (complex), got {eps!r}")
    eps = complex(eps)
    k = check_positive("k", k, unit="rad/m")
    ti, ts, ps, pi_ = broadcast_angles(
        theta_i=check_angle("theta_i", theta_i),
        theta_s=check_angle("theta_s", theta_s),
        phi_s=np.asarray(phi_s, float),
        phi_i=np.asarray(phi_i, float),
    )
    shape = ti.shape
    out = np.empty((2 if parts else 1, 2, 2, ti.size))
    sigma4 = rough.sigma**4
    for j, (a, b, c, d) in enumerate(
        zip(ti.ravel(), ts.ravel(), ps.ravel(), pi_.ravel(), strict=True)
    ):  # fmt: skip  (a reference: per geometry)
        si, ci, ss, cs = math.sin(a), math.cos(a), math.sin(b), math.cos(b)
        cphi, sphi = math.cos(c - d), math.sin(c - d)
        kis, ksv = (k * si, 0.0), (k * ss * cphi, k * ss * sphi)
        px, py, wt = _nodes(rough, eps, k, kis, ksv, n_radial, n_azimuth)
        cr, sr = math.cos(d), math.sin(d)

        def w(x, y, cr=cr, sr=sr):  # spectrum of the surface-frame wavevector
            return rough.spectrum(cr * x - sr * y, sr * x + cr * y)

        wt = wt * w(ksv[0] - px, ksv[1] - py) * w(px - kis[0], py - kis[1])
        g = _kernel(eps, k, si, ci, ss, cs, cphi, sphi, px, py)
        gp = _kernel(eps, k, si, ci, ss, cs, cphi, sphi, kis[0] + ksv[0] - px,
                     kis[1] + ksv[1] - py)  # fmt: skip
        if propagating:
            qx, qy = kis[0] + ksv[0] - px, kis[1] + ksv[1] - py
            inside = np.hypot(px, py) < k
            wt_l, wt_c = wt * inside, wt * inside * (np.hypot(qx, qy) < k)
        else:
            wt_l = wt_c = wt
        lad, crs = (g * np.conj(g)).real @ wt_l, (g * np.conj(gp)).real @ wt_c
        scale = 4.0 * math.pi * k * k * cs * cs * sigma4
        if parts:
            out[0, :, :, j], out[1, :, :, j] = scale * lad, scale * crs
        else:
            out[0, :, :, j] = scale * (lad + crs)
    return out.reshape(out.shape[0], 2, 2, *shape) if parts else out.reshape(2, 2, *shape)


def _partner(psi, shift: float):
    """Index of the azimuth node at ``ψ + shift`` (mod 2π) for every node ``ψ``, or None when
    the rule is not symmetric under that map (to 1e-9 rad)."""
    target = np.remainder(psi + shift + math.pi, 2.0 * math.pi) - math.pi
    order = np.argsort(psi)
    pos = np.clip(np.searchsorted(psi[order], target), 1, psi.size - 1)
    left, right = order[pos - 1], order[pos]
    idx = np.where(np.abs(psi[left] - target) <= np.abs(psi[right] - target), left, right)
    gap = np.abs(np.remainder(psi[idx] - target + math.pi, 2.0 * math.pi) - math.pi)
    return idx if np.all(gap <= 1e-9) else None


def backscatter_hv(roughness, eps, k: float, theta, phi_i=0.0, *, n_radial: int = 16,
                   n_azimuth: int = 16) -> np.ndarray:  # fmt: skip
    """Backscatter ``σ⁰⁽²²⁾_hv = σ⁰⁽²²⁾_vh`` [-] at incidence angles ``theta`` [rad] (any
    shape; azimuth ``phi_i`` [rad], scalar): the ``[0, 1]`` entry of :func:`sigma0_22` at
    ``θs = θi``, ``φs = φi + π`` on the same nodes, to rounding (tested), at an eighth of the
    kernel work. In backscatter ``k_s⊥ + k_i⊥ = 0``, so the crossed pairing's kernel is the
    ladder's at ``−p`` — a node of the same (point-symmetric) rule, not a second evaluation —
    and reciprocity maps ``g_vh(−p) = −g_hv(p)`` node by node, so only the incident-v kernel
    is evaluated. Where the spectrum is also even in the plane-of-incidence mirror
    (``y → −y``: isotropic, or axes along the plane), ``g_hv`` is odd under it and the
    integrand even: the kernel runs on the upper half plane only. Same inputs as
    :func:`sigma0_22` (a 2-D Gaussian or exponential surface, one dielectric ``eps``)."""
    rough = check_roughness(roughness)
    if rough.dimension != 2:
        raise ValueError(f"backscatter_hv needs a 2-D surface (dimension=2), got {rough.dimension}")
    eps = check_eps(eps)
    if is_pec(eps) or np.ndim(eps) != 0:
        raise ValueError(f"eps must be one dielectric permittivity (complex), got {eps!r}")
    eps = complex(eps)
    k = check_positive("k", k, unit="rad/m")
    th = check_angle("theta", theta)
    d = float(phi_i)
    if not math.isfinite(d):
        raise ValueError(f"phi_i must be a finite angle [rad], got {phi_i!r}")
    uniq, inv = np.unique(th, return_inverse=True)
    from emscatter.solvers.spm.compiled import spm2_backscatter_hv

    out = spm2_backscatter_hv(rough, eps, k, uniq, d, n_radial, n_azimuth)
    if out is None:
        out = _backscatter_hv_numpy(rough, eps, k, uniq, d, n_radial, n_azimuth)
    elif np.isnan(out).any():  # angles whose node rule lacks the point symmetry
        miss = np.isnan(out)
        out[miss] = _backscatter_hv_numpy(rough, eps, k, uniq[miss], d, n_radial, n_azimuth)
    return out[inv.reshape(th.shape)]


def _backscatter_hv_numpy(rough, eps, k, uniq, d, n_radial, n_azimuth):
    """The numpy reference of :func:`backscatter_hv` at the sorted distinct angles ``uniq``
    [rad] (azimuth ``d`` [rad]); the compiled path is :mod:`.kernel_crosspol`."""
    cphi, sphi = math.cos(math.pi), math.sin(math.pi)  # φs − φi = π, as sigma0_22 has it
    cr, sr = math.cos(d), math.sin(d)

    def w(x, y):  # spectrum of the surface-frame wavevector
        return rough.spectrum(cr * x - sr * y, sr * x + cr * y)

    out = np.empty(uniq.size)
    sigma4 = rough.sigma**4
    for j, a in enumerate(uniq):  # (one node rule per angle: its breaks follow sin θ)
        si, ci = math.sin(a), math.cos(a)
        kis, ksv = (k * si, 0.0), (k * si * cphi, k * si * sphi)
        kr, wr, psi, wpsi = _polar_nodes(rough, eps, k, kis, ksv, n_radial, n_azimuth)
        px = np.multiply.outer(kr, np.cos(psi))
        py = np.multiply.outer(kr, np.sin(psi))
        wt = (
            np.multiply.outer(wr * kr, wpsi)
            * w(ksv[0] - px, ksv[1] - py)
            * w(px - kis[0], py - kis[1])
        )
        neg = _partner(psi, math.pi)
        mirror = _partner(psi, -2.0 * psi)  # the node at −ψ
        half = (
            neg is not None
            and mirror is not None
            and np.allclose(wt, wt[:, mirror], rtol=1e-12, atol=0.0)
        )
        if half:  # upper half: g(−p) = −g(ρ, π − ψ), the mirror of −p
            up = np.flatnonzero(psi > 0.0)
            pos = np.searchsorted(up, mirror[neg[up]])
            g = _kernel(eps, k, si, ci, si, ci, cphi, sphi, px[:, up].ravel(), py[:, up].ravel(),
                        pols=(1,))[0, 0].reshape(kr.size, up.size)  # fmt: skip
            val = 2.0 * np.sum(wt[:, up] * (g * np.conj(g - g[:, pos])).real)
        elif neg is not None:  # the whole plane, crossed kernel from the node at −p
            g = _kernel(eps, k, si, ci, si, ci, cphi, sphi, px.ravel(), py.ravel(),
                        pols=(1,))[0, 0].reshape(kr.size, psi.size)  # fmt: skip
            val = np.sum(wt * (g * np.conj(g + g[:, neg])).real)
        else:  # (a rule without the point symmetry: as sigma0_22)
            s = sigma0_22(rough, eps, k, a, a, d + math.pi, d, n_radial=n_radial,
                          n_azimuth=n_azimuth)  # fmt: skip
            out[j] = 0.5 * (s[0, 1] + s[1, 0])
            continue
        out[j] = 4.0 * math.pi * k * k * ci * ci * sigma4 * val
    return out
