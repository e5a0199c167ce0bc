"""Importance sampling of a tabulated BRDF: a marginal/conditional distribution of half-vectors.

For each incident node (θi, and φi for anisotropic tables) an n × n grid of cells covers the
half-vector hemisphere: rows split ``φh − φi`` (``φh`` for anisotropic tables) uniformly over
``[−π, π)``, columns split ``θh`` at ``(c/n)² · π/2`` (the ``u_θ = √(2θh/π)`` spacing of
Mitsuba's ``measured``, fine near the mirror direction). Each cell's probability is the
reflected power ``f_r cosθo dωo`` through it (midpoint rule, ``dωo = 4 (wi·h) dωh``); a sample
draws the row from the marginal distribution and the column from the row's conditional
distribution, each by Walker's alias method (O(1): one uniform variate picks a bin and, from its
leftover bits, whether to take the bin or its alias), then a half-vector uniformly in the cell's
solid angle (uniform in φh and cosθh). The density is thus piecewise constant in half-vector
solid angle, ``p(ωo) = P_cell / (Ω_cell · 4 wi·h)``, exact for the samples drawn and finite at
the mirror direction. Between incident nodes the distribution is the mixture of the
neighbouring nodes' (weights linear in θi, φi), sampled by picking one node with those weights.

Cells whose reflected direction is below the horizon take the value of the nearest cell whose
direction is above it, and the ring of cells around the support of ``f_r`` half its neighbours'
density, so no direction where ``f_r > 0`` has zero density (samples that land below the
horizon are discarded by the BSDF with weight 0 and pdf 0) while compact lobes waste no samples.

``dωo = 4 (wi·h) dωh``: the half-vector Jacobian (Walter et al. 2007, eq. 14).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..brdf.rgl_warp import direction, fill_from_neighbours, u2phi, u2theta

__all__ = ["HalfVectorSampler", "alias_table", "build_sampler", "cell_edges"]


def alias_table(weights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Walker alias tables ``(prob, alias)`` for every distribution along the last axis.

    ``weights`` (..., N) ≥ 0 with positive sums. Bin ``i`` is drawn with probability 1/N and
    kept with probability ``prob[i]``, else replaced by ``alias[i]``; built by pairing the
    poorest with the richest unfinished bin (vectorized over the leading axes).
    """
    w = np.asarray(weights, dtype=float)
    lead, n = w.shape[:-1], w.shape[-1]
    w = w.reshape(-1, n)
    total = w.sum(axis=1, keepdims=True)
    if np.any(~(total > 0)):
        raise ValueError("alias_table: a distribution has zero total weight")
    mass = w * (n / total)
    rows = np.arange(w.shape[0])
    prob = np.ones_like(mass)
    alias = np.tile(np.arange(n, dtype=np.uint32), (w.shape[0], 1))
    done = np.zeros(mass.shape, dtype=bool)
    for _ in range(n - 1):  # each step finalizes one bin of every distribution
        poor = np.argmin(np.where(done, np.inf, mass), axis=1)
        rich = np.argmax(np.where(done, -np.inf, mass), axis=1)
        pm = mass[rows, poor]
        prob[rows, poor] = pm
        alias[rows, poor] = rich
        mass[rows, rich] -= 1.0 - pm
        done[rows, poor] = True
    prob = np.clip(np.where(done, prob, 1.0), 0.0, 1.0)
    return prob.reshape(*lead, n), alias.reshape(*lead, n)


def cell_edges(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Column edges in θh [rad] (n+1) and row edges in φh − φi [rad] (n+1)."""
    e = np.arange(n + 1) / n
    return u2theta(e), u2phi(e)


@dataclass(frozen=True)
class HalfVectorSampler:
    """Alias tables and densities, one slice per incident node (float32 / uint32).

    ``density[..., r, c]``: probability per steradian of half-vector in cell (row r, column c),
    each slice summing to 1 over the hemisphere. Slices are indexed ``[i_theta]`` (isotropic)
    or ``[i_phi, i_theta]``.
    """

    theta_i: np.ndarray  # [rad] uniform nodes
    phi_i: np.ndarray | None  # [rad] uniform periodic nodes on [0, 2π), anisotropic only
    density: np.ndarray
    marginal_prob: np.ndarray
    marginal_alias: np.ndarray
    conditional_prob: np.ndarray
    conditional_alias: np.ndarray

    @property
    def resolution(self) -> int:
        return self.density.shape[-1]

    def sample(self, slice_index: int, ux, uy):
        """numpy reference of the plugin's sampling in one slice (flat index): returns the
        half-vector ``(θh, φh − φi)`` [rad] and its density [1/sr] for uniform variates."""
        n = self.resolution
        ux, uy = np.asarray(ux, float), np.asarray(uy, float)
        mp = self.marginal_prob.reshape(-1, n)[slice_index]
        ma = self.marginal_alias.reshape(-1, n)[slice_index]
        row, vy = _alias_pick(
            np.broadcast_to(mp, (uy.size, n)), np.broadcast_to(ma, (uy.size, n)), uy
        )
        cp = self.conditional_prob.reshape(-1, n, n)[slice_index, row]
        ca = self.conditional_alias.reshape(-1, n, n)[slice_index, row]
        col, vx = _alias_pick(cp, ca, ux)
        th_e, ph_e = cell_edges(n)
        cos_t = np.cos(th_e[col]) + (np.cos(th_e[col + 1]) - np.cos(th_e[col])) * vx
        phi = ph_e[row] + (ph_e[row + 1] - ph_e[row]) * vy
        dens = self.density.reshape(-1, n, n)[slice_index, row, col]
        return np.arccos(np.clip(cos_t, -1, 1)), phi, dens


def _neighbour_sum(a: np.ndarray) -> np.ndarray:
    """Sum over the 4-neighbours of each cell of ``a`` (..., rows, cols): rows (φ) periodic,
    columns (θ) not."""
    out = np.roll(a, 1, axis=-2) + np.roll(a, -1, axis=-2)
    out[..., 1:] += a[..., :-1]
    out[..., :-1] += a[..., 1:]
    return out


def _alias_pick(prob: np.ndarray, alias: np.ndarray, u: np.ndarray):
    """Bin and leftover uniform variate for each lane (``prob``, ``alias``: (P, n))."""
    n = prob.shape[-1]
    x = u * n
    idx = np.minimum(x.astype(int), n - 1)
    frac = x - idx
    p = np.take_along_axis(prob, idx[:, None], 1)[:, 0].astype(float)
    a = np.take_along_axis(alias, idx[:, None], 1)[:, 0]
    keep = frac < p
    with np.errstate(divide="ignore", invalid="ignore"):
        v = np.where(keep, frac / p, (frac - p) / (1 - p))
    return np.where(keep, idx, a).astype(int), np.clip(np.nan_to_num(v), 0.0, 1.0)


def build_sampler(source, weights: np.ndarray, theta_i, phi_i, n: int) -> HalfVectorSampler:
    """Tables for ``source`` (a BrdfFunction) at incident nodes ``theta_i`` (× ``phi_i``) [rad].

    ``weights`` (n_source_channels,): how channels combine into the sampled quantity.
    """
    th_e, ph_e = cell_edges(n)
    th_h = 0.5 * (th_e[:-1] + th_e[1:])[None, :]  # columns: θh
    ph_h = 0.5 * (ph_e[:-1] + ph_e[1:])[:, None]  # rows: φh (− φi)
    solid = (np.cos(th_e[:-1]) - np.cos(th_e[1:]))[None, :] * np.diff(ph_e)[:, None]  # Ω_cell
    h = direction(th_h, ph_h)  # (n, n, 3)
    if phi_i is None:
        wi = direction(np.asarray(theta_i), 0.0)  # (n_ti, 3), φi = 0: relative φh = absolute
    else:
        wi = direction(np.asarray(theta_i)[None, :], np.asarray(phi_i)[:, None])  # (n_pi, n_ti, 3)
    lead = wi.shape[:-1]
    wi_b = wi.reshape(lead + (1, 1, 3))
    h_b = np.broadcast_to(h, lead + h.shape)
    dot = np.sum(wi_b * h_b, -1)
    wo = 2 * dot[..., None] * h_b - wi_b
    ok = (wo[..., 2] > 1e-9) & (dot > 0)
    f = np.zeros(ok.shape)
    if ok.any():
        f[ok] = source.evaluate(np.broadcast_to(wi_b, wo.shape)[ok], wo[ok]) @ weights
    power = np.where(ok, np.maximum(f, 0.0) * wo[..., 2] * 4 * dot * solid, 0.0)  # f cos dωo
    dens = (power / solid).reshape(-1, n, n)  # per steradian of h
    ok = ok.reshape(-1, n, n)
    # f may be > 0 in part of a cell whose centre has f = 0 (compact lobes: the seed's uniform
    # distribution): give the ring around the support half its neighbours' mean density
    support = dens > 0
    total, count = _neighbour_sum(np.where(support, dens, 0.0)), _neighbour_sum(support * 1.0)
    ring = ok & ~support & (count > 0)
    dens = np.where(ring, 0.5 * total / np.maximum(count, 1), dens)
    valid = ok & (dens > 0)
    empty = ~valid.any(axis=(1, 2))
    dens[empty] = 1.0  # nothing reflected at this incidence: uniform over the hemisphere
    valid[empty] = True
    # cells whose centre reflects below the horizon: the nearest cell with a direction above it
    geometry = ok | empty[:, None, None]
    dens = fill_from_neighbours(dens[:, None], geometry)[:, 0].reshape(lead + (n, n))
    prob = dens * solid
    dens = dens / prob.sum(axis=(-2, -1), keepdims=True)  # Σ density · Ω_cell = 1
    prob = dens * solid
    rows = prob.sum(axis=-1)
    mprob, malias = alias_table(rows)
    # a row without power is never drawn; its conditional table just has to exist
    cprob, calias = alias_table(np.where(rows[..., None] > 0, prob, 1.0))
    return HalfVectorSampler(
        theta_i=np.asarray(theta_i, dtype=float),
        phi_i=None if phi_i is None else np.asarray(phi_i, dtype=float),
        density=dens.astype(np.float32),
        marginal_prob=mprob.astype(np.float32),
        marginal_alias=malias,
        conditional_prob=cprob.astype(np.float32),
        conditional_alias=calias,
    )
