"""The closed-form pieces of the IEM multiple-scattering cross-pol kernel shared by the numpy
path (:mod:`.crosspol`) and the compiled one (:mod:`.crosspol_kernel`): the slope polynomials
``B₁…B₆`` of Chen et al., IEEE TGRS 41 (2003) 90, appendix C, and the Gauss–Legendre rule."""

from __future__ import annotations

from functools import lru_cache

import numpy as np

__all__ = ["gauss_legendre", "slope_coefficients"]


@lru_cache(maxsize=32)
def gauss_legendre(n: int):
    """Gauss–Legendre nodes and weights on [0, 1]."""
    x, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * (x + 1.0), 0.5 * w


def slope_coefficients(si, cs, ss, css, sf, cf, u, v):
    """``cosθi cosθs × B₁…B₆`` (Chen et al. 2003, appendix C) at ``q = 0`` with the 1992
    slopes (module docstring); polynomials in ``u, v`` (Chen's frame, φi = 0)."""
    zx, zy = -(ss * cf + u), -(ss * sf + v)  # cosθs × last-point slopes
    zxp, zyp = si + u, v  # cosθi × first-point slopes
    cc = cs * css
    b1 = css * sf * (cc + zx * zxp) - ss * cs * zy - cf * css * zxp * zy
    b2 = (
        css * sf * (cs * cs * u * zx + si * u * zx * zxp + cc * v * zyp + si * v * zx * zyp)
        - ss * cs * (u * zx + v * zy) * zyp
        - cf * css * (cs * cs * u * zy + si * u * zxp * zy - cc * u * zyp + si * v * zy * zyp)
    )
    b3 = cs * (css * css * (sf * u * u - cf * u * v) - ss * u * (u * zy - v * zx))
    b4 = cf * (si * css * zyp - cs * zx * zyp) - sf * (cs * cc + si * css * zxp + cs * zy * zyp)
    b5 = cf * v * (cs * zx - css * zxp) + sf * (u * css * zxp + v * cs * zy)
    b6 = css * zyp * (cf * u + sf * v)
    return b1, b2, b3, b4, b5, b6  # fmt: skip
