"""Small-perturbation method (SPM, Rice 1951): the numerics of the first-order bistatic σ⁰ and
the second-order coherent reflectivity (the public solver is :mod:`.model`; its validity
checks, which evaluate these numerics, are :mod:`.validity`).

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

Validity (:data:`~emscatter.solvers.spm.validity.VALIDITY`, in :mod:`.validity`): ``kσ ≤ 0.3`` and
rms slope ``≤ 0.3`` (Ulaby, Moore & Fung 1982, vol. II ch. 12; Thorsos & Jackson, JASA 86 (1989)
261), and per incidence angle a first-order scattered fraction ``r₁(θi) ≤ 0.36`` (which fails
near grazing for a conductor in TM).
"""

from __future__ import annotations

import math

import numpy as np

from emscatter import cache
from emscatter.conventions import broadcast_angles, check_angle, check_positive
from emscatter.fresnel import PEC, fresnel_cos, is_pec
from emscatter.solvers.spm import compiled as spm_compiled
from emscatter.solvers.spm.second_order import (  # noqa: F401 (re-exported to model)
    _eps_array,
    _first_order_amplitudes,
    _root,
    _second_order_R,
    _spectral_scales,
)
from emscatter.spectra import Roughness, check_roughness

__all__ = ["coherent_reflectivity", "coherent_cutoff", "sigma0_broadcast"]


_CHUNK = 1 << 15  # geometries per vectorized block (cache-friendly)


# ----------------------------------------------------------------------------- helpers
_check_roughness = check_roughness


def _check_order(order) -> int:
    if isinstance(order, bool) or order not in (0, 1, 2):
        raise ValueError(f"order must be 0, 1 or 2, got {order!r}")
    return int(order)


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
    k_max: float | None = None,
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
    n_radial, n_azimuth : Gauss–Legendre nodes per radial / azimuthal segment. 16 gives a
        relative error of ``R⁽²⁾`` of at most ~6e-6 (against 96 nodes; Gaussian and
        exponential spectra, kℓ 0.5–100, θi 0–89°, PEC and ε = 17 + 2i, with and without
        ``k_max``; typically 1e-8–1e-6; tests/test_spm.py).
    k_max : spectral cutoff [rad/m]: the roughness spectrum is taken as zero for
        ``|k⊥ − k_i⊥| > k_max`` (:func:`coherent_cutoff`). Default: the whole spectrum
        (its support). Over a lossy medium the coherent term of an exponential/power-law
        spectrum depends on how far the spectrum extends — the sub-wavelength roughness
        couples through evanescent fields: h converges by ``k_max ≈ 100k–1000k``, TM at
        oblique incidence keeps growing ~1e-3 per decade (validation/spm2_cutoff, where the
        MoM emissivity of exponential profiles agrees with SPM2 at the MoM's own cutoff
        ``π/dx`` to 0.005 and is 0.006–0.021 away from a 2k cutoff); give the surface's own
        inner scale if it is known.

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
    cut = coherent_cutoff(rough, k, k_max)
    return _coherent(rough, eps_c, k, ti, shape, n_radial, n_azimuth, pi_, cut)[0]


def coherent_cutoff(rough: Roughness, k: float, k_max=None) -> float:
    """The cutoff [rad/m] of the second-order coherent term: ``k_max`` if given (and below
    the support), else the spectrum's support radius — the whole spectrum: ``13/ℓ`` for
    the Gaussian (``e^{−q²/4} < 1e-18`` beyond), ``2e4/ℓ`` for algebraic tails (relative
    spectral mass ≲ 1e-4 beyond), ``ℓ`` the shorter correlation length."""
    support = _spectral_scales(rough)[0] / min(rough.length, rough.length_y)
    if k_max is not None:
        return min(check_positive("k_max", k_max, unit="rad/m"), support)
    return support


def _coherent(rough, eps_c, k, ti, shape, n_radial, n_azimuth, phi_i=0.0, k_max=None):
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
        key = {"surface": rough, "eps": e, "k": k, "angles": uniq, "nodes": (n_radial, n_azimuth),
               "k_max": k_max}  # fmt: skip
        r0, r2 = cache.cached(  # the quadrature costs ms per angle: kept on disk (emscatter.cache)
            "spm2-coherent",
            key,
            lambda e=e, u=uniq: _second_order_R(
                rough, e, k, u[:, 0], n_radial, n_azimuth, phi_i=u[:, 1], k_max=k_max
            ),
        )
        r2 = r2 * rough.sigma**2
        refl = np.abs(r0) ** 2 + 2.0 * (np.conj(r0) * r2).real
        clipped += int(np.count_nonzero((refl < 0) | (refl > 1)))
        refl = np.clip(refl, 0.0, 1.0)
        out[:, mask] = refl[:, inv.ravel()]
    return out.reshape(2, *shape), clipped


def sigma0_broadcast(rough, eps, k, ti, ts, phi_s, phi_i=0.0, *, fresnel=False, own_phi=False):
    """First-order σ⁰ for checked inputs (``rough`` a Roughness, ``k`` > 0 [rad/m], ``eps``
    "pec" or complex (array broadcasting with the angles), ``ti``/``ts`` [rad] in [0, π/2]):
    returns ``(sigma0 (2, 2, *shape), (ti, ts, phi_s, phi_i, eps) broadcast, fresnel)`` where
    ``fresnel`` is ``|R|²`` (2, *shape) at θi when asked, else None. The compiled kernel runs
    where it covers the case (:mod:`.compiled`), else the numpy reference in blocks.
    ``own_phi``: ``phi_s``, ``phi_i`` are the caller's own float arrays (the public API's
    checked copies): range-checked here, not copied a second time."""
    eps_c = PEC if is_pec(eps) else np.asarray(eps, dtype=complex)
    big = 1e6
    copy = not own_phi
    ps = check_angle("phi_s", phi_s, low=-big, high=big, copy=copy)
    pi_ = check_angle("phi_i", phi_i, low=-big, high=big, copy=copy)
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
    # φi = +0.0 (the usual call): φs − φi is φs bit for bit (x − 0.0 = x, −0.0 included)
    zero = pi_.ndim == 0 and float(pi_) == 0.0 and math.copysign(1.0, float(pi_)) > 0
    dphi = ps_b.ravel() if zero else (ps_b - pi_b).ravel()
    fe = eps_c if scalar_eps else eps_b.ravel()
    coh = np.empty((2, n)) if fresnel else None
    compiled = scalar_eps and spm_compiled.spm1_sigma0(rough, eps_c, k, fi, fs, dphi, sig)
    fpi = None if compiled else pi_b.ravel()  # (a copy when φi is a number: numpy path only)
    for s in range(0, n, _CHUNK):
        sl = slice(s, s + _CHUNK)
        e = fe if scalar_eps else fe[sl]
        if not compiled:  # numpy reference path (the compiled kernel covers the common cases)
            _sigma0_first(rough, e, k, fi[sl], fs[sl], dphi[sl], fpi[sl], sig[:, :, sl])
        if coh is not None:
            coh[:, sl] = _fresnel_power(e, fi[sl])
    if rough.dimension == 1:
        sig[0, 1] = 0.0
        sig[1, 0] = 0.0
    coh = None if coh is None else coh.reshape(2, *shape)
    return sig.reshape(2, 2, *shape), (ti_b, ts_b, ps_b, pi_b, eps_b), coh
