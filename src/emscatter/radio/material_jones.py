"""Per-ray Jones matrices of :class:`emscatter.radio.material.EmscatterRadioMaterial`'s
events, Dr.Jit: the diffuse lobe looked up in the material's textures (:func:`diffuse_lobe`, the
``(hh, hv, vh, vv)`` power lobes [1/sr] of the slice built by :mod:`.material_slice` or
:mod:`.texture_jit`), the local real Jones matrix of a diffuse reflection into a solid angle
(:func:`local_diffuse_matrix`, ``√(lobe · Ω)`` with the sign pattern of Sionna's XPD matrix) and
the world-frame (implicit basis) matrix of a specular or diffuse lane
(:func:`specular_or_diffuse_matrix`, ``R_out · D · R_in`` as
:func:`sionna.rt.utils.jones_matrix_to_world_implicit` builds it). The material's docstring
describes the model and the Sionna convention (``exp(+jωt)``: :mod:`.convention`)."""

from __future__ import annotations

import math

import drjit as dr
import mitsuba as mi
from sionna.rt.utils import (
    implicit_basis_vector,
    jones_matrix_from_real_imag,
    jones_matrix_rotator,
    transverse_basis_from_normal,
)

from .material_slice import _Slice
from .texture_jit import folded_azimuth, tex_coord, textured_lookup, to_texture_frame

__all__ = ["diffuse_lobe", "local_diffuse_matrix", "specular_or_diffuse_matrix"]


def diffuse_lobe(ki, ko, sl: _Slice, active, tex=None):
    """``(hh, hv, vh, vv)`` lobe values [1/sr] for local directions ``ki`` (incident,
    propagating) and ``ko`` (scattered; with diffuse transmission either hemisphere: the
    back one reads the transmitted block of the stacked texture at ``(μ = |ko.z|, φ)``)."""
    if sl.n_psi:
        psi, flip = folded_azimuth(ki, tex)
        ki, ko = to_texture_frame(ki, tex), to_texture_frame(ko, tex)
    cos_i = -ki.z
    sin_i = dr.safe_sqrt(1.0 - cos_i * cos_i)
    degenerate = sin_i < 1e-6
    inv = dr.select(degenerate, 0.0, dr.rcp(sin_i))
    e1x = dr.select(degenerate, 1.0, ki.x * inv)
    e1y = dr.select(degenerate, 0.0, ki.y * inv)
    dx0 = ko.x - ki.x
    dy0 = ko.y - ki.y
    dx = dx0 * e1x + dy0 * e1y
    dy = dy0 * e1x - dx0 * e1y
    dy = dr.select(flip, -dy, dy) if sl.n_psi else dr.abs(dy)
    rho = dr.sqrt(dx * dx + dy * dy)
    has = rho > 1e-9
    inv_rho = dr.select(has, dr.rcp(rho), 0.0)
    cos_a = dr.select(has, dx * inv_rho, 1.0)
    sin_a = dr.select(has, dy * inv_rho, 0.0)
    alpha = dr.atan2(sin_a, cos_a)
    rmax = -sin_i * cos_a + dr.safe_sqrt(1.0 - dr.square(sin_i * sin_a))
    t = dr.clip(rho * dr.rcp(dr.maximum(rmax, 1e-9)), 0.0, 1.0)
    if sl.linear_s:
        s = t
    else:
        s = dr.select(t > 0.0, dr.exp(dr.log(dr.maximum(t, 1e-30)) * sl.inv_grading), 0.0)
    th = dr.clip(dr.safe_acos(cos_i) * sl.inv_theta_max, 0.0, 1.0)
    if sl.n_psi:
        return textured_lookup(sl, s, alpha, th, psi, active)
    if sl.stacked:  # one lookup: reflection block 0, transmission block 1 (material_slice)
        back = ko.z < 0.0
        kx = ko.x * e1x + ko.y * e1y
        ky = dr.abs(ko.y * e1x - ko.x * e1y)
        phi = dr.atan2(ky, kx)
        s = dr.select(back, dr.clip(-ko.z, 0.0, 1.0), s)
        alpha = dr.select(back, phi, alpha)
        idx = th * (sl.n_theta - 1) + dr.select(back, float(sl.n_theta), 0.0)
        z = (idx + 0.5) * (1.0 / (2 * sl.n_theta))
    else:
        z = tex_coord(th, sl.n_theta)
    pos = mi.Point3f(tex_coord(s, sl.n_s), tex_coord(alpha * (1.0 / math.pi), sl.n_alpha), z)
    v = sl.lobe.eval(pos, active)
    return [dr.maximum(x, 0.0) for x in v]


def local_diffuse_matrix(ki, ko, sl: _Slice, solid_angle, active, tex=None) -> mi.Matrix2f:
    """Real Jones matrix of a diffuse reflection into ``ko`` in the local ``(h, v)`` bases
    of the incident and scattered planes: ``√(lobe_qp · Ω)``, co-pol on the diagonal,
    cross-pol with the sign pattern of Sionna's XPD matrix ``[[a, −b], [b, a]]``
    (norm-preserving when hv = vh, hh = vv)."""
    hh, hv, vh, vv = diffuse_lobe(ki, ko, sl, active, tex)
    root_omega = dr.sqrt(dr.maximum(solid_angle, 0.0))
    return mi.Matrix2f(dr.sqrt(hh), -dr.sqrt(hv), dr.sqrt(vh), dr.sqrt(vv)) * root_omega


def specular_or_diffuse_matrix(
    to_world, ki, ko_spec, c_te, c_tm, sl, diffuse, ko_diff, solid_angle, active,
    tex=None,
) -> mi.Matrix4f:  # fmt: skip
    """Jones matrix (world implicit frame): ``R_out · D · R_in`` with ``D`` = diag(c_te,
    c_tm) for a specular lane and the local diffuse matrix for a diffuse lane, as
    :func:`sionna.rt.utils.jones_matrix_to_world_implicit` builds it — but with one
    incident rotator for both events and one scattered rotator for the lane's direction
    (each rotator needs the implicit basis of a world direction: two atan2, two sincos)."""
    n = mi.Vector3f(0.0, 0.0, 1.0)
    h_in = transverse_basis_from_normal(ki, n)  # TE direction, local frame
    ki_w = to_world @ ki
    r_in = jones_matrix_rotator(ki, to_world.T @ implicit_basis_vector(ki_w), h_in)
    # The specular scattered plane shares the incident TE direction (Sionna's convention).
    ko = dr.select(diffuse, ko_diff, ko_spec)
    h_out = dr.select(diffuse, transverse_basis_from_normal(ko_diff, n), h_in)
    ko_w = to_world @ ko
    r_out = jones_matrix_rotator(ko_w, to_world @ h_out, implicit_basis_vector(ko_w))
    d = local_diffuse_matrix(ki, ko_diff, sl, solid_angle, mi.Bool(active) & diffuse, tex)
    zero = mi.Float(0.0)
    d_re = dr.select(diffuse, d, mi.Matrix2f(c_te.real, zero, zero, c_tm.real))
    d_im = dr.select(diffuse, mi.Matrix2f(0.0), mi.Matrix2f(c_te.imag, zero, zero, c_tm.imag))
    return jones_matrix_from_real_imag(r_out @ d_re @ r_in, r_out @ d_im @ r_in)
