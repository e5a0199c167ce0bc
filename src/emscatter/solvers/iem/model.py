"""Integral-equation model (IEM family): the advanced IEM for bistatic σ⁰, all four
polarizations, between the small-perturbation and Kirchhoff regimes (kσ ≈ 0.3–3).

Which IEM, and why
------------------
Three IEM versions are in use. The original IEM (Fung, Li & Chen, IEEE TGRS 30, 356, 1992;
Fung 1994, *Microwave Scattering and Emission Models*) drops the phase of the Green's function
in the complementary (multiple-bounce) surface field, which limits it to ``kσ·kℓ ≲ 1.2√|ε|``
and makes it inaccurate in bistatic geometries. The improved IEM (I2EM: Fung, Liu, Chen &
Tsay, J. Electromagn. Waves Appl. 16, 689, 2002; Fung & Chen, IEEE GRSL 1, 75, 2004; the
Ulaby & Long 2014 codes and SMRT's ``iiem_fung02``) keeps the upper-medium phase and adds the
Fresnel *transition* between ``R(θi)`` (small roughness) and ``R`` at the local specular
angle (large roughness, Wu et al. IEEE TGRS 39, 2001), but it is co-polarized in bistatic
(no ``hv`` out of the plane) and its published codes evaluate the Fresnel coefficients with
``Re ε`` only. The advanced IEM (AIEM: Chen, Wu, Tsang, Li, Shi & Fung, IEEE TGRS 41, 90,
2003; Wu & Chen, IEEE TGRS 42, 743, 2004) keeps the Green's-function phase in *both* media,
gives all four polarizations at any bistatic geometry with the same transition, and is the
version checked against exact 3-D numerical (method-of-moments) solutions: emission within
~1 % (Chen et al. 2003, against the 3-D MoM of Zhou, Tsang et al.) and backscatter within
~1 dB over kσ ≲ 3 (Wu & Chen 2004), where the 1992 IEM errs by several dB for large kσ·kℓ.
Its cost over I2EM is four more complementary terms (linear in the number of geometries).
The BRDF and radio bridges need bistatic cross-polarization, so this module implements the
AIEM, with ``complementary="fung92"`` giving the 1992 model (used to reproduce SMRT's
``iem_fung92`` to 1e-6 in the tests).

The model (normalized to the free-space wavenumber, ``k = 1``)
----------------------------------------------------------------
Single scattering (Chen et al. 2003, eqs. 9–10)::

    σ⁰_qp = ½ e^{−(kσ)²(kz²+ksz²)} Σ_{n≥1} (kσ)^{2n}/n! |Iₙ|² Ŵₙ(ks⊥ − ki⊥)
    Iₙ = (kz+ksz)ⁿ f_qp e^{−(kσ)² kz ksz}
         + ¼ Σ_{8 terms} F̃_j e^{−(kσ)²(q_j² − q_j(ksz−kz))} α_j^(n−1)

``Ŵₙ = k² Wₙ`` with Ulaby's ``Wₙ = 2π wₙ``, ``wₙ`` the normalized spectrum of ``ρⁿ``
(:func:`emscatter.solvers.kirchhoff.po.log_nfold`: closed forms for Gaussian and exponential,
the power-law table). The complementary coefficients ``F̃_j`` and the bases ``α_j`` are in
:mod:`emscatter.solvers.iem.terms` (reduced so that they stay finite where ``α_j = 0``, e.g.
backscatter).

Choices made here, where the papers are silent or inconsistent (each tested):

* **Kirchhoff coefficient.** ``f = f_vec(R_l) + f_scalar(R_T − R_l)``: the vector tangent-plane
  coefficient (polarization mixing out of the plane, the physical-optics limit) with ``R`` at
  the local specular angle ``cosθ_l = |ks − ki|/2k``, plus the scalar I2EM coefficient for the
  difference between the transition ``R_T`` and ``R_l``. In the plane of incidence (and so in
  backscatter) this *is* the published AIEM/I2EM coefficient with ``R_T``; as kσ grows
  (``R_T → R_l``) it becomes the physical-optics amplitude of :mod:`emscatter.solvers.kirchhoff.po`
  exactly.
  The published vector form with ``R_T`` is discontinuous at backscatter (its facet frame is
  undefined there and ``R_h + R_v ≠ 0``: approaching backscatter in azimuth swaps hh and vv);
  this combination is continuous.
* **First order.** The published AIEM reduces to first-order SPM in backscatter and in the
  plane of incidence near specular, but not in general bistatic geometries (its n = 1 amplitude
  is off by up to ~30 % out of the plane, e.g. θi = 20°, θs = 70°, φ = 120°). With
  ``first_order="spm"`` (default) the n = 1 amplitude gets the difference ``D`` to the exact
  first-order (SPM) amplitude, attenuated like the rest of the series by
  ``e^{−(kσ)²(kz²+ksz²)/2}``: σ⁰ → SPM1 as kσ → 0 in every geometry, the n ≥ 2 terms are
  untouched, and ``D = 0`` in backscatter (the published backscatter values are unchanged).
* **Lower-medium phase.** AIEM averages ``exp(±i q₂ (z − z'))`` over all heights; for
  ``Im q₂ · σ ≳ 1`` (skin depth below the rms height: metals, very lossy media) this grows like
  ``e^{3 (Im q₂ σ)²}`` although the true factor ``e^{i q₂|z−z'|}`` is bounded by 1. The height
  phase of the lower-medium terms uses ``Re q₂`` (their coefficients keep the complex ``q₂``):
  identical for lossless media, a relative change ``O((Im q₂ σ)²)`` (< 2 % for a wet soil,
  ε = 15 + 2i, kσ = 0.5) otherwise, and every term stays bounded (tested up to ε = 1e7i).
* **Co-pol ratio (issue 20): the default ``complementary="aiem-faded"``.** The published AIEM
  (``"aiem"``) puts σhh above σvv in backscatter at kσ ≳ 0.5 (kσ 0.79–1.32, 40°, exponential,
  ε 3–30: HH − VV = +0.9 dB on average, up to +2.4), where exact 3-D solutions give −1.2 dB
  (NMM3D) and measured soils σhh ≤ σvv (Oh et al. 1992). Why: the Kirchhoff term with
  ``R(θi)`` (or a partial transition) has ``|R_h| > |R_v|``; the complementary terms that
  restore ``|α_vv| > |α_hh|`` (SPM) are, in backscatter, the lower-medium ones, and with the
  lower-medium height phase they carry ``e^{−σ²(Re q₂)²}`` (an average of ``e^{±i q₂ (z − z')}``
  over all heights; the true ``e^{i q₂|z−z'|}`` decays only algebraically in σ q₂), so they
  vanish once ``kσ √ε ≳ 1``. Giving them the upper-medium phase (``"aiem-upper"``, as I2EM:
  Fung et al. 2002, Fung & Chen 2004, SMRT's ``iiem_fung02``) keeps the ratio but never lets
  them fade: the physical-optics limit is missed by 2.5 dB at kσ = 3. The default does both:
  upper-medium phase, amplitude times ``1 − γ_v``, the transition factor of Wu et al. (2001).
  The argument: γ is *defined* (Wu et al. 2001; Fung & Chen 2004) from the ratio of the
  Kirchhoff-plus-complementary field to the Kirchhoff field with ``R(0)`` — it is the share of
  the complementary correction that ``R_T`` has already absorbed into the Kirchhoff term
  (``γ → 1`` where the tangent-plane field with ``R`` at the specular point is the whole
  field). Keeping the complementary lower-medium field at full strength on top of a Kirchhoff
  term that has moved to ``R(0)`` counts that correction twice; ``(1 − γ)`` removes it at the
  rate the transition takes it over, so the model runs from SPM (γ = 0) to PO (γ = 1). One
  factor for all polarizations (γ_v, whose ``F_t`` form is the one the I2EM codes of Ulaby &
  Long 2014 use for both ``R_vT`` and ``R_hT``): with γ_h on hh the lower-medium terms of hh
  would fade faster than those of vv, and hh rise above vv again (measured: +0.8 dB worse at
  70°). The first-order defect ``D`` is taken with the unfaded terms (the fade, like the
  transition, is part of the model, not undone at n = 1; ``D = 0`` in backscatter still), and
  γ → 0 as kσ → 0, so the SPM limit is unchanged. Against the NMM3D 40° table (162 cases,
  validation/iem/copol_ratio.md): HH RMSE 0.58 dB (published AIEM 1.13), HH − VV −1.42 dB
  mean at kσ 0.79–1.32 (NMM3D −1.23; max −0.46), PO limit at kσ = 3 within 0.03 dB; VV RMSE
  1.28 dB (AIEM 0.94: VV +0.9 dB biased at kσ 0.26–0.8, as every IEM with full lower-medium
  terms — I2EM, SMRT ``iiem_fung02``, the 1992 IEM; AIEM's lower VV there came with the
  inverted ratio). Past the Brewster angle of a low-ε soil (ε ≈ 4, θ ≈ 70°, kσ 1–4.5) hh
  stays below vv since the transition's phase variable is (kσ)², not the papers' (kσ cosθ)²
  (:mod:`emscatter.solvers.iem.terms`: with it hh exceeded vv there by up to +2.1 dB).
* **Reciprocity.** The transition and the complementary coefficients use ``R(θi)``, so the
  published bistatic σ⁰ is not reciprocal. ``reciprocal=True`` (default) returns
  ``½[σ⁰_qp(i→s) + σ⁰_pq(−s→−i)]`` (exactly reciprocal; a single evaluation in backscatter and
  at specular, where the two coincide); ``info["nonreciprocity"]`` reports the largest relative
  difference of the two, a measure of the model's own error.
* **Shadowing** (optional factor, default ``"direction-correlated"``): Smith's ``Λ`` with the
  direction-correlated form ``1/(1 + Λ_max + λ(ψ) Λ_min)``, ``λ = 4.41ψ/(4.41ψ + 1)``
  (van Ginneken, Stavridi & Koenderink, Appl. Opt. 37, 130, 1998; Heitz, JCGT 3, 2014), ``ψ``
  the azimuth between the two directions seen from the surface: the monostatic ``1/(1 + Λ)``
  in backscatter, ~``1/(1 + Λi + Λs)`` (Fung et al. 2002, eq. 7) near specular.
  ``"height-correlated"`` is Fung's form, ``False`` none. The slope is the model's nominal
  per-direction rms slope (Ulaby & Long 2014, I2EM codes): ``√2 σ/ℓ`` (Gaussian), ``σ/ℓ``
  (exponential), ``√(2H) σ/ℓ`` (power law, equal to the exponential's at H = ½), or
  ``rms_slope=``.

Cross-polarization
------------------
* Bistatic, out of the plane of incidence: the single-scattering ``hv``, ``vh`` above
  (Kirchhoff mixing + the AIEM cross-pol complementary coefficients). They vanish in the plane
  of incidence, hence in backscatter.
* Multiple scattering, every geometry: the cross-polarized term of Fung et al. 1992 (appendix)
  / Fung 1994 — in backscatter the form of Ulaby & Long 2014 (§10-3.9, code 10.1) and SMRT's
  ``iiem_fung02`` (``σ⁰_hv = σ⁰_vh``) — continued to bistatic geometry with the bistatic
  kernel (Chen et al. 2003 appendix B/C at the intermediate wavevector), ladder + crossed
  height pairings and a reciprocal symmetrization, :mod:`emscatter.solvers.iem.crosspol`
  (derivation, what is
  approximated). Continuous through backscatter, where it equals the published backscatter
  form; reciprocal (``hv(i→s) = vh(−s→−i)``); against second-order SPM
  (:mod:`emscatter.solvers.spm.crosspol`) within 1–3 dB at kσ = 0.05 in the plane of incidence (θs
  ≤ 40°).
  Outer shadowing: the direction-correlated form (``1/(1 + Λ)`` in backscatter). The
  co-polarized multiple scattering (weak) is not included. ``crosspol=False`` omits it
  (~0.3–0.6 ms per geometry with numba at ``crosspol_order=8``, ×5–10 the co-pol cost).
* 1-D profiles (2-D problem): no cross-polarization.

Coherent part: the Kirchhoff mean field ``|R(θi)|² exp(−(2kσ cosθi)²)`` (what Chen et al. 2003
use with AIEM for emission), :func:`emscatter.solvers.kirchhoff.common.coherent_reflectivity`.

1-D profiles (``dimension=1``): the same amplitudes in the plane of incidence with the 1-D
spectrum, ``Ŵₙ = k² · 2π wₙ⁽¹ᴰ⁾/(2k)`` — the mapping between the 3-D and 2-D problems that the
first-order SPM and the physical-optics series obey (:mod:`emscatter.solvers.spm`,
:mod:`emscatter.solvers.kirchhoff.po`).

Numerics: the series sums to ``rtol`` in log space (:mod:`emscatter.solvers.iem.series`); no fixed
term count.
Compiled kernels (:mod:`emscatter.solvers.iem.compiled`, numba, optional;
``EMSCATTER_KERNELS=numpy`` forces the
reference path) cover Gaussian and exponential correlations.

Known traits (validation/iem/README.md): with ``complementary="aiem"``, for high-permittivity
soils toward 60–70° vv falls below the 1992 IEM/I2EM (the lower-medium terms are attenuated by
``e^{−σ² Re q₂²}``, which the versions without the lower-medium phase lack); for
exponential spectra the model, like physical optics, loses energy at kσ ≳ 0.5 (a PEC "emits"
0.1–0.8): emissivities are upper bounds there; near grazing (θ > 70°, and > 45° for
conductors) it can create energy — the validity report flags those angles.
"""

from __future__ import annotations

import inspect
import math

import numpy as np

from emscatter.conventions import check_positive
from emscatter.fresnel import is_pec
from emscatter.scattering import Scattering
from emscatter.solvers.iem import backscatter_path as back_path
from emscatter.solvers.iem.amplitudes import (
    _amplitudes,
    _series,
    _spectral_args,
)
from emscatter.solvers.iem.backscatter_path import _backscatter
from emscatter.solvers.iem.options import _options, _slope
from emscatter.solvers.iem.shadowing import _shadowing
from emscatter.solvers.iem.validity import (  # noqa: F401 (re-exported: the solver's contract)
    OPTIONS,
    VALIDITY,
    _conductor,
    check_validity,
    nominal_rms_slope,
)
from emscatter.solvers.kirchhoff.common import (
    _broadcast,
    check_roughness,
    coherent_local,
    geometry,
)
from emscatter.solvers.kirchhoff.po import log_nfold

__all__ = ["bistatic", "check_validity", "VALIDITY", "OPTIONS", "nominal_rms_slope"]

_BACK_TOL = 1e-9
_MODEL_NAMES = {
    "aiem": "AIEM",
    "aiem-upper": "AIEM, lower-medium terms with the upper-medium phase (I2EM)",
    "aiem-faded": "AIEM, lower-medium terms with the upper-medium phase, faded by 1 − γ",
    "fung92": "IEM (Fung et al. 1992)",
}


# ----------------------------------------------------------------------------- solver


def _single(rough, eps, k, loc, opt, slope, shadow_mode, reciprocal, log_w):
    """Single-scattering σ⁰ (2, 2, n) on a chunk, and the largest non-reciprocity."""
    n = loc.n
    ks = k * rough.sigma
    dim = rough.dimension
    K, pref = _spectral_args(rough, k, loc, n)
    shadow = _shadowing(shadow_mode, loc, slope)
    with np.errstate(divide="ignore"):
        pref = pref + np.log(np.broadcast_to(shadow, (n,)))
    b = lambda v: np.broadcast_to(v, (n,))  # noqa: E731
    si, cs, ss, css = b(loc.si), b(loc.ci), b(loc.ss), b(loc.cs)
    cf = b(loc.cd)
    sf = b(loc.sd) if dim == 2 else np.zeros(n)
    sf = np.where(np.abs(sf) < 1e-12, 0.0, sf)  # in the plane: exact zeros (no cross-pol)
    eps_f = eps if (is_pec(eps) or np.ndim(eps) == 0) else b(eps)
    # reversed geometry (−k_s → −k_i) only where it differs from the forward one
    if reciprocal:
        same = (np.abs(si - ss) <= 1e-12) & (np.abs(sf) <= 1e-12)
        rev = np.nonzero(~same)[0]
    else:
        rev = np.zeros(0, dtype=np.int64)
    if rev.size:
        cat = lambda a, c: np.concatenate([a, c[rev]])  # noqa: E731
        g_si, g_cs, g_ss, g_css = cat(si, ss), cat(cs, css), cat(ss, si), cat(css, cs)
        g_sf, g_cf = np.concatenate([sf, -sf[rev]]), cat(cf, cf)
        g_K, g_pref = cat(K, K), cat(np.broadcast_to(pref, (n,)), np.broadcast_to(pref, (n,)))
        g_eps = eps_f if (is_pec(eps_f) or np.ndim(eps_f) == 0) else cat(eps_f, eps_f)
    else:
        g_si, g_cs, g_ss, g_css, g_sf, g_cf = si, cs, ss, css, sf, cf
        g_K, g_pref, g_eps = K, np.broadcast_to(pref, (n,)), eps_f
    la, lx, ph, sxx, d = _amplitudes(
        rough, g_si, g_cs, g_ss, g_css, g_sf, g_cf, g_eps, ks, log_w, g_K, opt
    )
    pols = (0, 1, 2, 3) if dim == 2 and np.any(g_sf != 0) else (0, 3)
    m = la.shape[1]
    P = len(pols)
    log_s, log_prec = _series(
        rough,
        la[list(pols)].reshape(P * m, -1),
        np.tile(lx, (P, 1)),
        ph[list(pols)].reshape(P * m, -1),
        np.tile(sxx, (P, 1)),
        d[list(pols)].reshape(P * m),
        2.0 * math.log(ks),
        log_w,
        np.tile(g_K, P),
        np.tile(g_pref, P),
        opt,
    )
    vals = np.zeros((4, m))
    vals[list(pols)] = np.exp(log_s).reshape(P, m)
    prec = np.full((4, m), -np.inf)
    prec[list(pols)] = log_prec.reshape(P, m)
    fwd = vals[:, :n]
    out = fwd.copy()
    nonrec = 0.0
    tr = [0, 2, 1, 3]  # (hh, hv, vh, vv) → transposed [pol_s, pol_i]
    if reciprocal:
        both = np.nonzero(same)[0]
        out[:, both] = 0.5 * (fwd[:, both] + fwd[tr][:, both])
        if rev.size:
            back = vals[:, n:][tr]
            scale = np.max(fwd[:, rev], axis=0) + np.max(back, axis=0) + 1e-300
            nonrec = float(np.max(np.abs(fwd[:, rev] - back) / scale)) if rev.size else 0.0
            out[:, rev] = 0.5 * (fwd[:, rev] + back)
    sig = np.empty((2, 2, n))
    sig[0, 0], sig[0, 1], sig[1, 0], sig[1, 1] = out
    return sig, 2.0 * nonrec, float(np.max(prec))


def bistatic(
    roughness,
    eps,
    k: float,
    theta_i,
    theta_s,
    phi_s,
    phi_i=0.0,
    *,
    coherent: bool = True,
    rtol: float = 1e-8,
    max_terms: int = 10**6,
    fresnel: str = "transition",
    complementary: str = "aiem-faded",
    first_order: str = "spm",
    reciprocal: bool = True,
    shadowing="direction-correlated",
    rms_slope=None,
    crosspol: bool = True,
    crosspol_order: int = 8,
    threads: int | None = None,
) -> Scattering:
    """Integral-equation (AIEM) bistatic scattering coefficients σ⁰, all four polarizations.

    Parameters
    ----------
    roughness : Gaussian, exponential, power-law or measured (``measured_roughness``) roughness,
        ``dimension`` 2 (surface, per unit area) or 1 (profile, per unit length; hh and vv,
        ``φs ∈ {φi, φi + π}``).
    eps : relative permittivity (``Im ε ≥ 0``; broadcasts with the angles) or ``"pec"``.
    k : free-space wavenumber [rad/m].
    theta_i, theta_s, phi_s, phi_i : angles [rad], numpy-broadcast (θ ∈ [0, π/2]).
    coherent : ``False`` skips the coherent part (``coherent`` is then NaN).
    rtol : relative tolerance of the series (a bound on the neglected tail) [-].
    max_terms : safety cap on series terms per geometry.
    fresnel : ``"transition"`` (Wu et al. 2001, default) or ``"incident"`` (``R(θi)``, as the
        1992 IEM) in the Kirchhoff coefficient.
    complementary : ``"aiem-faded"`` (default: the lower-medium terms with the upper-medium
        phase, times ``1 − γ_v``: co-pol ratio and physical-optics limit, module docstring),
        ``"aiem"`` (Green's-function phase kept, Chen et al. 2003: HH above VV at kσ ≳ 0.5),
        ``"aiem-upper"`` (the lower-medium terms with the upper-medium phase, never faded, as
        I2EM) or ``"fung92"`` (phase dropped, Fung et al. 1992).
    first_order : ``"spm"`` (exact first-order amplitude, module docstring) or ``"model"``
        (the published coefficients as they are).
    reciprocal : symmetrize σ⁰ by reciprocity (module docstring).
    shadowing : ``"direction-correlated"`` (default, ``True``), ``"height-correlated"`` or
        ``False``.
    rms_slope : per-direction rms slope for the shadowing functions [-] (float or pair);
        default :func:`nominal_rms_slope`.
    crosspol : add the multiple-scattering ``hv``, ``vh`` at every geometry (2-D surfaces).
    crosspol_order : Gauss–Legendre nodes per graded segment of its 2-D integral (8: ≲ 1e-2
        relative, 12: ≲ 1e-3).
    threads : worker threads of the compiled exact-backscatter kernel (default: the CPU count,
        at most 8; used from 2 × ``compiled.BACK_MIN_CHUNK`` = 4096 backscatter angles on;
        results do not depend on it).

    Returns
    -------
    :class:`~emscatter.scattering.Scattering` (``method="iem"``); ``info`` holds the options,
    ``"nonreciprocity"`` and ``"precision"`` (rounding-error estimate of the series).
    """
    rough = check_roughness(roughness)
    k = check_positive("k", k, unit="rad/m")
    opt, shadow_mode = _options(
        rtol, max_terms, fresnel, complementary, first_order, reciprocal, shadowing, crosspol,
        crosspol_order, coherent, threads,
    )  # fmt: skip
    rtol = opt.rtol
    log_w = log_nfold(rough)
    slope = _slope(rough, rms_slope)
    dim = rough.dimension
    g = geometry(theta_i, theta_s, phi_s, phi_i, eps, dim)
    sig = np.empty((2, 2, g.size))
    nonrec, prec = 0.0, -np.inf
    block = 1 << 14
    back = g.backscatter_chunk(_BACK_TOL) if g.size <= block else None  # the common case, lean
    for st in range(0, g.size, block):
        sl = slice(st, st + block)
        loc = back if back is not None else g.chunk(sl, signed_azimuth=True)
        res = None
        if back is not None or _all_backscatter(loc):
            res = _backscatter(rough, loc.eps, k, loc, opt, slope, shadow_mode, log_w)
        if res is None:
            res = _single(rough, loc.eps, k, loc, opt, slope, shadow_mode, reciprocal, log_w)
        s, nr, pr = res
        sig[:, :, sl] = s
        nonrec, prec = max(nonrec, nr), max(prec, pr)
    if dim == 1:
        sig[0, 1] = sig[1, 0] = 0.0
    elif crosspol and g.size:
        _add_crosspol(sig, rough, g, k, slope, int(crosspol_order))
    sig = sig.reshape(2, 2, *g.shape)
    if coherent:
        coh = coherent_local(g.chunk(), rough.sigma, k).reshape(2, *g.shape)
    else:
        coh = np.full((2, *g.shape), np.nan)
    info = _info(opt, reciprocal, shadow_mode, slope, crosspol and dim == 2, nonrec, prec, coherent)
    return Scattering.from_geometry(g, sigma0=sig, coherent=coh, method="iem", k=k, info=info)


def _info(opt, reciprocal, shadow_mode, slope, crosspol, nonrec, prec, coherent) -> dict:
    """The result's ``info`` (:func:`bistatic`'s Returns)."""
    return {
        "model": _MODEL_NAMES[opt.complementary],
        "rtol": opt.rtol,
        "fresnel": opt.fresnel,
        "complementary": opt.complementary,
        "first_order": opt.first_order,
        "reciprocal": bool(reciprocal),
        "shadowing": shadow_mode or "none",
        "rms_slope": slope,
        "crosspol": "multiple scattering (bistatic, reciprocal)" if crosspol else "none",
        "nonreciprocity": nonrec,
        "precision": float(1e-16 * math.exp(min(prec, 700.0))),
        "coherent": "Kirchhoff |R(θi)|² exp(−(2kσ cosθi)²)"
        if coherent
        else "not computed (coherent=False)",  # fmt: skip
    }


def _api_checked(roughness, eps, k, theta_i, theta_s, phi_s, phi_i=0.0, *, monostatic=False,
                 **options) -> Scattering:  # fmt: skip
    """The public API's entry (``bistatic.checked``): :func:`bistatic` for inputs the API has
    checked (a Roughness, ``k`` a float > 0 [rad/m], float angle arrays in range [rad],
    ``eps`` "pec" or complex). ``monostatic``: the caller guarantees ``theta_s is theta_i``
    and ``φs = φi + π``; the exact-backscatter call then skips the general geometry
    (:func:`emscatter.solvers.iem.backscatter_path.monostatic`, same values bit for bit)
    where that path covers it (compiled kernels, Gaussian or exponential spectrum, one ε and
    one φi, ``coherent=False``, no multiple-scattering cross-pol on a 2-D surface), else
    it is :func:`bistatic` itself."""
    if monostatic:
        res = _monostatic(roughness, eps, k, theta_i, phi_s, phi_i, options)
        if res is not None:
            return res
    return bistatic(roughness, eps, k, theta_i, theta_s, phi_s, phi_i, **options)


def _monostatic(rough, eps, k, ti, ps, pi_, options) -> Scattering | None:
    """:func:`_api_checked`'s backscatter path, or None where it does not cover the call."""
    unknown = options.keys() - _DEFAULTS.keys()
    if unknown:  # bistatic raises the usual TypeError
        return None
    o = {**_DEFAULTS, **options}
    opt, shadow_mode = _options(
        o["rtol"], o["max_terms"], o["fresnel"], o["complementary"], o["first_order"],
        o["reciprocal"], o["shadowing"], o["crosspol"], o["crosspol_order"], o["coherent"],
        o["threads"],
    )  # fmt: skip
    dim = rough.dimension
    if o["coherent"] or (o["crosspol"] and dim == 2) or not isinstance(ti, np.ndarray):
        return None
    slope = _slope(rough, o["rms_slope"])
    res = back_path.monostatic(rough, eps, k, ti, ps, pi_, opt, slope, shadow_mode)
    if res is None:
        return None
    sig, nonrec, prec = res
    shape = ti.shape
    info = _info(opt, o["reciprocal"], shadow_mode, slope, False, nonrec, prec, False)
    theta = _broadcast(ti, shape)
    return Scattering._of(
        sigma0=sig.reshape(2, 2, *shape),
        coherent=np.full((2, *shape), np.nan),
        method="iem",
        theta_i=theta,
        theta_s=theta,
        phi_s=_broadcast(np.asarray(ps, dtype=float), shape),
        phi_i=_broadcast(np.asarray(pi_, dtype=float), shape),
        k=k,
        dimension=dim,
        info=info,
    )


bistatic.checked = _api_checked  # the API's entry for inputs it has checked
_SIGNATURE = inspect.signature(bistatic)
_DEFAULTS = {
    p.name: p.default
    for p in _SIGNATURE.parameters.values()
    if p.kind is inspect.Parameter.KEYWORD_ONLY
}
# the entry's signature is bistatic's plus ``monostatic`` (the API reads which options a
# solver entry takes from it: ``crosspol``, ``coherent``, ``monostatic``)
_api_checked.__signature__ = _SIGNATURE.replace(
    parameters=[
        *_SIGNATURE.parameters.values(),
        inspect.Parameter("monostatic", inspect.Parameter.KEYWORD_ONLY, default=False),
    ]
)


def _all_backscatter(loc) -> bool:
    """θs = θi and φs = φi + π (to 1e-9 rad) for every geometry of the chunk."""
    d = np.mod(loc.phi_s - loc.phi_i, 2 * math.pi)
    return bool(
        np.all(np.abs(loc.si - loc.ss) <= 1e-12) and np.all(np.abs(d - math.pi) <= _BACK_TOL)
    )


def _add_crosspol(sig, rough, g, k, slope, order):
    """Add the multiple-scattering hv, vh (:mod:`emscatter.solvers.iem.crosspol`) at every
    geometry."""
    from emscatter.solvers.iem.crosspol import multiple_scattering

    shadow = _shadowing("direction-correlated", g.chunk(signed_azimuth=True), slope)
    b = lambda a: np.broadcast_to(a, (g.size,))  # noqa: E731
    eps = g.eps if is_pec(g.eps) else b(g.eps_flat)
    angles = (b(g.ti_flat), b(g.ts_flat), b(g.dphi), b(g.phi_i_flat))
    hv, vh = multiple_scattering(rough, eps, k, *angles, slope=slope, shadow=b(shadow), order=order)
    sig[0, 1] += hv
    sig[1, 0] += vh
