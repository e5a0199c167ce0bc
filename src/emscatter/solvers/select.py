"""Validity checks across solvers and the ``method="auto"`` choice (BOARD interface 2).

Each solver module reports its own validity (``check_validity(roughness, k, *, eps,
theta_i)``, :mod:`.validity`); :func:`rank_methods` asks them in
:data:`emscatter.solvers.AUTO_ORDER` (cheapest first) and orders them: methods valid for the
roughness *and* at every requested angle first, cheapest first; then the others by how far
their criteria are exceeded (report ``"excess"`` = max log(value/limit), angle criteria
included; ties: fewer failed criteria, then cheaper). :func:`select_method` returns the first.
Outside every validity range the least-bad candidate is used and the caller's
``out_of_range`` policy applies: ``"warn"`` (default, :class:`ValidityWarning`), ``"raise"``
(:class:`ValidityError`), ``"nan"`` (results replaced by NaN, flagged in ``info``) or
``"ignore"``. Per-angle choices (e.g. an energy fallback) read each report's
``angle_valid`` / ``angle_excess``.

**Measured correction** (:mod:`.measured`): for Gaussian and exponential roughness inside the
validity maps' box (kσ ∈ [0.05, 3], kℓ ∈ [0.5, 20]) with a known medium class, the criteria's
ranking is corrected by the maps' measured σ⁰ errors at the nearest cell — when the criteria
put the cell's centre in the same regime (same first method, equally valid; so a limit
between the roughness and the cell centre keeps its say): where the criteria's
first method is measured more than 1 dB off while another candidate is measured within 1 dB
and has no angle-specific failure (an angle check failing by more than its roughness
checks), the cheapest such candidate goes first; where no method is valid and none is measured
within 1 dB, the candidates without angle-specific failures are ordered by measured error
(the maps are at θi = 20°; angle checks keep their say). Each report then
carries ``measured_error_dB`` and the first one ``measured`` (map, cell) and ``picked_by``
(``"criteria"`` or ``"measured"``).

:func:`check_options` maps the solver options a caller passed to the method actually used:
an option of that method is kept; an accuracy or execution knob that a closed-form method
satisfies anyway (``threads``, ``rtol``, ``max_terms``) is dropped; ``shadowing=False`` is
dropped for methods without shadowing; anything else is a ValueError naming the option, the
method that was picked (and that ``auto`` picked it) and the options that method takes.
"""

from __future__ import annotations

import inspect
import math
import warnings
from functools import lru_cache
from typing import Literal

import numpy as np

from . import AUTO_ORDER, get

__all__ = [
    "ValidityWarning",
    "ValidityError",
    "rank_methods",
    "select_method",
    "validity",
    "check_options",
    "solver_options",
    "enforce",
    "check_out_of_range",
]

OutOfRange = Literal["warn", "raise", "nan", "ignore"]
OUT_OF_RANGE_CHOICES = ("warn", "raise", "nan", "ignore")


class ValidityWarning(UserWarning):
    """A solver was used outside its documented validity range."""


class ValidityError(ValueError):
    """A solver was asked for outside its validity range with ``out_of_range="raise"``."""


def check_out_of_range(value) -> str:
    if value not in OUT_OF_RANGE_CHOICES:
        raise ValueError(f"out_of_range must be one of {OUT_OF_RANGE_CHOICES}, got {value!r}")
    return value


@lru_cache(maxsize=32)
def _takes(name: str) -> frozenset:
    """Keyword parameters of a solver's ``check_validity`` (eps/theta_i support)."""
    params = inspect.signature(get(name).check_validity).parameters
    return frozenset(params)


def _report(name: str, roughness, k: float, eps, theta_i) -> dict:
    takes = _takes(name)
    kw = {}
    if eps is not None and "eps" in takes:
        kw["eps"] = eps
    if theta_i is not None and "theta_i" in takes:
        kw["theta_i"] = theta_i
    try:
        return get(name).check_validity(roughness, k, **kw)
    except (ValueError, TypeError) as exc:  # e.g. a solver that cannot take this roughness
        return {"valid": False, "reasons": [str(exc)], "unsupported": True, "excess": math.inf}


def rank_methods(
    roughness, k: float, *, eps=None, theta_i=None, methods=AUTO_ORDER
) -> list[tuple[str, dict]]:
    """``[(name, validity report), ...]`` best first (module docstring) for wavenumber ``k``
    [rad/m], permittivity ``eps`` and incidence angles ``theta_i`` [rad] (any shape, optional).

    Raises ValueError when no method supports the roughness."""
    ranked, reports = _criteria_rank(roughness, k, eps, theta_i, methods)
    ranked = _measured_correction(ranked, reports, roughness, k, eps, theta_i, methods)
    ranked += [n for n in methods if reports[n].get("unsupported")]
    return [(n, reports[n]) for n in ranked]


def _criteria_rank(roughness, k, eps, theta_i, methods) -> tuple[list[str], dict]:
    """Supported methods ranked by their validity criteria alone, and every report."""
    reports = {n: _report(n, roughness, k, eps, theta_i) for n in methods}
    supported = [n for n in methods if not reports[n].get("unsupported")]
    if not supported:
        raise ValueError(
            "no solver supports this roughness: "
            + "; ".join(f"{n}: {r['reasons'][0]}" for n, r in reports.items())
        )
    order = {n: i for i, n in enumerate(methods)}

    def key(n):
        r = reports[n]
        if r["valid"]:
            return (0, 0.0, 0, order[n])
        return (1, r.get("excess", math.inf), len(r.get("reasons", [])), order[n])

    return sorted(supported, key=key), reports


def _measured_correction(ranked, reports, roughness, k, eps, theta_i, methods) -> list[str]:
    """The criteria's ranking corrected by the measured map errors (module docstring)."""
    from .measured import TOL_DB, cell_roughness, measured_errors

    meas = measured_errors(roughness, k, eps)
    if meas is None or not ranked:
        return ranked
    # the cell speaks for this roughness only if the criteria put both in the same regime
    center, center_reports = _criteria_rank(
        cell_roughness(roughness, k, meas["cell"]), k, eps, theta_i, methods
    )
    first = ranked[0]
    if center[:1] != [first] or center_reports[first]["valid"] != reports[first]["valid"]:
        return ranked
    err = {n: meas["errors"].get(n, math.nan) for n in ranked}
    for n in ranked:
        reports[n] = {**reports[n], "measured_error_dB": err[n]}

    def angles_ok(n):  # no angle-specific failure (one worse than the roughness checks')
        r = reports[n]
        a = r.get("angle_valid")
        if a is None or bool(np.all(a)):
            return True
        worst = float(np.max(r.get("angle_excess", math.inf)))
        return worst <= r.get("roughness_excess", 0.0) + 1e-9

    good = [n for n in methods if n in err and err[n] <= TOL_DB and angles_ok(n)]
    picked_by = "criteria"
    if good and not err[first] <= TOL_DB:
        ranked = [good[0]] + [n for n in ranked if n != good[0]]
        picked_by = "measured"
    elif not good and not reports[first]["valid"]:
        finite = [n for n in ranked if math.isfinite(err[n]) and angles_ok(n)]
        finite.sort(key=lambda n: err[n])
        if finite and finite[0] != first:
            ranked = finite + [n for n in ranked if n not in finite]
            picked_by = "measured"
    reports[ranked[0]] = {
        **reports[ranked[0]],
        "measured": {"map": meas["map"], "cell": meas["cell"]},
        "picked_by": picked_by,
    }
    return ranked


def select_method(
    roughness, k: float, methods=AUTO_ORDER, *, eps=None, theta_i=None
) -> tuple[str, dict]:
    """The first of :func:`rank_methods` and every method's report ``{name: report}``."""
    ranked = rank_methods(roughness, k, eps=eps, theta_i=theta_i, methods=methods)
    return ranked[0][0], dict(ranked)


def validity(roughness, k: float, methods=AUTO_ORDER, *, eps=None, theta_i=None) -> dict:
    """Validity report of each method for this roughness and wavenumber ``k`` [rad/m]."""
    return {n: _report(n, roughness, k, eps, theta_i) for n in methods}


# ----------------------------------------------------------------------------- options
#: Knobs that only tune accuracy or execution; a method without them meets them anyway.
_DROPPABLE = ("threads", "rtol", "max_terms")


def solver_options(name: str) -> tuple[str, ...]:
    """Names of the options the solver ``name`` takes (its module's ``OPTIONS``, else the
    keyword-only parameters of its ``bistatic``)."""
    mod = get(name)
    opts = getattr(mod, "OPTIONS", None)
    if opts is None:
        params = inspect.signature(mod.bistatic).parameters.values()
        opts = tuple(p.name for p in params if p.kind is inspect.Parameter.KEYWORD_ONLY)
    return tuple(opts)


def check_options(name: str, options: dict, *, picked_by_auto: bool) -> dict:
    """The options to pass to solver ``name`` (module docstring), or a ValueError."""
    allowed = solver_options(name)
    out = {}
    for opt, value in options.items():
        if opt in allowed:
            out[opt] = value
            continue
        if picked_by_auto and opt in _DROPPABLE:
            continue
        if picked_by_auto and opt == "shadowing" and value in (False, None):
            continue
        how = f"method='auto' picked {name!r}" if picked_by_auto else f"method {name!r}"
        hint = (
            "; pass the method explicitly (method=...) to use it, or drop the option"
            if picked_by_auto
            else ""
        )
        raise ValueError(
            f"option {opt}={value!r} does not apply: {how}, which takes "
            f"{sorted(allowed) or 'no options'}{hint}"
        )
    return out


def enforce(name: str, report: dict, out_of_range: str, *, stacklevel: int = 3) -> bool:
    """Apply the out-of-range policy for ``name``; returns True when results must become NaN."""
    if report.get("valid", True):
        return False
    why = "; ".join(report.get("reasons", [])) or "outside its validity range"
    msg = f"method {name!r} used outside its validity range: {why}"
    if out_of_range == "raise":
        raise ValidityError(msg)
    if out_of_range == "warn":
        warnings.warn(msg, ValidityWarning, stacklevel=stacklevel)
    return out_of_range == "nan"


# ----------------------------------------------------------------------------- blending
#: Half-width of auto's transition band, as a factor on the deciding parameter (kσ or kℓ):
#: within a factor :data:`BLEND_FACTOR` of a switch the two methods are blended.
BLEND_FACTOR = 1.25
_PROBES = 4  # probes per ray (a region narrower than δ/4 between them can be missed)
_BISECT = 12  # bisection steps locating a switch (its position to δ/4096)


def _scaled(roughness, log_s: float, log_l: float):
    """``roughness`` with σ scaled by ``e^log_s`` and both correlation lengths by ``e^log_l``."""
    p = roughness._params()
    fs, fl = math.exp(log_s), math.exp(log_l)
    p.update(sigma=p["sigma"] * fs, length=p["length"] * fl)
    if p.get("length_y") is not None:
        p["length_y"] = p["length_y"] * fl
    if roughness.dimension == 1:
        p["length_y"] = None
    return type(roughness)(**p)


def _smooth(t: float) -> float:
    """C¹ step on [0, 1]: 0 → 0, 1 → 1."""
    t = min(max(t, 0.0), 1.0)
    return t * t * (3.0 - 2.0 * t)


def _ray_switches(at, p0: str, end: float) -> list[tuple[float, str]]:
    """Every change of ``at(t)`` (the pick at log-offset ``t``) met going from ``t = 0``
    (pick ``p0``) to ``end``: ``[(t, method entered), ...]`` in order. :data:`_PROBES` probes
    catch regions wider than ``|end|/_PROBES``; between two probes, the interval is bisected
    to its first change, then again from there to the probe while the pick still differs, so
    that two switches between the same probes are both found (a region crossed on the way,
    e.g. IEM's between PO below and GO above, is not skipped)."""
    out = []
    lo, m_lo = 0.0, p0
    for j in range(1, _PROBES + 1):
        probe = end * j / _PROBES
        for _ in range(len(AUTO_ORDER) + 2):  # (each pass enters a new region; bounded)
            if at(probe) == m_lo:
                break
            hi = probe
            for _ in range(_BISECT):  # m_lo at lo, another at hi: to the first change
                mid = 0.5 * (lo + hi)
                if at(mid) == m_lo:
                    lo = mid
                else:
                    hi = mid
            m_lo, lo = at(hi), hi
            out.append((hi, m_lo))
        lo = probe
    return out


def blend_weights(roughness, k: float, *, eps=None, methods=AUTO_ORDER) -> dict:
    """The methods ``method="auto"`` blends for this roughness and their weights.

    ``auto``'s choice (:func:`rank_methods`, first) is piecewise constant over
    ``(log kσ, log kℓ)``: it switches where a validity limit is crossed (SPM's ``kσ ≤ 0.3``
    and slope, GO's stationary phase ``(2kσ)² ≥ 10`` and ``kℓ ≥ 6``, PO's ``kℓ`` and slope,
    the IEM's ``kσ ≤ 3`` and slope), where two out-of-range methods' excesses cross, and at
    the edges of the measured correction (map cells, the 1 dB tolerance; :mod:`.measured`).
    Between methods that disagree (up to ~3 dB, e.g. IEM → GO at ``kσ = √10/2``) a hard
    switch is a jump in σ⁰. So within a factor :data:`BLEND_FACTOR` of a switch σ⁰ is the
    linear combination ``Σ wₘ σ⁰ₘ``, a tensor product of 1-D blends: along kσ, the method of
    the side the roughness is on has raw weight 1 and each region met within the band
    ``s(1 − d/δ)`` (``d`` the distance to it in log kσ, ``δ = ln BLEND_FACTOR``, ``s`` a C¹
    step; the nearest entry per method); each of those regions, at the point where it is
    entered, is blended likewise along kℓ (normalized), and the products are summed and
    normalized: ``½ : ½`` at a switch, pure a factor ``BLEND_FACTOR`` away, and a neighbour
    that changes identity along kℓ (a corner: e.g. above SPM's kσ = 0.3 the IEM for kℓ < 4,
    PO beyond) fades instead of swapping. Linear (not dB) because σ⁰ integrates
    linearly: the blend's hemispherical reflectivity is the same convex combination of the
    methods' ones, so a blend of two energy-conserving answers conserves energy. The
    switches are found numerically (:func:`_ray_switches`: probes to ``± ln BLEND_FACTOR``,
    bisection to every switch between them), so they need no list kept in
    step with the criteria: a new limit or map blends like the others.

    Returns ``{"weights": {name: w}, "switches": [...], "pick": name}`` (weights sum to 1,
    names in decreasing weight; each switch: parameter, value of kσ or kℓ at the switch,
    methods on both sides; ``pick``: the method ``auto`` ranks first at the roughness itself,
    whose validity the blend reports). Roughness without a size scaling (not a
    :class:`~emscatter.spectra.Roughness`) gets its pick with weight 1."""
    methods = tuple(methods)
    picks: dict[tuple[float, float], str] = {}  # one ranking per probed point

    def pick(ls: float, ll: float) -> str:
        hit = picks.get((ls, ll))
        if hit is None:
            r = roughness if ls == 0.0 and ll == 0.0 else _scaled(roughness, ls, ll)
            hit = picks[(ls, ll)] = rank_methods(r, k, eps=eps, methods=methods)[0][0]
        return hit

    p0 = pick(0.0, 0.0)
    if not hasattr(roughness, "_params"):
        return {"weights": {p0: 1.0}, "switches": [], "pick": p0}
    d = math.log(BLEND_FACTOR)

    def line_blend(ls: float, ll: float, axis: int, m: str) -> dict:
        """1-D blend at ``(ls, ll)`` (pick ``m``) along ``axis``: ``{method: (raw weight,
        (ls, ll) where its region is entered)}``, ``m`` itself 1 at the point."""
        out = {m: (1.0, (ls, ll))}
        for sign in (1.0, -1.0):
            if axis == 0:
                hits = _ray_switches(lambda t: pick(ls + t, ll), m, sign * d)
            else:
                hits = _ray_switches(lambda t: pick(ls, ll + t), m, sign * d)
            for t, other in hits:
                r = _smooth(1.0 - abs(t) / d)
                if other != m and r > out.get(other, (0.0,))[0]:
                    out[other] = (r, (ls + t, ll) if axis == 0 else (ls, ll + t))
        return out

    # tensor product: the kσ blend, each of its regions blended along kℓ where it is met (so
    # a neighbour that changes identity along kℓ — a corner, e.g. IEM above SPM's kσ = 0.3
    # for kℓ < 4 and PO for kℓ > 4 — fades instead of swapping)
    raw: dict[str, float] = {}
    switches = []
    for m, (r, point) in line_blend(0.0, 0.0, 0, p0).items():
        across = line_blend(*point, 1, m)
        total = sum(w for w, _ in across.values())
        for other, (w, at) in across.items():
            raw[other] = raw.get(other, 0.0) + r * w / total
            if other != m:
                switches.append({"parameter": "k_l", "at": k * roughness.length * math.exp(at[1]),
                                 "methods": (m, other)})  # fmt: skip
        if m != p0:
            switches.append({"parameter": "k_sigma", "at": k * roughness.sigma * math.exp(point[0]),
                             "methods": (p0, m)})  # fmt: skip
    total = sum(raw.values())
    weights = {n: r / total for n, r in raw.items()}
    order = sorted(weights, key=lambda n: -weights[n])
    return {"weights": {n: weights[n] for n in order}, "switches": switches, "pick": p0}
