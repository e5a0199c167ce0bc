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
from dataclasses import dataclass, field

import numpy as np

from ..spectra import FractionalBrownian, Roughness
from .embedding import (  # noqa: F401 (the tests reach _stein_coeffs here)
    _edge_factor,
    _plan_circulant,
    _plan_davies_harte,
    _plan_periodic,
    _plan_stein,
    _stein_coeffs,
)

__all__ = ["Surface", "generate_surface", "generate_batch"]

_MIN_POINTS = 8

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
