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

**3-D cells** (:func:`.measured.measured_errors_3d`, the 3-D method of moments' cells for 2-D
surfaces): they take precedence over the 1-D maps, with a rule that needs no tolerance: in the
same regime test, the criteria's first method, when measured more than 1 dB off, gives way
only to a candidate measured lower by more than 2 combined standard errors of the Monte Carlo
(:func:`.measured.significant_pick`: the paired bootstrap SE of the difference), measured within
1 dB or better by more than 1 dB (the 1-D maps' tolerance), and with no angle-specific failure; then
``picked_by = "measured-3d"`` and the 1-D correction is skipped. Where the cell applies but
no difference is significant, the 1-D correction runs as before — unless the 3-D cell
measures the 1-D correction's pick significantly worse than the criteria's first (then that
stays, ``picked_by = "measured-3d"``). Every report then carries
``measured_3d_error_dB`` and ``measured_3d_se_dB`` and the first one ``measured_3d``
(map, cell (θi°, kσ, kℓ), realizations).

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
    ranked, meas3 = _measured_3d(ranked, reports, roughness, k, eps, theta_i, methods)
    if not reports[ranked[0]].get("picked_by") == "measured-3d":
        kept, saved = list(ranked), dict(reports)
        ranked = _measured_correction(ranked, reports, roughness, k, eps, theta_i, methods)
        if meas3 is not None and _vetoed(meas3, ranked[0], kept[0]):
            ranked, reports = kept, saved  # the 3-D cell measures the 1-D pick worse
            reports[kept[0]] = {**reports[kept[0]], "picked_by": "measured-3d"}
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


def _same_regime(ranked, reports, roughness, k, eps, theta_i, methods, cell) -> bool:
    """A cell speaks for this roughness only if the criteria put its centre ``cell``
    ``(kσ, kℓ)`` in the same regime (same first method, equally valid)."""
    from .measured import cell_roughness

    center, center_reports = _criteria_rank(
        cell_roughness(roughness, k, cell), k, eps, theta_i, methods
    )
    first = ranked[0]
    return center[:1] == [first] and center_reports[first]["valid"] == reports[first]["valid"]


def _angles_ok(r: dict) -> bool:
    """No angle-specific failure (an angle check failing by more than the roughness checks)."""
    a = r.get("angle_valid")
    if a is None or bool(np.all(a)):
        return True
    worst = float(np.max(r.get("angle_excess", math.inf)))
    return worst <= r.get("roughness_excess", 0.0) + 1e-9


def _vetoed(meas3: dict, pick: str, first: str) -> bool:
    """Whether a 3-D cell measures the 1-D correction's ``pick`` significantly worse than the
    criteria's ``first`` (then ``first`` stays: 3-D cells take precedence)."""
    from .measured import significant_pick

    return pick != first and significant_pick(meas3, pick, [first]) == first


def _measured_3d(ranked, reports, roughness, k, eps, theta_i, methods):
    """The 3-D cells' correction (module docstring): the ranking and the cell (None where no
    cell applies); the first report's ``picked_by`` is ``"measured-3d"`` where it decided."""
    from .measured import measured_errors_3d, significant_pick

    meas = measured_errors_3d(roughness, k, eps, theta_i)
    if meas is None or not ranked:
        return ranked, None
    if not _same_regime(ranked, reports, roughness, k, eps, theta_i, methods, meas["cell"][1:]):
        return ranked, None
    for n in ranked:
        reports[n] = {**reports[n], "measured_3d_error_dB": meas["errors"].get(n, math.nan),
                      "measured_3d_se_dB": meas["se"].get(n, math.nan)}  # fmt: skip
    info = {"map": meas["map"], "cell": meas["cell"], "realizations": meas["realizations"]}
    first = ranked[0]
    pick = significant_pick(meas, first, [n for n in ranked if _angles_ok(reports[n])])
    if pick is None:
        reports[first] = {**reports[first], "measured_3d": info}
        return ranked, meas
    ranked = [pick] + [n for n in ranked if n != pick]
    reports[pick] = {**reports[pick], "measured_3d": info, "picked_by": "measured-3d"}
    return ranked, meas


def _measured_correction(ranked, reports, roughness, k, eps, theta_i, methods) -> list[str]:
    """The criteria's ranking corrected by the measured map errors (module docstring)."""
    from .measured import TOL_DB, measured_errors

    meas = measured_errors(roughness, k, eps)
    if meas is None or not ranked:
        return ranked
    first = ranked[0]
    if not _same_regime(ranked, reports, roughness, k, eps, theta_i, methods, meas["cell"]):
        return ranked
    err = {n: meas["errors"].get(n, math.nan) for n in ranked}
    for n in ranked:
        reports[n] = {**reports[n], "measured_error_dB": err[n]}

    def angles_ok(n):
        return _angles_ok(reports[n])

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
