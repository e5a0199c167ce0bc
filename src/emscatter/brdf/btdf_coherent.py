"""The coherent (delta) part of the PO, SPM and IEM BTDF tables, and what decides it.

:func:`.btdf_table.build_btdf_table` stores beside the diffuse ``f_t`` of these methods the
coherent transmissivity ``coherent[w, i]`` [-] (mean of h and v), the delta lobe at the
refracted direction ``sinθt = sinθi/η`` that the table's ``values`` do not hold:

* ``"po"``: the Kirchhoff mean field ``T_F exp(−σ²(k₁cosθi − k₂cosθt)²)``
  (:func:`emscatter.solvers.kirchhoff.transmission.po.coherent_transmissivity`);
* ``"spm"``: second-order SPM's mean field, ``R + T = 1`` to ``O((kσ)²)`` with the SPM
  reflection (:func:`emscatter.solvers.spm.transmission.coherent_transmissivity`);
* ``"iem"``: the Kirchhoff mean field with SPM's second-order correction
  (:func:`emscatter.solvers.iem.transmission.coherent_transmissivity`, its ``first_order``).

This module holds what decides that part per wavelength: the checked surface and series
options of these methods (:func:`po_surface`), the method's validity at the θi nodes with the
table's ``out_of_range`` policy (:func:`validity_record`: one warning naming the failing
nodes, or a ValueError), the coherent row itself (:func:`coherent_row`) and the metadata that
names the solver and its coherent part (:func:`coherent_metadata`).
"""

from __future__ import annotations

import warnings

import numpy as np

from ..solvers.iem import transmission as tiem
from ..solvers.kirchhoff.transmission import po as tpo
from ..solvers.spm import transmission as tspm
from .btdf import checked_surface

__all__ = ["po_surface", "validity_record", "coherent_row", "coherent_metadata"]

_PO_OPTIONS = ("rtol", "max_terms")


def po_surface(surface, options, method="po"):
    """The roughness and the series options of a PO (SPM: none) BTDF table (clear errors)."""
    allowed = {"po": _PO_OPTIONS, "iem": (*_PO_OPTIONS, "first_order")}.get(method, ())
    unknown = set(options) - set(allowed)
    if unknown:
        raise ValueError(
            f"unknown option(s) {sorted(unknown)} for the {method.upper()} BTDF; allowed: "
            f"{list(allowed)}"
        )
    fo = options.get("first_order", "spm")
    if isinstance(fo, bool) or fo not in tiem.FIRST_ORDER:
        raise ValueError(f"first_order must be one of {tiem.FIRST_ORDER}, got {fo!r}")
    return checked_surface(surface, {}, "a BTDF table"), dict(options)


def validity_record(rough, eps, k, theta, lam, out_of_range, method="po") -> dict:
    """PO's (SPM's, IEM's) validity at the θi nodes ``theta`` [rad] for one wavelength ``lam``
    [m] (``k`` [rad/m]): the ``out_of_range`` policy (one warning naming the failing nodes, or
    a ValueError) and a record for the metadata."""
    from ..solvers.iem import validity as iem_validity
    from ..solvers.kirchhoff import po as rpo
    from ..solvers.spm import validity as spm_validity

    check = {"po": rpo.check_validity, "iem": iem_validity.check_validity}.get(
        method, spm_validity.check_validity
    )
    rep_ = check(rough, k, eps=eps, theta_i=theta)
    bad = ~np.broadcast_to(np.asarray(rep_.get("angle_valid", True), dtype=bool), theta.shape)
    if not rep_["valid"] and out_of_range != "ignore":
        nodes = np.degrees(theta[bad])
        where = f"θi {nodes.min():.3g}–{nodes.max():.3g}° ({bad.sum()} nodes)" if bad.any() else ""
        theory = {"po": "Kirchhoff approximation's", "iem": "IEM's"}.get(
            method, "small-perturbation method's"
        )
        msg = (
            f"build_btdf_table(method={method!r}) at λ = {lam:.6g} m is outside the {theory} "
            f"validity {where}: {'; '.join(rep_['reasons'])}"
        )
        if out_of_range == "raise":
            raise ValueError(msg + " (out_of_range='warn' builds it anyway)")
        warnings.warn(msg + " (out_of_range='raise' stops, 'ignore' only records)", stacklevel=4)
    return {
        "wavelength": lam,
        "valid": bool(rep_["valid"]),
        "reasons": list(rep_["reasons"]),
        "theta_i_out_of_range_deg": np.degrees(theta[bad]).tolist(),
    }


def coherent_row(method, rough, eps, k, theta, lam, out_of_range, options) -> tuple:
    """``(record, coherent)`` of one wavelength ``lam`` [m] (``k = 2π/λ`` [rad/m], ``eps`` the
    real ε): the validity record of :func:`validity_record` (its policy applied first), then
    the coherent transmissivity at the θi nodes ``theta`` [rad], mean of h and v [-]
    (module docstring; ``options``: the checked ones of :func:`po_surface`)."""
    record = validity_record(rough, eps, k, theta, lam, out_of_range, method)
    if method == "po":
        coh = tpo.coherent_transmissivity(rough, eps, k, theta)
    elif method == "spm":
        coh = tspm.coherent_transmissivity(rough, eps, k, theta)
    else:
        opts = {"first_order": options.get("first_order", "spm")}
        coh = tiem.coherent_transmissivity(rough, eps, k, theta, **opts)
    return record, coh.mean(axis=0)


def coherent_metadata(method, options, per_wavelength) -> dict:
    """The table metadata naming the ``method``'s solver, source and coherent part, with the
    validity records ``per_wavelength`` (PO, SPM, IEM; SPM has no shadowing)."""
    if method == "po":
        return {
            "solver": "kirchhoff-po-transmission",
            "source": "Kirchhoff approximation, local Fresnel transmission at the "
            "stationary-phase facet (emscatter.solvers.kirchhoff.transmission.po)",
            "shadowing": None,
            "coherent": "coherent transmissivity T_F exp(-sigma^2 (k1 cos ti - k2 cos tt)^2) "
            "(delta lobe at the refracted direction, not in values)",
            "per_wavelength": per_wavelength,
        }
    if method == "spm":
        return {
            "solver": "spm-transmission",
            "source": "first-order small-perturbation transmission (Rice 1951; Johnson, JOSA A "
            "16, 1999), coherent part to second order (emscatter.solvers.spm.transmission)",
            "shadowing": None,
            "coherent": "coherent transmissivity to second order in k sigma (delta lobe at the "
            "refracted direction, not in values)",
            "per_wavelength": per_wavelength,
        }
    return {
        "solver": "iem-transmission",
        "source": "IEM Kirchhoff series with the first-order SPM term, no complementary field "
        "(emscatter.solvers.iem.transmission)",
        "shadowing": None,
        "first_order": options.get("first_order", "spm"),
        "coherent": "Kirchhoff mean field with the second-order SPM correction (delta lobe at "
        "the refracted direction, not in values)",
        "per_wavelength": per_wavelength,
    }
