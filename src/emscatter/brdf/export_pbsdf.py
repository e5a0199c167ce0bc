"""Polarized ``.pbsdf`` files for Mitsuba 3's ``measured_polarized`` plugin, and a reader.

The format is the one of the KAIST pBRDF data set (Baek et al., "Image-based acquisition and
modeling of polarimetric reflectance", ACM TOG 39(4), 2020) as Mitsuba 3 reads it
(``src/bsdfs/measured_polarized.cpp``): a Mitsuba tensor file with

* ``phi_d``, ``theta_d``, ``theta_h``: float32, shape ``(1, n)`` each, the Rusinkiewicz
  nodes [rad] (any rising nodes: Mitsuba interpolates linearly between them and clamps
  outside them, ``Marginal2D`` in ``distr_2d.h``);
* ``wvls``: uint16, shape ``(5,)``, wavelengths [nm]. Mitsuba reads **exactly five** (a fixed
  ``wavelengths[5]`` array: fewer reads past the field, more leaves nodes undefined), and
  clamps outside the first and last;
* ``M``: float32, shape ``(n_phi_d, n_theta_d, n_theta_h, 5, 4, 4)``, C order, the Mueller
  BRDF ``M[i, j]`` [1/sr] (no cosine; Mitsuba multiplies by cosθ of the light direction).

Geometry, as ``measured_polarized`` evaluates (radiance transport): the light arrives along
``−L`` (``L`` = Mitsuba's ``wo`` = emscatter's renderer ``wi``) and leaves along ``V``
(``si.wi`` = our ``wo``); ``h = (L + V)/|L + V|``, ``θh = ∠(n, h)``, ``θd = ∠(h, L)``, and
``φd`` is the azimuth of ``L`` about ``h`` in the frame ``b̂ = n × h/|n × h|``, ``t̂ = b̂ × h``
(``cosφd = t̂·L⊥``, ``sinφd = b̂·L⊥``), so ``φd ∈ [−π, π]``. Inverting it at ``φh = 0``::

    h = (sinθh, 0, cosθh),  d = cosφd t̂ + sinφd b̂,  L = cosθd h + sinθd d,  V = cosθd h − sinθd d.

The Stokes frames of ``M``: incident wave (propagation ``−L``) and scattered wave
(propagation ``V``) both have the x axis ``normalize((L − V) × (−L))``-based one of the
plugin, which is ``∝ h × d`` (perpendicular to the plane of reflection; independent of θd,
so it has a limit at ``θd = 0``) and ``y = k̂ × x`` (right-handed, Mitsuba's convention);
the plugin then rotates them onto ``stokes_basis``. A GO table is therefore block-diagonal
in this frame (the facet's Fresnel Mueller matrix times the intensity).

Writing (:func:`write_pbsdf`): a :class:`~.mueller.MuellerTable` (emscatter's h/v frames,
(θi, θo, Δφ) grid) is interpolated trilinearly at each node's direction pair, element by
element, with the mirror symmetry of an isotropic surface for ``Δφ < 0`` (``M → D M D``,
``D = diag(1, 1, −1, −1)``; checked against the solver in the tests), linearly in λ onto the
five file wavelengths, and converted to the file's frames (:func:`.mueller.to_frames`). So
``M₀₀`` at a node *is* the unpolarized table's interpolant there (float32 rounding). Nodes
with ``L`` or ``V`` at or below the horizon are filled with the last valid θd node of their
(φd, θh) row (a continuation, so that Mitsuba's interpolation stays accurate up to the
horizon; Baek et al.'s files store NaN there, which the plugin turns into zero for every
cell touching it). Only isotropic tables fit the format.

Reading (:func:`read_pbsdf`) checks what the plugin needs (fields, dtypes, shapes, five rising
wavelengths, rising axes within ``[0, π/2]`` / ``[−π, π]``) and that every finite node is a
plausible Mueller BRDF: ``M₀₀ ≥ 0``, ``|M₀ⱼ| ≤ M₀₀`` and the degree of polarization of the
output for unpolarized input ``≤ 1`` (to :data:`REALIZABLE_TOL`); NaN is allowed only for a
whole node (the data set's invalid-configuration mark). Failures raise
:class:`PbsdfFormatError` naming the file and what is wrong.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..io import atomic_path
from . import grid
from .export_rgl import RglFormatError, _write_tensor_file, read_tensor_file
from .frames import fold_dphi
from .mueller import MuellerTable, to_frames

__all__ = [
    "PbsdfFormatError",
    "REALIZABLE_TOL",
    "DEFAULT_WAVELENGTHS_NM",
    "default_axes",
    "node_directions",
    "pbsdf_mueller",
    "write_pbsdf",
    "read_pbsdf",
]

#: The KAIST data set's five wavelengths [nm] (Baek et al. 2020).
DEFAULT_WAVELENGTHS_NM = (450, 500, 550, 600, 650)
#: Relative slack of the reader's realizability checks (float32 and measurement noise).
REALIZABLE_TOL = 1e-3
_D = np.diag([1.0, 1.0, -1.0, -1.0])
_FIELDS = ("phi_d", "theta_d", "theta_h", "wvls", "M")


class PbsdfFormatError(RglFormatError):
    """A ``.pbsdf`` file that ``measured_polarized`` cannot use (message names the file)."""


def default_axes(n_theta_h: int = 48, n_theta_d: int = 46, n_phi_d: int = 73):
    """``(phi_d, theta_d, theta_h)`` [rad]: φd uniform on ``[−π, π]``, θd uniform on
    ``[0, π/2]``, θh on ``[0, π/2]`` with nodes ``(π/2) u²`` (u uniform: dense near the
    specular peak, where microfacet lobes vary fastest)."""
    for name, n in (("n_theta_h", n_theta_h), ("n_theta_d", n_theta_d), ("n_phi_d", n_phi_d)):
        if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 2:
            raise ValueError(f"{name} must be an integer >= 2, got {n!r}")
    u = np.linspace(0.0, 1.0, n_theta_h)
    return (
        np.linspace(-math.pi, math.pi, n_phi_d),
        np.linspace(0.0, math.pi / 2, n_theta_d),
        0.5 * math.pi * u * u,
    )


def node_directions(phi_d, theta_d, theta_h):
    """Direction pairs and frames of the Rusinkiewicz nodes (module docstring), arrays
    broadcast: ``(L, V, x)`` each ``(..., 3)``: light direction, view direction (both away
    from the surface, renderer frame) and the Stokes x axis of both sides."""
    pd, td, th = np.broadcast_arrays(*(np.asarray(a, float) for a in (phi_d, theta_d, theta_h)))
    zero = np.zeros_like(th)
    h = np.stack([np.sin(th), zero, np.cos(th)], -1)
    b = np.stack([zero, np.ones_like(th), zero], -1)
    t = np.cross(b, h)
    d = np.cos(pd)[..., None] * t + np.sin(pd)[..., None] * b
    L = np.cos(td)[..., None] * h + np.sin(td)[..., None] * d
    V = np.cos(td)[..., None] * h - np.sin(td)[..., None] * d
    x = np.cross(h, d)
    return L, V, x / np.linalg.norm(x, axis=-1, keepdims=True)


def _interp_mueller(mt: MuellerTable, ti, to, dphi, wl_mat):
    """Trilinear interpolation of every Mueller element at renderer angles (φi = 0, φo =
    dphi), mirrored for dphi in (π, 2π) mod 2π; ``wl_mat`` (n_out, n_wl) mixes wavelengths.
    → ``(n_out, 4, 4, N)`` in emscatter's frames."""
    t = mt.table
    n_wl = t.wavelengths.size
    d = np.remainder(dphi, 2 * math.pi)
    mirrored = d > math.pi
    locs = [
        grid.locate_clamped(t.theta_i, ti),
        grid.locate_clamped(t.theta_o, to),
        grid.locate_clamped(t.phi_d, fold_dphi(d)),
    ]
    vals = np.asarray(mt.mueller, float).reshape(n_wl * 16, *t.values.shape[1:])
    m = grid.multilinear(vals, locs).reshape(n_wl, 4, 4, -1)
    m = np.einsum("ow,wabn->oabn", wl_mat, m)
    flip = np.einsum("ij,ojkn,kl->oiln", _D, m, _D)
    return np.where(mirrored, flip, m)


def _wavelength_matrix(table_wl_m: np.ndarray, wavelengths_nm) -> tuple[np.ndarray, np.ndarray]:
    wl = np.asarray(table_wl_m, float) * 1e9
    if wavelengths_nm is None:
        if wl.size != 5 or np.any(np.abs(wl - np.round(wl)) > 1e-3):
            raise ValueError(
                "measured_polarized reads exactly 5 wavelengths in whole nanometres; the table "
                f"has {np.round(wl, 4).tolist()} nm: pass wavelengths_nm=<5 rising integers "
                f"within [{wl[0]:.6g}, {wl[-1]:.6g}] nm> (interpolated linearly), e.g. "
                f"{list(DEFAULT_WAVELENGTHS_NM)} for a table spanning them"
            )
        wavelengths_nm = np.round(wl)
    req = np.asarray(wavelengths_nm, float).reshape(-1)
    if (
        req.size != 5
        or not np.all(np.isfinite(req))
        or np.any(req != np.round(req))
        or np.any(np.diff(req) <= 0)
        or req[0] < 1
        or req[-1] > 65535
    ):
        raise ValueError(
            "wavelengths_nm must be 5 rising whole numbers of nanometres (measured_polarized "
            f"reads exactly five, as uint16), got {wavelengths_nm!r}"
        )
    lo, hi = wl[0] - 1e-6, wl[-1] + 1e-6
    if np.any((req < lo) | (req > hi)):
        raise ValueError(
            f"wavelengths_nm {req.tolist()} must lie within the table's wavelengths "
            f"[{wl[0]:.6g}, {wl[-1]:.6g}] nm (build the table over them)"
        )
    i0, i1, t = grid.locate_clamped(wl, req)
    mat = np.zeros((5, wl.size))
    np.add.at(mat, (np.arange(5), i0), 1 - t)
    np.add.at(mat, (np.arange(5), i1), t)
    return mat, req.astype(np.uint16)


def _check_axis(name, axis, low, high):
    a = np.asarray(axis, float).reshape(-1)
    if a.size < 2 or not np.all(np.isfinite(a)) or np.any(np.diff(a) <= 0):
        raise ValueError(f"{name} must be >= 2 rising finite angles [rad], got {axis!r}")
    if a[0] < low - 1e-12 or a[-1] > high + 1e-12:
        raise ValueError(f"{name} must lie within [{low:.6g}, {high:.6g}] rad, got "
                         f"[{a[0]:.6g}, {a[-1]:.6g}]")  # fmt: skip
    return a


def pbsdf_mueller(mt: MuellerTable, *, phi_d=None, theta_d=None, theta_h=None,
                  wavelengths_nm=None) -> dict[str, np.ndarray]:  # fmt: skip
    """The file's fields (module docstring) from a Mueller table, in float64 ``M`` (the
    writer rounds it to float32): ``{"phi_d", "theta_d", "theta_h", "wvls", "M"}``.
    Axes default to :func:`default_axes`; ``wavelengths_nm`` to the table's (if five)."""
    if not isinstance(mt, MuellerTable):
        raise TypeError(f"mt must be a MuellerTable (build_mueller_table), got "
                        f"{type(mt).__name__}")  # fmt: skip
    if not mt.table.isotropic:
        raise ValueError("measured_polarized stores isotropic pBRDFs only (φd, θd, θh); "
                         "this Mueller table is anisotropic")  # fmt: skip
    dpd, dtd, dth = default_axes()
    pd = _check_axis("phi_d", dpd if phi_d is None else phi_d, -math.pi, math.pi)
    td = _check_axis("theta_d", dtd if theta_d is None else theta_d, 0.0, math.pi / 2)
    th = _check_axis("theta_h", dth if theta_h is None else theta_h, 0.0, math.pi / 2)
    wl_mat, wvls = _wavelength_matrix(mt.table.wavelengths, wavelengths_nm)
    P, T, H = np.meshgrid(pd, td, th, indexing="ij")
    L, V, x = node_directions(P, T, H)
    valid = (L[..., 2] > 1e-9) & (V[..., 2] > 1e-9)
    ti = np.arccos(np.clip(L[..., 2], 0.0, 1.0))
    to = np.arccos(np.clip(V[..., 2], 0.0, 1.0))
    pi_ = np.arctan2(L[..., 1], L[..., 0])
    po = np.arctan2(V[..., 1], V[..., 0])
    sel = valid.reshape(-1)
    m_em = _interp_mueller(mt, ti.reshape(-1)[sel], to.reshape(-1)[sel],
                           (po - pi_).reshape(-1)[sel], wl_mat)  # fmt: skip
    xs = x.reshape(-1, 3)[sel].T
    # rotate the frames about the normal so that φi = 0 (the interpolated matrix's geometry)
    c, s = np.cos(pi_.reshape(-1)[sel]), np.sin(pi_.reshape(-1)[sel])
    xr = np.stack([c * xs[0] + s * xs[1], -s * xs[0] + c * xs[1], xs[2]])
    dphi = (po - pi_).reshape(-1)[sel]
    ti_s, to_s = ti.reshape(-1)[sel], to.reshape(-1)[sel]
    m_file = np.stack([to_frames(m, ti_s, 0.0, to_s, dphi, xr, xr) for m in m_em])  # per λ
    out = np.zeros((5, 4, 4, P.size))
    out[..., sel] = m_file
    out = np.moveaxis(out.reshape(5, 4, 4, *P.shape), (1, 2), (-2, -1))  # (5, φd, θd, θh, 4, 4)
    out = np.moveaxis(out, 0, 3)  # (φd, θd, θh, 5, 4, 4)
    out = _fill_invalid(out, valid)
    return {"phi_d": pd[None], "theta_d": td[None], "theta_h": th[None], "wvls": wvls, "M": out}


def _fill_invalid(m: np.ndarray, valid: np.ndarray) -> np.ndarray:
    """Copy the last valid θd node of each (φd, θh) row into its invalid nodes (a row with
    none takes the filled row of the previous θh)."""
    n_td = valid.shape[1]
    idx = np.where(valid, np.arange(n_td)[None, :, None], -1)
    last = np.maximum.accumulate(idx, axis=1)  # last valid θd index at or before each node
    out = m.copy()
    for k in range(valid.shape[2]):
        if not valid[:, 0, k].all():  # θd = 0 invalid: h at or below the horizon
            out[:, :, k] = out[:, :, k - 1] if k > 0 else 0.0
            continue
        src = last[:, :, k]
        out[:, :, k] = np.take_along_axis(m[:, :, k], src[:, :, None, None, None], axis=1)
    return out


def write_pbsdf(mt: MuellerTable, path, *, phi_d=None, theta_d=None, theta_h=None,
                wavelengths_nm=None) -> Path:  # fmt: skip
    """Write a Mueller table as a ``.pbsdf`` file for ``measured_polarized`` (module
    docstring), atomically; returns the path. Load it in a ``*_spectral_polarized`` variant
    with ``{"type": "measured_polarized", "filename": str(path), "alpha_sample": α}``
    (α ≈ the lobe's GGX roughness, for sampling only). The incoherent part only: the
    coherent delta lobe of SPM tables (``mt.coherent``) has no place in this format (render
    it with the emscatter plugin, which keeps it)."""
    f = pbsdf_mueller(mt, phi_d=phi_d, theta_d=theta_d, theta_h=theta_h,
                      wavelengths_nm=wavelengths_nm)  # fmt: skip
    if not np.all(np.isfinite(f["M"])):
        raise ValueError("the Mueller table holds NaN/inf: nothing written")
    fields = {k: (v if k == "wvls" else np.asarray(v, np.float32)) for k, v in f.items()}
    with atomic_path(path) as tmp:
        _write_tensor_file(tmp, fields)
    return Path(path)


def read_pbsdf(path) -> dict[str, np.ndarray]:
    """Read and check a ``.pbsdf`` file (module docstring): its fields, as stored."""
    path = Path(path)
    try:
        f = read_tensor_file(path)
    except PbsdfFormatError:
        raise
    except RglFormatError as exc:
        raise PbsdfFormatError(str(exc)) from None

    def fail(what):
        raise PbsdfFormatError(f"{path} is not a measured_polarized file: {what}")

    missing = [k for k in _FIELDS if k not in f]
    if missing:
        fail(f"fields {missing} missing (has {sorted(f)})")
    for k in ("phi_d", "theta_d", "theta_h"):
        a = f[k]
        if a.dtype != np.float32 or a.ndim != 2 or a.shape[0] != 1 or a.shape[1] < 2:
            fail(f"{k!r} must be float32 of shape (1, n >= 2), got {a.dtype} {a.shape}")
        v = a[0].astype(float)
        lo, hi = (-math.pi, math.pi) if k == "phi_d" else (0.0, math.pi / 2)
        if not np.all(np.isfinite(v)) or np.any(np.diff(v) <= 0):
            fail(f"{k!r} must rise strictly and be finite")
        if v[0] < lo - 1e-5 or v[-1] > hi + 1e-5:
            fail(f"{k!r} spans [{v[0]:.6g}, {v[-1]:.6g}] rad, outside [{lo:.6g}, {hi:.6g}]")
    w = f["wvls"]
    if w.dtype != np.uint16 or w.shape != (5,):
        fail(f"'wvls' must be uint16 of shape (5,) (the plugin reads five), got {w.dtype} "
             f"{w.shape}")  # fmt: skip
    if np.any(np.diff(w.astype(int)) <= 0) or w[0] == 0:
        fail(f"'wvls' must be positive and rising [nm], got {w.tolist()}")
    m = f["M"]
    want = (f["phi_d"].shape[1], f["theta_d"].shape[1], f["theta_h"].shape[1], 5, 4, 4)
    if m.dtype != np.float32 or m.shape != want:
        fail(f"'M' must be float32 of shape {want}, got {m.dtype} {m.shape}")
    m = m.astype(float)
    nan = np.isnan(m)
    node_nan = nan.any(axis=(-2, -1))
    if np.any(node_nan & ~nan.all(axis=(-2, -1))) or np.any(np.isinf(m)):
        fail("'M' holds inf, or NaN in part of a node's 4×4 matrix (NaN marks whole nodes)")
    g = m[~node_nan]
    m00 = g[:, 0, 0]
    slack = REALIZABLE_TOL * max(float(m00.max(initial=0.0)), 1e-30)
    if np.any(m00 < -slack):
        fail(f"'M00' is negative at {int(np.sum(m00 < -slack))} nodes (min {m00.min():.3g})")
    bad = (np.abs(g[:, 0, 1:]).max(axis=1) > m00 * (1 + REALIZABLE_TOL) + slack) | (
        np.linalg.norm(g[:, 1:, 0], axis=1) > m00 * (1 + REALIZABLE_TOL) + slack
    )
    if np.any(bad):
        fail(f"{int(bad.sum())} nodes are not realizable Mueller BRDFs (|M0j| or the degree of "
             "polarization of M[:, 0] exceeds M00)")  # fmt: skip
    return f
