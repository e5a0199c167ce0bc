"""Anisotropic roughness for radio materials: walls with a texture direction.

A surface with correlation lengths ``ℓx ≠ ℓy`` (:mod:`emscatter.spectra`, ``length_y=``) has
its ``x`` axis (the ``ℓx`` axis) along a **texture direction** ``d`` given in the world frame
(``d = (0, 0, 1)`` with a long ``ℓx``: vertical grooves on every wall). At each hit the texture
axis is ``d`` projected onto the tangent plane, ``X = (d − (d·n) n) / |d − (d·n) n|``, and
``Y = n × X`` (:func:`texture_frame`).

**Degenerate rule** — where ``d`` is parallel to the normal (``|d − (d·n)n| < 1e-6``: vertical
grooves seen on a floor or ceiling), ``X`` is the projection of the world axis least aligned
with ``n`` (the smallest ``|n_i|``; ties → ``x`` before ``y`` before ``z``). The rule depends on
the normal only, never on the mesh's own tangents, so every triangle of a floor gets the same
axis.

**Tables** (:func:`build_textured_tables`) — the σ⁰ of an anisotropic surface depends on the
incidence azimuth ``ψ`` relative to ``X``, so the lobe gets an extra axis: ``n_psi`` nodes of ψ
on ``[0, π/2]`` (the statistics of Gaussian, exponential and power-law correlations are even in
``x`` and in ``y``: a mirror ``y → −y`` maps ψ → −ψ and the scattered azimuth φ → −φ, a mirror
``x → −x`` maps ψ → π − ψ, φ → −φ; :func:`fold_azimuth`), and the lobe azimuth ``α`` around the
specular point covers the full circle ``[−π, π]`` (no mirror symmetry about the plane of
incidence at oblique ψ). Why a table and not the solver per ray: emscatter's solvers run on the
host in NumPy (a spectral quadrature per point for SPM), the ray tracer needs a value per
diffuse lane in a Dr.Jit kernel; at the default grid the table costs
``46 × 7 × 73 × 96 ≈ 2.3 M`` solver points once per (material, frequency) and 36 MB of float32
texture, and a lane costs two trilinear lookups (ψ interpolated linearly between them).

The coherent roughness correction is tabulated at ψ = 0 (``ℓx`` along the incidence plane) and
ψ = π/2 (axes swapped) and carried to other ψ as ``cos²ψ r(0) + sin²ψ r(π/2)`` — exact at both
ends and exact at every ψ for Kirchhoff-type solvers (GO, PO: the coherent factor of a Gaussian
surface is ``exp(−2k²σ²cos²θ)``, independent of ℓ), an interpolation for SPM's second-order
mean field (its spread between the two ends is recorded, ``coherent_azimuth_spread``).
"""

from __future__ import annotations

import math
import re
import time
import warnings
from dataclasses import dataclass

import numpy as np

from ..conventions import wavenumber
from ..fresnel import fresnel_cos
from ..spectra import GaussianCorrelation, Roughness, check_roughness
from . import tables as _t
from .medium import real_number

__all__ = [
    "check_direction",
    "check_textured_surface",
    "texture_frame",
    "fold_azimuth",
    "TexturedTables",
    "build_textured_tables",
    "interpolate_textured_lobe",
    "parse_medium_option",
    "DEGENERATE_TOLERANCE",
]

#: ``|d − (d·n)n|`` below which the texture direction counts as parallel to the normal.
DEGENERATE_TOLERANCE = 1e-6


def check_direction(direction, name: str = "texture_direction") -> np.ndarray:
    """A unit 3-vector from three finite numbers, not all zero (clear error otherwise)."""
    try:
        d = np.asarray(direction, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        d = np.full(1, np.nan)
    norm = float(np.linalg.norm(d)) if d.size == 3 and np.all(np.isfinite(d)) else 0.0
    if norm == 0.0:
        raise ValueError(
            f"{name} must be a world-frame direction of three finite numbers, not all zero "
            f"(e.g. (0, 0, 1) for vertical grooves: the ℓx axis vertical), got {direction!r}"
        )
    return d / norm


def check_textured_surface(surface) -> Roughness:
    """2-D roughness (isotropic or not) for a textured radio material."""
    rough = check_roughness(surface, "surface")
    if rough.dimension != 2:
        raise ValueError(
            f"a textured radio material needs 2-D roughness (dimension=2), got {rough.describe()}"
        )
    return rough


def _fallback_axis(n):
    """The world axis least aligned with each normal (ties → x, then y, then z)."""
    a = np.abs(n)
    idx = np.argmin(a, axis=-1)
    return np.eye(3)[idx]


def texture_frame(normal, direction):
    """Tangent texture axes ``(X, Y)`` (unit, ``Y = n × X``) at normals ``normal`` (..., 3) for
    a world direction ``direction`` (module docstring, with the degenerate rule), and the mask
    of the normals where the rule applied. NumPy reference of the material's Dr.Jit code."""
    n = np.asarray(normal, dtype=float)
    n = n / np.linalg.norm(n, axis=-1, keepdims=True)
    d = np.broadcast_to(check_direction(direction), n.shape)
    t = d - np.sum(d * n, axis=-1, keepdims=True) * n
    size = np.linalg.norm(t, axis=-1, keepdims=True)
    degenerate = size[..., 0] < DEGENERATE_TOLERANCE
    f = _fallback_axis(n)
    tf = f - np.sum(f * n, axis=-1, keepdims=True) * n
    t = np.where(degenerate[..., None], tf, t)
    x = t / np.linalg.norm(t, axis=-1, keepdims=True)
    return x, np.cross(n, x), degenerate


def fold_azimuth(psi):
    """``(ψ' ∈ [0, π/2], flip)``: the table azimuth of an incidence azimuth ψ [rad] relative
    to the texture axis, and whether the scattered azimuth changes sign (an odd number of
    mirrors, module docstring)."""
    c, s = np.cos(psi), np.sin(psi)
    return np.arctan2(np.abs(s), np.abs(c)), c * s < 0


@dataclass
class TexturedTables(_t.RadioTables):
    """:class:`~emscatter.radio.tables.RadioTables` with the incidence-azimuth axis: ``lobe``
    (n_psi, n_theta, n_alpha, n_s, 4) with ``alpha_nodes`` on [−π, π]; ``coherent``, ``fresnel``
    (2, n_cos) at ψ = 0 and ``coherent_y`` at ψ = π/2; ``incoherent``, ``coherent_power``,
    ``energy_scale`` (n_psi, 2, n_theta)."""

    psi_nodes: np.ndarray | None = None
    coherent_y: np.ndarray | None = None
    coherent_azimuth_spread: float = 0.0

    def coherent_at(self, psi) -> np.ndarray:
        """``r_coh`` (2, n_cos) at incidence azimuth ψ [rad] (module docstring)."""
        c2 = math.cos(float(psi)) ** 2
        return c2 * self.coherent + (1.0 - c2) * self.coherent_y

    def incoherent_on_cos(self) -> np.ndarray:
        """``r_incoh,p`` (n_psi, 2, n_cos) on the coherent ``cosθi`` grid."""
        c = np.cos(self.theta_nodes)[::-1]
        return np.stack(
            [
                np.stack([np.interp(self.cos_nodes, c, inc[p][::-1]) for p in (0, 1)])
                for inc in self.incoherent
            ]
        )

    def describe(self) -> str:
        return super().describe() + f"; textured, {self.psi_nodes.size} incidence azimuths"


def _swap(rough: Roughness) -> Roughness:
    return type(rough)(**{**rough._params(), "length": rough.length_y, "length_y": rough.length})


def build_textured_tables(
    surface: Roughness,
    eps: complex,
    frequency: float,
    *,
    method: str = "auto",
    out_of_range: str = "warn",
    label: str = "material",
    options: _t.TableOptions | None = None,
) -> TexturedTables:
    """Tables of a textured material (module docstring) at ``frequency`` [Hz]: the roughness
    ``surface`` in its own axes (``length`` along the texture axis X, ``length_y`` along Y),
    permittivity ``eps`` (``Im ε ≥ 0``). Reused like
    :func:`~emscatter.radio.tables.build_tables`."""
    opts = options or _t.TableOptions()
    key = ("textured", repr(surface), complex(np.asarray(eps)), float(frequency), method,
           out_of_range, opts)  # fmt: skip
    hit = _t._CACHE.get(key)
    if hit is not None:
        _t._CACHE.move_to_end(key)
        return hit
    tables = _build(surface, eps, frequency, method, out_of_range, label, opts)
    _t._CACHE[key] = tables
    while len(_t._CACHE) > _t._CACHE_SIZE:
        _t._CACHE.popitem(last=False)
    return tables


def _build(surface, eps, frequency, method, out_of_range, label, opts) -> TexturedTables:
    from .. import api

    policy = _t.check_policy(out_of_range)
    rough = check_textured_surface(surface)
    k = wavenumber(frequency=frequency)
    eps = complex(np.asarray(eps))
    t0 = time.perf_counter()
    name, module, report, _ = api.resolve_method(rough, k, method, "ignore", eps)
    if not report.get("valid", True):
        why = "; ".join(report.get("reasons", [])) or "outside its validity range"
        msg = (
            f"radio material {label!r} at {frequency / 1e9:g} GHz: {rough.describe()}; method "
            f"{name!r} is outside its validity range ({why}). Pick another method= or "
            "out_of_range='raise' to make this an error."
        )
        if policy == "raise":
            raise api.select.ValidityError(msg)
        if policy == "warn":
            warnings.warn(msg, _t.RadioValidityWarning, stacklevel=3)
    cos_nodes = np.linspace(0.0, 1.0, opts.n_cos)
    fres = np.stack(fresnel_cos(eps, cos_nodes))
    coh_x, n1 = _t._coherent_on_grid(rough, eps, k, name, cos_nodes, fres, opts.n_cos_spm)
    if rough.is_isotropic:
        coh_y, n2 = coh_x, 0
    else:
        coh_y, n2 = _t._coherent_on_grid(_swap(rough), eps, k, name, cos_nodes, fres,
                                         opts.n_cos_spm)  # fmt: skip
    theta_nodes = np.radians(np.linspace(0.0, opts.theta_max_deg, opts.n_theta))
    alpha_nodes = np.linspace(-math.pi, math.pi, 2 * opts.n_alpha - 1)
    s_nodes = np.linspace(0.0, 1.0, opts.n_s)
    psi_nodes = np.linspace(0.0, 0.5 * math.pi, opts.n_psi)
    grading = _t._grading(rough, k, opts.n_s)
    theta_s, phi_rel = _t.lobe_directions(theta_nodes, alpha_nodes, s_nodes, grading)
    ti = np.broadcast_to(theta_nodes[:, None, None], theta_s.shape)
    skip = (
        {"coherent": False}
        if "coherent" in _t.inspect.signature(module.bistatic).parameters
        else {}
    )
    cos_i = np.cos(theta_nodes)[:, None, None, None]
    lobes, incs, cps, scales = [], [], [], []
    excess = 0.0
    for psi in psi_nodes:  # n_psi solver calls of n_theta·n_alpha·n_s points each
        res = module.bistatic(rough, eps, k, ti, theta_s, phi_rel + psi, float(psi), **skip)
        sig = np.maximum(np.nan_to_num(np.asarray(res.sigma0, float), nan=0.0, posinf=0.0), 0.0)
        lobe = np.stack([sig[0, 0], sig[0, 1], sig[1, 0], sig[1, 1]], axis=-1) / (
            4.0 * math.pi * cos_i
        )
        # full circle of α: the helper's factor 2 (two mirror halves) is undone
        inc = 0.5 * _t._lobe_integral(lobe, theta_nodes, alpha_nodes, s_nodes, grading)
        c2 = math.cos(psi) ** 2
        power = np.abs(c2 * coh_x + (1.0 - c2) * coh_y) ** 2
        cp = np.stack([np.interp(np.cos(theta_nodes), cos_nodes, power[p]) for p in (0, 1)])
        room = np.maximum(1.0 - cp, 0.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            scale = np.where(inc > room, room / np.where(inc > 0, inc, 1.0), 1.0)
        excess = max(excess, float(np.max(cp + inc) - 1.0))
        lobe = lobe * np.stack([scale[0], scale[1], scale[0], scale[1]], axis=-1)[:, None, None]
        lobes.append(lobe)
        incs.append(inc * scale)
        cps.append(cp)
        scales.append(scale)
    scale = np.stack(scales)
    scaled = scale < 1.0 - opts.energy_tolerance
    if np.any(scaled):
        first = float(np.degrees(theta_nodes[np.any(scaled, axis=(0, 1))].min()))
        if first < opts.energy_warn_below_deg:
            warnings.warn(
                f"radio material {label!r} at {frequency / 1e9:g} GHz (method {name!r}): coherent "
                f"+ incoherent reflectivity reaches {1 + excess:.3f} > 1 from θi = {first:.0f}°; "
                "the diffuse lobe is scaled down there to conserve energy.",
                _t.EnergyWarning,
                stacklevel=3,
            )
    seconds = time.perf_counter() - t0
    evals = {"bistatic_points": int(theta_s.size * psi_nodes.size), "coherent_points": n1 + n2}
    _t._LOG.append(
        {"label": label, "frequency": float(frequency), "method": name, **evals, "seconds": seconds}
    )
    return TexturedTables(
        label=label,
        frequency=float(frequency),
        eps=eps,
        method=name,
        valid=bool(report.get("valid", True)),
        reasons=list(report.get("reasons", [])),
        cos_nodes=cos_nodes,
        coherent=coh_x,
        fresnel=fres,
        theta_nodes=theta_nodes,
        alpha_nodes=alpha_nodes,
        s_nodes=s_nodes,
        grading=grading,
        lobe=np.stack(lobes),
        incoherent=np.stack(incs),
        coherent_power=np.stack(cps),
        energy_excess=max(excess, 0.0),
        energy_scale=scale,
        evaluations=evals,
        seconds=seconds,
        psi_nodes=psi_nodes,
        coherent_y=coh_y,
        coherent_azimuth_spread=float(np.max(np.abs(coh_x - coh_y))),
    )


def interpolate_textured_lobe(tables: TexturedTables, theta_i, psi_i, theta_s, phi_s):
    """Lobe ``(4, *shape)`` [1/sr] (NumPy reference of the material's lookup) at incidence
    ``(θi, ψi)`` and scattered ``(θs, φs)`` [rad], both azimuths relative to the texture axis X
    (``ψi`` the azimuth of the propagation direction, as emscatter's ``phi_i``)."""
    from scipy.interpolate import RegularGridInterpolator

    psi, flip = fold_azimuth(np.asarray(psi_i, dtype=float))
    rel = np.asarray(phi_s, dtype=float) - np.asarray(psi_i, dtype=float)
    p0 = np.sin(theta_i)
    px = np.sin(theta_s) * np.cos(rel) - p0
    py = np.where(flip, -1.0, 1.0) * np.sin(theta_s) * np.sin(rel)
    rho = np.hypot(px, py)
    safe = np.where(rho > 0, rho, 1.0)
    cos_a, sin_a = np.where(rho > 0, px / safe, 1.0), np.where(rho > 0, py / safe, 0.0)
    alpha = np.arctan2(sin_a, cos_a)
    rmax = _t._rho_max(p0, cos_a, sin_a)
    s = np.clip(rho / np.maximum(rmax, 1e-12), 0.0, 1.0) ** (1.0 / tables.grading)
    th = np.clip(theta_i, tables.theta_nodes[0], tables.theta_nodes[-1])
    interp = RegularGridInterpolator(
        (tables.psi_nodes, tables.theta_nodes, tables.alpha_nodes, tables.s_nodes), tables.lobe
    )
    pts = np.stack(np.broadcast_arrays(psi, th, alpha, s), axis=-1)
    return np.moveaxis(interp(pts), -1, 0)


_OPTION = re.compile(r"^\s*([A-Za-z_][\w:.\-]*)\s*=\s*([^@]+?)\s*(?:@\s*(.+?)\s*)?$")
_NAMED_DIRECTIONS = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0),
                     "vertical": (0.0, 0.0, 1.0)}  # fmt: skip


def parse_medium_option(text: str) -> dict:
    """Parse the CLI option ``--medium NAME=σ,ℓ`` or ``NAME=σ,ℓx,ℓy@DIR`` (lengths in metres,
    ``DIR`` = ``x|y|z|vertical`` or ``dx,dy,dz``; a third number needs ``@DIR``).

    Returns ``{"medium", "surface", "texture_direction"}`` (direction ``None`` when isotropic);
    raises ``ValueError`` naming the option, the value and the allowed form."""
    form = "NAME=σ,ℓ or NAME=σ,ℓx,ℓy@DIR (metres; DIR = x|y|z|vertical or dx,dy,dz)"
    m = _OPTION.match(text) if isinstance(text, str) else None
    if m is None:
        raise ValueError(f"--medium must be {form}, got {text!r}")
    name, numbers_, direction = m.groups()
    try:
        vals = [real_number("--medium", float(v)) for v in numbers_.split(",")]
    except ValueError:
        raise ValueError(f"--medium {text!r}: σ and ℓ must be numbers; expected {form}") from None
    if len(vals) not in (2, 3) or min(vals) <= 0:
        raise ValueError(f"--medium {text!r}: need 2 or 3 positive numbers; expected {form}")
    if len(vals) == 3 and direction is None:
        raise ValueError(f"--medium {text!r}: ℓx, ℓy need a texture direction @DIR; {form}")
    if direction is None:
        d = None
    elif direction.lower() in _NAMED_DIRECTIONS:
        d = _NAMED_DIRECTIONS[direction.lower()]
    else:
        try:
            d = tuple(check_direction([float(v) for v in direction.split(",")], "--medium DIR"))
        except ValueError:
            raise ValueError(f"--medium {text!r}: bad direction {direction!r}; {form}") from None
    ly = vals[2] if len(vals) == 3 else None
    surface = GaussianCorrelation(sigma=vals[0], length=vals[1], length_y=ly)
    return {"medium": name, "surface": surface, "texture_direction": d}
