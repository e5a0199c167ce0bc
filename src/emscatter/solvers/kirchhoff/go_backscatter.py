"""Geometric-optics σ⁰ in the exact backscatter direction, in closed form.

At ``k_s = −k_i`` the specular facet faces the wave (local incidence 0), so the GO σ⁰ of
:mod:`emscatter.solvers.kirchhoff.go` reduces to (2-D surface, isotropic slope variance
``s²`` per direction; Ulaby, Moore & Fung 1982 vol. II eq. 12.58; Tsang et al. 2001 vol. III
eq. 2.2.33)::

    σ⁰_pp = |R(0)|² exp(−tan²θ / (2 s²)) / (2 s² cos⁴θ) · S(θ),    σ⁰_hv = σ⁰_vh = 0

with ``S`` the shadowing factor at backscatter (``"smith"`` and ``"direction-correlated"``:
monostatic ``1/(1+Λ)``;
``"separable"``: ``1/(1+Λ)²``; ``"correlated"``: ``1/(1+2Λ)``; None: 1). The same numbers as
the general formula (to rounding) for a fraction of its operations: a backscatter curve does
not pay for the bistatic Fresnel and polarization geometry.
"""

from __future__ import annotations

import cmath
import math

import numpy as np
from scipy import special

__all__ = [
    "backscatter_sigma0", "covers", "normal_reflectivity", "smith_lambda_backscatter",
    "SHADOWING_MODES",
]  # fmt: skip

_SQRT_PI = math.sqrt(math.pi)


def backscatter_sigma0(theta: np.ndarray, eps, slope_variance: float, shadowing) -> np.ndarray:
    """σ⁰ (2, 2, n) [-] at backscatter for the flat incidence angles ``theta`` [rad] in
    [0, π/2]; ``eps`` "pec" or one complex permittivity; ``slope_variance`` ⟨ζx²⟩ = ⟨ζy²⟩
    [-]; ``shadowing`` None, "smith", "separable" or "correlated"."""
    s2 = float(slope_variance)
    si = np.sin(np.atleast_1d(np.asarray(theta, dtype=float)))  # in-place steps need arrays
    c2 = (1.0 - si) * (1.0 + si)  # cos²θ (as kirchhoff_common._trig, before its root)
    # cos²θ is 0 (θ = π/2: σ⁰ = 0) or ≥ 1e-16: the floor only keeps 0·∞ away
    r = 1.0 / np.maximum(c2, 1e-300)
    val = si * si
    val *= r  # tan²θ
    val *= -0.5 / s2
    np.exp(val, out=val)
    val *= 0.5 / s2
    val *= r  # one factor at a time: 0 (θ = π/2) times r² = 1e600 would overflow
    val *= r
    if shadowing is not None:
        lam = smith_lambda_backscatter(np.sqrt(c2), si, s2)
        if shadowing in ("smith", "direction-correlated"):  # both 1/(1 + Λ) at backscatter
            lam += 1.0
            val /= lam
        elif shadowing == "separable":
            lam += 1.0
            val /= lam
            val /= lam  # (Λ is huge at θ = π/2: no square)
        elif shadowing == "correlated":
            lam *= 2.0
            lam += 1.0
            val /= lam
        else:
            raise ValueError(f"no backscatter closed form for shadowing={shadowing!r}")
    out = np.zeros((2, 2, theta.size))
    np.multiply(val, normal_reflectivity(eps), out=out[0, 0])
    out[1, 1] = out[0, 0]  # |R_h(0)|² = |R_v(0)|²
    return out


def smith_lambda_backscatter(cos_t: np.ndarray, sin_t: np.ndarray, s2: float) -> np.ndarray:
    """Smith's ``Λ(a)``, ``a = cotθ/(√2 s)``
    (:func:`emscatter.solvers.kirchhoff.common.smith_lambda` of
    :func:`emscatter.solvers.kirchhoff.common._a`) in fewer passes: ``a`` is clipped to [1e-300,
    1e100]
    (θ = 0 gives ``Λ = 0``) and ``Λ`` is evaluated everywhere (for ``a ≥ 6``, where the
    reference stops, ``0 ≤ Λ < 1e-17``: ``1/(1+Λ)`` is the same double)."""
    den = sin_t * math.sqrt(2.0 * s2)
    np.maximum(den, 1e-300, out=den)
    a = cos_t / den
    # θ = π/2: floored as the reference (Λ huge, σ⁰ = 0 there anyway); a > 27: Λ = 0 exactly
    np.maximum(a, 1e-300, out=a)
    np.minimum(a, 1e100, out=a)
    e = a * a
    np.negative(e, out=e)
    np.exp(e, out=e)
    a_pi = a * _SQRT_PI
    e /= a_pi
    e -= special.erfc(a)
    e *= 0.5
    return np.maximum(e, 0.0, out=e)


def normal_reflectivity(eps) -> float:
    """``|R(0)|² = |(1 − √ε)/(1 + √ε)|²`` [-] (1 for "pec"; principal root, ``Im √ε ≥ 0``
    as :mod:`emscatter.fresnel`)."""
    if isinstance(eps, str):
        return 1.0
    w = cmath.sqrt(complex(eps))
    return abs((1.0 - w) / (1.0 + w)) ** 2


#: those with a closed form here ("direction-correlated": accuracy's continuous default, which is
#: 1/(1 + Λ) at backscatter, where ψ = 0)
SHADOWING_MODES = (None, "smith", "separable", "correlated", "direction-correlated")


def covers(g, dimension: int, sx: float, sy: float, shadowing) -> bool:
    """Whether :func:`backscatter_sigma0` applies to the geometry ``g``
    (:func:`emscatter.solvers.kirchhoff.common.geometry`) of a backscatter call: a 2-D isotropic
    surface, one
    permittivity, one φi with ``φs − φi`` exactly π (so the general formula's exact
    backscatter branch is the one taken), a shadowing mode of :data:`SHADOWING_MODES`."""
    ti, ts, dphi, phi_i, _, eps = g.compact
    return (
        shadowing in SHADOWING_MODES
        and dimension == 2
        and sx == sy
        and (isinstance(eps, str) or eps.ndim == 0)
        and phi_i.ndim == 0
        and dphi.ndim == 0
        and float(dphi) == np.pi
        and ts is ti
    )
