"""RGL ``.bsdf`` files for Mitsuba 3's ``measured`` plugin (Dupuy & Jakob 2018), and a reader.

The format (a Mitsuba "tensor file") and how ``measured`` reads it:

* ``theta_i`` [rad] and ``phi_i`` [rad] are the incident-direction nodes; one ``phi_i`` node
  means an isotropic material, more nodes span ``[−π, −π + 2π/r]`` where ``r`` ∈ {1, 2, 4}
  is the symmetry ``measured`` folds directions into (``r = 2``: f invariant under a rotation
  by π about the normal, true of every stationary random surface; ``r = 4``: mirror symmetry
  in x and y too, true of axis-aligned anisotropic statistics).
* ``ndf`` (2-D) and ``sigma`` (2-D) tabulate a microfacet distribution D(m) [1/sr] and its
  projected area σ(wi) = ∫ D(m) max(0, wi·m) dω_m on the unit square
  ``u = (√(2θ/π), (φ + π)/2π)``; ``vndf`` (4-D, one slice per incident node) is the visible
  normal density D_wi(m) = max(0, wi·m) D(m)/σ(wi) in that square, which ``measured`` turns
  into a sample warp ``s ∈ [0,1]² → m`` (a continuous marginal/conditional warp,
  ``Marginal2D`` in Mitsuba's ``distr_2d.h``).
* ``spectra`` (5-D: φi, θi, λ, s_y, s_x, with ``wavelengths`` [nm]) or ``rgb`` (same, 3
  channels, no ``wavelengths`` field) hold, at the nodes of the sample square ``s``, the value
  whose product with ``ndf(m)/(4 sigma(wi))`` is ``f_r · cosθo`` (``jacobian = 1``);
  ``luminance`` (4-D) is the density ``measured`` samples ``s`` from before warping it.

Here the microfacet distribution is a *proxy*: a Beckmann distribution about 1.5 times wider
than the lobe being stored (a narrower one breaks the fit badly), so that the stored ratio
``f_r cosθo · 4σ/D`` is smooth and bilinear interpolation in ``s`` is accurate; sample-square
nodes whose mirror direction falls below the horizon are filled from their valid neighbours
(zeroing them costs ~18 % at the 90th percentile). With 32 θi × 64² nodes the file reproduces
``roughconductor`` to a median of 0.02 % (see ``tests/test_export_rgl.py``).

Directions are in the renderer frame (normal +z, both pointing away from the surface, mirror
at φo = φi + π); ``f_r`` [1/sr]. Wavelengths are metres at this module's interface and
nanometres inside the file.

Reading (:func:`read_rgl`): the format is fixed by Mitsuba and has no checksum, so a file is
checked for what ``measured`` needs and what any BRDF satisfies, and rejected
(:class:`RglFormatError`, naming the file and what is wrong) when it fails: the field table
lies inside the file, every field lies after it, no two overlap, and the file ends with its
last field (at most 7 bytes of alignment after it); the fields have the dtypes and shapes
``measured`` reads; ``theta_i`` rises within ``[0, π/2]``, ``phi_i`` within ``[−π, π]``,
``wavelengths`` are positive and rising; every float field is finite; ``ndf``, ``vndf`` and
``luminance`` are ``≥ 0``, ``sigma > 0``; the stored values are ``≥ 0`` (the writer clips
out-of-gamut RGB to 0); every ``vndf`` and ``luminance`` slice
has mass (``measured`` normalizes them into sample warps); ``jacobian`` is 0 or 1; and the
mean stored value over each incident node's sample square — the directional albedo
``∫ f_r cosθo dωo`` when ``jacobian = 1``, since the warp maps the uniform square onto
``D_wi(m)`` and ``dωo = 4 (wi·m) dωm`` — is at most :data:`RGL_ALBEDO_MAX` = 10⁶. That bound
is loose on purpose: the node mean is exact only when the proxy distribution fits the lobe
(``≈ 0.93`` for the gold GO table of the tests, whose albedo is 0.92–0.93), and a badly fitted
proxy (e.g. a Lambertian stored with α = 0.05) gives means of ~10⁴; a damaged float32 exponent
gives 10²⁰ and more.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..io import atomic_path
from .colour import RGB_LUMINANCE, VISIBLE_NM, spectrum_to_rgb_weights
from .rgl_warp import (
    beckmann_d,
    beckmann_sigma,
    bilinear,
    direction,
    estimate_alpha,
    fill_from_neighbours,
    marginal2d_sample,
    theta2u,
    u2phi,
    u2theta,
)
from .source import BrdfFunction, as_brdf_source

__all__ = [
    "BrdfFunction",
    "RGL_ALBEDO_MAX",
    "RglFormatError",
    "read_rgl",
    "read_tensor_file",
    "write_rgl",
]

_MAGIC = b"tensor_file\0"
_DTYPES = {
    1: np.uint8,
    2: np.int8,
    3: np.uint16,
    4: np.int16,
    5: np.uint32,
    6: np.int32,
    7: np.uint64,
    8: np.int64,
    9: np.float16,
    10: np.float32,
    11: np.float64,
}
_CODES = {np.dtype(v): k for k, v in _DTYPES.items()}
_ALIGN = 8
#: Largest accepted mean stored value over an incident node's sample square (module docstring).
RGL_ALBEDO_MAX = 1.0e6


class RglFormatError(ValueError):
    """A file is not an RGL ``.bsdf`` tensor file that Mitsuba's ``measured`` can load."""


# --------------------------------------------------------------------------- writer


@dataclass(frozen=True)
class _Grid:
    theta_i: np.ndarray  # [rad]
    phi_i: np.ndarray  # [rad]
    alpha: tuple[float, float]  # proxy Beckmann (α_x, α_y)
    isotropic: bool


_N_NDF_THETA = 512
_N_NDF_PHI = 128
_SLICES_PER_CHUNK = 8


def _proxy_tables(grid: _Grid) -> tuple[np.ndarray, np.ndarray]:
    """``ndf`` and ``sigma`` on the unit square (rows φ, columns θ), float32."""
    ax, ay = grid.alpha
    n_phi = 2 if ax == ay else _N_NDF_PHI
    ut = np.linspace(0, 1, _N_NDF_THETA)
    up = np.linspace(0, 1, n_phi)
    w = direction(u2theta(ut)[None, :], u2phi(up)[:, None])
    return (
        beckmann_d(w, ax, ay).astype(np.float32),
        beckmann_sigma(w, ax, ay).astype(np.float32),
    )


def _vndf_slices(grid: _Grid, wi: np.ndarray, n: int) -> np.ndarray:
    """Visible-normal density in the unit square of m, one (n, n) slice per incident node."""
    ax, ay = grid.alpha
    u = np.linspace(0, 1, n)
    th = u2theta(u)[None, :]
    rel = u2phi(u)[:, None]
    phi_wi = np.arctan2(wi[..., 1], wi[..., 0])
    m = direction(th, rel + (phi_wi[..., None, None] if grid.isotropic else 0.0))
    dot = np.maximum(np.sum(wi[..., None, None, :] * m, -1), 0.0)
    sig = beckmann_sigma(wi, ax, ay)[..., None, None]
    dens = dot * beckmann_d(m, ax, ay) / sig * (2 * math.pi**2) * u[None, :] * np.sin(th)
    return dens.astype(np.float32)


def _incident(grid: _Grid) -> np.ndarray:
    return direction(grid.theta_i[None, :], grid.phi_i[:, None])  # (n_phi, n_theta, 3)


def _stored_values(source, grid, ndf, sigma, vndf, n, weights) -> np.ndarray:
    """``f_r cosθo · 4σ(wi)/D(m)`` at the sample-square nodes, (n_phi, n_theta, C, n, n)."""
    wi_all = _incident(grid)
    s = np.linspace(0, 1, n)
    sx, sy = (a.ravel() for a in np.meshgrid(s, s))  # sy along rows, sx along columns
    n_phi, n_theta = wi_all.shape[:2]
    wi_flat = wi_all.reshape(-1, 3)
    vflat = vndf.reshape(-1, *vndf.shape[2:]).astype(float)
    c_out = weights.shape[0] if weights is not None else source.n_channels
    out = np.empty((wi_flat.shape[0], c_out, n, n))
    valid = np.empty((wi_flat.shape[0], n, n), dtype=bool)
    for start in range(0, wi_flat.shape[0], _SLICES_PER_CHUNK):
        sl = slice(start, min(start + _SLICES_PER_CHUNK, wi_flat.shape[0]))
        wi = wi_flat[sl]
        k = wi.shape[0]
        ux, uy = marginal2d_sample(vflat[sl], np.tile(sx, (k, 1)), np.tile(sy, (k, 1)))
        phi_wi = np.arctan2(wi[:, 1], wi[:, 0])[:, None]
        m = direction(u2theta(ux), u2phi(uy) + (phi_wi if grid.isotropic else 0.0))
        wi_b = np.broadcast_to(wi[:, None, :], m.shape)
        dot = np.sum(wi_b * m, -1)
        wo = 2 * dot[..., None] * m - wi_b
        wo /= np.linalg.norm(wo, axis=-1, keepdims=True)
        d = bilinear(ndf, ux, uy)  # φ coordinate: relative (isotropic) or absolute, as in vndf
        sig = bilinear(
            sigma,
            theta2u(np.arccos(np.clip(wi[:, 2], -1, 1))),
            (phi_wi[:, 0] + math.pi) / (2 * math.pi),
        )
        ok = (wo[..., 2] > 1e-7) & (d > 1e-30) & (dot > 0)
        f = np.zeros(ok.shape + (source.n_channels,))
        if ok.any():
            f[ok] = source.evaluate(wi_b[ok], wo[ok])
        if weights is not None:
            f = np.maximum(f @ weights.T, 0.0)  # out-of-gamut components clipped
        val = f * (wo[..., 2] * 4 * sig[:, None] / np.where(ok, d, 1.0))[..., None]
        ok &= np.all(np.isfinite(val), axis=-1)
        out[sl] = np.moveaxis(val, -1, 1).reshape(k, c_out, n, n)
        valid[sl] = ok.reshape(k, n, n)
    if np.any(out[np.broadcast_to(valid[:, None], out.shape)] < 0):
        raise ValueError("the BRDF has negative values; f_r must be >= 0")
    out = fill_from_neighbours(out, valid)
    return out.reshape(n_phi, n_theta, c_out, n, n)


def write_rgl(
    path,
    brdf,
    *,
    channels: str = "spectral",
    n_theta_i: int = 32,
    n_samples: int = 64,
    n_phi_i: int = 16,
    symmetry: int = 2,
    alpha: float | tuple[float, float] | None = None,
    proxy_scale: float = 1.5,
    theta_i_max_deg: float = 87.5,
    description: str | None = None,
) -> Path:
    """Write ``brdf`` as an RGL ``.bsdf`` file for Mitsuba 3's ``measured`` plugin.

    Parameters
    ----------
    path : output file (written atomically).
    brdf : an emscatter BRDF table or a :class:`BrdfFunction` (the incoherent part only: the
        coherent delta lobe has no place in this format).
    channels : ``"spectral"`` (``spectra`` + ``wavelengths``; for Mitsuba's spectral
        variants) or ``"rgb"`` (linear sRGB under D65, :func:`spectrum_to_rgb_weights`; for the
        RGB variants).
    n_theta_i : incident elevation nodes, uniform over ``[0, theta_i_max_deg]``.
    n_samples : nodes per side of the sample square (and of the proxy's visible-normal grid).
    n_phi_i : incident azimuth nodes (anisotropic BRDFs only), spanning ``2π/symmetry``.
    symmetry : 1, 2 (f unchanged by a rotation of π about the normal) or 4 (also mirror
        symmetric in x and y); anisotropic only.
    alpha : the lobe's Beckmann roughness (α, or (α_x, α_y)); estimated from the BRDF at
        normal incidence by :func:`estimate_alpha` when ``None``.
    proxy_scale : the proxy distribution's α divided by the lobe's (> 1; 1.5 by default).
    theta_i_max_deg : the last incident node [deg] (``measured`` holds values beyond it).
    description : text stored in the file.
    """
    source = as_brdf_source(brdf)
    channels = _check_choice("channels", channels, ("spectral", "rgb"))
    n_theta_i = _check_count("n_theta_i", n_theta_i, 2)
    n = _check_count("n_samples", n_samples, 4)
    if not 1.0 < float(proxy_scale) <= 4.0:
        raise ValueError(f"proxy_scale must be in (1, 4], got {proxy_scale!r}")
    if not 0 < float(theta_i_max_deg) < 90:
        raise ValueError(f"theta_i_max_deg must be in (0, 90) [deg], got {theta_i_max_deg!r}")
    if channels == "spectral":
        if source.wavelengths is None:
            raise ValueError("channels='spectral' needs a BRDF with wavelengths; this one is RGB")
        lam_nm = source.wavelengths * 1e9
        if lam_nm[0] > VISIBLE_NM[1] or lam_nm[-1] < VISIBLE_NM[0]:
            raise ValueError(
                f"the BRDF's wavelengths {lam_nm[0]:.4g}–{lam_nm[-1]:.4g} nm miss the range "
                f"Mitsuba's spectral variants render, {VISIBLE_NM[0]:g}–{VISIBLE_NM[1]:g} nm"
            )
    if alpha is None:
        ax, ay = estimate_alpha(source)
        if source.isotropic:
            ax = ay = math.sqrt(ax * ay)
    else:
        ax, ay = (alpha, alpha) if np.ndim(alpha) == 0 else tuple(alpha)
        for name, a in (("alpha", ax), ("alpha", ay)):
            if not 0 < float(a) < 10:
                raise ValueError(f"{name} must be in (0, 10), got {a!r}")
    proxy = (
        float(np.clip(ax * proxy_scale, 0.02, 4.0)),
        float(np.clip(ay * proxy_scale, 0.02, 4.0)),
    )
    if source.isotropic:
        phi_i = np.zeros(1)
    else:
        symmetry = _check_choice("symmetry", symmetry, (1, 2, 4))
        n_phi = _check_count("n_phi_i", n_phi_i, 2)
        phi_i = np.linspace(-math.pi, -math.pi + 2 * math.pi / symmetry, n_phi)
    grid = _Grid(
        np.radians(np.linspace(0, theta_i_max_deg, n_theta_i)), phi_i, proxy, source.isotropic
    )
    ndf, sigma = _proxy_tables(grid)
    vndf = _vndf_slices(grid, _incident(grid), n)
    weights = None
    if channels == "rgb" and source.wavelengths is not None:
        weights = spectrum_to_rgb_weights(source.wavelengths)
    values = _stored_values(source, grid, ndf, sigma, vndf, n, weights).astype(np.float32)
    if channels == "rgb":
        lum = np.tensordot(RGB_LUMINANCE, values, axes=([0], [2]))
    else:
        lum = values.mean(axis=2)
    fields = {
        "description": np.frombuffer((description or source.name).encode(), dtype=np.uint8),
        "phi_i": grid.phi_i.astype(np.float32),
        "theta_i": grid.theta_i.astype(np.float32),
        "ndf": ndf,
        "sigma": sigma,
        "vndf": vndf,
        "luminance": np.ascontiguousarray(np.moveaxis(lum, 0, 0), dtype=np.float32),
        "jacobian": np.ones(1, dtype=np.uint8),
    }
    if channels == "rgb":
        fields["rgb"] = values
    else:
        fields["spectra"] = values
        fields["wavelengths"] = (source.wavelengths * 1e9).astype(np.float32)
    with atomic_path(path) as tmp:
        _write_tensor_file(tmp, fields)
    return Path(path)


def _check_count(name: str, value, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}, got {value!r}")
    return int(value)


def _check_choice(name: str, value, allowed: tuple):
    if value not in allowed:
        raise ValueError(f"{name} must be one of {allowed}, got {value!r}")
    return value


# --------------------------------------------------------------------------- tensor files


def _write_tensor_file(path: Path, fields: dict[str, np.ndarray], align: int = 8) -> None:
    """Mitsuba's tensor file: magic, version 1.0, field table, 8-byte aligned little-endian data."""
    arrays = {k: np.ascontiguousarray(v) for k, v in fields.items()}
    header = bytearray(_MAGIC + struct.pack("<BBI", 1, 0, len(arrays)))
    for k, v in arrays.items():
        label = k.encode()
        header += (
            struct.pack("<H", len(label)) + label + struct.pack("<HB", v.ndim, _CODES[v.dtype])
        )
        header += struct.pack("<Q", 0)  # offset, patched below
        header += struct.pack(f"<{v.ndim}Q", *v.shape)
    offsets, pos = [], len(header)
    for v in arrays.values():
        pos = (pos + align - 1) // align * align
        offsets.append(pos)
        pos += v.nbytes
    # patch the offsets in the header
    at = len(_MAGIC) + 6
    for (k, v), off in zip(arrays.items(), offsets, strict=True):
        at += 2 + len(k.encode()) + 3
        header[at : at + 8] = struct.pack("<Q", off)
        at += 8 + 8 * v.ndim
    with open(path, "wb") as fh:
        fh.write(header)
        for v, off in zip(arrays.values(), offsets, strict=True):
            fh.write(b"\0" * (off - fh.tell()))
            fh.write(v.astype(v.dtype.newbyteorder("<"), copy=False).tobytes())


def read_tensor_file(path) -> dict[str, np.ndarray]:
    """All fields of a Mitsuba tensor file, as numpy arrays (raises :class:`RglFormatError`
    for a foreign, truncated or inconsistent file: module docstring)."""
    path = Path(path)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise RglFormatError(f"cannot read {path}: {exc.strerror}") from None
    if raw[: len(_MAGIC)] != _MAGIC:
        raise RglFormatError(f"{path} is not a Mitsuba tensor file (no 'tensor_file' header)")
    try:
        major, minor, count = struct.unpack_from("<BBI", raw, len(_MAGIC))
        if (major, minor) != (1, 0):
            raise RglFormatError(f"{path}: tensor file version {major}.{minor}, expected 1.0")
        at = len(_MAGIC) + 6
        table = []
        for _ in range(count):
            (nlen,) = struct.unpack_from("<H", raw, at)
            label = raw[at + 2 : at + 2 + nlen]
            try:
                name = label.decode()
            except UnicodeDecodeError:
                raise RglFormatError(
                    f"{path} is damaged: field name {label!r} is not text"
                ) from None
            at += 2 + nlen
            ndim, code, offset = struct.unpack_from("<HBQ", raw, at)
            at += 11
            shape = struct.unpack_from(f"<{ndim}Q", raw, at)
            at += 8 * ndim
            if code not in _DTYPES:
                raise RglFormatError(f"{path}: field {name!r} has unknown type code {code}")
            if name in (t[0] for t in table):
                raise RglFormatError(f"{path} is damaged: field {name!r} appears twice")
            table.append((name, shape, np.dtype(_DTYPES[code]).newbyteorder("<"), offset))
    except struct.error:
        raise RglFormatError(f"{path} is truncated inside its field table") from None
    out, spans = {}, []
    for name, shape, dt, offset in table:
        count_ = math.prod(shape)
        size = count_ * dt.itemsize
        if offset + size > len(raw):
            raise RglFormatError(
                f"{path} is truncated: field {name!r} needs bytes {offset}..{offset + size}, "
                f"the file has {len(raw)}"
            )
        if offset < at:
            raise RglFormatError(
                f"{path} is damaged: field {name!r} starts at byte {offset}, inside the field "
                f"table (which ends at {at})"
            )
        spans.append((offset, offset + size, name))
        arr = np.frombuffer(raw, dtype=dt, count=count_, offset=offset)
        out[name] = arr.astype(dt.newbyteorder("="), copy=True).reshape(shape)
    spans.sort()
    for (_, end, a), (start, _, b) in zip(spans, spans[1:], strict=False):
        if start < end:
            raise RglFormatError(f"{path} is damaged: fields {a!r} and {b!r} overlap")
    last = max((end for _, end, _ in spans), default=at)
    if len(raw) - last >= _ALIGN:
        raise RglFormatError(
            f"{path} is longer than its fields: {len(raw)} bytes, the last field ends at {last}"
        )
    return out


_REQUIRED = ("theta_i", "phi_i", "ndf", "sigma", "vndf", "luminance", "description", "jacobian")


def read_rgl(path) -> dict[str, np.ndarray]:
    """Read and check an RGL ``.bsdf`` file the way Mitsuba's ``measured`` checks it.

    Returns the fields (``wavelengths`` in nm, as stored); raises :class:`RglFormatError`
    naming the field and what was expected.
    """
    f = read_tensor_file(path)
    missing = [k for k in _REQUIRED if k not in f]
    spectral = "wavelengths" in f
    data_key = "spectra" if spectral else "rgb"
    if data_key not in f:
        missing.append(data_key)
    if missing:
        raise RglFormatError(f"{path}: missing field(s) {missing} of an RGL .bsdf file")
    n_phi, n_theta = f["phi_i"].shape[0], f["theta_i"].shape[0]
    spec = f[data_key]
    n_ch = f["wavelengths"].shape[0] if spectral else 3
    lum = f["luminance"]

    def is_(name, ndim, dtype=np.float32):
        return f[name].ndim == ndim and f[name].dtype == dtype

    checks = [
        ("description", is_("description", 1, np.uint8), "1-D uint8"),
        ("theta_i", is_("theta_i", 1), "1-D float32 [rad]"),
        ("phi_i", is_("phi_i", 1), "1-D float32 [rad]"),
        ("ndf", is_("ndf", 2), "2-D float32"),
        ("sigma", is_("sigma", 2), "2-D float32"),
        ("vndf", is_("vndf", 4) and f["vndf"].shape[:2] == (n_phi, n_theta),
         f"4-D float32 ({n_phi}, {n_theta}, h, w)"),
        ("luminance", is_("luminance", 4) and lum.shape[:2] == (n_phi, n_theta)
         and lum.shape[2] == lum.shape[3], f"4-D float32 ({n_phi}, {n_theta}, n, n)"),
        (data_key, is_(data_key, 5) and spec.shape[:3] == (n_phi, n_theta, n_ch)
         and spec.shape[3:] == lum.shape[2:], f"5-D float32 ({n_phi}, {n_theta}, {n_ch}, n, n)"),
        ("jacobian", f["jacobian"].shape == (1,) and f["jacobian"].dtype == np.uint8, "one uint8"),
    ]  # fmt: skip
    if spectral:
        ok = f["wavelengths"].ndim == 1 and f["wavelengths"].dtype == np.float32
        checks.append(("wavelengths", ok, "1-D float32 [nm]"))
    for name, ok, want in checks:
        if not ok:
            got = f[name]
            raise RglFormatError(
                f"{path}: field {name!r} is {got.dtype} of shape {got.shape}, expected {want}"
            )
    for name in ("theta_i", "phi_i", "ndf", "sigma", "vndf", "luminance", data_key):
        if not np.all(np.isfinite(f[name])):
            raise RglFormatError(f"{path}: field {name!r} holds NaN or inf")
    _check_physics(path, f, data_key)
    return f


def _check_physics(path, f: dict[str, np.ndarray], data_key: str) -> None:
    """The value checks of :func:`read_rgl` (module docstring)."""

    def fail(what: str):
        raise RglFormatError(f"{path} is damaged: {what}")

    eps = 1e-6
    th, ph = f["theta_i"].astype(float), f["phi_i"].astype(float)
    if th.size == 0 or th.min() < -eps or th.max() > math.pi / 2 + eps or np.any(np.diff(th) <= 0):
        fail(f"theta_i must rise within [0, π/2] [rad], got {np.array2string(th, precision=4)}")
    if ph.size == 0 or ph.min() < -math.pi - eps or ph.max() > math.pi + eps:
        fail(f"phi_i must lie within [−π, π] [rad], got {np.array2string(ph, precision=4)}")
    if np.any(np.diff(ph) <= 0):
        fail(f"phi_i must rise, got {np.array2string(ph, precision=4)}")
    if "wavelengths" in f:
        wl = f["wavelengths"].astype(float)
        if not (np.all(np.isfinite(wl)) and np.all(wl > 0) and np.all(np.diff(wl) > 0)):
            fail(f"wavelengths must be positive and rising [nm], got {wl}")
    for name in ("ndf", "vndf", "luminance"):
        if np.any(f[name] < 0):
            fail(f"field {name!r} has negative values (least {f[name].min():.3g}); it is a density")
    if np.any(f["sigma"] <= 0):
        fail(f"field 'sigma' must be > 0 (a projected area), least {f['sigma'].min():.3g}")
    data = f[data_key].astype(float)
    if np.any(data < 0):
        fail(
            f"field {data_key!r} has {int((data < 0).sum())} negative values (least "
            f"{data.min():.3g}); a BRDF is >= 0"
        )
    for name in ("vndf", "luminance"):
        mass = f[name].astype(float).sum(axis=(-2, -1))
        if np.any(mass <= 0):
            j = tuple(int(i[0]) for i in np.nonzero(mass <= 0))
            fail(f"field {name!r} has an empty slice at (φi, θi) node {j}: no sample warp")
    if int(f["jacobian"][0]) not in (0, 1):
        fail(f"field 'jacobian' must be 0 or 1, got {int(f['jacobian'][0])}")
    n = data.shape[-1]
    w = np.full(n, 1.0 / (n - 1)) if n > 1 else np.ones(1)
    if n > 1:
        w[[0, -1]] *= 0.5
    albedo = np.einsum("...ij,i,j->...", data, w, w)  # trapezoid mean over the sample square
    if albedo.max() > RGL_ALBEDO_MAX:
        j = tuple(int(i[0]) for i in np.nonzero(albedo == albedo.max()))
        fail(
            f"the mean stored value over the sample square (the directional albedo) reaches "
            f"{albedo.max():.3g} at (φi, θi, channel) node {j}, above {RGL_ALBEDO_MAX:g}"
        )
