"""Random rough profiles ``h(x)`` and height maps ``h(y, x)`` in physical units.

Methods (``Surface.method``)
----------------------------
``"circulant-embedding"``
    Exact for stationary Gaussian roughness (:class:`~emscatter.spectra.GaussianCorrelation`,
    :class:`~emscatter.spectra.ExponentialCorrelation`,
    :class:`~emscatter.spectra.PowerLawCorrelation`, isotropic or ``ℓx ≠ ℓy``). The covariance
    ``σ² ρ(lag)`` sampled on the grid is embedded in a periodic grid at least twice the output
    in every axis (Dietrich & Newsam 1997, SIAM J. Sci. Comput. 18, 1088; Wood & Chan 1994,
    J. Comput. Graph. Stat. 3, 409). Its eigenvalues (a DFT, computed as a type-I DCT of the
    even covariance, or as an outer product of 1-D transforms for the separable Gaussian) must
    be nonnegative; the embedding is doubled until the smallest eigenvalue is ≥ −1e-10 × the
    largest. The padding used and the smallest eigenvalue are in ``Surface.info``. If the cap
    (8× the minimal embedding per axis, 2²⁶ points) is reached, negative eigenvalues are
    clipped, the relative negative mass is recorded as ``info["negative_mass"]`` and a
    ``RuntimeWarning`` is issued: the realization is then approximate.
``"davies-harte"``
    Exact 1-D fractional Brownian motion: circulant embedding of fractional Gaussian noise
    (Davies & Harte 1987, Biometrika 74, 95) then a cumulative sum, ``h(0) = 0``.
``"stein-2002"``
    Exact 2-D fractional Brownian surface (Stein 2002, J. Comput. Graph. Stat. 11, 587–599):
    circulant embedding of the compactly supported covariance
    ``ψ(r) = c0 − r^α + c2 r²`` (``r ≤ 1``), ``β (R − r)³ / r`` (``1 ≤ r ≤ R``), ``0`` beyond,
    ``α = 2H``, on a periodic grid of period ``≥ 2R``, plus the random linear term
    ``√(2 c2) (x N1 + y N2)``; the sum has structure function exactly ``2 r^α`` for ``r ≤ 1``.
    Stein uses ``R = 1`` for ``α ≤ 3/2`` and ``R = 2`` above; ``β`` and ``c2`` follow from
    continuity of ``ψ, ψ', ψ''`` at ``r = 1`` for any ``R > 1``
    (``β = α(2 − α) / (3R(R² − 1))``, ``c2 = (α − β (R − 1)² (R + 2)) / 2``,
    ``c0 = β (R − 1)³ + 1 − c2``). Here the smallest ``R`` of ``(1, 1.1, 1.2, 1.3, 1.5, 2)``
    whose embedding is nonnegative on the actual grid is used (``R = 1.1`` suffices up to
    ``H = 0.9`` — about 3× cheaper than ``R = 2``); the unit of length is the diagonal of the
    output grid, so every pair of output points is within ``r ≤ 1``.
``"fft-periodic"`` (``periodic=True``)
    Spectral synthesis on the output grid itself: independent complex Gaussian amplitudes
    on the grid wavenumbers ``2π m / L`` filtered by the target spectrum and one inverse
    real FFT. The result is exactly periodic (its spectrum holds only grid frequencies). For
    stationary roughness the discrete spectrum ``σ² w(K) ΔK^d`` is rescaled so that the
    variance is exactly ``σ²``. For fBm the spectrum is the power law
    ``S(K) = A |K|^(−2(H+1))`` (2-D) or ``A |k|^(−(2H+1))`` (1-D) with the DC term zero and
    ``A`` chosen so that the structure function of the infinite-domain process is
    ``increment_rms² (r/lag)^(2H)``: a *periodic self-affine* surface, **not** a true fBm
    (no long-wavelength content beyond the period; its structure function falls below the
    power law as ``r`` approaches ``L/2``).

All methods draw half-spectrum complex noise directly and apply one ``scipy.fft`` inverse real
transform; large arrays draw their noise in threads from children of the caller's generator
(a fixed number of blocks, so the result does not depend on the number of cores).

Randomness: ``rng`` is ``None`` (fresh OS entropy, recorded in ``Surface.seed``), an ``int``
seed, a :class:`numpy.random.SeedSequence` or a :class:`numpy.random.Generator`. The global
``numpy.random`` state is never used.
"""

from __future__ import annotations

import math
import numbers
import os
import warnings
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field

import numpy as np
import scipy.fft as sfft
from scipy import special

from ..spectra import FractionalBrownian, GaussianCorrelation, Roughness

__all__ = ["Surface", "generate_surface", "generate_batch"]

_MIN_POINTS = 8
_EIG_TOL = 1e-10  # relative: eigenvalues ≥ −_EIG_TOL·max count as round-off and are clipped
_MAX_EMBED_POINTS = 2**26
_MAX_PAD_FACTOR = 8
_STEIN_R = (1.0, 1.1, 1.2, 1.3, 1.5, 2.0)
_THREADED_NOISE_MIN = 2**20  # float pairs; below this the noise is drawn in one block
_NOISE_BLOCKS = 8

METHODS = ("circulant-embedding", "davies-harte", "stein-2002", "fft-periodic")


# --------------------------------------------------------------------------- Surface
@dataclass(frozen=True, eq=False)
class Surface:
    """A realization of a random rough surface, with the statistics it was drawn from.

    Attributes
    ----------
    heights : ``(n,)`` profile or ``(ny, nx)`` height map [m] (mean not removed).
    spacing : ``(dx,)`` or ``(dy, dx)`` [m], axis order as ``heights``.
    target : the roughness asked for (:class:`~emscatter.spectra.Roughness` or
        :class:`~emscatter.spectra.FractionalBrownian`).
    periodic : whether the map is periodic (``method == "fft-periodic"``).
    method : ``"circulant-embedding"``, ``"davies-harte"``, ``"stein-2002"`` or
        ``"fft-periodic"``.
    seed : the ``int`` seed given, or the OS entropy drawn when ``rng=None`` (pass it back as
        ``rng`` to reproduce the surface), or ``None`` when a Generator was given.
    info : details of the method: embedding shape, padding factor, smallest eigenvalue, …
    """

    heights: np.ndarray
    spacing: tuple[float, ...]
    target: Roughness | FractionalBrownian
    periodic: bool
    method: str
    seed: int | None = None
    info: dict = field(default_factory=dict)

    @property
    def shape(self) -> tuple[int, ...]:
        return self.heights.shape

    @property
    def dimension(self) -> int:
        """1 for a profile, 2 for a height map."""
        return self.heights.ndim

    @property
    def x(self) -> np.ndarray:
        """Sample positions along x (last axis) [m], starting at 0."""
        return np.arange(self.shape[-1]) * self.spacing[-1]

    @property
    def y(self) -> np.ndarray:
        """Sample positions along y (first axis of a map) [m]; raises for a profile."""
        if self.dimension != 2:
            raise AttributeError("a 1-D profile has no y axis")
        return np.arange(self.shape[0]) * self.spacing[0]

    @property
    def size(self) -> tuple[float, ...]:
        """Physical extent ``n · spacing`` per axis [m] (the period for a periodic map)."""
        return tuple(n * d for n, d in zip(self.shape, self.spacing, strict=True))

    def target_stats(self) -> dict:
        """Statistics asked for.

        Stationary roughness: ``sigma`` [m], ``length``/``length_y`` [m], ``correlation``,
        per-direction rms slopes ``rms_slope_x``, ``rms_slope_y`` and the total
        ``rms_slope = √(⟨h_x²⟩ + ⟨h_y²⟩)`` [-] where finite (Gaussian: ``⟨h_x²⟩ = 2σ²/ℓx²``),
        else ``None`` (exponential and power law need a cutoff). fBm: ``hurst``,
        ``fractal_dimension`` (2 − H profile, 3 − H surface), ``increment_rms`` [m], ``lag``
        [m]; ``sigma`` and slopes ``None`` (not stationary).
        """
        t = self.target
        if isinstance(t, FractionalBrownian):
            return {
                "kind": "fbm",
                "hurst": t.hurst,
                "fractal_dimension": t.fractal_dimension,
                "increment_rms": t.increment_rms,
                "lag": t.lag,
                "sigma": None,
                "rms_slope_x": None,
                "rms_slope_y": None,
                "rms_slope": None,
            }
        out = {
            "kind": t.name,
            "correlation": t.name,
            "sigma": t.sigma,
            "length": t.length,
            "length_y": t.length_y if t.dimension == 2 else None,
            "hurst": getattr(t, "hurst", None),
            "fractal_dimension": None,
        }
        closed = t._mss_closed()
        if closed is None:
            out.update(rms_slope_x=None, rms_slope_y=None, rms_slope=None)
        else:
            sx, sy = closed
            out.update(
                rms_slope_x=math.sqrt(sx),
                rms_slope_y=math.sqrt(sy) if t.dimension == 2 else None,
                rms_slope=math.sqrt(sx + sy),
            )
        return out

    def realized_stats(self) -> dict:
        """Statistics of this realization.

        ``mean`` [m]; ``sigma``: rms height about the mean, Rq (profile) / Sq (map), seed
        eqs. 2.1–2.2 [m]; ``rms_slope_x``, ``rms_slope_y``: rms of the central differences
        ``(h[i+1] − h[i−1]) / (2Δ)`` (seed eqs. 2.6–2.7; wrapped around for a periodic map,
        interior points otherwise) [-]; ``rms_slope``: √(sum of their squares), Rdq/Sdq.
        Central differences underestimate the Gaussian slope by a relative ``(Δ/ℓ)²``.
        """
        h = self.heights
        mean = float(np.mean(h))
        sigma = float(np.sqrt(np.mean((h - mean) ** 2)))
        slopes = []
        for axis in range(h.ndim):
            d = self.spacing[axis]
            if self.periodic:
                diff = np.roll(h, -1, axis=axis) - np.roll(h, 1, axis=axis)
            else:
                n = h.shape[axis]
                diff = np.take(h, range(2, n), axis=axis) - np.take(h, range(0, n - 2), axis=axis)
            slopes.append(float(np.sqrt(np.mean((diff / (2 * d)) ** 2))))
        return {
            "mean": mean,
            "sigma": sigma,
            "rms_slope_x": slopes[-1],
            "rms_slope_y": slopes[0] if h.ndim == 2 else None,
            "rms_slope": float(math.sqrt(sum(s * s for s in slopes))),
        }

    def measure(self, **kw) -> dict:
        """Full measurement (:func:`emscatter.surfaces.measure.summarize`) of the heights."""
        from .measure import summarize

        return summarize(self.heights, self.spacing, **kw)


# --------------------------------------------------------------------------- input checks
def _check_shape(shape) -> tuple[int, ...]:
    def is_int(v):
        return isinstance(v, numbers.Integral) and not isinstance(v, bool)

    if is_int(shape):
        shp = (int(shape),)
    elif isinstance(shape, tuple | list) and 1 <= len(shape) <= 2 and all(map(is_int, shape)):
        shp = tuple(int(s) for s in shape)
    else:
        raise TypeError(
            f"shape must be an int (profile of n points) or a tuple (ny, nx) of ints "
            f"(height map), got {shape!r}"
        )
    if min(shp) < _MIN_POINTS:
        raise ValueError(
            f"shape must have at least {_MIN_POINTS} points in every axis, got {shape!r}"
        )
    return shp


def _check_spacing(spacing, ndim: int) -> tuple[float, ...]:
    if isinstance(spacing, tuple | list | np.ndarray):
        vals = list(np.asarray(spacing, dtype=object).ravel())
        if len(vals) != ndim:
            raise ValueError(
                f"spacing must be a number or a tuple of {ndim} numbers "
                f"({'(dy, dx)' if ndim == 2 else '(dx,)'}) [m], got {spacing!r}"
            )
    else:
        vals = [spacing] * ndim
    out = []
    for v in vals:
        if isinstance(v, bool) or not isinstance(v, numbers.Real):
            raise TypeError(f"spacing must be real numbers [m], got {spacing!r}")
        f = float(v)
        if not math.isfinite(f) or f <= 0:
            raise ValueError(f"spacing must be finite and > 0 [m], got {spacing!r}")
        out.append(f)
    return tuple(out)


def _make_rng(rng) -> tuple[np.random.Generator, int | None]:
    if rng is None:
        ss = np.random.SeedSequence()
        return np.random.default_rng(ss), int(ss.entropy)
    if isinstance(rng, numbers.Integral) and not isinstance(rng, bool):
        if rng < 0:
            raise ValueError(f"rng seed must be a nonnegative int, got {rng!r}")
        return np.random.default_rng(int(rng)), int(rng)
    if isinstance(rng, np.random.SeedSequence):
        ent = rng.entropy
        return np.random.default_rng(rng), (int(ent) if isinstance(ent, numbers.Integral) else None)
    if isinstance(rng, np.random.Generator):
        return rng, None
    raise TypeError(
        "rng must be None, a nonnegative int seed, a numpy.random.SeedSequence or a "
        f"numpy.random.Generator (never the global numpy.random state), got {type(rng).__name__}"
    )


def _check_roughness(roughness, shp, spacing) -> None:
    if not isinstance(roughness, Roughness | FractionalBrownian):
        raise TypeError(
            "roughness must be an emscatter.spectra Roughness (GaussianCorrelation, "
            "ExponentialCorrelation, PowerLawCorrelation) or FractionalBrownian, "
            f"got {type(roughness).__name__}"
        )
    if roughness.dimension != len(shp):
        want = "an int (profile)" if roughness.dimension == 1 else "a tuple (ny, nx)"
        raise ValueError(
            f"shape {shp if len(shp) == 2 else shp[0]!r} does not match roughness.dimension="
            f"{roughness.dimension}: a dimension-{roughness.dimension} roughness needs shape "
            f"as {want} (use roughness.profile() / .surface() to change it)"
        )
    if isinstance(roughness, Roughness):
        lengths = (roughness.length,) if len(shp) == 1 else (roughness.length_y, roughness.length)
        names = ("dx",) if len(shp) == 1 else ("dy", "dx")
        for d, ell, nm, ln in zip(
            spacing, lengths, names, ("length_y", "length")[-len(shp) :], strict=True
        ):
            if d > ell:
                raise ValueError(
                    f"spacing {nm}={d!r} m is coarser than the correlation length "
                    f"{ln}={ell!r} m; spacing must be ≤ the correlation length (ideally ≤ ℓ/8)"
                )


# --------------------------------------------------------------------------- kernels
def _edge_factor(amp: np.ndarray, n_last: int) -> None:
    """In place: ×√2 on the kx = 0 and Nyquist columns, whose imaginary parts ``irfft``
    discards, so that their real part carries the full variance."""
    amp[..., 0] *= math.sqrt(2.0)
    if n_last % 2 == 0:
        amp[..., -1] *= math.sqrt(2.0)


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


def _plan(roughness, shape, spacing, periodic):
    shp = _check_shape(shape)
    sp = _check_spacing(spacing, len(shp))
    _check_roughness(roughness, shp, sp)
    if not isinstance(periodic, bool | np.bool_):
        raise TypeError(f"periodic must be True or False, got {periodic!r}")
    if periodic:
        return _plan_periodic(roughness, shp, sp), sp
    if isinstance(roughness, FractionalBrownian):
        if len(shp) == 1:
            return _plan_davies_harte(roughness, shp[0], sp[0]), sp
        return _plan_stein(roughness, shp, sp), sp
    return _plan_circulant(roughness, shp, sp), sp


# --------------------------------------------------------------------------- public API
def generate_surface(
    roughness: Roughness | FractionalBrownian,
    shape: int | tuple[int, int],
    spacing: float | tuple[float, ...],
    *,
    periodic: bool = False,
    rng: None | int | np.random.SeedSequence | np.random.Generator = None,
) -> Surface:
    """One random profile or height map with the given statistics.

    Parameters
    ----------
    roughness : :class:`~emscatter.spectra.GaussianCorrelation`,
        :class:`~emscatter.spectra.ExponentialCorrelation`,
        :class:`~emscatter.spectra.PowerLawCorrelation` or
        :class:`~emscatter.spectra.FractionalBrownian`; its ``dimension`` must match ``shape``.
    shape : ``n`` (profile, needs ``dimension=1``) or ``(ny, nx)`` (map, ``dimension=2``),
        at least 8 points per axis.
    spacing : ``dx`` or ``(dy, dx)`` [m], finite, > 0, and for stationary roughness no
        coarser than the correlation length along that axis.
    periodic : ``False`` (default): exact method (module docstring). ``True``: periodic FFT
        synthesis on the grid itself (for fBm a periodic self-affine surface, not a true fBm).
    rng : ``None``, an ``int`` seed, a ``SeedSequence`` or a ``numpy.random.Generator``.

    Returns
    -------
    :class:`Surface`, heights in [m], axis 0 = y, axis 1 = x.

    Examples
    --------
    >>> from emscatter.spectra import GaussianCorrelation
    >>> s = generate_surface(GaussianCorrelation(1e-3, 1e-2), (256, 256), 1e-3, rng=0)
    >>> s.shape, s.method
    ((256, 256), 'circulant-embedding')
    """
    plan, sp = _plan(roughness, shape, spacing, periodic)
    gen, seed = _make_rng(rng)
    heights = plan.realize(gen)
    return Surface(heights, sp, roughness, bool(periodic), plan.method, seed, dict(plan.info))


def generate_batch(
    roughness: Roughness | FractionalBrownian,
    count: int,
    shape: int | tuple[int, int],
    spacing: float | tuple[float, ...],
    *,
    seed: int | np.random.SeedSequence,
    periodic: bool = False,
) -> list[Surface]:
    """``count`` independent realizations, reproducible: realization ``i`` uses the ``i``-th
    child of ``numpy.random.SeedSequence(seed).spawn(count)``. The embedding (its
    eigenvalues) is computed once for the whole batch."""
    if isinstance(count, bool) or not isinstance(count, numbers.Integral) or count < 1:
        raise ValueError(f"count must be an int ≥ 1, got {count!r}")
    if isinstance(seed, np.random.SeedSequence):
        ss = seed
    elif isinstance(seed, numbers.Integral) and not isinstance(seed, bool) and seed >= 0:
        ss = np.random.SeedSequence(int(seed))
    else:
        raise TypeError(
            f"seed must be a nonnegative int or a numpy.random.SeedSequence, got {seed!r}"
        )
    plan, sp = _plan(roughness, shape, spacing, periodic)
    out = []
    for i, child in enumerate(ss.spawn(int(count))):
        h = plan.realize(np.random.default_rng(child))
        info = {**plan.info, "batch_index": i, "spawn_key": child.spawn_key}
        out.append(Surface(h, sp, roughness, bool(periodic), plan.method, None, info))
    return out
