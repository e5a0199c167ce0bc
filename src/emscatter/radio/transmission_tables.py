"""Tables of a rough wall's diffuse transmission for the radio material (NumPy, no Dr.Jit).

Built once per (material, frequency) from :func:`emscatter.radio.slab_diffuse.diffuse_transmission`
(its ``face=`` model, default ``"auto"``: GO where it holds, else SPM, PO or the IEM; radiative
transport inside the slab) on the incidence nodes of the material's
reflection tables (:mod:`emscatter.radio.tables`), for ``transmission="diffuse"``:

* ``lobe[θi, φ, μ, c]`` [1/sr] on a uniform grid in ``μ = |cosθo| ∈ [0, 1]`` and in the
  azimuth ``φ ∈ [0, π]`` from the plane of incidence (``φ = 0``: the transverse direction of
  propagation), channels ``c``: the diffusely transmitted power per unit solid angle for
  incident h and v (back hemisphere), and the internal diffuse light that leaves again through
  the front face for incident h and v (front hemisphere: the part of ``R_diff`` the front
  face's own σ⁰ lobe does not hold). The lobes are resampled from the Gauss nodes of
  ``slab_diffuse`` (linear in ``μ``, azimuthal Fourier modes in ``φ``, negatives clipped)
  and renormalized so that the bilinear interpolant the material evaluates integrates, over the
  hemisphere (``dΩ = dμ dφ``, both halves of the azimuth), to the powers below — exactly at each
  incidence node. The grid defaults to the reflection lobe's ``n_s × n_alpha``: the material
  stacks the transmitted lobe (:func:`transmitted_block`) and the reflection lobe plus the
  internal light (:func:`internal_on_lobe_grid`, renormalized to the lobe grid's quadrature) in
  one texture (:mod:`emscatter.radio.material_slice`).
* **energy** — the powers are ``slab_diffuse``'s ``T_diff`` and internal ``R_diff`` times
  ``scale = E_mat / E_slab`` per incidence and polarization: ``E_slab`` is the power that
  ``slab_diffuse`` lets into the slab (``T_diff + R_int + A``), ``E_mat = 1 − R_coh − T_coh −
  R_front`` the power the material's own coherent slab and front-face lobe leave for it (they
  come from the solver of the reflection tables, ``slab_diffuse``'s front face is its ``face``
  model). Then the material's ``R_coh + R_diff + T_coh + T_diff + A = 1`` per incidence
  (``A = scale · A_slab``), and ``scale`` (recorded) states how far the two front faces differ.

The depolarization: ``slab_diffuse`` carries the light inside unpolarized, so the material
splits both lobes equally between the two scattered polarizations (XPD 0 dB for that light).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..conventions import wavenumber
from .slab import slab_coefficients
from .slab_diffuse import diffuse_transmission
from .tables import _lobe_integral, lobe_directions

__all__ = [
    "TransmissionTables",
    "build_transmission_tables",
    "internal_on_lobe_grid",
    "transmitted_block",
    "DiffuseTransmissionWarning",
]


class DiffuseTransmissionWarning(UserWarning):
    """Diffuse transmission was asked for where a solver cannot carry it (Sionna's PathSolver)."""


@dataclass(frozen=True)
class TransmissionTables:
    """What :func:`build_transmission_tables` returns (module docstring); ``(2, n_theta)``
    arrays over ``(pol_i, θi)`` are fractions of the incident power."""

    theta_nodes: np.ndarray
    mu_nodes: np.ndarray
    phi_nodes: np.ndarray
    lobe: np.ndarray  # (n_theta, n_phi, n_mu, 4) [1/sr]: T_h, T_v, R_int,h, R_int,v
    t_diff: np.ndarray
    r_internal: np.ndarray
    absorbed: np.ndarray
    r_coh: np.ndarray
    t_coh: np.ndarray
    r_front: np.ndarray
    scale: np.ndarray
    valid: bool
    reasons: list
    seconds: float
    face: str = "go"  # slab_diffuse's face model (resolved from face="auto")

    @property
    def total(self) -> np.ndarray:
        """``R_coh + R_front + R_int + T_coh + T_diff + A`` per (pol_i, θi): 1 to rounding."""
        return (self.r_coh + self.r_front + self.r_internal + self.t_coh + self.t_diff
                + self.absorbed)  # fmt: skip

    def describe(self) -> str:
        i = int(np.argmin(np.abs(self.theta_nodes - math.radians(45.0))))
        return (
            f"diffuse transmission ({self.face.upper()} faces"
            f"{'' if self.valid else ', OUTSIDE validity'}): "
            f"T_diff(45°) = {self.t_diff[:, i].mean():.3g}, energy scale "
            f"{self.scale.min():.3f}…{self.scale.max():.3f}"
        )


def _hemisphere_integral(lobe, mu, phi):
    """``2 ∫₀^π ∫₀¹ lobe dμ dφ`` of the bilinear interpolant (trapezoid), over the last two
    axes ``(φ, μ)``."""
    return 2.0 * np.trapezoid(np.trapezoid(lobe, mu, axis=-1), phi, axis=-1)


def _on_grid(lobe_gauss, mu_gauss, mu):
    """``(2, nθ, n_mu_gauss, nφ)`` → ``(2, nθ, nφ, n_mu)``, linear in ``μ`` (ends held)."""
    x = np.moveaxis(lobe_gauss, 2, -1)  # (2, nθ, nφ, n_mu_gauss)
    flat = x.reshape(-1, x.shape[-1])
    out = np.stack([np.interp(mu, mu_gauss, row) for row in flat])
    return np.maximum(out.reshape(*x.shape[:-1], mu.size), 0.0)


def build_transmission_tables(
    surface,
    eps: complex,
    frequency: float,
    thickness: float,
    tables,
    *,
    out_of_range: str = "warn",
    n_quad: int = 48,
    n_modes: int = 16,
    n_mu: int | None = None,
    n_phi: int | None = None,
    face: str = "auto",
) -> TransmissionTables:
    """Diffuse-transmission tables of one rough wall at one frequency (module docstring).

    ``tables`` — the material's :class:`~emscatter.radio.tables.RadioTables` at this frequency
    (its incidence nodes, coherent reflection and front-face incoherent reflectivity);
    ``thickness`` [m] > 0; ``eps`` the wall's permittivity (``Im ε ≥ 0``); ``out_of_range`` as
    :func:`~emscatter.radio.slab_diffuse.diffuse_transmission` (GO's validity); ``n_quad`` its
    Gauss nodes (μ and φ), ``n_modes`` its azimuthal modes; ``n_mu``, ``n_phi`` the grid the
    material interpolates (default: the reflection lobe's ``n_s`` and ``n_alpha``, which the
    material needs: it stacks both lobes in one texture); ``face`` the slab faces' model
    (``"auto"``, ``"go"``, ``"spm"``, ``"po"``, ``"iem"``; ``slab_diffuse``'s ``face=``).
    """
    import time

    t0 = time.perf_counter()
    theta = np.asarray(tables.theta_nodes, dtype=float)
    b = diffuse_transmission(
        surface, eps, frequency, thickness, theta=theta, n_mu=n_quad, n_phi=n_quad,
        out_of_range=out_of_range, n_modes=n_modes, face=face,
    )  # fmt: skip
    mu = np.linspace(0.0, 1.0, tables.s_nodes.size if n_mu is None else n_mu)
    phi = np.linspace(0.0, math.pi, tables.alpha_nodes.size if n_phi is None else n_phi)
    lt = _on_grid(b.transmitted_lobe(phi), b.mu_nodes, mu)
    lr = _on_grid(b.internal_reflection_lobe(phi), b.mu_nodes, mu)
    r_int = b.r_lobe.sum(-1)
    # the material's coherent slab and front face (its own solver), on the same nodes
    c = np.cos(theta)
    front = np.stack([np.interp(c, tables.cos_nodes, tables.coherent[p].real)
                      + 1j * np.interp(c, tables.cos_nodes, tables.coherent[p].imag)
                      for p in (0, 1)])  # fmt: skip
    sigma = float(surface.sigma)
    rh, rv, th, tv = slab_coefficients(
        eps, c, wavenumber(frequency=frequency), thickness, sigma=sigma, front=front
    )
    r_coh = np.abs(np.stack([rh, rv])) ** 2
    t_coh = np.abs(np.stack([th, tv])) ** 2
    r_front = np.asarray(tables.incoherent, dtype=float)
    e_mat = np.maximum(1.0 - r_coh - t_coh - r_front, 0.0)
    e_slab = b.t_diff + r_int + b.absorbed
    scale = np.where(e_slab > 1e-15, e_mat / np.maximum(e_slab, 1e-300), 0.0)
    lobes = []
    for lobe, power in ((lt, b.t_diff), (lr, r_int)):
        integral = _hemisphere_integral(lobe, mu, phi)  # (2, nθ)
        norm = np.where(integral > 0, power * scale / np.where(integral > 0, integral, 1.0), 0.0)
        lobes.append(lobe * norm[..., None, None])
    lobe = np.stack([lobes[0][0], lobes[0][1], lobes[1][0], lobes[1][1]], axis=-1)
    if not np.all(np.isfinite(lobe)):
        raise ValueError("diffuse transmission tables produced NaN/inf (please report the inputs)")
    return TransmissionTables(
        theta_nodes=theta, mu_nodes=mu, phi_nodes=phi, lobe=lobe.astype(float),
        t_diff=b.t_diff * scale, r_internal=r_int * scale, absorbed=b.absorbed * scale,
        r_coh=r_coh, t_coh=t_coh, r_front=r_front, scale=scale, valid=b.valid,
        reasons=list(b.reasons), seconds=time.perf_counter() - t0, face=b.face,
    )  # fmt: skip


def zero_transmission_tables(theta_nodes) -> TransmissionTables:
    """All-zero tables (a material traced by Dr.Jit but used by no object)."""
    th = np.asarray(theta_nodes, dtype=float)
    z = np.zeros((2, th.size))
    mu = np.linspace(0.0, 1.0, 4)
    phi = np.linspace(0.0, math.pi, 4)
    return TransmissionTables(th, mu, phi, np.zeros((th.size, 4, 4, 4)), z, z, z, z, z, z,
                              np.ones_like(z), True, [], 0.0)  # fmt: skip


def _check_grid(tt: TransmissionTables, tables):
    if (tt.mu_nodes.size, tt.phi_nodes.size) != (tables.s_nodes.size, tables.alpha_nodes.size):
        raise ValueError(
            f"transmission tables on a {tt.mu_nodes.size} × {tt.phi_nodes.size} (μ, φ) grid; the "
            f"material stacks them with its {tables.s_nodes.size} × {tables.alpha_nodes.size} "
            "lobe: build them with n_mu = n_s, n_phi = n_alpha"
        )


def transmitted_block(tt: TransmissionTables, tables) -> np.ndarray:
    """The transmitted lobe as the material reads it: ``(n_theta, n_phi, n_mu, 4)`` [1/sr]
    with channels ``hh, hv, vh, vv`` = ``T_h/2, T_v/2, T_h/2, T_v/2`` (unpolarized light:
    half into each scattered polarization)."""
    _check_grid(tt, tables)
    th, tv = tt.lobe[..., 0], tt.lobe[..., 1]
    return 0.5 * np.stack([th, tv, th, tv], axis=-1)


def internal_on_lobe_grid(tt: TransmissionTables, tables) -> np.ndarray:
    """The internal light out of the front face on the reflection lobe's grid
    (:func:`emscatter.radio.tables.lobe_directions`), ``(n_theta, n_alpha, n_s, 4)`` [1/sr],
    channels ``hh, hv, vh, vv`` as :func:`transmitted_block`, bilinear in ``(φ, μ)`` and scaled
    so that the lobe grid's own quadrature gives ``r_internal``."""
    from scipy.interpolate import RegularGridInterpolator

    _check_grid(tt, tables)
    theta_s, phi_s = lobe_directions(tables.theta_nodes, tables.alpha_nodes, tables.s_nodes,
                                     tables.grading)  # fmt: skip
    mu = np.cos(theta_s)
    phi = np.abs(phi_s)
    out = np.empty((*theta_s.shape, 2))
    for i in range(theta_s.shape[0]):
        for p in (0, 1):
            f = RegularGridInterpolator((tt.phi_nodes, tt.mu_nodes), tt.lobe[i, :, :, 2 + p])
            out[i, ..., p] = f(np.stack([phi[i].ravel(), mu[i].ravel()], -1)).reshape(mu[i].shape)
    lobe = 0.5 * np.stack([out[..., 0], out[..., 1], out[..., 0], out[..., 1]], axis=-1)
    got = _lobe_integral(lobe, tables.theta_nodes, tables.alpha_nodes, tables.s_nodes,
                         tables.grading)  # fmt: skip
    norm = np.where(got > 0, tt.r_internal / np.where(got > 0, got, 1.0), 0.0)  # (2, n_theta)
    return lobe * np.stack([norm[0], norm[1], norm[0], norm[1]], axis=-1)[:, None, None, :]
