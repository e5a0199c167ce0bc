"""Field coefficients of the integral-equation model (:mod:`emscatter.solvers.iem.model`):
Kirchhoff ``f_qp``,
complementary ``F_qp``, Fresnel transition.

Everything here is in units of the free-space wavenumber (``k = 1``: ``kz = cosθi``,
``ksz = cosθs``, ``q₂ = √(ε − sin²θ)``) and works on flat 1-D arrays of geometries with
``φi = 0``: ``si, cs`` = sin/cos θi, ``ss, css`` = sin/cos θs, ``sf, cf`` = sin/cos(φs − φi).
Polarization tuples are ordered ``(hh, hv, vh, vv)`` = ``[pol_s, pol_i]`` (scattered first).

Complementary field (Chen, Wu, Tsang, Li, Shi & Fung, IEEE TGRS 41, 90, 2003, eqs. 9–10 and
appendix B–C; the same algebra as Fung, Li & Chen, IEEE TGRS 30, 356, 1992, appendix). The
spectral integral of the Green's function is evaluated at the two stationary points
``(u, v) = (−kx, −ky)`` ("i" terms) and ``(−ksx, −ksy)`` ("s" terms), upward/downward
(``±q``), in the upper (``q₁``, coefficients ``F``) and lower (``q₂``, coefficients ``G``)
medium: eight terms. In each term the surface slopes are replaced, by integration by parts
of the height phase ``exp(i α z)``, with ``α = ksz − q`` (i terms) or ``kz + q`` (s terms):
``(zx, zy) = −(X, Y)/α``, ``X = sinθs cosφ − sinθi``, ``Y = sinθs sinφ`` (i terms; for s terms
the primed slopes). The coefficient is affine in those slopes, so we return the *reduced*
coefficient ``F̃ = α F`` — a polynomial, finite at ``α = 0``, which multiplies ``α^(n−1)`` in
the series. (Chen et al.'s code sets the slopes to zero where ``α = 0``, e.g. exact
backscatter for the ``q = kz`` term; the limit ``α → 0`` of ``α F`` is finite and that is what
the continuous expression gives.) The coefficients ``C₁…C₆`` (co-pol) and ``B₁…B₆`` (cross-pol)
of the appendix simplify at the stationary points (one pair of slopes vanishes,
``C₆ = B₆ = 0`` for i terms, ``C₆ = B₃ = 0`` for s terms); the simplified forms below are
checked against the full appendix expressions in ``tests/test_iem_kernels.py``.

Kirchhoff coefficients: the vector tangent-plane coefficients of Chen et al. 2003 (their
``f_qp`` with the stationary-phase slopes ``zx = −(ksx − kx)/(ksz + kz)``), multiplied through
by ``ksz + kz`` so they stay finite at forward grazing; and the scalar (I2EM) form
``f_vv = 2R_v (sinθi sinθs − (1 + cosθi cosθs) cosφ)/(cosθi + cosθs)``, ``f_hh`` with
``−R_h`` (Fung et al., J. Electromagn. Waves Appl. 16, 689, 2002, eq. 5). See
:mod:`emscatter.solvers.iem.model`
for how the two are combined.

Transition (Wu, Chen, Shi & Fung, IEEE TGRS 39, 2040, 2001; Chen et al. 2003; Fung & Chen,
IEEE GRSL 1, 75, 2004): ``R_T = R(θi) + (R(θ_l) − R(θi)) γ`` with ``γ = 1 − S_t/S_t0`` from
the series ratio of the papers, rewritten without the ``1/F_t`` division so that normal
incidence (``F_t = 0``) is regular:
``S_t/S_t0 = |F_t + 8R₀/cosθ|² Σ aₙWₙ / Σ aₙ |F_t + 2^(n+2) R₀ e^(−Q)/cosθ|² Wₙ``,
``aₙ = Qⁿ/n!``; the three sums are physical-optics-type series
(:func:`emscatter.solvers.kirchhoff.po.series_sum`). ``F_t = 2 F_vv(R_v(0))``: the I2EM
backscatter complementary coefficient of v (``F_vv``, ``F_hh`` of Fung et al. 2002 as coded
by Ulaby & Long 2014, code 10.1) at normal-incidence reflection, and ``2 F_hh(R_h(0)) =
−F_t`` (checked in ``tests/test_iem_transition.py``): h has ``−F_t`` against the same
Kirchhoff term (``f_hh(R_h(0)) = f_vv(R_v(0))``), so γ_h ≠ γ_v is one rule, as in the AIEM
code of Chen et al. (2003), not a per-polarization choice. (The I2EM codes of Ulaby & Long
2014 and of Fung & Chen 2010 take γ_v for both; the latter's comment says the ratio has no
polarization dependence, which holds only where ``F_t → 0``.)

**The phase variable (issue 20).** The papers take ``Q = (kσ cosθ)²``. Here ``Q = (kσ)²``,
everything else as published (``F_t`` at θ, the spectrum at the Bragg argument). This is a
documented change, not a published one. The argument: γ is the weight of the specular-facet
regime, where the Kirchhoff coefficient has ``R`` at the facets' local incidence angle — zero
in backscatter, at every θ; the ratio is built from the field with ``R(0)``, i.e. the field
of those facets, whose own phase variable at local normal incidence is kσ. Measured soils
agree (Oh, Sarabandi & Ulaby, IEEE TGRS 30, 370, 1992: ``p = σhh/σvv =
[1 − (2θ/π)^{1/(3Γ₀)} e^{−kσ}]²`` → 1 as ``e^{−kσ}`` at every angle from 10° to 70°, not
as a function of ``kσ cosθ``). With
``(kσ cosθ)²`` the transition at oblique incidence stalls half-way (γ_v ≈ 0.2 at 70°,
kσ = 3, exponential kℓ = 3, ε = 4 + 0.5i), where past the Brewster angle ``R_vT`` passes
through zero and the Kirchhoff term makes hh exceed vv (+1.2 dB; with γ_h := γ_v, the I2EM
rule, +4.6 dB), against p ≤ 1 in every data set. Identical at normal incidence; the SPM
(γ → 0 as kσ → 0) and physical-optics (γ → 1 as kσ → ∞) limits are kept for every
correlation. Against the NMM3D 40° table (validation/auto/nmm3d_table.md) the IEM's RMSE is
VV 1.28 → 1.28 dB, HH 0.62 → 0.58 dB.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "kirchhoff_vector",
    "kirchhoff_scalar",
    "complementary_terms",
    "transition_factor",
    "transition_from_sums",
    "transition_sums",
    "transition_q",
    "backscatter_terms",
    "branch_root",
]


def branch_root(z) -> np.ndarray:
    """``√z`` with ``Im ≥ 0`` (and ``Re ≥ 0`` on the positive real axis)."""
    r = np.sqrt(np.asarray(z, dtype=complex))
    return np.where(r.imag < 0, -r, r)


# ----------------------------------------------------------------------------- Kirchhoff
def kirchhoff_vector(si, cs, ss, css, sf, cf, rh, rv):
    """``(ksz + kz) f_qp`` of the vector Kirchhoff field (Chen et al. 2003), tuple
    (hh, hv, vh, vv). ``rh, rv``: Fresnel coefficients used in the tangent plane.

    The polarization-mixing part carries ``(R_h + R_v)`` times a ratio that is 0/0 at exact
    backscatter (the facet frame is undefined there); it is set to 0 where the facet's
    tangent vector vanishes, which is the limit when ``R_h + R_v → 0`` (local normal
    incidence, i.e. ``R`` at the local specular angle)."""
    den = css + cs  # ksz + kz
    zx = si - ss * cf  # (ksz + kz) × stationary slope zx
    zy = -ss * sf
    a = cs * den + si * zx  # (cs + si zx) × den
    hsnv = -(cs * cf * den + si * (zx * cf + zy * sf))
    vsnh = css * cf * den - zx * ss
    hsnh = -sf * den
    vsnv = zy * cs * ss + css * (zy * cf * si - a * sf)
    t = cs * zx - si * den
    d2 = t * t + zy * zy  # (den × d2 of Chen et al.)²
    n_t = -sf * t * den + cf * a * zy + si * sf * zy * zy
    n_d = -a * (si * ss * zy - css * (si * sf * den - cs * sf * zx + cs * cf * zy))
    n_hd = -a * (-cf * si * den + cs * cf * zx + cs * sf * zy)
    n_vt = t * (cf * css * den - ss * zx) + css * sf * a * zy - (cf * css * si + cs * ss) * zy * zy
    ok = d2 > 1e-300
    g = np.where(ok, zy / np.where(ok, d2, 1.0), 0.0)
    mix = rh + rv
    co = (n_t + n_d) * g * mix
    cr = (n_hd - n_vt) * g * mix
    fhh = (1 - rh) * hsnv + (1 + rh) * vsnh - co
    fvv = -((1 - rv) * hsnv + (1 + rv) * vsnh) + co
    fhv = -(1 + rv) * hsnh + (1 - rv) * vsnv + cr
    fvh = -(1 + rh) * hsnh + (1 - rh) * vsnv + cr
    return fhh, fhv, fvh, fvv


def kirchhoff_scalar(si, cs, ss, css, cf, rh, rv):
    """``(ksz + kz) f_pp`` of the scalar (I2EM) Kirchhoff coefficients, (hh, vv)."""
    g = 2.0 * (si * ss - (1.0 + cs * css) * cf)
    return -rh * g, rv * g


# ----------------------------------------------------------------------------- complementary
def _combine(C, B, R, Rx, qfix, eps, lower: bool, co_only: bool = False):
    """Appendix B combinations of the (reduced) C and B coefficients: (hh, hv, vh, vv).
    ``R = (R_h, R_v)`` for co-pol, ``Rx = (R_v − R_h)/2`` for cross-pol; ``co_only`` skips
    the cross-pol pair (returned as 0)."""
    c1, c2, c3, c4, c5 = C
    b1, b2, b3, b4, b5, b6 = B
    rh, rv = R
    # hh
    rp, rm = 1 + rh, 1 - rh
    a, b = rp / qfix, rm / qfix
    if lower:
        hh = a * (-rp * c1 * eps + rm * c2 + rp * c3) + b * (rm * c4 + rp * c5)
    else:
        hh = -(b * (-rp * c1 + rm * c2 + rp * c3) + a * (rm * c4 + rp * c5))
    # cross
    rp, rm = 1 + Rx, 1 - Rx
    a, b = rp / qfix, rm / qfix
    if co_only:
        hv = vh = 0.0
    elif lower:
        hv = a * (-rp * b1 + rm * b2 + rp * b3 / eps) - b * (rm * b4 * eps + rp * b5 + rm * b6)
        vh = -a * (rp * b4 + rm * b5 + rp * b6 / eps) + b * (-rm * b1 * eps + rp * b2 + rm * b3)
    else:
        hv = b * (rp * b1 - rm * b2 - rp * b3) + a * (rm * b4 + rp * b5 + rm * b6)
        vh = b * (rp * b4 + rm * b5 + rp * b6) - a * (-rm * b1 + rp * b2 + rm * b3)
    # vv
    rp, rm = 1 + rv, 1 - rv
    a, b = rp / qfix, rm / qfix
    if lower:
        vv = a * (rp * c1 - rm * c2 - rp * c3 / eps) - b * (rm * c4 * eps + rp * c5)
    else:
        vv = b * (-rp * c1 + rm * c2 + rp * c3) + a * (rm * c4 + rp * c5)
    return hh, hv, vh, vv


def _reduced_i(si, cs, ss, css, sf, cf, q, alpha):
    """Reduced ``α C`` and ``α B`` at ``(u, v) = (−kx, 0)`` (slopes ``zx, zy = −(X, Y)/α``),
    Green's-function ``q`` (complex for the lower medium)."""
    X = ss * cf - si
    Y = ss * sf
    P = ss - si * cf  # cosφ X + sinφ Y
    C = (
        alpha * cf,
        alpha * cf * cs * q + cs * si * P,
        alpha * cf * si * si - si * q * P,
        alpha * cs * css * cf + cs * ss * X,
        -alpha * cf * css * q - ss * q * X,
    )
    B = (
        alpha * css * sf + ss * Y,
        alpha * css * sf * cs * q + cs * sf * (ss * ss * q - css * si * si),
        alpha * css * sf * si * si + si * si * sf * (css * q + ss * ss),
        -alpha * sf * cs,
        alpha * sf * q,
        0.0,
    )
    return C, B


def _reduced_s(si, cs, ss, css, sf, cf, q, alpha):
    """Reduced coefficients at ``(u, v) = (−ksx, −ksy)`` (primed slopes ``−(X, Y)/α``)."""
    X = ss * cf - si
    Y = ss * sf
    P = ss - si * cf
    C = (
        alpha * cf,
        alpha * cf * cs * q - q * si * P,
        alpha * ss * si + ss * cs * X,
        alpha * css * cf * cs - css * si * P,
        -alpha * css * cf * q - css * ss * X,
    )
    B = (
        alpha * css * sf,
        alpha * css * sf * cs * q + css * sf * (q * si * si + cs * ss * ss),
        0.0,
        -alpha * sf * cs - si * si * sf,
        alpha * sf * q,
        ss * Y,
    )
    return C, B


def complementary_terms(si, cs, ss, css, sf, cf, eps, rh, rv, *, lower=True, phase="aiem"):
    """The eight complementary terms as a list of ``(name, F̃ (hh, hv, vh, vv), q_phase, side)``.

    ``q_phase`` is the (real) vertical wavenumber in the term's height phase: ``±kz``,
    ``±ksz`` (upper medium; also the lower-medium terms with ``phase="aiem-upper"``) or
    ``±Re q₂`` (lower medium, see :mod:`emscatter.solvers.iem.model` for why the real part); the
    term enters the
    series as ``¼ F̃ exp(−σ²(q² − q(ksz − kz))) α^(n−1)`` with
    ``α = ksz − q`` (side "i") or ``kz + q`` (side "s"). ``eps="pec"`` (or ``lower=False``)
    drops the lower-medium terms (their coefficients vanish as ``1/√ε``). ``phase``:

    * ``"aiem"`` (default of :mod:`emscatter.solvers.iem.model`): every term keeps its
      Green's-function phase, the
      lower-medium terms ``±Re q₂`` (Chen et al. 2003, with the real part,
      :mod:`emscatter.solvers.iem.model`);
    * ``"aiem-upper"``: the lower-medium terms keep their coefficients (complex ``q₂``) but
      take the upper-medium height phase of the same side and direction (``±kz``, ``±ksz``),
      as the improved IEM of Fung et al. 2002 / Fung & Chen 2004 and its codes do
      (:mod:`emscatter.solvers.iem.model`: the lower-medium phase removes these terms, and with
      them the co-pol
      ratio, once ``σ Re q₂ ≳ 1``);
    * ``"fung92"``: no Green's-function phase (``q = 0`` in the height phase and in ``α``:
      Fung et al. 1992, whose backscatter closed forms this reproduces; tested)."""
    R = (rh, rv)
    Rx = 0.5 * (rv - rh)
    terms = []
    for name, q, side in (
        ("up_i", cs, "i"),
        ("dn_i", -cs, "i"),
        ("up_s", css, "s"),
        ("dn_s", -css, "s"),
    ):
        qph = 0.0 * q if phase == "fung92" else q
        alpha = css - qph if side == "i" else cs + qph
        fn = _reduced_i if side == "i" else _reduced_s
        C, B = fn(si, cs, ss, css, sf, cf, q, alpha)
        qfix = cs if side == "i" else css
        # at exact grazing (cos = 0) these divide by zero: the geometry's prefactor vanishes
        # there and the model returns σ⁰ = 0 (tested), so the inf/nan is not a result
        with np.errstate(divide="ignore", invalid="ignore"):
            F = _combine(C, B, R, Rx, qfix, eps, False)
        terms.append((name, F, qph, side))
    if not lower:
        return terms
    q2i = branch_root(eps - si * si)
    q2s = branch_root(eps - ss * ss)
    for name, q, qup, side in (
        ("Gup_i", q2i, cs, "i"),
        ("Gdn_i", -q2i, -cs, "i"),
        ("Gup_s", q2s, css, "s"),
        ("Gdn_s", -q2s, -css, "s"),
    ):
        if phase == "aiem":
            qph = q.real
        elif phase in ("aiem-upper", "aiem-faded"):
            qph = qup + 0.0 * q.real
        else:
            qph = 0.0 * q.real
        alpha = css - qph if side == "i" else cs + qph
        fn = _reduced_i if side == "i" else _reduced_s
        C, B = fn(si, cs, ss, css, sf, cf, q, alpha)
        qfix = q2i if side == "i" else q2s
        terms.append((name, _combine(C, B, R, Rx, qfix, eps, True), qph, side))
    return terms


# ----------------------------------------------------------------------------- backscatter
def backscatter_terms(si, cs, eps, rh, rv, *, phase="aiem"):
    """Complementary terms in exact backscatter (``θs = θi``, ``φ = π``), co-polarized.

    Returns ``(U_h, U_v)`` — the ``q = kz`` "i" and ``q = −ksz`` "s" terms, which have
    ``α = 0`` (n = 1 only) and the closed form ``¼ F̃ = ±4 sin²θ R²`` each (hh with ``−R_h²``) —
    and, unless ``eps`` is ``"pec"``, ``(G⁺_h, G⁺_v, α⁺, G⁻_h, G⁻_v, α⁻)``: the lower-medium
    ``q = −q₂`` "i" plus ``q = +q₂`` "s" terms (base ``α⁺ = kz + a``) and the ``q = −q₂`` "s"
    term (base ``α⁻ = kz − a``), each times ¼, both with the height exponent ``−σ² a²``
    (besides the common ``−σ² kz²``), where ``a`` is the lower-medium height phase of
    :func:`complementary_terms`: ``a = Re q₂`` (``phase="aiem"``) or ``kz`` (``"aiem-upper"``:
    ``α⁺ = 2kz``, the Kirchhoff base and exponent; ``α⁻ = 0``, n = 1 only). The remaining
    terms cancel (``q = −kz`` "i" against ``q = +ksz`` "s") or vanish (``q = +q₂`` "i",
    co-pol). Checked against :func:`complementary_terms` in the tests."""
    s2 = si * si
    u = (-2.0 * s2 * rh * rh, 2.0 * s2 * rv * rv)  # per term; the two are equal
    u = (2.0 * u[0], 2.0 * u[1])
    if isinstance(eps, str):
        return u, None
    zero, minus = 0.0 * si, -1.0 + 0.0 * si
    q2 = branch_root(eps - s2)
    a = cs + 0.0 * q2.real if phase in ("aiem-upper", "aiem-faded") else q2.real
    R, Rx = (rh, rv), 0.5 * (rv - rh)
    plus = []
    for fn, q, alpha in ((_reduced_i, -q2, cs + a), (_reduced_s, q2, cs + a)):
        C, B = fn(si, cs, si, cs, zero, minus, q, alpha)
        plus.append(_combine(C, B, R, Rx, q2, eps, True, co_only=True))
    C, B = _reduced_s(si, cs, si, cs, zero, minus, -q2, cs - a)
    neg = _combine(C, B, R, Rx, q2, eps, True, co_only=True)
    gp_h = 0.25 * (plus[0][0] + plus[1][0])
    gp_v = 0.25 * (plus[0][3] + plus[1][3])
    return u, (gp_h, gp_v, cs + a, 0.25 * neg[0], 0.25 * neg[3], cs - a)


def fung92_backscatter_terms(si, cs, eps):
    """The 1992 IEM's complementary amplitude in exact backscatter, ``(G_h, G_v)``: the sum of
    the eight ``¼ F̃`` of :func:`complementary_terms` with ``phase="fung92"`` (all with base
    ``α = cosθ`` and no height phase), in closed form (Fung, Li & Chen 1992, eqs. 91 and 95;
    SMRT's ``iem_fung92``)::

        G_h = −4 sin²θ (ε − 1)/(cosθ + q₂)²
        G_v = 4 sin²θ (ε − 1)(ε cos²θ + sin²θ)/(ε cosθ + q₂)²

    (``sin²θ (1 + R)² …/cos²θ`` of the paper rewritten with ``1 + R_h = 2cosθ/(cosθ + q₂)``,
    ``1 + R_v = 2ε cosθ/(ε cosθ + q₂)``: finite at grazing), ``q₂ = √(ε − sin²θ)``;
    ``eps="pec"``: the limit ``(−4 sin²θ, 4 sin²θ)``. Unlike the AIEM forms
    (:func:`backscatter_terms`) there are no terms of their own at n = 1. Checked against
    :func:`complementary_terms` in the tests."""
    s2 = si * si
    if isinstance(eps, str):
        return -4.0 * s2 + 0j, 4.0 * s2 + 0j
    q2 = branch_root(eps - s2)
    dh, dv = cs + q2, eps * cs + q2
    return -4.0 * s2 * (eps - 1.0) / (dh * dh), 4.0 * s2 * (eps - 1.0) * (eps * cs * cs + s2) / (
        dv * dv
    )


# ----------------------------------------------------------------------------- transition
def transition_factor(eps, cs, ks: float, log_w, K, *, rtol: float = 1e-10):
    """``(γ_h, γ_v)`` ∈ [0, 1], the Fresnel transition of Wu et al. (2001) with the phase
    variable ``Q = (kσ)²`` (module docstring: why not ``(kσ cosθ)²``), at incidence cosine
    ``cs``, normalized roughness ``ks = kσ`` and scaled spectral argument ``K`` (as for
    ``log_w``, the n-fold spectrum of :func:`emscatter.solvers.kirchhoff.po.log_nfold`).

    With ``S(βQ) = Σₙ (βQ)ⁿ/n! Ŵₙ(K)``, ``c = cosθ`` and ``F_t c = 8R₀² sin²θ (c + q₂)/q₂``
    (finite at grazing), the ratio of the papers is
    ``|F_t c + 8R₀|² S(Q) / [|F_t c|² S(Q) + 8 Re(F_t c R₀*) e^{−Q} S(2Q)
    + 16 |R₀|² e^{−2Q} S(4Q)]`` for v (``R₀ = R_v(0)``) and the same with ``F_t → −F_t`` for h
    (the h complementary coefficient at ``R_h(0) = −R_v(0)`` is ``−F_t``, the Kirchhoff one
    ``f_hh(R_h(0)) = f_vv(R_v(0))``). The sums are :func:`transition_sums`."""
    cs = np.asarray(cs, dtype=float)
    Kb = np.broadcast_to(np.asarray(K, dtype=float), cs.shape).ravel()
    l1, l2, l4 = transition_sums(ks, log_w, Kb, rtol=rtol)
    return transition_from_sums(eps, cs, ks, *(v.reshape(cs.shape) for v in (l1, l2, l4)))


def transition_sums(ks: float, log_w, K, *, rtol: float = 1e-10, max_terms: int = 10**6):
    """``(log S(Q), log S(2Q), log S(4Q))``, ``S(βQ) = Σ_{n≥1} (βQ)ⁿ/n! Ŵₙ(K)``,
    ``Q = (kσ)²`` (:func:`transition_q`), for each element of ``K`` (1-D). A table of
    ``n log Q − log n! + log Ŵₙ(K)`` (:func:`emscatter.solvers.iem.series.orders_table`), as
    long as the Poisson tail of ``4Q`` asks, lengthened (×2) until every row's terms decrease
    at its end with a geometric tail bound below ``rtol`` of its sum (a spectrum that grows
    with n, e.g. a Gaussian at a large Bragg argument, moves the mass to higher orders); rows
    in chunks of at most ~2e6 table entries."""
    from emscatter.solvers.iem.series import _orders_needed

    K = np.asarray(K, dtype=float).ravel()
    N0 = int(_orders_needed(np.array([4.0 * transition_q(ks)]), math.log(rtol))[0]) + 4
    out = [np.empty(K.size) for _ in range(3)]
    step = max(1, int(2e6 // N0))
    for a in range(0, K.size, step):
        for o, v in zip(out, _transition_rows(ks, log_w, K[a : a + step], N0, rtol, max_terms),
                        strict=True):  # fmt: skip
            o[a : a + step] = v
    return out[0], out[1], out[2]


def _transition_rows(ks, log_w, K, N, rtol, max_terms):
    """:func:`transition_sums` for one chunk of rows, starting from ``N`` orders."""
    from emscatter.solvers.iem.series import orders_table

    while True:
        table = orders_table(2.0 * math.log(ks), log_w, K, N)
        n = np.arange(1.0, N + 1.0)
        out, ok = [], True
        for b in (1.0, 2.0, 4.0):
            t = table + n[None, :] * math.log(b)
            top = np.max(t, axis=1)
            top = np.where(np.isfinite(top), top, 0.0)
            ls = top + np.log(np.exp(t - top[:, None]).sum(axis=1))
            with np.errstate(invalid="ignore", divide="ignore"):
                r = np.exp(t[:, -1] - t[:, -2])  # N ≥ 5: the last term ratio
                r = np.where(np.isnan(r), 0.0, np.minimum(r, 1.0))  # −inf terms: none left
                tail = t[:, -1] + np.log(r) - np.log1p(-r)  # r = 1: infinite, not converged
                rel = np.where(np.isfinite(ls), tail - ls, -np.inf)
            ok = ok and bool(np.all(~(rel > math.log(rtol))))
            out.append(ls)
        if ok or N >= max_terms:
            return out
        N = min(2 * N, max_terms)


def transition_q(ks: float) -> float:
    """The transition's phase variable ``Q = (kσ)²`` [-] (module docstring): the sums
    ``S(βQ)`` of :func:`transition_from_sums` are taken at ``βQ``, β = 1, 2, 4."""
    return float(ks) * float(ks)


def transition_from_sums(eps, cs, ks: float, l1, l2, l4):
    """``(γ_h, γ_v)`` from ``l_β = log S(βQ)``, ``Q = (kσ)²`` (:func:`transition_factor`,
    :func:`transition_q`); ``cs`` enters through ``F_t`` only."""
    cs = np.asarray(cs, dtype=float)
    s2 = 1.0 - cs * cs
    sq = np.sqrt(eps)
    r0 = (sq - 1.0) / (sq + 1.0)
    q2 = branch_root(eps - s2)
    ftc = 8.0 * r0 * r0 * s2 * (cs + q2) / q2
    Q = transition_q(ks)
    with np.errstate(invalid="ignore", over="ignore"):
        e2 = np.exp(np.minimum(np.asarray(l2) - l1 - Q, 700.0))
        e4 = np.exp(np.minimum(np.asarray(l4) - l1 - 2.0 * Q, 700.0))
    e2 = np.where(np.isnan(e2), 2.0, e2)  # S = 0 (no spectrum left): the n = 1 ratios
    e4 = np.where(np.isnan(e4), 4.0, e4)
    a0 = 16.0 * np.abs(r0) ** 2
    out = []
    for f in (-ftc, ftc):  # h, v
        num = np.abs(f + 8.0 * r0) ** 2
        den = np.abs(f) ** 2 + 8.0 * (f * np.conj(r0)).real * e2 + a0 * e4
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.where(den > 0, num / np.where(den > 0, den, 1.0), 1.0)
        out.append(np.clip(1.0 - ratio, 0.0, 1.0))
    return out[0], out[1]
