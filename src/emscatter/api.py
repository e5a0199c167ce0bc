"""The public entry points: bistatic and backscatter coefficients, emissivity.

All take a roughness description (:mod:`emscatter.spectra`), a relative permittivity
(``exp(-iωt)``: ``Im ε ≥ 0``; ``"pec"``; or a material — any object with
``.eps(frequency=...)``, e.g. :mod:`emscatter.materials`), exactly one of ``frequency`` [Hz] or
``wavelength`` [m] — a number or an array (a band) that broadcasts with the angles — and
angles in radians that broadcast together (numpy rules). The solver runs once per distinct
frequency.

``method="auto"`` picks the best method valid for the regime (see
:mod:`emscatter.solvers.select`) and records it in the result. Validity is checked per call
(roughness) and per incidence angle (where the solver reports angular limits); emissivity also
checks the energy balance at every angle (:func:`emscatter.emissivity.energy_balance`), and
``auto`` then replaces the method at the angles where it breaks energy (see :func:`emissivity`).
``out_of_range`` applies to all of these: ``"warn"`` names the angles (degrees) and values,
``"nan"`` blanks those angles only, ``"raise"`` raises, ``"ignore"`` only records.
"""

from __future__ import annotations

import functools
import inspect
import math

import numpy as np

from emscatter.method_resolution import (
    angle_policy,
    angles_deg,
    blend_weights,
    call_report,
    rank_methods,
    validity_report,
)

from . import cache, solvers
from . import progress as _progress
from .conventions import (
    broadcast_angles,
    broadcast_view,
    check_angle,
    check_broadcast,
    check_finite,
    wavenumber,
)
from .emissivity import (
    Emissivity,
    TimeBudgetError,
    call_deadline,
    energy_balance,
    hemispherical_reflectivity,
    lobe_width,
)
from .frequency import Group, as_eps_or_material, eps_at, frequency_groups
from .fresnel import is_pec
from .scattering import Scattering
from .solvers import auto_crosspol, select
from .spectra import Roughness, check_roughness

__all__ = ["bistatic", "backscatter", "emissivity", "resolve_method"]


def _check_roughness(surface) -> Roughness:
    return check_roughness(surface, "surface")


def _check_method(method) -> str:
    if not isinstance(method, str):
        raise ValueError(f"method must be 'auto' or one of {solvers.available()}, got {method!r}")
    name = method.strip().lower()
    if name != "auto":
        solvers.get(name)  # raises naming the allowed methods
    return name


def _map_options(name: str, options: dict, auto: bool) -> dict:
    if not options:  # nothing to map (check_options would return {} too)
        return {}
    mapper = getattr(select, "check_options", None)
    # always a new dict: _bistatic_one pops from it, the caller's options stay whole (bands)
    return dict(mapper(name, options, picked_by_auto=auto) if mapper else options)


def resolve_method(
    roughness: Roughness,
    k: float,
    method: str,
    out_of_range: str,
    eps=None,
    *,
    theta_i=None,
    stacklevel: int = 5,
):
    """``(name, module, report, make_nan)`` for a method name or ``"auto"``.

    ``report`` is the roughness-level validity report (angle entries added when ``theta_i``
    [rad] is given); ``make_nan`` is True when ``out_of_range="nan"`` and the method is outside
    its roughness-level validity (the policy has been applied: warned or raised)."""
    select.check_out_of_range(out_of_range)
    name = _check_method(method)
    return _resolve(roughness, k, name, out_of_range, eps, theta_i, stacklevel + 1)


def _resolve(roughness, k, name, out_of_range, eps, theta_i, stacklevel):
    """:func:`resolve_method` for a ``name`` and ``out_of_range`` already checked (the API's
    own calls: each check once per call)."""
    if name == "auto":
        name = rank_methods(roughness, k, eps=eps)[0][0]
    # the per-angle checks are skipped where the policy does not need them (call_report)
    report = call_report(name, roughness, k, eps=eps, theta_i=theta_i, out_of_range=out_of_range)
    # the roughness-level policy sees the roughness-level verdict (angles: angle_policy)
    whole = {"valid": report["roughness_valid"], "reasons": report.get("reasons", [])}
    make_nan = select.enforce(name, whole, out_of_range, stacklevel=stacklevel)
    return name, solvers.get(name), report, make_nan


def _angle_mask(report: dict, shape) -> np.ndarray:
    """Per-element validity from a report's ``angle_valid`` (all True when absent)."""
    valid = report.get("angle_valid")
    if valid is None:
        return np.ones(shape, dtype=bool)
    valid = np.asarray(valid, dtype=bool)
    return valid if valid.shape == shape else broadcast_view(valid, shape)


def _takes(func, name: str) -> bool:
    """Whether ``func`` has a parameter ``name`` (signatures read once per function)."""
    try:
        return _params(func).__contains__(name)
    except TypeError:  # an unhashable callable: read its signature each time
        return name in inspect.signature(func).parameters


@functools.lru_cache(maxsize=256)
def _params(func) -> frozenset:
    return frozenset(inspect.signature(func).parameters)


def _solver_entry(module):
    """The solver's entry for inputs this module has checked: ``bistatic.checked`` when the
    solver provides one (same arguments; it skips the re-checks and its own validity report,
    which the API replaces), else ``bistatic`` itself (also when a caller replaced it)."""
    return getattr(module.bistatic, "checked", module.bistatic)


# ----------------------------------------------------------------------------- bistatic
def _bistatic_one(
    rough, eps, k, angles, method, out_of_range, options, monostatic=False, depth=0, picked=False
) -> Scattering:
    """One frequency: resolve the method, run the solver, apply the validity policies
    (``monostatic``: the angles are the backscatter ones, told to a solver entry that asks;
    ``depth``: frames between the public function's caller and the usual call path, so that
    warnings point at the user's line — 1 from a band's :func:`_bistatic_groups`; ``picked``:
    ``method`` is one of ``auto``'s blend). ``method="auto"``: the blend of
    :func:`emscatter.method_resolution.blend_weights` (one method away from every switch, else
    :func:`_bistatic_blend`), with the backscatter cross-pol of
    :mod:`emscatter.solvers.auto_crosspol` added to a closed-form branch."""
    ti, ts, ps, pi_ = angles
    if method == "auto":
        blend = blend_weights(rough, k, eps=eps, monostatic=monostatic)
        if len(blend["weights"]) > 1:
            return _bistatic_blend(
                rough, eps, k, angles, blend, out_of_range, options, monostatic, depth
            )
        method, picked = next(iter(blend["weights"])), True
    name = method
    opts = _map_options(name, options, picked)  # before any warning
    name, module, report, make_nan = _resolve(
        rough, k, name, out_of_range, eps, ti, 6 + depth
    )  # warnings point at the caller of bistatic/backscatter
    # BOARD interface 3: the coherent part is computed on first read, unless asked for eagerly
    lazy = _takes(module.bistatic, "coherent") and not opts.pop("coherent", False)
    extra = {"coherent": False} if lazy else {}
    entry = _solver_entry(module)
    if monostatic and _takes(entry, "monostatic"):
        extra["monostatic"] = True
    iem_hv = picked and monostatic and auto_crosspol.takes_iem_term(name, rough, opts)
    iem_hv = iem_hv and _takes(entry, "crosspol")
    if iem_hv:  # the IEM's hv from auto_crosspol's per-angle memory instead
        extra["crosspol"] = False
    result = entry(rough, eps, k, ti, ts, ps, pi_, **extra, **opts)
    shape = result.sigma0.shape[2:]
    info = {**result.info, "validity": report}
    info.pop("coherent", None)
    sigma0 = result.sigma0
    if picked:  # auto's closed-form branches: the backscatter cross-pol they lack
        what = auto_crosspol.IEM_BACKSCATTER if iem_hv else name
        hv, how = auto_crosspol.supplement(what, rough, eps, k, ti, ts, ps, pi_)
        if hv is not None:
            sigma0 = np.array(sigma0, dtype=float)
            sigma0[0, 1] += hv
            sigma0[1, 0] += hv
            if iem_hv:  # the IEM's own term, from the per-angle memory
                info["crosspol"] = "multiple scattering (backscatter; solvers.auto_crosspol)"
            else:
                info["crosspol_added"] = how
    if lazy:

        def coherent():  # the specular geometry: depends on θi, φi, ε only
            if is_pec(eps) or np.ndim(eps) == 0:
                t, p = np.broadcast_arrays(ti, pi_)
                e = eps
            else:
                t, p, e = np.broadcast_arrays(ti, pi_, eps)
            coh = module.bistatic(rough, e, k, t, t, p, p, **opts).coherent
            coh = coh.reshape(2, *(1,) * (len(shape) - t.ndim), *t.shape)
            return np.array(np.broadcast_to(coh, (2, *shape)))

    else:
        coherent = result.coherent
    blank = None  # the angles to blank (the per-angle policy), when any
    valid = report.get("angle_valid")
    if valid is not None and out_of_range != "ignore" and not np.all(valid):
        bad = ~_angle_mask(report, shape)
        reasons = report.get("angle_reasons", [])
        blank = angle_policy(name, bad, result.theta_i, out_of_range, reasons, stacklevel=5 + depth)
        blank = blank if blank.any() else None
    if make_nan or blank is not None:
        mask = np.ones(shape, dtype=bool) if make_nan else blank
        sigma0 = np.where(mask, np.nan, sigma0)
        coh_in = coherent
        coherent = (
            (lambda: np.where(mask, np.nan, coh_in()))
            if callable(coh_in)
            else np.where(mask, np.nan, coh_in)
        )
        info["out_of_range"] = True if make_nan else blank
    return Scattering._of(
        sigma0=sigma0,
        coherent=coherent,
        method=name,
        theta_i=result.theta_i,
        theta_s=result.theta_s,
        phi_s=result.phi_s,
        phi_i=result.phi_i,
        k=k,
        dimension=rough.dimension,
        info=info,
    )


def _bistatic_blend(rough, eps, k, angles, blend, out_of_range, options, monostatic, depth):
    """``method="auto"`` near a switch: ``Σ wₘ σ⁰ₘ`` (and the same combination of the
    coherent parts) over the blend's methods; ``method`` is ``"iem+go"`` (decreasing weight),
    ``info["blend"]`` the weights and switches. The validity policy and report are those of
    the heaviest method (``blend["pick"]``): the others enter with a smaller weight, near a
    limit (within a factor :data:`~emscatter.solvers.blend.BLEND_FACTOR`) or a measured
    tolerance (:mod:`emscatter.solvers.blend`); they run with ``out_of_range="ignore"``
    (no warning, no blanking, no raise for a method the caller did not get alone) and their
    reports are kept in ``info["validity"]["by_method"]``."""
    weights = blend["weights"]
    pick = blend.get("pick", next(iter(weights)))
    parts = []
    for name in weights:  # (a loop: warnings point at the caller, one frame deeper)
        policy = out_of_range if name == pick else "ignore"
        res = _bistatic_one(
            rough, eps, k, angles, name, policy, options, monostatic, depth + 1, True
        )
        parts.append((name, res))
    sigma0 = sum(weights[n] * res.sigma0 for n, res in parts)

    def coherent():
        return sum(weights[n] * np.asarray(res.coherent) for n, res in parts)

    reports = dict((n, res.info["validity"]) for n, res in parts)
    report = {**reports[pick], "method": pick, "by_method": reports}
    first = parts[0][1]
    info = {"validity": report, "blend": blend, "by_method": {n: r.info for n, r in parts}}
    blanks = [r.info["out_of_range"] for n, r in parts if n == pick and "out_of_range" in r.info]
    if blanks:
        info["out_of_range"] = np.logical_or.reduce(
            [np.broadcast_to(b, sigma0.shape[2:]) for b in blanks]
        )
    eager = all(res.coherent_computed for _, res in parts)
    return Scattering(
        sigma0=sigma0,
        coherent=coherent() if eager else coherent,
        method=_merge_methods(weights),
        theta_i=first.theta_i,
        theta_s=first.theta_s,
        phi_s=first.phi_s,
        phi_i=first.phi_i,
        k=k,
        dimension=rough.dimension,
        info=info,
    )


def _merge_methods(names) -> str:
    return "+".join(dict.fromkeys(names))


def _merged_validity(parts) -> dict:
    """One report for several frequencies: valid if all are; reasons name the frequency."""
    reports = [(g, res.info["validity"]) for g, res in parts]
    return {
        "valid": all(rep.get("valid", False) for _, rep in reports),
        "reasons": [
            f"at {g.frequency:.6g} Hz: {why}"
            for g, rep in reports
            for why in rep.get("reasons", [])
        ],
        "by_frequency": [
            {"frequency": g.frequency, "method": res.method, "validity": res.info["validity"]}
            for g, res in parts
        ],
    }


def _bistatic_groups(
    rough, groups: list[Group], shape, k_b, angles, method, out_of_range, opts, monostatic=False
):
    """Several frequencies: one solver run per group, results placed back element-wise."""
    parts = []
    for g in groups:  # (a loop, not a comprehension: its frame count differs across Pythons)
        res = _bistatic_one(
            rough, g.eps, g.k, g.take(angles), method, out_of_range, opts, monostatic, depth=1
        )
        parts.append((g, res))
    sigma0 = np.empty((2, 2, *shape))
    methods = np.empty(shape, dtype=object)
    for g, res in parts:
        sigma0[:, :, g.mask] = res.sigma0
        methods[g.mask] = res.method

    def gather_coherent():
        out = np.empty((2, *shape))
        for g, res in parts:
            out[:, g.mask] = res.coherent
        return out

    eager = all(res.coherent_computed for _, res in parts)  # then the band stays eager too
    coherent = gather_coherent() if eager else gather_coherent
    ti, ts, ps, pi_ = (np.broadcast_to(a, shape) for a in angles)
    info = {**parts[0][1].info, "validity": _merged_validity(parts), "methods": methods}
    info.pop("out_of_range", None)
    if any("out_of_range" in res.info for _, res in parts):
        blank = np.zeros(shape, dtype=bool)
        for g, res in parts:
            blank[g.mask] = np.broadcast_to(res.info.get("out_of_range", False), g.mask.sum())
        info["out_of_range"] = blank
    return Scattering(
        sigma0=sigma0,
        coherent=coherent,
        method=_merge_methods(res.method for _, res in parts),
        theta_i=ti,
        theta_s=ts,
        phi_s=ps,
        phi_i=pi_,
        k=k_b,
        dimension=rough.dimension,
        info=info,
    )


def bistatic(
    surface: Roughness,
    eps,
    *,
    frequency=None,
    wavelength=None,
    theta_i,
    theta_s,
    phi_s,
    phi_i=0.0,
    method: str = "auto",
    out_of_range: str = "warn",
    **options,
) -> Scattering:
    """Bistatic scattering coefficients σ⁰ (all four polarizations) and coherent reflectivity.

    Parameters
    ----------
    surface : roughness statistics (``dimension=2`` surface, or ``dimension=1`` profile).
    eps : relative permittivity of the lower medium (complex, ``Im ε ≥ 0``; may be an array
        broadcasting with the angles), ``"pec"``, or a material with ``.eps(frequency=...)``.
    frequency : [Hz], or ``wavelength`` [m] — exactly one; a number or an array broadcasting
        with the angles (the solver runs once per distinct value).
    theta_i, theta_s : incidence and scattering angles from the normal [rad], in [0, π/2].
    phi_s, phi_i : azimuths [rad]; ``phi_s = phi_i`` is the forward (specular) half-plane.
    method : ``"auto"`` or a registered solver (``"spm"``, ``"go"``, ``"po"``, ``"mom"`` ...).
    out_of_range : ``"warn"`` | ``"raise"`` | ``"nan"`` | ``"ignore"`` when the method is
        outside its validity range — for the whole call (roughness) or at some incidence
        angles (``"nan"`` then blanks those angles only).
    options : passed to the solver (e.g. ``shadowing=False`` for ``"go"``).

    Returns
    -------
    :class:`emscatter.scattering.Scattering` — ``sigma0[pol_s, pol_i]`` linear,
    ``coherent[pol_i]`` (computed on first access: a σ⁰ curve never pays for it), ``method``,
    ``k`` [rad/m] (an array when the frequencies vary).
    """
    rough = _check_roughness(surface)
    eps = as_eps_or_material(eps)
    k = wavenumber(frequency, wavelength)
    select.check_out_of_range(out_of_range)
    method = _check_method(method)
    ti = check_angle("theta_i", theta_i)
    ts = check_angle("theta_s", theta_s)
    ps = check_finite("phi_s", phi_s).astype(float)
    pi_ = check_finite("phi_i", phi_i).astype(float)
    return _bistatic_checked(rough, eps, k, (ti, ts, ps, pi_), method, out_of_range, options)


def _bistatic_checked(
    rough, eps, k, angles, method, out_of_range, options, monostatic=False
) -> Scattering:
    """:func:`bistatic` after its checks (``angles`` = checked θi, θs, φs, φi arrays;
    ``monostatic``: they are :func:`backscatter`'s, θs is θi and φs = φi + π)."""
    ti, ts, ps, pi_ = angles
    one_k = type(k) is float  # (frequency_groups' None, without building its arguments)
    spec = None if one_k else frequency_groups(k, eps, theta_i=ti, theta_s=ts, phi_s=ps, phi_i=pi_)
    if spec is None:  # one frequency: the solver sees the caller's shapes
        if not (monostatic and np.ndim(pi_) == 0):  # (θs is θi and one φi: nothing to check)
            check_broadcast(theta_i=ti, theta_s=ts, phi_s=ps, phi_i=pi_)
        e = eps_at(eps, k)
        return _bistatic_one(rough, e, k, angles, method, out_of_range, options, monostatic)
    shape, k_b, groups = spec
    return _bistatic_groups(
        rough, groups, shape, k_b, angles, method, out_of_range, options, monostatic
    )


def backscatter(
    surface: Roughness,
    eps,
    *,
    frequency=None,
    wavelength=None,
    theta_i,
    phi_i=0.0,
    method: str = "auto",
    out_of_range: str = "warn",
    **options,
) -> Scattering:
    """Monostatic (backscatter) coefficients: ``θs = θi``, ``φs = φi + π``. Parameters as
    :func:`bistatic`."""
    ti = check_angle("theta_i", theta_i)
    pi_ = np.asarray(check_finite("phi_i", phi_i), dtype=float)
    # bistatic's checks, each once (θs = θi and φs = φi + π need none of their own)
    rough = _check_roughness(surface)
    eps = as_eps_or_material(eps)
    k = wavenumber(frequency, wavelength)
    select.check_out_of_range(out_of_range)
    method = _check_method(method)
    ps = np.asarray(pi_ + math.pi, dtype=float)
    angles = (ti, ti, ps, pi_)
    return _bistatic_checked(rough, eps, k, angles, method, out_of_range, options, True)


# ----------------------------------------------------------------------------- emissivity
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
    eps_q = eps if is_pec(eps) or np.ndim(eps) == 0 else np.asarray(eps)[dims]
    # σ⁰ only inside the integral: skip a solver's coherent part when it offers to.
    skip = {"coherent": False} if _takes(module.bistatic, "coherent") else {}

    def sigma0_fn(theta_s, phi_s):
        return module.bistatic(
            rough, eps_q, k, ti[dims], theta_s, phi_s, pi_[dims], **skip, **options
        ).sigma0

    r_inc, err, evals = hemispherical_reflectivity(
        sigma0_fn,
        ti,
        pi_,
        dimension=rough.dimension,
        finest=lobe_width(rough, k),
        tol=tol,
    )
    if getattr(module, "COHERENT_IN_SIGMA0", False):  # GO: σ⁰ is the whole intensity
        return np.zeros_like(r_inc), r_inc, err, evals
    r_coh = module.bistatic(rough, eps, k, ti, ti, pi_, pi_, **options).coherent
    return np.asarray(r_coh), r_inc, err, evals


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
        quadrature["reason"] = (
            f"quadrature stopped at error {float(np.max(err)):.2g} > tol {tol:g} at "
            f"{angles_deg(ti, ~converged)} (evaluation or time budget)"
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
    of the last two refinements). Other parameters as :func:`bistatic`.

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
