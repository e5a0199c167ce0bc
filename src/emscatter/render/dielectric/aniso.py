"""The anisotropic BTDF lobe of the ``"emscatter_dielectric"`` plugin (:mod:`.plugin`): an
:class:`~emscatter.brdf.btdf_aniso.AnisotropicBtdfTable` looked up in Dr.Jit.

Frame as Mitsuba's anisotropic BSDFs and the anisotropic ``"emscatter"`` BRDF plugin: the
local ``+x`` axis (the shading frame's tangent ``s``, from ``dp/du`` or the mesh's tangents)
is the surface's ``ℓx`` direction, so turning the tangent by ``φ`` turns the lobe with it.
The table's folded azimuth is recovered as :func:`~emscatter.brdf.btdf_aniso.fold_phi` does
(``φi mod π``, then the mirror ``φi → π − φi``, ``Δφ → −Δφ`` above ``π/2``), and ``f_t`` is
the multilinear interpolant of the table in ``(θi, φi, θt, Δφ)`` (clamped in the first three,
periodic in ``Δφ``): 16 gathers per channel, the same interpolant as
:meth:`~emscatter.brdf.btdf_aniso.AnisotropicBtdfTable.evaluate` (to float32).

Polarized variants (:mod:`.polarized`): the same lookup of the 16 Mueller entries per channel
(:func:`aniso_mueller_channels`, :meth:`AnisoBtdfLookup.lookup` also returns the fold's mirror
flag, where :mod:`.polarized` applies ``P M P``, ``P = diag(1, 1, −1, −1)``, as
:meth:`~emscatter.brdf.btdf_aniso.AnisotropicBtdfTable.evaluate_mueller`).
"""

from __future__ import annotations

import math

import numpy as np

from ..plugin_data import Axis

__all__ = ["AnisoBtdfLookup", "aniso_mueller_channels", "check_axes", "reduce_albedo"]


def check_axes(bt) -> list[Axis]:
    """The table's four axes for the plugin: uniform, ``Δφ`` starting at 0 (periodic)."""
    axes = []
    for name in ("theta_i", "phi_i", "theta_t", "phi_d"):
        ax = Axis.of(getattr(bt, name))
        if not ax.uniform:
            raise ValueError(f"the plugin needs uniform BTDF axes; {name} is not uniform")
        axes.append(ax)
    pd = axes[3]
    if abs(pd.start) > 1e-12 or abs(pd.step * pd.size - 2 * math.pi) > 1e-9:
        raise ValueError("the plugin needs phi_d nodes k·2π/n (k = 0 … n−1) on [0, 2π)")
    return axes


def reduce_albedo(albedo) -> np.ndarray:
    """``(n_wl, n_ti)`` from an albedo that may carry a ``φi`` axis (its mean over φi: the
    lobe probabilities only, so the pdf stays consistent with the sampler)."""
    a = np.asarray(albedo, dtype=float)
    return a.mean(axis=tuple(range(2, a.ndim))) if a.ndim > 2 else a


def aniso_mueller_channels(bt, mix) -> np.ndarray:
    """The Mueller BTDF of an anisotropic table as the plugin gathers it: float32 ``(n_ti,
    n_pi, n_tt, n_pd, C·16)`` [1/sr] in emscatter's h/v bases, channel-major; ``mix`` maps
    ``(..., n_wl, 16)`` to the plugin's ``(..., C, 16)`` (:func:`.polarized` passes its
    channel rule). ``M₀₀`` clipped at 0 as the unpolarized plugin. A table without a Mueller
    part: ``ValueError`` naming what builds one."""
    if getattr(bt, "mueller", None) is None:
        raise ValueError(
            "the emscatter_dielectric plugin in a polarized Mitsuba variant needs an "
            "AnisotropicBtdfTable with Mueller matrices (build_anisotropic_btdf_table(..., "
            "polarized=True)); this one has none"
        )
    m = np.asarray(bt.mueller, np.float32)  # (n_wl, 4, 4, ti, pi, tt, pd); float32 as stored
    m = np.moveaxis(m.reshape(m.shape[0], 16, *m.shape[3:]), (0, 1), (-2, -1))
    out = np.array(mix(m), dtype=np.float32)  # (ti, pi, tt, pd, C, 16)
    out[..., 0] = np.clip(out[..., 0], 0.0, None)
    if not np.all(np.isfinite(out)):
        raise ValueError("the BTDF table's Mueller part holds NaN/inf; nothing to render")
    return np.ascontiguousarray(out.reshape(*out.shape[:4], -1), dtype=np.float32)


class AnisoBtdfLookup:
    """``f_t`` of an anisotropic BTDF table in Dr.Jit (module docstring). ``mat``: ``(C,
    n_wl)`` plugin channels; :meth:`__call__` returns the ``C`` channels as Dr.Jit floats.
    ``vals``: instead of ``mat``, the ``(n_ti, n_pi, n_tt, n_pd, C)`` node values to look up
    (the Mueller entries of :func:`aniso_mueller_channels`)."""

    def __init__(self, mi, bt, mat: np.ndarray | None = None, vals: np.ndarray | None = None):
        self._mi = mi
        self._ax = check_axes(bt)
        if vals is None:
            vals = np.clip(np.moveaxis(np.asarray(bt.values, float), 0, -1) @ mat.T, 0.0, None)
        self._c = vals.shape[-1]
        self._shape = vals.shape[:-1]  # (n_ti, n_pi, n_tt, n_pd)
        self._flat = mi.Float(np.ascontiguousarray(vals, dtype=np.float32).ravel())

    def __call__(self, a, b, active):
        """``a`` above (towards the light or viewer outside), ``b`` below, local frame."""
        return self.lookup(a, b, active)[0]

    def lookup(self, a, b, active):
        """``(channels, mirrored)``: the channels at ``a`` above, ``b`` below, and the mask of
        the pairs whose ``φi`` was folded by the mirror ``φi → π − φi`` (module docstring)."""
        import drjit as dr

        mi = self._mi
        ti = dr.acos(dr.clip(dr.abs(a.z), 0.0, 1.0))
        tt = dr.acos(dr.clip(dr.abs(b.z), 0.0, 1.0))
        phi = dr.atan2(a.y, a.x)
        p = phi - math.pi * dr.floor(phi * (1.0 / math.pi))  # φi mod π
        flip = p > 0.5 * math.pi
        p = dr.select(flip, math.pi - p, p)
        d = dr.atan2(b.y, b.x) - phi
        d = dr.select(flip, -d, d)
        d = d - 2 * math.pi * dr.floor(d * (0.5 / math.pi))  # [0, 2π)

        def clamped(x, ax):
            pos = dr.clip((x - ax.start) * (1.0 / ax.step), 0.0, ax.size - 1.0)
            i0 = dr.minimum(mi.UInt32(pos), max(ax.size - 2, 0))
            return i0, dr.minimum(i0 + 1, ax.size - 1), pos - mi.Float(i0)

        ax = self._ax
        n = ax[3].size
        pos = d * (1.0 / ax[3].step)
        j0 = dr.minimum(mi.UInt32(dr.floor(pos)), n - 1)
        coords = [
            clamped(ti, ax[0]),
            clamped(p, ax[1]),
            clamped(tt, ax[2]),
            (j0, (j0 + 1) % n, dr.clip(pos - mi.Float(j0), 0.0, 1.0)),
        ]
        strides = [int(np.prod(self._shape[k + 1 :])) for k in range(4)]
        corners = [(mi.UInt32(0), mi.Float(1.0))]
        for (i0, i1, t), stride in zip(coords, strides, strict=True):
            corners = [
                (idx + node * stride, w * wt)
                for idx, w in corners
                for node, wt in ((i0, 1.0 - t), (i1, t))
            ]
        out = []
        for c in range(self._c):
            acc = mi.Float(0.0)
            for idx, w in corners:
                acc += w * dr.gather(mi.Float, self._flat, idx * self._c + c, active)
            out.append(acc)
        return out, flip
