"""Müller's second-kind integral equations of a dielectric interface ``z = f(x, y)`` between
air (above, ``ε₁ = 1``) and a lossy or lossless medium ``ε₂`` (below), pulse bases and point
matching, for :mod:`.dielectric_model`.

Unknowns (``H`` in units of ``E/η₀``, normal ``n̂`` up into air): ``J = n̂ × H`` and
``M = −n̂ × E`` on the interface, as projected densities ``u = sJ``, ``w = sM``
(``s = √(1 + f_x² + f_y²)``, ``J dS = u dx dy``), two tangential components each: four unknowns
per node, ordered ``[u_x, u_y, w_x, w_y]`` (N each). With ``T_i = (I + ∇∇/k_i²)∫ G_i``,
``k_i² = ε_i k₀²``, the magnetic- and electric-field equations taken from each side (extinction
theorem, the two media's Green's functions) are combined with weights ``(1, −1)`` and
``(ε₁, −ε₂)`` (Müller 1969; Poggio & Miller 1973 §4; Tsang, Kong, Ding & Ao 2001 vol. II
ch. 11 use the same pair of media for rough surfaces)::

    J − n̂ × PV∫(∇G₁ − ∇G₂) × J − i k₀ n̂ × K M = n̂ × H_inc,
    ½(ε₁ + ε₂) M − n̂ × PV∫(ε₁∇G₁ − ε₂∇G₂) × M + i k₀ n̂ × K J = −ε₁ n̂ × E_inc,
    K X = ∫ [(ε₁G₁ − ε₂G₂) X + ∇∇(G₁ − G₂)·X / k₀²] dS'.

The hypersingular ``∇∇G/R³`` parts cancel in ``K`` (``∇∇(G₁ − G₂) = O(1/R)``) and the
``∇G₁ − ∇G₂`` kernel is bounded, so the system is of the second kind, as the PEC MFIE of
:mod:`.operator`. The ``ε₁∇G₁ − ε₂∇G₂`` kernel has the static part ``(ε₁ − ε₂)`` times the PEC
one and takes the singularity subtraction of :mod:`.near` scaled by ``ε₁ − ε₂``. The self cell
of ``K`` is integrated on the tangent plane: with the small-``R`` expansion
``4π(G₁ − G₂) = i(k₁ − k₂) − (k₁² − k₂²)R/2 − i(k₁³ − k₂³)R²/6 + …``::

    ∫_cell K ≈ (ε₁ − ε₂)/(8π) (I₁ I + I₂) + i/(4π) [ε₁k₁ − ε₂k₂ − (k₁³ − k₂³)/(3k₀²)] Δx Δy I,
    I₁ = ∫ dx dy / R,   I₂ = ∫ R̂R̂ dx dy / R      (polar integration, exact radial part).

Rows: the x and y components of each equation (the z row follows, ``N_z = 1``); each block is
``P_m · kernel · B_n`` with ``P_m`` the x, y rows of ``[N_m]_×`` and ``B_n`` lifting
``(X_x, X_y)`` to ``(X_x, X_y, f_x X_x + f_y X_y)``.
"""

from __future__ import annotations

import math

import numpy as np

from emscatter.solvers.mom3d.near import near_correction
from emscatter.solvers.mom3d.operator import Patch, gmres_solve

__all__ = [
    "assemble_dielectric",
    "media",
    "pair_blocks",
    "rhs_dielectric",
    "self_blocks",
    "self_integrals",
    "solve_dielectric",
]

#: Bytes of complex temporaries per row block in :func:`assemble_dielectric`.
BLOCK_BYTES = 64 * 2**20
_N_ANGLE = 16


def self_integrals(fx: np.ndarray, fy: np.ndarray, dx: float, dy: float):
    """``I₁ = ∫ dxdy/R`` ``(N,)`` and ``I₂ = ∫ R̂R̂ dxdy/R`` ``(N, 3, 3)`` over each node's own
    cell on its tangent plane ``z = f_x ξ + f_y η`` [m]: ``R = ρ|t|``, ``t = (cosφ, sinφ,
    f_x cosφ + f_y sinφ)``, so the radial integral is the cell's edge distance ``ρ_e(φ)``;
    Gauss–Legendre in angle on each of the 8 triangle halves of the rectangle."""
    xg, wg = np.polynomial.legendre.leggauss(_N_ANGLE)
    a, b = dx / 2, dy / 2
    corner = math.atan2(b, a)
    edges = [0.0, corner, math.pi / 2, math.pi - corner, math.pi]
    edges += [math.pi + corner, 1.5 * math.pi, 2 * math.pi - corner, 2 * math.pi]
    i1 = np.zeros(fx.size)
    i2 = np.zeros((fx.size, 3, 3))
    for lo, hi in zip(edges[:-1], edges[1:], strict=True):
        phi = 0.5 * (hi - lo) * xg + 0.5 * (hi + lo)
        w = 0.5 * (hi - lo) * wg
        c, s = np.cos(phi), np.sin(phi)
        with np.errstate(divide="ignore"):
            rho_e = np.minimum(
                np.where(c != 0, a / np.abs(c), np.inf), np.where(s != 0, b / np.abs(s), np.inf)
            )
        tz = fx[:, None] * c + fy[:, None] * s  # (N, A)
        tn = np.sqrt(1.0 + tz * tz)
        base = w * rho_e / tn  # (N, A)
        i1 += base.sum(axis=1)
        t = np.stack([np.broadcast_to(c, tz.shape), np.broadcast_to(s, tz.shape), tz], axis=2)
        i2 += np.einsum("na,nai,naj->nij", base / (tn * tn), t, t)
    return i1, i2


def _lift_blocks(fxm, fym, fxn, fyn):
    """``P_m B_n`` (the identity kernel), four ``(m, n)`` arrays."""
    return -fym * fxn, -1.0 - fym * fyn, 1.0 + fxm * fxn, fxm * fyn


def media(k0: float, eps2: complex):
    """``(ε₁, ε₂, k₁, k₂, 2/(ε₁ + ε₂))`` with ``Im k₂ ≥ 0`` (the decaying branch)."""
    e1, e2 = 1.0, complex(eps2)
    k1, k2 = k0, k0 * np.sqrt(e2)
    if k2.imag < 0:
        k2 = -k2
    return e1, e2, k1, k2, 2.0 / (e1 + e2)


def pair_blocks(X, Y, Z, fxm, fym, fxn, fyn, self_mask, k0, eps2, area):
    """The 16 off-self entries of the Müller matrix for the pairs ``r_m − r_n = (X, Y, Z)``
    [m] (broadcast arrays; slopes of the observation ``m`` and source ``n`` nodes), as a dict
    ``(row block, column block) → array`` over the blocks ``[u_x, u_y, w_x, w_y]``; entries
    where ``self_mask`` is true are zero (the self cell is :func:`_add_self`'s)."""
    e1, e2, k1, k2, scale_e = media(k0, eps2)
    R = np.sqrt(X * X + Y * Y + Z * Z)
    R = np.where(self_mask, 1.0, R)
    e1r, e2r = np.exp(1j * k1 * R), np.exp(1j * k2 * R)
    inv = 1.0 / (4.0 * math.pi * R)
    g1, g2 = e1r * inv, e2r * inv
    # ∇G = a R with a = (ikR − 1) G / R²  (the ``a`` of :mod:`.operator`, per unit area)
    a1 = (1j * k1 * R - 1.0) * g1 / (R * R)
    a2 = (1j * k2 * R - 1.0) * g2 / (R * R)
    # G'' for each medium; ∇∇g = g'' R̂R̂ + (g'/R)(I − R̂R̂) with g = (G₁ − G₂)/k₀²
    d1 = (2.0 - 2j * k1 * R - (k1 * R) ** 2) * g1 / (R * R)
    d2 = (2.0 - 2j * k2 * R - (k2 * R) ** 2) * g2 / (R * R)
    gp_r = (a1 - a2) / k0**2  # g'/R
    alpha = np.where(self_mask, 0.0, (e1 * g1 - e2 * g2 + gp_r) * area)
    beta = np.where(self_mask, 0.0, ((d1 - d2) / k0**2 - gp_r) / (R * R) * area)
    D = Z - fxm * X - fym * Y
    dfx = fxn - fxm
    dfy = fyn - fym
    out = {}
    for a, off, sc in (((a1 - a2) * area, 0, 1.0), ((e1 * a1 - e2 * a2) * area, 2, scale_e)):
        a = np.where(self_mask, 0.0, a)
        out[off, off] = -sc * a * (X * dfx - D)
        out[off, off + 1] = -sc * a * X * dfy
        out[off + 1, off] = -sc * a * Y * dfx
        out[off + 1, off + 1] = -sc * a * (Y * dfy - D)
    lxx, lxy, lyx, lyy = _lift_blocks(fxm, fym, fxn, fyn)
    px, py = -Y - fym * Z, X + fxm * Z
    qx, qy = X + fxn * Z, Y + fyn * Z
    kxx = alpha * lxx + beta * px * qx
    kxy = alpha * lxy + beta * px * qy
    kyx = alpha * lyx + beta * py * qx
    kyy = alpha * lyy + beta * py * qy
    for r_off, c_off, c in ((0, 2, -1j * k0), (2, 0, 1j * k0 * scale_e)):
        out[r_off, c_off] = c * kxx
        out[r_off, c_off + 1] = c * kxy
        out[r_off + 1, c_off] = c * kyx
        out[r_off + 1, c_off + 1] = c * kyy
    return out


def assemble_dielectric(patch: Patch, k0: float, eps2: complex, dtype=np.complex128):
    """The dense ``(4N, 4N)`` Müller matrix for the interface air/``eps2`` at free-space
    wavenumber ``k0`` [rad/m]; unknowns ``[u_x, u_y, w_x, w_y]``; the electric rows scaled by
    ``2/(ε₁ + ε₂)`` (unit diagonal)."""
    n = patch.n
    e1, e2, k1, k2, scale_e = media(k0, eps2)
    x, y, z, fx, fy = patch.x, patch.y, patch.z, patch.fx, patch.fy
    area = patch.dx * patch.dy
    mat = np.zeros((4 * n, 4 * n), dtype=dtype)
    rows = max(1, int(BLOCK_BYTES // (16 * 16 * n)))
    for r0 in range(0, n, rows):
        m = slice(r0, min(n, r0 + rows))
        idx = np.arange(m.start, m.stop)
        X = x[m, None] - x[None, :]
        Y = y[m, None] - y[None, :]
        Z = z[m, None] - z[None, :]
        self_mask = np.zeros(X.shape, dtype=bool)
        self_mask[idx - r0, idx] = True
        blocks = pair_blocks(X, Y, Z, fx[m, None], fy[m, None], fx[None, :], fy[None, :],
                             self_mask, k0, eps2, area)  # fmt: skip
        for (bi, bj), val in blocks.items():
            mat[bi * n + m.start : bi * n + m.stop, bj * n : (bj + 1) * n] = val
    _add_self(mat, patch, k0, eps2)
    diag = np.arange(4 * n)
    mat[diag, diag] += 1.0
    _add_near(mat, patch, (e1 - e2) * scale_e)
    return mat


def self_blocks(patch, k0, eps2) -> dict:
    """The self-cell entries of the ``K`` blocks (module docstring), ``(row block, column
    block) → (N,)`` over the blocks ``[u_x, u_y, w_x, w_y]`` (the identity not included)."""
    e1, e2, k1, k2, scale_e = media(k0, eps2)
    n = patch.n
    area = patch.dx * patch.dy
    i1, i2 = self_integrals(patch.fx, patch.fy, patch.dx, patch.dy)
    const = 1j / (4 * math.pi) * (e1 * k1 - e2 * k2 - (k1**3 - k2**3) / (3 * k0**2)) * area
    kint = (e1 - e2) / (8 * math.pi) * (i1[:, None, None] * np.eye(3) + i2)
    kint = kint + const * np.eye(3)  # (N, 3, 3)
    fx, fy = patch.fx, patch.fy
    p = np.zeros((n, 2, 3))
    p[:, 0, 1], p[:, 0, 2] = -1.0, -fy
    p[:, 1, 0], p[:, 1, 2] = 1.0, fx
    b = np.zeros((n, 3, 2))
    b[:, 0, 0], b[:, 1, 1], b[:, 2, 0], b[:, 2, 1] = 1.0, 1.0, fx, fy
    blk = np.einsum("nij,njk,nkl->nil", p, kint, b)  # (N, 2, 2)
    out = {}
    for r_off, c_off, c in ((0, 2, -1j * k0), (2, 0, 1j * k0 * scale_e)):
        for i in range(2):
            for j in range(2):
                out[r_off + i, c_off + j] = c * blk[:, i, j]
    return out


def _add_self(mat, patch, k0, eps2):
    n = patch.n
    d = np.arange(n)
    for (bi, bj), val in self_blocks(patch, k0, eps2).items():
        mat[bi * n + d, bj * n + d] = val


def _add_near(mat, patch, factor):
    """The :mod:`.near` correction of the static ``∇G`` kernel, times ``factor``, on the
    electric rows (their ``ε₁∇G₁ − ε₂∇G₂`` kernel)."""
    n = patch.n
    ny, nx = patch.shape
    iy, ix = np.divmod(np.arange(n), nx)
    o = 2 * n
    for i, j, c in near_correction(patch, patch.z.reshape(ny, nx)):
        ok = (ix + i >= 0) & (ix + i < nx) & (iy + j >= 0) & (iy + j < ny)
        m = np.nonzero(ok)[0]
        col = m + i + j * nx
        mat[o + m, o + col] += factor * c[0, 0, m]
        mat[o + m, o + n + col] += factor * c[0, 1, m]
        mat[o + n + m, o + col] += factor * c[1, 0, m]
        mat[o + n + m, o + n + col] += factor * c[1, 1, m]


def rhs_dielectric(patch: Patch, e_inc: np.ndarray, h_inc: np.ndarray, eps2: complex):
    """Right-hand side ``[N × H_inc; −ε₁ N × E_inc · 2/(ε₁ + ε₂)]`` (x, y rows), fields
    ``(N, 3)`` in the units of :mod:`.incident`."""

    def ncross(v):
        vx, vy, vz = v[:, 0], v[:, 1], v[:, 2]
        return np.concatenate([-patch.fy * vz - vy, vx + patch.fx * vz])

    return np.concatenate([ncross(h_inc), -2.0 / (1.0 + complex(eps2)) * ncross(e_inc)])


def solve_dielectric(mat, rhs_list, *, tol=1e-6, max_iter=400):
    """GMRES (restart 80, :func:`~emscatter.solvers.mom3d.operator.gmres_solve`) for each
    right-hand side; returns ``(solutions, iterations, residuals)``. Raises
    :class:`RuntimeError` naming the residual when ``tol`` is missed: an unconverged current is
    never returned silently."""
    return gmres_solve(
        mat, rhs_list, tol=tol, max_iter=max_iter, restart=80, what="mom3d dielectric",
        hint="raise max_iter or refine the grid",
    )  # fmt: skip
