"""Welch's spectrum estimate of a height map (Welch 1967, IEEE Trans. Audio Electroacoust. 15,
70), the spectrum :class:`~.roughness.MeasuredRoughness` holds.

:func:`welch_psd`: the map cut into ``segments`` × ``segments`` patches overlapping by half,
each Hann-windowed (no per-patch mean removal: the map is detrended as a whole) times the hole
mask (patches that are mostly holes give no estimate), ``|FFT|²`` normalized so that the
height PSD integrates to the variance, averaged, optionally box-smoothed, and made symmetric
``P(K) = P(−K)`` on a grid spanning ``[−K_N, K_N]``. What decides the patch: the smallest
patch and segment counts below (:data:`MIN_PATCH`, :data:`MIN_SEGMENTS`,
:data:`MIN_MAP_SAMPLES`).
"""

from __future__ import annotations

import math

import numpy as np
import scipy.fft as sfft

from emscatter.surfaces.heightmap import HeightMap, HeightMapError

__all__ = ["welch_psd", "MIN_PATCH", "MIN_SEGMENTS", "MIN_MAP_SAMPLES"]

#: The fewest samples per axis of a Welch patch. The Hann window's main lobe is ±2 bins, so
#: the band ``[2π/L, π/Δ]`` (bins 1…N/2) keeps bins 2…N/2 free of the leakage from K = 0:
#: 7 bins for N = 16 (a factor 4 in |K|), 3 for N = 8. The power-law tail is fitted on the
#: bins in ``[π/(4Δ), 0.9 π/Δ]`` (N/8…0.45 N) and needs at least 4: 6 for N = 16, 3 for
#: N = 8; and ρ, the inverse transform of the same PSD, reaches lags up to N/2 samples.
MIN_PATCH = 16
#: The fewest Welch segments per axis: 2 segments overlapping by half are 3 patches per axis
#: (9 on a map), the relative standard deviation of each bin ≈ √(1.06/K) (Welch 1967, Hann
#: at 50 % overlap): 0.34 on a map, 0.6 on a profile; one patch is a bare periodogram (100 %).
MIN_SEGMENTS = 2
#: The smallest map (samples along every axis) a measured roughness is estimated from.
MIN_MAP_SAMPLES = MIN_SEGMENTS * MIN_PATCH


def _symmetric_extended(p: np.ndarray) -> np.ndarray:
    """fftshifted grid → symmetric grid spanning ``[−K_N, K_N]`` on every even axis (the
    Nyquist line repeated), averaged with its point reflection ``P(−K)``."""
    for ax in range(p.ndim):
        if p.shape[ax] % 2 == 0:
            first = np.take(p, [0], axis=ax)
            p = np.concatenate([p, first], axis=ax)
    flip = p[(slice(None, None, -1),) * p.ndim]
    return 0.5 * (p + flip)


def _box(p: np.ndarray, half: int) -> np.ndarray:
    """Moving average over ``(2·half + 1)^d`` bins (edges: the bins that exist)."""
    if half == 0:
        return p
    out, cnt = p.copy(), np.ones_like(p)
    for ax in range(p.ndim):
        acc, c = out.copy(), cnt.copy()
        for s in range(1, half + 1):
            for sign in (1, -1):
                sl_to = [slice(None)] * p.ndim
                sl_from = [slice(None)] * p.ndim
                sl_to[ax] = slice(s, None) if sign > 0 else slice(None, -s)
                sl_from[ax] = slice(None, -s) if sign > 0 else slice(s, None)
                acc[tuple(sl_to)] += out[tuple(sl_from)]
                c[tuple(sl_to)] += cnt[tuple(sl_from)]
        out, cnt = acc, c
    return out / cnt


def _full_from_half(half: np.ndarray, patch: tuple) -> np.ndarray:
    """The FFT-ordered power grid from its ``rfftn`` half, by ``P(−K) = P(K)`` (real input)."""
    n = patch[-1]
    out = np.empty(patch)
    out[..., : half.shape[-1]] = half
    rest = np.arange(half.shape[-1], n)  # kx = rest ↔ −kx = n − rest, inside the half
    mirror = half[..., n - rest]
    for ax in range(half.ndim - 1):  # −ky on the other axes: index (−i) mod m
        mirror = np.roll(np.flip(mirror, axis=ax), 1, axis=ax)
    out[..., rest] = mirror
    return out


def welch_psd(hm: HeightMap, segments: int, smooth: int = 0):
    """Welch PSD ``P`` [m^(2+d)] on the symmetric fftshifted grid, with the grid origin and
    step per axis [rad/m] and the patch shape."""
    h, m = hm.heights, hm.mask.astype(float)
    shape = h.shape
    patch = tuple(max(MIN_PATCH, n // segments) for n in shape)
    step = tuple(max(1, p // 2) for p in patch)
    win = np.hanning(patch[0] + 2)[1:-1]
    if h.ndim == 2:
        win = np.outer(win, np.hanning(patch[1] + 2)[1:-1])
    wsum = 0.0
    cell = float(np.prod(hm.spacing))
    # strided views (no copy), patch rows batched per rfftn (half spectrum, P(−K) = P(K));
    # the map is detrended as a whole: no patch mean; a map without holes skips the mask
    views = [np.lib.stride_tricks.sliding_window_view(a, patch)[:: step[0]] for a in (h, m)]
    if h.ndim == 2:
        views = [v[:, :: step[1]] for v in views]
    hv, mv = views
    full = bool(hm.mask.all())
    per_row = int(np.prod(hv.shape[1 : h.ndim]))  # patches per row of patches
    rows = max(1, (1 << 22) // (per_row * int(np.prod(patch))))
    axes = tuple(range(1, h.ndim + 1))
    acc = np.zeros((*patch[:-1], patch[-1] // 2 + 1))
    for r0 in range(0, hv.shape[0], rows):
        hb = hv[r0 : r0 + rows].reshape(-1, *patch)
        if full:
            wm = win
            wsum += hb.shape[0] * float((win * win).sum())
        else:
            wm = win * mv[r0 : r0 + rows].reshape(-1, *patch)
            ok = wm.sum(axis=axes) > 0.5 * win.sum()  # mostly holes: no estimate from a patch
            if not ok.any():
                continue
            hb, wm = hb[ok], wm[ok]
            wsum += float((wm * wm).sum())
        spec = sfft.rfftn(hb * wm, axes=axes, workers=-1)
        acc += (spec.real**2 + spec.imag**2).sum(axis=0)
    acc = _full_from_half(acc, patch)
    if wsum == 0:
        raise HeightMapError(f"the map from {hm.source} has no patch with enough valid samples")
    p = _box(np.fft.fftshift(acc * cell / ((2 * math.pi) ** h.ndim * wsum)), smooth)
    dk = tuple(2 * math.pi / (n * d) for n, d in zip(patch, hm.spacing, strict=True))
    k0 = tuple(-(n // 2) * s for n, s in zip(patch, dk, strict=True))
    return _symmetric_extended(p), k0, dk, patch
