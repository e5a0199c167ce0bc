"""Fixed quadrature rules shared by the solvers and their validity checks: Gauss–Legendre on
[0, 1] and cosine-mapped segments that make square-root branch points at the ends smooth
(used by the second-order SPM kernel, :mod:`emscatter.solvers.spm.second_order`, and the
band-limited slope variances of :mod:`emscatter.solvers.validity`)."""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

__all__ = ["_gl", "_segment_nodes"]


@lru_cache(maxsize=64)
def _gl(n: int):
    x, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * (x + 1.0), 0.5 * w


def _segment_nodes(a: float, b: float, n: int, log: bool = False):
    """Nodes/weights on [a, b] with a cosine map that clusters at both ends, so
    ``√(x − a)`` and ``√(b − x)`` branch points become smooth; optional log stretch."""
    t, wt = _gl(n)
    s = 0.5 * (1.0 - np.cos(math.pi * t))
    ds = 0.5 * math.pi * np.sin(math.pi * t) * wt
    if log and a > 0 and b > 8.0 * a:
        lr = math.log(b / a)
        x = a * np.exp(lr * s)
        return x, x * lr * ds
    if log and b < 0 and a < 8.0 * b:  # mirrored: log stretch towards −∞
        x, wx = _segment_nodes(-b, -a, n, log=True)
        return -x[::-1], wx[::-1]
    return a + (b - a) * s, (b - a) * ds
