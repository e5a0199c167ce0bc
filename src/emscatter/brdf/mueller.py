"""Polarized (Mueller) BRDF tables from the solvers' scattering *amplitudes*.

A :class:`~.table.BrdfTable` keeps power per h/v pair (``polarized``), no phase. Here the
Jones (amplitude) matrix ``J[pol_s, pol_i]`` of a formulation is turned into the Mueller
matrix per (ωi, ωo, λ) with the standard map (Chipman, *Polarized Light and Optical Systems*,
2018, §6.10; Born & Wolf §10.8)::

    M = A (J ⊗ J*) A⁻¹,   A = [[1, 0, 0, 1], [1, 0, 0, −1], [0, 1, 1, 0], [0, i, −i, 0]]

so that ``S = (I, Q, U, V)`` with ``I = |E_x|² + |E_y|²``, ``Q = |E_x|² − |E_y|²``,
``U = 2 Re(E_x E_y*)``, ``V = −2 Im(E_x E_y*)``. A diagonal ``J = diag(r_s, r_p)`` (a flat
mirror, x = s = h, y = p = v) gives the closed form::

    M = ½ [[Rs+Rp, Rs−Rp, 0, 0], [Rs−Rp, Rs+Rp, 0, 0],
           [0, 0, 2 Re(r_s r_p*), 2 Im(r_s r_p*)], [0, 0, −2 Im(r_s r_p*), 2 Re(r_s r_p*)]].

Formulations (the intensity factors are exactly those of the unpolarized solvers, so
``M₀₀`` equals the table's ``values`` and ``½(M₀₀ ± M₀₁ ± M₁₀ ± M₁₁)`` its ``polarized``):

* **GO** (:mod:`emscatter.solvers.kirchhoff.go`): the facet with normal ``n̂ = q/|q|``
  (the half vector) reflects with the local Fresnel coefficients ``R_h(θl)``, ``R_v(θl)``,
  ``cosθl = |q|/2k``; in the facet's s/p basis ``t̂ ∝ k̂_i × k̂_s``, ``d̂ = t̂ × k̂``
  (:mod:`emscatter.solvers.kirchhoff.common`)::

      J_pq = R_h (p̂_s·t̂)(q̂_i·t̂) + R_v (p̂_s·d̂_s)(q̂_i·d̂_i),

  the complex rotation of the facet's Jones matrix ``diag(R_h, R_v)`` into emscatter's h/v
  bases, times ``√(π|q|⁴/q_z⁴ · p(ζ) · S / (4π cosθi cosθo))`` (slope density, shadowing).
  Exact within GO (each direction pair is reflected by one facet orientation).
* **First-order SPM** (:mod:`emscatter.solvers.spm.first_order`): the complex amplitudes
  ``f_pq`` (their relative phases in emscatter's h/v basis are checked against the
  boundary-value solution in the tests) times ``√(16π k⁴ σ² w(Δk⊥) / (4π cosθi cosθo))``:
  the spectrum is common to all four amplitudes, so ``⟨J ⊗ J*⟩ = 16πk⁴σ² w (f ⊗ f*)``.
* **Refused** (:class:`MuellerUnavailable`): physical optics (scalar Kirchhoff integral per
  polarization, as implemented: ``|F_pq|²`` enters as powers, no cross products), the IEM
  (single and multiple scattering terms summed as powers), the second-order SPM incoherent
  term, MoM and the measured-roughness solvers: none of them gives the phase between the
  amplitudes of different polarization pairs in emscatter.

Frames
------
emscatter (this module's ``mueller`` arrays): the Stokes vector of the incident wave is
referred to the basis ``(x, y) = (ĥ_i, v̂_i)`` and the scattered one to ``(ĥ_s, v̂_s)``,
``ĥ = (−sinφ, cosφ, 0)`` (= ``ẑ × k̂/|ẑ × k̂|``), ``v̂ = ĥ × k̂``, with the *propagation*
directions ``k̂_i = −wi``, ``k̂_s = wo`` (:mod:`.frames`). Note ``(ĥ, v̂, k̂)`` is a
*left*-handed triple (``ĥ × v̂ = −k̂``).

Mitsuba 3 (``*_polarized`` variants, ``mi.mueller``): a Stokes vector of light propagating
along ``w`` is referred to ``x = mi.mueller.stokes_basis(w)`` (the first vector of
``coordinate_system(w)``) and ``y = w × x`` (right-handed). A polarized BSDF's ``eval(ctx,
si, wo)`` (``si.wi`` towards the camera = our ``wo``, Mitsuba's ``wo`` towards the light = our
``wi``) maps the Stokes vector of light arriving along ``−wo_mitsuba`` (= our ``k̂_i``) to that
leaving along ``si.wi`` (= our ``k̂_s``), times ``cosθ`` of the light direction.
:func:`to_mitsuba` converts: first ``v̂ → −v̂`` on both sides (``D = diag(1, 1, −1, −1)``,
making the frame ``(ĥ, k̂ × ĥ)`` right-handed), then Mitsuba's
``rotate_mueller_basis`` from ``ĥ`` to ``stokes_basis`` on each side (reimplemented in numpy:
``rotate_stokes_basis(forward, current, target) = rotator(±∠(current, target))``, the sign
from ``forward · (current × target)``). Tested against Mitsuba's own ``roughconductor`` in
``scalar_spectral_polarized`` and its ``mi.mueller`` helpers (``tests/test_brdf_mueller.py``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import cache
from ..fresnel import fresnel_cos, is_pec
from ..solvers.kirchhoff import common as kc
from ..solvers.kirchhoff.go import slope_pdf_factor
from ..solvers.spm.first_order import _f_factors, coherent_cutoff
from ..solvers.spm.second_order import _second_order_R
from ..spectra import check_roughness
from . import frames
from .build import build_table, material_eps
from .table import BrdfTable

__all__ = [
    "MuellerTable",
    "MuellerUnavailable",
    "SUPPORTED",
    "build_mueller_table",
    "jones_to_mueller",
    "mueller_at",
    "coherent_amplitudes",
    "coherent_mueller",
    "go_jones",
    "spm_jones",
    "to_mitsuba",
    "to_frames",
    "stokes_basis",
    "power_pairs",
]

#: Solvers whose amplitudes give a Mueller matrix here.
SUPPORTED = ("go", "spm")

_REFUSED = {
    "po": "physical optics sums |F_pq|² per polarization (scalar Kirchhoff integral), no "
    "cross products between polarization pairs",
    "iem": "the IEM as implemented sums single- and multiple-scattering powers per "
    "polarization pair, no cross products",
}

#: Chipman's Jones→Mueller matrix (module docstring) and its inverse.
A = np.array([[1, 0, 0, 1], [1, 0, 0, -1], [0, 1, 1, 0], [0, 1j, -1j, 0]], dtype=complex)
A_INV = np.linalg.inv(A)
#: emscatter's Stokes vector → Mitsuba's, same x axis ĥ: ``v̂ → −v̂`` (left-handed ``(ĥ, v̂)``
#: → right-handed ``(ĥ, k̂ × ĥ)``: ``diag(1, 1, −1, −1)``) times Mitsuba's opposite sign of
#: ``V`` (``diag(1, 1, 1, −1)``, measured against Mitsuba's ``roughconductor``, tests).
D_MITSUBA = np.diag([1.0, 1.0, -1.0, 1.0])


class MuellerUnavailable(ValueError):
    """The formulation gives no phase between polarization pairs: no Mueller matrix."""


def jones_to_mueller(jones) -> np.ndarray:
    """Mueller matrices ``(4, 4, ...)`` (real) of Jones matrices ``(2, 2, ...)`` (complex,
    ``[out, in]``): ``M = A (J ⊗ J*) A⁻¹`` (module docstring)."""
    j = np.asarray(jones, dtype=complex)
    if j.ndim < 2 or j.shape[:2] != (2, 2):
        raise ValueError(f"jones must have shape (2, 2, ...), got {j.shape}")
    w = np.einsum("ac...,bd...->abcd...", j, np.conj(j)).reshape(4, 4, *j.shape[2:])
    m = np.einsum("ij,jk...,kl->il...", A, w, A_INV)
    return np.ascontiguousarray(m.real)


def power_pairs(mueller) -> np.ndarray:
    """``|J_pq|²`` ``(2, 2, ...)`` ``[pol_s, pol_i]`` (0 = h, 1 = v) from Mueller matrices
    ``(4, 4, ...)`` in an h/v basis: ``½(M₀₀ ± M₀₁ ± M₁₀ ± M₁₁)``."""
    m = np.asarray(mueller, dtype=float)
    a, b, c, d = m[0, 0], m[0, 1], m[1, 0], m[1, 1]
    return 0.5 * np.stack(
        [np.stack([a + b + c + d, a - b + c - d]), np.stack([a + b - c - d, a - b - c + d])]
    )


def _unit(v):
    return v / np.linalg.norm(v, axis=0, keepdims=True)


def _hv(theta, phi, sign_z):
    """Propagation direction ``k̂`` and emscatter's ``ĥ``, ``v̂ = ĥ × k̂``: each ``(3, ...)``."""
    st, ct = np.sin(theta), np.cos(theta)
    k = np.stack([st * np.cos(phi), st * np.sin(phi), sign_z * ct])
    h = np.stack([-np.sin(phi), np.cos(phi), np.zeros_like(phi)])
    return k, h, np.cross(h, k, axis=0)


def _dot(a, b):
    return np.einsum("i...,i...->...", a, b)


def _em_angles(theta_i, phi_i, theta_o, phi_o):
    """Renderer angles → broadcast emscatter ``(θi, φi, θs, φs)`` [rad]."""
    ti, ts, ps, pi_ = frames.to_emscatter(theta_i, phi_i, theta_o, phi_o)
    return ti, pi_, ts, ps


def go_jones(eps, theta_i, phi_i, theta_o, phi_o) -> np.ndarray:
    """The GO facet Jones matrix ``J[pol_s, pol_i]`` ``(2, 2, ...)`` (complex, emscatter's
    h/v bases, no intensity factor) at renderer angles [rad] (module docstring)."""
    return _facet_jones(lambda cos_l: fresnel_cos(eps, cos_l), theta_i, phi_i, theta_o, phi_o)


def _facet_jones(fresnel, theta_i, phi_i, theta_o, phi_o) -> np.ndarray:
    """``J_pq = R_h (p̂_s·t̂)(q̂_i·t̂) + R_v (p̂_s·d̂_s)(q̂_i·d̂_i)`` with ``(R_h, R_v) =
    fresnel(cosθl)`` of the facet bisecting the pair (module docstring)."""
    ti, pi_, ts, ps = _em_angles(theta_i, phi_i, theta_o, phi_o)
    ki, hi, vi = _hv(ti, pi_, -1.0)
    ks, hs, vs = _hv(ts, ps, 1.0)
    tau = np.cross(ki, ks, axis=0)
    t2 = _dot(tau, tau)
    degenerate = t2 < 1e-28  # exact backscatter: t̂ = ĥ_i (kirchhoff.common)
    t = np.where(degenerate, hi, tau / np.sqrt(np.where(degenerate, 1.0, t2)))
    di, ds = np.cross(t, ki, axis=0), np.cross(t, ks, axis=0)
    q = ks - ki
    cos_l = np.minimum(0.5 * np.sqrt(_dot(q, q)), 1.0)
    rh, rv = fresnel(cos_l)
    out_b, in_b = (hs, vs), (hi, vi)
    j = np.empty((2, 2, *cos_l.shape), dtype=complex)
    for s in range(2):
        for i in range(2):
            p, r = out_b[s], in_b[i]
            j[s, i] = rh * _dot(p, t) * _dot(r, t) + rv * _dot(p, ds) * _dot(r, di)
    return j


def spm_jones(eps, theta_i, phi_i, theta_o, phi_o) -> np.ndarray:
    """First-order SPM amplitudes ``f_pq`` as ``J[pol_s, pol_i]`` ``(2, 2, ...)`` (complex,
    emscatter's h/v bases; :func:`emscatter.solvers.spm.first_order._f_factors`)."""
    ti, pi_, ts, ps = _em_angles(theta_i, phi_i, theta_o, phi_o)
    d = ps - pi_
    e = eps if is_pec(eps) else np.complex128(eps)
    fhh, fhv, fvh, fvv = _f_factors(
        e, np.cos(ti), np.sin(ti), np.cos(ts), np.sin(ts), np.cos(d), np.sin(d)
    )
    return np.stack([np.stack([fhh, fhv]), np.stack([fvh, fvv])]).astype(complex)


def coherent_amplitudes(surface, material, wavelength, theta_i, powers, *, method, order=2):
    """Complex coherent (mean-field) reflection amplitudes ``(a_h, a_v)`` ``(2, n)`` of the
    rough interface at incidence angles ``theta_i`` [rad] (renderer = emscatter θi), for
    ``powers`` ``(2, n)`` the coherent power reflectivities (h, v) the table holds
    (``coherent_polarized``): ``|a_p|² = powers_p`` and ``arg a_p = arg R_p`` with

    * ``R_p = R_p⁽⁰⁾ + σ² R_p⁽²⁾`` for the second-order SPM (``method="spm"``, ``order=2``;
      :mod:`emscatter.solvers.spm.second_order`, the structure of Tsang, Kong, Ding & Ao 2001
      vol. III ch. 4): the mean field's phase to the order of its power;
    * the flat-interface Fresnel ``R_p`` otherwise (SPM ``order`` 0/1, and any Kirchhoff-type
      attenuation ``exp(−2(kσ cosθ)²)``, which is real, positive and the same for h and v).

    An isotropic surface's mean field keeps h and v apart (no cross-polarized mean field),
    so the coherent Jones matrix is ``diag(a_h, a_v)`` in the s/p = h/v frames."""
    rough = check_roughness(surface, "surface")
    lam = float(wavelength)
    k = 2 * math.pi / lam
    eps = material_eps(material, lam)
    ti = np.asarray(theta_i, float).reshape(-1)
    if method == "spm" and order == 2:
        r = _spm_mean_field(rough, eps, k, ti)
    else:
        r = np.stack(fresnel_cos(eps, np.cos(ti))).astype(complex)
    mag = np.abs(r)
    phase = np.where(mag > 0, r / np.where(mag > 0, mag, 1.0), 1.0)
    p = np.clip(np.asarray(powers, float).reshape(2, -1), 0.0, None)
    return np.sqrt(p) * phase


def _spm_mean_field(rough, eps, k, ti) -> np.ndarray:
    """``R⁽⁰⁾ + σ² R⁽²⁾`` ``(2, n)`` (h, v), through the solver's disk cache (same key as
    :func:`emscatter.solvers.spm.first_order._coherent`, so a table build already paid)."""
    cut = coherent_cutoff(rough, k, None)
    e = eps if is_pec(eps) else complex(eps)
    uniq, inv = np.unique(np.stack([ti, np.zeros_like(ti)], axis=1), axis=0, return_inverse=True)
    key = {"surface": rough, "eps": e, "k": k, "angles": uniq, "nodes": (16, 16), "k_max": cut}
    r0, r2 = cache.cached(
        "spm2-coherent",
        key,
        lambda: _second_order_R(rough, e, k, uniq[:, 0], 16, 16, phi_i=uniq[:, 1], k_max=cut),
    )
    return (r0 + rough.sigma**2 * r2)[:, inv.ravel()]


def coherent_mueller(amplitudes, theta_i) -> np.ndarray:
    """Mueller matrices ``(4, 4, n)`` of the coherent (delta) lobe in emscatter's h/v frames
    at the mirror pair (renderer ``(θi, 0) → (θi, π)``), from the complex amplitudes
    ``(a_h, a_v)`` (:func:`coherent_amplitudes`): the facet Jones matrix of the flat mirror
    (:func:`go_jones`'s projection with ``n̂ = ẑ``) mapped by :func:`jones_to_mueller`; in
    Mitsuba's frames it is ``mi.mueller.specular_reflection`` times the attenuation (tests).
    Unitless (a reflectance, not per sr)."""
    a = np.asarray(amplitudes, complex).reshape(2, -1)
    ti = np.asarray(theta_i, float).reshape(-1)
    jones = _facet_jones(lambda cos_l: (a[0], a[1]), ti, 0.0, ti, math.pi)
    return jones_to_mueller(jones)


def _go_intensity(rough, eps, k, ti, pi_, ts, ps, shadowing, slope_variance, k_max):
    """``π|q|⁴/q_z⁴ p(ζ) S`` (:mod:`emscatter.solvers.kirchhoff.go`) at emscatter angles."""
    sx, sy = kc.slope_variances(rough, k_max, slope_variance, k=k)
    mode = kc.check_shadowing(shadowing)
    g = kc.geometry(ti, ts, ps, pi_, eps, 2)
    loc = g.chunk(signed_azimuth=True)
    val = slope_pdf_factor(loc, sx, sy, 2)
    if mode is not None:
        val = val * kc.shadowing_factor(loc, sx, sy, mode)
    return np.asarray(val).reshape(g.shape)


def mueller_at(
    surface, material, wavelength, theta_i, phi_i, theta_o, phi_o, *, method, **options
) -> np.ndarray:
    """Mueller BRDF ``(4, 4, ...)`` [1/sr] at renderer angles [rad] (arrays broadcast),
    in emscatter's h/v frames (module docstring); ``M[0, 0]`` is the unpolarized ``f_r``.

    ``method``: ``"go"`` (options ``shadowing``, ``slope_variance``, ``k_max`` as the solver)
    or ``"spm"`` (first order); others raise :class:`MuellerUnavailable`."""
    rough = check_roughness(surface, "surface")
    if rough.dimension != 2:
        raise ValueError("a Mueller BRDF needs a 2-D surface (dimension=2), got a 1-D profile")
    name = _check_method(method)
    lam = float(wavelength)
    if not (math.isfinite(lam) and lam > 0):
        raise ValueError(f"wavelength must be a positive finite number [m], got {wavelength!r}")
    k = 2 * math.pi / lam
    eps = material_eps(material, lam)
    ti, pi_, ts, ps = (np.asarray(a, float) for a in _em_angles(theta_i, phi_i, theta_o, phi_o))
    ti, pi_, ts, ps = np.broadcast_arrays(ti, pi_, ts, ps)
    norm = 1.0 / (4 * math.pi * np.cos(ti) * np.cos(ts))
    if name == "go":
        allowed = {"shadowing", "slope_variance", "k_max", "threads"}
        _check_options(name, options, allowed)
        inten = _go_intensity(
            rough, eps, k, ti, pi_, ts, ps, options.get("shadowing", True),
            options.get("slope_variance"), options.get("k_max"),
        )  # fmt: skip
        jones = go_jones(eps, theta_i, phi_i, theta_o, phi_o)
    else:
        _check_options(name, options, {"order"})
        dkx = k * (np.sin(ts) * np.cos(ps) - np.sin(ti) * np.cos(pi_))
        dky = k * (np.sin(ts) * np.sin(ps) - np.sin(ti) * np.sin(pi_))
        inten = 16 * math.pi * k**4 * rough.sigma**2 * rough.spectrum(dkx, dky)
        jones = spm_jones(eps, theta_i, phi_i, theta_o, phi_o)
    m = jones_to_mueller(np.broadcast_to(jones, (2, 2, *ti.shape))) * (inten * norm)
    if not np.all(np.isfinite(m)):
        raise ValueError(f"Mueller matrix of {name!r} holds NaN/inf at λ = {lam:.6g} m")
    return m


def _check_method(method) -> str:
    name = str(method).lower() if isinstance(method, str) else method
    if name in SUPPORTED:
        return name
    why = _REFUSED.get(name, "its amplitudes carry no phase between polarization pairs here")
    raise MuellerUnavailable(
        f"method={method!r} gives no Mueller matrix: {why}. Mueller tables are available for "
        f"method in {SUPPORTED} (give one explicitly; 'auto' is resolved per wavelength and "
        "must land on one of them)"
    )


def _check_options(name, options, allowed) -> None:
    bad = sorted(set(options) - set(allowed))
    if bad:
        raise ValueError(
            f"option(s) {bad} not accepted by the {name!r} Mueller matrix; allowed: "
            f"{sorted(allowed)}"
        )


@dataclass(frozen=True, eq=False)
class MuellerTable:
    """A :class:`~.table.BrdfTable` (``values``, ``polarized``, built by
    :func:`~.build.build_table`) with its Mueller matrices on the same nodes.

    ``mueller``: ``(n_wl, 4, 4, *grid)`` [1/sr] in emscatter's h/v frames (module
    docstring); the energy remedy's reciprocal scale ``s(ωi) s(ωo)`` of the table is applied
    to it as to ``values``, so ``mueller[:, 0, 0] == table.values``.

    ``coherent``: ``(n_wl, 4, 4, n_ti)`` [-] the delta lobe's Mueller matrix at the mirror
    pair of each θi node (:func:`coherent_mueller`, emscatter's h/v frames), with
    ``coherent[:, 0, 0] == table.coherent`` and ``M₀₀ ± M₀₁`` the table's
    ``coherent_polarized``; None when the table has no delta lobe (GO) or is anisotropic."""

    table: BrdfTable
    mueller: np.ndarray
    coherent: np.ndarray | None = None

    def node_angles(self) -> tuple[np.ndarray, ...]:
        """Renderer angles ``(θi, φi, θo, φo)`` [rad] of every node, each of the grid shape
        (isotropic tables: ``φi = 0``, ``φo = Δφ``)."""
        t = self.table
        if t.isotropic:
            ti, to, po = np.meshgrid(t.theta_i, t.theta_o, t.phi_d, indexing="ij")
            return ti, np.zeros_like(ti), to, po
        return tuple(np.meshgrid(t.theta_i, t.phi_i, t.theta_o, t.phi_o, indexing="ij"))

    def polarized_powers(self) -> np.ndarray:
        """``(n_wl, 2, 2, *grid)``: the |J_pq|² entries (compare ``table.polarized``, whose
        layout is ``(2, 2, n_wl, *grid)``)."""
        return np.moveaxis(power_pairs(np.moveaxis(self.mueller, 0, 2)), 2, 0)

    def to_mitsuba(self) -> np.ndarray:
        """``mueller`` in Mitsuba's Stokes frames (:func:`to_mitsuba`), same shape."""
        return np.stack([to_mitsuba(m, *self.node_angles()) for m in self.mueller])


def build_mueller_table(
    surface,
    material,
    wavelengths,
    *,
    method: str,
    resolution=None,
    theta=None,
    phi=None,
    anisotropic=None,
    energy: str = "rescale",
    out_of_range: str = "warn",
    **options,
) -> MuellerTable:
    """A polarized table: :func:`~.build.build_table` (``polarized=True``, same arguments)
    and the Mueller matrix at every node (:func:`mueller_at`), scaled by the table's energy
    remedy. ``method`` must be one of :data:`SUPPORTED` (or ``"auto"`` resolving to them at
    every wavelength); otherwise :class:`MuellerUnavailable` before any work."""
    if method != "auto":
        _check_method(method)
    table = build_table(
        surface, material, wavelengths, method=method, resolution=resolution, theta=theta,
        phi=phi, anisotropic=anisotropic, polarized=True, energy=energy,
        out_of_range=out_of_range, **options,
    )  # fmt: skip
    per_wl = table.metadata.get("per_wavelength", [])
    mt = MuellerTable(table, np.empty((table.wavelengths.size, 4, 4, *table.values.shape[1:])))
    angles = mt.node_angles()
    energy_meta = table.metadata.get("energy", {})
    scales = energy_meta.get("scale") if energy_meta.get("remedy_applied") else None
    out = np.empty_like(mt.mueller)
    for j, lam in enumerate(table.wavelengths):
        name = per_wl[j]["solver"] if j < len(per_wl) else method
        m = mueller_at(surface, material, float(lam), *angles, method=_check_method(name),
                       **options)  # fmt: skip
        if scales is not None:
            s = np.asarray(scales[j])
            if table.isotropic:
                fac = s[:, None, None] * s[None, :, None]
            else:
                fac = (s[:, None] * s[None, :]).reshape(table.values.shape[1:])
            m = m * fac
        out[j] = m
    out.setflags(write=False)
    return MuellerTable(table, out, _coherent_part(table, surface, material, method, options))


def _coherent_part(table, surface, material, method, options):
    """:attr:`MuellerTable.coherent` of a built table (None: no delta lobe, or anisotropic)."""
    cp = np.asarray(table.coherent_polarized, float)  # (2, n_wl, n_ti[, n_pi])
    if not table.isotropic or not np.any(cp > 0):
        return None
    per_wl = table.metadata.get("per_wavelength", [])
    out = np.empty((table.wavelengths.size, 4, 4, table.theta_i.size))
    for j, lam in enumerate(table.wavelengths):
        name = per_wl[j]["solver"] if j < len(per_wl) else method
        amp = coherent_amplitudes(
            surface, material, float(lam), table.theta_i, cp[:, j], method=name,
            order=options.get("order", 2),
        )  # fmt: skip
        out[j] = coherent_mueller(amp, table.theta_i)
    out.setflags(write=False)
    return out


# ------------------------------------------------------------------ Mitsuba's frames
def stokes_basis(w) -> np.ndarray:
    """Mitsuba's ``mi.mueller.stokes_basis(w)``: the first vector of
    ``coordinate_system(w)`` (Duff et al. 2017), ``w`` of shape ``(3, ...)``."""
    x, y, z = w
    sign = np.where(z >= 0, 1.0, -1.0)
    a = -1.0 / (sign + z)
    b = x * y * a
    return np.stack([x * x * a * sign + 1.0, b * sign, -x * sign])


def _rotator(theta) -> np.ndarray:
    c, s = np.cos(2 * theta), np.sin(2 * theta)
    one, zero = np.ones_like(c), np.zeros_like(c)
    return np.stack(
        [
            np.stack([one, zero, zero, zero]),
            np.stack([zero, c, s, zero]),
            np.stack([zero, -s, c, zero]),
            np.stack([zero, zero, zero, one]),
        ]
    )


def _rotate_stokes_basis(forward, current, target) -> np.ndarray:
    """Mitsuba's ``rotate_stokes_basis``: ``(4, 4, ...)``."""
    cu, ta = _unit(current), _unit(target)
    ang = np.arccos(np.clip(_dot(cu, ta), -1.0, 1.0))
    ang = np.where(_dot(forward, np.cross(cu, ta, axis=0)) < 0, -ang, ang)
    return _rotator(ang)


def to_mitsuba(mueller, theta_i, phi_i, theta_o, phi_o) -> np.ndarray:
    """Mueller matrices ``(4, 4, ...)`` from emscatter's h/v frames to Mitsuba's Stokes
    frames (module docstring) at renderer angles [rad]: the matrix a Mitsuba polarized BSDF
    returns from ``eval`` divided by the light direction's ``cosθ``."""
    return to_frames(mueller, theta_i, phi_i, theta_o, phi_o)


def to_frames(mueller, theta_i, phi_i, theta_o, phi_o, x_in=None, x_out=None) -> np.ndarray:
    """Mueller matrices ``(4, 4, ...)`` from emscatter's h/v frames to right-handed Stokes
    frames (Mitsuba's convention, ``y = k̂ × x``) whose x axes are ``x_in`` (incident wave,
    propagating along ``−wi``) and ``x_out`` (scattered wave, along ``wo``), each ``(3, ...)``
    and perpendicular to its propagation direction; ``None`` → Mitsuba's ``stokes_basis``
    (:func:`to_mitsuba`). Angles are renderer angles [rad]."""
    ti, pi_, ts, ps = np.broadcast_arrays(*_em_angles(theta_i, phi_i, theta_o, phi_o))
    ki, hi, _ = _hv(ti, pi_, -1.0)
    ks, hs, _ = _hv(ts, ps, 1.0)
    r_in = _rotate_stokes_basis(ki, hi, stokes_basis(ki) if x_in is None else x_in)
    r_out = _rotate_stokes_basis(ks, hs, stokes_basis(ks) if x_out is None else x_out)
    m = np.einsum("ij,jk...,kl->il...", D_MITSUBA, np.asarray(mueller, float), D_MITSUBA)
    return np.einsum("ij...,jk...,lk...->il...", r_out, m, r_in)
