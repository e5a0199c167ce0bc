"""The slope density of a height map: what geometric optics takes in place of the Gaussian.

:func:`measure_slope_density` builds it from the map's cell-centred finite differences
(:func:`~.estimators.cell_slopes`): their histogram smoothed by a variance-preserving Gaussian
kernel (Jones 1991) whose width follows Scott's rule on the number of *independent* slope
samples ``N/Σρ_ζ²`` (:func:`~.estimators.slope_acf_sum`), and beyond the well-sampled slopes the
recorded tail (:mod:`.slope_tail`). :func:`kernel_density` evaluates the kernel estimate on its
grid (bilinear between bin centres, 0 beyond it). :mod:`.roughness` documents the choices.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import partial

import numpy as np

from emscatter.surfaces.heightmap import HeightMap, HeightMapError
from emscatter.surfaces.measured.bilinear import bilinear
from emscatter.surfaces.measured.estimators import cell_slopes, density_estimate, slope_acf_sum
from emscatter.surfaces.measured.slope_tail import fit_tail

__all__ = ["SlopeDensity", "measure_slope_density", "kernel_density"]


@dataclass(frozen=True)
class SlopeDensity:
    """A map's slope density: ``density`` [-] on ``grid`` (``((x0, step), (y0, step) | None)``
    in slopes), the map's mean-square slopes ``mean_square`` (x, y) [-], ``info`` (how it was
    built: bins, bandwidth, effective samples, the tail record) and ``tail`` (the
    :func:`~.slope_tail.fit_tail` record, or None for ``slope_tail="none"``)."""

    density: np.ndarray
    grid: tuple
    mean_square: tuple
    info: dict
    tail: dict | None


def kernel_density(density: np.ndarray, grid: tuple, zx, zy=None) -> np.ndarray:
    """The kernel estimate ``density`` on its ``grid`` at slopes ``(zx, zy)`` [-] (a 1-D grid,
    ``(gx, None)``, ignores ``zy``), bilinear between bin centres, 0 beyond the grid."""
    if grid[1] is None:
        (x0, sx), _ = grid
        v = bilinear(density, x0, sx, zx)
    else:
        (x0, sx), (y0, sy) = grid
        zx, zy = np.broadcast_arrays(zx, zy)
        v = bilinear(density, x0, sx, zx, y0, sy, zy)
    return np.nan_to_num(v, nan=0.0)


def _check_bandwidth(slope_bandwidth) -> None:
    if slope_bandwidth is not None and (
        isinstance(slope_bandwidth, bool)
        or not isinstance(slope_bandwidth, (int, float))
        or not 0 <= slope_bandwidth <= 2
    ):
        raise ValueError(
            f"slope_bandwidth must be None (Scott's rule) or a number 0…2 (rms slopes; 0: the "
            f"raw histogram), got {slope_bandwidth!r}"
        )


def measure_slope_density(
    hm: HeightMap, *, slope_bins: int | None, slope_bandwidth: float | None, slope_tail: str
) -> SlopeDensity:
    """The slope density of ``hm`` (parameters as :func:`~.roughness.measured_roughness`'s:
    ``slope_bins`` per axis or None for 3 per kernel rms, ``slope_bandwidth`` in rms slopes or
    None for Scott's rule, ``slope_tail`` one of :data:`~.slope_tail.SLOPE_TAILS`)."""
    _check_bandwidth(slope_bandwidth)
    zx, zy = cell_slopes(hm)
    n_sl = zx.size
    n_eff = n_sl / slope_acf_sum(hm, zx, zy)
    if slope_bandwidth is None:
        b_rule = (4 / 3) ** 0.2 * n_eff**-0.2 if hm.dimension == 1 else n_eff ** (-1 / 6)
    else:
        b_rule = float(slope_bandwidth)
    if slope_bins:
        bins = slope_bins
    elif b_rule > 0:  # ≥ 3 bins per kernel rms over the (6 + 4b) rms half-width
        bins = int(np.clip(math.ceil(6 * (6 + 4 * b_rule) / b_rule), 21, 301))
    else:
        bins = int(np.clip(2 * round(n_sl**0.25), 21, 201))
    dens, gx, gy, lost, b_used = density_estimate(zx, zy, bins, b_rule, n_eff)
    mss = (float(np.mean(zx * zx)), float(np.mean(zy * zy)) if zy is not None else 0.0)
    info = {"slope_bins": bins, "slopes_outside_histogram": float(lost),
            "slope_bandwidth": b_used, "slope_samples_effective": float(n_eff),
            "slope_density": "histogram" if b_used == 0 else "variance-preserving Gaussian "
            "kernel estimate (Jones 1991), bandwidth "
            + ("Scott's rule" if slope_bandwidth is None else "given")}  # fmt: skip
    rec = None
    if slope_tail != "none":
        rms = tuple(math.sqrt(v) for v in mss[: hm.dimension])
        grids = (gx,) if gy is None else (gx, gy)
        half = tuple((g[0] * -1) / r for g, r in zip(grids, rms, strict=True))
        inner = partial(kernel_density, dens, (gx, gy))
        try:
            rec = fit_tail(inner, slope_tail, zx, zy, n_eff, half, rms)
        except ValueError as exc:
            raise HeightMapError(f"the map from {hm.source}: no {slope_tail} slope tail ({exc}); "
                                 "use slope_tail='none'") from None  # fmt: skip
    return SlopeDensity(density=dens, grid=(gx, gy), mean_square=mss, info=info, tail=rec)
