"""He, Torrance, Sillion & Greenberg 1991's physical BRDF ("A comprehensive physical model for
light reflection", SIGGRAPH '91, Computer Graphics 25(4) 175–186; the seed's §2.3.2), on the
footing of :mod:`emscatter.brdf.analytic` (renderer frame, ``wi``/``wo`` unit vectors
``(..., 3)`` pointing away, normal ``+z``; ``f_r`` [1/sr], 0 below the horizon; vectorized).

Surface: Gaussian heights of rms ``σ₀`` [m] with the Gaussian autocorrelation
``C(r) = exp(−r²/τ²)`` (seed eq. 2.3, ``τ`` [m] the autocorrelation length); material: the
complex index ``n = n' + i n''`` (``n'' ≥ 0``, emscatter's ``exp(−iωt)``; ``ε = n²``) or
``"pec"``; wavelength ``λ`` [m], ``k = 2π/λ``. With ``k̂_i = −wi``, ``k̂_r = wo``,
``v̂ = k̂_r − k̂_i = wi + wo`` (HTSG's ``v = k v̂``):

``ρ = ρ_sp + ρ_dd + ρ_ud``

* specular (coherent, a delta lobe kept apart as a table's ``coherent``; HTSG eq. 45):
  ``R_sp(θi) = |F(θi)|² e^{−g} S(θi)²``, ``g = (2kσ cosθi)²``.
* directional diffuse (HTSG eqs. 46, 78–80)::

      ρ_dd = |F(wi·h)|² G S D / (π cosθi cosθo)
      D    = (kτ)²/16 Σ_{m≥1} g^m e^{−g}/(m! m) exp(−v̂_xy² (kτ)²/(4m)),  g = (kσ v̂_z)²
      G    = (v̂·v̂ / v̂_z)²

  (HTSG's ``G`` carries the factor ``[(ŝ_r·k̂_i)² + (p̂_r·k̂_i)²][(ŝ_i·k̂_r)² + (p̂_i·k̂_r)²]
  /|k̂_r × k̂_i|⁴``; each bracket is the squared part of a unit vector orthogonal to the other,
  ``|k̂_r × k̂_i|²``, so for unpolarized light the factor is exactly 1.) ``|F|²`` is the
  unpolarized Fresnel reflectance at the local (bisector) angle ``cos θ_l = wi·h = |v̂|/2``.
* uniform diffuse: ``a/π`` with a given albedo ``a`` (HTSG derive ``a(λ)`` from multiple and
  subsurface scattering; here a parameter, 0 by default).

Shadowing (HTSG eq. 24, Smith 1967 with the height factor), ``S = S(θi) S(θo)``::

    S(θ) = [1 − ½ erfc(τ cotθ/(2σ₀))] / (Λ(cotθ) + 1),
    Λ    = ½ [(2/√π) σ₀/(τ cotθ) e^{−τ² cot²θ/(4σ₀²)} − erfc(τ cotθ/(2σ₀))]

— Smith's ``Λ`` for Gaussian slopes of Beckmann ``m = 2σ₀/τ`` (seed eq. 3.1).

Effective roughness (HTSG eqs. 81–82): the lit, visible part of the surface is smoother,
``σ = σ₀ (1 + z₀²/σ₀²)^{−1/2}`` with ``z₀`` the root of
``√(π/2) z₀ = (σ₀/4)(K_i + K_r) e^{−z₀²/(2σ₀²)}``, ``K = tanθ erfc(τ cotθ/(2σ₀))``; it
replaces ``σ₀`` in ``g`` (both terms). Solved by bisection on ``[0, (K_i + K_r)/(4√(π/2))]``
to 1e-12 relative.

Where it equals emscatter's physical optics. With ``shadowing=False`` and
``effective_roughness=False``, ``ρ_dd`` *is* emscatter's PO (:mod:`emscatter.solvers.kirchhoff.po`,
Gaussian correlation, ``ℓ = τ``, ``σ = σ₀``) converted to a BRDF, ``f = σ⁰/(4π cosθi cosθo)``
with ``σ⁰ = (σ⁰_hh + σ⁰_vh + σ⁰_hv + σ⁰_vv)/2`` — term by term: PO's
``π|q|⁴σ²|F_pq|² e^{−Q} Σ Q^{n−1}/n! w_n``, ``w_n = τ²/(4πn) e^{−q⊥²τ²/(4n)}``,
``Σ_pq |F_pq|² = 2|F|²`` gives ``|F|² G D/(π cosθi cosθo)`` (tested to 1e-6), and
``R_sp`` is PO's Kirchhoff coherent ``|R|² e^{−(2kσ cosθ)²}``. With shadowing the two differ
by ``S`` and ``σ_eff/σ₀``: where the shadowing fades (``τ/σ₀`` large, moderate angles)
``K → 0``, ``σ_eff → σ₀``, ``S → 1`` and HTSG tends to PO (measured in dB in
``validation/brdf/catalogue.md``).

Series: in log space, ``log t_m = m log g − g − lgamma(m+1) − log m − a/m``
(``a = v̂_xy²(kτ)²/4``); the ratio ``t_{m+1}/t_m = g m e^{a/(m(m+1))}/(m+1)²`` decreases in ``m``,
so once it is below 1 the tail is at most ``t_m r/(1 − r)``: the sum stops when that bound is
below ``rtol`` (default 1e-8) of the partial sum, per direction pair (an active set; no
loop over angles). Large ``g`` (``kσ ≫ 1``) takes about ``g + 10√g`` terms.

Beckmann equivalent (the seed's chapter-3 general roughness, :func:`htsg_equivalent_beckmann`):
``m = 2σ₀/τ`` (seed eq. 3.1) — the slope statistics of the surface, the ``m`` of HTSG's own
shadowing, and the ``kσ → ∞`` limit of ``D`` (``D → Beckmann(m_eff = 2σ/τ)``, ``σ`` the
effective roughness); at finite ``kσ`` the lobe is narrower and carries the coherent spike,
the fit by :data:`~.equivalence.FIT_CRITERION` of the ``D`` lobe is reported beside it.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from scipy import special

from emscatter.brdf.analytic import _upper, fresnel_unpolarized
from emscatter.conventions import check_in_range, check_positive

__all__ = [
    "htsg",
    "htsg_specular",
    "htsg_shadowing",
    "htsg_effective_roughness",
    "htsg_equivalent_beckmann",
    "htsg_table",
]

_SQRT_HALF_PI = math.sqrt(0.5 * math.pi)


def _check_surface(sigma0, tau, wavelength):
    s = check_positive("sigma0", sigma0, unit="m")
    t = check_positive("tau", tau, unit="m")
    lam = check_positive("wavelength", wavelength, unit="m")
    return s, t, lam


def _eps(n, wavelength):
    """``ε = n²`` from a complex index (or a callable ``n(λ)``), or ``"pec"``."""
    if callable(n):
        n = n(wavelength)
    if isinstance(n, str):
        if n.lower() != "pec":
            raise ValueError(f"n must be a complex refractive index or 'pec', got {n!r}")
        return "pec"
    try:
        nc = complex(n)
    except (TypeError, ValueError):
        raise ValueError(f"n must be a complex refractive index or 'pec', got {n!r}") from None
    if not (math.isfinite(nc.real) and math.isfinite(nc.imag)) or nc.real <= 0 or nc.imag < 0:
        raise ValueError(
            f"n must be a finite complex index with Re n > 0 and Im n ≥ 0 (exp(−iωt)), got {n!r}"
        )
    return nc * nc


def _cot_tan(c):
    """``(cotθ, tanθ)`` from ``cosθ ∈ [0, 1]`` (``cot = inf``, ``tan = 0`` at the normal)."""
    c = np.clip(c, 0.0, 1.0)
    s = np.sqrt(np.maximum(1.0 - c * c, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        cot = np.where(s > 0, c / np.where(s > 0, s, 1.0), np.inf)
        tan = np.where(c > 0, s / np.where(c > 0, c, 1.0), np.inf)
    return cot, tan


def htsg_shadowing(cos_theta, sigma0: float, tau: float) -> np.ndarray:
    """HTSG's one-direction shadowing ``S(θ)`` [-] (module docstring; HTSG eq. 24 — Smith's
    with Beckmann ``m = 2σ₀/τ``) at ``cos_theta`` (array); ``sigma0``, ``tau`` in one unit."""
    s0 = check_positive("sigma0", sigma0)
    t = check_positive("tau", tau)
    cot, _ = _cot_tan(np.asarray(cos_theta, dtype=float))
    x = t * cot / (2.0 * s0)  # ≥ 0; inf at the normal
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        lam = 0.5 * (np.exp(-x * x) / (math.sqrt(math.pi) * x) - special.erfc(x))
    lam = np.where(np.isfinite(x), lam, 0.0)
    lam = np.where(x > 0, lam, np.inf)
    return np.where(x > 0, (1.0 - 0.5 * special.erfc(x)) / (lam + 1.0), 0.0)


def htsg_effective_roughness(cos_i, cos_o, sigma0: float, tau: float) -> np.ndarray:
    """Effective roughness ``σ`` [unit of ``sigma0``] of the lit, visible surface (HTSG eqs.
    81–82, module docstring) for incidence/exit cosines ``cos_i``, ``cos_o`` (arrays)."""
    s0 = check_positive("sigma0", sigma0)
    t = check_positive("tau", tau)

    def kfac(c):
        cot, tan = _cot_tan(np.asarray(c, dtype=float))
        with np.errstate(invalid="ignore"):
            k = tan * special.erfc(t * cot / (2.0 * s0))
        return np.where(np.isfinite(cot), np.where(np.isfinite(tan), k, np.inf), 0.0)

    big_k = kfac(cos_i) + kfac(cos_o)
    finite = np.isfinite(big_k)
    kk = np.where(finite, big_k, 0.0)
    # x = z0/σ0: √(π/2) x = (K/4) e^{−x²/2}; f(x) increasing, f(0) ≤ 0 ≤ f(K/(4√(π/2)))
    lo = np.zeros_like(kk)
    hi = kk / (4.0 * _SQRT_HALF_PI)
    for _ in range(60):  # bisection: 2^-60 of the bracket, every direction pair at once
        mid = 0.5 * (lo + hi)
        pos = _SQRT_HALF_PI * mid - 0.25 * kk * np.exp(-0.5 * mid * mid) > 0
        hi = np.where(pos, mid, hi)
        lo = np.where(pos, lo, mid)
    x = 0.5 * (lo + hi)
    return np.where(finite, s0 / np.sqrt(1.0 + x * x), 0.0)


def _series(g, a, rtol: float, max_terms: int) -> np.ndarray:
    """``Σ_{m≥1} g^m e^{−g}/(m! m) e^{−a/m}`` (module docstring), elementwise, flat arrays."""
    out = np.zeros(g.shape)
    active = np.flatnonzero(g > 0)
    lg = np.log(np.where(g > 0, g, 1.0))
    m = 0
    while active.size:
        m += 1
        if m > max_terms:
            raise ValueError(
                f"HTSG series not converged after max_terms={max_terms} terms (g up to "
                f"{float(g[active].max()):.4g}); raise max_terms or use geometric optics"
            )
        ga, aa, la = g[active], a[active], lg[active]
        logt = m * la - ga - math.lgamma(m + 1) - math.log(m) - aa / m
        t = np.exp(logt)
        out[active] += t
        r = ga * m * np.exp(np.minimum(aa / (m * (m + 1.0)), 700.0)) / (m + 1.0) ** 2
        with np.errstate(divide="ignore", invalid="ignore"):
            tail = np.where(r < 1, t * r / (1 - r), np.inf)
        done = (r < 1) & (tail <= rtol * out[active])
        active = active[~done]
    return out


def htsg(
    wi,
    wo,
    wavelength: float,
    sigma0: float,
    tau: float,
    n=1.5,
    *,
    a_ud: float = 0.0,
    shadowing: bool = True,
    effective_roughness: bool = True,
    rtol: float = 1e-8,
    max_terms: int = 100_000,
) -> np.ndarray:
    """HTSG's directional-diffuse plus uniform-diffuse BRDF ``ρ_dd + a_ud/π`` [1/sr] (module
    docstring; the specular delta lobe is :func:`htsg_specular`). ``wavelength``, ``sigma0``
    (rms height), ``tau`` (autocorrelation length) [m]; ``n``: complex index ``n' + i n''``
    (``n'' ≥ 0``), a callable ``n(λ)`` or ``"pec"``; ``a_ud`` ∈ [0, 1]: uniform-diffuse
    albedo; ``shadowing=False`` / ``effective_roughness=False`` drop ``S`` / use ``σ₀`` in
    ``g`` (both off: emscatter's PO, exactly); ``rtol``: the series' tail tolerance."""
    s0, t, lam = _check_surface(sigma0, tau, wavelength)
    eps = _eps(n, lam)
    a_ud = check_in_range("a_ud", a_ud, 0.0, 1.0, low_open=False, high_open=False)
    rtol = check_in_range("rtol", rtol, 0.0, 1.0)
    if isinstance(max_terms, bool) or not isinstance(max_terms, int) or max_terms < 1:
        raise ValueError(f"max_terms must be a positive integer, got {max_terms!r}")
    return _directional_diffuse(
        wi,
        wo,
        lam,
        s0,
        t,
        t,
        eps,
        shadowing=shadowing,
        effective_roughness=effective_roughness,
        rtol=rtol,
        max_terms=max_terms,
        a_ud=a_ud,
    )


def _directional_diffuse(
    wi,
    wo,
    lam: float,
    s0: float,
    tau_x: float,
    tau_y: float,
    eps,
    *,
    shadowing: bool,
    effective_roughness: bool,
    rtol: float,
    max_terms: int,
    a_ud: float = 0.0,
) -> np.ndarray:
    """The Kirchhoff series BRDF shared by :func:`htsg` and :func:`~.stam.stam` [1/sr] (module
    docstring), inputs already checked: ``|F(wi·h)|² G S D/(π cosθi cosθo) + a_ud/π`` with
    ``D = k²τ_xτ_y/16 Σ_m g^m e^{−g}/(m! m) exp(−k²(τ_x²v̂_x² + τ_y²v̂_y²)/(4m))`` — HTSG's
    ``D`` for ``τ_x = τ_y = τ``, Stam's anisotropic noise otherwise (``S`` and the effective
    roughness are HTSG's isotropic ones, used with ``τ_x``)."""
    wi, wo, up = _upper(wi, wo)
    shape = up.shape
    wi, wo, upf = wi.reshape(-1, 3), wo.reshape(-1, 3), up.reshape(-1)
    k = 2.0 * math.pi / lam
    ci, co = np.clip(wi[:, 2], 0.0, 1.0), np.clip(wo[:, 2], 0.0, 1.0)
    v = wi + wo  # v̂ = k̂_r − k̂_i
    vz = v[:, 2]
    vv = np.sum(v * v, axis=-1)
    cos_l = np.clip(0.5 * np.sqrt(vv), 0.0, 1.0)  # wi·h
    if effective_roughness:
        sig = htsg_effective_roughness(ci, co, s0, tau_x)
    else:
        sig = np.full(ci.shape, s0)
    g = np.where(upf, (k * sig * vz) ** 2, 0.0)
    a = 0.25 * k * k * ((tau_x * v[:, 0]) ** 2 + (tau_y * v[:, 1]) ** 2)
    series = _series(g, a, rtol, max_terms)
    d = k * k * tau_x * tau_y / 16.0 * series
    geo = np.where(upf, vv * vv / np.where(upf, vz * vz, 1.0), 0.0)
    f = fresnel_unpolarized(eps, cos_l)
    if shadowing:
        f = f * htsg_shadowing(ci, s0, tau_x) * htsg_shadowing(co, s0, tau_x)
    den = math.pi * np.where(upf, ci * co, 1.0)
    out = np.where(upf, f * geo * d / den + a_ud / math.pi, 0.0)
    return out.reshape(shape)


def htsg_specular(
    theta_i,
    wavelength: float,
    sigma0: float,
    tau: float,
    n=1.5,
    *,
    shadowing: bool = True,
    effective_roughness: bool = True,
) -> np.ndarray:
    """HTSG's specular (coherent) reflectance ``|F(θi)|² e^{−g} S(θi)²`` [-],
    ``g = (2kσ cosθi)²`` with the effective roughness at ``θo = θi`` (HTSG eq. 45), at
    incidence angles ``theta_i`` [rad]: the weight of the delta lobe at the mirror direction
    (a table's ``coherent``)."""
    s0, t, lam = _check_surface(sigma0, tau, wavelength)
    eps = _eps(n, lam)
    th = np.asarray(theta_i, dtype=float)
    if not np.all(np.isfinite(th)) or np.any(th < 0) or np.any(th > 0.5 * math.pi):
        raise ValueError(f"theta_i must be in [0, π/2] rad, got {theta_i!r}")
    c = np.cos(th)
    sig = htsg_effective_roughness(c, c, s0, t) if effective_roughness else s0
    k = 2.0 * math.pi / lam
    r = fresnel_unpolarized(eps, c) * np.exp(-((2.0 * k * sig * c) ** 2))
    if shadowing:
        r = r * htsg_shadowing(c, s0, t) ** 2
    return r


def htsg_equivalent_beckmann(sigma0: float, tau: float, *, wavelength: float | None = None):
    """The seed's chapter-3 general roughness of HTSG as an :class:`~.equivalence.Equivalence`.

    Without ``wavelength``: Beckmann ``m = 2σ₀/τ`` (seed eq. 3.1; the ``m`` of HTSG's own
    shadowing, and exact as ``kσ → ∞``), ``error`` 0. With ``wavelength`` [m]: the Beckmann
    ``m`` fitted by :data:`~.equivalence.FIT_CRITERION` to HTSG's distribution part ``G·D``
    (σ = σ₀, no shadowing) as a function of the half-vector angle ``γ`` in the backscatter
    geometry ``wi = wo = h(γ)`` (``θ_d = 0``: ``v̂ = 2h``), both at level 1 for ``γ = 0``, and
    the rms difference. In the ``kσ → ∞`` limit ``G·D → exp(−tan²γ/m²)/(4m² cos⁴γ)`` (module
    docstring), so the fit returns ``2σ₀/τ`` there; at finite ``kσ`` the incoherent lobe
    differs (at small ``kσ`` it is the first-order spectrum's, wider)."""
    from emscatter.brdf.analytic.equivalence import (
        _GAMMA,
        Equivalence,
        _fit_scalar,
        beckmann_shape,
        fit_error,
    )

    s0 = check_positive("sigma0", sigma0, unit="m")
    t = check_positive("tau", tau, unit="m")
    m = 2.0 * s0 / t
    if wavelength is None:
        return Equivalence(m, 0.0, "m = 2 sigma0 / tau (seed eq. 3.1), exact as k sigma -> inf")
    lam = check_positive("wavelength", wavelength, unit="m")
    k = 2.0 * math.pi / lam
    cg, sg = np.cos(_GAMMA), np.sin(_GAMMA)
    g = (2.0 * k * s0 * cg) ** 2  # v̂_z = 2 cosγ
    a = (k * t * sg) ** 2  # v̂_xy²(kτ)²/4 with v̂_xy = 2 sinγ
    lobe = _series(g, a, 1e-10, 100_000) * (4.0 / cg**2)  # ∝ G·D, G = 4/cos²γ
    lobe = lobe / lobe[0]
    x = _fit_scalar(lambda mm: fit_error(lobe, beckmann_shape(_GAMMA, mm)), 1e-3, 10.0)
    return Equivalence(x, fit_error(lobe, beckmann_shape(_GAMMA, x)))


def htsg_table(
    wavelengths,
    sigma0: float,
    tau: float,
    n: Callable | complex | str = 1.5,
    *,
    resolution: tuple[int, int] = (90, 180),
    **options,
):
    """An isotropic :class:`~emscatter.brdf.table.BrdfTable` of HTSG (``values`` = ρ_dd +
    ρ_ud, ``coherent`` = :func:`htsg_specular` on the θ nodes), for the exporters and the
    Mitsuba plugin like any solver table; ``n`` a complex index or ``n(λ)`` [λ in m];
    ``options`` go to :func:`htsg` (``a_ud``, ``shadowing``, ``effective_roughness``, ``rtol``)."""
    from dataclasses import replace

    from emscatter.brdf.analytic import table_from_function
    from emscatter.brdf.energy import record_albedo

    spec_opts = {k: options[k] for k in ("shadowing", "effective_roughness") if k in options}
    table = table_from_function(
        lambda wi, wo, lam: htsg(wi, wo, lam, sigma0, tau, n, **options),
        wavelengths,
        resolution=resolution,
        metadata={
            "model": "htsg",
            "surface": {"sigma0": float(sigma0), "tau": float(tau), "units": "m"},
            "options": {k: v for k, v in options.items()},
        },
    )
    coh = np.stack(
        [
            htsg_specular(table.theta_i, lam, sigma0, tau, n, **spec_opts)
            for lam in table.wavelengths
        ]
    )
    meta = dict(table.metadata)
    meta["coherent"] = "HTSG specular |F|^2 exp(-g) S^2"
    table = replace(table, coherent=coh, metadata=meta)
    return record_albedo(table, "off (analytic model)")
