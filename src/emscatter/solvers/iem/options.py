"""The IEM solver's options (:func:`emscatter.solvers.iem.model.bistatic`): their checks, with
clear errors naming the option, the value and what is allowed, and the memory of checked
option tuples that spares a repeated call the checks.

:func:`_options` returns ``(opt, shadow_mode)``: ``opt`` the :class:`~.amplitudes._Options`
the amplitudes and series read (``fresnel``, ``complementary``, ``first_order``, ``rtol``,
``max_terms``, ``threads``), ``shadow_mode`` the key of :data:`.shadowing._SHADOW_MODES`.
Remembered per distinct argument tuple (values and their types); the checks themselves are
:func:`_check_options`. :func:`_slope` checks ``rms_slope`` (default: the nominal rms slope
of :func:`.validity.nominal_rms_slope`). The defaults are :func:`~.model.bistatic`'s
signature (``model._DEFAULTS`` reads them from it).
"""

from __future__ import annotations

import numpy as np

from emscatter.conventions import check_positive
from emscatter.solvers.iem.amplitudes import _Options
from emscatter.solvers.iem.shadowing import _SHADOW_MODES
from emscatter.solvers.iem.validity import nominal_rms_slope
from emscatter.solvers.kirchhoff.common import workers_for


def _choice(name, value, allowed):
    if isinstance(value, bool) or value not in allowed:
        raise ValueError(f"{name} must be one of {list(allowed)}, got {value!r}")
    return value


def _options(rtol, max_terms, fresnel, complementary, first_order, reciprocal, shadowing,
             crosspol, crosspol_order, coherent, threads):  # fmt: skip
    """The checked options ``(opt, shadow_mode)`` of :func:`~.model.bistatic` (ValueError naming
    the option otherwise). Remembered per distinct argument tuple (values and their types, so
    that e.g. ``shadowing=1`` is still refused after ``shadowing=True``): a call with the
    options of an earlier call pays a dictionary lookup, not the checks (a fixed cost of
    each call, which matters at a few angles). ``opt`` is shared: read, never written."""
    args = (rtol, max_terms, fresnel, complementary, first_order, reciprocal, shadowing,
            crosspol, crosspol_order, coherent, threads)  # fmt: skip
    try:
        key = (*args, *map(type, args))
        hit = _OPTION_MEMO.get(key)
    except TypeError:  # an unhashable value (e.g. an array): check it every time
        key = hit = None
    if hit is None:
        hit = _check_options(*args)
        if key is not None and len(_OPTION_MEMO) < 256:
            _OPTION_MEMO[key] = hit
    return hit


_OPTION_MEMO: dict = {}


def _check_options(rtol, max_terms, fresnel, complementary, first_order, reciprocal, shadowing,
                   crosspol, crosspol_order, coherent, threads):  # fmt: skip
    """:func:`_options` without the memory."""
    rtol = check_positive("rtol", rtol)
    if not rtol < 1:
        raise ValueError(f"rtol must be in (0, 1), got {rtol!r}")
    if isinstance(max_terms, bool) or not isinstance(max_terms, int | np.integer) or max_terms < 1:
        raise ValueError(f"max_terms must be a positive integer, got {max_terms!r}")
    opt = _Options()
    opt.fresnel = _choice("fresnel", fresnel, ("transition", "incident"))
    opt.complementary = _choice(
        "complementary", complementary, ("aiem-faded", "aiem", "aiem-upper", "fung92")
    )
    opt.first_order = _choice("first_order", first_order, ("spm", "model"))
    opt.rtol, opt.max_terms = rtol, int(max_terms)
    opt.threads = workers_for(threads, 8)
    if shadowing not in _SHADOW_MODES or (isinstance(shadowing, str) is False and
                                          not isinstance(shadowing, bool | None)):  # fmt: skip
        raise ValueError(
            "shadowing must be 'direction-correlated' (or True), 'height-correlated' or False, "
            f"got {shadowing!r}"
        )
    shadow_mode = _SHADOW_MODES[shadowing]
    for name, flag in (("reciprocal", reciprocal), ("crosspol", crosspol), ("coherent", coherent)):
        if not isinstance(flag, bool | np.bool_):
            raise ValueError(f"{name} must be True or False, got {flag!r}")
    if (
        isinstance(crosspol_order, bool)
        or not isinstance(crosspol_order, int | np.integer)
        or not (2 <= crosspol_order <= 64)
    ):
        raise ValueError(f"crosspol_order must be an integer in [2, 64], got {crosspol_order!r}")
    return opt, shadow_mode


def _slope(rough, rms_slope) -> tuple[float, float]:
    if rms_slope is None:
        return nominal_rms_slope(rough)
    arr = np.atleast_1d(np.asarray(rms_slope, dtype=float))
    if arr.ndim != 1 or arr.size not in (1, 2) or not np.all(np.isfinite(arr)) or np.any(arr <= 0):
        raise ValueError(
            f"rms_slope must be a positive float or a pair (s_x, s_y), got {rms_slope!r}"
        )
    return float(arr[0]), float(arr[-1])
