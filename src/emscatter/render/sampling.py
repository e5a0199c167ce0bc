"""Importance sampling of a tabulated BRDF: a marginal/conditional distribution of half-vectors.

For each incident node (θi, and φi for anisotropic tables) the reflected power
``f_r cosθo |dωo/du|`` is tabulated at the cell centres of an n × n grid on the unit square of
half-vectors ``u = (√(2θh/π), (φh − φi)/2π + ½)`` (``φh`` absolute for anisotropic tables;
rows u_φ, columns u_θ). The density is piecewise constant on the cells; a sample draws the row
from the marginal distribution and the column from the row's conditional distribution, each by
Walker's alias method (O(1): one uniform variate picks a bin and, from its leftover bits,
whether to take the bin or its alias; what is left positions the sample inside the cell), so
the density returned is exact for the samples drawn. Between incident nodes the distribution
is the mixture of the neighbouring nodes' (weights linear in θi, φi), sampled by picking one
node at random with those weights.

Cells whose reflected direction is below the horizon take the value of the nearest valid
cell, so no direction where ``f_r > 0`` has zero density (samples that land below the horizon
are discarded by the BSDF with weight 0).

``|dωo/du|``: ``θh = u_θ² π/2``, ``φh = 2π u_φ − π`` ⇒ ``dωh = 2π² u_θ sinθh du``, and
``dωo = 4 (wi·h) dωh`` (the half-vector Jacobian, Walter et al. 2007 eq. 14).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..brdf.rgl_warp import direction, fill_from_neighbours, u2phi, u2theta

__all__ = ["HalfVectorSampler", "alias_table", "build_sampler", "half_vector_jacobian"]


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


def half_vector_jacobian(u_theta, theta_h, wi_dot_h):
    """``|dωo/du|`` [sr] of the half-vector square (module docstring)."""
    return 8 * math.pi**2 * u_theta * np.sin(theta_h) * np.maximum(wi_dot_h, 0.0)


@dataclass(frozen=True)
class HalfVectorSampler:
    """Alias tables and densities, one slice per incident node (float32 / uint32).

    ``density[..., r, c]``: density w.r.t. u on cell (row r = u_φ, column c = u_θ), each slice
    integrating to 1. Slices are indexed ``[i_theta]`` (isotropic) or ``[i_phi, i_theta]``.
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
        """numpy reference of the plugin's sampling in one slice (flat index): returns
        ``(u_θ, u_φ, density)`` for uniform variates ``ux``, ``uy`` (arrays)."""
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
        dens = self.density.reshape(-1, n, n)[slice_index, row, col]
        return (col + vx) / n, (row + vy) / n, dens


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
    u = (np.arange(n) + 0.5) / n
    th_h = u2theta(u)[None, :]  # columns u_θ
    ph_h = u2phi(u)[:, None]  # rows u_φ
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
    dens = np.where(
        ok, np.maximum(f, 0.0) * wo[..., 2] * half_vector_jacobian(u[None, :], th_h, dot), 0.0
    )
    valid = ok & (dens > 0)
    flat = dens.reshape(-1, 1, n, n)
    vflat = valid.reshape(-1, n, n)
    empty = ~vflat.any(axis=(1, 2))
    flat[empty] = 1.0  # nothing reflected at this incidence: uniform over the square
    vflat[empty] = True
    dens = fill_from_neighbours(flat, vflat).reshape(lead + (n, n))
    dens = dens / dens.mean(axis=(-2, -1), keepdims=True)  # ∫ density du = 1
    mprob, malias = alias_table(dens.sum(axis=-1))
    cprob, calias = alias_table(dens)
    return HalfVectorSampler(
        theta_i=np.asarray(theta_i, dtype=float),
        phi_i=None if phi_i is None else np.asarray(phi_i, dtype=float),
        density=dens.astype(np.float32),
        marginal_prob=mprob.astype(np.float32),
        marginal_alias=malias,
        conditional_prob=cprob.astype(np.float32),
        conditional_alias=calias,
    )
