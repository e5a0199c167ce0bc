"""Kirchhoff approximation, physical optics in the scalar approximation (series form).

Surface (``dimension=2``, per unit area)::

    σ⁰_pq = |q|⁴/(4π q_z²) |F_pq|² ∫ d²r e^{i q⊥·r} [e^{−q_z²σ²(1−ρ(r))} − e^{−q_z²σ²}]
          = π |q|⁴ σ² |F_pq|² · e^{−Q} Σ_{n≥1} Q^{n−1}/n! · w_n(q_x, q_y),   Q = q_z² σ²

with ``w_n`` the normalized spectrum of ``ρⁿ`` (:meth:`Roughness.nfold_spectrum`, the
``1/(2π)²`` transform: ``∫ρⁿ e^{iK·r} d²r = (2π)² w_n``). Ulaby, Moore & Fung (1982) vol. II
§12-4 (eqs. 12.52–12.55; their ``W⁽ⁿ⁾ = 2π w_n``) and Tsang, Kong & Ding (2001) vol. III ch. 2;
at backscatter this is ``σ⁰ = 2k²|R(0)|²/cos²θ e^{−Q} Σ Qⁿ/n! W⁽ⁿ⁾(2k sinθ)``, Fung's
Kirchhoff term. Profile (``dimension=1``, per unit length; 2-D Green's function
``(i/4) H₀⁽¹⁾``, its far field ``|G|² = 1/(8πkρ)``)::

    σ⁰_pp = |q|⁴/(4 k q_z²) |F_pp|² ∫ dx e^{i q_x x}[…] = π |q|⁴ σ² |F_pp|²/(2k) · e^{−Q} Σ …

Polarization amplitudes ``F_pq``: Fresnel coefficients at the **local specular angle**
``cosθl = |q|/(2k)`` with the polarization mixing of the stationary-phase facet
(:mod:`emscatter.solvers.kirchhoff.common`; Tsang et al. 2001 vol. III ch. 2 — the "Kirchhoff
approximation
with stationary-phase polarization factors"). At backscatter this is Ulaby's ``R(0)``; in the
specular direction it is ``R(θi)``, and as ``kσ → ∞`` (fixed slope) the series becomes the
geometric-optics result of :mod:`emscatter.solvers.kirchhoff.go` (tested).

Numerics. Terms are summed in log space,
``log t_n = (n−1) log Q − lgamma(n+1) − Q + log w_n``, starting at the (located) largest term
and walking up and down in blocks until the geometric bound on the remaining tail
(the log-terms are concave in n past the first few) is below ``rtol`` of the sum. No
overflow for any ``Q`` (tested from kσ = 1e-4 to 100, where ~10⁴ terms are needed).
Writing ``Q^{n−1}`` (not ``Qⁿ/q_z²``) keeps forward-grazing ``q_z → 0`` finite.

``w_n``: closed forms for the Gaussian (``ρⁿ``: Gaussian of length ``ℓ/√n``) and exponential
(``ℓ/n``) correlations; for the power law (Matérn, Hurst ``H``) a table per (H, dimension)
built once (cached) by product integration of ``ρⁿ`` against the exact Bessel/cosine kernel in
the scaled variable ``t = u/u_n``, ``u_n = (n c)^{−1/(2H)}``, ``1 − ρ ≈ c u^{2H}``; log w_n is
interpolated bilinearly in (log n, log s) for ``s ≤ 30``, clamped to the scaling limit for
n > 1e8; beyond ``s = 30`` the asymptotic (stable-law) series of :func:`_powerlaw_tail`
(accuracy ~1e-3, tested against ``H = 1/2``, the exponential correlation).
"""

from __future__ import annotations

import functools
import math
from concurrent.futures import ThreadPoolExecutor

import numpy as np
from scipy import special

from emscatter.conventions import check_angle, check_positive
from emscatter.fresnel import check_eps, is_pec
from emscatter.scattering import Scattering
from emscatter.solvers.kirchhoff import compiled as kirchhoff_compiled
from emscatter.solvers.kirchhoff.common import (
    check_flag,
    check_roughness,
    coherent_local,
    fresnel_factors,
    geometry,
    grazing_parameter,
    tangent_plane_checks,
    workers_for,
)
from emscatter.solvers.validity import (
    angle_lower,
    build_report,
    check_solver_options,
    lower,
    upper,
    wave_slope_variances,
)
from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation, PowerLawCorrelation

__all__ = ["bistatic", "check_validity", "VALIDITY", "series_sum", "log_nfold"]

#: Validity of the scalar (physical-optics) Kirchhoff approximation. Textbook limits (Ulaby,
#: Moore & Fung 1982 vol. II §12-4, Table 12.2): ``kℓ > 6``, ``ℓ² > 2.76 σλ``, rms slope
#: ``m < 0.25``. Here ``kℓ > 4`` and ``m < 0.4``, from the method-of-moments validity maps
#: (validation/validity_maps/, 1-D Gaussian, θi = 20°, 128 realizations): PO σ⁰ is within 1 dB
#: for kℓ ≥ 5.8 and m ≤ 0.39 (PEC and ε = 3), but 1.1–1.9 dB off for PEC at kℓ ≈ 3.2 and
#: 1.3–1.8 dB at m ≈ 0.65. Outside every method's range, ``method="auto"`` takes the method
#: whose criteria are exceeded by the smallest factor (report ``"excess"``), which is PO in
#: those cells rather than SPM at kσ > 0.3 (1.3–17 dB off).
#: ``smoothness``: the tangent plane needs a locally smooth (differentiable) surface; the
#: exponential maps (validation/validity_maps, exp_*) find PO 1.1–2.2 dB off in v at every
#: kℓ ≤ 20 and kσ ≤ 0.8 (its local-specular polarization factor is wrong at the large angles
#: the algebraic tail scatters into), where the IEM is within 1 dB; ratio 1/H (2 for the
#: exponential) ranks PO as a fallback. The check applies to conductors (PEC, ``|ε| ≥ 100``,
#: or ``eps`` not given): over ε = 3 the same exponential surfaces give PO within 0.6–0.9 dB
#: at kσ ≈ 0.8 and kℓ ≥ 3 (validation/validity_maps, exp_eps3+0j) — the TM polarization factor
#: that fails is the conductor's.
#: Per angle (with ``theta_i``), ``grazing``: Kirchhoff without shadowing needs the grazing
#: angle large against the facet tilts, ``a = cotθi/(√2 s) ≥ a_min`` (``s`` the larger
#: per-direction rms slope; Smith's shadowing parameter, Smith 1967; Thorsos 1988 JASA 83,
#: 78, on the Kirchhoff approximation toward grazing). The limits are measured
#: (validation/angular_validity/energy_scan_summary.md, 2592 (roughness, ε, θi) cases): PO's
#: emissivity leaves [0, 1] by more than 0.01 for a conductor where ``a < 4.1`` (e down to
#: −0.23 at 75°, a = 0.8, where Smith's illuminated fraction is still 0.95: not shadowing
#: alone), for a dielectric (ε = 3, 17 + 2i) only where ``a < 0.75``: ``a_min`` = 4.5 for a
#: perfect conductor or ``|ε| ≥ 100`` (or when ``eps`` is not given), 1.0 otherwise.
#: Slopes of non-differentiable spectra are those of the spectrum below ``2k``
#: (:mod:`.validity`).
VALIDITY = {
    "k_l_min": 4.0,
    "curvature_factor": 2.76,
    "rms_slope_max": 0.4,
    "grazing_a_min": 4.5,
    "grazing_a_min_dielectric": 1.0,
    "conductor_abs_eps": 100.0,
    "smoothness_min": 1.0,
}

_SRC_H = (
    "tangent plane on a locally smooth surface (Ulaby, Moore & Fung 1982 §12-4); validity maps: "
    "PO 1.1–2.2 dB off (v) on exponential profiles at every kℓ ≤ 20"
)


def _conductor_like(eps) -> bool:
    """True for a perfect conductor, ``|ε| ≥ 100`` anywhere, or an unknown medium."""
    if eps is None:
        return True
    eps = check_eps(eps)
    if is_pec(eps):
        return True
    return bool(np.any(np.abs(np.asarray(eps)) >= VALIDITY["conductor_abs_eps"]))


def smoothness_exponent(rough) -> float:
    """``H`` of ``1 − ρ(r) ∝ r^{2H}`` at small lags: 1 for a differentiable correlation
    (finite slope variance: Gaussian, band-limited), ½ for the exponential, the Hurst
    exponent for the power law."""
    if rough._mss_closed() is not None:
        return 1.0
    if isinstance(rough, PowerLawCorrelation):
        return float(rough.hurst)
    if isinstance(rough, ExponentialCorrelation):
        return 0.5
    return 1.0


#: Options of :func:`bistatic` (what ``check_validity`` accepts).
OPTIONS = ("rtol", "max_terms", "threads", "coherent")

_SRC_M = "validity maps (validation/validity_maps); Ulaby, Moore & Fung 1982 Table 12.2"
_SRC_SH = (
    "Smith 1967; Thorsos 1988 JASA 83 78 (Kirchhoff toward grazing); limit from "
    "validation/angular_validity/energy_scan_summary.md"
)

_LOG_2PI = math.log(2 * math.pi)
_BLOCK = 1 << 15  # geometries per series block (one thread each)


def check_validity(roughness, k: float, *, eps=None, theta_i=None, **solver_options) -> dict:
    """Validity report (BOARD interface 1, :mod:`.validity`) for ``k`` [rad/m]; criteria in
    :data:`VALIDITY`. ``theta_i`` [rad] adds the per-angle grazing check; ``eps`` selects the
    conductor or dielectric limits (grazing, smoothness; a conductor when not given)."""
    check_solver_options("po", solver_options, OPTIONS)
    rough = check_roughness(roughness)
    k = check_positive("k", k, unit="rad/m")
    v = VALIDITY
    sx, sy, k_cut = wave_slope_variances(rough, k)
    m = math.sqrt(sx + sy)
    checks = [
        *tangent_plane_checks(rough, k, v),
        upper("rms_slope", m, v["rms_slope_max"], "total rms slope m", _SRC_M),
    ]
    if _conductor_like(eps):
        checks.append(
            lower(
                "smoothness",
                smoothness_exponent(rough),
                v["smoothness_min"],
                "exponent H of 1 − ρ(r) ∝ r^{2H} (1: differentiable; conductors)",
                _SRC_H,
            )
        )
    angle_checks = []
    ti = None
    if theta_i is not None:
        ti = check_angle("theta_i", theta_i)
        a_min = v["grazing_a_min"] if _conductor_like(eps) else v["grazing_a_min_dielectric"]
        angle_checks.append(
            angle_lower("grazing", grazing_parameter(ti, max(sx, sy)), a_min,
                        "a = cotθi/(√2 s) (grazing angle against the facet tilts)", _SRC_SH,
                        increasing=True)
        )  # fmt: skip
    return build_report(
        rough, k, checks, theta_i=ti, angle_checks=angle_checks, rms_slope=m, slope_cutoff=k_cut
    )


# ----------------------------------------------------------------------------- n-fold spectra
def log_nfold(roughness):
    """``f(n, K) = log(w_n / L)`` for the scaled wavenumber ``K`` (``√((qxℓx)²+(qyℓy)²)``,
    or ``|qx|ℓ`` for a profile), ``L = ℓxℓy`` (2-D) or ``ℓ`` (1-D); ``n`` ≥ 1 (float ok)."""
    d = roughness.dimension
    table = getattr(roughness, "log_nfold_table", None)
    if table is not None:  # a roughness that tabulates its own n-fold spectra
        return table()
    if isinstance(roughness, GaussianCorrelation):
        if d == 2:
            return lambda n, K: -math.log(4 * math.pi) - np.log(n) - K * K / (4 * n)
        c1 = -math.log(2 * math.sqrt(math.pi))
        return lambda n, K: c1 - 0.5 * np.log(n) - K * K / (4 * n)
    if isinstance(roughness, ExponentialCorrelation):
        if d == 2:
            return lambda n, K: -_LOG_2PI - 2 * np.log(n) - 1.5 * np.log1p((K / n) ** 2)
        return lambda n, K: -math.log(math.pi) - np.log(n) - np.log1p((K / n) ** 2)
    if isinstance(roughness, PowerLawCorrelation):
        table = _powerlaw_table(roughness.hurst, d)
        return functools.partial(_powerlaw_log_w, table)
    raise TypeError(
        "physical optics needs the n-fold spectrum of a GaussianCorrelation, "
        "ExponentialCorrelation, PowerLawCorrelation or MeasuredRoughness "
        f"(emscatter.surfaces.measured_roughness), got {type(roughness).__name__}"
    )


def _matern_one_minus_rho(u: np.ndarray, h: float) -> np.ndarray:
    """``1 − ρ(u)`` of the unit Matérn correlation, accurate for tiny u."""
    c = special.gamma(1 - h) / (special.gamma(1 + h) * 4**h)
    small = u < 1e-3
    us = np.where(small, u, 1.0)
    ul = np.where(small, 1.0, u)
    series = c * us ** (2 * h) - us * us / (4 * (1 - h))
    direct = 1.0 - 2 ** (1 - h) / special.gamma(h) * ul**h * special.kv(h, ul)
    return np.where(small, series, direct)


@functools.lru_cache(maxsize=16)
def _powerlaw_table(h: float, d: int):
    """Scaled transforms ``Ŵ_n(s)`` of ρⁿ for the Matérn correlation (module docstring)."""
    c = special.gamma(1 - h) / (special.gamma(1 + h) * 4**h)
    n_nodes = np.unique(np.concatenate([np.arange(1.0, 17.0), np.geomspace(16, 1e8, 57)]))
    u_n = (n_nodes * c) ** (-1 / (2 * h))
    t_hi = 1.5 * max(45.0 ** (1 / (2 * h)), 80.0 / u_n[0])
    nodes = np.concatenate([[0.0], np.geomspace(1e-9, t_hi, int(200 * math.log10(t_hi / 1e-9)))])
    a, b = nodes[:-1], nodes[1:]
    s_nodes = np.geomspace(1e-3, 1e3, 181)
    s = s_nodes[:, None]
    # ∫ f J0(st) t dt = −(1/s) ∫ f'(t) t J1(st) dt, f piecewise linear between nodes (exact
    # kernel integrals): ∫_0^X x J1(x) dx = −X J0(X) + ∫_0^X J0 (series for small X).
    if d == 2:

        def prim(x):
            xs = np.minimum(x, 1e-2)
            series = xs**3 / 6 - xs**5 / 80
            ij0 = special.itj0y0(x)[0]
            return np.where(x < 1e-2, series, ij0 - x * special.j0(x))

        kern = (prim(s * b) - prim(s * a)) / (2 * math.pi * s**3)
    else:  # ∫ f cos(st) dt = −(1/s) ∫ f' sin(st) dt
        kern = 2 * np.sin(0.5 * s * (a + b)) * np.sin(0.5 * s * (b - a)) / (math.pi * s**2)
    u = u_n[:, None] * nodes[None, 1:]
    om = np.minimum(_matern_one_minus_rho(u, h), 1.0)
    with np.errstate(divide="ignore"):
        f = np.exp(n_nodes[:, None] * np.log1p(-np.minimum(om, 1 - 1e-300)))
    f = np.concatenate([np.ones((n_nodes.size, 1)), f], axis=1)
    slope = np.diff(f, axis=1) / (b - a)[None, :]
    w = -(slope @ kern.T)  # (n, s)
    log_w = np.log(np.maximum(w, 1e-300))
    return np.log(n_nodes), np.log(s_nodes), log_w, math.log(c), d, h


#: Scaled wavenumber above which the power-law n-fold spectrum uses its asymptotic series.
_S_TAIL = 30.0


def _powerlaw_tail(n, s, h: float, d: int):
    """Large-``s`` series of ``Ŵ_n(s)``: the singular part of ``ρⁿ(u_n t)`` at ``t → 0`` is
    ``(1 − t^{2H}/n)ⁿ = Σ_k C(n,k) (−1)^k t^{2Hk}/n^k`` and the transform of ``t^μ`` is
    ``2^{μ+1} Γ(1+μ/2)/Γ(−μ/2) s^{−μ−2}`` (2-D, over 2π) or ``Γ(1+μ) cos(π(1+μ)/2) s^{−1−μ}``
    (1-D, over π). The regular ``u²`` part adds ``O(s^{−2})`` relative (< 1e-3 at s ≥ 30).
    For ``2H < 1`` this is the convergent series of the symmetric stable law (n → ∞).

    Summed by recurrences over k (``C(n,k)/n^k = C(n,k−1)/n^{k−1} · (n−k+1)/(k n)``,
    ``s^{−μ_k} = s^{−μ_{k−1}} s^{−2H}``): a few multiplications per term, no special
    functions per element (these were most of the run time of large-kℓ power-law calls)."""
    tk, p0 = _powerlaw_tail_coefficients(h, d)
    n = np.asarray(n, dtype=float)
    s = np.asarray(s, dtype=float)
    ratio = s ** (-2.0 * h)
    binom = np.ones(np.broadcast_shapes(n.shape, s.shape))  # C(n, k)/n^k, k = 0
    power = np.ones_like(binom)  # s^{−2Hk}
    val = np.zeros_like(binom)
    for k in range(1, tk.size + 1):
        binom = np.where(k <= n, binom * (n - k + 1.0) / (k * n), 0.0)
        power *= ratio
        val += tk[k - 1] * binom * power
    with np.errstate(divide="ignore"):
        return np.log(np.maximum(val * s**p0, 1e-300))


@functools.lru_cache(maxsize=16)
def _powerlaw_tail_coefficients(h: float, d: int):
    """``(−1)^k t_k`` for k = 1…14 and the power ``p0`` of ``s`` common to every term."""
    k = np.arange(1, 15, dtype=float)
    mu = 2 * h * k
    if d == 2:
        tk = 2 ** (mu + 1) * special.gamma(1 + mu / 2) * special.rgamma(-mu / 2) / (2 * math.pi)
        p0 = -2.0
    else:
        tk = special.gamma(1 + mu) * np.cos(0.5 * math.pi * (1 + mu)) / math.pi
        p0 = -1.0
    return tk * (-1.0) ** k, p0


def _powerlaw_log_w(table, n, K):
    log_nn, log_s, log_w, log_c, d, h = table
    n, K = np.broadcast_arrays(np.asarray(n, dtype=float), np.asarray(K, dtype=float))
    x = np.clip(np.log(n), log_nn[0], log_nn[-1])
    log_un = -(x + log_c) / (2 * h)
    ls = np.log(np.maximum(K, 1e-300)) + log_un
    j = np.clip(np.searchsorted(log_nn, x) - 1, 0, log_nn.size - 2)
    fx = (x - log_nn[j]) / (log_nn[j + 1] - log_nn[j])
    lsc = np.clip(ls, log_s[0], log_s[-1])
    i = np.clip(np.searchsorted(log_s, lsc) - 1, 0, log_s.size - 2)
    fs = (lsc - log_s[i]) / (log_s[i + 1] - log_s[i])
    w0 = log_w[j, i] * (1 - fs) + log_w[j, i + 1] * fs
    w1 = log_w[j + 1, i] * (1 - fs) + log_w[j + 1, i + 1] * fs
    val = w0 * (1 - fx) + w1 * fx
    tail = ls > math.log(_S_TAIL)
    if np.any(tail):
        val = val.copy()
        val[tail] = _powerlaw_tail(np.exp(x[tail]), np.exp(ls[tail]), h, d)
    return val + d * log_un


# ----------------------------------------------------------------------------- series
def series_sum(log_w, Q, K, *, rtol: float = 1e-8, max_terms: int = 10**6) -> np.ndarray:
    """``log T`` with ``T = e^{−Q} Σ_{n≥1} Q^{n−1}/n! · exp(log_w(n, K))`` (1-D arrays).

    Log-space summation outward from the largest term, in blocks, until the geometric tail
    bound is below ``rtol`` × sum on both sides (module docstring)."""
    Q = np.asarray(Q, dtype=float)
    K = np.asarray(K, dtype=float)
    N = Q.size
    logQ = np.log(np.maximum(Q, 1e-300))

    def lt(n, a):
        return (n - 1) * logQ[a, None] - special.gammaln(n + 1) - Q[a, None] + log_w(n, K[a, None])

    # locate the peak: coarse log-grid, then golden-section refinement (on log n) where the
    # grid is coarse (large Q or K); the outward walk below is correct from any start.
    allidx = np.arange(N)
    hi = np.log(2 * Q + 2 * K + 20.0)
    grid = np.linspace(0, 1, 16)[None, :] * hi[:, None]
    vals = lt(np.exp(grid), allidx)
    best = np.argmax(vals, axis=1)
    x_best = grid[allidx, best]
    refine = np.nonzero(hi > math.log(60.0))[0]
    if refine.size:
        step = hi[refine] / 15
        lo_x = np.maximum(x_best[refine] - step, 0.0)
        hi_x = x_best[refine] + step
        gr = (math.sqrt(5) - 1) / 2
        for _ in range(12):
            x1 = hi_x - gr * (hi_x - lo_x)
            x2 = lo_x + gr * (hi_x - lo_x)
            f1 = lt(np.exp(x1)[:, None], refine)[:, 0]
            f2 = lt(np.exp(x2)[:, None], refine)[:, 0]
            left = f1 > f2
            hi_x = np.where(left, x2, hi_x)
            lo_x = np.where(left, lo_x, x1)
        x_best[refine] = 0.5 * (lo_x + hi_x)
    n0 = np.maximum(np.round(np.exp(x_best)), 1.0)
    log_rtol = math.log(rtol)
    big = n0 >= _N_CONTINUUM
    log_int = None
    if np.any(big):
        b = np.nonzero(big)[0]
        log_int, ok = _continuum_sum(lt, b, n0[b], log_rtol)
        big[b[~ok]] = False
        log_int = log_int[ok]
    L0 = lt(n0[:, None], allidx)[:, 0]
    acc = np.zeros(N)
    count = np.zeros(N)

    for direction in (+1, -1):
        nxt = n0 + 1 if direction > 0 else n0 - 1
        active = (nxt >= 1 if direction < 0 else np.ones(N, dtype=bool)) & ~big
        if direction > 0:
            acc += 1.0  # the peak term itself
            count += 1
        c = 16
        while np.any(active):
            a = np.nonzero(active)[0]
            c = int(min(c, max(8, (1 << 22) // a.size)))
            offs = np.arange(c)[None, :]
            nn = nxt[a, None] + direction * offs
            valid = nn >= 1
            nn_eval = np.maximum(nn, 1.0)
            rel = np.where(valid, lt(nn_eval, a) - L0[a, None], -np.inf)
            acc[a] += np.exp(rel).sum(axis=1)
            count[a] += valid.sum(axis=1)
            last, prev = rel[:, -1], rel[:, -2]
            with np.errstate(invalid="ignore"):
                lr = last - prev
            tail_ok = (lr < 0) & (
                last + lr - np.log(-np.expm1(np.where(lr < 0, lr, -1.0)))
                <= log_rtol + np.log(acc[a])
            )
            if direction < 0:
                done = ~valid[:, -1] | (tail_ok & (nn[:, -1] > 8))
            else:
                done = tail_ok
            if np.any(count[a] > max_terms):
                raise RuntimeError(
                    f"physical-optics series did not converge to rtol={rtol:g} within "
                    f"max_terms={max_terms} terms (largest Q = q_z²σ² = {Q.max():.3g}); "
                    "raise max_terms or rtol"
                )
            active[a[done]] = False
            nxt[a] += direction * c
            c = min(2 * c, 4096)
    with np.errstate(divide="ignore"):
        out = L0 + np.log(acc)
    if log_int is not None:
        out[big] = log_int
    return out


#: Peak term index above which :func:`series_sum` replaces the sum over n by its integral.
_N_CONTINUUM = 400.0


def _continuum_sum(lt, idx: np.ndarray, n0: np.ndarray, log_rtol: float):
    """``log Σ_n t_n`` as ``log ∫ t(n) dn`` for peaks at large ``n`` (``(log T, ok)``).

    The terms ``t(n) = exp(lt(n))`` are analytic in ``n`` and log-concave, with a peak of
    width ``s ≈ √n ≥ 20`` here; by Poisson summation ``Σ_n t(n) = ∫ t(n) dn`` up to
    ``O(e^{−2π² s²})`` plus the end terms, both far below any tolerance. This is the series'
    own continuum (large-``Q``) limit — the road to geometric optics, without GO's ``O(1/Q)``
    error, and for every spectrum (the exponential's limit is not GO's Gaussian slopes). Cost:
    a few Newton steps and 64 Gauss–Legendre nodes per geometry, whatever ``Q`` (issue 11:
    PO at kσ = 1e3 used to walk ~10⁴ terms per geometry). ``ok`` is False where the window
    does not reach the tolerance or would cross ``n = 1`` (those take the direct sum)."""
    n = n0.astype(float).copy()
    d2 = np.full(n.shape, -1.0)
    todo = np.arange(n.size)
    for _ in range(8):  # Newton on d lt/dn with central differences of step ≈ the width
        nt = n[todo]
        h = np.sqrt(nt)
        f = lt(np.stack([nt, nt + h, nt - h], axis=1), idx[todo])
        d1 = (f[:, 1] - f[:, 2]) / (2 * h)
        d2[todo] = np.minimum((f[:, 1] - 2 * f[:, 0] + f[:, 2]) / (h * h), -1e-300)
        step = np.clip(-d1 / d2[todo], -0.5 * nt, 0.5 * nt)
        n[todo] = np.maximum(nt + step, 2.0)
        todo = todo[np.abs(step) >= 1e-3 * h]
        if not todo.size:
            break
    width = 1.0 / np.sqrt(-d2)
    L0 = lt(n[:, None], idx)[:, 0]
    half = (math.sqrt(-2 * log_rtol) + 4.0) * width
    x, w = np.polynomial.legendre.leggauss(16)
    panels = np.linspace(-1.0, 1.0, 5)
    lo, up = panels[:-1, None], panels[1:, None]
    t = (0.5 * (lo + up) + 0.5 * (up - lo) * x[None, :]).ravel()
    wt = (0.5 * (up - lo) * w[None, :]).ravel()
    nodes = n[:, None] + half[:, None] * t[None, :]
    vals = np.exp(lt(np.maximum(nodes, 1.0), idx) - L0[:, None])
    total = (vals * wt[None, :]).sum(axis=1) * half
    edges = np.maximum(vals[:, 0], vals[:, -1])
    ok = (n - half > 1.0) & (edges * width < math.exp(log_rtol) * total) & np.isfinite(total)
    with np.errstate(divide="ignore"):
        return L0 + np.log(total), ok


# ----------------------------------------------------------------------------- solver
def bistatic(
    roughness,
    eps,
    k: float,
    theta_i,
    theta_s,
    phi_s,
    phi_i=0.0,
    *,
    rtol: float = 1e-8,
    max_terms: int = 10**6,
    threads: int | None = None,
    coherent: bool = True,
) -> Scattering:
    """Physical-optics (scalar Kirchhoff) bistatic scattering coefficients σ⁰.

    Parameters
    ----------
    roughness : Gaussian, exponential or power-law :class:`~emscatter.spectra.Roughness`, or a
        measured map's (:class:`~emscatter.surfaces.measured.MeasuredRoughness`: its n-fold
        spectra tabulated by :mod:`emscatter.surfaces.measured.nfold`), ``dimension`` 2 (all four
        polarizations) or 1 (hh, vv; ``φ ∈ {0, π}``).
    eps : relative permittivity (``Im ε ≥ 0``, broadcasts with the angles) or "pec".
    k : free-space wavenumber [rad/m].
    theta_i, theta_s, phi_s, phi_i : angles [rad], numpy-broadcast.
    rtol : relative tolerance of the series (tail bound) [-].
    max_terms : safety cap on the number of series terms per geometry.
    threads : worker threads over blocks of geometries (default: CPU count, at most 8).
    coherent : False skips the coherent part (``coherent`` is then NaN and
        ``info["coherent"]`` says so; BOARD interface 3).
    """
    rough = check_roughness(roughness)
    k = check_positive("k", k, unit="rad/m")
    rtol = check_positive("rtol", rtol)
    if not rtol < 1:
        raise ValueError(f"rtol must be in (0, 1), got {rtol!r}")
    if isinstance(max_terms, bool) or not isinstance(max_terms, int | np.integer) or max_terms < 1:
        raise ValueError(f"max_terms must be a positive integer, got {max_terms!r}")
    want_coh = check_flag("coherent", coherent)
    log_w = log_nfold(rough)
    dim = rough.dimension
    g = geometry(theta_i, theta_s, phi_s, phi_i, eps, dim)
    loc = g.chunk(signed_azimuth=dim == 2 and rough.length != rough.length_y)
    ks = k * rough.sigma
    Q = np.broadcast_to((ks * loc.qz) ** 2, (loc.n,))
    if dim == 2:
        K = np.hypot(loc.qx * (k * rough.length), loc.qy * (k * rough.length_y))
        pref = math.pi * ks**2 * (k * rough.length) * (k * rough.length_y)
    else:
        K = np.abs(loc.qx) * (k * rough.length)
        pref = 0.5 * math.pi * ks**2 * (k * rough.length)
    K = np.broadcast_to(K, (loc.n,))
    starts = range(0, loc.n, _BLOCK)
    workers = workers_for(threads, len(starts))

    def block(st: int) -> np.ndarray:
        sl = slice(st, st + _BLOCK)
        opts = {"rtol": rtol, "max_terms": int(max_terms)}
        compiled = kirchhoff_compiled.po_log_series(
            rough, log_w, Q[sl], K[sl], series_sum=series_sum, **opts
        )
        return compiled if compiled is not None else series_sum(log_w, Q[sl], K[sl], **opts)

    if workers > 1:
        with ThreadPoolExecutor(max_workers=workers) as pool:
            parts = list(pool.map(block, starts))
    else:
        parts = [block(st) for st in starts]
    logT = np.concatenate(parts) if parts else np.empty(0)
    geo = pref * loc.q2 * loc.q2 * np.exp(logT)
    sigma0 = fresnel_factors(loc, dim, geo).reshape(2, 2, *g.shape)
    if want_coh:
        coh = coherent_local(loc, rough.sigma, k).reshape(2, *g.shape)
    else:
        coh = np.full((2, *g.shape), np.nan)
    info = {"rtol": rtol, "polarization_factors": "local specular (stationary phase)"}
    if not want_coh:
        info["coherent"] = "not computed (coherent=False)"
    return Scattering.from_geometry(
        g, sigma0=sigma0, coherent=coh, method="kirchhoff-po", k=k, info=info
    )
