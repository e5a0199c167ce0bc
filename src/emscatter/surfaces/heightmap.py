"""Measured height maps in: files (through SurfaceTopography's readers) and NumPy arrays.

A :class:`HeightMap` is a profile ``(n,)`` or a map ``(ny, nx)`` of heights [m] on a regular
grid of spacing ``(dx,)`` / ``(dy, dx)`` [m] — emscatter's axis order (axis 0 = y, axis 1 = x,
as :func:`emscatter.surfaces.generate_surface`). SurfaceTopography stores ``(nx, ny)`` with
axis 0 = x; :func:`read_height_map` and :func:`write_height_map` transpose at that boundary.

What is recorded (``HeightMap.detrend``, ``HeightMap.holes``, ``HeightMap.source``):

* **units** come from the file (``µm``, ``nm``, … converted to metres); a file without a
  height unit is an error unless ``unit=`` is given (never a silent "metres");
* **detrending** (least squares over the valid samples): ``"none"``, ``"mean"``, ``"plane"``
  (the default: the tilt of the sample on the stage), ``"quadratic"`` or a polynomial order
  ``0…5`` (total degree in x, y); the coefficients [m, m/m, …] are kept;
* **NaN holes** (unmeasured points): ``holes="reject"`` (default) raises naming the file and
  how many; ``holes="mask"`` keeps a validity mask — the spectrum estimate then weights the
  window by it and the slopes use only pairs of valid neighbours (:mod:`.measured`).

SurfaceTopography (Pastewka et al., https://github.com/ContactEngineering/SurfaceTopography)
is optional at run time: install the ``heightmap`` extra (``pip install
emscatter[heightmap]``) to read files; arrays work without it.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from emscatter.io import atomic_path

__all__ = [
    "HeightMap",
    "HeightMapError",
    "height_map",
    "read_height_map",
    "write_height_map",
    "MIN_SAMPLES",
    "UNITS",
]

#: The fewest samples per axis a spectrum estimate is made from (4 Welch patches of 8).
MIN_SAMPLES = 16

#: Length units SurfaceTopography writes, in metres.
UNITS = {
    "m": 1.0,
    "dm": 1e-1,
    "cm": 1e-2,
    "mm": 1e-3,
    "µm": 1e-6,
    "μm": 1e-6,
    "um": 1e-6,
    "nm": 1e-9,
    "Å": 1e-10,
    "A": 1e-10,
    "pm": 1e-12,
    "km": 1e3,
}

_DETREND = {"none": None, "mean": 0, "plane": 1, "quadratic": 2}
_HOLES = ("reject", "mask")
_EXTRA = (
    "reading height-map files needs SurfaceTopography: install the 'heightmap' extra "
    "(pip install 'emscatter[heightmap]', or pip install SurfaceTopography)"
)


class HeightMapError(ValueError):
    """A height map (file or array) that cannot be used; the message names it and why."""


@dataclass(frozen=True, eq=False)
class HeightMap:
    """A detrended height map with its spacing and the choices made reading it.

    Attributes
    ----------
    heights : ``(n,)`` or ``(ny, nx)`` [m], detrended; 0 at masked points.
    spacing : ``(dx,)`` or ``(dy, dx)`` [m], axis order as ``heights``.
    mask : bool array like ``heights``, True where measured (all True without holes).
    source : the file it was read from, or ``"array"``.
    unit : the height unit of the source (``"m"`` for arrays unless given).
    detrend : ``{"mode": …, "order": …, "coefficients": […]}``, what was removed.
    holes : ``{"policy": "reject"|"mask", "count": int}``.
    """

    heights: np.ndarray
    spacing: tuple[float, ...]
    mask: np.ndarray
    source: str = "array"
    unit: str = "m"
    detrend: dict = field(default_factory=dict)
    holes: dict = field(default_factory=dict)

    @property
    def dimension(self) -> int:
        """1 for a profile, 2 for a map."""
        return self.heights.ndim

    @property
    def shape(self) -> tuple[int, ...]:
        return self.heights.shape

    @property
    def size(self) -> tuple[float, ...]:
        """Physical size per axis ``n·Δ`` [m], axis order as ``heights``."""
        return tuple(n * d for n, d in zip(self.heights.shape, self.spacing, strict=True))

    @property
    def band(self) -> tuple[float, float]:
        """``(2π/L, π/Δx)`` [rad/m]: the wavenumbers the map resolves (the longest side
        and the finest spacing; per-axis values in :meth:`band_per_axis`)."""
        return 2 * math.pi / max(self.size), math.pi / min(self.spacing)

    def band_per_axis(self) -> tuple[tuple[float, float], ...]:
        """``((2π/L, π/Δ), …)`` per axis [rad/m], axis order as ``heights``."""
        pairs = zip(self.size, self.spacing, strict=True)
        return tuple((2 * math.pi / L, math.pi / d) for L, d in pairs)

    def rms_height(self) -> float:
        """Rms height of the valid samples [m] (mean removed by the detrending)."""
        h = self.heights[self.mask]
        return float(np.sqrt(np.mean((h - h.mean()) ** 2)))

    def describe(self) -> str:
        kind = "profile" if self.dimension == 1 else "map"
        sp = " × ".join(f"{d:.4g}" for d in self.spacing)
        return (
            f"{kind} {self.shape} from {self.source}, spacing {sp} m, σ={self.rms_height():.4g} m, "
            f"detrend {self.detrend.get('mode')}, holes {self.holes.get('count', 0)} "
            f"({self.holes.get('policy')})"
        )


# ----------------------------------------------------------------------------- checks
def _where(source: str) -> str:
    return "array" if source == "array" else f"file {source!r}"


def _check_spacing(spacing, ndim: int, source: str) -> tuple[float, ...]:
    if isinstance(spacing, bool | str) or spacing is None:
        raise HeightMapError(
            f"spacing of the {_where(source)} must be a positive number [m] or (dy, dx), "
            f"got {spacing!r}"
        )
    vals = (spacing,) * ndim if np.ndim(spacing) == 0 else tuple(np.ravel(spacing).tolist())
    if len(vals) != ndim:
        want = "(dx,)" if ndim == 1 else "(dy, dx)"
        raise HeightMapError(
            f"spacing of the {_where(source)} must be a number or {want} for ndim={ndim}, "
            f"got {spacing!r}"
        )
    out = []
    for v in vals:
        if isinstance(v, bool) or not isinstance(v, numbers.Real):
            raise HeightMapError(f"spacing must be real and > 0 [m], got {spacing!r}")
        f = float(v)
        if not (math.isfinite(f) and f > 0):
            raise HeightMapError(
                f"spacing of the {_where(source)} must be finite and > 0 [m], got {spacing!r}"
            )
        out.append(f)
    return tuple(out)


def _detrend_order(detrend) -> tuple[str, int | None]:
    if isinstance(detrend, str) and detrend in _DETREND:
        return detrend, _DETREND[detrend]
    if isinstance(detrend, numbers.Integral) and not isinstance(detrend, bool):
        if 0 <= int(detrend) <= 5:
            return f"polynomial-{int(detrend)}", int(detrend)
    raise HeightMapError(
        f"detrend must be one of {sorted(_DETREND)} or a polynomial order 0…5, got {detrend!r}"
    )


def _powers(order: int, ndim: int) -> list[tuple[int, int]]:
    if ndim == 1:
        return [(i, 0) for i in range(order + 1)]
    return [(i, j) for t in range(order + 1) for j in range(t + 1) for i in [t - j]]


def _detrend(h: np.ndarray, mask: np.ndarray, order: int | None, spacing) -> tuple:
    """Least-squares polynomial (total degree ``order`` in x, y [m]) over the valid samples
    removed; returns (heights, coefficients [m/m^(i+j)] for the powers x^i y^j)."""
    if order is None:
        return h, []
    if h.ndim == 1:
        x = np.arange(h.shape[0]) * spacing[0]
        y = np.zeros_like(x)
    else:
        y, x = np.meshgrid(
            np.arange(h.shape[0]) * spacing[0], np.arange(h.shape[1]) * spacing[1], indexing="ij"
        )
    xc, yc = x - x[mask].mean(), y - y[mask].mean()
    pw = _powers(order, h.ndim)
    A = np.stack([xc[mask] ** i * yc[mask] ** j for i, j in pw], axis=1)
    coef, *_ = np.linalg.lstsq(A, h[mask], rcond=None)
    trend = sum(c * xc**i * yc**j for c, (i, j) in zip(coef, pw, strict=True))
    return np.where(mask, h - trend, 0.0), [
        {"x_power": i, "y_power": j, "value": float(c)} for c, (i, j) in zip(coef, pw, strict=True)
    ]


def height_map(
    heights,
    spacing,
    *,
    unit: str = "m",
    detrend="plane",
    holes: str = "reject",
    source: str = "array",
) -> HeightMap:
    """A :class:`HeightMap` from an array ``(n,)`` or ``(ny, nx)`` in ``unit`` (default m)
    with ``spacing`` ``dx`` or ``(dy, dx)`` [m], detrended (module docstring).

    Errors (:class:`HeightMapError`, naming the source): not a real 1-D/2-D array, fewer than
    :data:`MIN_SAMPLES` samples per axis, NaN/inf with ``holes="reject"``, infinite values
    (never maskable), more than half the samples missing, an unknown unit or detrend mode.
    """
    where = _where(source)
    if isinstance(heights, bool | str | bytes) or heights is None:
        raise HeightMapError(f"heights of the {where} must be a real array, got {heights!r}")
    arr = np.asarray(heights)
    if arr.dtype == object or not (
        np.issubdtype(arr.dtype, np.integer) or np.issubdtype(arr.dtype, np.floating)
    ):
        raise HeightMapError(f"heights of the {where} must be real numbers, got dtype {arr.dtype}")
    if arr.ndim not in (1, 2):
        raise HeightMapError(
            f"heights of the {where} must be a profile (n,) or a map (ny, nx), got shape "
            f"{arr.shape}"
        )
    if min(arr.shape) < MIN_SAMPLES:
        raise HeightMapError(
            f"the {where} is too small for a spectrum estimate: shape {arr.shape}, at least "
            f"{MIN_SAMPLES} samples per axis are needed"
        )
    if unit not in UNITS:
        raise HeightMapError(f"unit of the {where} must be one of {sorted(UNITS)}, got {unit!r}")
    if holes not in _HOLES:
        raise HeightMapError(f"holes must be one of {_HOLES}, got {holes!r}")
    mode, order = _detrend_order(detrend)
    sp = _check_spacing(spacing, arr.ndim, source)
    arr = arr.astype(float) * UNITS[unit]
    if np.any(np.isinf(arr)):
        raise HeightMapError(
            f"the {where} has {int(np.isinf(arr).sum())} infinite heights; only NaN holes "
            "(unmeasured points) can be masked"
        )
    mask = ~np.isnan(arr)
    n_holes = int(arr.size - mask.sum())
    if n_holes and holes == "reject":
        raise HeightMapError(
            f"the {where} has {n_holes} NaN holes (unmeasured points) of {arr.size}; pass "
            "holes='mask' to leave them out of the spectrum and slopes, or fill them first"
        )
    if mask.sum() < 0.5 * arr.size:
        raise HeightMapError(
            f"the {where} has {n_holes} NaN holes of {arr.size} samples: more than half is "
            "missing, too little for a spectrum estimate"
        )
    arr = np.where(mask, arr, 0.0)
    h, coef = _detrend(arr, mask, order, sp)
    if order is None:  # no trend removed: the spectrum estimate removes the mean per patch
        pass
    hm = HeightMap(
        heights=h,
        spacing=sp,
        mask=mask,
        source=str(source),
        unit=unit,
        detrend={"mode": mode, "order": order, "coefficients": coef},
        holes={"policy": holes, "count": n_holes},
    )
    if not hm.rms_height() > 0:
        raise HeightMapError(f"the {where} is flat after detrending ({mode}): σ = 0")
    return hm


def _surface_topography():
    try:
        import SurfaceTopography  # noqa: F401  (lazy, optional)
    except ImportError:  # pragma: no cover - exercised where the extra is absent
        raise ImportError(_EXTRA) from None
    return SurfaceTopography


def _read_topography(st, fobj, src: str, channel, unit):
    """(topography, its unit) from an open file through SurfaceTopography's readers."""
    try:
        reader = st.open_topography(fobj)
    except Exception as exc:  # the readers raise many types; the message says which file
        raise HeightMapError(
            f"height-map file {src!r} could not be read by any SurfaceTopography reader "
            f"({type(exc).__name__}: {exc})"
        ) from None
    channels = reader.channels
    ci = reader.default_channel.index if channel is None else channel
    if not isinstance(ci, int) or not 0 <= ci < len(channels):
        raise HeightMapError(
            f"channel of height-map file {src!r} must be an index 0…{len(channels) - 1}, "
            f"got {channel!r}"
        )
    info = channels[ci]
    kw = {"channel_index": ci}
    if info.physical_sizes is None:
        raise HeightMapError(
            f"height-map file {src!r} (channel {ci}) stores no physical size, so its spacing is "
            "unknown; give it to emscatter.surfaces.height_map(array, spacing) instead"
        )
    file_unit = info.unit
    if file_unit is None:
        if unit is None:
            raise HeightMapError(
                f"height-map file {src!r} (channel {ci}) stores no unit; pass unit= (one of "
                f"{sorted(UNITS)}) — emscatter does not assume metres"
            )
        kw["unit"] = unit
        file_unit = unit
    try:
        topo = reader.topography(**kw)
    except Exception as exc:
        raise HeightMapError(
            f"height-map file {src!r} (channel {ci}) could not be read: {type(exc).__name__}: {exc}"
        ) from None
    close = getattr(reader, "close", None)
    if close is not None:
        close()
    return topo, file_unit


def read_height_map(
    path,
    *,
    channel: int | None = None,
    unit: str | None = None,
    detrend="plane",
    holes: str = "reject",
) -> HeightMap:
    """Read a height map through SurfaceTopography (``.x3p``, ``.sur``, ``.opd``, ``.datx``,
    ``.plu``, ``.nc``, ``.gwy``, text, … — its 42 readers) into a :class:`HeightMap` [m].

    Parameters
    ----------
    path : the file.
    channel : the data channel (default: the reader's default channel).
    unit : the height unit when the file does not store one (an error otherwise); ignored,
        with the file's own unit used, when it does.
    detrend, holes : as :func:`height_map`.

    Errors name the file: missing, unreadable (no reader recognised it), without physical
    sizes or units, a nonuniform (line-scan) topography, NaN holes (``holes="reject"``), too
    small.
    """
    st = _surface_topography()
    p = Path(path).expanduser()
    src = str(path)
    if not p.is_file():
        raise HeightMapError(f"height-map file {src!r} does not exist (or is not a file)")
    with open(p, "rb") as fobj:  # our handle, closed here (the readers may leave theirs)
        topo, file_unit = _read_topography(st, fobj, src, channel, unit)
    if not hasattr(topo, "pixel_size") or not hasattr(topo, "heights"):
        raise HeightMapError(f"height-map file {src!r} is not a uniform grid (line scans are not)")
    if file_unit not in UNITS:
        raise HeightMapError(
            f"height-map file {src!r} has unit {file_unit!r}; known: {sorted(UNITS)}"
        )
    h = np.asarray(topo.heights(), dtype=float)
    if np.ma.isMaskedArray(topo.heights()):
        h = np.ma.filled(topo.heights().astype(float), np.nan)
    scale = UNITS[file_unit]
    px = np.atleast_1d(np.asarray(topo.pixel_size, dtype=float)) * scale
    if h.ndim == 2:  # SurfaceTopography (nx, ny), axis 0 = x → emscatter (ny, nx)
        h, spacing = h.T, (float(px[1]), float(px[0]))
    else:
        spacing = (float(px[0]),)
    return height_map(h, spacing, unit=file_unit, detrend=detrend, holes=holes, source=src)


def write_height_map(hm: HeightMap, path, *, unit: str = "µm") -> Path:
    """Write ``hm`` atomically through SurfaceTopography: ``.nc`` (netCDF) or ``.x3p``
    (ISO 25178-72), heights and sizes in ``unit``; masked points become NaN. Returns the path.
    """
    st = _surface_topography()
    if not isinstance(hm, HeightMap):
        raise TypeError(f"hm must be a HeightMap, got {type(hm).__name__}")
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix not in (".nc", ".x3p"):
        raise ValueError(f"path must end in .nc or .x3p, got {str(path)!r}")
    if unit not in UNITS:
        raise ValueError(f"unit must be one of {sorted(UNITS)}, got {unit!r}")
    s = UNITS[unit]
    h = np.where(hm.mask, hm.heights, np.nan) / s
    if h.ndim == 2:
        h = h.T  # → SurfaceTopography (nx, ny)
        sizes = (hm.size[1] / s, hm.size[0] / s)
    else:
        sizes = (hm.size[0] / s,)
    topo = st.Topography(h, sizes, unit=unit, periodic=False)
    with atomic_path(p) as tmp:
        tmp.unlink(missing_ok=True)
        (topo.to_netcdf if suffix == ".nc" else topo.to_x3p)(str(tmp))
    return p
