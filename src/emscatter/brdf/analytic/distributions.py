"""Microfacet distributions ``D(ĥ)`` of the seed's chapters 2–3, normalized
``∫ D(ĥ) cosθh dωh = 1``, with Smith's ``Λ`` for shadowing.

Renderer frame (normal ``+z``, tangent ``+x``); ``h`` are unit half vectors ``(..., 3)``.

* :class:`Beckmann` — seed eq. 2.14 (``m`` the rms slope, ``α = m``; the GO distribution of a
  Gaussian surface with ``m = 2σ/T``, eq. 3.1), anisotropic (``α_x``, ``α_y``) as in Mitsuba.
  The seed's corrected Ward distribution (eq. 3.2, Ward with ``1/cos⁴γ``) is this one.
* :class:`GGX` — Trowbridge–Reitz (Walter et al. 2007), for fits and Mitsuba's ``ggx``.
* :class:`BlinnPhongDistribution` — ``(n+2)/(2π) cosⁿθh`` (the seed's ``(N·H)^n``, eq. 2.19).
* :class:`AshikhminShirleyDistribution` — ``√((nu+1)(nv+1))/(2π) cos^(nu cos²φh + nv sin²φh)θh``
  (seed eq. 2.22's lobe, Ashikhmin & Shirley 2000).
* :class:`SeedDistribution` — the seed's non-Gaussian facet-angle densities (eqs. 3.8–3.12):
  uniform, exponential, Rayleigh, Cauchy, Simpson (triangular). The seed writes a density
  ``d(α)`` of the facet tilt angle ``α`` (signed, in the profile picture of Fig. 2.8) and puts it
  in Cook–Torrance in place of Beckmann's ``D`` (section 3.3.2: "only the distribution term
  changes"). Here ``D(θh) = c · (d(θh) + d(−θh))`` (``θh = |α|``), with ``c`` set so that the
  distribution is normalized; that is the seed's ``D = c·d(γ)`` (as for Blinn's eq. 2.13) made
  energy-consistent.

Smith's ``Λ`` (Smith 1967; Walter et al. 2007 eqs. 18–27): closed forms for Beckmann and GGX;
for the radial (isotropic) distributions it is computed once from the slope density
``P22(r) = D(θh) cos⁴θh`` (``r = tanθh``) by the polar form
``Λ(a) = (2/a) ∫_a^∞ (√(r² − a²) − a·acos(a/r)) P22(r) r dr`` with ``a = cotθ`` (tested against
Beckmann's closed form).
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from functools import cached_property

import numpy as np
from scipy import special

from emscatter.brdf.grid import gauss_legendre
from emscatter.conventions import check_positive

__all__ = [
    "Distribution",
    "Beckmann",
    "GGX",
    "BlinnPhongDistribution",
    "AshikhminShirleyDistribution",
    "SeedDistribution",
    "SEED_KINDS",
]

HALF_PI = 0.5 * math.pi


def _gl(n: int, a: float, b: float):
    return gauss_legendre(n, a, b)


def _cos_tan2(w):
    """``(cosθ, tan²θ, φ)`` of unit vectors ``w`` (``tan² = inf`` on the horizon)."""
    w = np.asarray(w, dtype=float)
    c = w[..., 2]
    s2 = w[..., 0] ** 2 + w[..., 1] ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        t2 = np.where(c > 0, s2 / np.where(c > 0, c * c, 1.0), np.inf)
    return c, t2, np.arctan2(w[..., 1], w[..., 0])


class Distribution(ABC):
    """A normalized microfacet distribution (``∫ D cosθh dωh = 1``)."""

    name: str = "distribution"

    @abstractmethod
    def __call__(self, h) -> np.ndarray:
        """``D(ĥ)`` [1/sr] at unit half vectors ``h`` (``(..., 3)``); 0 for ``h.z ≤ 0``."""

    @abstractmethod
    def smith_lambda(self, w) -> np.ndarray:
        """Smith's ``Λ(ω)`` [-] for unit directions ``w`` (``G1 = 1/(1 + Λ)``)."""

    @property
    def params(self) -> dict:
        return {}

    @cached_property
    def rms_slope(self) -> float:
        """Total rms slope ``m = √⟨tan²θh⟩`` (Beckmann: ``α`` for isotropic, ``√((αx²+αy²)/2)``)
        — the ``m`` of Schlick's shadowing (seed eq. 2.12)."""
        th, wt = _gl(400, 0.0, HALF_PI - 1e-9)
        ph, wp = _gl(64, 0.0, 2 * math.pi)
        T, P = np.meshgrid(th, ph, indexing="ij")
        h = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], -1)
        integrand = self(h) * np.tan(T) ** 2 * np.cos(T) * np.sin(T)
        return float(math.sqrt(np.einsum("ij,i,j->", integrand, wt, wp)))

    def describe(self) -> str:
        args = ", ".join(f"{k}={v:g}" for k, v in self.params.items())
        return f"{self.name}({args})"


class _Elliptic(Distribution):
    """Shared pieces of the (an)isotropic Beckmann and GGX distributions."""

    def __init__(self, alpha: float, alpha_y: float | None = None):
        self.alpha_x = check_positive("alpha", alpha)
        self.alpha_y = self.alpha_x if alpha_y is None else check_positive("alpha_y", alpha_y)

    @property
    def params(self) -> dict:
        return {"alpha_x": self.alpha_x, "alpha_y": self.alpha_y}

    def _slope2(self, h):
        """``(cosθh, tan²θh·(cos²φ/αx² + sin²φ/αy²))``."""
        h = np.asarray(h, dtype=float)
        c = h[..., 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            q = (h[..., 0] / self.alpha_x) ** 2 + (h[..., 1] / self.alpha_y) ** 2
            e = np.where(c > 0, q / np.where(c > 0, c * c, 1.0), np.inf)
        return c, e

    def _alpha_along(self, w):
        """``α`` projected on the azimuth of ``w``: ``√(αx² cos²φ + αy² sin²φ)``."""
        w = np.asarray(w, dtype=float)
        s2 = w[..., 0] ** 2 + w[..., 1] ** 2
        with np.errstate(divide="ignore", invalid="ignore"):
            a2 = np.where(
                s2 > 0,
                (self.alpha_x**2 * w[..., 0] ** 2 + self.alpha_y**2 * w[..., 1] ** 2)
                / np.where(s2 > 0, s2, 1.0),
                self.alpha_x**2,
            )
        return np.sqrt(a2)


class Beckmann(_Elliptic):
    """``D = exp(−tan²θh (cos²φh/αx² + sin²φh/αy²)) / (π αx αy cos⁴θh)`` (seed eq. 2.14 with
    ``m = α``, normalized; Walter et al. 2007 eq. 25)."""

    name = "beckmann"

    def __call__(self, h):
        c, e = self._slope2(h)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            d = np.exp(-e) / (math.pi * self.alpha_x * self.alpha_y * c**4)
        return np.where(c > 0, d, 0.0)

    def smith_lambda(self, w):
        c, t2, _ = _cos_tan2(w)
        with np.errstate(divide="ignore", invalid="ignore"):
            a = np.where(t2 > 0, 1.0 / (self._alpha_along(w) * np.sqrt(t2)), np.inf)
        out = np.zeros(np.shape(a))
        need = a < 6.0  # Λ < 1e-17 beyond
        an = np.maximum(a[need], 1e-300)
        out[need] = 0.5 * (np.exp(-an * an) / (an * math.sqrt(math.pi)) - special.erfc(an))
        return np.maximum(out, 0.0)

    @cached_property
    def rms_slope(self) -> float:
        return math.sqrt(0.5 * (self.alpha_x**2 + self.alpha_y**2))


class GGX(_Elliptic):
    """``D = 1 / (π αx αy cos⁴θh (1 + tan²θh (cos²φh/αx² + sin²φh/αy²))²)`` (Walter et al.
    2007 eq. 33)."""

    name = "ggx"

    def __call__(self, h):
        c, e = self._slope2(h)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            d = 1.0 / (math.pi * self.alpha_x * self.alpha_y * c**4 * (1.0 + e) ** 2)
        return np.where(c > 0, d, 0.0)

    def smith_lambda(self, w):
        _, t2, _ = _cos_tan2(w)
        a2t2 = self._alpha_along(w) ** 2 * t2
        with np.errstate(invalid="ignore"):
            return np.where(np.isfinite(a2t2), 0.5 * (np.sqrt(1.0 + a2t2) - 1.0), np.inf)

    @cached_property
    def rms_slope(self) -> float:  # GGX slopes have infinite variance
        return math.inf


class _Radial(Distribution):
    """An isotropic distribution from an unnormalized shape ``g(θh)``, normalized numerically,
    with a tabulated Smith ``Λ``."""

    #: discontinuities of ``g`` in θh (quadrature breakpoints)
    breaks: tuple[float, ...] = ()

    @abstractmethod
    def shape(self, theta_h: np.ndarray) -> np.ndarray:
        """Unnormalized ``g(θh) ≥ 0`` on ``[0, π/2]``."""

    def _nodes(self, n: int = 200):
        pts = sorted({0.0, HALF_PI, *(b for b in self.breaks if 0 < b < HALF_PI)})
        xs, ws = zip(*(_gl(n, a, b) for a, b in zip(pts[:-1], pts[1:], strict=True)), strict=True)
        return np.concatenate(xs), np.concatenate(ws)

    @cached_property
    def norm(self) -> float:
        """``c`` with ``2π c ∫ g(θ) cosθ sinθ dθ = 1``."""
        th, w = self._nodes()
        total = 2 * math.pi * np.sum(w * self.shape(th) * np.cos(th) * np.sin(th))
        if not total > 0:
            raise ValueError(f"{self.describe()} has no weight in [0, π/2]")
        return 1.0 / total

    @cached_property
    def rms_slope(self) -> float:
        th, w = self._nodes()
        if self.shape(np.array(HALF_PI)) > 1e-9 * np.max(self.shape(th)):
            return math.inf  # D(π/2) > 0: ⟨tan²θh⟩ diverges (logarithmically)
        th = np.minimum(th, HALF_PI - 1e-12)
        m2 = 2 * math.pi * self.norm * np.sum(w * self.shape(th) * np.sin(th) ** 3 / np.cos(th))
        return float(math.sqrt(m2))

    def __call__(self, h):
        c = np.asarray(h, dtype=float)[..., 2]
        th = np.arccos(np.clip(c, -1.0, 1.0))
        return np.where(c > 0, self.norm * self.shape(np.minimum(th, HALF_PI)), 0.0)

    @cached_property
    def _lambda_table(self):
        """``(log a, log Λ, tail)`` on a grid of ``a = cotθ``, from the slope density."""
        th, w = self._nodes(400)
        th = np.minimum(th, HALF_PI - 1e-12)
        r = np.tan(th)
        p22 = self.norm * self.shape(th) * np.cos(th) ** 4
        jac = w / np.cos(th) ** 2  # dr = dθ / cos²θ
        a = np.logspace(-4, 3, 300)
        ra = r[None, :]
        aa = a[:, None]
        with np.errstate(invalid="ignore"):
            kern = np.where(
                ra > aa,
                np.sqrt(np.maximum(ra * ra - aa * aa, 0.0))
                - aa * np.arccos(np.minimum(aa / np.where(ra > 0, ra, 1.0), 1.0)),
                0.0,
            )
        lam = (2.0 / a) * np.sum(kern * p22 * ra * jac, axis=1)
        # grazing (a → 0): Λ → E[ζx⁺]/a, so a·Λ at the first node continues the table
        return np.log(a), np.log(np.maximum(lam, 1e-300)), a[0] * lam[0]

    def smith_lambda(self, w):
        _, t2, _ = _cos_tan2(w)
        with np.errstate(divide="ignore"):
            a = np.where(t2 > 0, 1.0 / np.sqrt(t2), np.inf)
        loga, loglam, tail = self._lambda_table
        out = np.exp(np.interp(np.log(np.clip(a, 1e-300, 1e300)), loga, loglam))
        out = np.where(a < math.exp(loga[0]), tail / np.maximum(a, 1e-300), out)
        return np.where(a > math.exp(loga[-1]), 0.0, out)


class BlinnPhongDistribution(_Radial):
    """``D = (n + 2)/(2π) cosⁿθh`` — the seed's Blinn lobe ``(N·H)^{n_B}`` (eq. 2.19),
    normalized."""

    name = "blinn-phong"

    def __init__(self, n: float):
        self.n = check_positive("n", n)

    @property
    def params(self):
        return {"n": self.n}

    @cached_property
    def norm(self) -> float:
        return (self.n + 2.0) / (2.0 * math.pi)

    def shape(self, theta_h):
        return np.cos(theta_h) ** self.n


class AshikhminShirleyDistribution(Distribution):
    """``D = c cos^(nu cos²φh + nv sin²φh)θh`` (Ashikhmin & Shirley 2000; seed eqs. 2.22,
    2.24) with ``c = 1/∫₀^{2π} dφ/(e(φ) + 2)`` so that ``∫ D cosθh dωh = 1`` (``c = (n+2)/(2π)``
    when ``nu = nv = n``). The paper's ``√((nu+1)(nv+1))/(2π)`` normalizes ``∫ D dωh`` instead
    (its sampling pdf) and is kept in :func:`emscatter.brdf.analytic.ashikhmin_shirley`.
    Smith's Λ is not available in closed form: use Schlick or Blinn shadowing with it."""

    name = "ashikhmin-shirley"

    def __init__(self, nu: float, nv: float):
        self.nu = check_positive("nu", nu)
        self.nv = check_positive("nv", nv)
        ph, w = _gl(256, 0.0, HALF_PI)  # e(φ) has period π and mirror symmetry
        e = self.nu * np.cos(ph) ** 2 + self.nv * np.sin(ph) ** 2
        self.norm = 1.0 / (4.0 * float(np.sum(w / (e + 2.0))))

    @property
    def params(self):
        return {"nu": self.nu, "nv": self.nv}

    def exponent(self, h):
        """``nu cos²φh + nv sin²φh`` at half vectors ``h``."""
        h = np.asarray(h, dtype=float)
        s2 = h[..., 0] ** 2 + h[..., 1] ** 2
        with np.errstate(invalid="ignore", divide="ignore"):
            e = (self.nu * h[..., 0] ** 2 + self.nv * h[..., 1] ** 2) / np.where(s2 > 0, s2, 1.0)
        return np.where(s2 > 0, e, 0.5 * (self.nu + self.nv))

    def __call__(self, h):
        c = np.asarray(h, dtype=float)[..., 2]
        return np.where(c > 0, self.norm * np.maximum(c, 0.0) ** self.exponent(h), 0.0)

    def smith_lambda(self, w):
        raise ValueError(
            "Smith shadowing is not available for the Ashikhmin–Shirley distribution; "
            "use shadowing='schlick', 'blinn' or 'none'"
        )


#: the seed's non-Gaussian facet-angle densities (eqs. 3.8–3.12) and their parameters
SEED_KINDS = {
    "uniform": ("a",),  # eq. 3.8: 1/(2a) on [−a, a]
    "exponential": ("lam",),  # eq. 3.9: λ e^{−λ|α|}
    "rayleigh": ("sigma",),  # eq. 3.10: α/σ² e^{−α²/(2σ²)}, α > 0
    "cauchy": ("a",),  # eq. 3.11: a/(π(a² + α²))
    "simpson": ("a", "b", "c"),  # eq. 3.12: triangular on [a, b], mode c
}


class SeedDistribution(_Radial):
    """The seed's non-Gaussian distributions (eqs. 3.8–3.12) as normalized microfacet
    distributions ``D(θh) = c (d(θh) + d(−θh))`` (module docstring). Angles [rad].

    ``SeedDistribution("uniform", a=0.1)``, ``("exponential", lam=0.5)``,
    ``("rayleigh", sigma=0.1)``, ``("cauchy", a=0.1)``, ``("simpson", a=-1, b=1, c=0)``
    (the seed's Fig. 3.13–3.17 values; ``simpson(a=1)`` alone means the symmetric triangle on
    ``[−1, 1]``).
    """

    def __init__(self, kind: str, **params):
        if kind not in SEED_KINDS:
            raise ValueError(f"kind must be one of {sorted(SEED_KINDS)}, got {kind!r}")
        if kind == "simpson" and set(params) == {"a"}:
            w = check_positive("a", params["a"])
            params = {"a": -w, "b": w, "c": 0.0}
        need = SEED_KINDS[kind]
        if set(params) != set(need):
            raise ValueError(f"{kind} distribution takes parameters {need}, got {sorted(params)}")
        p = {k: float(v) for k, v in params.items()}
        if kind == "simpson":
            if not (p["a"] < p["b"] and p["a"] <= p["c"] <= p["b"]):
                raise ValueError(f"simpson needs a ≤ c ≤ b with a < b, got {p}")
            self.breaks = tuple(abs(x) for x in (p["a"], p["b"], p["c"]))
        else:
            for k, v in p.items():
                check_positive(k, v, unit="rad" if k != "lam" else "1/rad")
            if kind == "uniform":
                self.breaks = (p["a"],)
        self.kind = kind
        self._p = p
        self.name = kind

    @property
    def params(self):
        return dict(self._p)

    def density(self, alpha) -> np.ndarray:
        """The seed's ``d(α)`` (eqs. 3.8–3.12) of the signed facet angle ``α`` [rad]."""
        a = np.asarray(alpha, dtype=float)
        p = self._p
        if self.kind == "uniform":
            return np.where(np.abs(a) <= p["a"], 0.5 / p["a"], 0.0)
        if self.kind == "exponential":
            return p["lam"] * np.exp(-p["lam"] * np.abs(a))
        if self.kind == "rayleigh":
            s2 = p["sigma"] ** 2
            return np.where(a > 0, a / s2 * np.exp(-(a * a) / (2 * s2)), 0.0)
        if self.kind == "cauchy":
            return p["a"] / (math.pi * (p["a"] ** 2 + a * a))
        lo, hi, mode = p["a"], p["b"], p["c"]
        up = np.where(mode > lo, 2 * (a - lo) / ((hi - lo) * max(mode - lo, 1e-300)), 0.0)
        down = np.where(hi > mode, 2 * (hi - a) / ((hi - lo) * max(hi - mode, 1e-300)), 0.0)
        return np.where((a > lo) & (a <= mode), up, np.where((a > mode) & (a < hi), down, 0.0))

    def shape(self, theta_h):
        return self.density(theta_h) + self.density(-np.asarray(theta_h))
