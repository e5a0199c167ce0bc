"""``method="auto"``'s blend: continuous weights over the methods, by construction.

``auto`` chooses, for a roughness, the first method (cheapest first, :data:`AUTO_ORDER`) whose
validity criteria hold; where none holds, the one that exceeds them least; and inside the
validity maps' box, the measured errors correct that choice (:mod:`.measured`). A hard choice
jumps in σ⁰ where it switches (up to ~3 dB co-pol and ~8 dB cross-pol between methods that
disagree there, e.g. IEM → GO at ``kσ = √10/2``). Here each step of that choice is made
smooth, so that the weights ``wₘ`` of ``σ⁰ = Σ wₘ σ⁰ₘ`` are continuous functions of the
roughness — of every parameter the criteria read — with no search for the switches:

1. **Criteria.** A method's margin ``cₘ = max log(value/limit)`` over its roughness checks
   (the ``ratio`` of every check in its validity report, passed ones included: ``cₘ ≤ 0`` is
   valid; an unsupported roughness has ``cₘ = ∞``; a check of the spectrum's kind, not of
   its size — :data:`CATEGORY_CHECKS`, PO's smoothness exponent on conductors — holds fully
   or not at all). Its soft validity
   ``vₘ = s(½ − cₘ / 2δ)``, ``δ = ln`` :data:`BLEND_FACTOR`, ``s`` the C¹ smoothstep: 1 a
   factor :data:`BLEND_FACTOR` inside every limit, 0 a factor outside one, ½ on it.
   "The first valid method" becomes the stick-breaking ``vₘ Π_{j before m} (1 − v_j)``; the
   rest ``Π (1 − v_j)`` (no method valid) goes to the least-exceeded method, softly:
   ``∝ Π_{j≠m} s(½ + (c_j − cₘ)/2δ)`` (the two least-exceeded share it where their
   margins are within ``δ``).
2. **Measured errors.** Inside the maps' box the measured σ⁰ error ``ēₘ`` [dB] is the
   bilinear interpolation (in log kσ, log kℓ) of the four surrounding cells that have a value,
   with an availability ``Aₘ ∈ [0, 1]`` (the interpolation weight of those cells, faded to 0
   over the half step beyond the outermost cells); a method is measured good with weight
   ``gₘ = Aₘ s(½ − (ēₘ − TOL)/2Δ)`` (``TOL = 1 dB``, ``Δ =`` :data:`MEASURED_WIDTH_DB`).
   The criteria's choice ``f`` stays where it is measured good (``g_f``); otherwise the
   cheapest measured-good method takes it (stick-breaking over ``g``), and where none is
   measured good the criteria's choice stays if valid (``v_f``), else the method measured
   closest (a soft argmin of ``ē`` with width Δ, weighted by availability) — the rule of
   :func:`emscatter.solvers.select.rank_methods` with each ``if`` made a weight.

3. **Small weights** fade out (:data:`FADE_WEIGHTS`: below 1 % a method is not run; between 1
   and 3 % its weight is tapered by a smoothstep), and the rest is renormalized: a blend of
   four methods where one carries 0.1 % would cost four solver calls for nothing.

Every factor is a continuous function of the margins and of the interpolated errors, which
are continuous in the roughness, so the weights are; pure (one method, weight 1) wherever every
margin is at least ``δ`` from its limit and every measured error at least Δ from the
tolerance. Linear (not dB) blending because σ⁰ integrates linearly: the blend's hemispherical
reflectivity is the same convex combination of the methods' ones, so a blend of
energy-conserving answers conserves energy. What is not smoothed: the medium class of the
measured maps (conductor for ``|ε| ≥ 100`` or Re ε < 0) is a switch in ε.
The 3-D method of moments' cells (:func:`.measured.measured_errors_3d`) correct
:func:`~emscatter.solvers.select.rank_methods` (with ``theta_i``) but not these weights yet: they
are nearest-cell verdicts per θi, and entering the blend would need them interpolated
continuously in (kσ, kℓ, θi) as the 1-D maps are.

**Backscatter of a dielectric: IEM before PO** (:func:`auto_order`). In backscatter
(``θs = θi``, ``φs = φi + π``; :func:`emscatter.backscatter` tells the API, which passes
``monostatic=True``) the order is :data:`BACKSCATTER_DIELECTRIC_ORDER` — ``spm, go, iem, po`` —
for a dielectric (not PEC, Re ε ≥ 0, ``|ε| < 100``): where both IEM and PO hold, the IEM is
taken. Why: PO's backscatter is the stationary-phase (specular-point) Kirchhoff field, and the
facet that reflects back to the radar is normal to the incident direction, so both
polarizations see the Fresnel coefficient at normal incidence, ``R_h(0) = −R_v(0)``, and
``σ⁰hh = σ⁰vv`` exactly (Ulaby, Moore & Fung 1982 vol. II ch. 12, the stationary-phase Kirchhoff
solution with ``R(0)``; the same for GO). Exact solutions and measurements of dielectric
surfaces at kσ ≲ 2 give ``σ⁰hh < σ⁰vv`` by 1–2 dB at 30–50° (NMM3D, ``validation/auto/``; Oh et
al. 1992's ``p = σhh/σvv ≤ 1``): the polarization dependence there is the complementary
(non-specular, local-slope) part of the tangent-plane field, which the IEM adds to the same
Kirchhoff term (Fung, Li & Chen 1992; Fung 1994; Ulaby, Moore & Fung vol. II ch. 12 on the
Kirchhoff field's slope terms), with the IEM's PO limit checked within 0.03 dB
(``tests/test_iem*.py``). GO stays before both (its regime kσ ≳ 2–3 is where ``hh → vv`` is the
physics); for a conductor (``R_h = −R_v`` at every angle, no dielectric polarization contrast)
and for bistatic geometries (PO's local Fresnel coefficients at the specular facet's own angle
do tell the polarizations apart; BRDF tables and emissivity keep their cost) the order stays
:data:`~emscatter.solvers.AUTO_ORDER`. The order is a switch in the geometry (backscatter or
not) and in the medium class, never in the roughness: for either order the weights stay
continuous in every roughness parameter.
"""

from __future__ import annotations

import math

import numpy as np

from . import AUTO_ORDER
from .measured import TOL_DB, interpolated_errors
from .select import _report

__all__ = [
    "BACKSCATTER_DIELECTRIC_ORDER",
    "BLEND_FACTOR",
    "MEASURED_WIDTH_DB",
    "auto_order",
    "blend_weights",
    "margins",
]

#: Half-width of a transition, as a factor on the parameter a criterion reads (kσ, kℓ, slope):
#: within a factor :data:`BLEND_FACTOR` of a limit the methods on both sides are blended.
BLEND_FACTOR = 1.25
#: Half-width [dB] of the transition at the measured tolerance (``TOL_DB ± Δ``).
MEASURED_WIDTH_DB = 0.1
#: Checks of the spectrum's kind (not of kσ, kℓ): held fully or not at all, never blended.
CATEGORY_CHECKS = frozenset({"smoothness"})
#: Small weights fade out, continuously, before a method is run for them: a weight ``w`` becomes
#: ``w s((w − lo)/(hi − lo))`` (0 below ``lo``, untouched above ``hi``) and the rest is
#: renormalized (the heaviest weight, ≥ 1/4, is never touched, so the sum stays ≥ 1/4).
FADE_WEIGHTS = (0.01, 0.03)
#: ``auto``'s order in backscatter of a dielectric: the IEM before PO (module docstring).
BACKSCATTER_DIELECTRIC_ORDER: tuple[str, ...] = ("spm", "go", "iem", "po")


def _dielectric(eps) -> bool:
    """True for a dielectric medium (every element: Re ε ≥ 0 and ``|ε| < 100``), False for a
    PEC, a conductor or an unknown medium (``eps`` None)."""
    if eps is None or isinstance(eps, str):
        return False
    e = np.asarray(eps, dtype=complex)
    return bool(e.size) and bool(np.all((e.real >= 0) & (np.abs(e) < 100.0)))


def auto_order(eps=None, *, monostatic: bool = False) -> tuple[str, ...]:
    """The methods ``auto`` tries, in order: :data:`BACKSCATTER_DIELECTRIC_ORDER` for the
    backscatter (``monostatic``) of a dielectric ``eps``, else
    :data:`~emscatter.solvers.AUTO_ORDER` (module docstring)."""
    if monostatic and _dielectric(eps):
        return BACKSCATTER_DIELECTRIC_ORDER
    return AUTO_ORDER


def _smooth(t):
    """C¹ step on [0, 1]: 0 → 0, 1 → 1 (element-wise, clipped outside)."""
    t = np.clip(t, 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def margins(
    roughness, k: float, *, eps=None, methods=AUTO_ORDER, report=None, stop_below=None
) -> tuple[dict, dict]:
    """``({method: cₘ}, {method: report})``: each method's margin ``max log(ratio)`` over its
    roughness checks (≤ 0 valid; ∞ unsupported; module docstring) and its validity report.
    ``report(name)``: the roughness-level validity report of a method (default: its
    ``check_validity``; the API passes its cached reports, so that the method it then runs
    reuses the one computed here). ``stop_below``: the methods are checked in order and the
    rest is not checked (left out of both dicts) after the first with a finite margin
    ``cₘ ≤ stop_below``."""
    out, reports = {}, {}
    for n in methods:
        rep = reports[n] = _report(n, roughness, k, eps, None) if report is None else report(n)
        ratios = [
            (d.get("ratio", math.inf) if name not in CATEGORY_CHECKS else
             (0.0 if d.get("ok") else math.inf))
            for name, d in rep.get("details", {}).items()
        ]  # fmt: skip
        if rep.get("unsupported"):
            c = math.inf
        elif not ratios:  # no roughness check: valid (or not) everywhere
            c = -math.inf if rep.get("valid") else math.inf
        else:
            c = max((math.log(r) if r > 0 else -math.inf) for r in ratios)
        out[n] = math.inf if math.isnan(c) else c
        if stop_below is not None and math.isfinite(out[n]) and out[n] <= stop_below:
            break
    return out, reports


def _first_of(soft_valid: np.ndarray) -> tuple[np.ndarray, float]:
    """Stick-breaking: the weight of "the first that holds", and the rest (none holds)."""
    held = np.concatenate([[1.0], np.cumprod(1.0 - soft_valid)])
    return soft_valid * held[:-1], float(held[-1])


def _soft_argmin(values: np.ndarray, width: float, present: np.ndarray) -> np.ndarray:
    """Weights ``∝ presentₘ Π_{j≠m} [present_j s(½ + (v_j − vₘ)/2w) + 1 − present_j]``,
    normalized (zeros when nothing is present)."""
    v = np.where(np.isfinite(values), values, 0.0)
    pair = _smooth(0.5 + (v[None, :] - v[:, None]) / (2.0 * width))  # [m, j]
    pair = present[None, :] * pair + (1.0 - present[None, :])
    np.fill_diagonal(pair, 1.0)
    raw = present * np.prod(pair, axis=1)
    total = raw.sum()
    return raw / total if total > 0 else raw


def blend_weights(
    roughness, k: float, *, eps=None, methods=None, monostatic: bool = False, report=None
) -> dict:
    """The methods ``method="auto"`` blends for this roughness at wavenumber ``k`` [rad/m]
    (permittivity ``eps``, optional) and their weights (module docstring); ``methods`` in
    order (default :func:`auto_order` of ``eps`` and ``monostatic``: True for backscatter);
    ``report``: as in :func:`margins`.

    Returns ``{"weights": {name: w}, "pick": name, "soft_valid": {name: vₘ},
    "margins": {name: cₘ}, "measured": {...} or None}``: weights sum to 1, names in
    decreasing weight (small ones faded out: :data:`FADE_WEIGHTS`); ``pick`` is the heaviest, whose
    validity the blend reports; ``measured`` the interpolated errors and availabilities used;
    ``soft_valid`` and ``margins`` name the methods checked (those after the first one valid
    a factor :data:`BLEND_FACTOR` inside its limits are not: their weight is 0)."""
    methods = tuple(auto_order(eps, monostatic=monostatic) if methods is None else methods)
    d = math.log(BLEND_FACTOR)
    # after a method valid with v = 1 (c ≤ −δ) every later one has weight 0 whatever its
    # criteria (stick-breaking; the measured step reads the maps, not the reports): unchecked
    c, reports = margins(roughness, k, eps=eps, methods=methods, report=report, stop_below=-d)
    cm = np.array([c.get(n, math.nan) for n in methods])
    supported = np.isfinite(cm).astype(float)
    if not supported.any():
        raise ValueError(
            "no solver supports this roughness: "
            + "; ".join(f"{n}: {r['reasons'][0]}" for n, r in reports.items())
        )
    v = np.where(supported > 0, _smooth(0.5 - np.where(supported > 0, cm, 0.0) / (2 * d)), 0.0)
    first, rest = _first_of(v)
    crit = first + rest * _soft_argmin(cm, d, supported)

    meas = interpolated_errors(roughness, k, eps)
    w = crit
    if meas is not None:
        e = np.array([meas["errors"].get(n, math.nan) for n in methods])
        avail = np.array([meas["availability"].get(n, 0.0) for n in methods])
        avail = np.where(np.isfinite(e), avail, 0.0)
        g = avail * _smooth(0.5 - (np.where(avail > 0, e, 0.0) - TOL_DB) / (2 * MEASURED_WIDTH_DB))
        cheapest_good, none_good = _first_of(g)
        closest = _soft_argmin(e, MEASURED_WIDTH_DB, avail)
        mapped = float(avail.max())
        w = np.zeros(len(methods))
        eye = np.eye(len(methods))
        for i in np.flatnonzero(crit > 0):  # each criteria choice f, by its weight
            keep_if_invalid = mapped * closest + (1.0 - mapped) * eye[i]
            fallback = v[i] * eye[i] + (1.0 - v[i]) * keep_if_invalid
            w += crit[i] * (g[i] * eye[i] + (1.0 - g[i]) * (cheapest_good + none_good * fallback))
    lo, hi = FADE_WEIGHTS
    w = w * _smooth((w - lo) / (hi - lo))
    w = w / w.sum()
    order = sorted((i for i in range(len(methods)) if w[i] > 0), key=lambda i: (-w[i], i))
    weights = {methods[i]: float(w[i]) for i in order}
    return {
        "weights": weights,
        "pick": methods[order[0]],
        "soft_valid": {n: float(x) for n, x in zip(methods, v, strict=True) if n in c},
        "margins": dict(c),
        "measured": meas,
    }
