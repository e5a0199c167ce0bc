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

import math

import numpy as np

from emscatter.method_resolution import (
    _angle_mask,
    _check_method,
    _check_roughness,
    _map_options,
    _merge_methods,
    _merged_validity,
    _resolve,
    _takes,
    angle_policy,
    blend_weights,
    resolve_method,
)

from .conventions import (
    check_angle,
    check_broadcast,
    check_finite,
    wavenumber,
)
from .emissivity_api import emissivity
from .frequency import Group, as_eps_or_material, eps_at, frequency_groups
from .fresnel import is_pec
from .scattering import Scattering
from .solvers import auto_crosspol, select
from .spectra import Roughness

__all__ = ["bistatic", "backscatter", "emissivity", "resolve_method"]


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
        blend = blend_weights(rough, k, eps=eps, monostatic=monostatic, theta_i=ti)
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
        hv, how = auto_crosspol.supplement(what, rough, eps, k, ti, ts, ps, pi_, options=opts)
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
    reports are kept in ``info["validity"]["by_method"]``.

    Where the 3-D cells' layer is active (Gaussian 2-D surfaces in their box,
    :mod:`emscatter.solvers.blend`) the weights depend on θi: each is then an array of θi's
    shape (broadcastable to σ⁰'s angle shape, as θi is) and the sum is taken per angle; the
    methods run are those with a weight > 0 at some angle (0 elsewhere: their σ⁰ does not
    enter there, NaN included), ``pick`` the heaviest summed over the distinct angles, and
    ``info["blend"]["weights"]`` holds the arrays (``info["blend"]["measured_3d"]`` the
    interpolated cells)."""
    weights = blend["weights"]
    pick = blend.get("pick", next(iter(weights)))
    parts = []
    for name in weights:  # (a loop: warnings point at the caller, one frame deeper)
        policy = out_of_range if name == pick else "ignore"
        res = _bistatic_one(
            rough, eps, k, angles, name, policy, options, monostatic, depth + 1, True
        )
        parts.append((name, res))
    sigma0 = sum(_weighted(weights[n], res.sigma0) for n, res in parts)

    def coherent():
        return sum(_weighted(weights[n], np.asarray(res.coherent)) for n, res in parts)

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


def _weighted(w, values):
    """``w · values``: a scalar weight, or per angle (an array broadcasting against the
    trailing axes of ``values``) with 0 where the weight is 0 (a method out of the blend at
    that angle adds nothing, not even a NaN)."""
    if np.ndim(w) == 0:
        return w * values
    return np.where(w > 0, w * values, 0.0)


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
    ti = _checked_copy(theta_i, 0.0, math.pi / 2)
    ti = check_angle("theta_i", theta_i) if ti is None else ti
    ts = _checked_copy(theta_s, 0.0, math.pi / 2)
    ts = check_angle("theta_s", theta_s) if ts is None else ts
    ps = _checked_copy(phi_s)
    ps = check_finite("phi_s", phi_s).astype(float) if ps is None else ps
    pi_ = check_finite("phi_i", phi_i).astype(float)
    return _bistatic_checked(rough, eps, k, (ti, ts, ps, pi_), method, out_of_range, options)


def _checked_copy(value, low=-math.inf, high=math.inf):
    """The checked copy of a large C-contiguous float64 array in ``[low, high]`` (finite) in
    one compiled pass (:mod:`emscatter.kernels.checks`; bit for bit what ``check_angle`` /
    ``check_finite(...).astype(float)`` return), or None: a small or other array, the numpy
    backend, or a value that fails (the usual check then raises its message)."""
    from .kernels import backend
    from .kernels.gate import MIN_GEOMETRIES

    if not (
        type(value) is np.ndarray and value.dtype.char == "d" and value.size >= MIN_GEOMETRIES
        and value.flags.c_contiguous and backend() == "numba"
    ):  # fmt: skip
        return None
    from .kernels.checks import copy_in_range

    return copy_in_range(value, low, high)


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
    ti = _checked_copy(theta_i, 0.0, math.pi / 2)
    ti = check_angle("theta_i", theta_i) if ti is None else ti
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
