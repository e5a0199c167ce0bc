"""Method resolution for the public API: validity reports (cached), ranking, per-angle policy.

* :func:`validity_report` — one solver's ``check_validity`` for a roughness and ``k``, with
  ``eps`` and ``theta_i`` passed when the solver accepts them (BOARD interface 1), cached per
  input so that repeated calls for the same roughness integrate nothing twice.
* :func:`rank_methods` — ``select.rank_methods`` (BOARD interface 2) when the solvers package
  provides it, else the same answer built from today's ``select.select_method``: best first,
  each with its report.
* :func:`angle_policy` — the caller's ``out_of_range`` policy applied per incidence angle:
  ``"warn"`` names the angles in degrees (and values), ``"nan"`` blanks those angles only,
  ``"raise"`` raises :class:`~emscatter.solvers.select.ValidityError`, ``"ignore"`` records.

Roughness-level validity (the whole call) keeps :func:`emscatter.solvers.select.enforce`.

Also the checks and helpers that both entry-point modules (:mod:`emscatter.api` and
:mod:`emscatter.emissivity_api`) share: :func:`resolve_method`, the method/roughness checks,
option mapping, per-angle masks and the merge of per-frequency results.
"""

from __future__ import annotations

import functools
import inspect
import math
import warnings
from collections import OrderedDict

import numpy as np

from emscatter import solvers
from emscatter.conventions import broadcast_view, fmt
from emscatter.fresnel import is_pec
from emscatter.solvers import blend, measured, select
from emscatter.solvers.validity import with_angle_total
from emscatter.spectra import Roughness, check_roughness

__all__ = [
    "validity_report", "angle_report", "call_report", "rank_methods", "angle_policy",
    "angles_deg", "blend_weights", "resolve_method",
]  # fmt: skip

_CACHE: OrderedDict = OrderedDict()
_CACHE_SIZE = 512
_UNCACHEABLE = object()


def _key_of(value):
    """A hashable key for eps / theta_i / option values, or ``_UNCACHEABLE``."""
    if value is None or isinstance(value, str | bool | int | float | complex):
        return value
    arr = np.asarray(value)
    if arr.dtype == object or arr.size > 4096:
        return _UNCACHEABLE
    return (arr.dtype.str, arr.shape, arr.tobytes())


@functools.lru_cache(maxsize=256)
def _accepts(func, name: str) -> bool:
    params = inspect.signature(func).parameters
    return name in params or any(p.kind is p.VAR_KEYWORD for p in params.values())


def _call_check(module, roughness, k, eps, theta_i, options) -> dict:
    check = module.check_validity
    kw = {n: v for n, v in options.items() if _accepts(check, n)}
    if eps is not None and _accepts(check, "eps"):
        kw["eps"] = eps
    if theta_i is not None and _accepts(check, "theta_i"):
        try:
            return dict(check(roughness, k, theta_i=theta_i, **kw))
        except (TypeError, ValueError):  # a solver that takes one scalar angle only
            pass
    return dict(check(roughness, k, **kw))


def _remember(key, value) -> None:
    if key is not None:
        _CACHE[key] = value
        if len(_CACHE) > _CACHE_SIZE:
            _CACHE.popitem(last=False)


def _recall(key):
    if key is None:
        return None
    value = _CACHE.get(key)
    if value is not None:
        _CACHE.move_to_end(key)
    return value


def validity_report(name: str, roughness, k: float, *, eps=None, theta_i=None, **options):
    """``solvers.get(name).check_validity(roughness, k, ...)`` — a fresh dict each call, cached
    on ``(name, roughness, k, eps, theta_i, options)``. A solver that cannot take this
    roughness gives ``{"valid": False, "unsupported": True, "reasons": [why]}``."""
    parts = (name, roughness, float(k), _key_of(eps), _key_of(theta_i))
    parts += tuple(sorted((n, _key_of(v)) for n, v in options.items()))
    key = None if _UNCACHEABLE in parts else parts
    hit = _recall(key)
    if hit is not None:
        return dict(hit)
    module = solvers.get(name)
    try:
        report = _call_check(module, roughness, k, eps, theta_i, options)
    except (ValueError, TypeError) as exc:
        report = {"valid": False, "reasons": [str(exc)], "unsupported": True}
    _remember(key, report)
    return dict(report)


#: above this many angles (after the axes along which θi is constant are dropped) the report
#: is not built on ``np.unique``'s sorted angles (module docstring of :func:`angle_report`)
_DISTINCT_MAX = 4096
_PROBES = 257


def _varying_part(ti: np.ndarray) -> tuple[np.ndarray, tuple]:
    """``(part, index)``: ``ti`` with the axes along which it is constant (broadcast axes —
    stride 0 — or equal values, as in a meshgrid) cut to length 1, and the index that takes
    ``part`` back to ``ti``'s shape by broadcasting. One comparison pass per non-broadcast
    axis, stopped at the first difference."""
    part = ti
    for axis in range(ti.ndim):
        if part.shape[axis] <= 1:
            continue
        first = part[(slice(None),) * axis + (slice(0, 1),)]
        second = part[(slice(None),) * axis + (slice(1, 2),)]  # differs: not constant (cheap)
        if part.strides[axis] == 0 or (
            np.array_equal(second, first)
            and np.array_equal(part, np.broadcast_to(first, part.shape))
        ):
            part = first
    return part, part.shape


def _threshold_report(name, roughness, k, eps, flat: np.ndarray) -> dict | None:
    """The angle entries at every angle of ``flat`` (1-D), or None where no threshold is
    known. Every angle at or below a threshold passes; the angles above it (they hold every
    failing angle) are checked one by one — no sort; the cost follows the angles that can
    fail, not the call's size. The threshold: the solver's proven ``angle_safe_below`` (SPM)
    when its report has one; else, for a solver whose angle checks all grow with θi
    (``angle_monotone``), the largest passing one of :data:`_PROBES` angles spanning
    ``[min, max]``."""
    lo, hi = float(flat.min()), float(flat.max())
    probe = np.unique(np.linspace(lo, hi, _PROBES))
    probed = validity_report(name, roughness, k, eps=eps, theta_i=probe)
    if "angle_valid" not in probed:
        return None
    safe = probed.get("angle_safe_below")
    if safe is not None and not probed.get("angle_monotone"):
        safe = float(safe)
        if hi <= safe:
            return _all_pass(flat.shape)
        rest = np.flatnonzero(flat > safe)
    elif probed.get("angle_monotone"):
        ok = np.asarray(probed["angle_valid"], dtype=bool)
        j = ok.size if ok.all() else int(np.argmin(ok))  # first failing probe
        if ok[j:].any():  # a pass above a failure: not monotone after all
            return None
        if j == ok.size:
            return _all_pass(flat.shape)
        rest = np.flatnonzero(flat > probe[j - 1]) if j else np.arange(flat.size)
    else:
        return None
    out = _all_pass(flat.shape)
    sub = validity_report(name, roughness, k, eps=eps, theta_i=flat[rest])
    out["angle_valid"][rest] = sub["angle_valid"]
    out["angle_excess"][rest] = sub["angle_excess"]
    out["angle_reasons"] = [with_angle_total(r, flat.size) for r in sub["angle_reasons"]]
    return out


def _as_shape(value, shape) -> np.ndarray:
    """``value`` as an array of ``shape``: itself when it has it, else a broadcast view."""
    arr = np.asarray(value)
    return arr if arr.shape == shape else np.broadcast_to(arr, shape)


def _all_pass(shape) -> dict:
    """Angle entries where every angle passes (fresh arrays)."""
    return {"angle_valid": np.ones(shape, dtype=bool), "angle_excess": np.zeros(shape),
            "angle_reasons": []}  # fmt: skip


def angle_report(name: str, roughness, k: float, *, eps=None, theta_i) -> dict:
    """The per-angle entries (``angle_valid``, ``angle_excess`` in ``theta_i``'s shape,
    ``angle_reasons``) of :func:`validity_report` for incidence angles ``theta_i`` [rad];
    cached on the angles themselves. Fresh arrays each call.

    The cost follows what is decided, not the call's size: the axes along which θi does not
    change are dropped first (a grid's θs, φs axes); up to :data:`_DISTINCT_MAX` angles remain
    → the report at the distinct angles (``np.unique``), mapped back; more → without a sort:
    for checks that all grow with θi (GO, PO) a threshold found on a few probe angles, with
    only the angles above it checked one by one (:func:`_threshold_report`); other checks are
    evaluated at each angle, vectorized (SPM's scattered fraction is first bounded over
    ``[min θi, max θi]``: two passes when every angle passes). The verdicts are those of the
    solver's own ``check_validity`` at each angle; the "(n of m angles)" of a reason then
    counts the angles given (after the constant axes are dropped), not the distinct ones."""
    ti = np.asarray(theta_i, dtype=float)
    parts = ("angles", name, roughness, float(k), _key_of(eps), _key_of(ti))
    key = None if _UNCACHEABLE in parts else parts
    hit = _recall(key)
    if hit is not None:
        return {n: v.copy() if isinstance(v, np.ndarray) else v for n, v in hit.items()}
    part, part_shape = _varying_part(ti)
    own = False  # whether the arrays of ``take`` are this call's own (fresh, not shared)
    if part.size <= _DISTINCT_MAX:
        uniq, inverse = np.unique(part, return_inverse=True)
        angular = validity_report(name, roughness, k, eps=eps, theta_i=uniq)
        index = inverse.reshape(part_shape)
        take = {e: np.asarray(angular[e])[index] for e in ("angle_valid", "angle_excess")
                if e in angular}  # fmt: skip
        own = True  # (fancy indexing copies)
    else:
        flat = part.ravel()
        fast = getattr(solvers.get(name), "angle_entries", None)  # a compiled pass (GO)
        angular = fast(roughness, k, flat) if fast is not None else None
        if angular is None:
            angular = _threshold_report(name, roughness, k, eps, flat)
        own = angular is not None  # fresh arrays of flat's shape
        if angular is None:  # uncached (> 4096 angles): the report's arrays are fresh too
            angular = validity_report(name, roughness, k, eps=eps, theta_i=flat)
        take = {e: _as_shape(angular[e], flat.shape).reshape(part_shape)
                for e in ("angle_valid", "angle_excess") if e in angular}  # fmt: skip
    # a copy only where the entry is a broadcast view or shared: 1e6 angles cost no pass here
    out = {
        e: v if own and v.shape == ti.shape and v.flags.writeable
        else np.array(np.broadcast_to(v, ti.shape))
        for e, v in take.items()
    }  # fmt: skip
    if "angle_reasons" in angular:
        out["angle_reasons"] = angular["angle_reasons"]
    if key is None:  # not cached (a large call): these arrays are already this call's own
        return out
    _remember(key, out)
    return {n: v.copy() if isinstance(v, np.ndarray) else v for n, v in out.items()}


def call_report(name: str, roughness, k: float, *, eps=None, theta_i=None, out_of_range=None):
    """:func:`validity_report` with ``"roughness_valid"`` (its own ``valid``) and, when
    ``theta_i`` [rad] is given, :func:`angle_report`'s entries merged in (``valid`` then also
    requires every angle); cached on the inputs as one entry. A fresh dict each call; its
    arrays are read-only (shared between calls).

    ``out_of_range``: the caller's policy, when the per-angle checks may be skipped where it
    does not need them — ``"nan"`` or ``"raise"`` with the roughness itself outside the
    method's validity (every angle is blanked, or the call stops): no ``angle_*`` entries
    then, and ``"angle_check"`` says ``"not checked: …"`` and why."""
    ti = None if theta_i is None else np.asarray(theta_i, dtype=float)
    parts = ("call", name, roughness, float(k), _key_of(eps), _key_of(ti), out_of_range)
    key = None if _UNCACHEABLE in parts else parts
    hit = _recall(key)
    if hit is None:
        hit = validity_report(name, roughness, k, eps=eps)
        hit["roughness_valid"] = bool(hit.get("valid", False))
        if ti is not None and not hit["roughness_valid"] and out_of_range in ("nan", "raise"):
            hit["angle_check"] = (
                f"not checked: the roughness is outside method {name!r}'s validity and "
                f"out_of_range={out_of_range!r} " + ("blanks every angle" if out_of_range ==
                "nan" else "stops the call")
            )  # fmt: skip
        elif ti is not None:  # checked at the distinct angles, mapped back to theta_i's shape
            hit.update(angle_report(name, roughness, k, eps=eps, theta_i=ti))
            if "angle_valid" in hit:
                hit["valid"] = hit["roughness_valid"] and bool(np.all(hit["angle_valid"]))
        for v in hit.values():
            if isinstance(v, np.ndarray):
                v.flags.writeable = False  # shared by the calls that hit this entry
        _remember(key, hit)
    return dict(hit)


def clear_cache() -> None:
    """Forget every cached validity report and ranking."""
    _CACHE.clear()


def _excess(report: dict) -> float:
    if report.get("valid", False):
        return 0.0
    return float(report.get("excess", math.inf))


def rank_methods(roughness, k: float, *, eps=None, theta_i=None, methods=None):
    """``[(name, report), ...]`` best first for ``method="auto"`` (BOARD interface 2).

    Uses :func:`emscatter.solvers.select.rank_methods` when it exists. Otherwise: the method
    :func:`~emscatter.solvers.select.select_method` picks, then the other supported methods
    by (valid, excess, cost order). Raises ValueError when no method supports the roughness.
    """
    methods = tuple(methods or solvers.AUTO_ORDER)
    native = getattr(select, "rank_methods", None)
    if native is not None:  # cached like the reports (fresh report dicts each call)
        parts = ("rank", methods, roughness, float(k), _key_of(eps), _key_of(theta_i))
        key = None if _UNCACHEABLE in parts else parts
        ranked = _recall(key)
        if ranked is None:
            ranked = list(native(roughness, k, eps=eps, theta_i=theta_i, methods=methods))
            _remember(key, ranked)
        return [(n, dict(r)) for n, r in ranked]
    first, _ = select.select_method(roughness, k, methods)
    reports = {n: validity_report(n, roughness, k, eps=eps, theta_i=theta_i) for n in methods}
    order = {n: i for i, n in enumerate(methods)}
    rest = sorted(
        (n for n in methods if n != first and not reports[n].get("unsupported")),
        key=lambda n: (not reports[n].get("valid", False), _excess(reports[n]), order[n]),
    )
    return [(n, reports[n]) for n in (first, *rest)]


def blend_weights(roughness, k: float, *, eps=None, monostatic: bool = False, theta_i=None) -> dict:
    """:func:`emscatter.solvers.blend.blend_weights` (``auto``'s methods and their continuous
    weights; ``monostatic``: for backscatter, where a dielectric's order puts the IEM before
    PO), cached; a fresh dict each call. The methods' validity reports come from
    :func:`validity_report` (cached: the method that then runs does not check its validity
    again).

    ``theta_i`` [rad] (any shape, optional): the incidence angles, for the 3-D cells' layer.
    The cache keys on the roughness alone — ``(roughness, k, eps, monostatic)`` — and keeps
    with the weights the θi interval where a 3-D map can apply
    (:func:`emscatter.solvers.measured.support_3d`); where the angles lie outside it (or no
    3-D map applies: the common case) the roughness-only weights are returned (scalars),
    with no look at the angles beyond that test. Only inside it is the entry keyed on θi too
    (weights then arrays of θi's shape)."""
    parts = ("blend", roughness, float(k), _key_of(eps), bool(monostatic))
    key = None if _UNCACHEABLE in parts else parts

    def report(name):  # the reports the chosen methods' runs then find cached
        return validity_report(name, roughness, k, eps=eps)

    hit = _recall(key)
    if hit is None:
        weights = blend.blend_weights(roughness, k, eps=eps, monostatic=monostatic, report=report)
        hit = (weights, measured.support_3d(roughness, k, eps))
        _remember(key, hit)
    weights, support = hit
    if support is not None and theta_i is not None and _inside(theta_i, support):
        parts3 = (*parts, _key_of(np.asarray(theta_i, dtype=float)))
        key3 = None if _UNCACHEABLE in parts3 else parts3
        weights = _recall(key3)
        if weights is None:
            weights = blend.blend_weights(
                roughness, k, eps=eps, monostatic=monostatic, report=report, theta_i=theta_i
            )
            _remember(key3, weights)
    return {**weights, "weights": dict(weights["weights"])}


def _inside(theta_i, support) -> bool:
    """Whether some angle of ``theta_i`` [rad] lies in the open interval ``support`` [deg]."""
    ti = np.degrees(np.asarray(theta_i, dtype=float))
    lo, hi = support
    return bool(np.any((ti > lo) & (ti < hi)))


def angles_deg(theta_i, mask, *, limit: int = 8) -> str:
    """``"85°, 88°, 89°"`` for the angles where ``mask`` is True (at most ``limit`` shown)."""
    deg = np.degrees(np.broadcast_to(theta_i, np.shape(mask))[mask]).ravel()
    uniq = np.unique(np.round(deg, 6))
    shown = ", ".join(f"{d:.4g}°" for d in uniq[:limit])
    more = f" and {uniq.size - limit} more" if uniq.size > limit else ""
    return f"θi = {shown}{more}"


def angle_policy(
    name: str, bad: np.ndarray, theta_i, out_of_range: str, reasons: list[str], *, stacklevel=4
) -> np.ndarray:
    """Apply ``out_of_range`` at the incidence angles where ``bad`` is True.

    Returns the mask of elements to set to NaN (all False unless ``out_of_range="nan"``).
    """
    bad = np.asarray(bad, dtype=bool)
    if not bad.any() or out_of_range == "ignore":
        return np.zeros(bad.shape, dtype=bool)
    why = "; ".join(reasons) if reasons else "outside its validity range"
    msg = f"method {name!r} at {angles_deg(theta_i, bad)}: {why}"
    if out_of_range == "raise":
        raise select.ValidityError(msg)
    if out_of_range == "warn":
        warnings.warn(
            msg + " (out_of_range='nan' blanks these angles, 'raise' stops)",
            select.ValidityWarning,
            stacklevel=stacklevel,
        )
        return np.zeros(bad.shape, dtype=bool)
    return bad


def eps_label(eps) -> str:
    """A permittivity for messages: ``pec``, ``(17+2j)``, or ``array of shape (n,)``."""
    if is_pec(eps):
        return "pec"
    arr = np.asarray(eps)
    return fmt(complex(arr)) if arr.ndim == 0 else f"array of shape {arr.shape}"


# ------------------------------------------------------ shared by the API entry points
def _check_roughness(surface) -> Roughness:
    return check_roughness(surface, "surface")


def _check_method(method) -> str:
    if not isinstance(method, str):
        raise ValueError(f"method must be 'auto' or one of {solvers.available()}, got {method!r}")
    name = method.strip().lower()
    if name != "auto":
        solvers.get(name)  # raises naming the allowed methods
    return name


def _map_options(name: str, options: dict, auto: bool) -> dict:
    if not options:  # nothing to map (check_options would return {} too)
        return {}
    mapper = getattr(select, "check_options", None)
    # always a new dict: _bistatic_one pops from it, the caller's options stay whole (bands)
    return dict(mapper(name, options, picked_by_auto=auto) if mapper else options)


def resolve_method(
    roughness: Roughness,
    k: float,
    method: str,
    out_of_range: str,
    eps=None,
    *,
    theta_i=None,
    stacklevel: int = 5,
):
    """``(name, module, report, make_nan)`` for a method name or ``"auto"``.

    ``report`` is the roughness-level validity report (angle entries added when ``theta_i``
    [rad] is given); ``make_nan`` is True when ``out_of_range="nan"`` and the method is outside
    its roughness-level validity (the policy has been applied: warned or raised)."""
    select.check_out_of_range(out_of_range)
    name = _check_method(method)
    return _resolve(roughness, k, name, out_of_range, eps, theta_i, stacklevel + 1)


def _resolve(roughness, k, name, out_of_range, eps, theta_i, stacklevel):
    """:func:`resolve_method` for a ``name`` and ``out_of_range`` already checked (the API's
    own calls: each check once per call)."""
    if name == "auto":
        name = rank_methods(roughness, k, eps=eps)[0][0]
    # the per-angle checks are skipped where the policy does not need them (call_report)
    report = call_report(name, roughness, k, eps=eps, theta_i=theta_i, out_of_range=out_of_range)
    # the roughness-level policy sees the roughness-level verdict (angles: angle_policy)
    whole = {"valid": report["roughness_valid"], "reasons": report.get("reasons", [])}
    make_nan = select.enforce(name, whole, out_of_range, stacklevel=stacklevel)
    return name, solvers.get(name), report, make_nan


def _angle_mask(report: dict, shape) -> np.ndarray:
    """Per-element validity from a report's ``angle_valid`` (all True when absent)."""
    valid = report.get("angle_valid")
    if valid is None:
        return np.ones(shape, dtype=bool)
    valid = np.asarray(valid, dtype=bool)
    return valid if valid.shape == shape else broadcast_view(valid, shape)


def _takes(func, name: str) -> bool:
    """Whether ``func`` has a parameter ``name`` (signatures read once per function)."""
    try:
        return _params(func).__contains__(name)
    except TypeError:  # an unhashable callable: read its signature each time
        return name in inspect.signature(func).parameters


@functools.lru_cache(maxsize=256)
def _params(func) -> frozenset:
    return frozenset(inspect.signature(func).parameters)


def _merge_methods(names) -> str:
    return "+".join(dict.fromkeys(names))


def _merged_validity(parts) -> dict:
    """One report for several frequencies: valid if all are; reasons name the frequency."""
    reports = [(g, res.info["validity"]) for g, res in parts]
    return {
        "valid": all(rep.get("valid", False) for _, rep in reports),
        "reasons": [
            f"at {g.frequency:.6g} Hz: {why}"
            for g, rep in reports
            for why in rep.get("reasons", [])
        ],
        "by_frequency": [
            {"frequency": g.frequency, "method": res.method, "validity": res.info["validity"]}
            for g, res in parts
        ],
    }
