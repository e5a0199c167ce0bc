"""The R + T + A budget of a BRDF table beside its BTDF table (:mod:`.btdf_table`).

:func:`energy_budget` reports per incidence node ``R`` (the BRDF table's albedo), ``T`` (the
BTDF's transmitted fraction, :meth:`~.btdf_table.BtdfTable.albedo`, interpolated to the BRDF's
θi nodes) and the deficit ``1 − R − T − A``; for GO on a lossless dielectric it is single
scattering's missing multiple scattering (``A = 0``), a few percent towards grazing, never
negative. :func:`cap_reflection` caps the reflection at ``1 − T − A`` with the reciprocal
remedy of :mod:`.energy` (a PO or IEM reflection table beside a GO transmission can exceed that
budget); :func:`cap_energy` also scales the transmission where the coherent reflection alone
leaves less than ``T`` (PO glass, m = 0.1, 88°: R + T = 1.27 → 1, ending at the smooth
interface's R 0.82 / T 0.18). ``btdf`` arguments are :class:`~.btdf_table.BtdfTable`
(which re-exports these functions)."""

from __future__ import annotations

import numpy as np

from .energy import apply_energy_remedy
from .table import BrdfTable

__all__ = ["energy_budget", "cap_reflection", "cap_energy"]


def _transmission_at(brdf: BrdfTable, btdf) -> np.ndarray:
    """``T`` (``(n_wl, n_ti)``) of ``btdf`` at ``brdf``'s wavelengths and θi nodes."""
    if not brdf.isotropic:
        raise ValueError("the R + T budget needs an isotropic BRDF table (θi, θo, Δφ)")
    if brdf.wavelengths.shape != btdf.wavelengths.shape or not np.allclose(
        brdf.wavelengths, btdf.wavelengths, rtol=1e-12
    ):
        raise ValueError(
            "the BRDF and BTDF tables must have the same wavelengths, got "
            f"{brdf.wavelengths.tolist()} and {btdf.wavelengths.tolist()} m"
        )
    t = btdf.albedo()
    if np.array_equal(brdf.theta_i, btdf.theta_i):
        return t
    return np.stack([np.interp(brdf.theta_i, btdf.theta_i, row) for row in t])


def energy_budget(brdf: BrdfTable, btdf, absorption=0.0) -> dict:
    """Per wavelength and θi node of ``brdf``: ``R`` (its albedo, coherent included), ``T``
    (``btdf``'s, interpolated in θi), ``A`` (given, default 0: a lossless dielectric) and the
    ``deficit = 1 − R − T − A`` (for single-scattering GO: its missing multiple scattering;
    negative where the tables hand out more energy than arrives). Arrays ``(n_wl, n_ti)``."""
    r = brdf.albedo().total
    t = _transmission_at(brdf, btdf)
    a = np.broadcast_to(np.asarray(absorption, dtype=float), r.shape)
    return {
        "theta_i_deg": np.degrees(brdf.theta_i),
        "wavelengths": brdf.wavelengths,
        "R": r,
        "T": t,
        "A": np.array(a),
        "deficit": 1.0 - r - t - a,
    }


def cap_reflection(brdf: BrdfTable, btdf, absorption=None) -> BrdfTable:
    """``brdf`` with its reflection capped at ``1 − T − A`` per incidence node by the
    reciprocal remedy of :mod:`.energy` (``T`` from ``btdf``); rows already within the
    budget are unchanged, ``metadata["energy"]`` records where and by how much it acted."""
    try:
        return apply_energy_remedy(
            brdf, transmission=_transmission_at(brdf, btdf), absorption=absorption
        )
    except ValueError as err:
        if "coherent reflectivity exceeds" not in str(err) and "exceed the energy" not in str(err):
            raise
        raise ValueError(
            f"{err}: the BTDF transmits more than the BRDF's coherent lobe leaves room for; "
            "use cap_energy(brdf, btdf), which scales the transmission there too"
        ) from None


def cap_energy(brdf: BrdfTable, btdf, absorption=None) -> tuple:
    """``(brdf, btdf)`` with ``R + T + A ≤ 1`` at every incidence node, whatever the two
    approximations hand out: first, where the coherent reflection alone leaves less than
    ``T`` (``R_coh + T + A > 1``: e.g. PO's coherent lobe beside GO's transmission at
    grazing), the BTDF's rows are scaled to ``1 − A − R_coh`` (linear in θi between the BRDF's
    nodes); then the incoherent reflection is capped at ``1 − T − A`` by the reciprocal
    remedy (:func:`cap_reflection`). Both tables record what was done in
    ``metadata["energy"]``; rows already within the budget are unchanged."""
    t = _transmission_at(brdf, btdf)
    a = _as_budget("absorption", absorption, t.shape)
    room = np.maximum(1.0 - a - brdf.coherent - 1e-12, 0.0)
    scale = np.where(t > room, room / np.maximum(t, 1e-300), 1.0)  # (n_wl, n_ti of brdf)
    meta = dict(btdf.metadata)
    if np.any(scale < 1):
        per_node = np.stack([np.interp(btdf.theta_i, brdf.theta_i, row) for row in scale])
        per_node = np.minimum(per_node, 1.0)
        values = np.asarray(btdf.values, dtype=float) * per_node[:, :, None, None]
        meta["energy"] = {
            "remedy": "rows scaled so that R_coh + T + A <= 1",
            "remedy_applied": True,
            "scale": per_node.tolist(),
            "min_scale": float(per_node.min()),
        }
        coh = None if btdf.coherent is None else btdf.coherent * per_node  # PO's delta lobe
        btdf = btdf.replace(values=values.astype(btdf.values.dtype), metadata=meta, coherent=coh)
    else:
        meta["energy"] = {"remedy": "none needed", "remedy_applied": False}
        btdf = btdf.replace(metadata=meta)
    return cap_reflection(brdf, btdf, absorption=absorption), btdf


def _as_budget(name, value, shape):
    if value is None:
        return np.zeros(shape)
    out = np.broadcast_to(np.asarray(value, dtype=float), shape)
    if not np.all(np.isfinite(out)) or np.any(out < 0) or np.any(out > 1):
        raise ValueError(f"{name} must be fractions of the incident power in [0, 1], got {value!r}")
    return out
