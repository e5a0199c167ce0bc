"""The sparse-matrix/canonical-grid (SMCG) product of Müller's dielectric equations
(:mod:`.dielectric`): both media's kernels, ``O(N log N)`` time and ``O(N r_d²)`` memory
instead of the dense ``16 N²``.

The scheme is the PEC one of :mod:`.smcg` (Tsang, Chan, Pak & Sangani, IEEE Trans. Antennas
Propag. 43, 1995; Pak, Tsang & Johnson, J. Opt. Soc. Am. A 14, 1997; for dielectric surfaces
Tsang, Kong, Ding & Ao, *Scattering of Electromagnetic Waves* vol. II, 2001, ch. 11, where the
same strong/weak split is applied to both media's Green's functions). Strong pairs
(``ρ < r_d``) are the exact entries of the dense assembly (:func:`.dielectric.pair_blocks`,
the self cell, the near-cell correction and the unit diagonal) in a CSR matrix. For weak pairs
(``ρ ≥ r_d``) every radial factor of the four kernels is a sum over the two media of
``f_i(R) = e^{i k_i R}/(4π) Σ_j c_j R^{−j}``::

    a_H = Σ s_i F_i,   a_E = (2/(ε₁+ε₂)) Σ s_i ε_i F_i,   α = Σ s_i (ε_i G_i + F_i/k₀²),
    β = Σ s_i (G_i'' − F_i)/(k₀² R²),     G_i = e^{ik_iR}/(4πR),  F_i = G_i'/R,

``s = (+1, −1)`` for air and the lower medium (``k₂ = √ε₂ k₀``, ``Im k₂ ≥ 0``). Each is
expanded in ``Z²`` about the flat surface, ``f(√(ρ² + Z²)) = Σ_p (L^p f)(ρ) Z^{2p}/(2^p p!)``,
``L = R⁻¹ d/dR`` (exact on the ``e^{ikR} R^{−j}`` terms: ``L`` maps them to
``ik R^{−j−1} − j R^{−j−2}``), so the two media share one canonical-grid kernel per term and
medium 2 costs no extra FFT. With the sources ``u, w`` lifted to 3-vectors
``U = (u_x, u_y, f_x u_x + f_y u_y)`` the weak part of each row is (``X, Y, Z = r_m − r_n``,
``S^k_W(v)_m = Σ_n k_mn W_mn v_n``)::

    magnetic:  −[S^a_X(U_z) − S^a_Z(u_x) + f_ym C],  −[S^a_Y(U_z) − S^a_Z(u_y) − f_xm C]
               − i k₀ P_m V(W),     C = S^a_Y(u_x) − S^a_X(u_y),
    electric:  the same with a_E and w, + i k₀ (2/(ε₁+ε₂)) P_m V(U),
    V(X) = S^α_1(X) + S^β_R(R·X),   P_m V = (−V_y − f_ym V_z, V_x + f_xm V_z),

every ``S`` a sum of flat convolutions of ``k_p(ρ) X^a Y^b`` with ``(−z_n)^l v_n``, weighted
by ``z_m^{e−l}`` (binomial expansion of ``Z^e``, ``e ≤ 2P + 2``): ``6(2P + 3)`` forward and
``6(2P + 3)`` inverse zero-padded FFTs per product (the twelve sums are folded into the six
combinations the rows need before the inverse transforms).

Taylor order: the remainder is the PEC one of :mod:`.smcg` with ``ξ_i = |k_i| Z²/(2ρ)``, so
medium 2's part needs the order of a wavenumber ``|√ε₂|`` times larger; its loss only helps
(the kernel falls as ``e^{−Im k₂ ρ}``, 1e-3 at 8.8λ for ``ε = 4 + 0.5i``, which is why it
cannot simply be dropped beyond ``r_d``). Measured relative error of the whole product
against the dense matrix for a random vector (validation/mom3d/dielectric_smcg.md, 1.5λ
patches, Gaussian kℓ = 3), Taylor order 0…5, with ``ξ₂`` at the peak-to-valley height:

=========  ====  =====  ====  =======  =======  =======  =======  =======  =======
ε          kσ    r_d    ξ₂    0        1        2        3        4        5
=========  ====  =====  ====  =======  =======  =======  =======  =======  =======
4 + 0.5i   0.3   0.5λ   0.50  3.7e-3   2.7e-4   2.0e-5   1.3e-6   7.7e-8   4.3e-9
4 + 0.5i   0.3   1λ     0.25  1.0e-3   5.3e-5   2.6e-6   1.2e-7   4.8e-9   1.7e-10
4 + 0.5i   0.5   0.5λ   1.38  1.0e-2   2.1e-3   4.2e-4   7.6e-5   1.3e-5   2.0e-6
15 + 2i    0.3   0.5λ   1.13  8.7e-3   2.1e-3   4.1e-4   6.9e-5   1.0e-5   1.3e-6
15 + 2i    0.3   1λ     0.57  8.5e-4   9.1e-5   1.1e-5   1.3e-6   1.3e-7   1.1e-8
=========  ====  =====  ====  =======  =======  =======  =======  =======  =======

The default (``r_d = 0.5λ``, order 3) is within 1e-4 for kσ ≤ 0.5 up to ε = 15 + 2i; the
solved amplitudes agree with the dense solve's to the GMRES tolerance (≤ 3e-6 of the largest,
σ⁰ within 2e-3 dB in the lobes, 2λ patches, ε = 4 + 0.5i and 3, kσ 0.15/0.3).

Cost per product: the sparse part ``16 N π (r_d/Δ)²`` nonzeros (≈ 3e7 for 6λ × 6λ at
ε = 4 + 0.5i, 16 points/λ₀), the FFT part ``18(2P + 3)`` FFTs of ``≈ 4N`` points.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import fft as sfft
from scipy import sparse

from emscatter.solvers.mom3d.dielectric import media, pair_blocks, self_blocks
from emscatter.solvers.mom3d.near import WIDTH, near_correction
from emscatter.solvers.mom3d.smcg import (
    ROW_BLOCK,
    NearFarProduct,
    _check_order,
    _offsets,
    far_grid,
)

__all__ = ["DielectricSmcgOperator", "dielectric_smcg_operator", "radial_series"]

# sources: 0..2 = U (x, y, z), 3..5 = W; outputs (see ``_TERMS``)
_OUT = ("hx", "hy", "hc", "ex", "ey", "ec", "vwx", "vwy", "vwz", "vux", "vuy", "vuz")
# kernel factors: (radial function, power of X, power of Y)
_KERNELS = (("aH", 1, 0), ("aH", 0, 1), ("aH", 0, 0), ("aE", 1, 0), ("aE", 0, 1), ("aE", 0, 0),
            ("al", 0, 0), ("be", 2, 0), ("be", 1, 1), ("be", 0, 2), ("be", 1, 0),
            ("be", 0, 1), ("be", 0, 0))  # fmt: skip


def _terms():
    """``(output, kernel, extra power of Z, source, coefficient)`` of the weak part."""
    names = (
        "aHX",
        "aHY",
        "aH1",
        "aEX",
        "aEY",
        "aE1",
        "al1",
        "beXX",
        "beXY",
        "beYY",
        "beX",
        "beY",
        "be1",
    )  # fmt: skip  (same order as _KERNELS)
    kx = {name: q for q, name in enumerate(names)}
    o = {name: q for q, name in enumerate(_OUT)}
    t = []
    for f, off, (ox, oy, oc) in (("aH", 0, ("hx", "hy", "hc")), ("aE", 3, ("ex", "ey", "ec"))):
        fX, fY, f1 = kx[f + "X"], kx[f + "Y"], kx[f + "1"]
        t += [(o[ox], fX, 0, off + 2, 1.0), (o[ox], f1, 1, off + 0, -1.0),
              (o[oy], fY, 0, off + 2, 1.0), (o[oy], f1, 1, off + 1, -1.0),
              (o[oc], fY, 0, off + 0, 1.0), (o[oc], fX, 0, off + 1, -1.0)]  # fmt: skip
    for pre, off in (("vw", 3), ("vu", 0)):
        vx, vy, vz = o[pre + "x"], o[pre + "y"], o[pre + "z"]
        t += [(vx, kx["al1"], 0, off, 1.0), (vx, kx["beXX"], 0, off, 1.0),
              (vx, kx["beXY"], 0, off + 1, 1.0), (vx, kx["beX"], 1, off + 2, 1.0),
              (vy, kx["al1"], 0, off + 1, 1.0), (vy, kx["beXY"], 0, off, 1.0),
              (vy, kx["beYY"], 0, off + 1, 1.0), (vy, kx["beY"], 1, off + 2, 1.0),
              (vz, kx["al1"], 0, off + 2, 1.0), (vz, kx["beX"], 1, off, 1.0),
              (vz, kx["beY"], 1, off + 1, 1.0), (vz, kx["be1"], 2, off + 2, 1.0)]  # fmt: skip
    return t


_TERMS = _terms()


def radial_series(k: complex, coef: dict, rho: np.ndarray, order: int) -> np.ndarray:
    """Coefficients of ``Z^{2p}``, ``p = 0..order``, in ``f(√(ρ² + Z²))`` for
    ``f(R) = e^{ikR}/(4π) Σ_j c_j R^{−j}`` (``coef = {j: c_j}``, ``k`` [rad/m], complex for a
    lossy medium): ``(L^p f)(ρ)/(2^p p!)``, ``(order + 1, *ρ.shape)`` complex."""
    rho = np.asarray(rho, dtype=float)
    out = np.empty((order + 1, *rho.shape), dtype=complex)
    phase = np.exp(1j * k * rho) / (4.0 * math.pi)
    inv = 1.0 / rho
    cur = dict(coef)
    for p in range(order + 1):
        out[p] = phase * sum(c * inv**j for j, c in cur.items()) / (2.0**p * math.factorial(p))
        new: dict[int, complex] = {}
        for j, c in cur.items():  # L(e^{ikR} R^{-j}) = e^{ikR}(ik R^{-j-1} − j R^{-j-2})
            new[j + 1] = new.get(j + 1, 0) + 1j * k * c
            new[j + 2] = new.get(j + 2, 0) - j * c
        cur = new
    return out


def _radial(k0: float, eps2: complex, rho: np.ndarray, order: int) -> dict:
    """The four radial kernels' Taylor coefficients summed over both media (docstring)."""
    e1, e2, k1, k2, scale_e = media(k0, eps2)
    out = {}
    for s, e, k in ((1.0, e1, k1), (-1.0, e2, k2)):
        f = {2: 1j * k, 3: -1.0}  # F = G'/R = (ikR − 1) e^{ikR}/(4πR³)
        g = {1: 1.0}
        d = {3: 2.0, 2: -2j * k, 1: -(k**2)}  # G''
        al = {j: e * g.get(j, 0) + f.get(j, 0) / k0**2 for j in (1, 2, 3)}
        be = {j + 2: (d.get(j, 0) - f.get(j, 0)) / k0**2 for j in (1, 2, 3)}
        for name, cf, sc in (("aH", f, s), ("aE", f, s * e * scale_e), ("al", al, s),
                             ("be", be, s)):  # fmt: skip
            val = sc * radial_series(k, cf, rho, order)
            out[name] = out[name] + val if name in out else val
    return out


def _strong(patch, k0: float, eps2: complex, radius: float, dtype) -> sparse.csr_matrix:
    """The exact Müller entries of :func:`.dielectric.assemble_dielectric` (self cell,
    near-cell correction and unit diagonal included) for the pairs ``ρ < radius``, as a
    ``(4N, 4N)`` CSR matrix (16 blocks per pair)."""
    n = patch.n
    ny, nx = patch.shape
    z, fx, fy = patch.z, patch.fx, patch.fy
    area = patch.dx * patch.dy
    e1, e2, _, _, scale_e = media(k0, eps2)
    oi, oj = _offsets(patch.dx, patch.dy, radius, nx, ny)
    shift = oi + oj * nx
    iy, ix = np.divmod(np.arange(n), nx)
    where = {(int(i), int(j)): q for q, (i, j) in enumerate(zip(oi, oj, strict=True))}
    self_q = where[(0, 0)]
    corr = [(where[(i, j)], c) for i, j, c in near_correction(patch, z.reshape(ny, nx))]
    selfb = self_blocks(patch, k0, eps2)
    factor = (e1 - e2) * scale_e
    cx, cy = ix[:, None] + oi[None, :], iy[:, None] + oj[None, :]
    counts = ((cx >= 0) & (cx < nx) & (cy >= 0) & (cy < ny)).sum(axis=1)
    del cx, cy
    indptr = np.zeros(4 * n + 1, dtype=np.int64)
    indptr[1:] = np.cumsum(np.tile(4 * counts, 4))
    nnz = int(indptr[-1])
    itype = np.int32 if nnz < 2**31 - 1 and 4 * n < 2**31 else np.int64
    data = np.empty(nnz, dtype=dtype)
    indices = np.empty(nnz, dtype=itype)
    X, Y = -oi * patch.dx, -oj * patch.dy  # x_m − x_n per offset (exact on the grid)
    mask = np.zeros(oi.size, dtype=bool)
    mask[self_q] = True
    for r0 in range(0, n, ROW_BLOCK):
        r = np.arange(r0, min(n, r0 + ROW_BLOCK))
        cx, cy = ix[r, None] + oi[None, :], iy[r, None] + oj[None, :]
        ok = (cx >= 0) & (cx < nx) & (cy >= 0) & (cy < ny)
        col = np.where(ok, r[:, None] + shift[None, :], r[:, None])
        Z = z[r, None] - z[col]
        blocks = pair_blocks(X[None, :], Y[None, :], Z, fx[r, None], fy[r, None], fx[col],
                             fy[col], mask[None, :], k0, eps2, area)  # fmt: skip
        for key, val in selfb.items():
            blocks[key][:, self_q] += val[r]
        for b in range(4):
            blocks[b, b][:, self_q] += 1.0
        for q, c in corr:
            for s in range(2):
                for t in range(2):
                    blocks[2 + s, 2 + t][:, q] += factor * c[s, t, r]
        ok4 = np.concatenate([ok] * 4, axis=1)
        cols4 = np.concatenate([col + b * n for b in range(4)], axis=1)[ok4]
        for bi in range(4):
            lo, hi = indptr[bi * n + r[0]], indptr[bi * n + r[-1] + 1]
            data[lo:hi] = np.concatenate([blocks[bi, bj] for bj in range(4)], axis=1)[ok4]
            indices[lo:hi] = cols4
    return sparse.csr_matrix((data, indices, indptr), shape=(4 * n, 4 * n))


class DielectricSmcgOperator(NearFarProduct):
    """The Müller matrix of a :class:`~.operator.Patch` as a product ``op @ v`` (module
    docstring): ``shape`` ``(4N, 4N)``, ``dtype`` complex128 (the iteration's precision; the
    strong entries are stored in ``strong.dtype``), ``nbytes``."""

    def __init__(self, patch, k0: float, eps2: complex, near_radius: float, taylor_order: int,
                 dtype, strong=None):  # fmt: skip
        self.patch, self.k0, self.eps2 = patch, float(k0), complex(eps2)
        self.order, self.near_radius = int(taylor_order), float(near_radius)
        self.shape = (4 * patch.n, 4 * patch.n)
        self.dtype = np.dtype(np.complex128)
        if strong is None:
            strong = _strong(patch, k0, eps2, near_radius, dtype)
        self.strong = strong
        self.pad, dd_x, dd_y, rho, far = far_grid(patch, near_radius)
        py, px = self.pad
        radial = _radial(k0, eps2, rho[far], self.order)
        area = patch.dx * patch.dy
        spec = np.zeros((len(_KERNELS), self.order + 1, py, px), dtype=complex)
        for q, (name, ax, ay) in enumerate(_KERNELS):
            spec[q][:, far] = area * radial[name] * (dd_x[far] ** ax * dd_y[far] ** ay)
        self.spec = sfft.fft2(spec, axes=(-2, -1), workers=-1, overwrite_x=True)
        self.zc = patch.z - patch.z.mean()
        # the 12 sums of _TERMS folded into 6 (their row combinations, docstring):
        # H' = (h_x − ik₀V_y(W), h_y + ik₀V_x(W), h_c − ik₀V_z(W)), E' likewise with +c_e V(U)
        ik, ce = 1j * self.k0, 1j * self.k0 * media(self.k0, self.eps2)[4]
        fold = {o: (o, 1.0) for o in range(6)}
        fold.update({6: (1, ik), 7: (0, -ik), 8: (2, -ik), 9: (4, -ce), 10: (3, ce), 11: (5, ce)})
        self.terms = [(fold[o][0], kq, e0, s, c * fold[o][1]) for o, kq, e0, s, c in _TERMS]

    def with_order(self, taylor_order: int) -> DielectricSmcgOperator:
        """The same strong matrix with another Taylor order for the weak pairs (cheap)."""
        _check_order(taylor_order)
        return DielectricSmcgOperator(self.patch, self.k0, self.eps2, self.near_radius,
                                      int(taylor_order), self.strong.dtype,
                                      strong=self.strong)  # fmt: skip

    @property
    def nbytes(self) -> int:
        s = self.strong
        return int(s.data.nbytes + s.indices.nbytes + s.indptr.nbytes + self.spec.nbytes)

    def far(self, v: np.ndarray) -> np.ndarray:
        """The weak-pair (``ρ ≥ r_d``) part of the product, by the Taylor series and FFTs."""
        pch, p = self.patch, self.order
        n = pch.n
        ny, nx = pch.shape
        py, px = self.pad
        fx, fy = pch.fx, pch.fy
        ux, uy, wx, wy = v[:n], v[n : 2 * n], v[2 * n : 3 * n], v[3 * n :]
        srcs = (ux, uy, fx * ux + fy * uy, wx, wy, fx * wx + fy * wy)
        npow = 2 * p + 3
        mz = -self.zc
        pw = np.stack([mz**q for q in range(npow)])  # (−z_n)^l
        src = np.zeros((6, npow, py, px), dtype=complex)
        for s, vv in enumerate(srcs):
            src[s, :, :ny, :nx] = (pw * vv).reshape(npow, ny, nx)
        fs = sfft.fft2(src, axes=(-2, -1), workers=-1, overwrite_x=True)
        acc = np.zeros((6, npow, py, px), dtype=complex)  # per power of z_m
        for o, kq, e0, s, c in self.terms:
            for q in range(p + 1):
                e = 2 * q + e0
                kern = self.spec[kq, q]
                for lo in range(e + 1):  # Z^e = Σ C(e, l) z_m^{e−l} (−z_n)^l
                    acc[o, e - lo] += (c * math.comb(e, lo)) * (kern * fs[s, lo])
        back = sfft.ifft2(acc, axes=(-2, -1), workers=-1, overwrite_x=True)[:, :, :ny, :nx]
        zp = np.stack([self.zc**q for q in range(npow)])
        hx, hy, hc, ex, ey, ec = np.einsum("ojn,jn->on", back.reshape(6, npow, n), zp)
        return np.concatenate([-(hx + fy * hc), -(hy - fx * hc), -(ex + fy * ec), -(ey - fx * ec)])


def dielectric_smcg_operator(patch, k0: float, eps2, *, near_radius: float,
                             taylor_order: int = 3,
                             dtype=np.complex64) -> DielectricSmcgOperator:  # fmt: skip
    """The SMCG product of Müller's equations for ``patch`` at free-space wavenumber ``k0``
    [rad/m] over ``eps2``: strong pairs within ``near_radius`` [m] (at least the near-cell
    stencil, ``√2·(WIDTH+1)`` cells), Taylor order ``taylor_order`` (0 … 8) in ``Z²`` for the
    rest; strong entries stored in ``dtype``."""
    _check_order(taylor_order)
    least = math.sqrt(2.0) * (WIDTH + 1) * max(patch.dx, patch.dy)
    if not near_radius >= least:
        raise ValueError(
            f"near_radius={near_radius:.4g} m must be ≥ {least:.4g} m (√2·{WIDTH + 1} cells: "
            "the near-cell correction stencil must lie inside the strong part)"
        )
    return DielectricSmcgOperator(patch, k0, eps2, near_radius, taylor_order, dtype)
