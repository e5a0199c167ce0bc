"""Physical optics on a height map itself: the Kirchhoff (tangent-plane) field of one
realization, by FFT, at the grating orders of the map taken as one period.

The map ``h(x, y)`` (a :class:`~emscatter.surfaces.heightmap.HeightMap`, spacing ``Δx, Δy``,
size ``Lx × Ly``) is one period of a periodic surface. A plane wave ``k_i`` then scatters only
into the grating (Floquet) orders ``k_s⊥ = k_i⊥ + (2πm/Lx, 2πn/Ly)``; those with
``|k_s⊥| < k`` propagate, at ``sinθs cosφs = sinθi cosφi + mλ/Lx`` (and the same along y).
In the Kirchhoff approximation with the stationary-phase polarization factors of
:mod:`emscatter.solvers.kirchhoff.po` (``F_pq`` at the local specular angle, factored out of
the integral — Tsang, Kong & Ding 2001 vol. III ch. 2; Beckmann & Spizzichino 1963 ch. 4 for
periodic surfaces), the fraction of the incident power carried by order ``(m, n)`` is

    η_pq(m, n) = |q|⁴ / (4 k² q_z² cosθi cosθs) · |F_pq|² · |c_mn(q_z)|²,
    c_mn(q_z) = (1/LxLy) ∫_cell e^{−i q_z h(r)} e^{−i q⊥·r} d²r,     q = k_s − k_i,

(flat surface: ``c = 1`` at the specular order and ``η = |R|²``). It is the statistical PO of
:mod:`.po` before the ensemble average: the σ⁰ equivalent of an order,
``σ⁰ = η k² LxLy cosθi cosθs / π = |q|⁴ |F_pq|² LxLy |c|² / (4π q_z²)``, averages over
realizations to ``|q|⁴/(4π q_z²) |F|² ∫ e^{iq⊥·r} e^{−q_z²σ²(1−ρ)} d²r`` (tested against
:func:`.po.bistatic` within 0.3 dB over the lobe).

Numerics. ``c_mn`` is the DFT (rectangle rule) of ``e^{−i q_z h}`` — one FFT would give every
order for one ``q_z``, but ``q_z = k(cosθi + cosθs)`` differs per order. The Jacobi–Anger
expansion in ``t = (q_z − q̄)/δ ∈ [−1, 1]`` (``q̄ = k(cosθi + ½)``, ``δ = k/2``, the range of
the propagating orders) separates the two::

    e^{−i q_z h} = e^{−i q̄ h} Σ_{j≥0} ε_j (−i)^j J_j(δ h) T_j(t)      (ε_0 = 1, ε_j = 2)

so ``c_mn = Σ_j ε_j (−i)^j T_j(t_mn) FFT[e^{−i q̄ h} J_j(δ h)]_mn``: one FFT per term, the
terms stopping where ``|J_j(δ max|h|)| < 1e-14`` (``j ≈ δ max|h| + 10``; ``h`` centred on its
range). Exact up to that truncation for the sampled map; the sampling itself must resolve
``e^{−i q_z h}``: the power of its spectrum in the outer tenth of the FFT band is reported
(``info["aliased_fraction"]``) and a warning is given above 1e-3.

A map that is not periodic (a measured one) can be tapered by a Gaussian footprint
``W = exp(−|r − r₀|²/g²)`` (``footprint=g`` [m], centred): ``c`` is then the DFT of
``W e^{−i q_z h}`` over ``√(LxLy ∫W²)`` and the orders sample the σ⁰ of the illuminated patch
(speckle) on the FFT's grid of directions; ``∫W² = πg²/2`` is the illuminated area.

Energy: ``Σ_orders Σ_p η_pq`` is the reflectance per incident polarization (``reflectance``);
a perfect conductor gives 1 − O(slope²) (Kirchhoff has no multiple scattering, shadowing or
evanescent power); above ``1 + 1e-3`` a :class:`MapEnergyWarning` names the excess, never
silently.
"""

from __future__ import annotations

import math
import numbers
import warnings
from dataclasses import dataclass, field

import numpy as np
from scipy import special

from emscatter.conventions import check_angle, check_finite, check_positive
from emscatter.fresnel import check_eps
from emscatter.solvers.kirchhoff.common import fresnel_factors, geometry
from emscatter.surfaces.heightmap import HeightMap

__all__ = ["po_map", "MapOrders", "MapEnergyWarning", "ENERGY_TOL", "ALIAS_TOL"]

#: Reflectance above ``1 + ENERGY_TOL`` warns (:class:`MapEnergyWarning`).
ENERGY_TOL = 1e-3
#: Spectral power of ``e^{−i q_z h}`` in the outer tenth of the FFT band above which the map is
#: too coarse for its own PO integral (a warning).
ALIAS_TOL = 1e-3
_J_TOL = 1e-14


class MapEnergyWarning(UserWarning):
    """Deterministic PO on a map returned more power than came in (Kirchhoff's error)."""


@dataclass(frozen=True, eq=False)
class MapOrders:
    """The propagating grating orders of one map and one incidence.

    Attributes
    ----------
    order : ``(M, 2)`` ints ``(m, n)``: ``k_s⊥ = k_i⊥ + (2πm/Lx, 2πn/Ly)``.
    theta_s, phi_s : ``(M,)`` scattering directions [rad].
    efficiency : ``(2, 2, M)`` fraction of the incident power per order, ``[pol_s, pol_i]``.
    sigma0 : ``(2, 2, M)`` the σ⁰ equivalent of each order ``η k² LxLy cosθi cosθs / π`` [-].
    reflectance : ``(2,)`` ``Σ_orders Σ_pol_s η`` per incident polarization (h, v) [-].
    specular : index of the ``(0, 0)`` order.
    theta_i, phi_i, k : the incidence [rad] and the wavenumber [rad/m].
    info : terms of the expansion, ``aliased_fraction``, footprint, the map's description.
    """

    order: np.ndarray
    theta_s: np.ndarray
    phi_s: np.ndarray
    efficiency: np.ndarray
    sigma0: np.ndarray
    reflectance: np.ndarray
    specular: int
    theta_i: float
    phi_i: float
    k: float
    info: dict = field(default_factory=dict)

    def select(self, m=None, n=None) -> np.ndarray:
        """Indices of the orders with the given ``m`` and/or ``n`` (sorted by the other)."""
        keep = np.ones(self.order.shape[0], dtype=bool)
        if m is not None:
            keep &= self.order[:, 0] == m
        if n is not None:
            keep &= self.order[:, 1] == n
        idx = np.nonzero(keep)[0]
        return idx[np.argsort(self.order[idx, 1 if m is not None else 0])]


def _check_map(hm) -> tuple[np.ndarray, float, float]:
    if not isinstance(hm, HeightMap):
        raise TypeError(
            "height_map must be an emscatter.surfaces.HeightMap (emscatter.surfaces.height_map "
            f"or read_height_map), got {type(hm).__name__}"
        )
    if not bool(np.all(hm.mask)):
        raise ValueError(
            f"height_map {hm.source!r} has {int((~hm.mask).sum())} masked holes: the PO integral "
            "over the map needs every height; fill them (or crop the map) first"
        )
    if hm.dimension == 1:  # a profile: a map invariant along y (one row)
        return hm.heights[None, :], hm.spacing[0], hm.spacing[0]
    return hm.heights, hm.spacing[1], hm.spacing[0]


def _footprint(footprint, shape, dx, dy) -> np.ndarray | None:
    if footprint is None:
        return None
    g = check_positive("footprint", footprint, unit="m")
    ny, nx = shape
    lx, ly = nx * dx, ny * dy if ny > 1 else math.inf
    if 6 * g > min(lx, ly):
        raise ValueError(
            f"footprint must be at most 1/6 of the map's side (the taper ≤ e^-9 at its edges): "
            f"got {g:g} m for a map of {lx:g} × {ly:g} m"
        )
    x = (np.arange(nx) - nx / 2) * dx
    y = (np.arange(ny) - ny / 2) * dy
    return np.exp(-(x[None, :] ** 2 + y[:, None] ** 2) / g**2)


def po_map(
    height_map: HeightMap,
    eps,
    k: float,
    theta_i: float,
    phi_i: float = 0.0,
    *,
    footprint: float | None = None,
    max_terms: int = 4000,
) -> MapOrders:
    """Deterministic physical optics of one height map at its grating orders (module docstring).

    Parameters
    ----------
    height_map : :class:`~emscatter.surfaces.heightmap.HeightMap` (a map ``(ny, nx)``, or a
        profile taken as invariant along y), every height measured (no masked holes); its
        spacing must resolve every propagating order: ``π/Δ ≥ k(1 + sinθi)``.
    eps : relative permittivity (complex, ``Im ε ≥ 0``) or ``"pec"``.
    k : free-space wavenumber [rad/m].
    theta_i, phi_i : one incidence direction [rad] (scalars: the orders depend on it).
    footprint : ``None`` (the map is one period) or the radius ``g`` [m] of a centred Gaussian
        illumination ``exp(−r²/g²)``, at most 1/6 of the map's side.
    max_terms : cap on the Jacobi–Anger terms (one FFT each, ``≈ k max|h|/2 + 10``).

    Returns
    -------
    :class:`MapOrders` (efficiencies ``[pol_s, pol_i]``, their σ⁰ equivalent, reflectance).
    """
    h, dx, dy = _check_map(height_map)
    eps = check_eps(eps)
    if np.ndim(eps) != 0:
        raise ValueError(f"eps must be one permittivity or 'pec' here, got shape {np.shape(eps)}")
    k = check_positive("k", k, unit="rad/m")
    for name, val in (("theta_i", theta_i), ("phi_i", phi_i)):
        if np.ndim(val) != 0:
            raise ValueError(f"{name} must be one angle [rad] (the orders depend on it)")
    ti = float(check_angle("theta_i", theta_i))
    if not ti < math.pi / 2:
        raise ValueError(f"theta_i must be below π/2 (grazing has no illuminated map), got {ti}")
    pi_ = float(check_finite("phi_i", phi_i))
    if isinstance(max_terms, bool) or not isinstance(max_terms, numbers.Integral) or max_terms < 1:
        raise ValueError(f"max_terms must be a positive integer, got {max_terms!r}")
    ny, nx = h.shape
    si, ci = math.sin(ti), math.cos(ti)
    need = k * (1 + si)
    dmax = dx if ny == 1 else max(dx, dy)
    if math.pi / dmax < need:
        raise ValueError(
            f"the spacing of height_map {height_map.source!r} ({dmax:g} m) is too coarse for "
            f"its propagating orders: π/Δ = {math.pi / dmax:.4g} rad/m must be ≥ k(1 + sinθi) = "
            f"{need:.4g} rad/m (Δ ≤ {math.pi / need:.4g} m)"
        )
    lx, ly = nx * dx, ny * dy
    win = _footprint(footprint, h.shape, dx, dy)
    # the propagating orders
    kix, kiy = k * si * math.cos(pi_), k * si * math.sin(pi_)
    gx = 2 * math.pi / lx
    mx = np.arange(math.ceil((-k - kix) / gx), math.floor((k - kix) / gx) + 1)
    if ny == 1:
        my = np.zeros(1, dtype=np.int64)
    else:
        gy = 2 * math.pi / ly
        my = np.arange(math.ceil((-k - kiy) / gy), math.floor((k - kiy) / gy) + 1)
    MY, MX = np.meshgrid(my, mx, indexing="ij")
    ksx = kix + MX * gx
    ksy = kiy + MY * (0.0 if ny == 1 else 2 * math.pi / ly)
    kt2 = (ksx**2 + ksy**2) / k**2
    prop = kt2 < 1.0 - 1e-12
    MX, MY, ksx, ksy, kt2 = (a[prop] for a in (MX, MY, ksx, ksy, kt2))
    cs = np.sqrt(1.0 - kt2)
    ts = np.arccos(cs)
    ps = np.arctan2(ksy, ksx)
    qz = k * (ci + cs)
    # Jacobi–Anger: e^{−i q_z h} = e^{−i q̄ h} Σ ε_j (−i)^j J_j(δ h) T_j(t)
    h0 = h - 0.5 * (h.max() + h.min())
    qbar, half = k * (ci + 0.5), 0.5 * k
    b = half * h0
    bmax = float(np.abs(b).max())
    n_terms = int(bmax + 10 * bmax ** (1 / 3) + 12)
    while n_terms > 1 and abs(special.jv(n_terms, bmax)) < _J_TOL:
        n_terms -= 1
    n_terms += 1
    if n_terms > max_terms:
        raise ValueError(
            f"height_map {height_map.source!r} needs {n_terms} expansion terms (k max|h|/2 = "
            f"{bmax:.4g}) over max_terms={max_terms}: raise max_terms (one FFT each)"
        )
    t = (qz - qbar) / half
    base = np.exp(-1j * qbar * h0)
    if win is not None:
        base = base * win
        norm = math.sqrt(float(np.sum(win**2)) * h.size)  # √(LxLy ∫W²)/(ΔxΔy)
    else:
        norm = float(h.size)
    iy, ix = np.mod(MY, ny), np.mod(MX, nx)
    c = np.zeros(t.shape, dtype=complex)
    t_prev, t_cur = np.ones_like(t), t.copy()
    for j in range(n_terms):
        tj = np.ones_like(t) if j == 0 else t_cur
        spec = np.fft.fft2(base * special.jv(j, b))
        c += (1.0 if j == 0 else 2.0) * (-1j) ** j * tj * spec[iy, ix]
        if j >= 1:
            t_prev, t_cur = t_cur, 2 * t * t_cur - t_prev
    c /= norm
    # aliasing: e^{−i q_z h} at the largest q_z, its power in the outer tenth of the band
    f_hi = np.fft.fft2(np.exp(-1j * k * (ci + 1.0) * h0) * (1.0 if win is None else win))
    p = np.abs(f_hi) ** 2
    fy = np.abs(np.fft.fftfreq(ny))[:, None]
    fx = np.abs(np.fft.fftfreq(nx))[None, :]
    outer = (fx > 0.45) | ((fy > 0.45) & (ny > 1))
    aliased = float(p[np.broadcast_to(outer, p.shape)].sum() / p.sum())
    if aliased > ALIAS_TOL:
        warnings.warn(
            f"height_map {height_map.source!r}: {aliased:.2g} of the spectrum of e^(-i q_z h) "
            f"lies in the outer tenth of the FFT band (tolerance {ALIAS_TOL:g}): the spacing "
            "is too coarse for this k and these slopes; the orders' powers are aliased",
            RuntimeWarning,
            stacklevel=2,
        )
    # polarization factors of po.py at each order
    g = geometry(ti, ts, ps, pi_, eps, 2)
    loc = g.chunk(signed_azimuth=True)
    scale = loc.q2**2 / (4.0 * loc.qz**2 * ci * cs) * np.abs(c) ** 2
    eff = fresnel_factors(loc, 2, scale)
    sigma0 = eff * (k * k * lx * ly * ci * cs / math.pi)
    refl = eff.sum(axis=(0, 2))
    if not np.all(np.isfinite(eff)):
        raise FloatingPointError("deterministic PO produced non-finite efficiencies")
    order = np.stack([MX, MY], axis=1).astype(np.int64)
    spec_idx = np.nonzero((order[:, 0] == 0) & (order[:, 1] == 0))[0]
    info = {
        "terms": n_terms,
        "aliased_fraction": aliased,
        "footprint": None if footprint is None else float(footprint),
        "height_map": height_map.describe(),
        "polarization_factors": "local specular (stationary phase)",
    }
    if np.any(refl > 1 + ENERGY_TOL):
        warnings.warn(
            f"deterministic PO on height_map {height_map.source!r} reflects {refl.max():.4f} of "
            f"the incident power (> 1 + {ENERGY_TOL:g}): the Kirchhoff approximation is outside "
            "its range here (slopes, grazing angles)",
            MapEnergyWarning,
            stacklevel=2,
        )
    return MapOrders(
        order=order,
        theta_s=ts,
        phi_s=ps,
        efficiency=eff,
        sigma0=sigma0,
        reflectance=refl,
        specular=int(spec_idx[0]) if spec_idx.size else -1,
        theta_i=ti,
        phi_i=pi_,
        k=k,
        info=info,
    )
