"""Input checks fused with the copy the public API keeps: one pass per large angle array.

:func:`emscatter.conventions.check_angle` proves a float64 array in range with ``min`` and
``max`` (two passes over the array) and then copies it (a third read and a write) — the API
records the angles it was given in its result, not aliased (issue 22). At 1e6 angles that is
≈ 1.1 ms per array, 3 arrays per :func:`emscatter.bistatic` call; here one compiled loop reads
each element once, writes the copy and compares it with the bounds (NaN fails the
comparison, ``v − v = 0`` fails for ±inf). The copy is the array bit for bit; anything the
loop rejects goes back to :func:`~emscatter.conventions.check_angle` for its message.
"""

from __future__ import annotations

import numpy as np

from ._runtime import jit

__all__ = ["copy_in_range", "all_in_range"]


@jit
def _copy_in_range(src, dst, low, high):
    ok = True
    for j in range(src.size):
        v = src[j]
        dst[j] = v
        ok &= (v >= low) & (v <= high) & (v - v == 0.0)  # NaN, ±inf: False
    return ok


def copy_in_range(value: np.ndarray, low: float, high: float) -> np.ndarray | None:
    """A copy of the C-contiguous float64 array ``value`` when every element lies in
    ``[low, high]`` (finite), else None (nothing decided: the caller checks as usual)."""
    out = np.empty_like(value)
    ok = _copy_in_range(value.reshape(-1), out.reshape(-1), float(low), float(high))
    return out if ok else None


@jit
def _all_in_range(src, low, high):
    ok = True
    for j in range(src.size):
        v = src[j]
        ok &= (v >= low) & (v <= high)  # NaN: False
    return ok


def all_in_range(value: np.ndarray, low: float, high: float) -> bool:
    """Whether every element of the C-contiguous float64 array ``value`` lies in
    ``[low, high]`` (NaN does not): ``low <= value.min() and value.max() <= high`` in one
    pass instead of two."""
    return bool(_all_in_range(value.reshape(-1), float(low), float(high)))
