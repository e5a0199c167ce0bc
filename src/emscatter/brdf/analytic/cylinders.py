"""Poulin & Fournier 1990's anisotropic surface of parallel cylinders (SIGGRAPH '90, "A model
for anisotropic reflection"; seed §2.6.1, Fig. 2.13), single scattering with exact 2-D
shadowing and masking.

Geometry (renderer frame, normal ``+z``): cylinders of radius 1 with their axes along the
tangent ``+y``, spaced ``d`` apart (in radii) along ``x``, centres at height ``h`` [radii]
above the base plane, ``h ∈ [−1, 0]`` — the "positive cylinder" surface of the seed's
Fig. 2.13 (``h = 0`` half cylinders, ``h → −1`` the flat plane; ``h > 0`` overhangs and the
"negative" (groove) surface are not implemented). The exposed arc is ``|φ| ≤ φ_m``,
``cos φ_m = −h``, with normal ``(sin φ, 0, cos φ)``; between the arcs lies the flat base
(``d ≥ 2 sin φ_m``).

BRDF (the single-scattering height-field average that Poulin & Fournier evaluate by
integrating over the visible, lit part of a cross-section):

``f(wi, wo) = 1/(d cosθi cosθo) [∫_arc f_loc (n·wi)(n·wo) V dφ + ∫_base f_loc cosθi cosθo V dx]``

with ``V`` = 1 where the point sees both ``wi`` and ``wo`` past the neighbouring cylinders
(2-D ray–circle tests in the ``x–z`` projection) and the local BRDF
``f_loc = k_d/π + k_s (n_s+2)/(2π) max(0, R_n(wi)·wo)^{n_s}`` (a normalized Phong lobe about
the local mirror direction, as Poulin & Fournier's local Phong model). ``f`` is reciprocal
(every factor is symmetric), and its albedo is ≤ the local one (≤ ``k_s + k_d``): the lit,
visible elements project onto the macro surface without overlap, and light that would
reach a second bounce is dropped (single scattering, as in the paper).

Roughness (the seed: "aucune référence à la rugosité n'est faite explicitement"): the
profile's rms slope across the cylinders ``m_x² = ∫_arc tan²φ cosφ dφ / d
= 2 (ln(sec φ_m + tan φ_m) − sin φ_m)/d`` (:func:`poulin_fournier_rms_slope`), ``m_y = 0`` —
the anisotropic Beckmann ``(m_x, 0)`` of the seed's eq. 3.1 definition; it diverges for
``h → 0`` (vertical walls).
"""

from __future__ import annotations

import math

import numpy as np

from emscatter.brdf.analytic import _upper
from emscatter.brdf.grid import gauss_legendre
from emscatter.conventions import check_in_range, check_positive

__all__ = ["poulin_fournier", "poulin_fournier_rms_slope"]


def _geometry(d: float, h: float) -> tuple[float, float]:
    h = check_in_range("h", h, -1.0, 0.0, low_open=True, high_open=False)
    phi_m = math.acos(-h)
    d = check_positive("d", d)
    if d < 2 * math.sin(phi_m) - 1e-12:
        raise ValueError(
            f"d must be ≥ the cylinders' footprint 2 sin φ_m = {2 * math.sin(phi_m):.6g} "
            f"(radii) for h = {h:g}, got {d:g}"
        )
    return d, phi_m


def poulin_fournier_rms_slope(d: float, h: float) -> float:
    """rms slope ``m_x`` [-] of the cylinder profile across the axes (module docstring);
    ``inf`` for ``h = 0``."""
    d, phi_m = _geometry(d, h)
    if phi_m >= 0.5 * math.pi - 1e-12:
        return math.inf
    sec, tan = 1 / math.cos(phi_m), math.tan(phi_m)
    return math.sqrt(2 * (math.log(sec + tan) - math.sin(phi_m)) / d)


def _psi(w):
    """Angle ``ψ`` [rad] of ``w``'s projection on the ``x–z`` plane from ``+z`` (``+x``
    positive); 0 when ``w`` is along the axes (no shadow across the cylinders)."""
    ux, uz = w[..., 0], w[..., 2]
    return np.where(np.hypot(ux, uz) > 1e-12, np.arctan2(ux, uz), 0.0)


def _arc_interval(psi, d: float, h: float, phi_m: float):
    """``[lo, hi]`` of arc angles ``φ`` lit from (or visible toward) projected angle ``ψ``:
    facing (``|φ − ψ| < π/2``) and not shadowed by the neighbour at ``x = ±d``. For ``ψ ≥ 0``
    the ray from ``(sin φ, h + cos φ)`` meets the neighbour ``(d, h)`` iff
    ``sin(φ − ψ) > d cos ψ − 1`` (distance of the centre from the ray < 1), so
    ``hi = ψ + asin(min(1, d cos ψ − 1))``; ``ψ < 0`` by symmetry."""
    a = np.abs(psi)
    cut = np.arcsin(np.clip(d * np.cos(a) - 1.0, -1.0, 1.0))
    near, far = a - 0.5 * np.pi, a + cut  # in the frame where ψ ≥ 0
    lo = np.where(psi >= 0, near, -far)
    hi = np.where(psi >= 0, far, -near)
    return np.maximum(lo, -phi_m), np.minimum(hi, phi_m)


def _base_interval(psi, d: float, h: float, half: float):
    """``[lo, hi]`` of base abscissae ``x ∈ [sin φ_m, d − sin φ_m]`` lit from ``ψ``: for
    ``ψ ≥ 0`` the ray from ``(x, 0)`` meets the cylinder ``(d, h)`` above the base iff
    ``|h| cot ψ < d − x < (1 + h sin ψ)/cos ψ`` (centre within 1 of the ray, ahead of it);
    that range, when not empty, starts inside the cylinder's footprint, so the lit part is
    ``d − x ≥ (1 + h sin ψ)/cos ψ``."""
    a = np.abs(psi)
    with np.errstate(divide="ignore"):
        upper = (1.0 + h * np.sin(a)) / np.cos(a)
        lower = np.where(a > 0, -h * np.cos(a) / np.where(a > 0, np.sin(a), 1.0), np.inf)
    cut = np.where(lower < upper, np.maximum(upper, half), half)
    lo = np.where(psi >= 0, half, cut)
    hi = np.where(psi >= 0, d - cut, d - half)
    return lo, hi


def _mapped(lo, hi, x, w):
    """Gauss–Legendre nodes ``x`` ∈ [−1, 1] mapped on ``[lo, hi]`` per row (empty → 0)."""
    span = np.maximum(hi - lo, 0.0)[:, None]
    return lo[:, None] + 0.5 * (x[None, :] + 1.0) * span, 0.5 * w[None, :] * span


def poulin_fournier(
    wi,
    wo,
    d: float = 2.5,
    h: float = -0.3,
    *,
    n_s: float = 50.0,
    ks: float = 1.0,
    kd: float = 0.0,
    nodes: int = 64,
) -> np.ndarray:
    """Poulin–Fournier cylinders [1/sr] (module docstring): spacing ``d`` and centre height
    ``h ∈ (−1, 0]`` in cylinder radii, local Phong exponent ``n_s``, ``k_s + k_d ≤ 1``;
    ``nodes`` Gauss–Legendre nodes on the part of the arc both lit and visible (its ends
    from the shadow and masking lines in closed form, so the quadrature is smooth)."""
    d, phi_m = _geometry(d, h)
    n_s = check_positive("n_s", n_s)
    ks = check_in_range("ks", ks, 0.0, 1.0, low_open=False, high_open=False)
    kd = check_in_range("kd", kd, 0.0, 1.0, low_open=False, high_open=False)
    if ks + kd > 1.0 + 1e-12:
        raise ValueError(f"ks + kd must be ≤ 1 for energy conservation, got {ks + kd:g}")
    if int(nodes) < 4:
        raise ValueError(f"nodes must be ≥ 4, got {nodes!r}")
    wi, wo, up = _upper(wi, wo)
    shape = up.shape
    wi, wo = wi.reshape(-1, 3), wo.reshape(-1, 3)
    lobe_c = ks * (n_s + 2) / (2 * math.pi)

    cos_io = np.sum(wi * wo, axis=-1)[:, None]

    def local(nx, nz, ni, no):
        # R_n(wi)·wo = 2 (n·wi)(n·wo) − wi·wo
        rv = 2 * ni * no - cos_io
        return kd / math.pi + lobe_c * np.clip(rv, 0.0, 1.0) ** n_s

    x, w = gauss_legendre(int(nodes))
    pi_, po = _psi(wi), _psi(wo)
    # the arc, φ on the part both lit and visible (element length dφ, radius 1)
    lo_i, hi_i = _arc_interval(pi_, d, h, phi_m)
    lo_o, hi_o = _arc_interval(po, d, h, phi_m)
    phi, wphi = _mapped(np.maximum(lo_i, lo_o), np.minimum(hi_i, hi_o), x, w)
    nx, nz = np.sin(phi), np.cos(phi)
    ni = np.maximum(wi[:, :1] * nx + wi[:, 2:] * nz, 0.0)
    no = np.maximum(wo[:, :1] * nx + wo[:, 2:] * nz, 0.0)
    total = np.sum(local(nx, nz, ni, no) * ni * no * wphi, axis=1)
    # the base between x = sin φ_m and d − sin φ_m (normal +z)
    half = math.sin(phi_m)
    if d - 2 * half > 1e-12:
        lo_i, hi_i = _base_interval(pi_, d, h, half)
        lo_o, hi_o = _base_interval(po, d, h, half)
        _, wb = _mapped(np.maximum(lo_i, lo_o), np.minimum(hi_i, hi_o), x, w)
        ci, co = wi[:, 2], wo[:, 2]
        flat = local(0.0, 1.0, ci[:, None], co[:, None])[:, 0] * ci * co
        total = total + flat * np.sum(wb, axis=1)
    den = d * np.maximum(wi[:, 2] * wo[:, 2], 1e-300)
    return np.where(up.reshape(-1), total / den, 0.0).reshape(shape)
