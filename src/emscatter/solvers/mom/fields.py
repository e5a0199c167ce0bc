"""Incident and radiated fields of the 1-D method of moments (:mod:`emscatter.solvers.mom.model`).

* Thorsos's tapered plane wave and its incident power (Thorsos 1988, JASA 83, 78), by
  quadrature of the Poynting flux through ``z = 0``;
* the far-field amplitude radiated by the surface sources into either medium (stationary
  phase of the 2-D Green's function, Tsang et al. 2001 vol. II ch. 4);
* the Gauss–Legendre angular grid used to integrate scattered power.
"""

from __future__ import annotations

import functools
import math

import numpy as np
from scipy import special


def tapered_wave(x, z, k: float, theta_i: float, g: float) -> np.ndarray:
    """Thorsos's tapered plane wave ``ψ_inc(x, z)`` (Thorsos 1988) [-].

    ``x, z`` [m], ``k`` [rad/m], ``theta_i`` [rad] (incidence towards +x), ``g`` [m].
    """
    x = np.asarray(x, dtype=float)
    z = np.asarray(z, dtype=float)
    ci, si = math.cos(theta_i), math.sin(theta_i)
    t = x + z * math.tan(theta_i)
    w = (2.0 * t * t / (g * g) - 1.0) / (k * g * ci) ** 2
    return np.exp(1j * k * (x * si - z * ci) * (1.0 + w) - t * t / (g * g))


def _dz_tapered_wave(x, k: float, theta_i: float, g: float) -> np.ndarray:
    """``∂ψ_inc/∂z`` at ``z = 0``, differentiated analytically from :func:`tapered_wave`."""
    ci, si, ti = math.cos(theta_i), math.sin(theta_i), math.tan(theta_i)
    a = 1.0 / (k * g * ci) ** 2
    w = (2.0 * x * x / (g * g) - 1.0) * a
    dw_dz = 4.0 * x * ti / (g * g) * a
    dphase_dz = k * (-ci * (1.0 + w) + x * si * dw_dz)
    psi = tapered_wave(x, 0.0, k, theta_i, g)
    return psi * (1j * dphase_dz - 2.0 * x * ti / (g * g))


def incident_power(k: float, theta_i: float, g: float, *, n: int = 4001) -> float:
    """Power of the tapered wave through the plane ``z = 0`` [m] (flux ``Im(ψ*∇ψ)/k``,
    so a unit plane wave carries ``cosθi`` per metre): ``P = −(1/k)∫ Im(ψ* ∂ψ/∂z) dx``,
    by the trapezoidal rule over ``|x| ≤ 8g`` (spectrally accurate for a Gaussian)."""
    x = np.linspace(-8.0 * g, 8.0 * g, n)
    psi = tapered_wave(x, 0.0, k, theta_i, g)
    flux = -np.imag(np.conj(psi) * _dz_tapered_wave(x, k, theta_i, g)) / k
    return float(np.trapezoid(flux, x))


def incident_power_thorsos(k: float, theta_i: float, g: float) -> float:
    """Thorsos's closed form (1988), ``g√(π/2) cosθi [1 − (1+2tan²θi)/(2k²g²cos²θi)]``
    [m]; equal to :func:`incident_power` (the integral is Gaussian)."""
    ci = math.cos(theta_i)
    return (
        g
        * math.sqrt(math.pi / 2)
        * ci
        * (1.0 - (1.0 + 2.0 * math.tan(theta_i) ** 2) / (2.0 * (k * g * ci) ** 2))
    )


def _expi(phase: np.ndarray) -> np.ndarray:
    """``exp(i·phase)`` for real ``phase``: reduced to ``[−π, π]`` in float64, cosine and sine
    in float32 (SIMD), absolute error ~1.5e-7 (see
    :func:`emscatter.solvers.mom.operators._asym_real`)."""
    if np.iscomplexobj(phase):
        return np.exp(1j * phase)
    r = (phase - (2.0 * math.pi) * np.rint(phase * (0.5 / math.pi))).astype(np.float32)
    e = np.empty(phase.shape, complex)
    e.real = np.cos(r)
    e.imag = np.sin(r)
    return e


def _far_field(kk, x, z, fp, psi, u, theta, *, upward=True, rho=1.0, chunk=1 << 20):
    """Far-field amplitude ``A(θ)`` [m^½] radiated by the surface sources.

    ``upward=True``: medium 1, direction ``(sinθ, cosθ)``,
    ``A = c ∫[ik(f' sinθ − cosθ)ψ − u] e^{−ik(x sinθ + z cosθ)} dx``;
    ``upward=False``: medium 2 (``ψ₂ = −D₂ψ + ρ S₂u``), direction ``(sinθ, −cosθ)``,
    ``A = c ∫[−ik₂(f' sinθ + cosθ)ψ + ρu] e^{−ik₂(x sinθ − z cosθ)} dx``,
    ``c = (i/4)√(2/(πk)) e^{−iπ/4} dx`` (stationary phase of H0, A&S 9.2.3).
    """
    theta = np.asarray(theta, dtype=float)
    dx = x[1] - x[0]
    c = 0.25j * np.sqrt(2.0 / (math.pi * kk)) * np.exp(-0.25j * math.pi) * dx
    out = np.empty(theta.shape, complex)
    flat = theta.ravel()
    res = out.reshape(-1)
    step = max(1, chunk // x.size)
    sgn = 1.0 if upward else -1.0
    src = np.stack([psi, fp * psi, u], axis=1)
    for i in range(0, flat.size, step):
        t = flat[i : i + step]
        st, ct = np.sin(t)[:, None], np.cos(t)[:, None]
        e = _expi(-kk * (st * x[None, :] + sgn * ct * z[None, :]))
        ep, efp, eu = (e @ src).T
        if upward:
            res[i : i + step] = c * (1j * kk * (st[:, 0] * efp - ct[:, 0] * ep) - eu)
        else:
            res[i : i + step] = c * (-1j * kk * (st[:, 0] * efp + ct[:, 0] * ep) + rho * eu)
    return out


@functools.lru_cache(maxsize=16)
def _gauss_theta(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss–Legendre nodes and weights on ``(−π/2, π/2)``."""
    t, w = special.roots_legendre(n)
    return t * (math.pi / 2), w * (math.pi / 2)


def _n_quad(kk: float, length: float) -> int:
    return int(0.6 * kk * length) + 256
