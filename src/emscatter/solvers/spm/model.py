"""Small-perturbation method (SPM, Rice 1951): the solver — first-order bistatic σ⁰ (all
four polarizations) and the second-order coherent reflectivity, with its validity report.

The equations (first-order amplitudes, the second-order coherent kernel, their sources) are
in :mod:`.first_order` and :mod:`.second_order`; the validity limits in :mod:`.validity`;
the compiled σ⁰ kernel in :mod:`.kernel` (reached through :mod:`.compiled`).
"""

from __future__ import annotations

import numpy as np

from emscatter.conventions import check_angle, check_positive
from emscatter.scattering import Scattering
from emscatter.solvers.spm.first_order import (  # noqa: F401 (the tests reach the numerics here)
    _check_order,
    _check_roughness,
    _coherent,
    _f2_factors,
    _f_factors,
    _fresnel_power,
    _sigma0_first,
    coherent_cutoff,
    coherent_reflectivity,
    sigma0_broadcast,
)
from emscatter.solvers.spm.second_order import (  # noqa: F401 (the tests reach the kernel here)
    _eps_array,
    _first_order_amplitudes,
    _root,
    _second_order_R,
    _spectral_scales,
)
from emscatter.solvers.spm.validity import OPTIONS, VALIDITY, check_validity  # noqa: F401
from emscatter.spectra import Roughness

__all__ = [
    "VALIDITY",
    "OPTIONS",
    "bistatic",
    "coherent_reflectivity",
    "coherent_cutoff",
    "check_validity",
]


def bistatic(
    roughness: Roughness,
    eps,
    k: float,
    theta_i,
    theta_s,
    phi_s,
    phi_i=0.0,
    *,
    order: int = 2,
    coherent: bool = True,
    k_max: float | None = None,
) -> Scattering:
    """First-order SPM bistatic scattering coefficients σ⁰ (all four polarizations) and the
    coherent reflectivity to ``order``.

    Parameters
    ----------
    roughness : :class:`~emscatter.spectra.Roughness`; ``dimension=2`` (surface, 3-D problem)
        or ``dimension=1`` (profile, 2-D problem: hh and vv only, ``phi_s ∈ {phi_i,
        phi_i + π}``).
    eps : complex relative permittivity (``Im ε ≥ 0``; array broadcasting with the angles)
        or ``"pec"``.
    k : free-space wavenumber [rad/m].
    theta_i, theta_s : incidence / scattering angles [rad] in ``[0, π/2]``.
    phi_s, phi_i : azimuths [rad] (finite; only ``phi_s − phi_i`` and ``phi_i`` enter).
    order : coherent part: 0/1 → Fresnel ``|R|²``; 2 → with the second-order correction.
    k_max : spectral cutoff [rad/m] of the second-order coherent term (default: the whole
        spectrum; :func:`coherent_reflectivity`). σ⁰ does not depend
        on it (first order uses the spectrum at the Bragg wavenumber only).
    coherent : ``False`` skips the coherent part (its quadrature dominates the cost when only
        σ⁰ is needed, e.g. inside the hemispherical integral); ``coherent`` is then a
        read-only NaN array and ``info["coherent"]`` says so.

    Returns
    -------
    :class:`~emscatter.scattering.Scattering` with ``sigma0`` (2, 2, *shape) — per unit area
    (2-D) or length (1-D), eq. in the module docstring — and ``coherent`` (2, *shape).
    """
    rough = _check_roughness(roughness)
    k = check_positive("k", k, unit="rad/m")
    order = _check_order(order)
    coherent_cutoff(rough, k, k_max)  # checks k_max here, in the order of the messages
    eps_c = _eps_array(eps)
    ti = check_angle("theta_i", theta_i)
    ts = check_angle("theta_s", theta_s)
    return _bistatic_checked(
        rough, eps_c, k, ti, ts, phi_s, phi_i, order=order, coherent=coherent, k_max=k_max,
        validity=True,
    )  # fmt: skip


def _bistatic_checked(
    rough, eps, k, ti, ts, phi_s, phi_i=0.0, *, order=2, coherent=True, k_max=None, validity=False,
    own_phi=False,
) -> Scattering:  # fmt: skip
    """:func:`bistatic` for inputs checked as it checks them (``bistatic.checked``, the public
    API's entry): ``rough`` a Roughness, ``k`` a float > 0, ``eps`` "pec" or complex, ``ti``
    and ``ts`` float arrays in [0, π/2]. ``info["validity"]`` is None unless ``validity``
    (the API supplies its own report)."""
    order = _check_order(order)
    cut = coherent_cutoff(rough, k, k_max)
    band_check = getattr(rough, "warn_band", None)  # a measured map: does it resolve 2k?
    band = band_check(k, stacklevel=4) if band_check is not None else None
    sig, (ti_b, ts_b, ps_b, pi_b, eps_b), coh = sigma0_broadcast(
        rough, eps, k, ti, ts, phi_s, phi_i, fresnel=order < 2, own_phi=own_phi
    )
    shape = ti_b.shape
    if not coherent:
        # a read-only NaN placeholder (no fill, no copy: the API discards it)
        coh, clipped = np.broadcast_to(np.nan, (2, *shape)), 0
    elif order < 2:
        clipped = 0
    else:
        coh, clipped = _coherent(rough, eps_b, k, ti_b, shape, 16, 16, pi_b, cut)
    coh = np.broadcast_to(coh, (2, *shape))
    info = {
        "validity": check_validity(rough, k, k_max=k_max) if validity else None,
        "order": order,
        "coherent_clipped": clipped,
        "coherent_cutoff": cut if order == 2 and coherent else None,
    }
    if band is not None:
        info["band"] = band
    if not coherent:
        info["coherent"] = "not computed (coherent=False)"
    return Scattering(
        sigma0=sig,
        coherent=np.array(coh) if coherent else coh,
        method="spm",
        theta_i=ti_b,
        theta_s=ts_b,
        phi_s=ps_b,
        phi_i=pi_b,
        k=k,
        dimension=rough.dimension,
        info=info,
    )


def _api_checked(*args, **options) -> Scattering:
    """The public API's entry (``bistatic.checked``): :func:`_bistatic_checked` with the
    API's own checked φ copies, range-checked but not copied again (``own_phi``)."""
    return _bistatic_checked(*args, **options, own_phi=True)


bistatic.checked = _api_checked  # the API's entry for inputs it has checked
