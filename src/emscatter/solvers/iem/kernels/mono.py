"""The per-angle geometry of exact backscatter (cosθ, the spectral argument K) computed inside
:func:`emscatter.solvers.iem.kernels.lanes.back_kernel` (its ``geo`` argument), so that a backscatter call through the
API pays one pass over its angles instead of a numpy temporary per step (issue 22). Numpy
reference (the same formulas, bit for bit): :func:`emscatter.solvers.kirchhoff.common._trig`,
``Geometry._lateral_q`` and :func:`emscatter.solvers.iem.amplitudes._spectral_args`."""

from __future__ import annotations

import math

from emscatter.kernels._runtime import jit


# fastmath=False: no FMA contraction, so cosθ and K are the numpy path's numbers bit for bit
# (the instructions keep these flags where back_kernel's compilation inlines this function)
@jit(fastmath=False)
def back_geometry(si, geo, dim, ci, K):
    """Exact-backscatter geometry (θs = θi, φs − φi = Δφ) at incidence angles with sines
    ``si`` (n,) into ``ci`` (cosθ = √((1 − sinθ)(1 + sinθ))) and ``K`` (n,): the lateral
    wavevector ``q = (sinθ cosΔφ − sinθ, sinθ sinΔφ)`` (per unit k), rotated by φi when
    ``geo[5]`` ≠ 0, and ``K = √((q_x kℓ)² + (q_y kℓ_y)²)`` (``dim`` 2) or ``|q_x| kℓ``
    (``dim`` 1). ``geo = (1, cos Δφ, sin Δφ, cos φi, sin φi, rotate, kℓ, kℓ_y)``, kℓ
    dimensionless (k [rad/m] times the correlation lengths [m])."""
    cd, sd, cpi, spi, rotate, kl, kly = geo[1], geo[2], geo[3], geo[4], geo[5], geo[6], geo[7]
    for r in range(si.shape[0]):
        s = si[r]
        ci[r] = math.sqrt((1.0 - s) * (1.0 + s))
        qx = s * cd - s
        qy = s * sd
        if rotate != 0.0:
            qx, qy = qx * cpi - qy * spi, qx * spi + qy * cpi
        if dim == 2:
            a, b = qx * kl, qy * kly
            K[r] = math.sqrt(a * a + b * b)
        else:
            K[r] = abs(qx) * kl
