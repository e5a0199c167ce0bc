"""Near-singular corrections of the pulse-basis MFIE (:mod:`.operator`): the self cell and its
neighbours integrated instead of point-sampled.

Near node ``m`` the surface is its Taylor model ``z_n − z_m = f_x ξ + f_y η + ½Q``,
``Q = f_xx ξ² + 2 f_xy ξη + f_yy η²`` (``ξ, η = x_n − x_m, y_n − y_m``). To leading order
in the distance, with ``R³ ≈ (ρᵀ G ρ)^{3/2}``, ``G = I + ∇f ∇fᵀ`` and
``∇G ≈ −R/(4πR³)``, the MFIE entries of :mod:`.operator` become
``(1/4π) ∫ A(ξ, η) / R³ dξ dη`` over the cell of node ``n`` with::

    A_xx = −½ f_xx ξ² + ½ f_yy η²,     A_xy = −f_xy ξ² − f_yy ξη,
    A_yx = −f_xx ξη − f_xy η²,         A_yy =  ½ f_xx ξ² − ½ f_yy η².

The kernel is ``O(curvature/ρ)``: integrable, but point matching misses its self cell
(``O(Δ κ)``, the principal value of a curved cell; zero on a flat one) and samples its
neighbours poorly. This module adds, for the self cell and the ``(2w+1)² − 1`` cells around
it, ``∫_cell model − Δ² · model(centre)`` (singularity subtraction): the self cell by polar
integration (the radial integral of ``ρ^2/ρ^3 · ρ`` is exact, Gauss–Legendre in angle on
each of the 8 triangle halves), the others by tensor Gauss–Legendre. Without it the energy
error of a rough patch decreases only as ``O(Δ)``.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["curvatures", "near_correction"]

#: Half-width of the corrected neighbourhood in cells (the self cell and 24 neighbours).
WIDTH = 2
_N_ANGLE = 12
_N_GL = 8


def curvatures(h: np.ndarray, dx: float, dy: float) -> tuple[np.ndarray, ...]:
    """``(f_xx, f_xy, f_yy)`` of a ``(ny, nx)`` map by repeated 2nd-order differences."""
    fx = np.gradient(h, dx, axis=1, edge_order=2)
    fy = np.gradient(h, dy, axis=0, edge_order=2)
    fxx = np.gradient(fx, dx, axis=1, edge_order=2)
    fxy = np.gradient(fx, dy, axis=0, edge_order=2)
    fyy = np.gradient(fy, dy, axis=0, edge_order=2)
    return fxx, fxy, fyy


def _moments_self(fx, fy, dx, dy):
    """``∫_cell (ξ², ξη, η²) / (ρᵀGρ)^{3/2}`` over the node's own cell, ``(3, N)``."""
    xg, wg = np.polynomial.legendre.leggauss(_N_ANGLE)
    a, b = dx / 2, dy / 2
    corner = math.atan2(b, a)
    edges = [0.0, corner, math.pi - corner, math.pi, math.pi + corner, 2 * math.pi - corner]
    edges.append(2 * math.pi)
    out = np.zeros((3, fx.size))
    for lo, hi in zip(edges[:-1], edges[1:], strict=True):
        phi = 0.5 * (hi - lo) * xg + 0.5 * (hi + lo)
        w = 0.5 * (hi - lo) * wg
        c, s = np.cos(phi), np.sin(phi)
        with np.errstate(divide="ignore"):
            rho_e = np.minimum(
                np.where(c != 0, a / np.abs(c), np.inf), np.where(s != 0, b / np.abs(s), np.inf)
            )
        sl = np.sqrt(1.0 + (fx[:, None] * c + fy[:, None] * s) ** 2) ** 3  # (N, A)
        base = w * rho_e / sl
        out[0] += (base * c * c).sum(axis=1)
        out[1] += (base * c * s).sum(axis=1)
        out[2] += (base * s * s).sum(axis=1)
    return out


def _moments_cell(fx, fy, dx, dy, i, j):
    """``∫_cell − Δ² · centre`` of ``(ξ², ξη, η²)/R³`` for the cell offset ``(i, j)``."""
    xg, wg = np.polynomial.legendre.leggauss(_N_GL)
    xi = (i + 0.5 * xg) * dx
    et = (j + 0.5 * xg) * dy
    xx, ee = np.meshgrid(xi, et, indexing="ij")
    ww = np.outer(wg, wg) * (0.25 * dx * dy)
    pts = [(xx.ravel(), ee.ravel(), ww.ravel()), (np.array([i * dx]), np.array([j * dy]), None)]
    res = []
    for px, py, pw in pts:
        r3 = (px * px + py * py + (fx[:, None] * px + fy[:, None] * py) ** 2) ** 1.5
        wt = (pw if pw is not None else np.array([dx * dy])) / r3
        res.append(np.stack([(wt * px * px).sum(1), (wt * px * py).sum(1), (wt * py * py).sum(1)]))
    return res[0] - res[1]


def near_correction(patch, heights: np.ndarray) -> list[tuple[int, int, np.ndarray]]:
    """Corrections to add to the dense matrix of :func:`.operator.assemble`: a list of
    ``(i, j, C)`` for each cell offset (``i`` along x, ``j`` along y) with ``C`` of shape
    ``(2, 2, N)`` (rows x/y × columns x/y × observation node)."""
    fxx, fxy, fyy = (c.ravel() for c in curvatures(heights, patch.dx, patch.dy))
    fx, fy = patch.fx, patch.fy
    out = []
    for j in range(-WIDTH, WIDTH + 1):
        for i in range(-WIDTH, WIDTH + 1):
            if i == 0 and j == 0:
                m20, m11, m02 = _moments_self(fx, fy, patch.dx, patch.dy)
            else:
                m20, m11, m02 = _moments_cell(fx, fy, patch.dx, patch.dy, i, j)
            c = np.empty((2, 2, fx.size))
            c[0, 0] = -0.5 * fxx * m20 + 0.5 * fyy * m02
            c[0, 1] = -fxy * m20 - fyy * m11
            c[1, 0] = -fxx * m11 - fxy * m02
            c[1, 1] = 0.5 * fxx * m20 - 0.5 * fyy * m02
            out.append((i, j, c / (4.0 * math.pi)))
    return out
