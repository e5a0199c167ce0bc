"""GO's per-angle validity entries at many incidence angles in one compiled pass.

:func:`emscatter.solvers.kirchhoff.go.check_validity` with ``theta_i`` decides two per-angle
criteria, both functions of θi alone that fail above one angle (Ulaby, Moore & Fung 1982
vol. II §12-4, Table 12.2; Smith 1967; Thorsos 1988 JASA 83, 78)::

    stationary phase   Q(θi) = (2kσ cosθi)² ≥ 10           ratio 10/Q
    illuminated        G1(θi) = 1/(1 + Λ(cotθi/√(2 s²))) ≥ g_min     ratio g_min/G1

with ``s² = max(⟨ζx²⟩, ⟨ζy²⟩)`` and ``g_min = 0.5`` (shadowed, the default the API's angle
report uses). At 1e6 angles the numpy route (:func:`emscatter.method_resolution.angle_report`:
min/max, probe angles, a comparison and an index of the angles above the threshold, the
report on those, a scatter back) costs 5–10 ms, half the GO kernel itself. Here: the largest
angle below which both criteria certainly pass is found once (closed form for Q, bisection
for G1, less a 1e-6 rad margin that dwarfs any rounding), and one loop writes
``angle_valid``/``angle_excess`` — a comparison per angle below it, the exact criteria above
it (the same formulas as the numpy reference; libm's ``erfc`` for scipy's, so ``angle_excess``
agrees to rounding) — while it gathers each failing criterion's count, range and worst angle
for the reasons. The reasons are the text of :meth:`emscatter.solvers.validity.AngleCheck.reason`.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from emscatter.kernels import default_threads
from emscatter.kernels._runtime import _MIN_CHUNK, inline, jit, run_split

__all__ = ["angle_entries", "MIN_ANGLES"]

_SQRT_PI = math.sqrt(math.pi)
#: Below this many angles the numpy report is as fast (and the kernel not worth loading).
MIN_ANGLES = 4096
_MARGIN = 1e-6  # [rad] below the threshold: every angle there passes, whatever the rounding


@inline
def _g1(t, kappa):
    """``(G1(θ), cosθ)``: Smith's ``G1 = 1/(1 + Λ(a))``, ``a = cosθ/(sinθ √(2s²))``, as
    kirchhoff_common.illuminated_fraction computes it (``a`` clipped as its ``_a``, ``Λ = 0``
    for ``a ≥ 6``; libm's ``erfc`` for scipy's: equal to rounding)."""
    c = math.cos(t)
    s = math.sin(t)
    den = s * kappa
    a = c / den if den > c * 1e-300 else 1e300
    lam = 0.0
    if a < 6.0:
        an = max(a, 1e-300)
        lam = max(0.5 * (math.exp(-an * an) / (an * _SQRT_PI) - math.erfc(an)), 0.0)
    return 1.0 / (1.0 + lam), c


@jit
def _g1_at(t, kappa):
    """:func:`_g1` for one angle, from Python (the threshold's bisection)."""
    return _g1(t, kappa)[0]


@jit
def _angle_pass(theta, t_lo, q0, q_min, g_min, kappa, valid, excess, stats):
    """``valid``/``excess`` at every angle of ``theta`` [rad]; ``stats[c]`` for criterion
    ``c`` (0: stationary phase, 1: illuminated): count of failing angles, min and max failing
    θ, worst ratio, the criterion's value there and its θ (first index of the largest
    ratio, as ``np.argmax``)."""
    n0 = n1 = 0  # the gathered quantities in locals (registers), stored once at the end
    lo0 = lo1 = math.inf
    hi0 = hi1 = w0 = w1 = -math.inf
    v0 = v1 = a0 = a1 = 0.0
    for j in range(theta.size):
        t = theta[j]
        if t <= t_lo:
            valid[j] = True
            excess[j] = 0.0
            continue
        g, c = _g1(t, kappa)
        q = q0 * c * c
        r0 = q_min / q if q > 0 else math.inf
        r1 = g_min / g if g > 0 else math.inf
        if r0 > 1.0:
            n0 += 1
            lo0 = min(lo0, t)
            hi0 = max(hi0, t)
        if r0 > w0:
            w0, v0, a0 = r0, q, t
        if r1 > 1.0:
            n1 += 1
            lo1 = min(lo1, t)
            hi1 = max(hi1, t)
        if r1 > w1:
            w1, v1, a1 = r1, g, t
        r = max(r0, r1)  # max(log r0, log r1): one logarithm
        e = math.log(r) if r > 1.0 else 0.0
        valid[j] = e == 0.0
        excess[j] = e
    stats[0, 0], stats[0, 1], stats[0, 2], stats[0, 3], stats[0, 4], stats[0, 5] = (
        n0,
        lo0,
        hi0,
        w0,
        v0,
        a0,
    )
    stats[1, 0], stats[1, 1], stats[1, 2], stats[1, 3], stats[1, 4], stats[1, 5] = (
        n1,
        lo1,
        hi1,
        w1,
        v1,
        a1,
    )


@functools.lru_cache(maxsize=64)
def _threshold(q0: float, q_min: float, g_min: float, kappa: float) -> float:
    """[rad] an angle below which both criteria pass (``_MARGIN`` below the exact one)."""
    t_q = 0.0 if q0 <= q_min else math.acos(math.sqrt(q_min / q0))
    if _g1_at(0.0, kappa) < g_min:
        return -1.0
    lo, hi = 0.0, math.pi / 2  # G1 falls with θ: bisection for G1 = g_min
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        if _g1_at(mid, kappa) >= g_min:
            lo = mid
        else:
            hi = mid
    return min(t_q, lo) - _MARGIN


def _fmt(x: float) -> str:
    return f"{float(x):.3g}"


_WHAT = (
    ("stationary_phase_angle", "Q = (2kσ cosθi)²"),
    ("illuminated", "Smith's illuminated fraction G1(θi)"),
)


def angle_entries(q0: float, s2: float, q_min: float, g_min: float, theta: np.ndarray) -> dict:
    """``angle_valid``, ``angle_excess`` (``theta``'s shape) and ``angle_reasons`` for flat
    float64 ``theta`` [rad] — what ``check_validity(..., theta_i=theta)`` reports for them —
    with ``q0 = (2kσ)²``, ``s2`` the larger per-direction slope variance [-], the limits
    ``q_min`` (Q) and ``g_min`` (G1)."""
    theta = np.ascontiguousarray(theta, dtype=np.float64)
    kappa = math.sqrt(2.0 * s2)
    t_lo = _threshold(float(q0), float(q_min), float(g_min), kappa)
    valid = np.empty(theta.shape, dtype=bool)
    excess = np.empty(theta.shape)
    flat, v_out, e_out = theta.reshape(-1), valid.reshape(-1), excess.reshape(-1)
    threads = default_threads()
    parts = int(max(1, min(threads, flat.size // _MIN_CHUNK)))
    edges = np.linspace(0, flat.size, parts + 1).astype(np.int64)
    stats = np.empty((parts, 2, 6))
    consts = (t_lo, float(q0), float(q_min), float(g_min), kappa)

    index = {int(a): i for i, a in enumerate(edges[:-1])}  # run_split's chunks: these edges

    def part(a: int, b: int) -> None:
        i = index[a]
        _angle_pass(flat[a:b], *consts, v_out[a:b], e_out[a:b], stats[i])

    run_split(part, flat.size, parts, _MIN_CHUNK)
    reasons = []
    for c, ((name, what), limit) in enumerate(zip(_WHAT, (q_min, g_min), strict=True)):
        st = stats[:, c]
        count, lo, hi = st[:, 0].sum(), st[:, 1].min(), st[:, 2].max()
        r, v, at = st[int(np.argmax(st[:, 3])), 3:]  # the first chunk with the largest ratio
        if count == 0:
            continue
        lo, hi = math.degrees(lo), math.degrees(hi)
        span = f"θi = {lo:.4g}°" if lo == hi else f"θi ∈ [{lo:.4g}°, {hi:.4g}°]"
        reasons.append(
            f"{name}: fails for {span} ({int(count)} of {theta.size} angles); "
            f"{what} must be ≥ {_fmt(limit)}, worst "
            f"{_fmt(v)} at θi = {math.degrees(at):.4g}° (×{r:.3g})"
        )
    return {"angle_valid": valid, "angle_excess": excess, "angle_reasons": reasons}
