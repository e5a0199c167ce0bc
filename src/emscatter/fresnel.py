"""Fresnel reflection coefficients of a flat interface (vacuum above, medium ε below).

Time convention ``exp(-iωt)`` (see :mod:`emscatter.conventions`): the transmitted
vertical wavenumber ``k₂z = k √(ε − sin²θ)`` takes the branch with ``Im ≥ 0`` (decaying
into the lower medium) and ``Re ≥ 0`` when lossless. Relative permeability is 1.

* ``R_h = (cosθ − √(ε − sin²θ)) / (cosθ + √(ε − sin²θ))``  (TE)
* ``R_v = (ε cosθ − √(ε − sin²θ)) / (ε cosθ + √(ε − sin²θ))``  (TM)

(Tsang, Kong & Ding 2000, vol. I, eqs. 2.1.x; Ulaby et al. 1982, vol. II, ch. 12.)
A perfect conductor is ``eps="pec"``: ``R_h = −1``, ``R_v = +1``. Metals (``Re ε < 0``)
and very large ``|ε|`` (``1e7i``) are handled by the same formulas, written to avoid
cancellation.
"""

from __future__ import annotations

import numpy as np

from .conventions import check_permittivity

__all__ = ["PEC", "is_pec", "check_eps", "fresnel", "fresnel_cos", "reflectivity"]

#: Marker for a perfect electric conductor, accepted wherever ``eps`` is.
PEC = "pec"


def is_pec(eps) -> bool:
    return isinstance(eps, str) and eps.lower() == PEC


def check_eps(eps, name: str = "eps"):
    """Validated permittivity: the string ``"pec"`` or a complex array with ``Im ε ≥ 0``."""
    if isinstance(eps, str):
        if is_pec(eps):
            return PEC
        raise ValueError(f"{name} must be a complex permittivity or 'pec', got {eps!r}")
    return check_permittivity(eps, name)


def _sqrt_branch(x: np.ndarray) -> np.ndarray:
    """√x with Im ≥ 0 (and Re ≥ 0 on the real axis) — the decaying branch."""
    s = np.sqrt(x.astype(complex))
    return np.where(s.imag < 0, -s, s)


def fresnel_cos(eps, cos_theta):
    """``(R_h, R_v)`` at incidence cosine ``cos_theta`` ∈ [0, 1]; broadcasts with ``eps``."""
    c = np.clip(np.asarray(cos_theta, dtype=float), 0.0, 1.0)
    if is_pec(eps):
        ones = np.ones(c.shape, dtype=complex)
        return -ones, ones
    eps = np.asarray(eps, dtype=complex)
    s2 = 1.0 - c * c
    root = _sqrt_branch(eps - s2)
    den_h, den_v = c + root, eps * c + root
    # Both denominators vanish only for ε = 1 at grazing incidence: no interface, R = 0.
    with np.errstate(invalid="ignore", divide="ignore"):
        rh = np.where(den_h == 0, 0.0, (c - root) / np.where(den_h == 0, 1.0, den_h))
        rv = np.where(den_v == 0, 0.0, (eps * c - root) / np.where(den_v == 0, 1.0, den_v))
    return rh, rv


def fresnel(eps, theta):
    """``(R_h, R_v)`` at incidence angle ``theta`` [rad]."""
    return fresnel_cos(eps, np.cos(np.asarray(theta, dtype=float)))


def reflectivity(eps, theta) -> np.ndarray:
    """Power reflectivities ``(|R_h|², |R_v|²)`` stacked on axis 0, shape ``(2, ...)``."""
    rh, rv = fresnel(eps, theta)
    return np.stack([np.abs(rh) ** 2, np.abs(rv) ** 2])
