"""Energy balance of a table: detect directional albedo > 1 and the one remedy.

The approximations (GO, PO, SPM) can reflect more than they receive near grazing (the
negative emissivities seen at 85–89°): GO and PO lack multiple scattering and their
shadowing is approximate, first-order SPM is energy-consistent only to ``O((kσ)²)``.
A renderer must never get that energy.

Remedy — a reciprocal, separable attenuation
--------------------------------------------
Each node value is multiplied by ``s(ωi) s(ωo)`` with one factor ``s ∈ (0, 1]`` per
*direction* node (θ for isotropic tables, (θ, φ) for anisotropic ones)::

    f'(ωi, ωo) = s(ωi) f(ωi, ωo) s(ωo),    s = 1 wherever the albedo is already ≤ 1.

This keeps reciprocity: swapping ``ωi`` and ``ωo`` swaps the two factors of a symmetric
product, and the nodes of a symmetric grid stay symmetric (so does the interpolant). A
per-θi rescale ``f' = s(θi) f`` alone would not: ``f'(ωo, ωi) = s(θo) f ≠ s(θi) f``. The
form is the one microfacet theory itself uses for missing energy — a separable
masking–shadowing factor ``G1(ωi) G1(ωo)`` — so it acts where the excess comes from:
grazing directions, on both the incident and the outgoing side.

``s`` is found by a monotone fixed-point iteration on the exact albedo of the interpolated
table (:meth:`~.table.BrdfTable.outgoing_weights`): ``A_i = s_i Σ_o K_io s_o + R_coh,i`` with
``K_io = Σ W_o f_io``: ``s_i ← min(1, s_i √((1 − R_coh,i)/(A_i − R_coh,i)))`` (the square
root because the specular lobe of row ``i`` lies mostly on column ``i``; a capped symmetric
Sinkhorn scaling) until it settles, so every row that is reduced ends at albedo 1 and every
other keeps ``s = 1``; a final decrease-only pass guarantees ``A_i ≤ 1`` to rounding. The coherent
delta lobe is left as the solver gave it (it is ≤ 1 by construction). Where and by how much
the remedy acted is recorded in ``metadata["energy"]``.

Transmission and absorption. For a dielectric the reflection may not take the whole budget:
``apply_energy_remedy(table, transmission=T, absorption=A)`` caps the reflected albedo per
incidence node at ``limit − T − A`` (``R + T + A ≤ 1``), with ``T`` the transmitted fraction
(a :class:`~.btdf_table.BtdfTable`'s albedo, or the smooth Fresnel transmissivity) and ``A``
the absorbed one, instead of ``R ≤ 1`` alone (PO glass near grazing otherwise reflects up to 1
where the smooth interface reflects 0.88 and transmits the rest).
"""

from __future__ import annotations

import numpy as np

__all__ = ["reciprocal_energy_scale", "apply_energy_remedy", "record_albedo", "REMEDY"]

REMEDY = (
    "reciprocal separable attenuation f'(wi, wo) = s(wi) f(wi, wo) s(wo), s <= 1 per "
    "direction node, smallest reduction that makes every directional albedo <= 1"
)

_MAX_ITER = 500
_MARGIN = 1e-12  # target 1 − 1e-12 so that albedo sums in any order stay ≤ 1


def reciprocal_energy_scale(kernel: np.ndarray, coherent: np.ndarray, limit: float = 1.0):
    """``s`` (shape ``(n,)``) with ``s_i (K s)_i + c_i ≤ limit`` for all ``i``.

    ``kernel``: ``K[i, o]`` ≥ 0, the albedo contribution of outgoing node ``o`` to incident
    node ``i``; ``coherent``: ``c_i`` (must be ``≤ limit``). Returns ``(s, iterations)``.
    """
    k = np.asarray(kernel, dtype=float)
    c = np.asarray(coherent, dtype=float)
    over = c > np.asarray(limit, dtype=float) + 2 * _MARGIN
    if np.any(over):
        raise ValueError(
            f"coherent reflectivity exceeds the energy limit on its own: {c[over][0]!r} > "
            f"{np.broadcast_to(limit, c.shape)[over][0]!r} at incidence node "
            f"{int(np.flatnonzero(over)[0])}"
        )
    # coherent ≈ limit: no room left for the incoherent
    budget = np.maximum(np.asarray(limit, dtype=float) - c, 0.0)
    s = np.ones(k.shape[0])
    # 1) two-sided fixed point s_i ← min(1, s_i √(b_i / A_i)): rows that are reduced end at the
    #    limit, rows that are not keep s = 1 (a symmetric Sinkhorn scaling with a cap)
    for _ in range(_MAX_ITER):
        inc = s * (k @ s)
        ratio = budget / np.maximum(inc, 1e-300)
        new = np.minimum(1.0, s * np.sqrt(ratio))
        if np.max(np.abs(new - s)) < 1e-13:
            break
        s = new
    # 2) monotone guarantee: only decrease until every row is within the limit
    for it in range(_MAX_ITER):
        inc = s * (k @ s)
        over = inc > budget
        if not np.any(over):
            return s, it
        ratio = np.where(over, budget / np.where(over, inc, 1.0), 1.0)
        s = s * np.where(over, np.sqrt(ratio) * (1.0 - 1e-12), 1.0)
    raise RuntimeError(
        f"energy remedy did not converge in {_MAX_ITER} iterations "
        f"(largest albedo excess {float((inc - budget).max()):.3g})"
    )


def _per_node(name, value, shape):
    """``value`` (None → 0) as an array of ``shape`` (n_wl, n_ti[, n_pi]) in [0, 1], checked."""
    if value is None:
        return np.zeros(shape)
    a = np.asarray(value, dtype=float)
    try:
        a = np.broadcast_to(a, shape)
    except ValueError:
        raise ValueError(
            f"{name} must broadcast to (n_wl, n_theta_i[, n_phi_i]) = {shape}, got {a.shape}"
        ) from None
    if not np.all(np.isfinite(a)) or np.any(a < 0) or np.any(a > 1):
        bad = a[~(np.isfinite(a) & (a >= 0) & (a <= 1))].ravel()[0]
        raise ValueError(f"{name} must be fractions of the incident power in [0, 1], got {bad!r}")
    return a


def apply_energy_remedy(table, *, limit: float = 1.0, transmission=None, absorption=None):
    """The table with the remedy applied where needed and ``metadata["energy"]`` filled:
    ``max_albedo_before`` / ``max_albedo_after`` per wavelength, ``theta_i_deg_exceeding``
    (nodes where the albedo exceeded its limit), ``min_scale`` and the full ``scale`` per
    wavelength and direction node, ``remedy_applied``.

    ``transmission``, ``absorption``: fractions ``T``, ``A`` [-] of the incident power per
    wavelength and incidence node (anything broadcasting to ``(n_wl, n_ti)``, anisotropic
    ``(n_wl, n_ti, n_pi)``; None → 0): the reflected albedo is capped at ``limit − T − A``
    per node, so that ``R + T + A ≤ limit`` (module docstring)."""
    if not table.symmetric_grid:
        raise ValueError("the reciprocal energy remedy needs equal incident/outgoing axes")
    w = table.outgoing_weights()
    n_wl = table.wavelengths.size
    inc_shape = table.coherent.shape
    t_frac = _per_node("transmission", transmission, inc_shape)
    a_frac = _per_node("absorption", absorption, inc_shape)
    if np.any(t_frac + a_frac > limit):
        raise ValueError(
            f"transmission + absorption exceed the energy limit {limit}: up to "
            f"{float((t_frac + a_frac).max())!r} (nothing left for the reflection)"
        )
    budgets = limit - t_frac - a_frac
    values = np.array(table.values)
    pol = None if table.polarized is None else np.array(table.polarized)
    nd = w.size  # anisotropic: direction nodes θ × φ
    flat_w = w.reshape(-1)
    before, after, exceeding, scales = [], [], [], []
    applied = False
    for j in range(n_wl):
        if table.isotropic:  # K[i, o] = Σ_d W[o, d] f[i, o, d]
            kern = np.einsum("iod,od->io", values[j], w)
            c = table.coherent[j]
        else:
            f = values[j].reshape(nd, nd)
            kern = f * flat_w[None, :]
            c = table.coherent[j].reshape(-1)
        row_limit = budgets[j].reshape(-1)
        alb = kern.sum(axis=1) + c
        before.append(float(alb.max()))
        exceed = alb > row_limit
        if table.isotropic:
            exceeding.append(np.degrees(table.theta_i[exceed]).round(4).tolist())
        else:
            ti, pi_ = np.meshgrid(table.theta_i, table.phi_i, indexing="ij")
            exceeding.append(
                np.degrees(np.stack([ti.ravel()[exceed], pi_.ravel()[exceed]], -1))
                .round(4)
                .tolist()
            )
        s, _ = reciprocal_energy_scale(kern, c, np.maximum(row_limit - _MARGIN, 0.0))
        if np.any(s < 1):
            applied = True
            if table.isotropic:
                fac = s[:, None, None] * s[None, :, None]
            else:
                fac = (s[:, None] * s[None, :]).reshape(values.shape[1:])
            values[j] *= fac
            if pol is not None:
                pol[:, :, j] *= fac
            kern = kern * s[:, None] * s[None, :]
        after.append(float((kern.sum(axis=1) + c).max()))
        scales.append(s)
    meta = dict(table.metadata)
    meta["energy"] = {
        "remedy": REMEDY,
        "remedy_applied": applied,
        "limit": limit,
        "transmission_counted": transmission is not None,
        "absorption_counted": absorption is not None,
        "max_albedo_before": before,
        "max_albedo_after": after,
        "theta_i_deg_exceeding": exceeding,
        "min_scale": [float(s.min()) for s in scales],
        "scale": [s.tolist() for s in scales],
    }
    return table.replace(values=values, polarized=pol, metadata=meta)


def record_albedo(table, remedy: str):
    """``table`` with its albedo recorded in ``metadata["energy"]`` (``remedy`` names why no
    remedy was applied), the values unchanged."""
    alb = table.albedo().total
    table.metadata["energy"] = {
        "remedy": remedy,
        "remedy_applied": False,
        "max_albedo_before": alb.reshape(alb.shape[0], -1).max(axis=1).tolist(),
        "albedo_exceeds_one": bool(np.any(alb > 1)),
    }
    return table
