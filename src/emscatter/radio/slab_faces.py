"""Rough faces of a slab wall beyond geometric optics: SPM, PO and IEM face kernels and the
diffuse power budget of a slab whose coherent field survives (NumPy).

:mod:`emscatter.radio.slab_diffuse` tracks the diffuse light inside a rough wall per internal
direction cosine. With geometric-optics faces the coherent field is negligible (``< e⁻⁵``) and
every face interaction is diffuse. At the small and medium roughness of common walls (brick,
concrete, glass at 3.5–28 GHz, kσ 0.05–0.5) most of the power stays coherent: the coherent
slab of :mod:`emscatter.radio.slab` carries ``R_coh, T_coh`` and this module adds what the
coherent field loses to the faces, without counting it twice.

Face models (``face=``): first-order SPM (:func:`emscatter.solvers.spm.model.bistatic`,
:func:`emscatter.solvers.spm.transmission.bistatic_transmission`), physical optics
(:func:`emscatter.solvers.kirchhoff.po.bistatic`,
:func:`emscatter.solvers.kirchhoff.transmission.po.bistatic_transmission`) and the IEM
(:func:`emscatter.solvers.iem.model.bistatic`,
:func:`emscatter.solvers.iem.transmission.bistatic_transmission`): their incoherent σ⁰ only.
``"auto"`` picks GO where it holds (then the GO path of ``slab_diffuse``, unchanged), else the
first of SPM, PO, IEM whose validity report passes from air and from inside (wavenumber
``k √Re ε``: the inside faces see a rougher face, kσ√Re ε). PO comes before the IEM: ~100×
faster here and it takes a lossy ε; ``face="iem"`` on request.

* **From air** (the front face, incident plane wave): the complex ``ε`` (flux through the mean
  plane per real ``k⊥``, the transmission solvers' convention), except the IEM transmission,
  which is lossless only and takes ``Re ε`` (the front face's reflection keeps the complex ε).
  The part of the flux beyond the real-index cone (``T_beyond``) and the roughness layer's
  own absorption (``layer_absorption``, ``O((kσ)² Im ε)``) are not carried: with
  ``conserve=True`` the face's rows are scaled to its coherent deficit (below), so they are
  returned to the lobe.
* **From inside** (both faces, ``ε_rel = 1/Re ε``, incident wavenumber ``k √Re ε``): all three
  solvers take a real ``ε_rel < 1`` (light from the denser side, total internal reflection of
  the coherent part beyond the critical angle), so no reciprocity step is needed. None takes
  the complex ``1/ε`` (``Im < 0``: not a passive lower medium); the ε-weighted reciprocity
  ``σ⁰_t(ε; i → t) = ε σ⁰_t(1/ε; −t → −i)`` of the solvers holds for real ε only (a complex
  weight on a power), so the inside faces are lossless and the bulk loss is charged per
  crossing, ``a(μ) = exp(−2 d Im k₂z)``, as in ``slab_diffuse``.

Coherent parts of a face (those of :mod:`emscatter.radio.slab`, Kirchhoff mean fields):
reflection ``|r χ|²`` (``χ = exp(−2σ²k_z²)``, ``k_z`` of the incident side), transmission
``(1 − |r|²) χ_t²`` (``χ_t = exp(−σ²(k₁z − k₂z)²/2)``). Their deficit ``ℓ = 1 − |rχ|² −
(1 − |r|²)χ_t²`` is what the face scatters diffusely; ``conserve=True`` scales the face's
diffuse rows to it (the ratio recorded as ``face_deficit`` = ``ℓ − Σ diffuse``, before scaling).
Cosine nodes: Gauss–Legendre on (0, 1) in air; inside, split at the critical cosine
``√(1 − 1/Re ε)`` (the inside faces' coherent refraction has a kink there; one rule was off
by 1.3e-3 in T_diff at 75° with 48 nodes, the split one is within 8e-5 of 96 nodes with 32).
For the diffuse light inside, a face's kernel is its diffuse σ⁰ plus its coherent parts
(specular reflection back into the same node, refraction into the air node at
``μ_a = √(1 − Re ε (1 − μ²))``, split linearly between the two nearest nodes).

Sources of diffuse light, per incidence and polarization (module ``slab_diffuse``'s transport
carries them): the front face hit from air (unit flux), the coherent wave inside hitting the back
face going down (flux ``F_b``) and the front face going up (``F_f``), with ``D = √(1 − |r|²)
χ_t / (1 − r_in² e^{2iq})`` the coherent downward amplitude just inside the front face
(``slab.py``'s geometric series), ``F_b = |D|² a_c``, ``F_f = F_b |r_in|² a_c``, ``a_c =
|e^{iq}|²``. The coherent field's absorption is ``A_coh = |D|²(1 − a_c)(1 + |r_in|² a_c)``
per pass, times the ratio that makes it exact for the flat slab (``1 − |R|² − |T|²`` of ITU's
slab over the same per-pass sum at σ = 0: the interference of the up- and down-going waves in
a lossy slab; 1 for a lossless wall, where ``A_coh = 0``).
Each excitation scatters in proportion to its own flux (the interference of the two coherent
waves meeting a face from both sides is not in the faces' σ⁰); the three sources are scaled by
one factor per incidence, ``source_scale = S / (ℓ₀ + (F_b + F_f) ℓ_in)``, so that they carry
exactly the power the coherent field loses, ``S = 1 − R_coh − T_coh − A_coh`` (Poynting's
theorem for the coherent field). ``source_scale`` is recorded: its distance from 1 measures the
neglected interference (≤ a few % at kσ ≤ 0.5, tested). Then ``R_coh + R_diff + T_coh + T_diff
+ A (+ L) = 1`` per incidence to rounding, and σ → 0 gives the coherent slab exactly.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from ..fresnel import fresnel_cos
from .slab import gaussian_mean_field, slab_coefficients

__all__ = ["FACES", "choose_face", "face_validity", "rough_face_budget", "sigma0_kernels"]

#: The ``face=`` values of :func:`emscatter.radio.slab_diffuse.diffuse_transmission`.
FACES = ("auto", "go", "spm", "po", "iem")


def check_face(face) -> str:
    """``face`` checked against :data:`FACES` (ValueError naming it otherwise)."""
    if not isinstance(face, str) or face not in FACES:
        raise ValueError(f"face must be one of {FACES}, got face={face!r}")
    return face


def face_validity(face: str, rough, k: float, eps) -> dict:
    """The validity report of one face model at free-space wavenumber ``k`` [rad/m]: the
    solvers' ``check_validity`` from air (``k``, ``ε``) and from inside (``k √Re ε``,
    ``1/Re ε``: the inside faces see the roughness ``√Re ε`` times larger); ``valid`` when
    both pass, ``reasons`` as strings (the inside ones prefixed ``inside:``)."""
    e = complex(eps)
    out = _face_validity(face, rough, k, e)
    inside = _face_validity(face, rough, k * math.sqrt(e.real), 1.0 / e.real)
    return {"valid": out["valid"] and inside["valid"],
            "reasons": out["reasons"] + [f"inside: {r}" for r in inside["reasons"]]}  # fmt: skip


def _face_validity(face: str, rough, k: float, eps) -> dict:
    if face == "go":
        from ..solvers.kirchhoff import go

        rep = go.check_validity(rough, k)
    elif face == "spm":
        from ..solvers.spm import validity

        rep = validity.check_validity(rough, k, eps=eps)
    elif face == "po":
        from ..solvers.kirchhoff import po

        rep = po.check_validity(rough, k, eps=eps)
    else:
        from ..solvers.iem import validity

        rep = validity.check_validity(rough, k, eps=eps)
    return {"valid": bool(rep["valid"]), "reasons": [str(r) for r in rep.get("reasons", [])]}


def choose_face(face: str, rough, k: float, eps):
    """``(face, report)``: ``"auto"`` resolved to the first of GO, SPM, PO, IEM whose validity
    holds (GO when none does, with GO's report: the caller's ``out_of_range`` decides)."""
    if face != "auto":
        return face, face_validity(face, rough, k, eps)
    reports = {}
    for name in ("go", "spm", "po", "iem"):
        reports[name] = face_validity(name, rough, k, eps)
        if reports[name]["valid"]:
            return name, reports[name]
    why = [f"{n}: {'; '.join(r['reasons'])}" for n, r in reports.items()]
    return "go", {"valid": False, "reasons": why}


def _sigma0(face, kind, rough, eps, k, ti, tj, ph):
    """Incoherent σ⁰ ``(2, 2, ...)`` of one face model (reflection ``"r"``, transmission
    ``"t"``); the solvers' own validity policy off (the caller applied ``face_validity``)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if face == "spm":
            from ..solvers.spm import model, transmission

            if kind == "r":
                return model.bistatic(rough, eps, k, ti, tj, ph, coherent=False).sigma0
            return transmission.bistatic_transmission(
                rough, eps, k, ti, tj, ph, out_of_range="ignore"
            ).sigma0
        if face == "po":
            from ..solvers.kirchhoff import po
            from ..solvers.kirchhoff.transmission import po as tpo

            if kind == "r":
                return po.bistatic(rough, eps, k, ti, tj, ph, coherent=False).sigma0
            return tpo.bistatic_transmission(
                rough, eps, k, ti, tj, ph, out_of_range="ignore"
            ).sigma0
        from ..solvers.iem import model, transmission

        if kind == "r":
            return model.bistatic(rough, eps, k, ti, tj, ph, coherent=False).sigma0
        e_real = complex(eps).real  # IEM transmission is lossless only (module docstring)
        return transmission.bistatic_transmission(
            rough, e_real, k, ti, tj, ph, out_of_range="ignore"
        ).sigma0


def sigma0_kernels(face, rough, eps_rel, k: float, cos_in, nodes_r, nodes_t, n_phi: int,
                   n_modes=0):  # fmt: skip
    """Diffuse kernels ``(K_r, K_t)``, ``(n_modes + 1, 2, n_in, n_j)`` [-], of one SPM/PO/IEM
    face, defined as :func:`emscatter.radio.slab_diffuse.face_kernels` (GO): mode ``m`` of
    ``w_j ∫ Σ_q σ⁰_qp cos(mφ) / (4π cosθi) dφ``, on the cosine nodes and weights
    ``nodes_r = (μ, w)`` of the reflected side and ``nodes_t`` of the transmitted side. ``k`` is
    the incident medium's wavenumber [rad/m]; ``eps_rel`` the lower medium's permittivity
    relative to it."""
    xp, wp = np.polynomial.legendre.leggauss(n_phi)
    phi = 0.5 * math.pi * (xp + 1.0)
    wphi = 0.5 * math.pi * wp
    cosm = np.cos(np.arange(n_modes + 1)[:, None] * phi[None, :]) * wphi
    ci = np.clip(np.asarray(cos_in, dtype=float), 1e-9, 1.0)
    ti = np.arccos(ci)[:, None, None]
    ph = phi[None, None, :]
    out = []
    for kind, (mu, w_mu) in (("r", nodes_r), ("t", nodes_t)):
        tj = np.arccos(mu)[None, :, None]
        sig = _sigma0(face, kind, rough, eps_rel, k, ti, tj, ph).sum(axis=0)
        if not np.all(np.isfinite(sig)):
            raise ValueError(f"{face} face σ⁰ produced NaN/inf (please report the inputs)")
        ker = 2.0 * np.einsum("pijf,mf->mpij", sig, cosm)
        out.append(ker / (4.0 * math.pi * ci[None, None, :, None]) * w_mu)
    return out[0], out[1]


def _coherent_inside(e: complex, k: float, d: float, c, sigma: float):
    """The coherent downward flux just inside the front face ``|D|²``, one crossing's ``a_c``,
    ``|r_in|²`` and the per-pass absorption ``|D|²(1 − a_c)(1 + |r_in|² a_c)`` (module
    docstring), ``(2, n)`` over (h, v) and the incidence cosines ``c``."""
    r0 = np.stack(fresnel_cos(e, c))
    root = np.sqrt(e - (1.0 - c * c) + 0j)
    root = np.where(root.imag < 0, -root, root)
    k2z = k * root
    chi_t = gaussian_mean_field((k * c - k2z) ** 2, sigma)
    r_in = -r0 * gaussian_mean_field(4.0 * k2z * k2z, sigma)
    ph = np.exp(1j * k * d * root)
    dflux = (1.0 - np.abs(r0) ** 2) * np.abs(chi_t) ** 2 / np.abs(1.0 - r_in * r_in * ph * ph) ** 2
    a_c = np.exp(-2.0 * k * d * root.imag)  # |e^{iq}|², exactly 1 when lossless
    r_in2 = np.abs(r_in) ** 2
    return dflux, a_c, r_in2, dflux * (1.0 - a_c) * (1.0 + r_in2 * a_c)


def _inside_coherent(er: float, m, k: float, sigma: float):
    """Coherent parts of a face hit from inside at internal cosines ``m`` (lossless index):
    ``(rc, tc, mu_air)``, ``rc, tc`` ``(2, ...)`` (h, v) [-]."""
    m = np.asarray(m, dtype=float)
    r = np.abs(np.stack(fresnel_cos(1.0 / er, m))) ** 2
    s2 = er * (1.0 - m * m)
    ca = np.sqrt(np.clip(1.0 - s2, 0.0, 1.0))
    chi_i = np.exp(-2.0 * (sigma * k) ** 2 * er * m * m)
    chi_t = np.exp(-0.5 * (sigma * k) ** 2 * (math.sqrt(er) * m - ca) ** 2)
    tc = np.where(s2 < 1.0, (1.0 - r) * chi_t**2, 0.0)
    return r * chi_i**2, tc, ca


def _specular_deposit(ca, power, mu):
    """``(n_in, n_air)``: ``power[j]`` refracted to air cosine ``ca[j]``, split linearly
    between the two nearest air nodes ``mu`` (ends held)."""
    n = mu.size
    j = np.clip(np.searchsorted(mu, ca) - 1, 0, n - 2)
    w = np.clip((ca - mu[j]) / (mu[j + 1] - mu[j]), 0.0, 1.0)
    out = np.zeros((ca.size, n))
    rows = np.arange(ca.size)
    np.add.at(out, (rows, j), power * (1.0 - w))
    np.add.at(out, (rows, j + 1), power * w)
    return out


def rough_face_budget(face, rough, e: complex, k: float, d: float, c, air, inner, n_phi: int,
                      n_modes: int, conserve: bool, r_coh, t_coh):  # fmt: skip
    """The diffuse budget of a slab with SPM/PO/IEM faces (module docstring). ``c`` the
    incidence cosines, ``air = (μ, w)`` the air-side cosine nodes on (0, 1), ``inner`` those
    inside (split at the critical cosine), ``r_coh, t_coh`` ``(2, n)`` the coherent slab's
    powers. Returns a dict of ``slab_diffuse.DiffuseTransmission`` fields."""
    er = e.real
    sigma = float(rough.sigma)
    mu_a = air[0]
    mu = inner[0]
    n_mu = mu.size
    # coherent parts of the front face from air (slab.py's mean fields, complex ε)
    r0 = np.stack(fresnel_cos(e, c))
    root = np.sqrt(e - (1.0 - c * c) + 0j)
    root = np.where(root.imag < 0, -root, root)
    k2z = k * root
    chi_r = np.abs(gaussian_mean_field(4.0 * (k * c) ** 2, sigma))
    chi_t = gaussian_mean_field((k * c - k2z) ** 2, sigma)
    t0f = 1.0 - np.abs(r0) ** 2
    ell0 = np.maximum(1.0 - np.abs(r0) ** 2 * chi_r**2 - t0f * np.abs(chi_t) ** 2, 0.0)
    # the coherent waves inside (slab.py's geometric series, flux-normalized)
    dflux, a_c, r_in2, a_pass = _coherent_inside(e, k, d, c, sigma)
    f_b = dflux * a_c
    f_f = f_b * r_in2 * a_c
    # their absorption, per pass, calibrated to Poynting's theorem of the flat slab
    _, _, _, a_pass0 = _coherent_inside(e, k, d, c, 0.0)
    fr = np.stack(slab_coefficients(e, c, k, d))
    a_flat = 1.0 - np.abs(fr[:2]) ** 2 - np.abs(fr[2:]) ** 2
    a_coh = a_pass * np.where(a_pass0 > 0, a_flat / np.where(a_pass0 > 0, a_pass0, 1.0), 1.0)
    mu_c = np.sqrt(np.clip(1.0 - (1.0 - c * c) / er, 0.0, 1.0))  # its internal cosine
    rcc, tcc, _ = _inside_coherent(er, mu_c, k, sigma)
    ell_c = np.maximum(1.0 - rcc - tcc, 0.0)  # (2, n)
    rc1, tc1, ca1 = _inside_coherent(er, mu, k, sigma)
    rc1, tc1 = rc1.mean(0), tc1.mean(0)  # the diffuse light inside is unpolarized
    ell1 = np.maximum(1.0 - rc1 - tc1, 0.0)
    # diffuse kernels: front from air (pol-resolved), inside at μ_c (pol-resolved), nodes (mean)
    kin = k * math.sqrt(er)
    kr0m, kt0m = sigma0_kernels(face, rough, e, k, c, air, inner, n_phi, n_modes)
    krcm, ktcm = sigma0_kernels(face, rough, 1.0 / er, kin, mu_c, inner, air, n_phi, n_modes)
    kr1m, kt1m = sigma0_kernels(face, rough, 1.0 / er, kin, mu, inner, air, n_phi, n_modes)
    kr1m, kt1m = kr1m.mean(axis=1), kt1m.mean(axis=1)
    sums = [(m[0].sum(-1) + n[0].sum(-1)) for m, n in ((kr0m, kt0m), (krcm, ktcm), (kr1m, kt1m))]
    ells = (ell0, ell_c, ell1)
    deficits = [ell - s for ell, s in zip(ells, sums, strict=True)]
    if conserve:
        scales = [np.where(s > 0, ell / np.where(s > 0, s, 1.0), 0.0)
                  for ell, s in zip(ells, sums, strict=True)]  # fmt: skip
        kr0m, kt0m = kr0m * scales[0][..., None], kt0m * scales[0][..., None]
        krcm, ktcm = krcm * scales[1][..., None], ktcm * scales[1][..., None]
        kr1m, kt1m = kr1m * scales[2][:, None], kt1m * scales[2][:, None]
        losses = [np.zeros_like(x) for x in deficits]
    else:
        losses = deficits
    # the inside face for diffuse light: diffuse σ⁰ plus its coherent parts (all modes alike)
    kr1m = kr1m + np.diag(rc1)[None]
    kt1m = kt1m + _specular_deposit(ca1, tc1, mu_a)[None]
    s_total = np.clip(1.0 - r_coh - t_coh - a_coh, 0.0, None)
    raw = ell0 + (f_b + f_f) * ell_c
    g = np.where(raw > 0, s_total / np.where(raw > 0, raw, 1.0), 0.0)  # source_scale
    gb, gf = (g * f_b)[..., None], (g * f_f)[..., None]
    att = np.exp(-2.0 * d * np.abs((k * np.sqrt(e - er * (1.0 - mu * mu) + 0j)).imag))
    eye = np.eye(n_mu)
    pm = att[None, :, None] * kr1m  # (M + 1, n_mu, n_mu)
    tm = att[None, :, None] * kt1m
    inv2m = np.linalg.inv(eye[None] - pm @ pm)
    far = inv2m @ tm  # a source leaving one face: out through the other face
    near = pm @ far  # ... out through the face it left
    down = g[..., None] * kt0m + gf * krcm  # (M + 1, 2, n, n_mu): leaving the front face, down
    up = gb * krcm  # leaving the back face, up
    t_modes = (np.einsum("mpij,mjk->pikm", down, far) + np.einsum("mpij,mjk->pikm", up, near)
               + np.moveaxis(gb[None] * ktcm, 0, -1))  # fmt: skip
    r_modes = (np.einsum("mpij,mjk->pikm", down, near) + np.einsum("mpij,mjk->pikm", up, far)
               + np.moveaxis(gf[None] * ktcm, 0, -1))  # fmt: skip
    src = down[0] + up[0]
    absorbed = a_coh + src @ np.linalg.solve(eye - pm[0], 1.0 - att)
    lost = (g * losses[0] + (g * (f_b + f_f)) * losses[1]
            + src @ np.linalg.solve(eye - pm[0], att * losses[2]))  # fmt: skip
    t_lobe, r_lobe = t_modes[..., 0], r_modes[..., 0]
    return {
        "r_diff": g * kr0m[0].sum(-1) + r_lobe.sum(-1), "t_diff": t_lobe.sum(-1),
        "absorbed": absorbed, "lost": lost, "face_deficit": deficits[0], "t_lobe": t_lobe,
        "t_modes": t_modes if n_modes else None, "r_lobe": r_lobe,
        "r_modes": r_modes if n_modes else None, "source_scale": g,
    }  # fmt: skip
