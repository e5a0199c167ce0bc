"""The public emissivity entry point: h and v emissivity by hemispherical integration.

:func:`emissivity` takes the same inputs as :func:`emscatter.api.bistatic` (roughness, ``ε``
or a material, exactly one of ``frequency`` [Hz] or ``wavelength`` [m], angles in radians) and
integrates the incoherent σ⁰ over the upper hemisphere plus the coherent reflectivity
(:func:`emscatter.emissivity.hemispherical_reflectivity`), ``e = 1 − r_coh − r_incoh``
(Kirchhoff's law; Ulaby, Moore & Fung 1982 vol. II), with the energy balance checked at every angle
(:func:`emscatter.emissivity.energy_balance`). ``method="auto"`` replaces the method at the
angles where it breaks energy. Re-exported as :func:`emscatter.api.emissivity` and
:func:`emscatter.emissivity`.
"""

from __future__ import annotations

import functools
import inspect
import math
import warnings

import numpy as np

from . import cache, solvers
from . import progress as _progress
from .conventions import broadcast_angles, check_angle, check_finite, wavenumber
from .emissivity import (
    MAX_EVALUATIONS_PER_ANGLE,
    Emissivity,
    QuadratureWarning,
    TimeBudgetError,
    call_deadline,
    current_time_budget,
    energy_balance,
    hemispherical_reflectivity,
    lobe_width,
)
from .frequency import as_eps_or_material, eps_at, frequency_groups
from .fresnel import is_pec
from .method_resolution import (
    _angle_mask,
    _check_method,
    _check_roughness,
    _map_options,
    _merge_methods,
    _merged_validity,
    _takes,
    angle_policy,
    angles_deg,
    rank_methods,
    resolve_method,
    validity_report,
)
from .solvers import select
from .spectra import Roughness

__all__ = ["emissivity"]


def _integrate(module, rough, eps, k, ti, pi_, tol, options):
    """:func:`_integrate_uncached` through the on-disk result cache (:mod:`emscatter.cache`;
    a Monte Carlo solver only with a fixed seed)."""
    if hasattr(module, "reflectivity") and options.get("seed") is None:
        return _integrate_uncached(module, rough, eps, k, ti, pi_, tol, options)
    key = {"method": module.__name__, "surface": rough, "eps": eps, "k": k, "theta_i": ti,
           "phi_i": pi_, "tol": tol, "options": options}  # fmt: skip
    return cache.cached(
        "emissivity", key, lambda: _integrate_uncached(module, rough, eps, k, ti, pi_, tol, options)
    )


def _integrate_uncached(module, rough, eps, k, ti, pi_, tol, options):
    """(r_coh, r_incoh, error, evaluations) by the shared hemispherical quadrature."""
    if hasattr(module, "reflectivity"):  # e.g. the method of moments: its own far-field sums
        r_coh, r_inc, err = module.reflectivity(rough, eps, k, ti, pi_, **options)
        return np.asarray(r_coh), np.asarray(r_inc), np.asarray(err), 0
    dims = (Ellipsis,) + (None,) * (1 if rough.dimension == 1 else 2)
    # σ⁰ only inside the integral: skip a solver's coherent part when it offers to.
    skip = {"coherent": False} if _takes(module.bistatic, "coherent") else {}

    def make(sel=None, **extra):
        """σ⁰(θs, φs) at the incidence angles ``ti[sel]`` (all when ``sel`` is None)."""
        t, p, e = (ti, pi_, eps) if sel is None else (ti[sel], pi_[sel], _sub_eps(eps, sel))
        e_q = e if is_pec(e) or np.ndim(e) == 0 else np.asarray(e)[dims]
        kw = {**skip, **options, **extra}

        def sigma0_fn(theta_s, phi_s):
            return module.bistatic(rough, e_q, k, t[dims], theta_s, phi_s, p[dims], **kw).sigma0

        return sigma0_fn

    finest = lobe_width(rough, k)
    # isotropic roughness and a deterministic σ⁰ (no realizations): mirror-symmetric in φs − φi
    mirror = bool(getattr(rough, "is_isotropic", False)) and not _takes(module.bistatic, "seed")
    if _splits_multiple(module, rough, options):
        r_inc, err, evals = _split_multiple(make, ti, pi_, finest, tol, mirror)
    else:
        r_inc, err, evals = hemispherical_reflectivity(
            make(), ti, pi_, dimension=rough.dimension, finest=finest, tol=tol, mirror=mirror,
            restrict=make,
        )  # fmt: skip
    if getattr(module, "COHERENT_IN_SIGMA0", False):  # GO: σ⁰ is the whole intensity
        return np.zeros_like(r_inc), r_inc, err, evals
    r_coh = module.bistatic(rough, eps, k, ti, ti, pi_, pi_, **options).coherent
    return np.asarray(r_coh), r_inc, err, evals


#: Share of ``tol`` given to the multiple-scattering part when it is integrated on its own
#: (:func:`_split_multiple`); the single-scattering part gets the rest.
MULTIPLE_TOL_SHARE = 0.25


def _splits_multiple(module, rough, options) -> bool:
    """Whether σ⁰ has a separately switchable multiple-scattering term (the IEM's hv/vh:
    ``crosspol``, on by default) that :func:`_split_multiple` integrates on its own rule."""
    if rough.dimension != 2 or not _takes(module.bistatic, "crosspol"):
        return False
    default = _default(module.bistatic, "crosspol")
    return default is not inspect.Parameter.empty and bool(options.get("crosspol", default))


@functools.lru_cache(maxsize=64)
def _default(func, name: str):
    """The default of ``func``'s parameter ``name`` (signatures read once per function)."""
    return inspect.signature(func).parameters[name].default


def _split_multiple(make, ti, pi_, finest, tol, mirror=False):
    """``(r, error, evaluations)``: ∫σ⁰ = ∫σ⁰_single + ∫(σ⁰ − σ⁰_single), each integral on its
    own adaptive rule. The single-scattering σ⁰ is cheap (tens of µs per direction) and may
    have a narrow lobe; the multiple-scattering hv term (Fung 1994; Chen et al. 2003 app. C)
    is a 2-D integral per direction (~1 ms) but smooth and, at kσ ≲ 1, a 1e-5–1e-3 share of
    ``r``: integrated together, every node of the fine rule the single part needs paid for
    it. Here the difference starts on the coarsest rule (order 2, 8 azimuths) and refines
    only until it meets its share of ``tol`` (:data:`MULTIPLE_TOL_SHARE`); the errors add.
    ``evaluations`` counts both rules' directions. ``make(sel, **options)``: σ⁰ at
    ``ti[sel]``."""

    def single(sel=None):
        return make(sel, crosspol=False)

    def multiple(sel=None):
        full, one = make(sel), make(sel, crosspol=False)
        return lambda theta_s, phi_s: full(theta_s, phi_s) - one(theta_s, phi_s)

    r1, e1, n1 = hemispherical_reflectivity(
        single(), ti, pi_, finest=finest, tol=tol * (1.0 - MULTIPLE_TOL_SHARE), mirror=mirror,
        restrict=single,
    )  # fmt: skip
    r2, e2, n2 = hemispherical_reflectivity(
        multiple(), ti, pi_, finest=finest, tol=tol * MULTIPLE_TOL_SHARE, order=2, n_alpha=8,
        mirror=mirror, restrict=multiple,
    )  # fmt: skip
    return r1 + r2, e1 + e2, n1 + n2


def _excess(report: dict) -> float:
    return 0.0 if report.get("valid", False) else float(report.get("excess", math.inf))


def _sub_eps(eps, mask):
    return eps if is_pec(eps) or np.ndim(eps) == 0 else np.broadcast_to(eps, mask.shape)[mask]


def _energy_fallback(rough, eps, k, ti, pi_, tol, options, ranking, primary, state):
    """``method="auto"``: at the angles where the primary method is invalid or breaks energy,
    try the next methods of the ranking; keep the first that is valid there and conserves
    energy. Candidates further outside their roughness-level validity than the primary are
    skipped (auto never trades a method for a worse-founded one). Updates ``state``."""
    limit = _excess(primary)
    for cand, _ in ranking[1:]:
        ok = state["ok"]
        if ok.all():
            return
        cand_report = validity_report(cand, rough, k, eps=eps)
        if cand_report.get("unsupported") or _excess(cand_report) > limit:
            continue
        bad = ~ok
        sub_ti, sub_pi = ti[bad], pi_[bad]
        module = solvers.get(cand)
        try:
            opts = _map_options(cand, options, True)
            rc, ri, er, ev = _integrate(
                module, rough, _sub_eps(eps, bad), k, sub_ti, sub_pi, tol, opts
            )
        except (ValueError, TypeError):  # this method cannot take these inputs
            continue
        except TimeBudgetError:  # not within what is left of the call's time budget
            continue
        angular = validity_report(cand, rough, k, eps=eps, theta_i=sub_ti)
        accept = energy_balance(rc, ri, er, sub_ti, tol=tol)["ok"] & _angle_mask(
            angular, sub_ti.shape
        )
        if not accept.any():
            continue
        where = np.flatnonzero(bad)[accept]
        for key, val in (("r_coh", rc), ("r_inc", ri), ("err", er)):
            state[key].reshape(2, -1)[:, where] = np.asarray(val).reshape(2, -1)[:, accept]
        state["methods"].reshape(-1)[where] = cand
        state["ok"].reshape(-1)[where] = True
        state["evals"] += ev


def _emissivity_one(rough, eps, k, ti, pi_, method, tol, out_of_range, options) -> Emissivity:
    """One frequency; ``ti`` and ``pi_`` broadcast to the same shape."""
    if method == "auto":  # the regime's ranking; angles are handled one by one below
        ranking = rank_methods(rough, k, eps=eps)
    else:
        ranking = [(method, None)]
    opts = _map_options(ranking[0][0], options, method == "auto")  # before any warning
    name, module, report, make_nan = resolve_method(
        rough, k, ranking[0][0], out_of_range, eps, theta_i=ti
    )
    r_coh, r_inc, err, evals = _integrate(module, rough, eps, k, ti, pi_, tol, opts)
    state = {
        "r_coh": np.array(r_coh, dtype=float),
        "r_inc": np.array(r_inc, dtype=float),
        "err": np.array(err, dtype=float),
        "methods": np.full(ti.shape, name, dtype=object),
        "ok": _angle_mask(report, ti.shape) & energy_balance(r_coh, r_inc, err, ti, tol=tol)["ok"],
        "evals": evals,
    }
    if method == "auto" and not make_nan:
        _energy_fallback(rough, eps, k, ti, pi_, tol, options, ranking, report, state)
    r_coh, r_inc, err = state["r_coh"], state["r_inc"], state["err"]
    balance = energy_balance(r_coh, r_inc, err, ti, tol=tol)
    ok = state["ok"]
    reasons = [*(report.get("angle_reasons", []) if not ok.all() else []), *balance["reasons"]]
    report = {
        **report,
        "angle_valid": ok,
        "angle_reasons": reasons,
        "energy_ok": balance["ok"],
        "valid": bool(report.get("roughness_valid", False) and ok.all()),
    }
    methods = state["methods"]
    label = _merge_methods(methods.ravel()) if methods.size else name
    blank = angle_policy(label, ~ok, ti, out_of_range, reasons)
    e = 1.0 - r_coh - r_inc
    converged = np.all(err <= tol, axis=0)
    quadrature = {"tol": tol, "converged": converged}
    if not converged.all():
        per_angle = state["evals"] / max(1, ti.size)
        quadrature["reason"] = (
            f"quadrature stopped at error {float(np.nanmax(err)):.2g} > tol {tol:g} at "
            f"{angles_deg(ti, ~converged)} (evaluation or time budget)"
        )
        warnings.warn(
            QuadratureWarning(
                f"emissivity ({label}): the {quadrature['reason']}: {per_angle:.0f} σ⁰ "
                f"evaluations per angle of at most {MAX_EVALUATIONS_PER_ANGLE}, time budget "
                f"{current_time_budget()} s; the result holds to the error reached "
                "(result.error); ways out: a looser tol, or a larger time budget "
                "(emscatter.emissivity.time_budget(seconds))"
            ),
            stacklevel=3,
        )
    info = {"validity": report, "energy": balance, "methods": methods, "quadrature": quadrature}
    if make_nan:
        e = np.full_like(e, np.nan)
        info["out_of_range"] = True
    elif blank.any():
        e = np.where(blank, np.nan, e)
        info["out_of_range"] = blank
    return Emissivity(
        emissivity=e,
        coherent=r_coh,
        incoherent=r_inc,
        error=err,
        method=label,
        theta_i=ti,
        evaluations=int(state["evals"]),
        info=info,
        k=k,
        energy_ok=balance["ok"],
    )


def _check_tol(tol) -> float:
    if isinstance(tol, bool) or not (
        isinstance(tol, int | float | np.floating) and math.isfinite(tol) and 0 < tol < 1
    ):
        raise ValueError(
            f"tol must be a number in (0, 1) (absolute quadrature tolerance), got {tol!r}"
        )
    return float(tol)


def emissivity(
    surface: Roughness,
    eps,
    *,
    frequency=None,
    wavelength=None,
    theta_i,
    phi_i=0.0,
    method: str = "auto",
    tol: float = 1e-4,
    out_of_range: str = "warn",
    progress: bool | None = None,
    **options,
) -> Emissivity:
    """h and v emissivity ``e_p = 1 − r_coh,p − r_incoh,p`` (Kirchhoff's law) by hemispherical
    integration of the incoherent σ⁰ plus the coherent reflectivity, with an error estimate and
    the energy balance checked at every angle.

    ``tol`` [-]: absolute tolerance of the quadrature (the reported ``error`` is the difference
    of the last two refinements; only the angles not yet within ``tol`` are refined). Where
    it stops short of ``tol`` (evaluation or time budget) a
    :class:`~emscatter.emissivity.QuadratureWarning` names the error reached and the angles
    (``info["quadrature"]`` records it). Other parameters as :func:`emscatter.api.bistatic`.

    Energy is a checked law: wherever ``e ∉ [0, 1]`` or ``r_coh + r_incoh > 1`` beyond the
    quadrature error (:func:`emscatter.emissivity.energy_balance`), the angle is flagged in
    ``result.energy_ok`` and ``info["validity"]["angle_valid"]``, and ``out_of_range``
    applies to those angles. With ``method="auto"`` the method is replaced **at those angles
    only** by the next ranked method that is valid there and conserves energy
    (``info["methods"]`` has the method of each angle, ``result.method`` lists them, e.g.
    ``"spm+go"``): the rest of the curve keeps the best method for the regime, and the angles
    that an approximation gets wrong (typically near grazing) get one that holds there.

    ``progress``: a tqdm bar on stderr counting σ⁰ evaluations of the quadrature, advanced
    per chunk (its total grows as refinements start) — ``None`` (auto) on a terminal past
    2 s, ``True`` always, ``False`` never (:mod:`emscatter.progress`).
    """
    with call_deadline(), _progress.task("emissivity", None, progress, unit="σ⁰"):
        rough = _check_roughness(surface)
        eps = as_eps_or_material(eps)
        k = wavenumber(frequency, wavelength)
        select.check_out_of_range(out_of_range)
        method = _check_method(method)
        ti = check_angle("theta_i", theta_i)
        pi_ = check_finite("phi_i", phi_i).astype(float)
        tol = _check_tol(tol)
        spec = frequency_groups(k, eps, theta_i=ti, phi_i=pi_)
        if spec is None:
            ti_b, pi_b = broadcast_angles(theta_i=ti, phi_i=pi_)
            return _emissivity_one(
                rough, eps_at(eps, k), k, ti_b, pi_b, method, tol, out_of_range, options
            )
        shape, k_b, groups = spec
        parts = []
        for g in groups:
            sub_ti, sub_pi = g.take((ti, pi_))
            parts.append(
                (
                    g,
                    _emissivity_one(
                        rough, g.eps, g.k, sub_ti, sub_pi, method, tol, out_of_range, options
                    ),
                )
            )
        fields = {
            name: np.empty((2, *shape))
            for name in ("emissivity", "coherent", "incoherent", "error")
        }
        energy_ok = np.empty(shape, dtype=bool)
        methods = np.empty(shape, dtype=object)
        for g, res in parts:
            for name, arr in fields.items():
                arr[:, g.mask] = getattr(res, name)
            energy_ok[g.mask] = res.energy_ok
            methods[g.mask] = res.info["methods"]
        info = {"validity": _merged_validity(parts), "methods": methods}
        return Emissivity(
            **fields,
            method=_merge_methods(res.method for _, res in parts),
            theta_i=np.broadcast_to(ti, shape),
            evaluations=sum(res.evaluations for _, res in parts),
            info=info,
            k=k_b,
            energy_ok=energy_ok,
        )
