"""The magnetic-field integral equation (MFIE) of a perfectly conducting surface ``z = f(x, y)``,
discretized with pulse bases and point matching, and its GMRES solution.

With ``J = n̂ × H`` the surface current, ``G = e^{ikR}/(4πR)`` and ``R = r − r'``, the total
field just above a perfect conductor gives (Poggio & Miller 1973; Tsang, Kong, Ding & Ao 2001
vol. II ch. 10 for rough surfaces)::

    J(r)/2 − n̂ × PV∫ ∇G(r − r') × J(r') dS' = n̂ × H_inc(r),
    ∇G(R) = R (ikR − 1) e^{ikR} / (4π R³).

Multiplied by ``s = √(1 + f_x² + f_y²)`` it is written for the projected density
``u = s J`` (``J dS = u dx dy``) and the unnormalized normal ``N = (−f_x, −f_y, 1)``::

    u/2 − N × Σ' ∇G × u' Δx Δy = N × H_inc,    N × (R × u') = R (N·u') − u' (N·R).

``u`` is tangential, ``u_z = f_x u_x + f_y u_y``, so two unknowns ``(u_x, u_y)`` per node
(Tsang's two tangential unknowns) and the x, y rows are the equations (the z row is their
consequence since ``N_z = 1``). Entries ``m ≠ n``, with ``X, Y, Z = r_m − r_n``,
``D = N_m·R = Z − f_xm X − f_ym Y``, ``a = Δx Δy (ikR − 1) e^{ikR}/(4πR³)``::

    M_xx = δ/2 − a [X (f_xn − f_xm) − D],   M_xy = −a X (f_yn − f_ym),
    M_yx = −a Y (f_xn − f_xm),              M_yy = δ/2 − a [Y (f_yn − f_ym) − D].

Self term: the principal value over the node's own cell vanishes on a flat cell
(``R ⊥ N`` and ``u ⊥ N``) and is ``O(Δ · curvature)`` otherwise; it is taken as zero, leaving
the analytic ``J/2``. Slopes by 4th-order central differences (2nd order at the two edge
rows, where the taper has made the current negligible).

The matrix is assembled densely in row blocks (vectorized: no Python loop over nodes) and
solved by restarted GMRES (:func:`scipy.sparse.linalg.gmres`) on a
:class:`~scipy.sparse.linalg.LinearOperator`. The MFIE is of the second kind, so GMRES
converges in tens of iterations without preconditioning.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.sparse import linalg as spla

from emscatter.solvers.mom3d.near import near_correction

__all__ = ["Patch", "assemble", "make_patch", "solve", "slopes"]

#: Bytes of complex temporaries per row block in :func:`assemble` (keeps peak memory bounded).
BLOCK_BYTES = 64 * 2**20


@dataclass(frozen=True)
class Patch:
    """A sampled surface: node coordinates and slopes, all flattened ``(N,)`` in C order of a
    ``(ny, nx)`` grid (axis 0 = y) [m, -]; ``dx, dy`` the spacings [m]."""

    x: np.ndarray
    y: np.ndarray
    z: np.ndarray
    fx: np.ndarray
    fy: np.ndarray
    dx: float
    dy: float
    shape: tuple[int, int]

    @property
    def n(self) -> int:
        return self.x.size

    @property
    def points(self) -> np.ndarray:
        return np.stack([self.x, self.y, self.z], axis=1)


def _diff4(h: np.ndarray, d: float, axis: int) -> np.ndarray:
    out = np.gradient(h, d, axis=axis, edge_order=2)
    a, o = np.moveaxis(h, axis, 0), np.moveaxis(out, axis, 0)  # o is a view of out
    if a.shape[0] >= 5:
        o[2:-2] = (-a[4:] + 8.0 * a[3:-1] - 8.0 * a[1:-3] + a[:-4]) / (12.0 * d)
    return out


def slopes(h: np.ndarray, dx: float, dy: float) -> tuple[np.ndarray, np.ndarray]:
    """``(f_x, f_y)`` of a ``(ny, nx)`` height map [-], 4th-order central differences."""
    return _diff4(h, dx, 1), _diff4(h, dy, 0)


def make_patch(heights: np.ndarray, dx: float, dy: float) -> Patch:
    """A :class:`Patch` centred on the origin from a ``(ny, nx)`` height map [m]."""
    h = np.asarray(heights, dtype=float)
    ny, nx = h.shape
    xs = (np.arange(nx) - (nx - 1) / 2) * dx
    ys = (np.arange(ny) - (ny - 1) / 2) * dy
    xx, yy = np.meshgrid(xs, ys)
    fx, fy = slopes(h, dx, dy)
    return Patch(xx.ravel(), yy.ravel(), h.ravel(), fx.ravel(), fy.ravel(), dx, dy, (ny, nx))


def assemble(patch: Patch, k: float, dtype=np.complex128, *, near: bool = True) -> np.ndarray:
    """The dense ``(2N, 2N)`` MFIE matrix, unknowns ordered ``[u_x (N), u_y (N)]``; with
    ``near`` the self and neighbour cells integrated (:mod:`.near`)."""
    n = patch.n
    x, y, z, fx, fy = patch.x, patch.y, patch.z, patch.fx, patch.fy
    area = patch.dx * patch.dy
    mat = np.empty((2 * n, 2 * n), dtype=dtype)
    rows = max(1, int(BLOCK_BYTES // (16 * 8 * n)))
    for r0 in range(0, n, rows):  # row blocks bound the memory; each block is vectorized
        m = slice(r0, min(n, r0 + rows))
        X = x[m, None] - x[None, :]
        Y = y[m, None] - y[None, :]
        Z = z[m, None] - z[None, :]
        R = np.sqrt(X * X + Y * Y + Z * Z)
        idx = np.arange(m.start, m.stop)
        R[idx - r0, idx] = 1.0
        a = area * (1j * k * R - 1.0) * np.exp(1j * k * R) / (4.0 * math.pi * R**3)
        a[idx - r0, idx] = 0.0
        D = Z - fx[m, None] * X - fy[m, None] * Y
        dfx = fx[None, :] - fx[m, None]
        dfy = fy[None, :] - fy[m, None]
        mat[m, :n] = -a * (X * dfx - D)
        mat[m, n:] = -a * (X * dfy)
        mat[n + m.start : n + m.stop, :n] = -a * (Y * dfx)
        mat[n + m.start : n + m.stop, n:] = -a * (Y * dfy - D)
    diag = np.arange(2 * n)
    mat[diag, diag] += 0.5
    if near:
        _add_near(mat, patch)
    return mat


def _add_near(mat: np.ndarray, patch: Patch) -> None:
    n = patch.n
    ny, nx = patch.shape
    iy, ix = np.divmod(np.arange(n), nx)
    for i, j, c in near_correction(patch, patch.z.reshape(ny, nx)):
        ok = (ix + i >= 0) & (ix + i < nx) & (iy + j >= 0) & (iy + j < ny)
        m = np.nonzero(ok)[0]
        col = m + i + j * nx
        mat[m, col] += c[0, 0, m]
        mat[m, n + col] += c[0, 1, m]
        mat[n + m, col] += c[1, 0, m]
        mat[n + m, n + col] += c[1, 1, m]


def rhs(patch: Patch, h_inc: np.ndarray) -> np.ndarray:
    """``N × H_inc`` (x and y rows) for ``h_inc`` of shape ``(N, 3)``."""
    hx, hy, hz = h_inc[:, 0], h_inc[:, 1], h_inc[:, 2]
    return np.concatenate([-patch.fy * hz - hy, hx + patch.fx * hz])


def current(patch: Patch, sol: np.ndarray) -> np.ndarray:
    """The 3-D projected density ``u = s J`` (``(N, 3)`` [A/m in E/η units]) from ``(u_x, u_y)``."""
    ux, uy = sol[: patch.n], sol[patch.n :]
    return np.stack([ux, uy, patch.fx * ux + patch.fy * uy], axis=1)


@dataclass(frozen=True)
class Solution:
    """GMRES output: ``u`` the ``(N, 3)`` density per right-hand side (list), ``iterations``
    the inner iterations of each, ``residual`` the relative residual of each."""

    u: list
    iterations: list
    residual: list


def gmres_solve(mat: np.ndarray, rhs_list: list, *, tol: float, max_iter: int, restart: int,
                physical_optics_start: bool = False, what: str = "mom3d",
                hint: str = "raise max_iter or check the surface sampling"):  # fmt: skip
    """``M x = b`` for each ``b`` in ``rhs_list`` by GMRES (``restart``) on a
    :class:`~scipy.sparse.linalg.LinearOperator` wrapping the dense matrix (complex64 matrices
    are applied in single precision, the iteration in double). ``physical_optics_start``:
    start from ``x = 2b`` (the PEC current ``2 N × H_inc``). Returns ``(solutions, iterations,
    residuals)``; raises :class:`RuntimeError` naming the residual if GMRES has not reached
    ``tol`` within ``max_iter`` iterations: an unconverged current is never returned silently."""
    n = mat.shape[0]
    low = mat.dtype == np.complex64

    def mv(v):
        v = np.asarray(v).ravel()
        if low:
            return (mat @ v.astype(np.complex64)).astype(np.complex128)
        return mat @ v

    op = spla.LinearOperator((n, n), matvec=mv, dtype=np.complex128)
    xs, its, res = [], [], []
    for b in rhs_list:
        count = [0]

        def cb(_r, count=count):
            count[0] += 1

        x, info = spla.gmres(
            op,
            b,
            x0=2.0 * b if physical_optics_start else None,
            rtol=tol,
            atol=0.0,
            restart=restart,
            maxiter=max(1, max_iter // restart + 1),
            callback=cb,
            callback_type="pr_norm",
        )
        r = float(np.linalg.norm(mv(x) - b) / np.linalg.norm(b))
        if info != 0 and r > 10 * tol:
            raise RuntimeError(
                f"{what}: GMRES did not converge: relative residual {r:.3g} > tol={tol:g} "
                f"after {count[0]} iterations ({hint})"
            )
        xs.append(x)
        its.append(count[0])
        res.append(r)
    return xs, its, res


def solve(
    mat: np.ndarray, patch: Patch, rhs_list: list, *, tol: float = 1e-5, max_iter: int = 300
) -> Solution:
    """Solve ``M u = b`` for each ``b`` in ``rhs_list`` (:func:`gmres_solve`, restart 50, from
    the physical-optics current) and return the surface currents."""
    xs, its, res = gmres_solve(mat, rhs_list, tol=tol, max_iter=max_iter, restart=50,
                               physical_optics_start=True)  # fmt: skip
    return Solution([current(patch, x) for x in xs], its, res)
