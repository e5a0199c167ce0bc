"""Far field radiated by the surface current of the 3-D method of moments, and the hemisphere
quadrature that integrates scattered power.

With ``exp(−iωt)``, ``E = iωμ (I − k̂k̂)·∫ G J dS`` (``H`` and ``J`` in units of ``E/η``, so
``ωμ → k``); far from the patch (``r → ∞`` along ``k̂_s``)::

    E_s = i k e^{ikr} / (4π r) (I − k̂_s k̂_s)·F,   F = Σ_n u_n e^{−i k k̂_s·r_n} Δx Δy,

and the power per steradian is ``r² |p̂_s·E_s|² = k² |p̂_s·F|² / (16π²)`` for the scattered
polarization ``p̂_s`` (:mod:`emscatter.conventions`: ``ĥ_s = (−sinφs, cosφs, 0)``,
``v̂_s = ĥ_s × k̂_s = (cosθs cosφs, cosθs sinφs, −sinθs)``; signs do not enter powers). With
the incident power ``P_inc`` (:mod:`.incident`), the package's σ⁰
(``r = 1/(4π cosθi) Σ∫σ⁰ dΩ``) is ``σ⁰ = 4π cosθi (dP/dΩ) / P_inc
= k² cosθi |p̂_s·F|² / (4π P_inc)``.

:func:`amplitudes` sums ``F`` directly (``O(N D)``, the reference) or, for points on a regular
``(x, y)`` grid (every patch of :mod:`.operator`), by the Taylor-in-height / non-uniform-FFT
scheme of :mod:`.gridsum` (``O(Q (N log N + D w²))``, error ``≤ tol Σ_n |u_n| ΔxΔy``):
``method="auto"`` takes it above :data:`FAST_MIN_WORK` point-direction pairs.
:func:`amplitudes_em` is the same for the two densities ``u = sJ``, ``w = sM`` of the
dielectric (Müller) formulation radiating into a medium of real index ``n``
(:mod:`.dielectric_model`: ``p̂·(F_u − n k̂ × F_w)`` with ``F_X = Σ X_n e^{−i n k₀ k̂·r_n}
ΔxΔy``): both take the same six planar sums per incident polarization through
:func:`far_sums`, by the same two methods and the same bound per component.
"""

from __future__ import annotations

import math

import numpy as np

from emscatter.solvers.mom3d.gridsum import grid_of, grid_sums

__all__ = ["amplitudes", "amplitudes_em", "far_sums", "hemisphere", "pol_vectors"]

#: Directions per block in :func:`amplitudes` (bounds the ``(block, N)`` phase matrix).
DIR_BLOCK = 512
#: ``method="auto"`` sums by :mod:`.gridsum` above this many point × direction pairs.
FAST_MIN_WORK = 2_000_000
#: Default error bound of the fast sum, relative to ``Σ_n |u_n| ΔxΔy``.
FAST_TOL = 1e-7
METHODS = ("auto", "direct", "fast")


def pol_vectors(
    theta_s: np.ndarray, phi_s: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``k̂_s, ĥ_s, v̂_s``, each ``(D, 3)``, for flat direction arrays [rad]."""
    st, ct = np.sin(theta_s), np.cos(theta_s)
    sp, cp = np.sin(phi_s), np.cos(phi_s)
    khat = np.stack([st * cp, st * sp, ct], axis=1)
    h = np.stack([-sp, cp, np.zeros_like(sp)], axis=1)
    v = np.stack([ct * cp, ct * sp, -st], axis=1)
    return khat, h, v


def far_sums(points, kvec, src: np.ndarray, *, method: str = "auto", tol: float = FAST_TOL):
    """``S[d, t] = Σ_n src[n, t] e^{−i kvec_d·r_n}`` ``(D, T)`` for the sources ``src``
    ``(N, T)`` at ``points`` ``(N, 3)`` [m] and real wavevectors ``kvec`` ``(D, 3)`` [rad/m]:
    ``"direct"`` (blocks of :data:`DIR_BLOCK` directions), ``"fast"`` (:mod:`.gridsum`, error
    ``≤ tol Σ_n |src[n, t]|``; the points must lie on a regular ``(x, y)`` grid, ``x``
    fastest) or ``"auto"`` (fast on a grid above :data:`FAST_MIN_WORK` pairs)."""
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    d_all = kvec.shape[0]
    grid = None
    if method == "fast" or (method == "auto" and src.shape[0] * d_all > FAST_MIN_WORK):
        grid = grid_of(points)
        if grid is None and method == "fast":
            raise ValueError("method='fast' needs points on a regular (x, y) grid, x fastest")
    if grid is not None:
        return grid_sums(src.T, points[:, 2], grid, kvec, tol=tol).T
    out = np.empty((d_all, src.shape[1]), dtype=complex)
    for d0 in range(0, d_all, DIR_BLOCK):
        d = slice(d0, min(d_all, d0 + DIR_BLOCK))
        out[d] = np.exp(-1j * (kvec[d] @ points.T)) @ src
    return out


def amplitudes(
    points,
    area: float,
    k: float,
    u: np.ndarray,
    theta_s,
    phi_s,
    *,
    method: str = "auto",
    tol: float = FAST_TOL,
) -> np.ndarray:
    """``p̂_s·F`` for the densities ``u`` (``(P, N, 3)``: one per incident polarization) in the
    directions ``theta_s, phi_s`` (flat, ``(D,)``) [rad]; returns ``(2, P, D)`` complex
    (index 0 = h, 1 = v scattered), in units of m² (per unit incident amplitude).

    ``method``: ``"direct"`` (the ``O(N D)`` sum), ``"fast"`` (:mod:`.gridsum`; the points
    must lie on a regular ``(x, y)`` grid, ``x`` fastest; error ``≤ tol Σ|u| area`` per
    component) or ``"auto"`` (fast on a grid above :data:`FAST_MIN_WORK` pairs)."""
    theta_s = np.asarray(theta_s, dtype=float).ravel()
    phi_s = np.asarray(phi_s, dtype=float).ravel()
    khat, hs, vs = pol_vectors(theta_s, phi_s)
    p = u.shape[0]
    uu = u.transpose(1, 0, 2).reshape(u.shape[1], 3 * p)  # (N, 3P)
    f = far_sums(points, k * khat, uu, method=method, tol=tol).reshape(-1, p, 3) * area
    return np.stack([np.einsum("dpc,dc->pd", f, hs), np.einsum("dpc,dc->pd", f, vs)])


def amplitudes_em(
    points,
    area: float,
    k0: float,
    n_med: float,
    u: np.ndarray,
    w: np.ndarray,
    theta_s,
    phi_s,
    *,
    method: str = "auto",
    tol: float = FAST_TOL,
) -> np.ndarray:
    """``p̂·(F_u − n k̂ × F_w)`` ``(2, P, D)`` (h, v scattered) for densities ``u, w``
    ``(P, N, 3)`` radiating into a medium of real index ``n_med`` in directions
    ``theta_s, phi_s`` [rad] (flat; ``θ > π/2`` below the interface) [m²]
    (:mod:`.dielectric_model`'s far field). ``method`` and ``tol`` as :func:`amplitudes`'s:
    the fast sum's error per component of ``F_u`` (``F_w``) is ``≤ tol Σ|u| area``
    (``tol Σ|w| area``), so that of the amplitude is ``≤ tol area (Σ|u| + n Σ|w|)`` (sums of
    the component moduli; ``|p̂| = 1``, ``|k̂ × e| ≤ |e|``)."""
    theta_s = np.asarray(theta_s, dtype=float).ravel()
    phi_s = np.asarray(phi_s, dtype=float).ravel()
    khat, hs, vs = pol_vectors(theta_s, phi_s)
    p = u.shape[0]
    uu = np.concatenate([u, w], axis=0).transpose(1, 0, 2).reshape(u.shape[1], 6 * p)
    f = far_sums(points, k0 * n_med * khat, uu, method=method, tol=tol)
    f = f.reshape(-1, 2 * p, 3) * area
    vec = f[:, :p] - n_med * np.cross(khat[:, None, :], f[:, p:])
    return np.stack([np.einsum("dpc,dc->pd", vec, hs), np.einsum("dpc,dc->pd", vec, vs)])


def hemisphere(n_mu: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Upper-hemisphere quadrature: Gauss–Legendre in ``μ = cosθ ∈ (0, 1)`` × ``2 n_mu``
    uniform azimuths (exact for trigonometric polynomials). Returns flat
    ``theta, phi, weight`` with ``Σ weight = 2π`` [rad, rad, sr]."""
    x, w = np.polynomial.legendre.leggauss(n_mu)
    mu, wmu = 0.5 * (x + 1.0), 0.5 * w
    n_phi = 2 * n_mu
    phi = (np.arange(n_phi) + 0.5) * (2.0 * math.pi / n_phi)
    th = np.arccos(mu)
    tt, pp = np.meshgrid(th, phi, indexing="ij")
    ww = np.outer(wmu, np.full(n_phi, 2.0 * math.pi / n_phi))
    return tt.ravel(), pp.ravel(), ww.ravel()
