"""Validity reports shared by every solver (BOARD interface 1) and the slope "the wave sees".

Every solver's ``check_validity(roughness, k, *, eps=None, theta_i=None, **solver_options)``
builds its report here, so that all reports read alike::

    "valid"         bool   every roughness-level check passes (and every angle, with theta_i)
    "reasons"       list[str]  one per failed check: its name, the value, the limit and the
                    factor by which the limit is exceeded (angles in degrees)
    "checks"        dict name -> bool (angle checks: True when every angle passes)
    "details"       dict name -> {"value", "limit", "ratio", "ok", "source"} (roughness checks)
    "excess"        float  max log(ratio) over failed checks, angles included (0 when valid)
    with theta_i (radians, any shape):
    "angle_valid"   bool ndarray of theta_i's shape (all angle checks pass at that angle)
    "angle_excess"  float ndarray, max log(ratio) over the angle checks at each angle
    "angle_reasons" list[str]  per failed angle check: the failing range of θi in degrees
    optional, with theta_i:
    "angle_safe_below" float [rad]  every θi ≤ it passes every angle check (a bound the
                    solver proves, e.g. SPM's per-segment bound of r₁): lets
                    :func:`emscatter.method_resolution.angle_report` check only the angles
                    above it when the checks do not grow with θi (``angle_monotone`` False)

A check's ``ratio`` is ``value/limit`` for an upper limit and ``limit/value`` for a lower one,
so ``ratio > 1`` means failed and says by how much; ``excess`` ranks out-of-range methods in
:func:`emscatter.solvers.select.rank_methods`.

Slope of a non-differentiable spectrum
--------------------------------------
The exponential and power-law (H ≤ 1) correlations have an infinite slope variance. What a
wave of wavenumber ``k`` responds to is the part of the spectrum it can scatter into
propagating waves at first order: surface wavenumbers ``|K| ≤ 2k`` (the Bragg band, from
backscatter at grazing, ``|k_s⊥ − k_i⊥| ≤ 2k``). Components with ``|K| > 2k`` only couple to
evanescent waves; they tilt facets shorter than ``λ/2``, which do not reflect as facets. So
the slope used by the validity checks (SPM, GO, PO) and by GO's slope density when no
``k_max`` is given is the slope of the spectrum below ``k_max = 2k``
(:data:`SLOPE_CUTOFF_FACTOR`). :func:`cutoff_slope_variances` gives it in closed form for
isotropic spectra (``∫ K² w``: elementary for the exponential, a hypergeometric function
for the 1-D power law) and by cached quadrature for anisotropic ones; how well GO with this
slope matches the method of moments on exponential profiles is on the validity maps
(validation/validity_maps/, including GO on the MoM grid's own cutoff ``π/dx``).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..spectra import ExponentialCorrelation, PowerLawCorrelation, Roughness

__all__ = [
    "SLOPE_CUTOFF_FACTOR",
    "Check",
    "AngleCheck",
    "upper",
    "lower",
    "angle_upper",
    "angle_lower",
    "unsupported",
    "build_report",
    "cutoff_slope_variances",
    "wave_slope_variances",
    "check_solver_options",
    "with_angle_total",
]

#: ``k_max = SLOPE_CUTOFF_FACTOR · k``: the Bragg band ``|K| ≤ 2k`` (module docstring).
SLOPE_CUTOFF_FACTOR = 2.0


def _fmt(x: float) -> str:
    return f"{float(x):.3g}"


@dataclass(frozen=True)
class Check:
    """One roughness-level criterion. ``ratio > 1`` = failed, by that factor."""

    name: str
    ok: bool
    value: float
    limit: float
    ratio: float
    text: str
    source: str = ""


def upper(name: str, value: float, limit: float, what: str, source: str = "") -> Check:
    """``value ≤ limit`` (e.g. ``kσ ≤ 0.3``)."""
    value, limit = float(value), float(limit)
    ratio = value / limit if limit > 0 else math.inf
    ok = bool(value <= limit)
    text = f"{name}: {what} = {_fmt(value)} > {_fmt(limit)} (limit exceeded ×{ratio:.3g})"
    return Check(name, ok, value, limit, ratio, text, source)


def lower(name: str, value: float, limit: float, what: str, source: str = "") -> Check:
    """``value ≥ limit`` (e.g. ``kℓ ≥ 4``)."""
    value, limit = float(value), float(limit)
    ratio = limit / value if value > 0 else math.inf
    ok = bool(value >= limit)
    text = f"{name}: {what} = {_fmt(value)} < {_fmt(limit)} (short of the limit ×{ratio:.3g})"
    return Check(name, ok, value, limit, ratio, text, source)


def unsupported(name: str, why: str) -> Check:
    """A criterion that cannot be evaluated (infinite excess)."""
    return Check(name, False, math.nan, math.nan, math.inf, f"{name}: {why}")


@dataclass(frozen=True)
class AngleCheck:
    """A criterion per incidence angle: ``ratio`` (theta_i's shape) > 1 fails there."""

    name: str
    ratio: np.ndarray
    value: np.ndarray
    limit: float
    what: str
    source: str = ""
    relation: str = "≤"
    #: ``ratio`` never decreases as θi grows on [0, π/2] (the check fails above one angle):
    #: lets :func:`emscatter.method_resolution.angle_report` decide 1e6 angles by a threshold
    increasing: bool = False

    def reason(self, theta_i: np.ndarray) -> str | None:
        bad = self.ratio > 1
        if not np.any(bad):
            return None
        ratio = np.asarray(self.ratio)
        worst = int(np.argmax(ratio))  # the largest ratio is > 1, so a failing angle ...
        if not ratio.flat[worst] > 1:  # ... unless a NaN came first: the failing ones only
            worst = int(np.argmax(np.where(bad, ratio, -np.inf)))
        failing = np.broadcast_to(theta_i, bad.shape)[bad]  # [rad]; degrees are monotone
        lo, hi = math.degrees(float(failing.min())), math.degrees(float(failing.max()))
        span = f"θi = {lo:.4g}°" if lo == hi else f"θi ∈ [{lo:.4g}°, {hi:.4g}°]"
        v = np.broadcast_to(self.value, bad.shape).ravel()[worst]
        r = np.broadcast_to(ratio, bad.shape).ravel()[worst]
        at = math.degrees(float(np.broadcast_to(theta_i, bad.shape).ravel()[worst]))
        return (
            f"{self.name}: fails for {span} ({np.count_nonzero(bad)} of {bad.size} angles); "
            f"{self.what} must be {self.relation} {_fmt(self.limit)}, worst "
            f"{_fmt(v)} at θi = {at:.4g}° (×{r:.3g})"
        )


def angle_upper(name, value, limit, what, source="", *, increasing=False) -> AngleCheck:
    """Per-angle ``value ≤ limit``; ``increasing``: ``value`` grows with θi (see AngleCheck)."""
    value = np.asarray(value, dtype=float)
    ratio = value / limit if limit > 0 else np.full(value.shape, math.inf)
    return AngleCheck(name, ratio, value, float(limit), what, source, "≤", increasing)


def angle_lower(name, value, limit, what, source="", *, increasing=False) -> AngleCheck:
    """Per-angle ``value ≥ limit``; ``increasing``: ``value`` falls as θi grows."""
    value = np.asarray(value, dtype=float)
    with np.errstate(divide="ignore"):
        ratio = np.where(value > 0, limit / np.where(value > 0, value, 1.0), math.inf)
    return AngleCheck(name, ratio, value, float(limit), what, source, "≥", increasing)


_ANGLE_COUNT = re.compile(r"\((\d+) of \d+ angles\)")


def with_angle_total(reason: str, total: int) -> str:
    """An :meth:`AngleCheck.reason` text with its "(n of m angles)" count out of ``total``
    angles (a report checked on a subset that holds every failing angle)."""
    return _ANGLE_COUNT.sub(lambda m: f"({m[1]} of {int(total)} angles)", reason, count=1)


def build_report(
    roughness: Roughness,
    k: float,
    checks: list[Check],
    *,
    theta_i=None,
    angle_checks: list[AngleCheck] = (),
    **extra,
) -> dict:
    """The report of the module docstring from roughness and angle checks."""
    failed = [c for c in checks if not c.ok]
    reasons = [c.text for c in failed]
    excess = max((math.log(max(c.ratio, 1.0)) for c in failed), default=0.0)
    report = {
        "valid": not failed,
        "reasons": reasons,
        "checks": {c.name: c.ok for c in checks},
        "details": {
            c.name: {
                "value": c.value,
                "limit": c.limit,
                "ratio": c.ratio,
                "ok": c.ok,
                "source": c.source,
            }
            for c in checks
        },
        "excess": excess,
        "roughness_excess": excess,
        "k_sigma": k * roughness.sigma,
        "k_l": k * roughness.length,
    }
    if theta_i is not None:
        ti = np.asarray(theta_i, dtype=float)
        # one reduction per check decides whether any angle fails; only then the stack
        passes = [not a.ratio.size or bool(np.max(a.ratio) <= 1) for a in angle_checks]
        if not all(passes):
            ratios = np.stack([np.broadcast_to(a.ratio, ti.shape) for a in angle_checks])
            with np.errstate(divide="ignore"):
                a_exc = np.max(np.log(np.maximum(ratios, 1.0)), axis=0)
            a_ok = a_exc == 0
        else:  # every angle passes: excess 0, valid everywhere (what the stack would give)
            a_exc, a_ok = np.zeros(ti.shape), np.ones(ti.shape, dtype=bool)
        a_reasons = [a.reason(ti) for a, ok in zip(angle_checks, passes, strict=True) if not ok]
        a_reasons = [r for r in a_reasons if r]
        for a, ok in zip(angle_checks, passes, strict=True):
            report["checks"][a.name] = ok
        report["angle_valid"] = a_ok
        report["angle_excess"] = a_exc
        report["angle_reasons"] = a_reasons
        report["angle_sources"] = {a.name: a.source for a in angle_checks}
        report["angle_monotone"] = all(a.increasing for a in angle_checks)
        report["reasons"] = reasons + a_reasons
        report["valid"] = report["valid"] and bool(np.all(a_ok))
        if a_exc.size:
            report["excess"] = max(excess, float(np.max(a_exc)))
    report.update(extra)
    return report


# ----------------------------------------------------------------------------- slopes
def _isotropic_closed(rough: Roughness, k_max: float) -> tuple[float, float] | None:
    """Closed-form per-direction slope variances of the spectrum below ``k_max``."""
    from scipy import special

    s2, ell = rough.sigma**2, rough.length
    u = k_max * ell
    if type(rough) is ExponentialCorrelation:  # exact types: subclasses may change the spectrum
        h = 0.5
    elif type(rough) is PowerLawCorrelation:
        h = float(rough.hurst)
    else:
        return None
    if rough.dimension == 1:
        # 2 ∫_0^K k² w₁ dk, w₁ = c ℓ (1 + k²ℓ²)^−(H+½):  (2 c/ℓ²) ∫_0^U u² (1+u²)^−a du
        if h == 0.5:
            integral = u - math.atan(u)  # c = 1/π
            return 2 * s2 * integral / (math.pi * ell**2), 0.0
        a = h + 0.5
        c = math.gamma(a) / (math.sqrt(math.pi) * math.gamma(h))
        integral = u**3 / 3 * float(special.hyp2f1(a, 1.5, 2.5, -u * u))
        return 2 * s2 * c * integral / ell**2, 0.0
    # ∫_{|K|<K_c} K² w₂ d²K = (H/ℓ²)[(T^{1−H} − 1)/(1 − H) + (T^{−H} − 1)/H], T = 1 + U²
    # (w₂ = Hℓ²/π (1+K²ℓ²)^−(H+1); H = ½ is the exponential); half of it per direction.
    t = 1.0 + u * u
    if u < 1e-4:  # series: ∫ 2H u³ du (1 − ...) → H U⁴/2
        total = h * u**4 / (2 * ell**2)
    else:
        lt = math.log(t)
        total = h / ell**2 * (math.expm1((1 - h) * lt) / (1 - h) + math.expm1(-h * lt) / h)
    return 0.5 * s2 * total, 0.5 * s2 * total


@lru_cache(maxsize=512)
def cutoff_slope_variances(rough: Roughness, k_max: float) -> tuple[float, float]:
    """Per-direction slope variances ``(⟨h_x²⟩, ⟨h_y²⟩)`` [-] of the spectrum restricted to
    ``|K| < k_max`` [rad/m]: closed forms for isotropic exponential / power-law spectra,
    cached Gauss–Legendre quadrature otherwise (``⟨h_y²⟩ = 0`` for a profile)."""
    if rough.dimension == 1 or rough.is_isotropic:
        closed = _isotropic_closed(rough, float(k_max))
        if closed is not None:
            return closed
    from emscatter.solvers.quadrature import _gl, _segment_nodes  # fixed Gauss–Legendre rules

    x, w = _segment_nodes(0.0, float(k_max), 200)
    if rough.dimension == 1:
        return rough.sigma**2 * float(2.0 * np.sum(w * x * x * rough.spectrum(x))), 0.0
    t, wt = _gl(128)
    psi = 2 * math.pi * t
    kr, ps = np.meshgrid(x, psi, indexing="ij")
    wgt = np.outer(w * x, 2 * math.pi * wt)
    kx, ky = kr * np.cos(ps), kr * np.sin(ps)
    sp = rough.spectrum(kx, ky)
    s2 = rough.sigma**2
    return s2 * float(np.sum(wgt * kx * kx * sp)), s2 * float(np.sum(wgt * ky * ky * sp))


def wave_slope_variances(rough: Roughness, k: float, k_max: float | None = None):
    """Per-direction slope variances the wave sees: the closed form for a differentiable
    (Gaussian) correlation when no ``k_max`` is given, else the spectrum below ``k_max``
    (default ``2k`` for non-differentiable spectra, module docstring). Returns
    ``(sx, sy, k_cut)`` with ``k_cut`` None when no cutoff was used."""
    if k_max is None and rough._mss_closed() is not None:
        sx, sy = rough.mean_square_slope()
        return sx, sy, None
    k_cut = SLOPE_CUTOFF_FACTOR * k if k_max is None else float(k_max)
    sx, sy = cutoff_slope_variances(rough, k_cut)
    return sx, sy, k_cut


def check_solver_options(method: str, options: dict, allowed) -> None:
    """ValueError naming ``method`` and the allowed set when ``options`` has other names."""
    bad = sorted(set(options) - set(allowed))
    if bad:
        raise ValueError(
            f"option(s) {', '.join(map(repr, bad))} not accepted by method {method!r}; "
            f"allowed: {sorted(allowed)}"
        )
