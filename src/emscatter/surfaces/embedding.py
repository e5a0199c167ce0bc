"""How a surface is synthesized: the spectral plans (eigenvalues and amplitudes) of circulant
embedding for stationary correlations, Davies–Harte for a 1-D fBm, Stein (2002) for a 2-D fBm and
the periodic FFT method. :func:`emscatter.surfaces.generate.generate_surface` picks a plan and
draws the noise; the references are in that module's docstring."""

from __future__ import annotations

import math
import os
import warnings
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np
import scipy.fft as sfft
from scipy import special

from ..spectra import FractionalBrownian, GaussianCorrelation, Roughness

_EIG_TOL = 1e-10  # relative: eigenvalues ≥ −_EIG_TOL·max count as round-off and are clipped
_MAX_EMBED_POINTS = 2**26
_MAX_PAD_FACTOR = 8
_STEIN_R = (1.0, 1.1, 1.2, 1.3, 1.5, 2.0)
_THREADED_NOISE_MIN = 2**20  # float pairs; below this the noise is drawn in one block
_NOISE_BLOCKS = 8


def _rows_of(amp, m0: int, m1: int) -> np.ndarray:
    """Amplitude rows for |ky| indices ``m0..m1−1``: a stored quarter array or a callable."""
    if callable(amp):
        return amp(m0, m1)
    return amp[m0:m1]


def _synthesize(
    amp, full: tuple[int, ...], rng: np.random.Generator, keep_rows: int | None = None
) -> np.ndarray:
    """Real Gaussian field on the periodic grid ``full``: ``h = irfftn(a · ζ)``.

    ``ζ``: complex noise with independent N(0, 1) real and imaginary parts, drawn directly
    in the half spectrum (rows ky, columns kx = 0..nx//2). ``a``: mode amplitudes, even in
    ky, given for ``|ky| = 0..ny//2`` only, as an array (1-D: the whole half spectrum) or a
    callable ``rows(m0, m1) → (m1 − m0, nx//2 + 1)`` array for ``|ky|`` indices ``m0..m1−1``,
    edge columns already corrected
    (:func:`_edge_factor`). ``keep_rows``: only the first rows of the field are returned
    (2-D), computed with a pruned inverse transform. Large grids are filled in
    ``_NOISE_BLOCKS`` row blocks, each from its own child generator, noise and filter fused,
    in threads (numpy releases the GIL);
    the block split does not depend on the number of cores, so results are reproducible.
    """
    rows = full[0] if len(full) == 2 else 1
    cols = full[-1] // 2 + 1
    buf = np.empty((rows, cols, 2))
    z = buf.view(np.complex128)[..., 0]
    if len(full) == 1:
        rng.standard_normal(out=buf.reshape(-1))
        z = z[0]
        z *= amp
        return sfft.irfft(z, n=full[0], overwrite_x=True, workers=-1)
    ny = rows
    half = ny // 2 + 1  # |ky| indices 0..ny//2 are stored; row ny − m holds −m
    last_mirrored = (ny + 1) // 2  # m < ny/2 has a distinct negative row

    def fill(gen, m0, m1):
        """Noise and filter for |ky| ∈ [m0, m1): rows m0..m1−1 and their mirrors."""
        gen.standard_normal(out=buf[m0:m1].reshape(-1))
        rows_amp = _rows_of(amp, m0, m1)
        z[m0:m1] *= rows_amp
        a2, b2 = max(m0, 1), min(m1, last_mirrored)
        if b2 > a2:
            lo, hi = ny - b2 + 1, ny - a2 + 1
            gen.standard_normal(out=buf[lo:hi].reshape(-1))
            z[lo:hi] *= rows_amp[a2 - m0 : b2 - m0][::-1]

    if buf.size < _THREADED_NOISE_MIN or half < _NOISE_BLOCKS:
        fill(rng, 0, half)
    else:
        seeds = np.random.SeedSequence(rng.integers(0, 2**63, size=4)).spawn(_NOISE_BLOCKS)
        edges = np.linspace(0, half, _NOISE_BLOCKS + 1).astype(int)
        jobs = [
            (np.random.default_rng(sq), int(edges[i]), int(edges[i + 1]))
            for i, sq in enumerate(seeds)
        ]
        workers = max(1, min(_NOISE_BLOCKS, os.cpu_count() or 1))
        if workers == 1:
            for job in jobs:
                fill(*job)
        else:
            with ThreadPoolExecutor(max_workers=workers) as ex:
                list(ex.map(lambda j: fill(*j), jobs))
    if keep_rows is None or keep_rows >= ny:
        return sfft.irfft2(z, s=full, overwrite_x=True, workers=-1)
    # pruned inverse: the ky transform on every column, then the kx (c2r) transform only on
    # the rows kept — the same numbers as irfft2(...)[:keep_rows], fewer operations.
    t = sfft.ifft(z, axis=0, overwrite_x=True, workers=-1)
    return sfft.irfft(t[:keep_rows], n=full[1], axis=1, workers=-1)


# --------------------------------------------------------------------------- kernels
def _edge_factor(amp: np.ndarray, n_last: int) -> None:
    """In place: ×√2 on the kx = 0 and Nyquist columns, whose imaginary parts ``irfft``
    discards, so that their real part carries the full variance."""
    amp[..., 0] *= math.sqrt(2.0)
    if n_last % 2 == 0:
        amp[..., -1] *= math.sqrt(2.0)


def _amp_from_eigenvalues(lam_q: np.ndarray, full: tuple[int, ...]) -> np.ndarray:
    """Mode amplitudes ``√(N λ / 2)`` for noise with unit-variance parts (in place)."""
    n_tot = math.prod(full)
    np.maximum(lam_q, 0.0, out=lam_q)
    lam_q *= n_tot / 2.0
    np.sqrt(lam_q, out=lam_q)
    _edge_factor(lam_q, full[-1])
    return lam_q


def _even_len(n: int) -> int:
    """Smallest even 5-smooth length ≥ n."""
    m = sfft.next_fast_len(int(n), real=True)
    while m % 2:
        m = sfft.next_fast_len(m + 1, real=True)
    return m


def _lag_axes(full: tuple[int, ...], spacing: tuple[float, ...]) -> list[np.ndarray]:
    """Lags 0..M/2 [m] per axis of the quarter of an even periodic grid."""
    return [np.arange(m // 2 + 1) * d for m, d in zip(full, spacing, strict=True)]


def _check_eigs(lam: np.ndarray) -> tuple[float, float]:
    """(min/max ratio, negative mass Σ|λ<0| / Σ|λ|) of the quarter DCT eigenvalues."""
    top = float(np.max(lam))
    low = float(np.min(lam))
    ratio = low / top if top > 0 else -np.inf
    neg = float(-np.sum(lam[lam < 0]))
    return ratio, neg / float(np.sum(np.abs(lam)))


# --------------------------------------------------------------------------- plans
@dataclass
class _Plan:
    method: str
    full: tuple[int, ...]
    amp: np.ndarray
    shape: tuple[int, ...]
    info: dict
    post: object = None  # callable(field, rng) -> heights, or None (crop only)

    def realize(self, rng: np.random.Generator) -> np.ndarray:
        f = _synthesize(self.amp, self.full, rng, self.shape[0] if len(self.shape) == 2 else None)
        if f.shape != self.shape:
            f = np.ascontiguousarray(f[tuple(slice(0, n) for n in self.shape)])
        if self.post is not None:
            f = self.post(f, rng)
        return f


def _stationary_eigs(rough: Roughness, full, spacing) -> np.ndarray:
    """Eigenvalues (quarter, rows ky ≥ 0, cols rfft) of the embedded covariance σ²ρ."""
    lags = _lag_axes(full, spacing)
    s2 = rough.sigma**2
    if isinstance(rough, GaussianCorrelation):
        # separable: exp(−x²/ℓx² − y²/ℓy²) → outer product of 1-D DCT-I transforms
        ells = (rough.length,) if len(full) == 1 else (rough.length_y, rough.length)
        vecs = [
            sfft.dct(np.exp(-((lag / ell) ** 2)), type=1)
            for lag, ell in zip(lags, ells, strict=True)
        ]
        if len(full) == 1:
            return s2 * vecs[0]
        return s2 * np.multiply.outer(vecs[0], vecs[1])
    if len(full) == 1:
        c = rough.correlation(lags[0])
        return s2 * sfft.dct(c, type=1)
    c = rough.correlation(lags[1][None, :], lags[0][:, None])
    return s2 * sfft.dctn(c, type=1, workers=-1)


def _plan_circulant(rough: Roughness, shp, spacing) -> _Plan:
    base = tuple(_even_len(2 * (n - 1)) for n in shp)
    full = base
    while True:
        lam = _stationary_eigs(rough, full, spacing)
        ratio, neg_mass = _check_eigs(lam)
        if ratio >= -_EIG_TOL:
            break
        nxt = tuple(_even_len(2 * m) for m in full)
        if (
            math.prod(nxt) > _MAX_EMBED_POINTS
            or max(a / b for a, b in zip(nxt, base, strict=True)) > _MAX_PAD_FACTOR
        ):
            warnings.warn(
                f"circulant embedding of {rough.describe()} on grid {shp} stays indefinite up "
                f"to embedding {full} (smallest eigenvalue {ratio:.2e} of the largest); "
                f"negative eigenvalues clipped, relative negative mass {neg_mass:.2e}: the "
                "realization is approximate (use a larger spacing or a longer grid)",
                RuntimeWarning,
                stacklevel=3,
            )
            break
        full = nxt
    info = {
        "embedding_shape": full,
        "padding": tuple(m / (2 * (n - 1)) for m, n in zip(full, shp, strict=True)),
        "min_eigenvalue_ratio": ratio,
        "negative_mass": neg_mass if ratio < -_EIG_TOL else 0.0,
        "exact": ratio >= -_EIG_TOL,
    }
    amp = _amp_from_eigenvalues(lam, full)
    return _Plan("circulant-embedding", full, amp, shp, info)


def _plan_davies_harte(fbm: FractionalBrownian, n: int, dx: float) -> _Plan:
    h2 = 2.0 * fbm.hurst
    s2 = fbm.increment_rms**2 * (dx / fbm.lag) ** h2  # variance of one increment
    m_inc = n - 1
    base = _even_len(2 * (m_inc - 1)) if m_inc > 1 else 2
    full_n = base
    while True:
        k = np.arange(full_n // 2 + 1, dtype=float)
        gamma = 0.5 * s2 * (np.abs(k + 1) ** h2 - 2 * k**h2 + np.abs(k - 1) ** h2)
        lam = sfft.dct(gamma, type=1)
        ratio, neg_mass = _check_eigs(lam)
        if ratio >= -_EIG_TOL or full_n > _MAX_PAD_FACTOR * base:
            break
        full_n = _even_len(2 * full_n)
    info = {
        "embedding_shape": (full_n,),
        "padding": (full_n / max(2 * (m_inc - 1), 1),),
        "min_eigenvalue_ratio": ratio,
        "negative_mass": neg_mass if ratio < -_EIG_TOL else 0.0,
        "exact": ratio >= -_EIG_TOL,
        "increment_variance": s2,
    }
    if ratio < -_EIG_TOL:  # pragma: no cover - fGn embeddings are nonnegative (Craigmile 2003)
        warnings.warn(
            f"Davies–Harte embedding indefinite (ratio {ratio:.2e}); clipped",
            RuntimeWarning,
            stacklevel=3,
        )
    amp = _amp_from_eigenvalues(lam, (full_n,))

    def post(inc, rng):
        out = np.empty(n)
        out[0] = 0.0
        np.cumsum(inc, out=out[1:])
        return out

    plan = _Plan("davies-harte", (full_n,), amp, (m_inc,), info, post)
    return plan


def _stein_coeffs(alpha: float, big_r: float) -> tuple[float, float, float]:
    """(c0, c2, β) of Stein's (2002) covariance ψ for α = 2H and support radius R."""
    if big_r == 1.0:
        if alpha > 1.5:
            raise ValueError("R = 1 needs α ≤ 3/2")
        return 1.0 - alpha / 2.0, alpha / 2.0, 0.0
    beta = alpha * (2.0 - alpha) / (3.0 * big_r * (big_r**2 - 1.0))
    c2 = (alpha - beta * (big_r - 1.0) ** 2 * (big_r + 2.0)) / 2.0
    c0 = beta * (big_r - 1.0) ** 3 + 1.0 - c2
    return c0, c2, beta


def _stein_psi(r2: np.ndarray, alpha: float, big_r: float) -> np.ndarray:
    """Stein's ψ at squared distance ``r2`` (in place on ``r2``)."""
    c0, c2, beta = _stein_coeffs(alpha, big_r)
    mid = None
    if beta > 0:
        mid = (r2 > 1.0) & (r2 < big_r * big_r)
        rm = np.sqrt(r2[mid])
        vm = beta * (big_r - rm) ** 3 / rm
    outer = r2 > 1.0
    out = np.power(r2, alpha / 2.0)
    np.subtract(c2 * r2, out, out=out)
    out += c0
    out[outer] = 0.0
    if mid is not None:
        out[mid] = vm
    return out


def _plan_stein(fbm: FractionalBrownian, shp, spacing) -> _Plan:
    ny, nx = shp
    dy, dx = spacing
    alpha = 2.0 * fbm.hurst
    unit = math.hypot((ny - 1) * dy, (nx - 1) * dx)  # [m]: output diameter ↦ r = 1
    du = (dy / unit, dx / unit)
    last = None
    for big_r in _STEIN_R:
        if big_r == 1.0 and alpha > 1.5:
            continue
        full = tuple(_even_len(math.ceil(2 * big_r / d - 1e-9)) for d in du)
        ly, lx = _lag_axes(full, du)
        psi = _stein_psi(np.add.outer(ly * ly, lx * lx), alpha, big_r)
        lam = sfft.dctn(psi, type=1, workers=-1)
        ratio, neg_mass = _check_eigs(lam)
        last = (big_r, full, lam, ratio, neg_mass)
        if ratio >= -_EIG_TOL:
            break
    big_r, full, lam, ratio, neg_mass = last
    if ratio < -_EIG_TOL:  # pragma: no cover - R = 2 is nonnegative (Stein 2002, Thm. 1)
        warnings.warn(
            f"Stein embedding indefinite (ratio {ratio:.2e}); clipped",
            RuntimeWarning,
            stacklevel=3,
        )
    _, c2, _ = _stein_coeffs(alpha, big_r)
    # unit field: D(r) = 2 r^α (r in units of `unit`); physical D = inc² (r/lag)^α
    scale = fbm.increment_rms * math.sqrt(0.5 * (unit / fbm.lag) ** alpha)
    info = {
        "embedding_shape": full,
        "stein_R": big_r,
        "unit_length": unit,
        "padding": tuple(m / (2 * (n - 1)) for m, n in zip(full, shp, strict=True)),
        "min_eigenvalue_ratio": ratio,
        "negative_mass": neg_mass if ratio < -_EIG_TOL else 0.0,
        "exact": ratio >= -_EIG_TOL,
    }
    amp = _amp_from_eigenvalues(lam, full)
    xu = np.arange(nx) * du[1]
    yu = np.arange(ny) * du[0]
    k2 = math.sqrt(2.0 * c2)

    def post(f, rng):
        g = rng.standard_normal(2) * k2
        f -= f[0, 0]
        f += yu[:, None] * g[0]
        f += xu[None, :] * g[1]
        f *= scale
        return f

    return _Plan("stein-2002", full, amp, shp, info, post)


def _fbm_spectrum_prefactor(fbm: FractionalBrownian) -> float:
    """``A`` in ``S = A |K|^(−2(H+1))`` (2-D) or ``A |k|^(−(2H+1))`` (1-D) [height PSD with
    ∫ S d^dK = variance] giving ``D(r) = inc² (r/lag)^(2H)``:
    ``D(r) = 2 ∫ S(K) (1 − cos K·r) d^dK``; 1-D ``= 4 A r^{2H} I1``,
    ``I1 = ∫₀^∞ u^{−2H−1}(1 − cos u) du = π / (2 Γ(2H+1) sin πH)``;
    2-D ``= 4π A r^{2H} I2``, ``I2 = ∫₀^∞ u^{−2H−1}(1 − J0(u)) du = Γ(1−H) / (2^{2H} 2H Γ(1+H))``.
    """
    h = fbm.hurst
    c = fbm.increment_rms**2 * fbm.lag ** (-2 * h)
    if fbm.dimension == 1:
        i1 = math.pi / (2 * special.gamma(2 * h + 1) * math.sin(math.pi * h))
        return c / (4 * i1)
    i2 = special.gamma(1 - h) / (2 ** (2 * h) * 2 * h * special.gamma(1 + h))
    return c / (4 * math.pi * i2)


def _plan_periodic(rough, shp, spacing) -> _Plan:
    ndim = len(shp)
    dk = [2 * math.pi / (n * d) for n, d in zip(shp, spacing, strict=True)]
    dvol = math.prod(dk)
    n_tot = math.prod(shp)
    kx = np.arange(shp[-1] // 2 + 1) * dk[-1]
    ky = np.arange(shp[0] // 2 + 1) * dk[0] if ndim == 2 else None
    # mode amplitude for noise with unit-variance parts: X = N √(var/2) ζ, var = S ΔK^d
    if isinstance(rough, FractionalBrownian):
        a = _fbm_spectrum_prefactor(rough)
        const = n_tot * math.sqrt(a * dvol / 2.0)
        info = {"spectrum_prefactor": a, "embedding_shape": shp}
        if ndim == 1:
            k = kx.copy()
            k[0] = 1.0
            amp = const * k ** (-(rough.hurst + 0.5))
            amp[0] = 0.0
            _edge_factor(amp, shp[-1])
            return _Plan("fft-periodic", shp, amp, shp, info)
        # float32 for the power law: the filter needs no more than 1e-7 relative precision
        # (noise and transform stay float64) and float32 pow is ~2.5× faster
        kx2 = (kx * kx).astype(np.float32)
        ky2 = (ky * ky).astype(np.float32)
        expo = np.float32(-(rough.hurst + 1.0) / 2.0)
        edge_nyq = shp[-1] % 2 == 0

        def amp_rows(m0, m1):
            out = np.add.outer(ky2[m0:m1], kx2)
            if m0 == 0:
                out[0, 0] = 1.0
            np.power(out, expo, out=out)
            out *= np.float32(const)
            if m0 == 0:
                out[0, 0] = 0.0
            out[:, 0] *= np.float32(math.sqrt(2.0))
            if edge_nyq:
                out[:, -1] *= np.float32(math.sqrt(2.0))
            return out

        return _Plan("fft-periodic", shp, amp_rows, shp, info)
    s2 = rough.sigma**2
    if ndim == 1:
        var = s2 * dvol * rough.spectrum(kx)
    else:
        var = s2 * dvol * rough.spectrum(kx[None, :], ky[:, None])
    # multiplicity of each stored (|ky|, kx ≥ 0) mode in the full spectrum
    wx = np.full(kx.size, 2.0)
    wx[0] = 1.0
    if shp[-1] % 2 == 0:
        wx[-1] = 1.0
    if ndim == 1:
        total = float(np.sum(wx * var))
    else:
        wy = np.full(ky.size, 2.0)
        wy[0] = 1.0
        if shp[0] % 2 == 0:
            wy[-1] = 1.0
        total = float(wy @ var @ wx)
    info = {"discrete_variance_ratio": total / s2, "embedding_shape": shp}
    var *= (s2 / total) * n_tot * n_tot / 2.0
    np.sqrt(var, out=var)
    _edge_factor(var, shp[-1])
    return _Plan("fft-periodic", shp, var, shp, info)
