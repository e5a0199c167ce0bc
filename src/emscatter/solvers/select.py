"""Validity checks across solvers and the ``method="auto"`` choice.

Each solver module reports its own validity (``check_validity(roughness, k)``); this module
asks them in :data:`emscatter.solvers.AUTO_ORDER` (cheapest first) and picks the first one
that is valid. Outside every validity range the least-bad candidate is used and the caller's
``out_of_range`` policy applies: ``"warn"`` (default, :class:`ValidityWarning`), ``"raise"``
(:class:`ValidityError`) or ``"nan"`` (results replaced by NaN, flagged in ``info``).
"""

from __future__ import annotations

import math
import warnings
from typing import Literal

from . import AUTO_ORDER, get

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


def validity(roughness, k: float, methods=AUTO_ORDER) -> dict[str, dict]:
    """Validity report of each method for this roughness and wavenumber ``k`` [rad/m]."""
    return {name: get(name).check_validity(roughness, k) for name in methods}


def select_method(roughness, k: float, methods=AUTO_ORDER) -> tuple[str, dict]:
    """The cheapest valid method, and all reports. If none is valid, the one whose criteria
    are exceeded by the smallest factor (report ``"excess"`` = max log(value/limit); ties:
    fewer violated criteria, then cheaper) is returned with ``valid=False``."""
    reports = {}
    for name in methods:
        try:
            reports[name] = get(name).check_validity(roughness, k)
        except (ValueError, TypeError) as exc:  # e.g. a solver that cannot take this roughness
            reports[name] = {"valid": False, "reasons": [str(exc)], "unsupported": True}
        if reports[name]["valid"]:
            return name, reports
    supported = [n for n in methods if not reports[n].get("unsupported")]
    if not supported:
        raise ValueError(
            "no solver supports this roughness: "
            + "; ".join(f"{n}: {r['reasons'][0]}" for n, r in reports.items())
        )
    order = {n: i for i, n in enumerate(methods)}
    best = min(
        supported,
        key=lambda n: (
            reports[n].get("excess", math.inf),
            len(reports[n].get("reasons", [])),
            order[n],
        ),
    )
    return best, reports


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
