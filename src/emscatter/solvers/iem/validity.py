"""Validity of the IEM (:mod:`.model`): the limits in kσ, nominal rms slope and incidence
angle, with their sources, and the report :func:`check_validity` builds from them."""

from __future__ import annotations

import math
import sys

import numpy as np

from emscatter.conventions import check_angle, check_positive
from emscatter.fresnel import is_pec
from emscatter.solvers.kirchhoff.common import check_roughness
from emscatter.solvers.validity import angle_upper, build_report, check_solver_options, upper
from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation, PowerLawCorrelation

__all__ = ["OPTIONS", "VALIDITY", "check_validity", "nominal_rms_slope"]

#: Options :func:`bistatic` takes (for :func:`check_validity` and ``select.check_options``).
OPTIONS = (
    "coherent", "rtol", "max_terms", "fresnel", "complementary", "first_order", "reciprocal",
    "shadowing", "rms_slope", "crosspol", "crosspol_order", "threads",
)  # fmt: skip
_SRC_KS = "Fung, Li & Chen 1992; Wu & Chen 2004 (AIEM vs 3-D MoM up to kσ ≈ 3)"
_SRC_SLOPE = "single scattering; Ulaby & Long 2014 I2EM codes (σ/ℓ ≤ 0.25)"
_SRC_ANGLE = "validation/iem/energy_scan.csv (emissivity in [0, 1])"

#: Validity limits (see :func:`check_validity`).
VALIDITY = {
    "k_sigma_max": 3.0,
    "rms_slope_max": 0.4,
    "theta_i_max_deg": 70.0,
    "theta_i_max_conductor_deg": 45.0,
}


def nominal_rms_slope(roughness) -> tuple[float, float]:
    """The model's per-direction rms slopes ``(s_x, s_y)`` [-] for shadowing (module docstring):
    Gaussian ``√2 σ/ℓ``, exponential ``σ/ℓ``, power law ``√(2H) σ/ℓ``; a measured map
    (:mod:`emscatter.surfaces.measured`) its own finite-difference rms slopes."""
    rough = check_roughness(roughness)
    # a MeasuredRoughness exists only once its module is loaded: no import here (the surfaces
    # package brings scipy.optimize, ~0.2–0.8 s of a first IEM call; issue 22)
    measured = sys.modules.get("emscatter.surfaces.measured")
    if measured is not None and isinstance(rough, measured.MeasuredRoughness):
        sx, sy = rough.mean_square_slope()
        return math.sqrt(sx), math.sqrt(sy if rough.dimension == 2 else sx)
    if isinstance(rough, GaussianCorrelation):
        c = math.sqrt(2.0)
    elif isinstance(rough, ExponentialCorrelation):
        c = 1.0
    elif isinstance(rough, PowerLawCorrelation):
        c = math.sqrt(2.0 * rough.hurst)
    else:  # pragma: no cover - check_roughness + log_nfold reject others first
        raise TypeError(f"no nominal slope for {type(rough).__name__}")
    return c * rough.sigma / rough.length, c * rough.sigma / rough.length_y


def _conductor(eps) -> bool:
    """PEC, a metal (Re ε < 0) or a good conductor (|ε| ≥ 100) — any element of an array."""
    if eps is None:
        return False
    if isinstance(eps, str):
        return is_pec(eps)
    e = np.asarray(eps, dtype=complex)
    return bool(np.any((e.real < 0) | (np.abs(e) >= 100.0)))


def check_validity(roughness, k: float, *, eps=None, theta_i=None, **solver_options) -> dict:
    """Validity report (BOARD interface 1, built by :mod:`.validity`): ``valid``, ``reasons``
    (check, value, limit, factor), ``checks``, ``details``, ``excess`` (max log(value/limit));
    with ``theta_i`` [rad] also ``angle_valid``, ``angle_excess`` (theta_i's shape) and
    ``angle_reasons``. ``solver_options``: the names :func:`bistatic` takes (:data:`OPTIONS`;
    the limits do not depend on them), anything else is an error naming the method.

    Limits (:data:`VALIDITY`), from the literature and this module's own checks:

    * ``kσ ≤ 3`` — Fung et al. 1992/1994 and SMRT's ``iem_fung92``; Wu & Chen (2004) find AIEM
      within ~1 dB of 3-D MoM backscatter up to kσ ≈ 3. (The 1992 model's extra condition
      ``kσ·kℓ < 1.2√|ε|`` comes from dropping the Green's-function phase; AIEM keeps it.)
    * nominal rms slope ``≤ 0.4`` (√2σ/ℓ Gaussian, σ/ℓ exponential; Ulaby & Long's I2EM codes
      restrict σ/ℓ ≤ 0.25, i.e. 0.35 for a Gaussian): single scattering, no multiple bounces.
    * ``θi ≤ 70°`` (dielectrics) or ``≤ 45°`` (PEC, metals, ``|ε| ≥ 100``, when ``eps`` is
      given): energy. validation/iem/energy_scan.csv — over kσ = 0.2–3, kℓ = 2–20 inside the
      two limits above, the emissivity of ε = 3 and 15 + 2i stays in [0, 1] up to 70°, while a
      perfect conductor reflects more than it receives (e < −0.02, v) from 50–60° on.
    """
    check_solver_options("iem", solver_options, OPTIONS)
    rough = check_roughness(roughness)
    k = check_positive("k", k, unit="rad/m")
    v = VALIDITY
    slope = max(nominal_rms_slope(rough))
    checks = [
        upper("k_sigma", k * rough.sigma, v["k_sigma_max"], "kσ", _SRC_KS),
        upper("rms_slope", slope, v["rms_slope_max"], "nominal rms slope", _SRC_SLOPE),
    ]
    angle_checks, ti = [], None
    if theta_i is not None:
        ti = check_angle("theta_i", theta_i)
        cond = _conductor(eps)
        lim = v["theta_i_max_conductor_deg"] if cond else v["theta_i_max_deg"]
        what = "θi [deg] (conductor: energy)" if cond else "θi [deg] (energy, shadowing)"
        angle_checks.append(angle_upper("theta_i", np.degrees(ti), lim, what, _SRC_ANGLE))
    return build_report(rough, k, checks, theta_i=ti, angle_checks=angle_checks,
                        rms_slope=slope)  # fmt: skip
