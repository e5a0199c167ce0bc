"""Per-angle helpers of the compiled exact-backscatter kernel
(:func:`emscatter.solvers.iem.kernels.lanes.back_kernel`): the geometry (cosθ, the spectral
argument K; its ``geo`` argument, so that a backscatter call through the API pays one pass over
its angles instead of a numpy temporary per step, issue 22 — numpy reference, the same
formulas bit for bit: :func:`emscatter.solvers.kirchhoff.common._trig`,
``Geometry._lateral_q``, :func:`emscatter.solvers.iem.amplitudes._spectral_args`), the
complex square root and division of its Fresnel setup in real arithmetic, and the closed-form
lower-medium and 1992 complementary amplitudes of exact backscatter."""

from __future__ import annotations

import math

from emscatter.kernels._runtime import inline, jit


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


@inline
def fast_root(z):
    """:func:`.series.root` (√z with Im ≥ 0) in real arithmetic, a few ulp from it and
    without the complex library call (Kahan's half-angle form, ``|z|`` from ``x² + y²``:
    no overflow for |z| < 1e150, far beyond any permittivity)."""
    x, y = z.real, z.imag
    m = math.sqrt(x * x + y * y)
    if x >= 0.0:
        t = math.sqrt(0.5 * (m + x))
        re, im = t, (0.5 * y / t if t > 0.0 else 0.0)
    else:
        t = math.sqrt(0.5 * (m - x))
        re, im = 0.5 * abs(y) / t, math.copysign(t, y)
    if im < 0.0:
        re, im = -re, -im
    return complex(re, im)


@inline
def cdiv(a, b):
    """``a / b`` (0 where ``b`` = 0) by ``a b* / |b|²``: one real division (numba's complex
    division scales and branches: slower); ≤ 2 ulp from it for |b| in [1e-150, 1e150]."""
    d = b.real * b.real + b.imag * b.imag
    if d == 0.0:
        return 0j
    inv = 1.0 / d
    return complex((a.real * b.real + a.imag * b.imag) * inv,
                   (a.imag * b.real - a.real * b.imag) * inv)  # fmt: skip


@inline
def lower_back(s2, c, q2, iq, rh, rv, eps, ieps, a, f):
    """The two lower-medium amplitudes of the fast walk, ``(g₁h, g₁v, g₂h, g₂v)`` =
    ``f (p₁ + p₂)``, ``f m`` of :func:`lower_setup` (``f`` = ¼, times the fade), in closed
    form: at exact backscatter (φ = π, θs = θi) the reduced coefficients of
    :func:`emscatter.solvers.iem.terms._reduced_i`, ``_reduced_s`` are, with ``s² = sin²θ``,
    ``c = cosθ``, the side "i" (``q = −q₂``, ``α₁ = c + a``) and "s" (``q = q₂``, ``α₁``) terms
    summed: ``C₁ = −2α₁``, ``C₃ = 2s²(q₂ − c)``, ``C₄ = −2c(α₁c + 2s²)``,
    ``C₂ + C₅ = 4s²(c − q₂)``; the "s" term at ``q = −q₂``, ``α₂ = c − a``: ``C₁ = −α₂``,
    ``C₃ = s²(α₂ − 2c)``, ``C₄ = −c(α₂c + 2s²)``, ``C₂ + C₅ = 2s²(c + q₂)`` (``C₂`` and ``C₅``
    enter :func:`lower_co` only as their sum once its products are expanded:
    ``hh = q₂⁻¹[(1+R_h)²(C₃ − εC₁) + (1+R_h)(1−R_h)(C₂ + C₅) + (1−R_h)²C₄]``,
    ``vv = q₂⁻¹[(1+R_v)²(C₁ − C₃/ε) − (1+R_v)(1−R_v)(C₂ + C₅) − (1−R_v)²εC₄]``). The same
    amplitudes as :func:`lower_setup` to rounding (tests/test_iem_fast.py), two thirds of its
    arithmetic."""
    hp, hm = 1.0 + rh, 1.0 - rh
    vp, vm = 1.0 + rv, 1.0 - rv
    fi = f * iq
    ah, bh, ch = fi * hp * hp, fi * hp * hm, fi * hm * hm
    av, bv, cv = fi * vp * vp, fi * vp * vm, fi * vm * vm * eps
    a1, a2 = c + a, c - a
    c1 = -2.0 * a1
    c3 = 2.0 * s2 * (q2 - c)
    c4 = -2.0 * c * (a1 * c + 2.0 * s2)
    c25 = 4.0 * s2 * (c - q2)
    g1h = ah * (c3 - c1 * eps) + bh * c25 + ch * c4
    g1v = av * (c1 - c3 * ieps) - bv * c25 - cv * c4
    c1 = -a2
    c3 = s2 * (a2 - 2.0 * c)
    c4 = -c * (a2 * c + 2.0 * s2)
    c25 = 2.0 * s2 * (c + q2)
    g2h = ah * (c3 - c1 * eps) + bh * c25 + ch * c4
    g2v = av * (c1 - c3 * ieps) - bv * c25 - cv * c4
    return g1h, g1v, g2h, g2v


@inline
def fung92_co(s, c, q2, eps, pec):
    """The 1992 IEM's complementary amplitude in exact backscatter, ``(G_h, G_v)`` (base
    ``cosθ``, no height phase; :func:`emscatter.solvers.iem.terms.fung92_backscatter_terms`)."""
    s2 = s * s
    if pec:
        return -4.0 * s2 + 0j, 4.0 * s2 + 0j
    dh = c + q2
    dv = eps * c + q2
    gh = -4.0 * s2 * (eps - 1.0) / (dh * dh)
    return gh, 4.0 * s2 * (eps - 1.0) * (eps * c * c + s2) / (dv * dv)
