"""The sparse-matrix/canonical-grid (SMCG) matrix-vector product of the PEC MFIE
(:mod:`.operator`): ``O(N log N)`` time and ``O(N r_d²)`` memory instead of the dense ``4N²``.

Tsang, Chan & Pak, J. Opt. Soc. Am. A 10 (1993); Tsang, Chan, Pak & Sangani, IEEE Trans.
Antennas Propag. 43 (1995); Pak, Tsang & Johnson, J. Opt. Soc. Am. A 14 (1997) for 2-D
surfaces; Tsang, Kong, Ding & Ao, *Scattering of Electromagnetic Waves* vol. II (2001) ch. 10.

With ``X, Y, Z = r_m − r_n`` and ``w = f_x u_x + f_y u_y`` (``= u_z``) the MFIE rows of
:mod:`.operator` regroup as::

    y_x = u_x/2 − [S_X(w) + f_ym C − S_Z(u_x)],    y_y = u_y/2 − [S_Y(w) − f_xm C − S_Z(u_y)],
    C = S_Y(u_x) − S_X(u_y),    S_W(v)_m = Σ_n a_mn W_mn v_n,
    a_mn = Δx Δy F(R),  F(R) = (ikR − 1) e^{ikR} / (4π R³),  R² = ρ² + Z².

Strong pairs (``ρ < r_d``, the ``near_radius``) are the exact entries of the dense code,
near-cell correction (:mod:`.near`) and ``J/2`` included, in a :mod:`scipy.sparse` CSR matrix.
Weak pairs (``ρ ≥ r_d``) use the Taylor series of ``F`` in ``Z²`` about the flat surface::

    F(√(ρ² + Z²)) = Σ_{p=0}^{P} g_p(ρ) Z^{2p} + E_P,    g_p = (L^{p+1} G)(ρ) / (2^p p!),
    L = (1/R) d/dR,   G = e^{ikR} / (4πR)          (d/d(R²) = L/2 and F = L G),

and ``(z_m − z_n)^q = Σ_l C(q, l) z_m^{q−l} (−z_n)^l``, so every term is a 2-D convolution on
the regular grid of a translation-invariant kernel (``g_p X``, ``g_p Y``, ``g_p``) with a
source ``(−z)^l v``, done by zero-padded FFTs (:func:`scipy.fft.fft2`, ``workers=-1``):
``3(2P+2) − 1`` forward and ``3(2P+2)`` inverse FFTs of size ``≈ 2n_y × 2n_x`` per product.
The canonical-grid kernels are zero for ``ρ < r_d`` — the near part of each flat
convolution is removed from the kernel itself, so no pair is counted twice and the
singular ``ρ = 0`` never enters.

Order and truncation error: ``P = taylor_order`` is the highest power of ``Z²`` kept (``P = 0``
is the flat-surface kernel alone). ``F`` is analytic in ``s = R²`` except at ``s = 0``; the
Cauchy estimate on the circle ``|s − ρ²| = r`` (``|e^{ik√s}| ≤ e^{kr/2ρ}`` there) with the
optimal ``r = 2ρ(P+1)/k`` (admissible for ``kρ > 2(P+1)``) gives, per pair,

    |E_P| ≤ c |F(ρ)| (e ξ / (P+1))^{P+1} / (1 − Z² / r),    ξ = k Z² / (2ρ),

with ``c = O(1)``: the remainder of the phase series ``exp(i ξ)`` (the static part
``(Z/ρ)^{2P+2}`` is smaller for ``kρ ≫ 1``). For ``kσ ≤ 1`` and ``r_d = 2.5λ`` the worst pair
(``|Z| ≈ 6σ``) has ``ξ ≤ 1.2`` and the typical one ``ξ ≈ 0.1``. Measured relative error of
the whole product against the dense one (tests/test_mom3d_smcg.py; 5λ patch, Gaussian kσ = 1,
kℓ = 3), order 0…4: 6.3e-3, 7.2e-4, 8.5e-5, 9.3e-6, 9.5e-7 at ``r_d = 2.5λ``; 1.5e-2, 2.6e-3,
5.4e-4, 1.3e-4, 2.9e-5 at ``1.5λ``. The series diverges where ``|Z| ≥ ρ``: the caller
(:mod:`.model`) keeps the peak-to-valley height below ``0.8 r_d``.

Cost per product: the sparse part ``4 N π (r_d/Δ)²`` nonzeros (≈ 8e7 for 16λ × 16λ at 8
points/λ and ``r_d = 2.5λ``, 12 bytes each in complex64), the FFT part ``O((2P+2) N log N)``.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import fft as sfft
from scipy import sparse

from emscatter.conventions import check_positive, fmt
from emscatter.solvers.mom3d.near import WIDTH, near_correction

__all__ = ["MAX_PTP_OVER_RD", "NearFarProduct", "SmcgOperator", "resolve_near_radius",
           "smcg_operator", "taylor_kernels"]  # fmt: skip

#: The Taylor series in ``Z²/ρ²`` converges for ``|Z| < ρ``: SMCG needs the patch's
#: peak-to-valley height below this fraction of ``r_d`` (``(Z/ρ)² < 0.64`` on every weak pair).
MAX_PTP_OVER_RD = 0.8

#: Rows per block in the strong-matrix assembly (bounds the ``(rows, offsets)`` temporaries).
ROW_BLOCK = 256


def taylor_kernels(k: float, rho: np.ndarray, order: int) -> np.ndarray:
    """``g_p(ρ)`` for ``p = 0..order`` (``(order + 1, *ρ.shape)`` complex [m⁻³ m⁻²ᵖ]), the
    coefficients of ``Z^{2p}`` in ``(ikR − 1) e^{ikR}/(4πR³)``, ``R² = ρ² + Z²``.

    ``L^n (e^{ikR} Σ_j c_j R^{−j}) = e^{ikR} Σ_j (ik c_j R^{−j−1} − j c_j R^{−j−2})`` with
    ``L = R⁻¹ d/dR`` applied to ``G = e^{ikR}/(4πR)`` (module docstring)."""
    rho = np.asarray(rho, dtype=float)
    coef = {1: 1.0 + 0j}  # G·4π e^{-ikR} = R^{-1}
    out = np.empty((order + 1, *rho.shape), dtype=complex)
    phase = np.exp(1j * k * rho) / (4.0 * math.pi)
    inv = 1.0 / rho
    for p in range(order + 1):
        new: dict[int, complex] = {}
        for j, c in coef.items():
            new[j + 1] = new.get(j + 1, 0) + 1j * k * c
            new[j + 2] = new.get(j + 2, 0) - j * c
        coef = new
        poly = sum(c * inv**j for j, c in coef.items())
        out[p] = phase * poly / (2.0**p * math.factorial(p))
    return out


def _offsets(dx: float, dy: float, radius: float, nx: int, ny: int):
    """Grid offsets ``(i, j)`` with ``(iΔx)² + (jΔy)² < r_d²``, ordered so that the column
    ``m + i + j n_x`` increases (``j`` then ``i``)."""
    mi, mj = min(nx - 1, int(radius / dx)), min(ny - 1, int(radius / dy))
    jj, ii = np.meshgrid(np.arange(-mj, mj + 1), np.arange(-mi, mi + 1), indexing="ij")
    keep = (ii * dx) ** 2 + (jj * dy) ** 2 < radius**2
    return ii[keep], jj[keep]


def _strong(patch, k: float, radius: float, dtype) -> sparse.csr_matrix:
    """The exact MFIE entries of :func:`.operator.assemble` (near correction and ``1/2``
    included) for the pairs ``ρ < radius``, as a ``(2N, 2N)`` CSR matrix."""
    n = patch.n
    ny, nx = patch.shape
    z, fx, fy = patch.z, patch.fx, patch.fy
    area = patch.dx * patch.dy
    oi, oj = _offsets(patch.dx, patch.dy, radius, nx, ny)
    shift = oi + oj * nx
    iy, ix = np.divmod(np.arange(n), nx)
    corr = {(i, j): c for i, j, c in near_correction(patch, z.reshape(ny, nx))}
    where = {(int(i), int(j)): q for q, (i, j) in enumerate(zip(oi, oj, strict=True))}
    self_q = where[(0, 0)]
    counts = np.zeros(n, dtype=np.int64)
    for r0 in range(0, n, ROW_BLOCK):  # first pass: nonzeros per row
        r = np.arange(r0, min(n, r0 + ROW_BLOCK))
        cx, cy = ix[r, None] + oi[None, :], iy[r, None] + oj[None, :]
        counts[r] = ((cx >= 0) & (cx < nx) & (cy >= 0) & (cy < ny)).sum(axis=1)
    indptr = np.zeros(2 * n + 1, dtype=np.int64)
    indptr[1:] = np.cumsum(np.concatenate([2 * counts, 2 * counts]))
    nnz = int(indptr[-1])
    itype = np.int32 if nnz < 2**31 - 1 and 2 * n < 2**31 else np.int64
    data = np.empty(nnz, dtype=dtype)
    indices = np.empty(nnz, dtype=itype)
    X, Y = -oi * patch.dx, -oj * patch.dy  # x_m − x_n etc. per offset (exact on the grid)
    rho2 = X * X + Y * Y
    q0 = area / (4.0 * math.pi)
    for r0 in range(0, n, ROW_BLOCK):  # second pass: the entries, vectorized per block
        r = np.arange(r0, min(n, r0 + ROW_BLOCK))
        cx, cy = ix[r, None] + oi[None, :], iy[r, None] + oj[None, :]
        ok = (cx >= 0) & (cx < nx) & (cy >= 0) & (cy < ny)
        col = np.where(ok, r[:, None] + shift[None, :], r[:, None])
        Z = z[r, None] - z[col]
        R2 = rho2 + Z * Z
        R2[:, self_q] = 1.0
        R = np.sqrt(R2)
        kr = k * R
        c, sn = np.cos(kr), np.sin(kr)
        q = q0 / (R2 * R)
        q[:, self_q] = 0.0
        a = (-c - kr * sn) * q + 1j * ((kr * c - sn) * q)  # Δ²(ikR − 1)e^{ikR}/(4πR³)
        D = Z - fx[r, None] * X - fy[r, None] * Y
        dfx, dfy = fx[col] - fx[r, None], fy[col] - fy[r, None]
        blocks = [a * (D - X * dfx), -a * (X * dfy), -a * (Y * dfx), a * (D - Y * dfy)]
        blocks[0][:, self_q] += 0.5
        blocks[3][:, self_q] += 0.5
        for (i, j), cc in corr.items():
            qq = where[(i, j)]
            for b, (s, t) in enumerate(((0, 0), (0, 1), (1, 0), (1, 1))):
                blocks[b][:, qq] += cc[s, t, r]
        ok2 = np.concatenate([ok, ok], axis=1)
        cols2 = np.concatenate([col, col + n], axis=1)[ok2]
        for half, (b0, b1) in enumerate(((0, 1), (2, 3))):
            lo, hi = indptr[half * n + r[0]], indptr[half * n + r[-1] + 1]
            data[lo:hi] = np.concatenate([blocks[b0], blocks[b1]], axis=1)[ok2]
            indices[lo:hi] = cols2
    return sparse.csr_matrix((data, indices, indptr), shape=(2 * n, 2 * n))


def far_grid(patch, near_radius: float):
    """The canonical grid of the weak pairs: ``pad`` (the FFT size, ≥ 2n − 1 per axis), the
    offsets ``dd_x, dd_y`` [m] of pairs ``m − n`` on it (FFT order), their distance ``rho`` [m]
    and the mask ``far`` of the offsets that are weak pairs (``ρ ≥ r_d``, inside the patch)."""
    ny, nx = patch.shape
    pad = (sfft.next_fast_len(2 * ny - 1), sfft.next_fast_len(2 * nx - 1))
    py, px = pad
    dj = np.fft.fftfreq(py, 1.0 / py).astype(int)  # offsets m − n in grid steps
    di = np.fft.fftfreq(px, 1.0 / px).astype(int)
    dd_y, dd_x = np.meshgrid(dj * patch.dy, di * patch.dx, indexing="ij")
    rho = np.hypot(dd_x, dd_y)
    far = (rho * rho >= near_radius**2) & (np.abs(dj)[:, None] < ny) & (np.abs(di) < nx)
    return pad, dd_x, dd_y, rho, far


class NearFarProduct:
    """``op @ v = strong @ v + far(v)`` (complex128 in and out; the strong sparse matrix is
    applied in its own ``strong.dtype``): the product protocol of the SMCG operators (the PEC
    MFIE's :class:`SmcgOperator`, the dielectric :class:`~.dielectric_smcg.DielectricSmcgOperator`),
    which set ``strong`` and define ``far``."""

    def matvec(self, v) -> np.ndarray:
        v = np.asarray(v, dtype=np.complex128).ravel()
        near = self.strong @ v.astype(self.strong.dtype)
        return near.astype(np.complex128) + self.far(v)

    def __matmul__(self, v):
        return self.matvec(v)


class SmcgOperator(NearFarProduct):
    """The MFIE matrix of a :class:`~.operator.Patch` as a product ``op @ v``: strong pairs
    sparse, weak pairs by FFT (module docstring). ``shape``, ``dtype`` (complex128: the
    iteration's precision; the sparse entries are stored in ``strong.dtype``), ``nbytes``."""

    def __init__(self, patch, k: float, near_radius: float, taylor_order: int, dtype,
                 strong=None):  # fmt: skip
        self.patch, self.k, self.order = patch, k, int(taylor_order)
        self.near_radius = near_radius
        self.shape = (2 * patch.n, 2 * patch.n)
        self.dtype = np.dtype(np.complex128)
        self.strong = _strong(patch, k, near_radius, dtype) if strong is None else strong
        self.pad, dd_x, dd_y, rho, far = far_grid(patch, near_radius)
        py, px = self.pad
        g = np.zeros((self.order + 1, py, px), dtype=complex)
        g[:, far] = patch.dx * patch.dy * taylor_kernels(k, rho[far], self.order)
        kern = np.concatenate([g * dd_x, g * dd_y, g])  # (3(P+1), py, px)
        spec = sfft.fft2(kern, workers=-1)
        p1 = self.order + 1
        self.kx, self.ky, self.k1 = spec[:p1], spec[p1 : 2 * p1], spec[2 * p1 :]
        self.zc = patch.z - patch.z.mean()

    def with_order(self, taylor_order: int) -> SmcgOperator:
        """The same strong matrix with another Taylor order for the weak pairs (cheap)."""
        _check_order(taylor_order)
        return SmcgOperator(self.patch, self.k, self.near_radius, int(taylor_order),
                            self.strong.dtype, strong=self.strong)  # fmt: skip

    @property
    def nbytes(self) -> int:
        s = self.strong
        spec = self.kx.nbytes + self.ky.nbytes + self.k1.nbytes
        return int(s.data.nbytes + s.indices.nbytes + s.indptr.nbytes + spec)

    def far(self, v: np.ndarray) -> np.ndarray:
        """The weak-pair (``ρ ≥ r_d``) part of the product, by the Taylor series and FFTs."""
        pch, p = self.patch, self.order
        n = pch.n
        ny, nx = pch.shape
        py, px = self.pad
        ux, uy = v[:n], v[n:]
        w = pch.fx * ux + pch.fy * uy
        mz = -self.zc
        pw = np.stack([mz**q for q in range(2 * p + 2)])  # (−z)^l
        src = np.zeros((3, 2 * p + 2, py, px), dtype=complex)
        for s, vv in enumerate((w, ux, uy)):
            src[s, :, :ny, :nx] = (pw * vv).reshape(2 * p + 2, ny, nx)
        fw, fux, fuy = sfft.fft2(src, axes=(-2, -1), workers=-1, overwrite_x=True)
        acc = np.zeros((3, 2 * p + 2, py, px), dtype=complex)  # [OX, OY, OC] per z_m power
        for q in range(p + 1):
            for lo in range(2 * q + 1):  # S_X, S_Y: Z^{2q} = Σ C(2q, l) z_m^{2q−l} (−z_n)^l
                c = math.comb(2 * q, lo)
                jj = 2 * q - lo
                acc[0, jj] += c * self.kx[q] * fw[lo]
                acc[1, jj] += c * self.ky[q] * fw[lo]
                acc[2, jj] += c * (self.ky[q] * fux[lo] - self.kx[q] * fuy[lo])
            for lo in range(2 * q + 2):  # S_Z: Z^{2q+1}
                c = math.comb(2 * q + 1, lo)
                jj = 2 * q + 1 - lo
                acc[0, jj] -= c * self.k1[q] * fux[lo]
                acc[1, jj] -= c * self.k1[q] * fuy[lo]
        back = sfft.ifft2(acc, axes=(-2, -1), workers=-1, overwrite_x=True)[:, :, :ny, :nx]
        back = back.reshape(3, 2 * p + 2, n)
        zp = np.stack([self.zc**q for q in range(2 * p + 2)])
        ox, oy, oc = np.einsum("sjn,jn->sn", back, zp)
        return np.concatenate([-(ox + pch.fy * oc), -(oy - pch.fx * oc)])


def resolve_near_radius(near_radius, heights: np.ndarray, k: float, default: float) -> float:
    """``r_d`` [m] from ``near_radius`` [free-space wavelengths ``2π/k``; ``None``: ``default``,
    enlarged to keep the Taylor series convergent, ``ptp/MAX_PTP_OVER_RD``]; an explicit radius
    too small for the surface's peak-to-valley height is refused."""
    lam = 2 * math.pi / k
    ptp = float(np.ptp(heights))
    if near_radius is None:
        return max(default * lam, ptp / MAX_PTP_OVER_RD)
    rd = check_positive("near_radius", near_radius, unit="wavelengths") * lam
    if ptp >= MAX_PTP_OVER_RD * rd:
        raise ValueError(
            f"near_radius={fmt(near_radius)} λ is too small for this surface: its "
            f"peak-to-valley height {ptp / lam:.3g} λ must be < {MAX_PTP_OVER_RD:g}·r_d for the "
            f"SMCG Taylor series to converge; use near_radius ≥ "
            f"{ptp / MAX_PTP_OVER_RD / lam:.3g} or accel='dense'"
        )
    return rd


def _check_order(taylor_order) -> None:
    if not isinstance(taylor_order, int | np.integer) or not 0 <= taylor_order <= 8:
        raise ValueError(f"taylor_order must be an int in 0 … 8, got {taylor_order!r}")


def smcg_operator(patch, k: float, *, near_radius: float, taylor_order: int = 3,
                  dtype=np.complex64) -> SmcgOperator:  # fmt: skip
    """The SMCG product for ``patch`` at wavenumber ``k`` [rad/m]: strong pairs within
    ``near_radius`` [m] (at least the near-correction stencil, ``√2·(WIDTH+1)`` cells),
    Taylor order ``taylor_order`` (0 … 8) for the rest; sparse entries stored in ``dtype``."""
    _check_order(taylor_order)
    least = math.sqrt(2.0) * (WIDTH + 1) * max(patch.dx, patch.dy)
    if not near_radius >= least:
        raise ValueError(
            f"near_radius={near_radius:.4g} m must be ≥ {least:.4g} m (√2·{WIDTH + 1} cells: "
            "the near-cell correction stencil must lie inside the strong part)"
        )
    return SmcgOperator(patch, k, float(near_radius), int(taylor_order), dtype)
