"""The shared gate of every compiled path: "is a compiled kernel worth it for this call?".

Each formulation's ``compiled`` module (:mod:`emscatter.solvers.spm.compiled`,
:mod:`emscatter.solvers.kirchhoff.compiled`, :mod:`emscatter.solvers.iem.compiled`) asks the
same questions here — is the numba backend selected (:func:`emscatter.kernels.backend`), is the
call big enough (:func:`worth_it`), is the permittivity one value (:func:`scalar_eps`), is the
azimuth inside the range where the kernels' cos reduction is exact (:func:`azimuth_ok`) — and
then returns ``True`` after filling the caller's arrays, or ``False`` (nothing touched) so the
solver runs its numpy reference code. Light to import: numba is imported only when a kernel runs.
"""

from __future__ import annotations

import sys

import numpy as np

from . import selection

__all__ = ["MAX_AZIMUTH", "MIN_GEOMETRIES", "worth_it", "scalar_eps", "flat", "azimuth_ok"]

MAX_AZIMUTH = 1.0e6  # |φs − φi| [rad] up to which the kernels' cos reduction is exact
#: Below this many geometries a call takes the numpy path unless the kernels are already
#: loaded in this process: a 90-angle curve costs ~0.2 ms in numpy, while the first kernel call
#: imports numba and loads the compiled code (~0.5 s; 3–4 s if it must compile).
MIN_GEOMETRIES = 4096


def worth_it(n: int) -> bool:
    if n >= MIN_GEOMETRIES or "emscatter.kernels._runtime" in sys.modules:
        return True
    return selection() == "numba"


def scalar_eps(eps):
    """``"pec"``, a Python complex, or None when ``eps`` is an array with more than one value."""
    if isinstance(eps, str):
        return "pec" if eps.lower() == "pec" else None
    arr = np.asarray(eps)
    if arr.ndim == 0:
        return complex(arr)
    return None


def flat(a, n: int, shape: tuple[int, ...] | None = None) -> np.ndarray:
    """``a`` broadcast to ``shape`` (default ``(n,)``) as a flat C-contiguous float64 array."""
    a = np.asarray(a, dtype=np.float64)
    if a.size == n and a.flags.c_contiguous:
        return a.reshape(n)
    out = np.empty((n,) if shape is None else shape)
    out[...] = a  # a broadcast copy (cheaper than reshaping a broadcast view)
    return out.reshape(n)


def azimuth_ok(dphi: np.ndarray) -> bool:
    if (
        dphi.size >= MIN_GEOMETRIES and dphi.dtype.char == "d" and dphi.flags.c_contiguous
        and "emscatter.kernels._runtime" in sys.modules
    ):  # fmt: skip
        from .checks import all_in_range  # one pass, not min and max (issue 22)

        return all_in_range(dphi, -MAX_AZIMUTH, MAX_AZIMUTH)
    return dphi.size == 0 or -MAX_AZIMUTH <= dphi.min() and dphi.max() <= MAX_AZIMUTH
