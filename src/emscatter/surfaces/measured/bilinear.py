"""Bilinear (linear in 1-D) interpolation on a uniform grid, NaN outside it: the lookup the
measured spectrum, correlation and slope density share (:mod:`.roughness`, :mod:`.slopes`)."""

from __future__ import annotations

import numpy as np

__all__ = ["bilinear"]


def bilinear(grid: np.ndarray, x0: float, dx: float, x: np.ndarray, y0=None, dy=None, y=None):
    """Bilinear (linear in 1-D) interpolation on a uniform grid; NaN outside it."""
    fx = (x - x0) / dx
    nx = grid.shape[-1]
    inside = (fx >= 0) & (fx <= nx - 1)
    fx = np.clip(fx, 0, nx - 1)
    ix = np.minimum(np.floor(fx).astype(np.intp), nx - 2)
    tx = fx - ix
    if y is None:
        val = grid[ix] * (1 - tx) + grid[ix + 1] * tx
        return np.where(inside, val, np.nan)
    fy = (y - y0) / dy
    ny = grid.shape[0]
    inside &= (fy >= 0) & (fy <= ny - 1)
    fy = np.clip(fy, 0, ny - 1)
    iy = np.minimum(np.floor(fy).astype(np.intp), ny - 2)
    ty = fy - iy
    val = (grid[iy, ix] * (1 - tx) + grid[iy, ix + 1] * tx) * (1 - ty) + (
        grid[iy + 1, ix] * (1 - tx) + grid[iy + 1, ix + 1] * tx
    ) * ty
    return np.where(inside, val, np.nan)
