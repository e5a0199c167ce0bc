"""The coherent (delta) lobes of the ``"emscatter_dielectric"`` plugin (:mod:`.plugin`):
their NumPy preparation (the lobe probabilities by energy, the coherent reflectivities and
transmissivity per plugin channel) and the Dr.Jit sampling of the four specular directions.

The lobes — those of Mitsuba's smooth ``dielectric`` (``src/bsdfs/dielectric.cpp``), with the
Fresnel factors replaced by the tables' coherent parts:

* outside reflection ``R_coh(θi, λ)`` (the reflection table's ``coherent``), mirror direction;
* transmission from outside ``T_coh(θi, λ)`` (the BTDF table's ``coherent``), Snell direction;
* inside reflection ``R_coh,in`` (the inner table's ``coherent``), mirror direction;
* transmission from inside at ``θ`` (inside): ``T_coh(θ_out)`` with ``sin θ_out = η sin θ``
  (the coherent transmissivity is reciprocal: ``T_F`` is, and ``exp(−σ²(k₁cosθ₁ − k₂cosθ₂)²)``
  is symmetric in the two sides), 0 beyond the critical angle.

Radiance scale of a refracted delta sample (``dielectric``'s ``η_ti²``): ``1/ε`` for a viewer
outside, ``ε`` for a viewer inside in radiance transport, 1 in importance transport. The
refraction and the Snell map take the mean ``η = √ε`` (one direction per path, as
``dielectric``); the transmissivities themselves are per table wavelength.

Lobe choice by energy at the viewer's θ (channel luminance): the delta lobes together with
probability ``P_δ = (R_coh + T_coh) / (R_coh + T_coh + R_inc + T_inc)`` (inside, the glossy
energy is ``1 − R_coh,in − T_coh,in``: the inside BTDF's albedo is not tabulated), then
reflection vs refraction by ``R_coh / (R_coh + T_coh)``; the glossy lobes with ``1 − P_δ`` and
the plugin's glossy rule. A sample's weight is the coherent part over its discrete
probability, its ``pdf`` that probability (Mitsuba's delta convention).

Interpolation in θ: the coherent parts are interpolated as their ratios to the smooth
interface's Fresnel powers ``R_F``, ``T_F = 1 − R_F`` (unpolarized, at the mean ``ε``),
multiplied back by the exact Fresnel power at the sampled angle: the ratio is the smooth
roughness factor (``exp(−(2kσcosθ)²)`` for PO's reflection), while ``R_F`` jumps to 1 at the
critical angle inside and rises steeply at grazing incidence (a 3° grid interpolated directly
made ``R + T`` reach 1.34 just below the critical angle). At the tables' nodes the product is
the table's value at every table wavelength (the ratio there is ``coh_λ / R_F(ε̄)``); between
nodes it follows the mean ``ε``'s Fresnel curve.
"""

from __future__ import annotations

import math

import numpy as np

from ...fresnel import reflectivity
from ..plugin_data import Axis

__all__ = ["DeltaData", "delta_data"]

_RESAMPLE = 361  # nodes of the uniform θ grid a non-uniform axis is resampled onto


class DeltaData:
    """Float32 arrays on uniform θ axes: ``r_out`` / ``t_out`` / ``r_in`` ``(n_θ, C)``
    coherent parts per plugin channel over the smooth interface's Fresnel power at the mean
    ``ε`` (``R_coh/R_F``, ``T_coh/T_F``, ``R_coh,in/R_F,in``; ``r_in`` None without an inner
    table), ``p_out`` /
    ``p_in`` ``(n_θ, 2)`` = ``(P_δ, P(reflection | δ))`` at the viewer's θ (outside: on the
    BTDF's θi axis; inside: on the inner table's, or a 1° grid without it)."""

    def __init__(self, **kw):
        self.__dict__.update(kw)


def _uniform(theta, values):
    """``(Axis, values)`` on a uniform axis: as given, or resampled linearly (axis 0)."""
    theta = np.asarray(theta, float)
    ax = Axis.of(theta)
    if ax.uniform:
        return ax, np.asarray(values, float)
    grid = np.linspace(theta[0], theta[-1], _RESAMPLE)
    vals = np.asarray(values, float)
    out = np.stack([np.interp(grid, theta, vals[:, c]) for c in range(vals.shape[1])], 1)
    return Axis.of(grid), out


def delta_data(reflection, transmission, inner, mat, lum, eta: float) -> DeltaData | None:
    """The delta lobes' data (module docstring), None when no table has a coherent part.
    ``mat``: ``(C, n_wl)`` plugin channels from the wavelengths; ``lum``: ``(n_wl,)``
    luminance weights; ``eta``: the mean refractive index ``√ε``."""

    def coh(t):
        c = getattr(t, "coherent", None)
        return None if t is None or c is None else np.clip(np.asarray(c, float), 0.0, 1.0)

    rc, tc, ric = coh(reflection), coh(transmission), coh(inner)
    if not any(c is not None and np.any(c > 0) for c in (rc, tc, ric)):
        return None
    bt = transmission
    ti = np.asarray(bt.theta_i, float)
    theta_r = np.asarray(reflection.theta_i, float)
    zero_t = np.zeros((bt.wavelengths.size, ti.size))
    rc = np.zeros((bt.wavelengths.size, theta_r.size)) if rc is None else rc
    tc = zero_t if tc is None else tc
    # outside, on the BTDF's θi nodes
    r_d = np.interp(ti, theta_r, lum @ rc)
    r_g = np.interp(ti, theta_r, lum @ reflection.albedo().incoherent)
    t_d, t_g = lum @ tc, lum @ bt.incoherent_albedo()
    p_out = _probabilities(r_d, t_d, r_g + t_g)
    # inside: the inner table's θ nodes (1° without it); T_coh at the Snell-mapped angle
    th_in = np.linspace(0, 0.5 * math.pi, 91) if inner is None else np.asarray(inner.theta_i)
    s_out = eta * np.sin(th_in)
    t_d_in = np.where(s_out < 1, np.interp(np.arcsin(np.minimum(s_out, 1)), ti, t_d), 0.0)
    if inner is None or ric is None:
        r_d_in = np.zeros_like(th_in)
    else:
        r_d_in = lum @ ric
    p_in = _probabilities(r_d_in, t_d_in, np.clip(1.0 - r_d_in - t_d_in, 0.0, 1.0))
    # stored as ratios to the smooth Fresnel powers at the mean ε (the plugin multiplies them
    # back): smooth in θ where R_F, T_F are not (the critical angle, grazing incidence)
    eps = eta**2
    f_out = reflectivity(eps, theta_r).mean(0)
    t_f = 1.0 - reflectivity(eps, ti).mean(0)
    ax_r, r_out = _uniform(theta_r, (rc / f_out).T @ mat.T)
    ax_t, t_out = _uniform(ti, (tc / np.where(t_f > 1e-9, t_f, np.inf)).T @ mat.T)
    ax_pi, p_in = _uniform(th_in, p_in)
    ax_po, p_out = _uniform(ti, p_out)
    r_in = ax_ri = None
    if inner is not None and ric is not None:
        f_in = reflectivity(1.0 / eps, np.asarray(inner.theta_i, float)).mean(0)
        ax_ri, r_in = _uniform(inner.theta_i, (ric / f_in).T @ mat.T)
    f32 = np.float32
    return DeltaData(
        ax_r=ax_r, r_out=r_out.astype(f32), ax_t=ax_t, t_out=t_out.astype(f32),
        ax_ri=ax_ri, r_in=None if r_in is None else r_in.astype(f32),
        ax_po=ax_po, p_out=p_out.astype(f32), ax_pi=ax_pi, p_in=p_in.astype(f32),
    )  # fmt: skip


def _probabilities(r_d, t_d, glossy):
    """``(P_δ, P(reflection | δ))`` per node from the three energies."""
    d = r_d + t_d
    p_delta = np.where(d > 0, d / np.maximum(d + glossy, 1e-12), 0.0)
    p_r = np.where(d > 0, r_d / np.maximum(d, 1e-30), 0.5)
    return np.stack([np.clip(p_delta, 0.0, 1.0), np.clip(p_r, 0.0, 1.0)], 1)


def refract(mi, dr, v, eta):
    """Mitsuba's ``refract(wi, cos_theta_t, eta_ti)`` for the flat normal ``ẑ``: the Snell
    direction of the viewer ``v`` through the interface, ``eta`` = n(inside)/n(outside).
    Returns ``(wo, ok, eta_it)``: ``ok`` false beyond the critical angle."""
    out = v.z > 0
    eta_it = dr.select(out, eta, 1.0 / eta)
    eta_ti = 1.0 / eta_it
    c2 = 1.0 - dr.square(eta_ti) * (1.0 - dr.square(v.z))
    ok = c2 > 0
    cos_t = dr.sqrt(dr.maximum(c2, 0.0))
    wo = mi.Vector3f(-eta_ti * v.x, -eta_ti * v.y, dr.select(out, -cos_t, cos_t))
    return wo, ok, eta_it
