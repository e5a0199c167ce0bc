"""Cross-polarized multiple scattering of the integral-equation model at any bistatic geometry.

The term (backscatter)
----------------------
Fung, Li & Chen (IEEE TGRS 30, 356, 1992, appendix) and Fung (1994, *Microwave Scattering and
Emission Models*, ch. 4), in the form of Ulaby & Long (2014, §10-3.9, code 10.1 ``IEMX``) and
SMRT's ``iiem_fung02``::

    σ⁰_hv = S(θ) (1/8π) e^{−2Q} ∫∫_{|r|<1} |F_hv(r)|² Σₙ Σₘ Qⁿ⁺ᵐ/(n! m!) Ŵₙ(k|r − ŝ|)
            Ŵₘ(k|r + ŝ|) S_m(r) d²r,      Q = (kσ cosθ)²,  ŝ = (sinθ, 0),

``F_hv = (uv/cosθ)[(b − c)(1 − 3R) − (b − c/ε)(1 + R) + (a − d)(1 + 3R) − (a − dε)(1 − R)]``,
``a, b = (1 ± R)/q``, ``c, d = (1 ± R)/q_t``, ``q = √(1 − r²)``, ``q_t = √(ε − r²)``,
``R = (R_v − R_h)/2`` at θ; ``S_m`` the Smith shadowing of the intermediate wave (it makes the
``1/q²`` horizon divergence of ``|F|²`` integrable), ``S`` the monostatic shadowing.

Where it comes from, and its bistatic form
------------------------------------------
``F_hv`` is the complementary-field coefficient of the IEM evaluated at an *arbitrary*
intermediate transverse wavevector ``−(u, v)`` rather than at the stationary points of single
scattering: the cross-polarized combination (Chen, Wu, Tsang, Li, Shi & Fung, IEEE TGRS 41, 90,
2003, appendix B, :func:`emscatter.solvers.iem.terms._combine`) of the coefficients ``B₁…B₆``
(their appendix
C) with both slope pairs present, the slopes eliminated as in the 1992 model (the Green's-
function phase dropped): ``(z_x, z_y) = −(k_sx + u, k_sy + v)/k_sz`` at the last scattering
point and ``(z'_x, z'_y) = (k_x + u, k_y + v)/k_z`` at the first. The appendix coefficients are
affine in ``q``, so the upward (``+q``) and downward (``−q``) terms sum to twice their
``q = 0`` part, and

    F_qp(u, v) = ½ Σ_{±q, ±q_t} (appendix-B combination) = [U_qp(B⁰)]/q + [L_qp(B⁰)]/q_t,

``B⁰`` the appendix coefficients at ``q = 0`` (upper ``U`` and lower-medium ``L``
combinations). In backscatter this *is* Fung's ``F_hv`` above (identity checked symbolically
and in ``tests/test_iem_crosspol.py``), for any ``θs, φs`` it is the bistatic kernel.

The spectral weights come from the Gaussian average of the four heights of ``|E_c|²`` (two
scattering points per path) exactly as in the 1992 derivation: pairing the last points of the
two paths (weight ``σ²k_sz²``) and the first points (``σ²k_z²``) — the *ladder* — gives

    L(r) = e^{−Q_s − Q_i} Σₙ Q_sⁿ/n! Ŵₙ(K_s) Σₘ Q_iᵐ/m! Ŵₘ(K_i),   K_s = k|k̂_s⊥ + r|,
                                                                 K_i = k|k̂_i⊥ + r|,

``Q_s = (kσ cosθs)²``, ``Q_i = (kσ cosθi)²``; pairing each path with its reversed partner (the
*crossed* pairing, last point with first, weight ``σ²k_z k_sz``) gives ``X(r)``, the same with
``c = (kσ)² cosθi cosθs`` in both sums. In backscatter ``L = X`` — the published ``1/8π`` is
``(L + X)/16π``. So, for any geometry::

    σ⁰_qp(i→s) = S_b (1/16π) ∫∫_{|r|<1} [L(r) + X(r)] |F_qp(r)|² S_m(r) d²r.

What is approximated (beyond the 1992 IEM itself)
-------------------------------------------------
* **The crossed pairing's kernel.** Its exact form is ``Re F(r) F*(r')``,
  ``r' = −(k̂_s⊥ + k̂_i⊥) − r`` (the reversed path); here ``|F(r)|²`` is used, as in
  backscatter (where ``r' = −r`` and ``F`` is even). Reason: at small roughness, second-order
  SPM — the exact limit — has the crossed pairing *identical* to the ladder at every geometry
  (its second-order kernel is symmetric under ``r ↔ r'``), and it is smooth through
  backscatter (:mod:`emscatter.solvers.spm.crosspol`, validation/iem/README.md), whereas
  ``F(r)F*(r')`` with
  the IEM's ``1/q`` horizon singularity makes a ``√δ`` cusp at backscatter (0.2 dB within
  0.01°, 1 dB within 1°; measured) that SPM2 does not have. The crossed pairing keeps its own
  height weights, ``X ≤ L`` away from backscatter (``X/L → e^{−(kσ)²(cosθi − cosθs)²}``-like
  decorrelation in elevation); in azimuth at ``θs = θi`` the two are equal, as in SPM2.
* **Reciprocity.** ``F`` uses ``R(θi)`` (1992 model); the result is symmetrized,
  ``½[σ⁰_qp(i→s) + σ⁰_pq(−s→−i)]`` (the reversed path's kernel at ``−r``, same weights): exactly
  reciprocal, a single value in backscatter.
* **Shadowing.** ``S_m`` as in backscatter; the outer ``S_b`` is the direction-correlated form
  of :mod:`emscatter.solvers.iem.model` (``1/(1 + Λ)`` in backscatter), always applied to this term.
* Against second-order SPM at kσ = 0.05 (validation/iem/, tested): in the plane of incidence
  (where single scattering has no cross-polarization, so this is the whole fourth-order hv)
  within ~2.6 dB in backscatter and ~4.4 dB over θs ≤ 40° for kℓ = 3–6 (crosspol_spm2.md);
  far lower for kℓ ≲ 1 (backscatter −6 dB at kℓ = 1, −15 dB at kℓ = 0.5; Gaussian), where
  SPM2's hv comes mostly from evanescent intermediate waves
  (``|r| > 1``), which the IEM omits. Out of
  the plane, SPM2's fourth order also holds single-scattering parts (the IEM's n = 2 terms) and
  ``2Re⟨a₁a₃*⟩``, so there this term alone is not comparable.
* Co-polarized multiple scattering is not included (see :mod:`emscatter.solvers.iem.model`).

Numerics
--------
``F̃ = cosθi cosθs F`` is a polynomial over ``q, q_t`` (finite at grazing);
``(kσ)⁴|F̃|² T(Q_s, K_s) T(Q_i, K_i)`` replaces ``L|F|²`` with the physical-optics series
``T(Q, K) = e^{−Q} Σ Q^{n−1}/n! wₙ(K)`` (:func:`emscatter.solvers.kirchhoff.po.series_sum`).
``log T`` is tabulated per roughness and ``k`` on ``(log Q, log(1 + K))`` (128 × 1024
nodes, summed to 1e-10; rows on demand) and interpolated bicubically (Catmull–Rom; ≲ 1e-4
relative where ``T`` matters). The integral over ``r = sin t`` uses products of
geometrically graded Gauss–Legendre rules (``order`` nodes per segment): in ``t`` graded toward
θi, θs and the horizon (width of the shadowing, ~slope), in azimuth toward the two spectral
peaks ``−k̂_i⊥``, ``−k̂_s⊥``; against order 24: ≲ 1e-2 relative at order 8 (the default
``crosspol_order`` of :func:`.iem.bistatic`), ≲ 1e-3 at 12 (tested). Compiled kernel:
:mod:`emscatter.solvers.iem.kernels.crosspol` (``EMSCATTER_KERNELS``), same formulas and tables.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from emscatter.fresnel import fresnel_cos, is_pec
from emscatter.solvers.iem.crosspol_terms import gauss_legendre, slope_coefficients  # noqa: F401
from emscatter.solvers.iem.terms import _combine, branch_root
from emscatter.solvers.kirchhoff.common import _trig, smith_lambda
from emscatter.solvers.kirchhoff.po import log_nfold, series_sum

__all__ = ["multiple_scattering", "backscatter", "kernel_coefficients"]

_S_SPAN = 14.0  # table range in log Q below (kσ)²: Q/Q_max ≥ 8e-7 (θ ≤ 89.95°)
_N_S, _N_X = 128, 1024
_CHUNK = 1 << 20  # (geometry, node) elements per numpy block


def _log_T(rough, log_w, Q, K):
    """log of the physical-optics series ``T(Q, K)`` (compiled sums where
    :mod:`emscatter.solvers.iem.compiled`
    covers the correlation)."""
    from emscatter.solvers.iem import compiled as iem_jit

    spec = iem_jit.spectrum_code(rough) if iem_jit.enabled() else None
    if spec is None or np.any(Q <= 0):
        return series_sum(log_w, Q, K, rtol=1e-10)
    lq = np.log(Q)
    return iem_jit.poisson_sums(lq, K, spec, rough.dimension, rtol=1e-10) - lq - Q


class SeriesTable:
    """``log T(Q, K)`` on a uniform grid in ``s = log Q`` and ``x = log(1 + K)``, padded by one
    node below and two above in each variable for Catmull–Rom interpolation. Rows (``s``) are
    summed on demand (:meth:`fill`): a few geometries need a few rows, and at large kσ each row
    costs ~(kσ)² series terms per node."""

    __slots__ = ("values", "filled", "rough", "s0", "hs", "ns", "hx", "nx")

    def __init__(self, rough, k: float):
        ks = k * rough.sigma
        s_max = 2.0 * math.log(ks)
        self.rough = rough
        self.s0, self.hs, self.ns = s_max - _S_SPAN, _S_SPAN / (_N_S - 1), _N_S
        x_max = math.log1p(2.0 * k * max(rough.length, rough.length_y))
        self.hx, self.nx = x_max / (_N_X - 1), _N_X
        self.values = np.zeros((_N_S + 3, _N_X + 3))
        self.filled = np.zeros(_N_S + 3, dtype=bool)

    def fill(self, Q) -> None:
        """Sum the rows that interpolation at ``Q`` (any shape) reads, where not yet done."""
        i, _ = self.position_s(np.unique(np.asarray(Q, dtype=float)))
        rows = np.unique((i[:, None] + np.arange(-1, 3)[None, :]).ravel())
        rows = rows[~self.filled[rows]]
        if not rows.size:
            return
        s = self.s0 + self.hs * (rows - 1.0)
        x = self.hx * np.arange(-1, _N_X + 2)
        S, X = np.meshgrid(s, x, indexing="ij")
        K = np.abs(np.expm1(X))  # T is even in K: the x < 0 pad continues it analytically
        vals = _log_T(self.rough, log_nfold(self.rough), np.exp(S).ravel(), K.ravel())
        self.values[rows] = vals.reshape(S.shape)
        self.filled[rows] = True

    def position_s(self, Q):
        """Row index ``i`` (≥ 1) and fraction for ``log Q`` (clamped to the table)."""
        with np.errstate(divide="ignore"):
            p = (np.log(np.asarray(Q, dtype=float)) - self.s0) / self.hs
        p = np.clip(p, 0.0, self.ns - 1.0)
        i = np.minimum(np.floor(p).astype(np.int64), self.ns - 2)
        return i + 1, p - i


@lru_cache(maxsize=16)
def series_table(rough, k: float) -> SeriesTable:
    """The cached :class:`SeriesTable` of a roughness at wavenumber ``k``."""
    return SeriesTable(rough, k)


def _catmull_rom(f):
    f2 = f * f
    f3 = f2 * f
    return (-0.5 * f3 + f2 - 0.5 * f, 1.5 * f3 - 2.5 * f2 + 1.0, -1.5 * f3 + 2.0 * f2 + 0.5 * f,
            0.5 * f3 - 0.5 * f2)  # fmt: skip


def _rows(table: SeriesTable, Q):
    """``log T(Q, ·)`` on the x grid per geometry (interpolated in s): (G, nx + 3)."""
    i, f = table.position_s(Q)
    w = _catmull_rom(f)
    v = table.values
    return sum(w[a][:, None] * v[i - 1 + a] for a in range(4))


def _lookup(rows, table: SeriesTable, K):
    """Catmull–Rom interpolation of per-geometry rows (G, nx + 3) at K (G, ...)."""
    p = np.minimum(np.log1p(K) / table.hx, table.nx - 1.0)
    j = np.minimum(np.floor(p).astype(np.int64), table.nx - 2)
    w = _catmull_rom(p - j)
    g = np.arange(rows.shape[0]).reshape((-1,) + (1,) * (K.ndim - 1))
    return sum(w[a] * rows[g, j + a] for a in range(4))


# ----------------------------------------------------------------------------- kernel
_ZERO_C = (0.0,) * 5


def kernel_coefficients(R, eps):
    """``γ[medium, pol, j]``: ``F̃_pol = Σⱼ γ[0, pol, j] B⁰ⱼ / q + Σⱼ γ[1, pol, j] B⁰ⱼ / q_t``
    (pol 0 = hv, 1 = vh; :func:`emscatter.solvers.iem.terms._combine` applied to unit
    coefficients), complex,
    shape (2, 2, 6, *R.shape); ``eps="pec"``: no lower medium (``R = 1``)."""
    R = np.asarray(R, dtype=complex)
    out = np.zeros((2, 2, 6, *R.shape), dtype=complex)
    lead = (1,) * R.ndim  # the six unit coefficient vectors on a leading axis: one call each
    unit = tuple(np.eye(6)[j].reshape(6, *lead) for j in range(6))
    pec = is_pec(eps)
    e = 1.0 if pec else np.asarray(eps, dtype=complex)[None]
    for medium in (0,) if pec else (0, 1):
        res = _combine(_ZERO_C, unit, (0.0, 0.0), R[None], 1.0, e, medium == 1)
        out[medium, 0], out[medium, 1] = res[1], res[2]
    return out


def kernel(si, cs, ss, css, sf, cf, u, v, eps, gamma, q=None):
    """``(F̃_hv, F̃_vh)`` at ``(u, v)`` with the coefficients of :func:`kernel_coefficients`
    (``gamma`` broadcast against ``u``); ``q = √(1 − u² − v²)`` if known."""
    B = slope_coefficients(si, cs, ss, css, sf, cf, u, v)
    r2 = u * u + v * v
    q2 = 1.0 - r2 if q is None else q * q
    inv_q = 1.0 / np.sqrt(np.maximum(q2, 1e-24))
    out = []
    for pol in (0, 1):
        f = sum(gamma[0, pol, j] * B[j] for j in range(6)) * inv_q
        if not is_pec(eps):
            qt = branch_root(eps - r2)
            qt = np.where(np.abs(qt) > 1e-12, qt, 1e-12)  # ε = 1 at the horizon only
            f = f + sum(gamma[1, pol, j] * B[j] for j in range(6)) / qt
        out.append(f)
    return out[0], out[1]


# ----------------------------------------------------------------------------- nodes
def graded(c, e, w, tau, wtau):
    """Nodes from ``c`` toward ``e`` (arrays, per geometry), geometric grading with finest
    scale ``w``: ``x = c + (e − c)((1 + λ)^τ − 1)/λ``, ``λ = |e − c|/w``, τ Gauss–Legendre."""
    c, e, w = (np.asarray(a, dtype=float)[..., None] for a in (c, e, w))
    L = np.abs(e - c)
    lam = L / w
    flat = lam < 1e-8
    lam = np.where(flat, 1.0, lam)
    ll = np.log1p(lam)
    g = np.where(flat, tau, np.expm1(tau * ll) / lam)
    dg = np.where(flat, 1.0, ll * np.exp(tau * ll) / lam)
    return c + (e - c) * g, L * dg * wtau


def finest_scales(rough, k: float, slope) -> tuple[float, float]:
    """(spectral, horizon) finest grading scales: ``min(0.25, 1/kℓ)/2`` and half the smallest
    nominal slope (the width of the intermediate-wave shadowing at the horizon)."""
    kl = k * min(rough.length, rough.length_y)
    return 0.5 * min(0.25, 1.0 / kl), 0.5 * min(min(slope), 1.0)


def radial_segments(ti, ts, w, w_rim):
    """(center, end, finest scale) of the five graded segments in ``t`` (``r = sin t``)."""
    lo, hi = np.minimum(ti, ts), np.maximum(ti, ts)
    w_lo = np.minimum(w / np.maximum(np.cos(lo), w), 1.0)
    w_hi = np.minimum(w / np.maximum(np.cos(hi), w), 1.0)
    mid, top = 0.5 * (lo + hi), 0.5 * (hi + 0.5 * math.pi)
    edge = np.full_like(hi, 0.5 * math.pi)
    return [(lo, 0.0 * lo, w_lo), (lo, mid, w_lo), (hi, mid, w_hi), (hi, top, w_hi),
            (edge, top, np.full_like(hi, w_rim))]  # fmt: skip


def azimuth_segments(si, ss, dphi, w):
    """(center, end, finest scale) of the four graded azimuth segments (centers π and
    π + Δφ: the two spectral peaks at ``−k̂_i⊥`` and ``−k̂_s⊥``)."""
    d = np.mod(dphi, 2.0 * math.pi)
    a1 = np.full_like(d, math.pi)
    a2 = a1 + d
    m1, m2 = a1 + 0.5 * d, a2 + 0.5 * (2.0 * math.pi - d)
    wi = np.minimum(w / np.maximum(si, w), 1.0)
    ws = np.minimum(w / np.maximum(ss, w), 1.0)
    return [(a1, m1, wi), (a2, m1, ws), (a2, m2, ws), (a1 + 2.0 * math.pi, m2, wi)]


def _nodes(segments, tau, wtau):
    parts = [graded(c, e, w, tau, wtau) for c, e, w in segments]
    return np.concatenate([p[0] for p in parts], -1), np.concatenate([p[1] for p in parts], -1)


def intermediate_shadowing(r, q, alpha, slope):
    """Smith shadowing ``1/(1 + Λ)`` of the intermediate wave (``a = q/(r √2 s(α))``,
    ``α`` its azimuth in the surface frame)."""
    sx, sy = slope
    s2 = (sx * np.cos(alpha)) ** 2 + (sy * np.sin(alpha)) ** 2
    with np.errstate(divide="ignore"):
        a = np.where(r > 0, q / (np.maximum(r, 1e-300) * np.sqrt(2.0 * s2)), np.inf)
    return 1.0 / (1.0 + smith_lambda(np.minimum(a, 1e300)))


# ----------------------------------------------------------------------------- term
def multiple_scattering(rough, eps, k: float, theta_i, theta_s, dphi, phi_i, *, slope, shadow,
                        order: int = 12):  # fmt: skip
    """Multiple-scattering ``(σ⁰_hv, σ⁰_vh)`` [-] (module docstring) on flat geometry arrays
    (broadcast together): angles [rad], ``dphi = φs − φi``; ``eps`` complex (scalar or per
    geometry) or ``"pec"``; ``slope = (s_x, s_y)`` nominal rms slopes; ``shadow`` the outer
    (bistatic) shadowing factor per geometry; ``order`` nodes per graded segment."""
    ti, ts, dp, pi_, sh = np.broadcast_arrays(*(np.asarray(a, dtype=float).ravel()
                                                 for a in (theta_i, theta_s, dphi, phi_i,
                                                           shadow)))  # fmt: skip
    G = ti.size
    pec = is_pec(eps)
    eps_g = None if pec else np.broadcast_to(np.asarray(eps, dtype=complex).ravel(), (G,))
    si, cs, ss, css = np.sin(ti), np.cos(ti), np.sin(ts), np.cos(ts)
    sf, cf = np.sin(dp), np.cos(dp)
    rh, rv = fresnel_cos("pec" if pec else eps_g, cs)
    gam = kernel_coefficients(0.5 * (rv - rh), "pec" if pec else eps_g)
    if np.array_equal(ti, ts):  # (θs = θi: the reversed path's coefficients are the same)
        gam_r = gam
    else:
        rh_r, rv_r = fresnel_cos("pec" if pec else eps_g, css)
        gam_r = kernel_coefficients(0.5 * (rv_r - rh_r), "pec" if pec else eps_g)
    ks = k * rough.sigma
    table = series_table(rough, float(k))
    Qs = ((ks * css) ** 2, (ks * cs) ** 2, ks * ks * cs * css)  # last, first point; crossed
    table.fill(np.concatenate(Qs))
    decor = np.exp(-((ks * (cs - css)) ** 2))
    norm = ks**4 * (2.0 * math.pi * k * rough.length * k * rough.length_y) ** 2 / (16.0 * math.pi)
    w, w_rim = finest_scales(rough, k, slope)
    args = (ti, ts, si, cs, ss, css, sf, cf, dp, pi_, eps_g, gam, gam_r, Qs, decor)
    from emscatter.solvers.iem import compiled as iem_jit

    if iem_jit.enabled():
        from emscatter.solvers.iem.kernels.crosspol import integrate

        hv, vh = integrate(rough, k, table, args, slope, w, w_rim, int(order), pec)
    else:
        hv, vh = _integrate_numpy(rough, k, table, args, slope, w, w_rim, int(order), pec)
    # a geometry that is its own reverse (backscatter): hv = vh exactly, not just to rounding
    own = (np.abs(si - ss) <= 1e-12) & (np.abs(np.mod(dp, 2.0 * math.pi) - math.pi) <= 1e-9)
    hv = np.where(own, 0.5 * (hv + vh), hv)
    vh = np.where(own, hv, vh)
    return norm * sh * hv, norm * sh * vh


def backscatter(rough, eps, k: float, theta, phi_i, *, slope, order: int = 8) -> np.ndarray:
    """Multiple-scattering ``σ⁰_hv = σ⁰_vh`` [-] in backscatter (``θs = θi``, ``φs = φi + π``)
    at the flat angles ``theta``, ``phi_i`` [rad] (broadcast together; checked by the caller),
    ``eps`` complex (scalar or per angle) or ``"pec"``, ``slope`` the nominal rms slopes
    ``(s_x, s_y)``: what :func:`emscatter.solvers.iem.model.bistatic` adds there
    (``_add_crosspol`` on that geometry, with its direction-correlated outer shadowing
    ``1/(1 + max Λ + c(ψ) min Λ)``, :mod:`emscatter.solvers.iem.shadowing`), without building
    the bistatic geometry (tested equal)."""
    ti, pi_ = np.broadcast_arrays(*(np.asarray(a, dtype=float).ravel() for a in (theta, phi_i)))
    ps = pi_ + math.pi
    dp = ps - pi_  # φs − φi as the geometry has it
    si, ci = _trig(ti)
    sx, sy = slope

    def lam(phi):  # shadowing._shadowing's Smith Λ of one direction
        s2 = (sx * np.cos(phi)) ** 2 + (sy * np.sin(phi)) ** 2 if sx != sy else sx * sx
        den = si * np.sqrt(2.0 * s2)
        a = np.where(den > ci * 1e-300, ci / np.where(den > 0, den, 1.0), 1e300)
        return smith_lambda(np.minimum(a, 1e300))

    lam_i = lam(pi_)
    lam_s = lam_i if sx == sy else lam(ps)
    psi = np.abs(np.mod(ps - pi_ - math.pi + math.pi, 2 * math.pi) - math.pi)
    corr = 4.41 * psi / (4.41 * psi + 1.0)
    shadow = 1.0 / (1.0 + np.maximum(lam_i, lam_s) + corr * np.minimum(lam_i, lam_s))
    hv, _ = multiple_scattering(rough, eps, k, ti, ti, dp, pi_, slope=(sx, sy), shadow=shadow,
                                order=order)  # fmt: skip
    return hv


def _integrate_numpy(rough, k, table, args, slope, w, w_rim, order, pec):
    """The reference integral (vectorized over geometry chunks × nodes)."""
    ti, ts, si, cs, ss, css, sf, cf, dp, pi_, eps_g, gam, gam_r, Qs, decor = args
    G = si.size
    tau, wtau = gauss_legendre(order)
    per = 5 * order * 4 * order
    step = max(1, _CHUNK // per)
    hv, vh = np.zeros(G), np.zeros(G)
    klx, kly = k * rough.length, k * rough.length_y
    for a in range(0, G, step):
        g = slice(a, a + step)
        t, wt = _nodes(radial_segments(ti[g], ts[g], w, w_rim), tau, wtau)
        al, wa = _nodes(azimuth_segments(si[g], ss[g], dp[g], w), tau, wtau)
        e3 = lambda x: np.asarray(x)[:, None, None]  # noqa: E731
        r, q = np.sin(t)[:, :, None], np.cos(t)[:, :, None]
        u, v = r * np.cos(al)[:, None, :], r * np.sin(al)[:, None, :]
        jac = (wt * np.sin(t) * np.cos(t))[:, :, None] * wa[:, None, :]
        geo = [e3(x[g]) for x in (si, cs, ss, css, sf, cf)]
        rev = [e3(x[g]) for x in (ss, css, si, cs, -sf, cf)]
        eps_c = "pec" if pec else e3(eps_g[g])
        f_hv, f_vh = kernel(*geo, u, v, eps_c, gam[..., g, None, None], q)
        ur, vr = u * e3(cf[g]) + v * e3(sf[g]), v * e3(cf[g]) - u * e3(sf[g])
        b_hv, b_vh = kernel(*rev, ur, vr, eps_c, gam_r[..., g, None, None], q)
        cp, sp = e3(np.cos(pi_[g])), e3(np.sin(pi_[g]))

        def scaled(dx, dy, cp=cp, sp=sp):  # |·| of a transverse vector in the surface frame
            X, Y = cp * dx - sp * dy, sp * dx + cp * dy
            return np.sqrt((X * klx) ** 2 + (Y * kly) ** 2)

        Ki = scaled(geo[0] + u, v + 0.0 * geo[0])
        Ks = scaled(geo[2] * geo[5] + u, geo[2] * geo[4] + v)
        ls, li, lc = (_rows(table, x[g]) for x in Qs)
        weight = np.exp(_lookup(ls, table, Ks) + _lookup(li, table, Ki))
        weight += e3(decor[g]) * np.exp(_lookup(lc, table, Ks) + _lookup(lc, table, Ki))
        alpha = al[:, None, :] + e3(pi_[g])  # intermediate-wave azimuth, surface frame
        weight *= jac * intermediate_shadowing(r, q, alpha, slope)
        hv[g] = 0.5 * np.sum(weight * (np.abs(f_hv) ** 2 + np.abs(b_vh) ** 2), axis=(1, 2))
        vh[g] = 0.5 * np.sum(weight * (np.abs(f_vh) ** 2 + np.abs(b_hv) ** 2), axis=(1, 2))
    return hv, vh
