"""The tail of a measured slope density: what geometric optics sees beyond the slopes a map
samples well.

A map holds as many independent slopes as correlation cells (``N_eff = N/Σρ_ζ²``,
:func:`~emscatter.surfaces.measured.estimators.slope_acf_sum`; ≈ 10³ on a 512² map), so its
smoothed histogram is ≈ 0 beyond a few rms (at 5 rms 0.08× the Gaussian's on such a map).
GO weighs that region by ``1/(cosθi cosθo)`` at grazing (the rim of a rendered sphere), where a
density without a tail is far too dark. The tail choice (``slope_tail``):

* ``"none"``: the kernel estimate as it is, 0 beyond the histogram grid (bounded slopes, e.g.
  a machined facet map);
* ``"gaussian"`` (default) or ``"exponential"``: in the normalized (elliptical) slope radius
  ``r = √(ζx²/⟨ζx²⟩ + ζy²/⟨ζy²⟩)`` the density beyond the junction ``r_j`` is
  ``T(r) = exp(a + c r²)`` (``"gaussian"``) or ``exp(a + c r)`` (``"exponential"``), ``a`` and
  ``c`` a least-squares fit of ``log`` of the ring-averaged kernel density over the last well
  sampled shells ``[r_j − 1, r_j]`` (``c`` at most :data:`MAX_LOG_SLOPE`: the tail decays).

The rule for the junction: ``r_j`` is the radius beyond which the map holds
:data:`N_TAIL` independent slope samples (``N_eff`` × the fraction of slopes with ``r > r_j``;
fewer than that and the kernel estimate's shells are mostly noise and then empty), at most the
histogram grid's edge less 0.5 rms and at least 1.5 rms. The measured density and the tail are
blended by a smoothstep ``w(r)`` over ``[r_j − 0.5, r_j]`` (continuous, no direction-dependent
jump where the measured density is noisy), which makes it elliptical beyond ``r_j`` (an
assumption, stated): ``p = w p_meas (λ0 + λx ζx² + λy ζy²) + (1 − w) T``, the core's weight
solved so that ``p`` integrates to 1 and keeps the measured mean-square slopes ``⟨ζx²⟩, ⟨ζy²⟩``
exactly, the tail kept as fitted (512² Gaussian map: λ0 ≈ 1.02, the weight ≈ 0.9 at ``r_j``).
Where that weight would leave :data:`WEIGHT_RANGE` on the core (a tail heavier than the
measured slopes allow: ``"exponential"`` on Gaussian slopes; or a map whose mean-square slopes
come from a few huge slopes beyond the histogram: Laplace facet angles, weight 0.76…21) only
the mass is kept (``λx = λy = 0``) and the density's own mean-square slopes are recorded
(``"keeps"``, ``"mean_square_slopes"``). Recorded in the
roughness's ``info["slope_tail"]``. Why ``"gaussian"`` fixes the curvature (``c = −1/2`` on
the measured rms slopes) and fits only the amplitude: a fitted curvature from the ≈ 10² samples
in ``[r_j − 1, r_j]`` of a 512² map erred by ±0.02, i.e. ×0.7…1.4 at 6 rms (4 seeds); the
fixed one puts GO at grazing within 2.2 % of the Gaussian's (tests/test_heightmap.py).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["SLOPE_TAILS", "N_TAIL", "MAX_LOG_SLOPE", "WEIGHT_RANGE", "fit_tail", "evaluate"]

#: The choices for the slope density beyond the well-sampled slopes.
SLOPE_TAILS = ("none", "gaussian", "exponential")
#: Independent slope samples beyond the junction radius (the rule in the module docstring).
N_TAIL = 30
#: The tail's log-slope ``c`` is at most this (per rms² for "gaussian", per rms otherwise).
MAX_LOG_SLOPE = -0.05
#: The range the core's weight may span (else only the mass is kept; module docstring).
WEIGHT_RANGE = (0.8, 1.25)
_BLEND = 0.5  # rms: the smoothstep's width
_FIT = 1.0  # rms: the fitted shells below r_j
_PHI = 256


def _radius(zx, zy, rms):
    r2 = (zx / rms[0]) ** 2
    if zy is not None:
        r2 = r2 + (zy / rms[1]) ** 2
    return np.sqrt(r2)


def _ring_mean(pdf_inner, r, rms, dim):
    """Ring averages of the inner density at the normalized radii ``r`` [-]."""
    if dim == 1:
        return 0.5 * (pdf_inner(r * rms[0]) + pdf_inner(-r * rms[0]))
    ph = np.linspace(0, 2 * math.pi, _PHI, endpoint=False)
    R, P = np.meshgrid(r, ph, indexing="ij")
    return pdf_inner(R * np.cos(P) * rms[0], R * np.sin(P) * rms[1]).mean(axis=1)


def _tail_value(shape, a, c, r):
    x = r * r if shape == "gaussian" else r
    return np.exp(a + c * x)


def _parts(pdf_inner, shape, fit, zx, zy, rms):
    """The blend's two terms at slopes ``zx, zy``: ``w p_meas`` and ``(1 − w) T``."""
    r = _radius(zx, zy, rms)
    rj, a, c = fit
    t = np.clip((rj - r) / _BLEND, 0.0, 1.0)
    w = t * t * (3 - 2 * t)  # 1 inside r_j − 0.5, 0 beyond r_j
    inner = pdf_inner(zx) if zy is None else pdf_inner(zx, zy)
    return w * inner, (1 - w) * _tail_value(shape, a, c, r)


def fit_tail(pdf_inner, shape, zx, zy, n_eff, grid_half_rms, rms_slopes):
    """Fit the tail (module docstring). ``pdf_inner(zx[, zy])`` is the kernel density,
    ``zx, zy`` the map's slopes (``zy`` None in 1-D), ``n_eff`` their independent count,
    ``grid_half_rms`` the histogram grid's half-width in rms per axis, ``rms_slopes`` the
    measured rms slopes per axis. Returns the record (a dict) :func:`evaluate` takes."""
    dim = 1 if zy is None else 2
    rms = tuple(float(s) for s in rms_slopes)
    r = _radius(zx, zy, rms)
    frac = min(0.5, N_TAIL / max(float(n_eff), 1.0))
    rj_q = float(np.quantile(r, 1.0 - frac))
    rj = float(np.clip(rj_q, 1.5, max(1.5, min(grid_half_rms) - 0.5)))
    rs = np.linspace(max(0.25, rj - _FIT), rj, 21)
    ring = _ring_mean(pdf_inner, rs, rms, dim)
    ok = ring > 0
    if ok.sum() < 3:
        raise ValueError("the slope density has no well-sampled shells below the junction")
    x = rs * rs if shape == "gaussian" else rs
    if shape == "gaussian":  # the measured slopes' own Gaussian curvature; amplitude fitted
        c = -0.5
        a = float(np.mean(np.log(ring[ok]) - c * x[ok]))
    else:
        c, a = np.polyfit(x[ok], np.log(ring[ok]), 1)
    clamped = c > MAX_LOG_SLOPE
    c = min(float(c), MAX_LOG_SLOPE)
    if clamped:  # keep the density at the junction
        a = float(math.log(ring[ok][-1]) - c * x[ok][-1])
    fit = (rj, float(a), float(c))
    # the core's weight λ0 + λx ζx² + λy ζy² (on w p_meas only: the tail is kept as fitted)
    # solves for mass 1 and the measured ⟨ζx²⟩, ⟨ζy²⟩; moments in normalized polar coordinates
    top = rj + (math.sqrt(-35.0 / c + rj * rj) - rj if shape == "gaussian" else -35.0 / c)
    rr = np.unique(np.concatenate([np.linspace(0.0, rj + 1, 2001),
                                   np.linspace(rj + 1, max(top, rj + 2), 1001)]))  # fmt: skip
    if dim == 1:
        zz = np.concatenate([-rr[:0:-1], rr]) * rms[0]
        core, tail = _parts(pdf_inner, shape, fit, zz, None, rms)
        m = lambda f, g: float(np.trapezoid(f * g, zz))  # noqa: E731
        x2 = zz * zz
        mat = np.array([[m(core, 1), m(core, x2)], [m(core, x2), m(core, x2 * x2)]])
        rhs = np.array([1 - m(tail, 1), rms[0] ** 2 - m(tail, x2)])
    else:
        ph = np.linspace(0, 2 * math.pi, 2 * _PHI, endpoint=False)
        R, P = np.meshgrid(rr, ph, indexing="ij")
        X, Y = R * np.cos(P) * rms[0], R * np.sin(P) * rms[1]
        core, tail = _parts(pdf_inner, shape, fit, X, Y, rms)
        jac = rms[0] * rms[1] * (2 * math.pi / ph.size)
        m = lambda f, g: float(np.trapezoid((f * g).sum(axis=1) * rr, rr)) * jac  # noqa: E731
        x2, y2 = X * X, Y * Y
        mat = np.array([[m(core, 1), m(core, x2), m(core, y2)],
                        [m(core, x2), m(core, x2 * x2), m(core, x2 * y2)],
                        [m(core, y2), m(core, x2 * y2), m(core, y2 * y2)]])  # fmt: skip
        rhs = np.array([1 - m(tail, 1), rms[0] ** 2 - m(tail, x2), rms[1] ** 2 - m(tail, y2)])
    lam = np.linalg.solve(mat, rhs)
    # the weight on the core (r ≤ r_j) must stay within WEIGHT_RANGE (its extremes over the
    # ellipse are at its centre and its vertices); where it cannot (the tail heavier or lighter
    # than the measured slopes allow: "exponential" on Gaussian slopes, a Gaussian tail on a
    # map whose mean-square slopes come from a few huge ones) only the mass is kept and the
    # tailed density's own mean-square slopes are recorded
    ends = [lam[0]] + [lam[0] + lv * (rj * r_) ** 2 for lv, r_ in zip(lam[1:], rms, strict=False)]
    keeps = "mass 1 and the measured mean-square slopes"
    if not all(WEIGHT_RANGE[0] <= e <= WEIGHT_RANGE[1] for e in ends):
        lam = np.zeros(len(rhs))
        lam[0] = rhs[0] / mat[0, 0]
        keeps = ("mass 1 only (keeping the measured mean-square slopes would reweight the "
                 f"measured core by {min(ends):.3g}…{max(ends):.3g})")  # fmt: skip
    tail_mass = m(tail, 1)
    mss = tuple(float(lam @ mat[i] + (rms[i - 1] ** 2 - rhs[i])) for i in range(1, len(rhs)))
    return {
        "shape": shape,
        "junction_rms": rj,
        "junction_quantile_rms": rj_q,
        "rule": f"r_j: {N_TAIL} independent slope samples (N_eff × fraction) beyond it, "
        f"clipped to [1.5, grid edge − 0.5] rms; fit of log ring-mean density over "
        f"[r_j − {_FIT:g}, r_j]; smoothstep blend over [r_j − {_BLEND:g}, r_j]; "
        "the core weighted by "
        "λ0 + λx ζx² + λy ζy² (the tail as fitted)",
        "fit_log_density": (float(a), c),
        "log_slope_clamped": bool(clamped),
        "core_weight": tuple(float(v) for v in lam),
        "tail_mass": tail_mass,
        "keeps": keeps,
        "mean_square_slopes": mss,
        "rms_slopes": rms,
        "extent_rms": float(top),
    }


def evaluate(pdf_inner, rec, zx, zy=None):
    """The tailed density at slopes ``zx[, zy]`` [-] (``rec`` from :func:`fit_tail`)."""
    fit = (rec["junction_rms"], *rec["fit_log_density"])
    core, tail = _parts(pdf_inner, rec["shape"], fit, zx, zy, rec["rms_slopes"])
    lam = rec["core_weight"]
    weight = lam[0] + lam[1] * zx * zx
    if zy is not None:
        weight = weight + lam[2] * zy * zy
    return core * weight + tail
