"""The numpy side of the Mitsuba plugin: everything it looks up, computed once per table.

:func:`prepare` turns an emscatter BRDF table (or any :class:`~emscatter.brdf.source.BrdfFunction`)
into :class:`PluginData`:

* ``values``: ``f_r`` [1/sr], ``(n_ti, n_to, n_pd, C)`` for isotropic tables (θi, θo,
  Δφ ∈ [0, π], Δφ = π the mirror half-plane) on an emscatter table's *own* nodes, uniform or
  not (adaptive ``tol=`` grids, user axes: :class:`Axis` with ``points``, located by a binary
  search), so the plugin reproduces :meth:`BrdfTable.evaluate` (multilinear, θ clamped beyond
  the end nodes) to float32 precision; analytic functions (no table) are sampled on 90 × 90 ×
  180. Anisotropic tables: ``(n_pi · n_ti, n_to, n_po + 1, C)``, φi blocks of θi rows
  (interpolated in φi by two lookups), φo periodic (first column repeated at 2π + φ₀).
* channels ``C``: the table's wavelengths (Mitsuba's spectral variants interpolate linearly
  between them, constant beyond), linear sRGB
  (:func:`~emscatter.brdf.colour.spectrum_to_rgb_weights`) or one luminance channel;
* ``coherent``: the delta lobe's ``R_coh`` on the θi nodes (× φi nodes), same channels;
* ``sampler``: a :class:`~emscatter.render.sampling.HalfVectorSampler` (marginal/conditional
  alias tables of ``f_r cosθo`` over the half-vector square, one per incident node);
* ``delta_probability``: the chance of sampling the delta lobe at each θi node,
  ``R_coh / (R_coh + albedo_incoherent)`` (channel means).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..brdf.colour import RGB_LUMINANCE, spectrum_to_rgb_weights
from ..brdf.rgl_warp import direction
from ..brdf.source import BrdfFunction, as_brdf_source
from .sampling import HalfVectorSampler, build_sampler

__all__ = ["Axis", "PluginData", "prepare", "CHANNELS"]

CHANNELS = ("spectral", "rgb", "mono")
_DEFAULT_THETA = 90
_DEFAULT_PHI = 180


@dataclass(frozen=True)
class Axis:
    """A table axis [rad]: uniform nodes ``start + k·step``, k = 0 … size−1, or (``points``
    given) any strictly increasing nodes — an adaptive (``tol=``) or user grid, looked up by a
    binary search in the plugin instead of the uniform formula."""

    start: float
    step: float
    size: int
    points: tuple[float, ...] | None = None

    @property
    def uniform(self) -> bool:
        return self.points is None

    @property
    def nodes(self) -> np.ndarray:
        if self.points is not None:
            return np.array(self.points)
        return self.start + self.step * np.arange(self.size)

    @staticmethod
    def of(nodes: np.ndarray) -> Axis:
        """The axis of ``nodes``: uniform when they are (relative 1e-9), else with ``points``
        (``step`` then the mean spacing; a single node has step 1)."""
        nodes = np.asarray(nodes, dtype=float).reshape(-1)
        if nodes.size < 2:
            return Axis(float(nodes[0]), 1.0, 1)
        step = (nodes[-1] - nodes[0]) / (nodes.size - 1)
        if step > 0 and np.max(np.abs(np.diff(nodes) - step)) <= 1e-9 * max(step, 1e-300):
            return Axis(float(nodes[0]), float(step), int(nodes.size))
        return Axis(float(nodes[0]), float(step), int(nodes.size), tuple(map(float, nodes)))


@dataclass(frozen=True)
class PluginData:
    """What the plugin looks up (see the module docstring); float32 arrays."""

    isotropic: bool
    channels: str
    wavelengths_nm: np.ndarray | None  # spectral channels' wavelengths [nm]
    theta_i: Axis
    theta_o: Axis
    phi: Axis  # Δφ (isotropic) or φo (anisotropic, without the repeated 2π column)
    phi_i: Axis | None  # anisotropic only
    values: np.ndarray
    coherent: np.ndarray  # (n_ti, C) or (n_pi, n_ti, C)
    sampler: HalfVectorSampler
    delta_probability: np.ndarray  # (n_ti,) or (n_pi, n_ti)
    has_coherent: bool
    description: str

    @property
    def n_channels(self) -> int:
        return self.values.shape[-1]


def _channel_matrix(source: BrdfFunction, channels: str) -> np.ndarray:
    """(C, n_source_channels): plugin channels from the source's channels."""
    if source.wavelengths is None:  # already linear sRGB
        if channels == "spectral":
            raise ValueError("a spectral Mitsuba variant needs a BRDF with wavelengths")
        rgb = np.eye(3)
    elif channels == "spectral":
        return np.eye(source.wavelengths.size)
    else:
        rgb = spectrum_to_rgb_weights(source.wavelengths)
    return RGB_LUMINANCE[None, :] @ rgb if channels == "mono" else rgb


def _isotropic_values(source: BrdfFunction, mat: np.ndarray):
    table = source.table
    axes = None
    if table is not None and table.isotropic:  # the table's own nodes, uniform or not
        axes = [Axis.of(a) for a in (table.theta_i, table.theta_o, table.phi_d)]
    if axes is not None:
        vals = np.moveaxis(table.values, 0, -1)  # (n_ti, n_to, n_pd, n_wl)
    else:  # resample on the builders' default uniform grid
        th = Axis(0.0, 0.5 * math.pi / _DEFAULT_THETA, _DEFAULT_THETA)
        axes = [th, th, Axis(0.0, math.pi / (_DEFAULT_PHI - 1), _DEFAULT_PHI)]
        ti, to, pd = np.meshgrid(*(a.nodes for a in axes), indexing="ij")
        wi = direction(ti, 0.0)
        wo = direction(to, pd)
        vals = source.evaluate(wi, wo)
    return axes, np.clip(vals @ mat.T, 0.0, None)


def _anisotropic_values(source: BrdfFunction, mat: np.ndarray):
    table = source.table
    axes = None
    if table is not None and not table.isotropic:  # its own nodes (φ: periodic, any spacing)
        axes = [Axis.of(a) for a in (table.theta_i, table.phi_i, table.theta_o, table.phi_o)]
        for k in (1, 3):  # a uniform φ axis must start at 0 and close 2π to use the formula
            a = axes[k]
            if a.uniform and not (
                abs(a.start) < 1e-12 and abs(a.step * a.size - 2 * math.pi) < 1e-9
            ):
                axes[k] = Axis(a.start, a.step, a.size, tuple(map(float, a.nodes)))
    if axes is not None:
        vals = np.moveaxis(table.values, 0, -1)  # (n_ti, n_pi, n_to, n_po, n_wl)
    else:
        th = Axis(0.0, 0.5 * math.pi / 45, 45)
        ph = Axis(0.0, 2 * math.pi / 72, 72)
        axes = [th, ph, th, ph]
        ti, pi_, to, po = np.meshgrid(*(a.nodes for a in axes), indexing="ij")
        vals = source.evaluate(direction(ti, pi_), direction(to, po))
    vals = np.clip(vals @ mat.T, 0.0, None)
    vals = np.concatenate([vals, vals[:, :, :, :1]], axis=3)  # φo periodic: repeat 0 at 2π
    ti_ax, pi_ax, to_ax, po_ax = axes
    # (n_pi, n_ti, n_to, n_po + 1, C) → φi blocks of θi rows
    vals = np.moveaxis(vals, 1, 0).reshape(pi_ax.size * ti_ax.size, to_ax.size, po_ax.size + 1, -1)
    return axes, vals


def prepare(brdf, channels: str, *, sampling_resolution: int = 64) -> PluginData:
    """:class:`PluginData` for ``brdf`` (a BrdfTable or BrdfFunction) in a Mitsuba variant
    whose colour representation is ``channels`` (``"spectral"``, ``"rgb"``, ``"mono"``)."""
    source = as_brdf_source(brdf)
    if channels not in CHANNELS:
        raise ValueError(f"channels must be one of {CHANNELS}, got {channels!r}")
    if (
        isinstance(sampling_resolution, bool)
        or not isinstance(sampling_resolution, int | np.integer)
        or not 8 <= sampling_resolution <= 1024
    ):
        raise ValueError(
            f"sampling_resolution must be an integer in [8, 1024], got {sampling_resolution!r}"
        )
    mat = _channel_matrix(source, channels)
    if source.isotropic:
        axes, values = _isotropic_values(source, mat)
        ti_ax, to_ax, ph_ax = axes
        pi_ax = None
        s_theta, s_phi = ti_ax.nodes, None
        coh = source.coherent(ti_ax.nodes) @ mat.T  # (n_ti, C)
    else:
        axes, values = _anisotropic_values(source, mat)
        ti_ax, pi_ax, to_ax, ph_ax = axes
        # sampling slices on at most 30 θi × 24 φi nodes (tables of 64² cells each)
        s_theta = np.linspace(ti_ax.nodes[0], ti_ax.nodes[-1], min(ti_ax.size, 30))
        s_phi = np.arange(min(pi_ax.size, 24)) * (2 * math.pi / min(pi_ax.size, 24))
        coh = _anisotropic_coherent(source, ti_ax, pi_ax) @ mat.T  # (n_pi, n_ti, C)
    coh = np.clip(coh, 0.0, 1.0)
    sampler = build_sampler(source, mat.mean(axis=0), s_theta, s_phi, int(sampling_resolution))
    albedo = _incoherent_albedo(source, mat, ti_ax, pi_ax)
    c_mean = coh.mean(axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        p_delta = np.where(c_mean > 0, c_mean / (c_mean + albedo), 0.0)
    return PluginData(
        isotropic=source.isotropic,
        channels=channels,
        wavelengths_nm=None if channels != "spectral" else source.wavelengths * 1e9,
        theta_i=ti_ax,
        theta_o=to_ax,
        phi=ph_ax,
        phi_i=pi_ax,
        values=np.ascontiguousarray(values, dtype=np.float32),
        coherent=np.ascontiguousarray(coh, dtype=np.float32),
        sampler=sampler,
        delta_probability=np.asarray(p_delta, dtype=np.float32),
        has_coherent=bool(np.any(coh > 0)),
        description=source.name,
    )


def _anisotropic_coherent(source, ti_ax: Axis, pi_ax: Axis) -> np.ndarray:
    table = source.table
    ti, pi_ = np.meshgrid(ti_ax.nodes, pi_ax.nodes, indexing="ij")
    if table is not None and not table.isotropic:
        out = np.moveaxis(table.coherent_reflectance(ti, pi_), 0, -1)  # (n_ti, n_pi, n_wl)
    else:
        out = source.coherent(ti)
    return np.moveaxis(out, 1, 0)


def _incoherent_albedo(source, mat, ti_ax: Axis, pi_ax: Axis | None) -> np.ndarray:
    """Channel-mean directional albedo of the incoherent part at the θi (× φi) nodes."""
    lum = mat.mean(axis=0)
    table = source.table
    if table is not None and table.isotropic == source.isotropic:
        alb = table.albedo().incoherent  # (n_wl, n_ti[, n_pi])
        lead_ti = table.theta_i
        a = np.tensordot(lum, alb, axes=(0, 0))
        if pi_ax is None:
            return np.interp(ti_ax.nodes, lead_ti, a)
        if a.shape == (ti_ax.size, pi_ax.size):
            return a.T
    # midpoint quadrature over the outgoing hemisphere
    n = 64
    to = (np.arange(n) + 0.5) * (0.5 * math.pi / n)
    po = (np.arange(2 * n) + 0.5) * (math.pi / n)
    wts = np.sin(to) * np.cos(to) * (0.5 * math.pi / n) * (math.pi / n)
    wo = direction(to[:, None], po[None, :])
    ti = ti_ax.nodes if pi_ax is None else ti_ax.nodes[None, :]
    pi_ = 0.0 if pi_ax is None else pi_ax.nodes[:, None]
    wi = direction(ti, pi_)[..., None, None, :]
    f = source.evaluate(np.broadcast_to(wi, wi.shape[:-3] + wo.shape), wo) @ lum
    return np.sum(f * wts[:, None], axis=(-2, -1))
