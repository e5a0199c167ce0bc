"""The one conversion between the renderer frame and emscatter's frame.

Renderer frame (Mitsuba 3, MERL, RGL ``.bsdf``, pbrt): local shading frame with the mean
normal along ``+z`` and the surface tangent along ``+x`` (Mitsuba's ``alpha_u`` direction);
both directions ``wi`` (towards the light) and ``wo`` (towards the viewer) point *away* from
the surface::

    w(θ, φ) = (sinθ cosφ, sinθ sinφ, cosθ),   mirror direction of wi at θo = θi, φo = φi + π.

emscatter's frame (:mod:`emscatter.conventions`): the incident wave *propagates* along
``k̂_i = (sinθi cosφi, sinθi sinφi, −cosθi)`` and the scattered wave along
``k̂_s = (sinθs cosφs, sinθs sinφs, cosθs)``; specular at ``θs = θi, φs = φi``.

Since ``k̂_i = −wi`` and ``k̂_s = wo``::

    θi = θi,   φi(emscatter) = φi(renderer) + π,   θs = θo,   φs = φo,
    Δφ(emscatter) = φs − φi = Δφ(renderer) − π      (Δφ(renderer) = φo − φi).

Same x axis in both frames, so anisotropic roughness (ℓx along x) means the same thing.
Tested against Mitsuba 3's own ``roughconductor`` (``tests/test_brdf_frames.py``): the
emscatter geometric-optics σ⁰ evaluated at the converted angles equals Mitsuba's
``eval(wi, wo)/cosθo`` for anisotropic Beckmann roughness (an error of π in φ or a swapped
axis shows up there as a lobe in the wrong place).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "directions",
    "angles",
    "to_emscatter",
    "from_emscatter",
    "renderer_dphi_to_emscatter",
    "mirror",
    "fold_dphi",
]


def directions(theta, phi) -> np.ndarray:
    """Unit vectors ``(sinθ cosφ, sinθ sinφ, cosθ)`` [-], shape ``(*broadcast, 3)``."""
    theta, phi = np.broadcast_arrays(np.asarray(theta, float), np.asarray(phi, float))
    s = np.sin(theta)
    return np.stack([s * np.cos(phi), s * np.sin(phi), np.cos(theta)], axis=-1)


def angles(w, name: str = "w") -> tuple[np.ndarray, np.ndarray]:
    """``(θ, φ)`` [rad] of direction vectors ``w`` (shape ``(..., 3)``, any nonzero length);
    ``θ ∈ [0, π]`` (``> π/2`` below the horizon), ``φ ∈ (−π, π]`` (0 on the normal)."""
    w = np.asarray(w, dtype=float)
    if w.ndim == 0 or w.shape[-1] != 3:
        raise ValueError(f"{name} must have shape (..., 3) (direction vectors), got {w.shape}")
    if not np.all(np.isfinite(w)):
        raise ValueError(f"{name} must be finite, got NaN or inf in an array of shape {w.shape}")
    x, y, z = w[..., 0], w[..., 1], w[..., 2]
    rho = np.hypot(x, y)
    if np.any((rho == 0) & (z == 0)):
        raise ValueError(f"{name} holds a zero vector (a direction needs a nonzero length)")
    return np.arctan2(rho, z), np.arctan2(y, x)


def to_emscatter(theta_i, phi_i, theta_o, phi_o) -> tuple[np.ndarray, ...]:
    """Renderer angles ``(θi, φi, θo, φo)`` [rad] → emscatter's ``(θi, θs, φs, φi)`` [rad],
    the argument order of :func:`emscatter.api.bistatic` (``theta_i, theta_s, phi_s,
    phi_i``). Arrays broadcast."""
    ti, pi_, to, po = np.broadcast_arrays(
        *(np.asarray(a, float) for a in (theta_i, phi_i, theta_o, phi_o))
    )
    return ti, to, po, pi_ + math.pi


def from_emscatter(theta_i, theta_s, phi_s, phi_i) -> tuple[np.ndarray, ...]:
    """Inverse of :func:`to_emscatter`: emscatter ``(θi, θs, φs, φi)`` → renderer
    ``(θi, φi, θo, φo)`` [rad]."""
    ti, ts, ps, pi_ = np.broadcast_arrays(
        *(np.asarray(a, float) for a in (theta_i, theta_s, phi_s, phi_i))
    )
    return ti, pi_ - math.pi, ts, ps


def renderer_dphi_to_emscatter(dphi) -> np.ndarray:
    """Renderer ``Δφ = φo − φi`` → emscatter ``Δφ = φs − φi`` (``Δφ − π``) [rad]."""
    return np.asarray(dphi, float) - math.pi


def fold_dphi(dphi) -> np.ndarray:
    """Fold a renderer azimuth difference into ``[0, π]`` (isotropic tables: ``f(Δφ)`` is
    even and 2π-periodic); the mirror direction is at ``π``."""
    d = np.remainder(np.asarray(dphi, float), 2 * math.pi)  # [0, 2π)
    return np.where(d > math.pi, 2 * math.pi - d, d)


def mirror(w) -> np.ndarray:
    """Mirror direction about the mean normal ``+z`` (renderer frame): ``(−x, −y, z)``."""
    w = np.asarray(w, dtype=float)
    return w * np.array([-1.0, -1.0, 1.0])
