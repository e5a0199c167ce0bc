"""A measured roughness: the statistics of a height map in the form every solver takes.

:func:`measured_roughness` turns a :class:`~emscatter.surfaces.heightmap.HeightMap` into a
:class:`MeasuredRoughness`, a :class:`~emscatter.spectra.Roughness` whose

* **spectrum** is Welch's estimate from the map (Welch 1967, IEEE Trans. Audio Electroacoust.
  15, 70): the map cut into ``segments`` × ``segments`` patches overlapping by half, each
  Hann-windowed (no per-patch mean removal: the map is detrended as a whole, and the low-K
  bins keep their content) (times the hole mask), ``|FFT|²`` normalized so that the height
  PSD integrates to the variance, averaged and made symmetric ``P(K) = P(−K)``; 2-D
  (anisotropic when the map is) or 1-D, bilinear on ``K``. Normalized as
  :mod:`emscatter.spectra` (``w = P/σ²``, ``σ²`` the map's variance);
* **band** is what the map resolves, ``[2π/L, π/Δ]`` (``L`` the patch side that sets the
  spectral resolution, ``Δ`` the spacing); beyond ``π/Δ`` the spectrum is a recorded choice:
  ``tail="none"`` (zero) or ``"power-law"`` (``C |K|^(−a)`` fitted to the radially averaged
  PSD over the top of the band ``[π/(4Δ), 0.9 π/Δ]``, isotropic);
* **correlation** ``ρ`` (:meth:`MeasuredRoughness.correlation`, ``acf``) is the whole map's
  autocorrelation (zero-padded FFT, each lag over its valid pairs, lags up to half the map)
  and ``length``/``length_y`` are its 1/e lags along x / y (unbiased to ≈ πℓxℓy/A, the
  removed mean: within 3 % on 512² maps of ℓ = 10Δ…30Δ, tested). The Welch patches' ρ
  (the inverse transform of the PSD, so ``ρ(0) = 1`` and the n-fold spectra ``FFT(ρⁿ)``
  are consistent with ``w``) is the one the n-fold spectra use; it is the true ρ times the
  window's autocorrelation and shorter (1.95 µm for a true 3 µm on a 64-sample patch);
* **slopes**: the mean-square slopes are the map's own cell-centred finite differences
  (``_mss_closed`` returns them: the solvers treat the measured surface as differentiable at
  its own resolution), and :meth:`MeasuredRoughness.slope_pdf` is their density (non-Gaussian
  as measured) that geometric optics uses in place of the Gaussian: the histogram smoothed by
  a variance-preserving Gaussian kernel whose width follows from the number of *independent*
  slope samples ``N/Σρ_ζ²`` (a map holds as many as correlation cells, not pixels: the raw
  histogram of a 512² brushed map, ≈ 700 of them, had noisy bins and a hard zero beyond its
  largest slope, 8.6 % L1 between its GO table and the Gaussian one; the kernel halves it);
  beyond the well-sampled slopes (``N_TAIL`` independent samples further out) a recorded tail
  (``slope_tail``: ``"gaussian"`` by default, ``"exponential"``, ``"none"``;
  :mod:`emscatter.surfaces.measured.slope_tail`), normalized, keeping the mean-square slopes.

:meth:`MeasuredRoughness.band_check` says how much of the band a wavenumber needs lies
outside the map: first-order SPM needs ``|K| = |k_s⊥ − k_i⊥|`` up to ``2k`` (backscatter at
grazing; at 500 nm that is 2.5e7 rad/m, a spacing ≤ 125 nm); the SPM solver runs it and warns
(:class:`BandWarning`) when part of the needed band is beyond the map with ``tail="none"``.
The Welch estimate itself and the smallest patches it takes are :mod:`.welch`.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from emscatter.spectra import Roughness
from emscatter.surfaces.heightmap import HeightMap, HeightMapError
from emscatter.surfaces.measured.bilinear import bilinear
from emscatter.surfaces.measured.estimators import map_acf
from emscatter.surfaces.measured.nfold import nfold_table
from emscatter.surfaces.measured.slope_tail import SLOPE_TAILS, evaluate
from emscatter.surfaces.measured.slopes import kernel_density, measure_slope_density
from emscatter.surfaces.measured.welch import MIN_MAP_SAMPLES, MIN_PATCH, MIN_SEGMENTS, welch_psd

__all__ = [
    "MeasuredRoughness",
    "measured_roughness",
    "BandWarning",
    "TAILS",
    "SLOPE_TAILS",
    "MIN_PATCH",
    "MIN_SEGMENTS",
    "MIN_MAP_SAMPLES",
]

#: The choices for the spectrum beyond the band the map resolves.
TAILS = ("none", "power-law")


class BandWarning(UserWarning):
    """Part of the spectral band a computation needs lies beyond what the map resolves."""


@dataclass(frozen=True, eq=False)
class MeasuredRoughness(Roughness):
    """The roughness of a measured height map (module docstring); build it with
    :func:`measured_roughness`. ``sigma`` [m] is the map's rms height, ``length`` /
    ``length_y`` [m] the 1/e lags of its correlation. The arrays are the estimates: ``psd``
    [m^(2+d)] on a uniform grid (origin ``k0``, step ``dk`` [rad/m] per axis, axis order
    (y, x)), ``slope_density`` [-] on a grid of slopes (origin, step per axis)."""

    psd: np.ndarray = None
    k0: tuple = ()
    dk: tuple = ()
    slope_density: np.ndarray = None
    slope_grid: tuple = ()
    slopes_ms: tuple = (0.0, 0.0)
    tail: str = "none"
    tail_fit: tuple = ()
    band_lo: float = 0.0
    band_hi: float = math.inf
    isotropic: bool = False
    source: str = "array"
    info: dict = field(default_factory=dict)
    acf: np.ndarray = None
    slope_tail: dict = None
    name: str = field(default="measured", init=False, repr=False)

    # ---------------------------------------------------------------- Roughness hooks
    @property
    def is_isotropic(self) -> bool:
        """True only when asked (``isotropic=True``: the spectrum averaged over rings)."""
        return bool(self.isotropic)

    @property
    def spectral_support(self):
        """(support radius, breakpoints) in units of 1/ℓ for the SPM2 quadrature: the band
        edge (``tail="none"``) or 1000× beyond it (power-law tail)."""
        lmin = min(self.length, self.length_y)
        top = self.band_hi * (1.0 if self.tail == "none" else 1e3)
        return top * lmin, tuple(b * lmin for b in (self.band_lo, 0.25 * self.band_hi))

    def _params(self) -> dict:
        raise TypeError(
            "a MeasuredRoughness cannot be rebuilt from (sigma, length); use "
            "measured_roughness(height_map) (profile() gives the 1-D spectrum along x)"
        )

    def _mss_closed(self):
        return tuple(float(s) for s in self.slopes_ms)

    def _rho_unit(self, u):
        return self.correlation(np.asarray(u, dtype=float) * self.length)

    def _w2_unit(self, q):
        return self.spectrum(np.asarray(q, dtype=float) / self.length) / (
            self.length * self.length_y
        )

    def _w1_unit(self, q):
        return self.spectrum(np.asarray(q, dtype=float) / self.length) / self.length

    # ---------------------------------------------------------------- spectrum
    @cached_property
    def _radial(self):
        """Ring average of the PSD: (K centres [rad/m], P [m^(2+d)])."""
        if self.dimension == 1:
            k = self.k0[0] + self.dk[0] * np.arange(self.psd.size)
            keep = k >= 0
            return k[keep], self.psd[keep]
        ky = self.k0[0] + self.dk[0] * np.arange(self.psd.shape[0])
        kx = self.k0[1] + self.dk[1] * np.arange(self.psd.shape[1])
        kr = np.hypot(*np.meshgrid(kx, ky, indexing="xy")[::-1])
        step = min(self.dk)
        idx = np.rint(kr / step).astype(np.intp)
        top = int(min(abs(self.k0[0]), abs(self.k0[1])) / step)
        cnt = np.bincount(idx.ravel(), minlength=top + 1)[: top + 1]
        tot = np.bincount(idx.ravel(), self.psd.ravel(), minlength=top + 1)[: top + 1]
        return np.arange(top + 1) * step, tot / np.maximum(cnt, 1)

    def _tail(self, kr):
        if self.tail == "none":
            return np.zeros(np.shape(kr))
        c, a = self.tail_fit
        with np.errstate(divide="ignore"):
            return c * np.maximum(kr, 1e-300) ** (-a)

    def height_spectrum(self, kx, ky=0.0) -> np.ndarray:
        """Height PSD ``σ² w`` [m^(2+d)]: the estimate inside the band, the tail beyond."""
        kx = np.asarray(kx, dtype=float)
        if self.dimension == 1:
            kr = np.abs(kx)
            kr0, lp = self._log_radial
            val = bilinear(lp, 0.0, kr0[1] - kr0[0], kr)
        elif self.isotropic:
            kr = np.sqrt(kx * kx + np.asarray(ky, dtype=float) ** 2)
            kr0, lp = self._log_radial
            val = bilinear(lp, 0.0, kr0[1] - kr0[0], kr)
        else:
            ky = np.asarray(ky, dtype=float)
            kx, ky = np.broadcast_arrays(kx, ky)
            kr = np.sqrt(kx * kx + ky * ky)
            val = bilinear(self._log_psd, self.k0[1], self.dk[1], kx, self.k0[0], self.dk[0], ky)
        return np.where(np.isnan(val), self._tail(kr), np.exp(val))

    @cached_property
    def _log_psd(self) -> np.ndarray:
        """log P (interpolated in log: a steep spectrum is not overestimated between bins)."""
        return np.log(np.maximum(self.psd, self.psd.max() * 1e-300))

    @cached_property
    def _log_radial(self):
        kr, pr = self._radial
        return kr, np.log(np.maximum(pr, pr.max() * 1e-300))

    def spectrum(self, kx, ky=0.0) -> np.ndarray:
        """Normalized spectrum ``w = P/σ²`` [m^d] (:mod:`emscatter.spectra`'s convention)."""
        return self.height_spectrum(kx, ky) / self.sigma**2

    # ---------------------------------------------------------------- correlation, n-fold
    @cached_property
    def _rho_grid(self) -> np.ndarray:
        """ρ on the lag grid of the patch (fftshifted, lag 0 at the centre), ρ(0) = 1."""
        core = self.psd[tuple(slice(0, n) for n in self.info["patch"])]
        rho = np.fft.fftshift(np.real(np.fft.ifftn(np.fft.ifftshift(core))))
        return rho / rho[tuple(n // 2 for n in rho.shape)]

    def correlation(self, x, y=0.0) -> np.ndarray:
        """ρ(x, y) [-], ``x, y`` [m]: the whole map's autocorrelation (``acf``, lags up to
        half the map, 0 beyond; :func:`measured_roughness`), else the PSD's (half a patch)."""
        rho = self._rho_grid if self.acf is None else self.acf
        sp = self.info["spacing"]
        x = np.asarray(x, dtype=float)
        if self.dimension == 1:
            c = rho.size // 2
            v = bilinear(rho, -c * sp[0], sp[0], x)
        else:
            cy, cx = rho.shape[0] // 2, rho.shape[1] // 2
            v = bilinear(rho, -cx * sp[1], sp[1], x, -cy * sp[0], sp[0], np.asarray(y, float))
        return np.nan_to_num(v, nan=0.0)

    def nfold_spectrum(self, n, kx, ky=0.0) -> np.ndarray:
        """Normalized transform of ``ρⁿ`` by FFT of the measured ρ [m^d] (``n`` ≥ 1; ``n = 1``
        is :meth:`spectrum` inside the band). Zero beyond the band."""
        n = np.asarray(n, dtype=float)
        kx = np.asarray(kx, dtype=float)
        ky = np.asarray(ky, dtype=float)
        n, kx, ky = np.broadcast_arrays(n, kx, ky)
        out = np.empty(n.shape)
        sp = self.info["spacing"]
        cell = float(np.prod(sp))
        for nv in np.unique(n):
            sel = n == nv
            grid = (
                np.fft.fftshift(np.real(np.fft.fftn(np.fft.ifftshift(self._rho_grid**nv))))
                * cell
                / (2 * math.pi) ** self.dimension
            )
            shp = grid.shape
            dk = tuple(2 * math.pi / (m * d) for m, d in zip(shp, sp, strict=True))
            k0 = tuple(-(m // 2) * s for m, s in zip(shp, dk, strict=True))
            if self.dimension == 1:
                v = bilinear(grid, k0[0], dk[0], kx[sel])
            else:
                v = bilinear(grid, k0[1], dk[1], kx[sel], k0[0], dk[0], ky[sel])
            out[sel] = np.nan_to_num(v, nan=0.0)
        return out

    @cached_property
    def _nfold(self):
        tail = None if self.tail == "none" else (lambda kr: self._tail(kr) / self.sigma**2)
        # the scale of s: the 1/e lags of the patch ρ it tabulates (``info["patch_lengths"]``)
        lengths = self.info.get("patch_lengths") or (
            (self.length,) if self.dimension == 1 else (self.length, self.length_y)
        )
        return nfold_table(self._rho_grid, self.info["spacing"], lengths, tail)

    def log_nfold_table(self):
        """``f(n, s) = log(w_n/L)`` for the PO and IEM series (``po.log_nfold``'s scaled ``s``):
        FFT of the measured ``ρⁿ`` averaged over ellipses
        (:mod:`emscatter.surfaces.measured.nfold`)."""
        return self._nfold[0]

    nfold_info = property(lambda self: dict(self._nfold[1]), doc="how the table was built")

    # ---------------------------------------------------------------- slopes
    def mean_square_slope(self, k_max: float | None = None) -> tuple[float, float]:
        """Per-direction mean-square slopes [-]: the map's finite differences, or with
        ``k_max`` [rad/m] the PSD's ``∫ Kx² P`` over ``|K| < k_max`` (band and tail)."""
        if k_max is None:
            return self._mss_closed()
        if self.dimension == 1:
            k = np.linspace(0, k_max, 4001)
            return float(2 * np.trapezoid(k * k * self.height_spectrum(k), k)), 0.0
        kr = np.linspace(0, k_max, 801)[1:]
        ph = np.linspace(0, 2 * math.pi, 257)[:-1]
        K, P = np.meshgrid(kr, ph, indexing="ij")
        cx, cy = K * np.cos(P), K * np.sin(P)
        hs = self.height_spectrum(cx, cy) * K * (2 * math.pi / ph.size)
        return (float(np.trapezoid((cx * cx * hs).sum(1), kr)),
                float(np.trapezoid((cy * cy * hs).sum(1), kr)))  # fmt: skip

    def _slope_kernel(self, zx, zy=None) -> np.ndarray:
        """The kernel estimate on its grid, bilinear between bin centres, 0 beyond it."""
        return kernel_density(self.slope_density, self.slope_grid, zx, zy)

    def slope_pdf(self, zx, zy=None) -> np.ndarray:
        """The measured slope density ``p(ζx, ζy)`` [-] (1-D: ``p₁(ζx)``): the kernel estimate
        (histogram → density, bilinear between bin centres) and, beyond the well-sampled
        slopes, the recorded tail (``slope_tail``, :mod:`.slope_tail`; ``"none"``: 0 beyond
        the histogram grid)."""
        zx = np.asarray(zx, dtype=float)
        zy = None if self.dimension == 1 else np.asarray(zy, dtype=float)
        if not self.slope_tail:
            return self._slope_kernel(zx, zy)
        return evaluate(self._slope_kernel, self.slope_tail, zx, zy)

    # ---------------------------------------------------------------- band
    def band_check(self, k: float, k_needed: float | None = None) -> dict:
        """How much of the band ``[0, K_need]`` (default ``2k``, first-order SPM's reach)
        lies outside ``[band_lo, band_hi]`` [rad/m]: ``fraction_above`` (beyond ``π/Δ``:
        zero or the tail, by ``tail``), ``fraction_below`` (under the patch resolution
        ``2π/L``, where the estimate is one bin wide), ``ok`` (nothing above, or a tail)."""
        k = float(k)
        need = 2 * k if k_needed is None else float(k_needed)
        above = max(0.0, need - self.band_hi) / need
        below = min(self.band_lo, need) / need
        ok = above == 0 or self.tail != "none"
        msg = (
            f"the band |K| ≤ {need:.4g} rad/m (2k at k={k:.4g} rad/m) is inside the map's "
            f"[{self.band_lo:.4g}, {self.band_hi:.4g}] rad/m"
            if above == 0
            else f"{100 * above:.1f}% of the band |K| ≤ {need:.4g} rad/m lies beyond the map's "
            f"π/Δ = {self.band_hi:.4g} rad/m (spacing {math.pi / self.band_hi:.4g} m; it needs "
            f"≤ {math.pi / need:.4g} m); beyond it the spectrum is "
            + ("zero (tail='none')" if self.tail == "none" else "the fitted power-law tail")
        )
        return {"k_needed": need, "band": (self.band_lo, self.band_hi),
                "fraction_above": above, "fraction_below": below, "tail": self.tail,
                "ok": ok, "message": msg}  # fmt: skip

    def warn_band(self, k: float, k_needed: float | None = None, stacklevel: int = 3) -> dict:
        """:meth:`band_check`, with a :class:`BandWarning` when it is not ``ok``."""
        rep = self.band_check(k, k_needed)
        if not rep["ok"]:
            warnings.warn(rep["message"], BandWarning, stacklevel=stacklevel)
        return rep

    # ---------------------------------------------------------------- views
    def profile(self) -> MeasuredRoughness:
        """The 1-D roughness along x: ``P₁(kx) = ∫ P(kx, ky) dky`` and the x-slopes."""
        if self.dimension == 1:
            return self
        p1 = self.psd[: self.info["patch"][0]].sum(axis=0) * self.dk[0]
        (x0, sx), (y0, sy) = self.slope_grid
        dens, gx = self.slope_density.sum(axis=0) * sy, (x0, sx)
        if self.slope_tail:  # the marginal of the tailed density, on a grid that holds it
            rec = self.slope_tail
            hx, hy = (rec["extent_rms"] * r for r in rec["rms_slopes"])
            nx, ny = (max(int(math.ceil(h / st)), abs(int(o / st))) for h, st, o in
                      ((hx, sx, x0), (min(hy, 60 * rec["rms_slopes"][1]), sy, y0)))  # fmt: skip
            xs, ys = np.arange(-nx, nx + 1) * sx, np.arange(-ny, ny + 1) * sy
            dens = self.slope_pdf(xs[None, :], ys[:, None]).sum(axis=0) * sy
            gx = (float(xs[0]), sx)
        info = {**self.info, "spacing": (self.info["spacing"][1],),
                "patch": (self.info["patch"][1],)}  # fmt: skip
        if "patch_lengths" in info:
            info["patch_lengths"] = info["patch_lengths"][:1]
        if self.slope_tail:
            info["slope_tail"] = {**info["slope_tail"], "profile": "the marginal of the map's "
                                  "tailed density (tail included on its grid)"}  # fmt: skip
        return MeasuredRoughness(
            sigma=self.sigma, length=self.length, dimension=1, psd=p1, k0=(self.k0[1],),
            dk=(self.dk[1],), slope_density=dens, slope_grid=(gx, None),
            slopes_ms=(self.slopes_ms[0], 0.0), tail=self.tail, tail_fit=self.tail_fit,
            band_lo=self.band_lo, band_hi=self.band_hi, source=self.source, info=info,
            acf=None if self.acf is None else self.acf[self.acf.shape[0] // 2].copy(),
        )  # fmt: skip

    def surface(self):
        raise TypeError("a measured profile has no 2-D spectrum; measure a map instead")

    def describe(self) -> str:
        holes = (self.info or {}).get("holes") or {}
        masked = f", {holes['count']} NaN holes masked" if holes.get("count") else ""
        return (
            f"measured ({self.source}): σ={self.sigma:.4g} m, ℓ={self.length:.4g} m, "
            f"ℓy={self.length_y:.4g} m, rms slopes {math.sqrt(self.slopes_ms[0]):.4g}/"
            f"{math.sqrt(self.slopes_ms[1]):.4g}, band [{self.band_lo:.4g}, {self.band_hi:.4g}]"
            f" rad/m, tail {self.tail}, slope tail "
            f"{(self.slope_tail or {}).get('shape', 'none')}{masked}"
        )


def _one_over_e(rho: np.ndarray, step: float) -> float:
    """First lag [m] where the (centre → edge) correlation falls below 1/e (linear)."""
    target = math.exp(-1.0)
    below = np.nonzero(rho < target)[0]
    if below.size == 0:
        return rho.size * step  # longer than the patch: at least that
    i = int(below[0])
    r0, r1 = rho[i - 1], rho[i]
    return ((i - 1) + (r0 - target) / (r0 - r1)) * step


def measured_roughness(
    hm: HeightMap,
    *,
    segments: int = 8,
    tail: str = "none",
    isotropic: bool = False,
    slope_bins: int | None = None,
    smooth: int = 0,
    slope_bandwidth: float | None = None,
    slope_tail: str = "gaussian",
) -> MeasuredRoughness:
    """The :class:`MeasuredRoughness` of a height map.

    Parameters
    ----------
    hm : a :class:`~emscatter.surfaces.heightmap.HeightMap` (:func:`read_height_map`,
        :func:`height_map`).
    segments : Welch patches per axis (patch side ``n // segments``, overlap ½): more
        segments, less variance, coarser resolution ``2π/L_patch``. Lowered (recorded in
        ``info["segments"]``, the request in ``info["segments_requested"]``) where a patch
        would be shorter than :data:`MIN_PATCH` samples; a map shorter than
        :data:`MIN_MAP_SAMPLES` along an axis (2 segments of 16) is a :class:`HeightMapError`
        naming its source and shape.
    tail : ``"none"`` or ``"power-law"`` (module docstring): the spectrum beyond ``π/Δ``.
    isotropic : True averages the spectrum over rings (for a map known to be isotropic).
    smooth : half-width in bins of a moving average of the Welch estimate (0: none; 1: 3×3
        bins, a ninth of the variance for a bias ∝ (Δk)² × the spectrum's curvature).
    slope_bins : bins per axis of the slope density grid (default: 3 per kernel rms,
        21…301; the raw histogram ``≈ N^(1/4)·2``, 21…201).
    slope_bandwidth : the kernel that smooths the slope histogram, in rms slopes per axis
        (``info["slope_bandwidth"]``). None (default): Scott's rule ``b = N_eff^(−1/6)``
        (2-D; ``1.06 N_eff^(−1/5)`` 1-D) with ``N_eff = N/Σρ_ζ²`` the independent slope
        samples (``info["slope_samples_effective"]``; a 512² map of a Gaussian surface with
        ℓx = 10Δ, ℓy = 30Δ has ≈ 4·10³, b ≈ 0.25). The kernel is variance-preserving, so
        the density keeps the measured mean-square slopes; its bias is the kernel's
        smoothing of the shape: none for Gaussian slopes, a jump or a cusp of the density
        is rounded over ≈ b rms. 0: the raw histogram (right only for maps whose slopes are
        not a random sample, or very many independent ones: its bins at 3 rms hold a few
        counts, and it is zero beyond the largest measured slope).
    slope_tail : the slope density beyond the well-sampled slopes (:mod:`.slope_tail`,
        ``info["slope_tail"]``): ``"gaussian"`` (default: a Gaussian-shaped tail in the
        normalized slope radius, its curvature fitted to the last well-sampled shells, so a
        random surface keeps the large slopes its map is too small to sample: the rim of a
        rendered sphere, GO at grazing), ``"exponential"`` (heavier), or ``"none"`` (the
        kernel estimate alone, 0 beyond it: for maps whose slopes are bounded, e.g. facets).
        The tailed density integrates to 1 and keeps the measured mean-square slopes.
    """
    if not isinstance(hm, HeightMap):
        raise TypeError(
            f"hm must be a HeightMap (emscatter.surfaces.height_map / read_height_map), got "
            f"{type(hm).__name__}"
        )
    if isinstance(segments, bool) or not isinstance(segments, int) or segments < 1:
        raise ValueError(f"segments must be a positive integer, got {segments!r}")
    if tail not in TAILS:
        raise ValueError(f"tail must be one of {TAILS}, got {tail!r}")
    if min(hm.shape) < MIN_MAP_SAMPLES:
        where = "array" if hm.source == "array" else f"file {hm.source!r}"
        raise HeightMapError(
            f"the map from the {where} is too small for a spectrum estimate: shape "
            f"{hm.shape}; Welch's estimate needs at least {MIN_SEGMENTS} segments of "
            f"{MIN_PATCH} samples per axis (overlapping by half), i.e. at least "
            f"{MIN_MAP_SAMPLES} samples along every axis"
        )
    requested = segments
    if min(hm.shape) // segments < MIN_PATCH:
        segments = max(1, min(hm.shape) // MIN_PATCH)
    if slope_tail not in SLOPE_TAILS:
        raise ValueError(f"slope_tail must be one of {SLOPE_TAILS}, got {slope_tail!r}")
    if isinstance(smooth, bool) or not isinstance(smooth, int) or not 0 <= smooth <= 8:
        raise ValueError(f"smooth must be an integer 0…8 (bins), got {smooth!r}")
    psd, k0, dk, patch = welch_psd(hm, segments, smooth)
    sigma = hm.rms_height()
    slopes = measure_slope_density(hm, slope_bins=slope_bins, slope_bandwidth=slope_bandwidth,
                                   slope_tail=slope_tail)  # fmt: skip
    dens, (gx, gy), mss = slopes.density, slopes.grid, slopes.mean_square
    band_lo = 2 * math.pi / max(p * d for p, d in zip(patch, hm.spacing, strict=True))
    band_hi = math.pi / max(hm.spacing)
    info = {"spacing": hm.spacing, "patch": patch, "segments": segments,
            "segments_requested": requested, "window": "hann",
            "overlap": 0.5, "smooth": smooth, **slopes.info,
            "map_band": hm.band, "detrend": hm.detrend, "holes": hm.holes,
            "spectral_mass": float(psd.sum() * np.prod(dk) / sigma**2)}  # fmt: skip
    rec = slopes.tail
    info["slope_tail"] = rec or {"shape": "none", "rule": "the kernel estimate alone, 0 "
                                 "beyond the histogram grid"}  # fmt: skip
    common = {"psd": psd, "k0": k0, "dk": dk, "slope_density": dens, "slope_grid": (gx, gy),
              "slopes_ms": mss, "band_lo": band_lo, "band_hi": band_hi,
              "isotropic": bool(isotropic) and hm.dimension == 2, "source": hm.source,
              "info": info, "dimension": hm.dimension}  # fmt: skip
    probe = MeasuredRoughness(sigma=sigma, length=1.0, length_y=None, **common)
    pr = probe._rho_grid
    if hm.dimension == 1:
        info["patch_lengths"] = (_one_over_e(pr[pr.size // 2 :], hm.spacing[0]),)
    else:
        py, px = pr.shape[0] // 2, pr.shape[1] // 2
        info["patch_lengths"] = (_one_over_e(pr[py, px:], hm.spacing[1]),
                                 _one_over_e(pr[py:, px], hm.spacing[0]))  # fmt: skip
        if isotropic:
            info["patch_lengths"] = (math.sqrt(math.prod(info["patch_lengths"])),) * 2
    rho = map_acf(hm)  # ℓ from the whole map, not from the (shorter, windowed) patches
    common["acf"] = rho
    if hm.dimension == 1:
        lx = _one_over_e(rho[rho.size // 2 :], hm.spacing[0])
        ly = None
    else:
        cy, cx = rho.shape[0] // 2, rho.shape[1] // 2
        lx = _one_over_e(rho[cy, cx:], hm.spacing[1])
        ly = _one_over_e(rho[cy:, cx], hm.spacing[0])
        if isotropic:
            lx = ly = math.sqrt(lx * ly)
    fit = ()
    if tail == "power-law":
        kr, pr = probe._radial
        sel = (kr >= 0.25 * band_hi) & (kr <= 0.9 * band_hi) & (pr > 0)
        if sel.sum() < 4:
            raise HeightMapError(
                f"the map from {hm.source} has too few spectral bins near π/Δ for a power-law "
                "tail fit; use tail='none'"
            )
        slope, icpt = np.polyfit(np.log(kr[sel]), np.log(pr[sel]), 1)
        fit = (float(math.exp(icpt)), float(-slope))
        info["tail_fit_range"] = (0.25 * band_hi, 0.9 * band_hi)
    return MeasuredRoughness(sigma=sigma, length=lx, length_y=ly, tail=tail, tail_fit=fit,
                             slope_tail=rec, **common)  # fmt: skip
