"""Fast far-field sums over a current on the regular ``(x, y)`` grid of a rough patch:
``S_t(k) = Σ_n s_tn e^{−i(k_x x_n + k_y y_n + k_z z_n)}`` for many real wavevectors ``k`` in
``O(Q (N log N + D w²))`` instead of the direct ``O(N D)`` (:mod:`.farfield` keeps the direct
sum as the reference).

Two expansions, each with an error bound relative to ``Σ_n |s_tn|``:

1. **Height, a Taylor series** about the mid height ``z_c`` and the mid vertical wavenumber
   ``k_c`` of the requested directions (``ζ = z − z_c``, ``δ = k_z − k_c``)::

       e^{−i k_z ζ} = e^{−i k_c ζ} Σ_{q<Q} (−i δ ζ)^q / q!  + E_Q,   |E_Q| ≤ x^Q / Q!,

   with ``x = max|δ| max|ζ|`` (Lagrange remainder of ``e^{−iθ}``, real ``θ``). ``Q`` is the
   smallest order with ``x^Q/Q! ≤ tol/2``; each term is a planar sum of the sources
   ``s e^{−i k_c ζ} ζ^q / q!`` weighted by ``(−i δ)^q`` at the target.

2. **Planar sums, a type-2 non-uniform FFT** by Gaussian gridding (Dutt & Rokhlin, SIAM J.
   Sci. Comput. 14, 1993; Greengard & Lee, SIAM Rev. 46, 2004, eqs. 3–9): with mode indices
   ``j`` (``|j| ≤ n/2``) and ``ω = k_x Δx`` per axis, ``f(ω) = Σ_j c_j e^{−ijω}`` is
   ``(1/M) Σ_m g_τ(ω − 2πm/M) h_m``, ``h = FFT_M(c_j √(π/τ) e^{j²τ})`` on ``M = R n``
   (``R ≥ 2``) points, ``g_τ(ω) = e^{−ω²/4τ}`` kept on the ``2 w`` nearest nodes, and
   ``τ = π w / (n² R (R − ½))`` (their eq. 9). Truncation and aliasing errors are each
   ``≈ e^{−π w (1 − 1/(2R−1))}`` per axis (``e^{−3πw/4}`` at ``R = 2``), the deconvolution
   grows them by at most ``e^{πw/12}`` (``R = 2``): ``w`` is the smallest width with
   ``4 e^{−3πw/4 + πw/12} ≤ tol/2`` (``w = 9`` for ``tol = 1e-7``). The interpolation is one
   sparse ``(D, M_y M_x)`` matrix with ``(2w)²`` entries per target, applied to all sources at
   once.

Measured against the direct sum (tests/test_mom3d_farfield.py): ≤ 1e-8 of ``max|F|`` at the
default ``tol = 1e-7``; for the dielectric far field (:func:`.farfield.amplitudes_em`, both
half-spaces) ≤ 3e-10 of the largest amplitude on a solved 3λ patch.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import fft as sfft
from scipy import sparse

__all__ = ["Grid", "grid_of", "grid_sums", "taylor_terms", "gridding_width"]

#: Oversampling ratio of the gridding FFT (Greengard & Lee's R).
OVERSAMPLE = 2.0
#: Largest Taylor order accepted (beyond it the direct sum is cheaper; ``x ≈ 30``).
MAX_TERMS = 80


class Grid:
    """A regular ``(ny, nx)`` grid: ``x = x0 + i_x dx``, ``y = y0 + i_y dy`` [m], points in
    row-major order (``x`` fastest, as :func:`.operator.make_patch` lays them out)."""

    __slots__ = ("x0", "y0", "dx", "dy", "ny", "nx")

    def __init__(self, x0: float, y0: float, dx: float, dy: float, ny: int, nx: int):
        self.x0, self.y0, self.dx, self.dy, self.ny, self.nx = x0, y0, dx, dy, ny, nx


def grid_of(points: np.ndarray, rtol: float = 1e-9) -> Grid | None:
    """The regular grid the ``(N, 3)`` points lie on (``x`` fastest), or ``None`` if they do
    not (positions tested to ``rtol`` of the patch size)."""
    pts = np.asarray(points, dtype=float)
    n = pts.shape[0]
    if pts.ndim != 2 or pts.shape[1] != 3 or n < 4:
        return None
    x, y = pts[:, 0], pts[:, 1]
    same_row = np.flatnonzero(np.abs(y - y[0]) > 0)
    nx = int(same_row[0]) if same_row.size else n
    if nx < 2 or n % nx:
        return None
    ny = n // nx
    dx = (x[nx - 1] - x[0]) / (nx - 1)
    dy = (y[n - 1] - y[0]) / (ny - 1) if ny > 1 else 0.0
    if dx <= 0 or dy <= 0:
        return None
    xs = x[0] + dx * np.arange(nx)
    ys = y[0] + dy * np.arange(ny)
    scale = max(abs(dx) * nx, abs(dy) * ny)
    ok = np.allclose(x.reshape(ny, nx), xs[None, :], rtol=0, atol=rtol * scale) and np.allclose(
        y.reshape(ny, nx), ys[:, None], rtol=0, atol=rtol * scale
    )
    return Grid(float(x[0]), float(y[0]), float(dx), float(dy), ny, nx) if ok else None


def taylor_terms(x: float, tol: float) -> int:
    """Smallest ``Q ≥ 1`` with ``x^Q / Q! ≤ tol`` (remainder of ``e^{−iθ}``, ``|θ| ≤ x``)."""
    q, term = 1, x
    while term > tol:
        q += 1
        term *= x / q
        if q > MAX_TERMS:
            raise ValueError(
                f"the far-field Taylor series needs more than {MAX_TERMS} terms "
                f"(max|δ k_z| max|ζ| = {x:.3g}); use the direct sum"
            )
    return q


def gridding_width(tol: float) -> int:
    """Half-width ``w`` (nodes each side) of the Gaussian at ``R = 2`` for error ``≤ tol``."""
    w = 2
    while 4.0 * math.exp(-3.0 * math.pi * w / 4.0 + math.pi * w / 12.0) > tol:
        w += 1
    return w


def _axis(n: int, omega: np.ndarray, w: int):
    """One axis of the gridding: the FFT length ``M``, the deconvolution ``(n,)`` for mode
    ``j = i − n//2``, and the ``(D, 2w)`` node indices and Gaussian weights at ``omega``."""
    m = sfft.next_fast_len(int(math.ceil(OVERSAMPLE * max(n, 2))))
    r = m / max(n, 2)
    tau = math.pi * w / (max(n, 2) ** 2 * r * (r - 0.5))
    j = np.arange(n) - n // 2
    deconv = math.sqrt(math.pi / tau) * np.exp(j.astype(float) ** 2 * tau)
    step = 2.0 * math.pi / m
    w0 = np.mod(omega, 2.0 * math.pi)
    m0 = np.floor(w0 / step).astype(np.int64)
    nodes = m0[:, None] + np.arange(-w + 1, w + 1)[None, :]  # (D, 2w)
    weights = np.exp(-((w0[:, None] - nodes * step) ** 2) / (4.0 * tau)) / m
    return m, deconv, np.mod(nodes, m), weights


def grid_sums(
    src: np.ndarray, z: np.ndarray, grid: Grid, kvec: np.ndarray, tol: float = 1e-7
) -> np.ndarray:
    """``S[t, d] = Σ_n src[t, n] e^{−i k_d·r_n}`` for sources ``src`` ``(T, N)`` on ``grid``
    with heights ``z`` ``(N,)`` [m] and real wavevectors ``kvec`` ``(D, 3)`` [rad/m]; error
    ``≤ tol Σ_n |src[t, n]|`` (module docstring). Returns ``(T, D)`` complex."""
    src = np.asarray(src)
    kvec = np.asarray(kvec, dtype=float)
    t, n = src.shape
    ny, nx = grid.ny, grid.nx
    if n != ny * nx:
        raise ValueError(f"src has {n} points, the grid {ny}×{nx}")
    d = kvec.shape[0]
    if d == 0:
        return np.zeros((t, 0), dtype=complex)
    kx, ky, kz = kvec[:, 0], kvec[:, 1], kvec[:, 2]
    zc = 0.5 * (float(np.max(z)) + float(np.min(z)))
    zeta = np.asarray(z, dtype=float) - zc
    zmax = max(float(np.max(np.abs(zeta))), 1e-300)
    kc = 0.5 * (float(kz.max()) + float(kz.min()))
    delta = kz - kc
    q_terms = taylor_terms(float(np.max(np.abs(delta))) * zmax, 0.5 * tol)
    w = gridding_width(0.5 * tol)
    mx, decx, ix, wx = _axis(nx, kx * grid.dx, w)
    my, decy, iy, wy = _axis(ny, ky * grid.dy, w)
    # the sparse interpolation matrix (D, my·mx): (2w)² entries per target, separable weights
    cols = (iy[:, :, None] * mx + ix[:, None, :]).reshape(d, -1)
    vals = (wy[:, :, None] * wx[:, None, :]).reshape(d, -1)
    rows = np.repeat(np.arange(d), cols.shape[1])
    interp = sparse.csr_matrix((vals.ravel(), (rows, cols.ravel())), shape=(d, my * mx))
    # sources: deconvolved, on the oversampled grid at index j mod M (j = i − n//2)
    pos_y = np.mod(np.arange(ny) - ny // 2, my)
    pos_x = np.mod(np.arange(nx) - nx // 2, mx)
    base = (src * np.exp(-1j * kc * zeta)[None, :]).reshape(t, ny, nx)
    base = base * (decy[:, None] * decx[None, :])[None]
    zn = (zeta / zmax).reshape(ny, nx)
    out = np.zeros((t, d), dtype=complex)
    term = base
    tgt = np.ones(d, dtype=complex)
    for q in range(q_terms):  # Taylor terms in height (not a loop over directions)
        if q:
            term = term * zn[None] / q
            tgt = tgt * (-1j * delta * zmax)
        pad = np.zeros((t, my, mx), dtype=complex)
        pad[:, pos_y[:, None], pos_x[None, :]] = term
        h = sfft.fft2(pad, workers=-1).reshape(t, my * mx)
        out += (interp @ h.T).T * tgt[None, :]
    # phases: the mode shift j = i − n//2, the grid origin and the mid height
    shift_x = grid.x0 + (nx // 2) * grid.dx
    shift_y = grid.y0 + (ny // 2) * grid.dy
    return out * np.exp(-1j * (kx * shift_x + ky * shift_y + kz * zc))[None, :]
