"""Shared helpers for the BRDF tests: Mitsuba 3 evaluation in the renderer frame."""

from __future__ import annotations

import numpy as np


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
