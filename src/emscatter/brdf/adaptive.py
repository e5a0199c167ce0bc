"""Grid resolution from a target interpolation error, measured against direct evaluation.

Start from a coarse grid; in each round evaluate the solver *directly* at the midpoints of
every θ interval (and of the interval between the last node and 90°) and of every φ
interval, compare with the table's multilinear interpolant there, and insert the midpoints
whose error exceeds ``tol``. Stop when a round inserts nothing (then every midpoint of the
final grid is within ``tol``) or at the node limits. θ is shared by θi and θo (so the grid
stays symmetric and the table reciprocal node by node): a θ midpoint is tested as θi against
all θo nodes (the θo side is the same numbers by reciprocity).

Error at a point, on ``g = f cosθi cosθo`` (∝ σ⁰: the power scattered per solid angle, what a
renderer's estimate weighs): ``|g_interp − g| / max(|g|, floor · g_peak(λ))`` — relative where
the lobe is significant, relative to ``floor`` (1 % by default) of the peak elsewhere — the
maximum over the other axes and the wavelengths. (Weighting by the cosines keeps the
refinement away from grazing pairs, where the specular lobe of ``f`` narrows in Δφ without
bound but carries no power.)
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from .table import BrdfTable

__all__ = ["refine_axes"]

HALF_PI = 0.5 * math.pi


def _table(values, theta, phi, anisotropic):
    kw = {"phi_i": phi, "phi_o": phi} if anisotropic else {"phi_d": phi}
    wl = np.arange(1, values.shape[0] + 1, dtype=float)  # placeholder wavelengths
    return BrdfTable(wavelengths=wl, theta_i=theta, theta_o=theta, values=values, **kw)


def _grid(direct, theta, phi, anisotropic):
    if anisotropic:
        ti, pi_, to, po = np.meshgrid(theta, phi, theta, phi, indexing="ij")
    else:
        ti, to, po = np.meshgrid(theta, theta, phi, indexing="ij")
        pi_ = np.zeros_like(ti)
    return ti, pi_, to, po, direct(ti, pi_, to, po)


def _error(table, direct, pts, peak, floor):
    ti, pi_, to, po = pts
    w = np.cos(ti) * np.cos(to)
    f = direct(ti, pi_, to, po) * w
    g = table.evaluate_angles(ti, pi_, to, po) * w
    den = np.maximum(np.abs(f), floor * peak.reshape((-1,) + (1,) * (f.ndim - 1)))
    err = np.abs(g - f) / den
    return err.reshape(err.shape[0], err.shape[1], -1).max(axis=(0, 2))  # per candidate


def _theta_candidates(theta):
    mids = 0.5 * (theta[:-1] + theta[1:])
    tail = theta[-1] + 0.5 * (HALF_PI - theta[-1])
    return np.append(mids, tail) if HALF_PI - theta[-1] > 1e-3 else mids


def _phi_candidates(phi, anisotropic):
    if anisotropic:
        return 0.5 * (phi + np.append(phi[1:], phi[0] + 2 * math.pi)) % (2 * math.pi)
    return 0.5 * (phi[:-1] + phi[1:])


def refine_axes(
    direct: Callable,
    theta: np.ndarray,
    phi: np.ndarray,
    *,
    anisotropic: bool,
    tol: float,
    floor: float = 1e-2,
    max_theta: int = 180,
    max_phi: int = 360,
    max_rounds: int = 10,
):
    """Refined ``(theta, phi, report)``; ``direct(θi, φi, θo, φo)`` [rad, renderer frame]
    returns unpolarized ``f_r`` with a leading wavelength axis. ``report`` holds ``tol``,
    ``floor``, ``rounds``, ``converged``, the final midpoint errors ``max_error_theta`` /
    ``max_error_phi`` and the node counts."""
    if not (isinstance(tol, int | float) and 0 < tol < 1):
        raise ValueError(f"tol must be a relative error in (0, 1), got {tol!r}")
    theta, phi = np.asarray(theta, float), np.asarray(phi, float)
    report = {"tol": float(tol), "floor": float(floor), "converged": False}
    for rounds in range(1, max_rounds + 1):
        ti, pi_, to, po, vals = _grid(direct, theta, phi, anisotropic)
        table = _table(vals, theta, phi, anisotropic)
        peak = (vals * np.cos(ti) * np.cos(to)).reshape(vals.shape[0], -1).max(axis=1)
        # θ midpoints as θi against every other node
        tc = _theta_candidates(theta)
        if anisotropic:
            pts = np.meshgrid(tc, phi, theta, phi, indexing="ij")
        else:
            a, b, c = np.meshgrid(tc, theta, phi, indexing="ij")
            pts = (a, np.zeros_like(a), b, c)
        err_t = _error(table, direct, pts, peak, floor)
        # φ midpoints (φo for anisotropic tables; φi is the same axis by reciprocity)
        pc = _phi_candidates(phi, anisotropic)
        if anisotropic:
            a, b, c, d = np.meshgrid(theta, phi, theta, pc, indexing="ij")
            pts = (a, b, c, d)
            err_p = _error(table, direct, tuple(np.moveaxis(x, 3, 0) for x in pts), peak, floor)
        else:
            a, b, c = np.meshgrid(theta, theta, pc, indexing="ij")
            pts = tuple(np.moveaxis(x, 2, 0) for x in (a, np.zeros_like(a), b, c))
            err_p = _error(table, direct, pts, peak, floor)
        report.update(
            rounds=rounds,
            max_error_theta=float(err_t.max(initial=0.0)),
            max_error_phi=float(err_p.max(initial=0.0)),
            n_theta=int(theta.size),
            n_phi=int(phi.size),
        )
        add_t = tc[err_t > tol]
        add_p = pc[err_p > tol]
        if add_t.size == 0 and add_p.size == 0:
            report["converged"] = True
            break
        grew = False
        room_t, room_p = max_theta - theta.size, max_phi - phi.size
        if add_t.size and room_t > 0:  # the worst first when the node limit is near
            theta = np.unique(np.append(theta, add_t[np.argsort(-err_t[err_t > tol])[:room_t]]))
            grew = True
        if add_p.size and room_p > 0:
            phi = np.unique(np.append(phi, add_p[np.argsort(-err_p[err_p > tol])[:room_p]]))
            grew = True
        if not grew:
            break
    return theta, phi, report
