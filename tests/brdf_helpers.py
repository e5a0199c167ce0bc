"""Shared helpers for the BRDF tests: Mitsuba 3 evaluation in the renderer frame."""

from __future__ import annotations

import math

import numpy as np

from emscatter import api
from emscatter.brdf import frames


def mitsuba_variant(mi, names=("llvm_ad_rgb", "scalar_rgb")) -> str | None:
    """Set the first Mitsuba variant that loads here; None when none does."""
    for name in names:
        try:
            mi.set_variant(name)
            mi.load_dict({"type": "diffuse"})
            return name
        except Exception:  # variant unavailable (e.g. no libLLVM for llvm_ad_rgb)
            continue
    return None


def mitsuba_fr(mi, bsdf_dict: dict, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
    """Mitsuba's own ``f_r(wi, wo)`` [1/sr] (``eval`` returns ``f_r cosθo``), first channel;
    ``wi``, ``wo`` unit vectors of shape (N, 3) in the local frame, pointing away."""
    bsdf = mi.load_dict(bsdf_dict)
    ctx = mi.BSDFContext()
    wi = np.asarray(wi, float)
    wo = np.asarray(wo, float)
    if mi.variant().startswith("scalar"):
        out = np.empty(len(wi))
        for j in range(len(wi)):
            si = mi.SurfaceInteraction3f()
            si.wi = mi.Vector3f(*wi[j])
            out[j] = bsdf.eval(ctx, si, mi.Vector3f(*wo[j]))[0]
    else:
        si = mi.SurfaceInteraction3f()
        si.wi = mi.Vector3f(*(mi.Float(c) for c in wi.T))
        val = bsdf.eval(ctx, si, mi.Vector3f(*(mi.Float(c) for c in wo.T)))
        out = np.array(val[0], dtype=float)
    cos_o = wo[:, 2]
    return np.where(cos_o > 0, out / np.where(cos_o > 0, cos_o, 1.0), 0.0)


def random_directions(rng, n: int, max_theta: float) -> np.ndarray:
    """``n`` directions in the upper hemisphere with θ ≤ max_theta [rad] (uniform in cosθ)."""
    cos_t = rng.uniform(np.cos(max_theta), 1.0, n)
    phi = rng.uniform(0, 2 * np.pi, n)
    s = np.sqrt(1 - cos_t**2)
    return np.stack([s * np.cos(phi), s * np.sin(phi), cos_t], axis=-1)


def go_fr(rough, eps, wi, wo, convert=frames.to_emscatter, **options) -> np.ndarray:
    """emscatter's GO unpolarized f_r [1/sr] at renderer-frame directions (``wavelength=1``),
    separable Smith shadowing unless ``shadowing=`` says otherwise."""
    options.setdefault("shadowing", SEPARABLE)
    ti, pi_ = frames.angles(wi)
    to, po = frames.angles(wo)
    et, es, ps, ei = convert(ti, pi_, to, po)
    res = api.bistatic(
        rough,
        eps,
        wavelength=1.0,
        theta_i=et,
        theta_s=es,
        phi_s=ps,
        phi_i=ei,
        method="go",
        out_of_range="ignore",
        **options,
    )
    return res.unpolarized() / (4 * math.pi * np.cos(ti) * np.cos(to))


def separable_shadowing() -> str:
    """The GO ``shadowing`` option for Mitsuba's separable Smith product ``G1(wi) G1(wo)``
    everywhere: ``"separable"`` where the solver knows it (the accuracy branch makes the
    default monostatic at exact backscatter), else ``"smith"`` (the separable product)."""
    from emscatter.solvers.kirchhoff.common import check_shadowing

    try:
        check_shadowing("separable")
        return "separable"
    except ValueError:
        return "smith"


SEPARABLE = separable_shadowing()
