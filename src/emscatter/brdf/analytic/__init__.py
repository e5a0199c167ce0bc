"""The seed's analytic BRDF models (chapters 2–3) on the tables' footing: renderer frame
(:mod:`.frames`; ``wi``, ``wo`` unit vectors ``(..., 3)`` pointing away, normal ``+z``),
vectorized, ``f_r`` [1/sr], 0 below the horizon.

* :func:`cook_torrance` — ``f = k_s F D G / (4 cosθi cosθo) + k_d/π`` (seed eqs. 2.13/3.6 with
  a normalized ``D`` and Walter et al. 2007's 1/4 — the seed, after Cook & Torrance 1982,
  writes ``1/π F G D/((N·S)(N·V))`` with an unnormalized ``D = π D_normalized``, i.e. four
  times this; only the normalized form conserves energy and matches geometric optics). ``D``
  from :mod:`.distributions` (Beckmann, GGX, Blinn–Phong, Ashikhmin–Shirley, the seed's
  uniform/exponential/Rayleigh/Cauchy/Simpson); Fresnel from a complex permittivity (seed
  eqs. 2.8–2.10 are its unpolarized form, :func:`fresnel_seed`), Schlick's ``F0`` or none;
  shadowing Smith (separable or height-correlated), Schlick (eq. 2.12) or Blinn (eq. 2.11).
  With Beckmann, Smith and a permittivity it *is* emscatter's geometric optics (tested to 1e-10).
* :func:`ward` — Ward 1992 isotropic/anisotropic (seed eqs. 2.15–2.16) and the seed's corrected
  form with ``1/cos⁴γ`` (eq. 3.2), which is Beckmann's lobe.
* :func:`phong` — the reciprocal, normalized Phong lobe ``k_s (n+2)/(2π) (R·V)ⁿ`` (seed eq. 2.18;
  Lewis 1994's normalization: albedo ``k_s`` at normal incidence).
* :func:`blinn_phong` — ``k_s (n+8)/(8π) (N·H)ⁿ`` (seed eq. 2.19, the usual normalization).
* :func:`ashikhmin_shirley` — seed eqs. 2.21–2.23 (Ashikhmin & Shirley 2000).

:func:`directional_albedo` integrates any of them (energy checks); :func:`table_from_function`
tabulates one as a :class:`~.table.BrdfTable` so that analytic models and solver tables are
exported and rendered the same way.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from emscatter.brdf.analytic.distributions import Beckmann, Distribution
from emscatter.brdf.grid import gauss_legendre
from emscatter.fresnel import check_eps, fresnel_cos, is_pec

__all__ = [
    "half_vector",
    "fresnel_unpolarized",
    "fresnel_seed",
    "fresnel_schlick",
    "shadowing",
    "cook_torrance",
    "ward",
    "phong",
    "blinn_phong",
    "ashikhmin_shirley",
    "directional_albedo",
    "table_from_function",
    "SHADOWING",
]

SHADOWING = ("smith", "smith-correlated", "schlick", "blinn", "none")


def _unit(w, name):
    w = np.asarray(w, dtype=float)
    if w.ndim == 0 or w.shape[-1] != 3:
        raise ValueError(f"{name} must have shape (..., 3), got {w.shape}")
    n = np.linalg.norm(w, axis=-1, keepdims=True)
    if np.any(n == 0) or not np.all(np.isfinite(n)):
        raise ValueError(f"{name} must hold finite nonzero direction vectors")
    return w / n


def _dot(a, b):
    return np.sum(a * b, axis=-1)


def half_vector(wi, wo) -> np.ndarray:
    """Unit half vector ``(wi + wo)/|wi + wo|`` (``+z`` where ``wo = −wi``)."""
    s = np.asarray(wi, float) + np.asarray(wo, float)
    n = np.linalg.norm(s, axis=-1, keepdims=True)
    return np.where(n > 0, s / np.where(n > 0, n, 1.0), np.array([0.0, 0.0, 1.0]))


def fresnel_unpolarized(eps, cos_theta) -> np.ndarray:
    """``(|R_h|² + |R_v|²)/2`` [-] for relative permittivity ``eps`` (``Im ε ≥ 0``; complex
    index ``n + ik`` ↦ ``ε = (n + ik)²``; or ``"pec"``) at incidence cosine ``cos_theta``."""
    eps = check_eps(eps)
    if is_pec(eps):
        return np.ones(np.shape(cos_theta))
    rh, rv = fresnel_cos(eps, cos_theta)
    return 0.5 * (np.abs(rh) ** 2 + np.abs(rv) ** 2)


def fresnel_seed(n, k, cos_theta) -> np.ndarray:
    """The seed's unpolarized conductor Fresnel term (eqs. 2.8–2.10, after Cook & Torrance
    1982), index ``n`` and extinction ``k``; equals :func:`fresnel_unpolarized` with
    ``ε = (n + ik)²`` (tested)."""
    c = np.asarray(cos_theta, dtype=float)
    t = n * n - k * k + c * c - 1.0
    root = np.sqrt(t * t + 4 * n * n * k * k)
    a2 = 0.5 * (root + t)  # eq. 2.9
    b2 = 0.5 * (root - t)  # eq. 2.10
    a = np.sqrt(a2)
    first = ((a - c) ** 2 + b2) / ((a + c) ** 2 + b2)
    with np.errstate(divide="ignore", invalid="ignore"):
        second = ((a + c - 1 / c) ** 2 + b2) / ((a - c + 1 / c) ** 2 + b2)
    return 0.5 * first * (np.where(c > 0, second, 1.0) + 1.0)  # eq. 2.8


def fresnel_schlick(f0, cos_theta) -> np.ndarray:
    """Schlick's ``F0 + (1 − F0)(1 − cosθ)⁵`` (Schlick 1994; seed eq. 2.22's ``F_λ``)."""
    c = np.clip(np.asarray(cos_theta, dtype=float), 0.0, 1.0)
    return f0 + (1.0 - f0) * (1.0 - c) ** 5


def shadowing(kind: str, wi, wo, h, distribution: Distribution) -> np.ndarray:
    """Masking–shadowing ``G(wi, wo)`` [-]:

    * ``"smith"``: ``G1(wi) G1(wo)``, ``G1 = χ⁺(w·h) / (1 + Λ(w))`` (Smith 1967; the
      separable form of Mitsuba 3 and of emscatter's GO);
    * ``"smith-correlated"``: ``χ⁺ / (1 + Λ(wi) + Λ(wo))`` (Heitz 2014);
    * ``"schlick"``: ``G1(cosθ) = cosθ/(cosθ − k cosθ + k)``, ``k = √(2m²/π)`` with ``m`` the
      distribution's rms slope (seed eq. 2.12, Schlick 1994), applied to both directions;
    * ``"blinn"``: ``min(1, 2(N·H)(N·V)/(V·H), 2(N·H)(N·S)/(V·H))`` (seed eq. 2.11);
    * ``"none"``: 1.
    """
    if kind not in SHADOWING:
        raise ValueError(f"shadowing must be one of {SHADOWING}, got {kind!r}")
    ci, co = wi[..., 2], wo[..., 2]
    if kind == "none":
        return np.ones(np.broadcast_shapes(ci.shape, co.shape))
    if kind in ("smith", "smith-correlated"):
        chi = (_dot(wi, h) > 0) & (_dot(wo, h) > 0)
        li, lo = distribution.smith_lambda(wi), distribution.smith_lambda(wo)
        g = 1.0 / ((1 + li) * (1 + lo)) if kind == "smith" else 1.0 / (1 + li + lo)
        return np.where(chi, g, 0.0)
    if kind == "schlick":
        m = distribution.rms_slope
        if not math.isfinite(m):
            raise ValueError(
                f"Schlick shadowing needs a finite rms slope; {distribution.describe()} has "
                "infinite slope variance — use 'smith' or 'blinn'"
            )
        k = math.sqrt(2 * m * m / math.pi)

        def g1(c):
            c = np.clip(c, 0.0, 1.0)
            return c / (c - k * c + k)

        return g1(ci) * g1(co)
    nh = h[..., 2]
    vh = np.maximum(_dot(wo, h), 1e-300)
    return np.minimum(1.0, np.minimum(2 * nh * co / vh, 2 * nh * ci / vh))


def _fresnel(cos_d, eps, f0):
    if eps is not None and f0 is not None:
        raise ValueError("give eps (a permittivity, or 'pec') or f0 (Schlick), not both")
    if eps is not None:
        return fresnel_unpolarized(eps, cos_d)
    if f0 is not None:
        f0 = float(f0)
        if not 0 <= f0 <= 1:
            raise ValueError(f"f0 must be in [0, 1], got {f0!r}")
        return fresnel_schlick(f0, cos_d)
    return np.ones(np.shape(cos_d))


def _upper(wi, wo):
    wi, wo = _unit(wi, "wi"), _unit(wo, "wo")
    wi, wo = np.broadcast_arrays(wi, wo)
    return wi, wo, (wi[..., 2] > 0) & (wo[..., 2] > 0)


def cook_torrance(
    wi,
    wo,
    distribution: Distribution | None = None,
    *,
    eps=None,
    f0: float | None = None,
    shadowing_kind: str = "smith",
    ks: float = 1.0,
    kd: float = 0.0,
) -> np.ndarray:
    """Cook–Torrance ``k_s F(wi·h) D(h) G / (4 cosθi cosθo) + k_d/π`` [1/sr] (module
    docstring). ``distribution`` defaults to :class:`~.distributions.Beckmann` (α = 0.3);
    ``eps``: complex permittivity (``Im ε ≥ 0``) or ``"pec"``; ``f0``: Schlick instead; neither:
    ``F = 1``."""
    dist = Beckmann(0.3) if distribution is None else distribution
    wi, wo, up = _upper(wi, wo)
    h = half_vector(wi, wo)
    ci, co = wi[..., 2], wo[..., 2]
    den = 4.0 * np.where(up, ci * co, 1.0)
    spec = _fresnel(np.clip(_dot(wi, h), 0, 1), eps, f0) * dist(h)
    spec = spec * shadowing(shadowing_kind, wi, wo, h, dist) / den
    return np.where(up, ks * spec + kd / math.pi, 0.0)


def ward(
    wi,
    wo,
    alpha_x: float,
    alpha_y: float | None = None,
    *,
    rho_s: float = 1.0,
    rho_d: float = 0.0,
    corrected: bool = False,
) -> np.ndarray:
    """Ward's BRDF ``ρd/π + ρs exp(−tan²γ (cos²φ/mx² + sin²φ/my²)) / (4π mx my √(cosθi cosθo))``
    (seed eqs. 2.15–2.16; ``γ``, ``φ`` the half vector's polar angle and azimuth; the seed
    prints ``4π m²`` also for the anisotropic form, ``mx my`` is Ward's). ``corrected=True``:
    the seed's eq. 3.2, the lobe divided by ``cos⁴γ`` — Beckmann's distribution, so
    ``ρs D_Beckmann(h) / (4 √(cosθi cosθo))``."""
    ay = alpha_x if alpha_y is None else alpha_y
    dist = Beckmann(alpha_x, ay)
    wi, wo, up = _upper(wi, wo)
    h = half_vector(wi, wo)
    ch = h[..., 2]
    lobe = dist(h) * (1.0 if corrected else ch**4)  # π mx my D cos⁴ = exp(...)
    root = np.sqrt(np.where(up, wi[..., 2] * wo[..., 2], 1.0))
    return np.where(up, rho_d / math.pi + rho_s * lobe / (4.0 * root), 0.0)


def phong(wi, wo, n: float, *, ks: float = 1.0, kd: float = 0.0) -> np.ndarray:
    """Reciprocal normalized Phong ``k_s (n+2)/(2π) max(0, R·V)ⁿ + k_d/π`` (seed eq. 2.18),
    ``R = mirror(wi)``."""
    wi, wo, up = _upper(wi, wo)
    r = wi * np.array([-1.0, -1.0, 1.0])
    c = np.clip(_dot(r, wo), 0.0, 1.0)
    return np.where(up, ks * (n + 2) / (2 * math.pi) * c**n + kd / math.pi, 0.0)


def blinn_phong(wi, wo, n: float, *, ks: float = 1.0, kd: float = 0.0) -> np.ndarray:
    """Blinn–Phong ``k_s (n+8)/(8π) (N·H)ⁿ + k_d/π`` (seed eq. 2.19)."""
    wi, wo, up = _upper(wi, wo)
    nh = np.clip(half_vector(wi, wo)[..., 2], 0.0, 1.0)
    return np.where(up, ks * (n + 8) / (8 * math.pi) * nh**n + kd / math.pi, 0.0)


def ashikhmin_shirley(
    wi, wo, nu: float, nv: float, *, rs: float = 1.0, rd: float = 0.0
) -> np.ndarray:
    """Ashikhmin–Shirley (seed eqs. 2.21–2.23): specular
    ``√((nu+1)(nv+1))/(8π) (n·h)^(nu cos²φh + nv sin²φh) / ((h·wi) max(cosθi, cosθo)) F(wi·h)``
    with Schlick's ``F = rs + (1 − rs)(1 − wi·h)⁵``, plus the coupled diffuse term
    ``28 rd/(23π) (1 − rs)(1 − (1 − cosθi/2)⁵)(1 − (1 − cosθo/2)⁵)``."""
    from emscatter.brdf.analytic.distributions import AshikhminShirleyDistribution

    lobe = AshikhminShirleyDistribution(nu, nv)
    wi, wo, up = _upper(wi, wo)
    h = half_vector(wi, wo)
    ci, co = wi[..., 2], wo[..., 2]
    kh = np.maximum(_dot(wi, h), 1e-300)
    pref = math.sqrt((nu + 1) * (nv + 1)) / (8 * math.pi)
    spec = pref * np.clip(h[..., 2], 0, 1) ** lobe.exponent(h)
    spec = spec / (kh * np.maximum(np.maximum(ci, co), 1e-300)) * fresnel_schlick(rs, kh)
    diff = 28 * rd / (23 * math.pi) * (1 - rs) * (1 - (1 - ci / 2) ** 5) * (1 - (1 - co / 2) ** 5)
    return np.where(up, spec + diff, 0.0)


def directional_albedo(
    brdf: Callable,
    theta_i,
    *,
    phi_i: float = 0.0,
    n_theta: int = 192,
    n_phi: int = 256,
    theta_h_breaks=(),
) -> np.ndarray:
    """``∫ f_r(wi, wo) cosθo dωo`` [-] at incidence angles ``theta_i`` [rad] (1-D) for any
    ``brdf(wi, wo)``, integrated over the half vector (``dωo = 4 (wi·h) dωh``), where specular
    lobes of every model sit near the normal: Gauss–Legendre in ``u`` with ``θh = (π/2)u²``
    (nodes dense near the normal) on each piece between ``theta_h_breaks`` [rad] (put the
    discontinuities of ``D`` there, e.g. the uniform distribution's edge) × in ``φh``."""
    ti = np.atleast_1d(np.asarray(theta_i, dtype=float))
    edges = sorted(
        {
            0.0,
            1.0,
            *(math.sqrt(b / (0.5 * math.pi)) for b in theta_h_breaks if 0 < b < 0.5 * math.pi),
        }
    )
    x, w = gauss_legendre(n_theta)
    us, ws = [], []
    for lo, hi in zip(edges[:-1], edges[1:], strict=True):
        us.append(lo + 0.5 * (hi - lo) * (x + 1))
        ws.append(0.5 * (hi - lo) * w)
    u, wu = np.concatenate(us), np.concatenate(ws)
    th = 0.5 * math.pi * u * u
    wth = wu * math.pi * u  # dθh = π u du
    xp, wp = gauss_legendre(n_phi)
    ph = math.pi * (xp + 1)
    wph = math.pi * wp
    T, P = np.meshgrid(th, ph, indexing="ij")
    h = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], -1)
    weight = (wth[:, None] * wph[None, :]) * np.sin(T)
    out = np.empty(ti.size)
    for j, t in enumerate(ti):  # one θi at a time: the integrand grid is vectorized
        wi = np.array([math.sin(t) * math.cos(phi_i), math.sin(t) * math.sin(phi_i), math.cos(t)])
        d = h @ wi
        wo = 2 * d[..., None] * h - wi
        ok = (d > 0) & (wo[..., 2] > 0)
        wo_safe = np.where(ok[..., None], wo, np.array([0.0, 0.0, 1.0]))
        f = brdf(np.broadcast_to(wi, wo.shape), wo_safe)
        out[j] = np.sum(np.where(ok, f * wo[..., 2] * 4 * d, 0.0) * weight)
    return out


def table_from_function(
    brdf: Callable,
    wavelengths,
    *,
    resolution: tuple[int, int] = (90, 180),
    anisotropic: bool = False,
    metadata: dict | None = None,
):
    """A :class:`~.table.BrdfTable` of ``brdf(wi, wo, wavelength)`` [1/sr] on the builders'
    default grid (θ nodes ``k·90°/n``, Δφ on ``[0, π]`` or φ on ``[0, 2π)``), one vectorized
    call per wavelength [m]; ``coherent = 0``. The energy remedy is *not* applied (an analytic
    model's energy is the model's); ``metadata["energy"]`` records its albedo."""
    from emscatter.brdf.build import default_phi, default_phi_d, default_theta, fill_from_function

    th = default_theta(resolution[0])
    phi = default_phi(resolution[1]) if anisotropic else default_phi_d(resolution[1])
    return fill_from_function(brdf, wavelengths, th, phi, anisotropic, metadata or {})
