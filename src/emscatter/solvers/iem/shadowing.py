"""Shadowing of the IEM's single-scattering terms (:mod:`emscatter.solvers.iem.model`):
Smith's Λ per direction (Smith 1967; :func:`emscatter.solvers.kirchhoff.common.smith_lambda`),
combined bistatically either height-correlated, ``1/(1 + Λi + Λs)`` (Walter et al. 2007), or
direction-correlated (Heitz 2014's interpolation in the azimuth ψ between −k_i and k_s:
``1/(1 + max Λ + c(ψ) min Λ)``, c = 4.41ψ/(4.41ψ + 1)), which is the monostatic ``1/(1 + Λ)`` in
backscatter; and the same factor's arguments for the compiled backscatter kernel."""

from __future__ import annotations

import math

import numpy as np

from emscatter.solvers.iem import compiled as iem_jit
from emscatter.solvers.kirchhoff.common import smith_lambda

_SHADOW_MODES = {
    True: "direction-correlated",
    "direction-correlated": "direction-correlated",
    "height-correlated": "height-correlated",
    False: None,
    None: None,
}


def _shadowing(mode, loc, slope) -> np.ndarray | float:
    """Bistatic shadowing factor (module docstring) on a checked chunk; 1 for ``mode=None``."""
    if mode is None:
        return 1.0
    sx, sy = slope

    def lam(cos_t, sin_t, phi):
        s2 = (sx * np.cos(phi)) ** 2 + (sy * np.sin(phi)) ** 2 if sx != sy else sx * sx
        den = sin_t * np.sqrt(2.0 * s2)
        a = np.where(den > cos_t * 1e-300, cos_t / np.where(den > 0, den, 1.0), 1e300)
        return smith_lambda(np.minimum(a, 1e300))

    lam_i = np.broadcast_to(lam(loc.ci, loc.si, loc.phi_i), (loc.n,))
    lam_s = np.broadcast_to(lam(loc.cs, loc.ss, loc.phi_s), (loc.n,))
    if mode == "height-correlated":
        return 1.0 / (1.0 + lam_i + lam_s)
    # azimuth between −k_i and k_s as seen from the surface: 0 in backscatter, π at specular
    psi = np.abs(np.mod(loc.phi_s - loc.phi_i - math.pi + math.pi, 2 * math.pi) - math.pi)
    corr = 4.41 * psi / (4.41 * psi + 1.0)
    hi, lo = np.maximum(lam_i, lam_s), np.minimum(lam_i, lam_s)
    return 1.0 / (1.0 + hi + corr * lo)


def _back_shadow_args(mode, loc, slope):
    """Shadowing of a backscatter chunk for the compiled kernel: ``(code, s, ψ)`` — code 0
    none, 1 direction-correlated, 2 height-correlated, evaluated in the kernel (the formulas
    of :func:`_shadowing` with one Smith Λ, isotropic slope ``s``, same directions in and out);
    code -1: anything else (the caller folds :func:`_shadowing` into the prefactor)."""
    none = np.zeros(1)
    if mode is None:
        return 0, 0.0, none
    same = (loc.ci is loc.cs and loc.si is loc.ss) or (
        np.array_equal(loc.ci, loc.cs) and np.array_equal(loc.si, loc.ss)
    )
    if not (slope[0] == slope[1] and same):
        return -1, 0.0, none
    if mode == "height-correlated":
        return 2, float(slope[0]), none
    psi = np.abs(np.mod(loc.phi_s - loc.phi_i - math.pi + math.pi, 2 * math.pi) - math.pi)
    return 1, float(slope[0]), iem_jit.flat_n(psi, loc.n)
