"""The tapered incident wave of the 3-D method of moments and its power.

The 3-D Thorsos-type taper of Tsang, Kong, Ding & Ao, *Scattering of Electromagnetic Waves*
vol. II (2001) ch. 10 (and Tsang et al.'s SMCG papers) is a Gaussian spectrum of plane waves
around the nominal incident direction::

    E_inc(r) = ∫∫ ψ(k⊥) ê(k) exp(i k⊥·ρ − i k_z z) d²k⊥,
    ψ(k⊥) = (g² / 4π) exp(−g² |k⊥ − k_i⊥|² / 4),     k_z = √(k² − |k⊥|²),

so that on ``z = 0`` the field is ``exp(i k_i⊥·ρ − ρ²/g²)`` to leading order (footprint of
radius ``g``). Tsang's closed form expands the integral about ``k_i⊥`` (Thorsos's
``1 + w`` phase correction in 3-D); here the integral itself is evaluated, by the trapezoidal
rule on a ``k⊥`` grid that resolves ψ and whose alias period ``2π/Δk`` puts every alias beam
at least ``6g`` beyond the patch (amplitude ≤ e⁻³⁶). Only propagating components
(``|k⊥| < k``) are kept, so the field is an exact Maxwell solution and its power through
``z = 0`` is, by Parseval, exactly::

    P_inc = (2π)² ∫∫ |ψ|² (k_z / k) d²k⊥                              [m²]

(fluxes ``E × H*`` with ``η = 1``, no ½, the same normalization as the scattered power
``r² |E_s|²``). A unit plane wave on area ``A`` carries ``A cosθi``; the leading term of
``P_inc`` is ``(π g² / 2) cosθi``.

Polarization of each component (smooth in ``k⊥``, also at normal incidence):
``ê_h(k) ∝ ĥ_i − (ĥ_i·k̂) k̂`` and ``ê_v = ê_h × k̂``, with the nominal
``ĥ_i = (−sinφi, cosφi, 0)`` and ``v̂_i = ĥ_i × k̂_i`` (so ``ê_v = v̂_i`` at the centre).
Magnetic field (``H`` in units of ``E/η``): ``H = k̂ × E``, i.e. ``−ê_v`` for h and ``ê_h``
for v.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["TaperedBeam", "tapered_beam"]

#: ψ is kept out to ``|k⊥ − k_i⊥| ≤ SPECTRAL_RADIUS / g`` (amplitude e^{-SPECTRAL_RADIUS²/4}).
SPECTRAL_RADIUS = 7.5


@dataclass(frozen=True)
class TaperedBeam:
    """A tapered incident wave as a list of plane waves.

    Attributes
    ----------
    k : wavenumber [rad/m]; theta_i, phi_i : nominal direction [rad]; g : taper radius [m].
    kvec : ``(M, 3)`` wave vectors ``(k_x, k_y, −k_z)`` [rad/m] (downgoing).
    weight : ``(M,)`` ψ Δk² (the quadrature weight of each plane wave) [-].
    e_h, e_v : ``(M, 3)`` unit polarization vectors of the h and v beams.
    power : the incident power through ``z = 0`` [m²] (module docstring).
    """

    k: float
    theta_i: float
    phi_i: float
    g: float
    kvec: np.ndarray
    weight: np.ndarray
    e_h: np.ndarray
    e_v: np.ndarray
    power: float

    def fields(self, points: np.ndarray, pol: str) -> tuple[np.ndarray, np.ndarray]:
        """``E_inc, H_inc`` at ``points`` (``(N, 3)`` [m]) for ``pol`` ``"h"`` or ``"v"``;
        each ``(N, 3)`` complex, ``H`` in units of ``E/η``."""
        e = self.e_h if pol == "h" else self.e_v
        khat = self.kvec / self.k
        hvec = np.cross(khat, e)
        phase = np.exp(1j * (points @ self.kvec.T)) * self.weight  # (N, M)
        return phase @ e, phase @ hvec


def _polarizations(khat: np.ndarray, theta_i: float, phi_i: float) -> tuple[np.ndarray, ...]:
    h_i = np.array([-math.sin(phi_i), math.cos(phi_i), 0.0])
    e_h = h_i - (khat @ h_i)[:, None] * khat
    e_h /= np.linalg.norm(e_h, axis=1)[:, None]
    e_v = np.cross(e_h, khat)
    return e_h, e_v


def tapered_beam(k: float, theta_i: float, phi_i: float, g: float, extent: float) -> TaperedBeam:
    """The tapered wave of radius ``g`` [m] for a patch whose points lie within ``extent`` [m]
    of the origin (horizontal distance), at wavenumber ``k`` [rad/m] and nominal incidence
    ``(theta_i, phi_i)`` [rad]."""
    kix = k * math.sin(theta_i) * math.cos(phi_i)
    kiy = k * math.sin(theta_i) * math.sin(phi_i)
    period = 2.0 * extent + 6.0 * g
    dk = 2.0 * math.pi / period
    half = int(math.ceil(SPECTRAL_RADIUS / g / dk))
    off = np.arange(-half, half + 1) * dk
    ox, oy = np.meshgrid(off, off, indexing="ij")
    ox, oy = ox.ravel(), oy.ravel()
    keep = ox * ox + oy * oy <= (SPECTRAL_RADIUS / g) ** 2
    kx, ky = kix + ox[keep], kiy + oy[keep]
    kperp2 = kx * kx + ky * ky
    prop = kperp2 < k * k * (1.0 - 1e-12)
    kx, ky, kperp2 = kx[prop], ky[prop], kperp2[prop]
    kz = np.sqrt(k * k - kperp2)
    psi = g * g / (4.0 * math.pi) * np.exp(-(g * g) * ((kx - kix) ** 2 + (ky - kiy) ** 2) / 4.0)
    kvec = np.stack([kx, ky, -kz], axis=1)
    e_h, e_v = _polarizations(kvec / k, theta_i, phi_i)
    power = float((2.0 * math.pi) ** 2 * np.sum(psi * psi * kz / k) * dk * dk)
    return TaperedBeam(k, theta_i, phi_i, g, kvec, psi * dk * dk, e_h, e_v, power)
