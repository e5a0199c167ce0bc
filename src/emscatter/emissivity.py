"""Hemispherical integration: incoherent reflectivity, emissivity, energy balance.

Shared by every solver (one place, not copied). For incident polarization ``p``

* 2-D surfaces: ``r_p(θi) = 1/(4π cosθi) Σ_q ∫_{2π} σ⁰_qp dΩs``
* 1-D profiles: ``r_p(θi) = 1/(2π cosθi) Σ_q ∫_{−π/2}^{π/2} σ⁰_qp dθs``

and by Kirchhoff's law ``e_p = 1 − r_coh,p − r_incoh,p`` (Ulaby, Moore & Fung 1982 vol. II;
Tsang, Kong & Ding 2000 vol. I ch. 6).

Quadrature
----------
Scattered directions are parametrized by their transverse unit vector ``p = k̂_s,⊥`` on the
unit disk (``dΩ = d²p / cosθs``), in polar coordinates ``(ρ, α)`` centred on the specular
point ``p₀ = k̂_i,⊥`` where lobes concentrate: ``ρ = ρ_max(α) t`` with ``t ∈ [0, 1]`` on
geometrically graded Gauss–Legendre panels (finest panel ≈ the lobe width) and the trapezoid
rule in ``α`` (periodic, spectrally accurate because panel edges do not depend on ``α``).
The last panel uses ``t = 1 − (1 − a) s²`` so the ``1/cosθs`` edge singularity becomes
smooth. 1-D profiles use the same graded rule in ``u = sinθs`` on both sides of ``sinθi``.
The rule is refined (doubling both orders) until two successive estimates agree within
``tol``; their difference is the reported error estimate.

Time budget and interrupts
--------------------------
σ⁰ is evaluated in chunks of scattered directions (each chunk ≈ :data:`CHUNK_SECONDS` of
work, sized from the measured cost of the previous one), so the interpreter regains control
between chunks: Ctrl-C (``KeyboardInterrupt``) and ``SIGALRM`` handlers run within about a
chunk's time even when the solver's loops are compiled. The measured cost per evaluation is
the estimate before each step: a refinement that would end past the time budget
(:data:`TIME_BUDGET_S`, or :func:`time_budget` / ``EMSCATTER_TIME_BUDGET_S``) is not started
and the last estimate is returned with its error (the documented cheaper path, as for the
evaluation budget); if even the first two, coarsest estimates (one is no error bound) would
end past it, the call raises :class:`TimeBudgetError` once a tenth of the budget is spent
(:data:`EARLIEST_REFUSAL`: the first chunks can be slowed by tables a solver fills on first
use; and not on the first chunk's rate alone, which carries compilation), naming the
estimate, the budget and the ways out.
"""

from __future__ import annotations

import contextlib
import contextvars
import math
import os
import time
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from . import progress as _progress
from .conventions import pol_index

__all__ = [
    "Emissivity",
    "energy_balance",
    "ENERGY_ATOL",
    "MAX_EVALUATIONS_PER_ANGLE",
    "TIME_BUDGET_S",
    "TimeBudgetError",
    "QuadratureWarning",
    "time_budget",
    "hemispherical_reflectivity",
    "lobe_width",
]


@dataclass(frozen=True)
class Emissivity:
    """Emissivity and its energy budget, per incident polarization (axis 0: h, v).

    ``emissivity = 1 − coherent − incoherent`` (Kirchhoff's law), ``error`` the quadrature
    error estimate, all of shape ``(2, *shape)``; ``energy_ok`` (``shape``) is False at the
    angles where the balance is broken beyond that error (:func:`energy_balance`); ``k``
    [rad/m] is a float or, for several frequencies, an array of ``shape``.
    """

    emissivity: np.ndarray
    coherent: np.ndarray
    incoherent: np.ndarray
    error: np.ndarray
    method: str
    theta_i: np.ndarray
    evaluations: int
    info: dict = field(default_factory=dict)
    k: float | np.ndarray | None = None
    energy_ok: np.ndarray | None = None

    h = property(lambda self: self.emissivity[0])
    v = property(lambda self: self.emissivity[1])

    @property
    def reflectivity(self) -> np.ndarray:
        """Total reflectivity ``r_coh + r_incoh`` per polarization."""
        return self.coherent + self.incoherent

    def pol(self, pol: str) -> np.ndarray:
        """Emissivity for ``"h"``/``"TE"`` or ``"v"``/``"TM"`` (case-insensitive)."""
        return self.emissivity[pol_index(pol)]

    def energy_balance(self, tol: float = 0.0) -> dict:
        """The per-angle balance (:func:`energy_balance`) of this result."""
        return energy_balance(self.coherent, self.incoherent, self.error, self.theta_i, tol=tol)


#: Default budget of σ⁰ evaluations per incidence angle in :func:`hemispherical_reflectivity`
#: (the graded rule needs ~1e3–9e4 for tol = 1e-4; the budget only stops pathological cases,
#: e.g. physical optics at kσ = 1e3, whose every evaluation sums thousands of series terms).
MAX_EVALUATIONS_PER_ANGLE = 100_000

#: Default wall-clock budget [s] of one hemispherical integral (one emissivity call per
#: frequency and method). ``EMSCATTER_TIME_BUDGET_S`` (seconds, or ``none``) overrides it for a
#: process, :func:`time_budget` for a block of code.
TIME_BUDGET_S = 60.0

#: Target duration [s] of one chunk of σ⁰ evaluations: how long Ctrl-C may wait.
CHUNK_SECONDS = 1.0

#: σ⁰ evaluations (directions × incidence angles) in the first chunk of an integral, which
#: measures the rate: each solver call has a fixed cost (~0.3–0.5 ms for the IEM), so the
#: former one-direction first chunk cost the IEM emissivity two to three extra calls per θi.
FIRST_CHUNK_EVALUATIONS = 64

#: Fraction of the time budget spent before a call is refused on its estimate: solvers fill
#: tables on first use (the first seconds can be 20× slower per σ⁰ than the rest).
EARLIEST_REFUSAL = 0.1

_BUDGET = contextvars.ContextVar("emscatter_time_budget", default=())


class TimeBudgetError(RuntimeError):
    """A hemispherical integral would not finish within its time budget."""


class QuadratureWarning(UserWarning):
    """An emissivity quadrature stopped short of its tolerance (evaluation or time budget):
    the message names the error reached and the angles; ``result.error`` holds it."""


def _check_budget(name: str, value) -> float | None:
    if value is None or (isinstance(value, str) and value.strip().lower() in ("none", "inf")):
        return None
    try:
        v = float(value)
    except (TypeError, ValueError):
        v = math.nan
    if not v > 0 or isinstance(value, bool):
        raise ValueError(
            f"{name} must be a positive number of seconds or None (no budget), got {value!r}"
        )
    return None if math.isinf(v) else v


@contextlib.contextmanager
def time_budget(seconds: float | None):
    """Within the block, every hemispherical integral (emissivity) gets ``seconds`` [s] of
    wall-clock time (``None``: no budget)::

        with emscatter.emissivity.time_budget(600):
            em.emissivity(surface, eps, wavelength=1.0, theta_i=theta, method="iem")
    """
    token = _BUDGET.set((_check_budget("time_budget", seconds),))
    try:
        yield
    finally:
        _BUDGET.reset(token)


_DEADLINE = contextvars.ContextVar("emscatter_call_deadline", default=None)


@contextlib.contextmanager
def call_deadline():
    """One time budget for a whole call (e.g. :func:`emscatter.emissivity` with
    ``method="auto"``, whose per-angle fallbacks are integrals of their own): every
    hemispherical integral inside the ``with`` block gets what is left of
    :func:`current_time_budget` counted from its start; blocks nested in it share the outer
    deadline. A context manager, not a decorator: it adds no frame between the user's call and
    the library, so warnings still point at the caller's line."""
    if _DEADLINE.get() is not None:
        yield
        return
    budget = current_time_budget()
    token = _DEADLINE.set((None if budget is None else time.perf_counter() + budget,))
    try:
        yield
    finally:
        _DEADLINE.reset(token)


def _budget_left() -> float | None:
    """Seconds left to the enclosing call's deadline, else the budget of a fresh call."""
    outer = _DEADLINE.get()
    if outer is None:
        return current_time_budget()
    if outer[0] is None:
        return None
    return max(outer[0] - time.perf_counter(), 1e-9)


def current_time_budget() -> float | None:
    """The budget [s] in force: :func:`time_budget`, else ``EMSCATTER_TIME_BUDGET_S``, else
    :data:`TIME_BUDGET_S` (``None``: no budget)."""
    override = _BUDGET.get()
    if override:
        return override[0]
    env = os.environ.get("EMSCATTER_TIME_BUDGET_S")
    if env is not None and env.strip():
        return _check_budget("EMSCATTER_TIME_BUDGET_S", env)
    return TIME_BUDGET_S


class _OverBudget(Exception):
    """Internal: the estimate in progress would end past the budget."""

    def __init__(self, predicted: float, evaluations: int, rate: float):
        super().__init__(predicted)
        self.predicted, self.evaluations, self.rate = predicted, evaluations, rate


class _Clock:
    """Wall clock of one integral and the measured cost of a σ⁰ evaluation [s] (the fastest
    chunk's: an optimistic estimate, so a refusal is sure).

    ``follow``: how many times this estimate's evaluations must follow it (the first
    estimate is useless without the second, ``growth`` times as large)."""

    def __init__(self, budget: float | None):
        self.t0 = time.perf_counter()
        self.budget = budget
        self.rate: float | None = None
        self.follow = 0
        self.chunks = 0  # chunks measured: a refusal needs two (the first carries one-offs)

    def elapsed(self) -> float:
        return time.perf_counter() - self.t0

    def fits(self, evaluations: int) -> bool:
        """Whether ``evaluations`` more would end within the budget (by the measured rate)."""
        if self.budget is None or self.rate is None:
            return True
        return self.elapsed() + self.rate * evaluations <= self.budget


def _evaluate(sigma0_fn, theta_s, phi_s, lead: int, clock: _Clock):
    """``sigma0_fn`` over directions of shape ``(*S, *D)`` (``lead = len(S)``), in chunks of
    the flattened ``D`` (each ≈ CHUNK_SECONDS by the measured rate); between chunks Python
    runs signal handlers and the budget is checked. :class:`_OverBudget` when the time is
    spent, or when at least :data:`EARLIEST_REFUSAL` of the budget is spent and even the
    fastest rate seen (one-off costs — compilation, tables a solver fills on first use —
    only slow chunks down) says this estimate and what must follow it would end past it."""
    lead_shape, tail = theta_s.shape[:lead], theta_s.shape[lead:]
    m = math.prod(tail)
    per_index = max(1, math.prod(lead_shape))
    total = m * per_index
    # (*S, *D) → (*S, m, 1, ...): the solver broadcasts θi[..., None, ...] against it as before
    flat = (*lead_shape, m, *([1] * (len(tail) - 1)))
    ts, ps = theta_s.reshape(flat), phi_s.reshape(flat)
    rest = (slice(None),) * (len(tail) - 1)
    parts = []
    start = 0
    # the first chunk measures the rate (at most FIRST_CHUNK_EVALUATIONS σ⁰ evaluations: a
    # few solver calls fewer than one direction, and bounded even for a pathological σ⁰);
    # later estimates start from that rate
    size = (
        max(1, FIRST_CHUNK_EVALUATIONS // per_index)
        if clock.rate is None
        else max(1, int(CHUNK_SECONDS / max(clock.rate * per_index, 1e-12)))
    )
    _progress.expect(total)  # the bar of the call, if any, counts σ⁰ evaluations
    while start < m:
        stop = min(m, start + size)
        done = stop - start  # this chunk's directions (the next chunk grows from it)
        t = time.perf_counter()
        idx = (Ellipsis, slice(start, stop), *rest)
        parts.append(sigma0_fn(ts[idx], ps[idx]))
        rate = (time.perf_counter() - t) / (done * per_index)
        _progress.advance(done * per_index)
        clock.rate = rate if clock.rate is None else min(clock.rate, rate)
        clock.chunks += 1
        start = stop
        left = (m - start) * per_index + clock.follow * total
        if clock.budget is not None and start < m:
            spent = clock.elapsed() > clock.budget
            early = clock.elapsed() < EARLIEST_REFUSAL * clock.budget
            if spent or (not early and clock.chunks >= 2 and not clock.fits(left)):
                predicted = clock.elapsed() + clock.rate * left
                raise _OverBudget(predicted, (1 + clock.follow) * total, clock.rate)
        size = max(1, min(8 * done, int(CHUNK_SECONDS / max(rate * per_index, 1e-12))))
        if clock.budget is not None:  # a chunk ends before the budget: a refusal comes in time
            room = 0.5 * (clock.budget - clock.elapsed())
            size = max(1, min(size, int(room / max(rate * per_index, 1e-12))))
    axis = lead + 2  # after (pol_s, pol_i)
    sig = np.concatenate(parts, axis=axis) if len(parts) > 1 else parts[0]
    return sig.reshape(*sig.shape[:axis], *tail)


#: Absolute slack [-] added to the quadrature error when checking the energy balance
#: (rounding of quantities of order 1).
ENERGY_ATOL = 1e-9


def _list(values, limit=6) -> str:
    vals = [f"{v:.4g}" for v in np.ravel(values)[:limit]]
    return ", ".join(vals) + (" ..." if np.size(values) > limit else "")


def energy_balance(
    r_coh, r_incoh, error, theta_i, *, tol: float = 0.0, atol: float = ENERGY_ATOL
) -> dict:
    """Check energy conservation per incidence angle.

    With ``e = 1 − r_coh − r_incoh`` and a margin ``m = max(error, tol) + atol`` per
    polarization (the quadrature's accuracy: the tolerance asked, or the error estimate where it
    is larger — the estimate, a difference of two refinements, can be optimistic), an
    angle conserves energy when, for both polarizations, everything is finite,
    ``r_coh ≥ −m``, ``r_incoh ≥ −m`` and ``−m ≤ e ≤ 1 + m`` (i.e. ``r_coh + r_incoh ≤ 1``
    beyond the quadrature error).

    Parameters: arrays of shape ``(2, *S)`` (h, v) and ``theta_i`` [rad] of shape ``S``.
    Returns ``{"ok": bool (S), "ok_pol": bool (2, *S), "emissivity", "reflectivity", "error",
    "reasons": [one line per polarization that fails, angles in degrees, values]}``.
    """
    r_coh = np.asarray(r_coh, dtype=float)
    r_incoh = np.asarray(r_incoh, dtype=float)
    error = np.asarray(error, dtype=float)
    e = 1.0 - r_coh - r_incoh
    m = np.maximum(np.where(np.isnan(error), np.inf, np.abs(error)), tol) + atol
    with np.errstate(invalid="ignore"):
        finite = np.isfinite(r_coh) & np.isfinite(r_incoh)
        ok_pol = finite & (r_coh >= -m) & (r_incoh >= -m) & (e >= -m) & (e <= 1 + m)
    ok = ok_pol.all(axis=0)
    reasons = []
    theta = np.broadcast_to(np.asarray(theta_i, dtype=float), ok.shape)
    for p, label in enumerate("hv"):
        bad = ~ok_pol[p]
        if not bad.any():
            continue
        deg = ", ".join(f"{d:.4g}°" for d in np.degrees(theta[bad]).ravel()[:6])
        deg += " ..." if bad.sum() > 6 else ""
        if not finite[p][bad].all():
            reasons.append(f"e_{label} is not finite at θi = {deg}")
            continue
        tot = (r_coh[p] + r_incoh[p])[bad]
        reasons.append(
            f"energy not conserved, e_{label} = {_list(e[p][bad])} at θi = {deg} "
            f"(r_coh + r_incoh = {_list(tot)}; allowed [0, 1] within the quadrature accuracy "
            f"≤ {float(np.max(m[p][bad])):.2g})"
        )
    return {
        "ok": ok,
        "ok_pol": ok_pol,
        "emissivity": e,
        "reflectivity": r_coh + r_incoh,
        "error": error,
        "margin": m,
        "reasons": reasons,
    }


def lobe_width(roughness, k: float) -> float:
    """A scale [-] (in ``sinθ`` units) of the narrowest lobe to resolve: the spectral width
    ``1/(kℓ)`` or the rms slope, whichever is smaller, clipped to ``[1e-4, 0.25]``."""
    ell = min(roughness.length, roughness.length_y)
    w = 1.0 / (k * ell)
    try:
        slope = math.sqrt(roughness.total_mean_square_slope())
        w = min(w, slope)
    except ValueError:
        pass
    return float(np.clip(w, 1e-4, 0.25))


@lru_cache(maxsize=64)
def _graded_rule(finest: float, order: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes and weights on [0, 1]: panels [0, f], [f, 4f], [4f, 16f], ... , [., 1],
    Gauss–Legendre of ``order`` on each, edge map on the last panel."""
    edges = [0.0]
    b = finest
    while b < 0.5:
        edges.append(b)
        b *= 4.0
    edges.append(1.0)
    x, w = np.polynomial.legendre.leggauss(order)
    s = 0.5 * (x + 1.0)  # on [0, 1]
    ws = 0.5 * w
    nodes, weights = [], []
    for a, b in zip(edges[:-2], edges[1:-1], strict=True):
        nodes.append(a + (b - a) * s)
        weights.append((b - a) * ws)
    a = edges[-2]
    # t = 1 - (1 - a) s², dt = 2 (1 - a) s ds  (removes the 1/sqrt(1 - t) edge singularity)
    nodes.append(1.0 - (1.0 - a) * s**2)
    weights.append(2.0 * (1.0 - a) * s * ws)
    return np.concatenate(nodes), np.concatenate(weights)


_WAYS_OUT = (
    "ways out: a method that is cheaper here (method='go' where its kσ limit holds, "
    "or 'spm' at small kσ), fewer incidence angles, a looser tol, or a larger budget "
    "(with emscatter.emissivity.time_budget(seconds): ..., or EMSCATTER_TIME_BUDGET_S)"
)


def _over_budget_message(over: _OverBudget, clock: _Clock, theta_i) -> str:
    return (
        f"the hemispherical integral would take about {over.predicted:.3g} s (its first two, "
        f"coarsest estimates need {over.evaluations} σ⁰ evaluations at {over.rate * 1e3:.3g} ms "
        f"each, measured on the first {clock.elapsed():.2g} s) for {np.size(theta_i)} "
        f"incidence angle(s), more than the time budget of {clock.budget:g} s; " + _WAYS_OUT
    )


def _reflectivity_2d(sigma0_fn, theta_i, phi_i, finest, order, n_alpha, clock, mirror=False):
    """One quadrature estimate; returns (r (2, *S), evaluations). ``mirror``: the azimuths
    ``α`` and ``−α`` (mirror images in the plane of incidence) carry the same σ⁰, so only
    ``0 ≤ α ≤ π`` is evaluated, the inner azimuths weighted twice (same sum, ~half the cost)."""
    t, wt = _graded_rule(finest, order)
    alpha = np.arange(n_alpha) * (2 * math.pi / n_alpha)
    wa = np.ones(n_alpha)
    if mirror and n_alpha % 2 == 0:
        alpha = alpha[: n_alpha // 2 + 1]
        wa = np.full(alpha.size, 2.0)
        wa[0] = wa[-1] = 1.0
    ti = theta_i[..., None, None]
    pi_ = phi_i[..., None, None]
    p0x, p0y = np.sin(ti) * np.cos(pi_), np.sin(ti) * np.sin(pi_)
    ca, sa = np.cos(alpha)[:, None], np.sin(alpha)[:, None]
    b = p0x * ca + p0y * sa
    c = p0x**2 + p0y**2 - 1.0
    rho_max = -b + np.sqrt(np.maximum(b * b - c, 0.0))
    rho = rho_max * t
    px, py = p0x + rho * ca, p0y + rho * sa
    s2 = np.minimum(px * px + py * py, 1.0)
    sin_s = np.sqrt(s2)
    cos_s = np.sqrt(1.0 - s2)
    theta_s = np.arctan2(sin_s, cos_s)
    phi_s = np.arctan2(py, px)
    shape = np.broadcast_shapes(theta_s.shape, phi_s.shape)
    theta_s, phi_s = np.broadcast_to(theta_s, shape), np.broadcast_to(phi_s, shape)
    sig = _evaluate(sigma0_fn, theta_s, phi_s, theta_i.ndim, clock)  # (2, 2, *S, n_alpha, n_t)
    summed = sig.sum(axis=0)  # over scattered pol -> (2, *S, n_alpha, n_t)
    with np.errstate(divide="ignore", invalid="ignore"):
        jac = np.where(cos_s > 0, rho_max * rho / cos_s, 0.0) * wt
    integral = ((summed * jac).sum(axis=-1) * wa).sum(axis=-1) * (2 * math.pi / n_alpha)
    r = integral / (4 * math.pi * np.cos(theta_i))
    return r, summed[0].size


def _reflectivity_1d(sigma0_fn, theta_i, phi_i, finest, order, clock):
    t, wt = _graded_rule(finest, order)
    u0 = np.sin(theta_i)[..., None]
    # forward side u in [u0, 1], backward side u in [-1, u0]
    u = np.concatenate([u0 + (1.0 - u0) * t, u0 - (1.0 + u0) * t], axis=-1)
    jl = np.concatenate([(1.0 - u0) * wt, (1.0 + u0) * wt], axis=-1)
    u = np.clip(u, -1.0, 1.0)
    cos_s = np.sqrt(1.0 - u * u)
    theta_s = np.arctan2(np.abs(u), cos_s)
    phi_s = phi_i[..., None] + np.where(u >= 0, 0.0, math.pi)
    shape = np.broadcast_shapes(theta_s.shape, phi_s.shape)
    theta_s, phi_s = np.broadcast_to(theta_s, shape), np.broadcast_to(phi_s, shape)
    sig = _evaluate(sigma0_fn, theta_s, phi_s, theta_i.ndim, clock)  # (2, 2, *S, n)
    summed = sig.sum(axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        jac = np.where(cos_s > 0, jl / cos_s, 0.0)
    r = (summed * jac).sum(axis=-1) / (2 * math.pi * np.cos(theta_i))
    return r, summed[0].size


def hemispherical_reflectivity(
    sigma0_fn,
    theta_i,
    phi_i=0.0,
    *,
    dimension: int = 2,
    finest: float = 0.05,
    tol: float = 1e-4,
    order: int | None = None,
    n_alpha: int | None = None,
    max_refinements: int = 4,
    max_evaluations: int | None = None,
    budget_s="default",
    mirror: bool = False,
    restrict=None,
):
    """Incoherent reflectivity ``r_p(θi)`` of a bistatic σ⁰ by the graded quadrature above.

    Parameters
    ----------
    sigma0_fn : callable ``(theta_s, phi_s) -> sigma0`` of shape ``(2, 2, *S, ...)`` where
        ``S`` is the shape of ``theta_i`` (the callable broadcasts ``theta_i[..., None, ...]``).
    theta_i, phi_i : incidence angles [rad], shape ``S``.
    dimension : 2 (surface, solid angle) or 1 (profile, in-plane angle).
    finest : width of the finest panel [in units of sinθ], ~ the narrowest lobe.
    tol : absolute tolerance on ``r`` [-] between successive refinements.
    order, n_alpha : starting Gauss–Legendre order per panel and number of azimuths; by
        default chosen from ``tol`` (coarser start for looser tolerances).
    max_refinements : at most this many refinements (each ×4 evaluations in 2-D, ×2 in 1-D).
    max_evaluations : budget of σ⁰ evaluations per incidence angle (all refinements
        together; default :data:`MAX_EVALUATIONS_PER_ANGLE`): a refinement that would exceed
        it is not started, so every call answers in bounded time; the returned error then
        says how far from ``tol`` it stopped.
    budget_s : wall-clock budget [s] (default :func:`current_time_budget`; ``None``: none).
        A refinement whose measured-rate estimate ends past it is not started (the error
        reached is returned); a first estimate that would end past it raises
        :class:`TimeBudgetError` (module docstring). σ⁰ is evaluated in chunks either way.
    restrict : optional ``restrict(mask) -> sigma0_fn`` for the incidence angles
        ``theta_i[mask]`` only (flattened): refinements then evaluate only the angles whose
        error is not yet within ``tol`` (the others keep their estimate and error).
    mirror : the caller guarantees that σ⁰ summed over the scattered polarization is even
        under reflection in the plane of incidence (``φs − φi → φi − φs``; isotropic
        roughness and a deterministic solver): 2-D estimates then evaluate half the azimuths.

    Returns ``(r, error, evaluations)`` with ``r`` and ``error`` of shape ``(2, *S)``.
    """
    theta_i = np.asarray(theta_i, dtype=float)
    phi_i = np.broadcast_to(np.asarray(phi_i, dtype=float), theta_i.shape)
    finest = float(np.clip(finest, 1e-4, 0.25))
    default_order, default_alpha = (4, 16) if tol >= 1e-3 else (6, 24) if tol >= 1e-5 else (8, 32)
    order = order or default_order
    n_alpha = n_alpha or default_alpha
    evals = 0
    clock = _Clock(_budget_left() if budget_s == "default" else
                   _check_budget("budget_s", budget_s))  # fmt: skip

    def estimate(o, na, fn=sigma0_fn, ti=theta_i, pi_=phi_i):
        if dimension == 1:
            return _reflectivity_1d(fn, ti, pi_, finest, o, clock)
        return _reflectivity_2d(fn, ti, pi_, finest, o, na, clock, mirror)

    per_angle = MAX_EVALUATIONS_PER_ANGLE if max_evaluations is None else int(max_evaluations)
    growth = 2 if dimension == 1 else 4
    clock.follow = growth if max_refinements > 0 else 0
    try:
        r_prev, n = estimate(order, n_alpha)
    except _OverBudget as over:
        raise TimeBudgetError(_over_budget_message(over, clock, theta_i)) from None
    clock.follow = 0
    evals += n
    last = n / max(1, theta_i.size)  # evaluations per angle of the last estimate
    used = last  # ... and so far, per angle still refined
    err = np.full(r_prev.shape, np.inf)
    active = np.ones(theta_i.shape, dtype=bool)  # angles not yet within tol
    for _ in range(max_refinements):
        n_active = max(1, int(active.sum()))
        if used + growth * last > per_angle and np.isfinite(err).all():
            break  # the next refinement would exceed the budget: report the error reached
        if not clock.fits(growth * last * n_active) and np.isfinite(err).all():
            break  # ... or end past the time budget (estimated from the measured rate)
        order, n_alpha = 2 * order, 2 * n_alpha
        try:
            if restrict is not None and not active.all():  # refine only where tol is not met
                sub, n = estimate(order, n_alpha, restrict(active), theta_i[active], phi_i[active])
                r = r_prev.copy()
                r[:, active] = sub
            else:
                r, n = estimate(order, n_alpha)
        except _OverBudget:
            if np.isfinite(err).all():
                break  # keep the previous estimate and its error
            raise TimeBudgetError(
                f"the hemispherical integral needs two estimates for an error bound and the "
                f"second would end past the time budget of {clock.budget:g} s; " + _WAYS_OUT
            ) from None
        evals += n
        last = n / n_active
        used += last
        err = np.where(active, np.abs(r - r_prev), err)
        r_prev = r
        if restrict is not None:
            active = ~np.all(err <= tol, axis=0)
        if np.all(err <= tol):
            break
    return r_prev, err, evals
