"""Dr.Jit side of textured (anisotropic) radio materials (:mod:`emscatter.radio.texture`):
the texture frame at a hit, the folded incidence azimuth and the lookup of the ψ-resolved lobe;
and the texture helpers the radio material shares. Imports Dr.Jit and Mitsuba."""

from __future__ import annotations

import math

import drjit as dr
import mitsuba as mi
import numpy as np

from .convention import to_sionna


def tex_coord(x, n):
    """Texture coordinate of a node-based grid of ``n`` nodes on [0, 1] (texel centres)."""
    return (x * (n - 1) + 0.5) / n


def texture(array: np.ndarray, dim: int):
    tensor = mi.TensorXf(np.ascontiguousarray(array, dtype=np.float32))
    cls = {1: mi.Texture1f, 2: mi.Texture2f, 3: mi.Texture3f}[dim]
    return cls(
        tensor, use_accel=False, filter_mode=dr.FilterMode.Linear, wrap_mode=dr.WrapMode.Clamp
    )


def opaque_float(x) -> mi.Float:
    """A host scalar as an opaque Dr.Jit variable: kernels do not embed it as a literal, so
    a new frequency or table does not trigger a new kernel compilation."""
    v = mi.Float(float(x))
    dr.make_opaque(v)
    return v


class TexturedSlice:
    """Dr.Jit textures of a textured (anisotropic) material (:mod:`emscatter.radio.texture`):
    ``per_cos`` on (ψ, cosθi); the lobe's ψ blocks stacked along the θ axis."""

    def __init__(self, tables):
        self.tables = tables
        inc = tables.incoherent_on_cos()  # (n_psi, 2, n_cos)
        rows = []
        for j, psi in enumerate(tables.psi_nodes):
            delta = to_sionna(tables.coherent_at(psi) - tables.fresnel)
            zero = np.zeros_like(inc[j, 0])
            rows.append(np.stack([delta[0].real, delta[0].imag, delta[1].real, delta[1].imag,
                                  inc[j, 0], inc[j, 1], zero, zero], axis=-1))  # fmt: skip
        self.n_cos = tables.cos_nodes.size
        self.per_cos = texture(np.stack(rows), 2)
        self.n_psi = tables.psi_nodes.size
        self.n_theta = tables.theta_nodes.size
        self.inv_theta_max = opaque_float(1.0 / float(tables.theta_nodes[-1]))
        self.n_alpha = tables.alpha_nodes.size
        self.n_s = tables.s_nodes.size
        self.linear_s = tables.grading == 1.0
        self.inv_grading = opaque_float(1.0 / tables.grading)
        lobe = tables.lobe
        self.lobe = texture(lobe.reshape(-1, *lobe.shape[2:]), 3)


def texture_axes(direction, si):
    """Texture axis ``(ux, uy)`` in the local (s, t) frame: the texture direction projected
    onto the tangent plane, or the world axis least aligned with the normal where they are
    parallel (:func:`emscatter.radio.texture.texture_frame`)."""
    fr = si.sh_frame
    ux, uy = dr.dot(direction, fr.s), dr.dot(direction, fr.t)
    an = dr.abs(fr.n)
    on_x = (an.x <= an.y) & (an.x <= an.z)
    on_y = ~on_x & (an.y <= an.z)
    fx = dr.select(on_x, fr.s.x, dr.select(on_y, fr.s.y, fr.s.z))
    fy = dr.select(on_x, fr.t.x, dr.select(on_y, fr.t.y, fr.t.z))
    deg = dr.sqrt(ux * ux + uy * uy) < 1e-6
    ux, uy = dr.select(deg, fx, ux), dr.select(deg, fy, uy)
    inv = dr.rsqrt(ux * ux + uy * uy)
    return ux * inv, uy * inv


def to_texture_frame(v, tex):
    """Local vector ``v`` in the texture frame (X, Y, n)."""
    ux, uy = tex
    return mi.Vector3f(v.x * ux + v.y * uy, v.y * ux - v.x * uy, v.z)


def folded_azimuth(ki, tex):
    """Table azimuth ψ' ∈ [0, π/2] of the incidence in the texture frame and the flip flag
    (:func:`emscatter.radio.texture.fold_azimuth`)."""
    k = to_texture_frame(ki, tex)
    return dr.atan2(dr.abs(k.y), dr.abs(k.x)), (k.x * k.y) < 0.0


def textured_lookup(sl, s, alpha, th, psi, active):
    """Lobe at (ψ, θ, α, s): two trilinear lookups in the ψ blocks, linear in ψ."""
    x = dr.clip(psi * (2.0 / math.pi), 0.0, 1.0) * (sl.n_psi - 1)
    j0 = dr.minimum(dr.floor(x), sl.n_psi - 2)
    w = x - j0
    u_s = tex_coord(s, sl.n_s)
    u_a = tex_coord(alpha * (0.5 / math.pi) + 0.5, sl.n_alpha)
    rows = sl.n_psi * sl.n_theta
    v = []
    for j in (j0, j0 + 1.0):
        u_t = (j * sl.n_theta + th * (sl.n_theta - 1) + 0.5) * (1.0 / rows)
        v.append(sl.lobe.eval(mi.Point3f(u_s, u_a, u_t), active))
    return [dr.maximum((1.0 - w) * a + w * b, 0.0) for a, b in zip(*v, strict=True)]
