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
"""

from __future__ import annotations

import numpy as np

__all__ = ["reciprocal_energy_scale", "apply_energy_remedy", "REMEDY"]

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
    if np.any(c > limit + 2 * _MARGIN):
        raise ValueError(f"coherent reflectivity exceeds {limit} on its own: {c.max()!r}")
    budget = np.maximum(limit - c, 0.0)  # coherent ≈ limit: no room left for the incoherent
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


def apply_energy_remedy(table, *, limit: float = 1.0):
    """The table with the remedy applied where needed and ``metadata["energy"]`` filled:
    ``max_albedo_before`` / ``max_albedo_after`` per wavelength, ``theta_i_deg_exceeding``
    (nodes where the albedo exceeded ``limit``), ``min_scale`` and the full ``scale`` per
    wavelength and direction node, ``remedy_applied``."""
    if not table.symmetric_grid:
        raise ValueError("the reciprocal energy remedy needs equal incident/outgoing axes")
    w = table.outgoing_weights()
    n_wl = table.wavelengths.size
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
        alb = kern.sum(axis=1) + c
        before.append(float(alb.max()))
        exceed = alb > limit
        if table.isotropic:
            exceeding.append(np.degrees(table.theta_i[exceed]).round(4).tolist())
        else:
            ti, pi_ = np.meshgrid(table.theta_i, table.phi_i, indexing="ij")
            exceeding.append(
                np.degrees(np.stack([ti.ravel()[exceed], pi_.ravel()[exceed]], -1))
                .round(4)
                .tolist()
            )
        s, _ = reciprocal_energy_scale(kern, c, limit - _MARGIN)
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
        "max_albedo_before": before,
        "max_albedo_after": after,
        "theta_i_deg_exceeding": exceeding,
        "min_scale": [float(s.min()) for s in scales],
        "scale": [s.tolist() for s in scales],
    }
    return table.replace(values=values, polarized=pol, metadata=meta)
