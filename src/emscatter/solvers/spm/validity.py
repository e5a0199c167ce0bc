"""Validity of the small-perturbation method (:func:`emscatter.solvers.spm.model.check_validity`).

Roughness-level criteria (:data:`VALIDITY`):

* ``k_sigma``: ``kσ ≤ 0.3`` (Ulaby, Moore & Fung 1982 vol. II ch. 12; Thorsos & Jackson 1989,
  JASA 86, 261, first-order SPM accurate for ``kσ ≲ 0.3`` at moderate ``kℓ``; the validity
  maps in validation/validity_maps agree);
* ``rms_slope``: per-direction rms slope ``≤ 0.3`` (Ulaby, Moore & Fung 1982: ``√2 σ/ℓ < 0.3``
  for a Gaussian correlation); for non-differentiable spectra the slope of the spectrum the wave
  sees, ``|K| ≤ 2k`` (:mod:`.validity`).

Angle criterion (with ``theta_i`` and ``eps``):

* ``scattered_fraction``: the first-order incoherent reflectivity ``r₁(θi)`` (σ⁰ integrated
  over the hemisphere, summed over scattered polarizations, the larger of h and v incident)
  must stay ``≤ 0.36``. Perturbation theory assumes the scattered field small against the
  specular one (Rice 1951); at second order ``r_coh = |R⁽⁰⁾|² − r₁ + O(σ⁴)`` (energy, Thorsos &
  Jackson 1989; tested in tests/test_spm.py), so ``r₁`` is the size of the correction. 0.36 is
  ``4(kσ)²`` at ``kσ = 0.3``, the scattered fraction that the ``kσ ≤ 0.3`` limit already
  allows at normal incidence over a wide spectrum. It fails near grazing for a conductor in
  TM (and a high-|ε| dielectric, ``cosθi ≲ 1/√|ε|``): with ``f_vv = sinθi sinθs − cosφ`` (no
  ``cosθi`` factor) ``r₁ ∝ (kσ)²/cosθi`` diverges — the low-grazing failure of lowest-order
  perturbation theory for the Neumann problem (Thorsos & Jackson 1991, Waves Random Media 1,
  S165). ``r₁`` is computed once per (roughness, k, ε) on 24 incidence angles and
  interpolated as ``cosθi · r₁`` (smooth up to grazing), so later calls cost nothing.

Spectral cutoff of the coherent term (a note, not a failed check): over a lossy medium the
second-order coherent reflectivity of an exponential or power-law spectrum depends on how far
the spectrum extends (``k_max``; default the whole spectrum,
:func:`emscatter.solvers.spm.model.coherent_cutoff`; validation/spm2_cutoff). The report then
carries ``coherent_depends_on_cutoff = True`` and a note; with ``coherent=True`` and
``theta_i`` it also measures ``cutoff_sensitivity``, the change of the coherent reflectivity
(larger of h, v) between ``k_max/10`` and ``k_max``, per angle.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from emscatter.conventions import check_angle, check_positive
from emscatter.fresnel import check_eps, is_pec
from emscatter.solvers.validity import (
    angle_upper,
    build_report,
    check_solver_options,
    upper,
    wave_slope_variances,
)
from emscatter.spectra import Roughness, check_roughness

__all__ = ["VALIDITY", "OPTIONS", "check_validity", "scattered_fraction"]

#: Documented validity limits of first-order SPM (module docstring). ``rms_slope`` is the
#: per-direction rms slope √⟨h_x²⟩ (Gaussian correlation: √2 σ/ℓ); for non-differentiable
#: spectra it is computed below ``k_max = slope_cutoff_factor · k``.
VALIDITY = {
    "k_sigma_max": 0.3,
    "rms_slope_max": 0.3,
    "slope_cutoff_factor": 2.0,
    "scattered_fraction_max": 0.36,
}

#: Options of :func:`emscatter.solvers.spm.model.bistatic` (what ``check_validity`` accepts).
OPTIONS = ("order", "coherent", "k_max")

_SRC_KS = "Ulaby, Moore & Fung 1982 vol. II ch. 12; Thorsos & Jackson 1989 JASA 86 261"
_SRC_R1 = "Rice 1951; Thorsos & Jackson 1989 (energy at O(σ²)); Thorsos & Jackson 1991 WRM 1 S165"
_GRID = np.radians(np.linspace(0.0, 89.9, 24))


@lru_cache(maxsize=256)
def _fraction_on_grid(rough: Roughness, k: float, eps) -> np.ndarray:
    """``cosθ · r₁(θ)`` on :data:`_GRID`, shape (2, 24) (incident h, v)."""
    from emscatter.emissivity import hemispherical_reflectivity, lobe_width
    from emscatter.solvers.spm.first_order import sigma0_broadcast

    ti = _GRID
    pi_ = np.zeros_like(ti)
    dims = (Ellipsis,) + (None,) * (1 if rough.dimension == 1 else 2)

    def sigma0(theta_s, phi_s):
        return sigma0_broadcast(rough, eps, k, ti[dims], theta_s, phi_s, pi_[dims])[0]

    r, _, _ = hemispherical_reflectivity(
        sigma0, ti, pi_, dimension=rough.dimension, finest=lobe_width(rough, k), tol=1e-2
    )
    return r * np.cos(ti)


def scattered_fraction(roughness: Roughness, k: float, eps, theta_i) -> np.ndarray:
    """First-order SPM incoherent reflectivity ``r₁`` [-] per incident polarization,
    shape ``(2, *theta_i.shape)`` (interpolated, ~1e-2 absolute; module docstring)."""
    rough = check_roughness(roughness)
    k = check_positive("k", k, unit="rad/m")
    ti = check_angle("theta_i", theta_i)
    eps = check_eps(eps)
    if not is_pec(eps):
        eps = complex(np.asarray(eps).item())
    g = _fraction_on_grid(rough, k, eps)
    ci = np.cos(ti)
    out = np.stack([np.interp(ti, _GRID, g[p]) for p in (0, 1)])
    with np.errstate(divide="ignore"):
        return np.where(ci > 0, out / np.where(ci > 0, ci, 1.0), np.inf)


def _fraction_bound(rough: Roughness, k: float, eps, ti: np.ndarray) -> float | None:
    """An upper bound of :func:`scattered_fraction` (larger of h, v) over every angle of
    ``ti`` [rad], or None (an array ``eps``, no angles): the linear interpolation between
    grid nodes never exceeds the nodes, and ``1/cosθ ≤ 1/cos(max θi)``. Costs two passes
    over ``ti``, so that 1e6 angles well inside the limit are decided without interpolating
    at each (a relative margin of 1e-12 covers the rounding of the interpolation)."""
    if not ti.size or not (is_pec(eps) or np.ndim(eps) == 0):
        return None
    lo, hi = float(ti.min()), float(ti.max())
    c_hi = math.cos(hi)
    if not c_hi > 0:
        return None
    g = _fraction_on_grid(rough, k, eps if is_pec(eps) else complex(np.asarray(eps).item()))
    j0 = max(int(np.searchsorted(_GRID, lo, side="right")) - 1, 0)
    j1 = int(np.searchsorted(_GRID, hi, side="left"))
    return float(np.max(g[:, j0 : j1 + 1])) / c_hi * (1.0 + 1e-12)


def _safe_angle(rough: Roughness, k: float, eps, limit: float) -> float:
    """θ_safe [rad]: every angle ≤ θ_safe passes the scattered-fraction check (scalar
    ``eps``) — the grid segments from 0° up, each bounded as in :func:`_fraction_bound`, until
    the first whose bound exceeds ``limit``; the angles above it are checked one by one."""
    g = _fraction_on_grid(rough, k, eps if is_pec(eps) else complex(np.asarray(eps).item()))
    seg = np.maximum(g[:, :-1], g[:, 1:]).max(axis=0) / np.cos(_GRID[1:]) * (1.0 + 1e-12)
    over = np.flatnonzero(seg > limit)
    return float(_GRID[over[0]] if over.size else _GRID[-1])


def check_validity(
    roughness: Roughness, k: float, *, eps=None, theta_i=None, **solver_options
) -> dict:
    """SPM validity report (BOARD interface 1; criteria in the module docstring).

    ``eps`` (complex or "pec", may be an array broadcasting with ``theta_i``) and ``theta_i``
    [rad] enable the per-angle scattered-fraction check; ``solver_options`` are those of
    :func:`~emscatter.solvers.spm.model.bistatic` (checked by name only)."""
    rough = check_roughness(roughness)
    k = check_positive("k", k, unit="rad/m")
    check_solver_options("spm", solver_options, OPTIONS)
    v = VALIDITY
    ks = k * rough.sigma
    user_cut = solver_options.get("k_max")
    if user_cut is not None:
        user_cut = check_positive("k_max", user_cut, unit="rad/m")
    k_max = None
    if rough._mss_closed() is None:
        k_max = v["slope_cutoff_factor"] * k
        if user_cut is not None:
            k_max = min(k_max, user_cut)
    sx, sy, k_cut = wave_slope_variances(rough, k, k_max)
    slope = math.sqrt(max(sx, sy))
    below = "" if k_cut is None else f" (spectrum below {k_cut / k:g}k)"
    checks = [
        upper("k_sigma", ks, v["k_sigma_max"], "kσ", _SRC_KS),
        upper("rms_slope", slope, v["rms_slope_max"], "per-direction rms slope" + below, _SRC_KS),
    ]
    angle_checks = []
    notes = []
    extra = {}
    ti = None
    if theta_i is not None:
        ti = check_angle("theta_i", theta_i)
        if eps is None:
            notes.append("eps not given: the per-angle scattered-fraction check was skipped")
        else:
            eps_c = check_eps(eps)
            bound = _fraction_bound(rough, k, eps_c, ti)
            if bound is not None:  # scalar eps: every angle ≤ θ_safe passes (the API's cue)
                safe = _safe_angle(rough, k, eps_c, v["scattered_fraction_max"])
                extra["angle_safe_below"] = safe
            if bound is not None and bound <= v["scattered_fraction_max"]:
                r1 = np.array([bound])  # every angle passes: its upper bound stands for them
            elif bound is not None and ti.size > 4096:  # many angles: exact only above θ_safe
                rest = ti > safe
                r1 = np.zeros((1, *ti.shape))  # below θ_safe every angle passes: 0 stands in
                r1[0, rest] = np.max(scattered_fraction(rough, k, eps_c, ti[rest]), axis=0)
            elif is_pec(eps_c):
                r1 = scattered_fraction(rough, k, eps_c, ti)
            else:
                e_b, t_b = np.broadcast_arrays(np.asarray(eps_c, dtype=complex), ti)
                r1 = np.empty((2, *t_b.shape))
                for e in np.unique(e_b):
                    m = e_b == e
                    r1[:, m] = scattered_fraction(rough, k, complex(e), t_b[m])
                ti = t_b
            angle_checks.append(
                angle_upper(
                    "scattered_fraction",
                    np.max(r1, axis=0),
                    v["scattered_fraction_max"],
                    "first-order incoherent reflectivity r₁ (larger of h, v)",
                    _SRC_R1,
                )
            )
    if eps is not None and rough._mss_closed() is None:
        e = check_eps(eps)
        lossy = not is_pec(e) and bool(np.any(np.imag(np.asarray(e)) > 0))
        if lossy:
            from emscatter.solvers.spm.first_order import coherent_cutoff

            cut = coherent_cutoff(rough, k, user_cut)
            extra["coherent_depends_on_cutoff"] = True
            notes.append(
                f"spm2_cutoff: over this lossy medium the coherent reflectivity of an "
                f"exponential/power-law spectrum depends on how far the spectrum extends "
                f"(here k_max = {cut / k:.3g}k{'' if user_cut else ', the whole spectrum'}; "
                "TM at oblique incidence grows ~1e-3 per decade; pass k_max, the surface's "
                "inner scale; validation/spm2_cutoff)"
            )
            if solver_options.get("coherent") is True and ti is not None:
                sens = _cutoff_sensitivity(rough, k, e, ti, cut)
                extra["cutoff_sensitivity"] = sens
                notes.append(
                    f"spm2_cutoff: k_max/10 → k_max changes the coherent reflectivity by up to "
                    f"{float(np.max(sens)):.2g}"
                )
    return build_report(
        rough,
        k,
        checks,
        theta_i=ti,
        angle_checks=angle_checks,
        k_length=k * min(rough.length, rough.length_y),
        rms_slope=slope,
        slope_cutoff=k_cut,
        notes=notes,
        **extra,
    )


def _cutoff_sensitivity(rough, k, eps, theta_i, cut) -> np.ndarray:
    """``max_p |r_coh,p(k_max/10) − r_coh,p(k_max)|`` per angle (theta_i's shape)."""
    from emscatter.solvers.spm.first_order import coherent_reflectivity

    a = coherent_reflectivity(rough, eps, k, theta_i, k_max=cut / 10)
    b = coherent_reflectivity(rough, eps, k, theta_i, k_max=cut)
    return np.max(np.abs(a - b), axis=0)
