"""MERL ``.binary`` BRDF files (Matusik, Pfister, Brand & McMillan 2003): writer and reader.

Format (the MERL database's ``BRDFRead.cpp``): three little-endian ``int32`` dimensions
``(90, 90, 180)`` = (θh, θd, φd) bins, then ``3 × 90·90·180`` ``float64`` values, all red, then
all green, then all blue, each array in C order ``[θh, θd, φd]``. A stored value ``s`` means
``f_r = s × scale`` with the standard channel scales ``(1/1500, 1.15/1500, 1.66/1500)``.
Bins (Rusinkiewicz's half/difference angles, isotropic so ``φh = 0``): θh index
``⌊90 √(θh/(π/2))⌋``, θd index ``⌊90 θd/(π/2)⌋``, φd index ``⌊180 φd/π⌋`` with
``φd ∈ [0, π)`` (``φd`` and ``φd + π`` are the same by reciprocity), each clamped to the range.

Export samples a table at each bin's centre in index space (``θh = ((j + ½)/90)² π/2``, …)
through :meth:`BrdfTable.evaluate`; bins whose directions fall below the horizon hold 0.
Channels: a single-wavelength table is grey; a three-wavelength table gives (R, G, B) =
(longest, middle, shortest) wavelength; otherwise pass ``channel_wavelengths=(λ_R, λ_G,
λ_B)`` [m] (interpolated in the table) or ``rgb_weights`` (3 × n_wl, e.g. render's
``emscatter.brdf.colour.spectrum_to_rgb_weights``). The coherent delta lobe cannot be
represented in MERL bins and is not written.

The format has no checksum and is read by other programs (Mitsuba, the MERL tools), so
:func:`read_merl` checks instead what any MERL BRDF must satisfy, and rejects a file that
fails (:class:`MerlFormatError` naming the file and what is wrong): the 12-byte header states
``(90, 90, 180)``; the file is exactly ``12 + 8 × 3·90·90·180`` bytes; every value is finite
and ``≥ 0``; and every ``f_r`` is at most :data:`MERL_F_MAX` = 10⁷ sr⁻¹ — the most an
energy-conserving BRDF can hold over a MERL bin: the smallest bin's outgoing cone (θh bin 0,
``θh < (1/90)² π/2``, so ``wo`` within 2θh ≈ 3.9·10⁻⁴ rad of the mirror direction) spans
≈ 4.8·10⁻⁷ sr, and ``f_r cosθo Ω ≤ 1`` gives ``f_r ≲ 2·10⁶ sr⁻¹``. A directional-albedo check
is not made: nearest-bin sums over the tiny near-specular bins misestimate narrow lobes by
orders of magnitude. Damage of a double's sign or exponent (what a flipped or overwritten byte
in its upper two bytes does) fails these checks; a change of low mantissa bits is harmless
and cannot be seen. The measured database marks unmeasured bins with negative values: pass
``allow_negative=True`` to read such files as they are.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..io import atomic_path
from .table import BrdfTable

__all__ = [
    "MERL_SHAPE",
    "MERL_SCALES",
    "MERL_F_MAX",
    "MerlFormatError",
    "MerlBrdf",
    "write_merl",
    "read_merl",
    "merl_bin_directions",
    "merl_indices",
]

MERL_SHAPE = (90, 90, 180)
MERL_SCALES = np.array([1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0])
_HEADER = 12
#: Largest ``f_r`` [1/sr] a MERL bin of an energy-conserving BRDF can hold (module docstring).
MERL_F_MAX = 1.0e7


class MerlFormatError(ValueError):
    """A file is not a complete MERL ``.binary`` BRDF."""


def _rot_y(v, a):
    c, s = np.cos(a), np.sin(a)
    x, y, z = v[..., 0], v[..., 1], v[..., 2]
    return np.stack([x * c + z * s, y, z * c - x * s], axis=-1)


def merl_bin_directions() -> tuple[np.ndarray, np.ndarray]:
    """``(wi, wo)`` (renderer frame, unit, shape ``(90, 90, 180, 3)``) at the bin centres."""
    nh, nd, nphi = MERL_SHAPE
    th = ((np.arange(nh) + 0.5) / nh) ** 2 * (0.5 * math.pi)
    td = (np.arange(nd) + 0.5) / nd * (0.5 * math.pi)
    pd = (np.arange(nphi) + 0.5) / nphi * math.pi
    TH, TD, PD = np.meshgrid(th, td, pd, indexing="ij")
    diff = np.stack([np.sin(TD) * np.cos(PD), np.sin(TD) * np.sin(PD), np.cos(TD)], axis=-1)
    wi = _rot_y(diff, TH)  # φh = 0: wi = R_y(θh) d
    h = np.stack([np.sin(TH), np.zeros_like(TH), np.cos(TH)], axis=-1)
    wo = 2.0 * np.sum(wi * h, axis=-1, keepdims=True) * h - wi
    return wi, wo


def merl_indices(wi, wo) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """MERL bin indices ``(θh, θd, φd)`` of direction pairs (the reference lookup)."""
    wi = np.asarray(wi, float)
    wo = np.asarray(wo, float)
    wi = wi / np.linalg.norm(wi, axis=-1, keepdims=True)
    wo = wo / np.linalg.norm(wo, axis=-1, keepdims=True)
    h = wi + wo
    h = h / np.linalg.norm(h, axis=-1, keepdims=True)
    theta_h = np.arccos(np.clip(h[..., 2], -1, 1))
    phi_h = np.arctan2(h[..., 1], h[..., 0])
    c, s = np.cos(-phi_h), np.sin(-phi_h)
    x, y, z = wi[..., 0], wi[..., 1], wi[..., 2]
    tmp = np.stack([x * c - y * s, x * s + y * c, z], axis=-1)  # R_z(−φh) wi
    d = _rot_y(tmp, -theta_h)
    theta_d = np.arccos(np.clip(d[..., 2], -1, 1))
    phi_d = np.arctan2(d[..., 1], d[..., 0])
    phi_d = np.where(phi_d < 0, phi_d + math.pi, phi_d)
    nh, nd, nphi = MERL_SHAPE
    ih = np.clip(np.sqrt(np.maximum(theta_h, 0) / (0.5 * math.pi) * nh * nh), 0, nh - 1)
    idd = np.clip(theta_d / (0.5 * math.pi) * nd, 0, nd - 1)
    ip = np.clip(phi_d / math.pi * nphi, 0, nphi - 1)
    return ih.astype(np.intp), idd.astype(np.intp), ip.astype(np.intp)


@dataclass(frozen=True)
class MerlBrdf:
    """A MERL BRDF as read from disk: ``raw`` the stored doubles ``(3, 90, 90, 180)`` (exactly
    the file's), ``values`` = ``raw × MERL_SCALES`` [1/sr] per channel (R, G, B)."""

    raw: np.ndarray

    @property
    def values(self) -> np.ndarray:
        return self.raw * MERL_SCALES[:, None, None, None]

    def evaluate(self, wi, wo) -> np.ndarray:
        """``f_r`` [1/sr], shape ``(3, ...)`` (R, G, B), by the reference bin lookup; 0 below
        the horizon."""
        wi = np.asarray(wi, float)
        wo = np.asarray(wo, float)
        ih, idd, ip = merl_indices(wi, wo)
        out = self.values[:, ih, idd, ip]
        below = (wi[..., 2] <= 0) | (wo[..., 2] <= 0)
        return np.where(below, 0.0, out)


def _channel_values(table: BrdfTable, channel_wavelengths, rgb_weights):
    wi, wo = merl_bin_directions()
    if rgb_weights is not None:
        w = np.asarray(rgb_weights, dtype=float)
        if w.shape != (3, table.wavelengths.size):
            raise ValueError(
                f"rgb_weights must have shape (3, {table.wavelengths.size}), got {w.shape}"
            )
        f = table.evaluate(wi, wo)
        return np.tensordot(w, f, axes=1)
    if channel_wavelengths is None:
        n = table.wavelengths.size
        if n == 1:
            channel_wavelengths = np.repeat(table.wavelengths, 3)
        elif n == 3:
            channel_wavelengths = table.wavelengths[::-1]  # R = longest, B = shortest
        else:
            raise ValueError(
                f"a MERL file has three channels but the table has {n} wavelengths: pass "
                "channel_wavelengths=(λ_R, λ_G, λ_B) [m] or rgb_weights (3 × n_wl)"
            )
    lam = np.asarray(channel_wavelengths, dtype=float)
    if lam.shape != (3,):
        raise ValueError(f"channel_wavelengths must be three wavelengths [m], got {lam!r}")
    return table.evaluate(wi, wo, wavelength=lam)


def _write_payload(fh, raw: np.ndarray) -> None:
    fh.write(np.array(MERL_SHAPE, dtype="<i4").tobytes())
    fh.write(np.ascontiguousarray(raw, dtype="<f8").tobytes())


def write_merl(
    table: BrdfTable,
    path: str | os.PathLike,
    *,
    channel_wavelengths=None,
    rgb_weights=None,
) -> Path:
    """Write an isotropic ``table`` as a MERL ``.binary`` file (atomically); returns the path.
    Channels: module docstring."""
    if not isinstance(table, BrdfTable):
        raise TypeError(f"table must be a BrdfTable, got {type(table).__name__}")
    if not table.isotropic:
        raise ValueError("MERL files hold isotropic BRDFs; this table is anisotropic")
    path = Path(path)
    f = _channel_values(table, channel_wavelengths, rgb_weights)
    raw = f / MERL_SCALES[:, None, None, None]
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:
        _write_payload(fh, raw)
    return path


def write_merl_raw(raw: np.ndarray, path: str | os.PathLike) -> Path:
    """Write stored MERL values ``raw`` (3, 90, 90, 180) as they are (atomically)."""
    raw = np.asarray(raw, dtype=float)
    if raw.shape != (3, *MERL_SHAPE):
        raise ValueError(f"raw MERL data must have shape {(3, *MERL_SHAPE)}, got {raw.shape}")
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:
        _write_payload(fh, raw)
    return Path(path)


def _where(mask: np.ndarray) -> str:
    c, ih, idd, ip = (int(i[0]) for i in np.nonzero(mask))
    return f"channel {'RGB'[c]}, bin (θh {ih}, θd {idd}, φd {ip})"


def read_merl(path: str | os.PathLike, *, allow_negative: bool = False) -> MerlBrdf:
    """Read a MERL ``.binary`` file; :class:`MerlFormatError` naming the file and what is
    wrong for a truncated, foreign or damaged one (checks: module docstring).

    ``allow_negative``: accept negative values (the measured database's marks of unmeasured
    bins; kept as they are in ``raw``); by default they are an error, as nothing emscatter
    writes has them."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no such MERL file: {str(path)!r}")
    data = path.read_bytes()
    name = repr(str(path))
    if len(data) < _HEADER:
        raise MerlFormatError(
            f"{name} is not a MERL BRDF: {len(data)} bytes, shorter than the 12-byte header"
        )
    dims = tuple(int(d) for d in np.frombuffer(data[:_HEADER], dtype="<i4"))
    if dims != MERL_SHAPE:
        raise MerlFormatError(
            f"{name} is not a MERL BRDF: header dimensions {dims}, expected {MERL_SHAPE}"
        )
    n = 3 * int(np.prod(MERL_SHAPE))
    want = _HEADER + 8 * n
    if len(data) != want:
        what = "truncated" if len(data) < want else "longer than a MERL BRDF"
        raise MerlFormatError(f"{name} is {what}: {len(data)} bytes, expected {want}")
    raw = np.frombuffer(data[_HEADER:], dtype="<f8").reshape(3, *MERL_SHAPE).copy()
    bad = ~np.isfinite(raw)
    if bad.any():
        raise MerlFormatError(
            f"{name} is damaged: {int(bad.sum())} values are NaN or inf (first at {_where(bad)})"
        )
    if not allow_negative:
        neg = raw < 0
        if neg.any():
            raise MerlFormatError(
                f"{name} is damaged: {int(neg.sum())} values are negative (first "
                f"{raw[neg][0]:.3g} at {_where(neg)}); a BRDF is >= 0 (measured-database files "
                "mark unmeasured bins so: read them with allow_negative=True)"
            )
    f = raw * MERL_SCALES[:, None, None, None]
    big = f > MERL_F_MAX
    if big.any():
        raise MerlFormatError(
            f"{name} is damaged: {int(big.sum())} values exceed {MERL_F_MAX:g} 1/sr, more than "
            f"an energy-conserving BRDF can hold in a MERL bin (largest {f.max():.3g} 1/sr, "
            f"first at {_where(big)})"
        )
    raw.setflags(write=False)
    return MerlBrdf(raw=raw)
