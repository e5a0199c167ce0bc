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

3. **3-D cells** (:func:`.measured.interpolated_errors_3d`: the 3-D method of moments' cells
   for 2-D Gaussian surfaces, interpolated trilinearly in (θi, log kσ, log kℓ), with an
   availability ``A₃ₘ`` that fades to 0 half a step beyond the outermost cells on each axis)
   take precedence over the 1-D maps where they apply, continuously:
   ``w = Σ_f crit_f [A₃ w₃|f + (1 − A₃) w₁|f]``, ``w₁|f`` the result of step 2 for the
   criteria's choice ``f`` and ``A₃ = maxₘ A₃ₘ``. ``w₃|f`` is the rule of
   :func:`.measured.significant_pick` (which :func:`~emscatter.solvers.select.rank_methods`
   applies with ``theta_i``) with each ``if`` made a weight: ``f`` is measured more than TOL
   off, ``o_f = s(½ + (ē_f − TOL)/2Δ)``; a candidate ``n`` qualifies with
   ``q_n = a_n σ((ē_f − ē_n)/S_fn) μ_fn`` — ``σ(z) = s(½ + (z − 2)/2Z)`` the significance
   of the gap in combined standard errors ``S_fn`` (the paired bootstrap SE, interpolated as
   the errors; ``Z =`` :data:`SIGNIFICANCE_WIDTH`), ``μ_fn = 1 − (1 − s(½ − (ē_n − TOL)/2Δ))
   (1 − s(½ + (ē_f − ē_n − TOL)/2Δ))`` "material" (within TOL, or better by more than TOL),
   ``a_n = A₃ₙ/A₃`` its share of the availability; ``f`` is replaced with weight
   ``P_f = a_f o_f (1 − Π_n (1 − q_n))`` by the candidate measured lowest among those that
   qualify (the soft argmin of ``ē`` with width Δ over the ``q``); with ``1 − P_f`` the 1-D
   result ``w₁|f`` stays — no difference is significant, and the 3-D cells then change
   nothing — except that a method ``p`` it puts in ``f``'s place that the cell measures
   significantly worse than ``f`` (``a_p o_p q_f`` with the roles swapped: rank_methods'
   veto) gives that weight back to ``f``. Where the margins are a width from the thresholds
   (``Z`` from 2 SE, Δ from TOL) the factors are 0 or 1 and the weights are the hard rule's
   at the cell: at a cell centre the method significant_pick picks is the heaviest
   (``tests/test_blend_3d.py``). Why a width of half an SE: the cells' SEs (0.1–0.6 dB) are
   the scale on which their differences are known; the blend turns over within ± half of it
   around the 2 SE of the hard rule. Not kept from rank_methods: its "same regime" test (the
   criteria at the cell centre), a switch in the roughness that the interpolation replaces
   (as for the 1-D maps), and its angle-specific exclusions of candidates (the API applies
   each method's per-angle validity policy). The layer reads θi: ``blend_weights(theta_i=)``
   gives each weight per distinct angle, mapped back to θi's shape (scalar θi: floats);
   where ``A₃ = 0`` at every angle (the common case: another correlation, medium, or outside
   the box) the weights are step 2's, the same floats as without ``theta_i``.

4. **Small weights** fade out (:data:`FADE_WEIGHTS`: below 1 % a method is not run; between 1
   and 3 % its weight is tapered by a smoothstep), and the rest is renormalized: a blend of
   four methods where one carries 0.1 % would cost four solver calls for nothing.

Every factor is a continuous function of the margins and of the interpolated errors, which are
continuous in the roughness, so the weights are; pure (one method, weight 1) wherever every
margin is at least ``δ`` from its limit and every measured error at least Δ from the tolerance.
The 3-D layer's availability is continuous in θi too (linear in the angle, to 0 half the table's
θi step beyond its outermost angles: with cells at 20° and 40°, from 10° to 50°), so the weights
are continuous in every parameter the cells read. Linear (not dB) blending because σ⁰ integrates
linearly: the blend's hemispherical reflectivity is the same convex combination of the methods'
ones, so a blend of energy-conserving answers conserves energy. What is not smoothed: the medium
class of the measured maps (conductor for ``|ε| ≥ 100`` or Re ε < 0) is a switch in ε, and so is
the range of ε a dielectric 3-D map applies to (:data:`.measured.EPS_FACTOR_3D`).

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
from .measured import SIGNIFICANCE, TOL_DB, interpolated_errors, interpolated_errors_3d
from .select import _report

__all__ = [
    "BACKSCATTER_DIELECTRIC_ORDER",
    "BLEND_FACTOR",
    "MEASURED_WIDTH_DB",
    "SIGNIFICANCE_WIDTH",
    "auto_order",
    "blend_weights",
    "margins",
]

#: Half-width of a transition, as a factor on the parameter a criterion reads (kσ, kℓ, slope):
#: within a factor :data:`BLEND_FACTOR` of a limit the methods on both sides are blended.
BLEND_FACTOR = 1.25
#: Half-width [dB] of the transition at the measured tolerance (``TOL_DB ± Δ``).
MEASURED_WIDTH_DB = 0.1
#: Half-width [combined standard errors] of the transition at the 3-D cells' significance
#: (``SIGNIFICANCE ± Z``, :func:`.measured.significant_pick`).
SIGNIFICANCE_WIDTH = 0.5
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
    roughness,
    k: float,
    *,
    eps=None,
    methods=None,
    monostatic: bool = False,
    report=None,
    theta_i=None,
) -> dict:
    """The methods ``method="auto"`` blends for this roughness at wavenumber ``k`` [rad/m]
    (permittivity ``eps``, optional) and their weights (module docstring); ``methods`` in
    order (default :func:`auto_order` of ``eps`` and ``monostatic``: True for backscatter);
    ``report``: as in :func:`margins`.

    Returns ``{"weights": {name: w}, "pick": name, "criteria": {name: weight},
    "soft_valid": {name: vₘ}, "margins": {name: cₘ}, "measured": {...} or None}``
    (``criteria``: step 1's weights, before the measured errors): weights sum to 1, names in
    decreasing weight (small ones faded out: :data:`FADE_WEIGHTS`); ``pick`` is the heaviest, whose
    validity the blend reports; ``measured`` the interpolated errors and availabilities used;
    ``soft_valid`` and ``margins`` name the methods checked (those after the first one valid
    a factor :data:`BLEND_FACTOR` inside its limits are not: their weight is 0).

    ``theta_i`` [rad] (any shape, optional): the incidence angles, for the 3-D cells' layer
    (module docstring, step 3). None, or a 3-D availability of 0 at every angle: the result
    above, unchanged. Else each weight is an array of θi's shape (a float for a scalar θi),
    summing to 1 at every angle; the names are those with a weight > 0 at some angle, in
    decreasing total weight over the distinct angles, ``pick`` the first; the result has
    ``"measured_3d"`` (:func:`.measured.interpolated_errors_3d`'s dict)."""
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
    eye = np.eye(len(methods))
    rows = eye.copy()  # the 1-D result for each criteria choice f (row f)
    if meas is not None:
        e = np.array([meas["errors"].get(n, math.nan) for n in methods])
        avail = np.array([meas["availability"].get(n, 0.0) for n in methods])
        avail = np.where(np.isfinite(e), avail, 0.0)
        g = avail * _smooth(0.5 - (np.where(avail > 0, e, 0.0) - TOL_DB) / (2 * MEASURED_WIDTH_DB))
        cheapest_good, none_good = _first_of(g)
        closest = _soft_argmin(e, MEASURED_WIDTH_DB, avail)
        mapped = float(avail.max())
        w = np.zeros(len(methods))
        for i in np.flatnonzero(crit > 0):  # each criteria choice f, by its weight
            keep_if_invalid = mapped * closest + (1.0 - mapped) * eye[i]
            fallback = v[i] * eye[i] + (1.0 - v[i]) * keep_if_invalid
            rows[i] = g[i] * eye[i] + (1.0 - g[i]) * (cheapest_good + none_good * fallback)
            w += crit[i] * rows[i]
    out = {
        "criteria": {n: float(x) for n, x in zip(methods, crit, strict=True) if x > 0},
        "soft_valid": {n: float(x) for n, x in zip(methods, v, strict=True) if n in c},
        "margins": dict(c),
        "measured": meas,
    }
    meas3 = None if theta_i is None else interpolated_errors_3d(roughness, k, eps, theta_i)
    if meas3 is not None:
        w3 = _layer_3d(methods, crit, rows, meas3, w)
        if w3 is not None:
            return {**_per_angle(methods, _faded(w3), meas3), **out, "measured_3d": meas3}
    w = _faded(w)
    order = sorted((i for i in range(len(methods)) if w[i] > 0), key=lambda i: (-w[i], i))
    weights = {methods[i]: float(w[i]) for i in order}
    return {"weights": weights, "pick": methods[order[0]], **out}


def _faded(w: np.ndarray) -> np.ndarray:
    """Small weights faded out (:data:`FADE_WEIGHTS`) and the rest renormalized, along the
    last axis (methods)."""
    lo, hi = FADE_WEIGHTS
    w = w * _smooth((w - lo) / (hi - lo))
    return w / w.sum(axis=-1, keepdims=True)


def _soft_argmin_rows(values: np.ndarray, width: float, present: np.ndarray) -> np.ndarray:
    """:func:`_soft_argmin` along the last axis of ``values`` and ``present`` (``(..., M)``):
    ``∝ presentₘ Π_{j≠m} [present_j s(½ + (v_j − vₘ)/2w) + 1 − present_j]``, normalized
    (zeros where nothing is present)."""
    v = np.where(np.isfinite(values), values, 0.0)
    pair = _smooth(0.5 + (v[..., None, :] - v[..., :, None]) / (2.0 * width))  # [.., m, j]
    pair = present[..., None, :] * pair + (1.0 - present[..., None, :])
    m = v.shape[-1]
    pair[..., np.arange(m), np.arange(m)] = 1.0
    raw = present * np.prod(pair, axis=-1)
    total = raw.sum(axis=-1, keepdims=True)
    return np.where(total > 0, raw / np.where(total > 0, total, 1.0), 0.0)


def _layer_3d(methods, crit, rows, meas3: dict, w1: np.ndarray) -> np.ndarray | None:
    """The weights ``(U, M)`` over the distinct angles of ``meas3`` with the 3-D cells'
    layer (module docstring, step 3): ``Σ_f crit_f [A₃ w₃|f + (1 − A₃) rows_f]``; the 1-D
    result ``w1`` (``Σ_f crit_f rows_f``, before the fade) itself at the angles where
    ``A₃ = 0``; None where ``A₃ = 0`` at every angle."""
    n_ang = meas3["theta_i_deg"].size
    e = np.stack([np.broadcast_to(meas3["errors"].get(n, np.nan), n_ang) for n in methods], -1)
    a = np.stack([np.broadcast_to(meas3["availability"].get(n, 0.0), n_ang) for n in methods], -1)
    have = np.isfinite(e) & (a > 0)
    a = np.where(have, a, 0.0)
    e = np.where(have, e, 0.0)
    a3 = a.max(axis=-1)  # (U,) the 3-D layer's precedence
    if not np.any(a3 > 0):
        return None
    rel = np.where(have, a / np.where(a3 > 0, a3, 1.0)[:, None], 0.0)  # (U, M)
    se = {n: np.broadcast_to(meas3["se"].get(n, np.nan), n_ang) for n in methods}
    m = len(methods)
    s_pair = np.full((n_ang, m, m), np.nan)
    for x, fx in enumerate(methods):
        for y, fy in enumerate(methods):
            if x != y:
                p = np.broadcast_to(meas3["pair_se"].get((fx, fy), np.nan), n_ang)
                s_pair[:, x, y] = np.where(np.isfinite(p), p, np.hypot(se[fx], se[fy]))
    d = MEASURED_WIDTH_DB
    gap = e[:, :, None] - e[:, None, :]  # [u, f, n]: how much lower n is measured than f
    ok = np.isfinite(s_pair) & (s_pair > 0)
    z = np.where(ok, gap / np.where(ok, s_pair, 1.0), 0.0)
    sig = np.where(ok, _smooth(0.5 + (z - SIGNIFICANCE) / (2 * SIGNIFICANCE_WIDTH)), 0.0)
    within = _smooth(0.5 - (e - TOL_DB) / (2 * d))  # [u, n] n within tolerance
    better = _smooth(0.5 + (gap - TOL_DB) / (2 * d))  # [u, f, n] n better by more than it
    material = 1.0 - (1.0 - within[:, None, :]) * (1.0 - better)
    q = rel[:, None, :] * sig * material  # [u, f, n] n may replace f
    q[:, np.arange(m), np.arange(m)] = 0.0
    over = rel * _smooth(0.5 + (e - TOL_DB) / (2 * d))  # [u, f] f more than TOL off
    replace = over * (1.0 - np.prod(1.0 - q, axis=-1))  # [u, f]
    lowest = _soft_argmin_rows(np.broadcast_to(e[:, None, :], q.shape), d, q)  # [u, f, n]
    veto = over[:, None, :] * np.swapaxes(q, 1, 2)  # [u, f, p]: p measured worse than f
    w = np.zeros((n_ang, m))
    for f in np.flatnonzero(crit > 0):
        row = rows[f][None, :]
        moved = row * veto[:, f, :]  # the 1-D pick p's weight that goes back to f
        vetoed = row - moved
        vetoed[:, f] += moved.sum(axis=-1)
        rule = replace[:, f, None] * lowest[:, f, :] + (1.0 - replace[:, f, None]) * vetoed
        w += crit[f] * (a3[:, None] * rule + (1.0 - a3[:, None]) * row)
    return np.where(a3[:, None] > 0, w, w1[None, :])


def _per_angle(methods, w: np.ndarray, meas3: dict) -> dict:
    """``{"weights", "pick"}`` from weights ``(U, M)`` over the distinct angles: each
    method's weight in θi's shape (``meas3["inverse"]``; a float for a scalar θi), methods
    with weight > 0 at some angle, in decreasing total weight; ``pick`` the heaviest in
    total."""
    total = w.sum(axis=0)
    order = sorted((i for i in range(len(methods)) if np.any(w[:, i] > 0)),
                   key=lambda i: (-total[i], i))  # fmt: skip
    inv = meas3["inverse"]
    if inv.ndim == 0:
        weights = {methods[i]: float(w[int(inv), i]) for i in order}
    else:
        weights = {methods[i]: w[inv, i] for i in order}
    return {"weights": weights, "pick": methods[order[0]]}
