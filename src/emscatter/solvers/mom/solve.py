"""One realization of the 1-D method of moments: assembly, solution, fields and powers.

The formulation and its sources are in :mod:`emscatter.solvers.mom.model`; the kernels in
:mod:`emscatter.solvers.mom.operators`, the incident and radiated fields in
:mod:`emscatter.solvers.mom.fields`.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from emscatter.conventions import check_angle, check_finite, check_polarization, check_positive
from emscatter.fresnel import check_eps, is_pec
from emscatter.solvers.mom.fields import (
    _far_field,
    _gauss_theta,
    _n_quad,
    incident_power,
    tapered_wave,
)
from emscatter.solvers.mom.operators import fill_operators, solve_fb, solve_lu

Solver = Literal["auto", "lu", "fb"]

#: Minimum points per wavelength (in the denser medium) accepted, and the level under which
#: a warning is issued. 10 is the usual default (Tsang et al. 2001 vol. II ch. 4).
MIN_PPW_ERROR = 4.0
MIN_PPW_WARN = 8.0
#: Above this many unknowns, ``solver="auto"`` uses forward–backward instead of LU.
AUTO_FB_UNKNOWNS = 256


class MomWarning(UserWarning):
    """The method of moments was asked for with a doubtful discretization or taper."""


# --------------------------------------------------------------------------- one realization


@dataclass(frozen=True)
class MomResult:
    """One surface realization solved by the method of moments.

    Attributes
    ----------
    x, heights : surface samples [m].
    polarization : ``"h"`` (TE) or ``"v"`` (TM).
    eps : ``"pec"`` or the relative permittivity.
    k, theta_i, taper_g : wavenumber [rad/m], incidence [rad], taper half-width [m].
    psi, dpsi : surface field ``ψ`` and ``u = √(1+f'²) ∂ψ/∂n`` on the grid (zeros where the
        boundary condition imposes them) [-], [1/m].
    theta_s : signed scattering angles [rad] (> 0 on the specular side).
    amplitude : far-field amplitude ``A(θs)`` [m^½], ``ψ_s ≈ A e^{ikr}/√r``.
    sigma : ``σ⁰(θs) = 2π cosθi |A|²/P_inc``, per unit length, this realization only
        (coherent and incoherent together) [-].
    incident_power : ``P_inc`` [m] (:func:`incident_power`).
    reflected : scattered power / incident power, integrated over the upper half-space [-].
    transmitted : power into medium 2 / incident power (``None`` for a perfect conductor):
        from the far field in medium 2 if lossless, else from the flux through the surface.
    absorbed_flux : power through the surface into medium 2 / incident power [-] (dielectric).
    reflection_coefficient : ``A(θi)/A_ref(θi)`` with ``A_ref`` the far field of the incident
        taper mirrored in ``z = 0``: the complex specular reflection coefficient of a flat
        surface (→ Fresnel; −1/+1 for a PEC in TE/TM) [-].
    solver, iterations, residual : ``"lu"``, ``"fb"`` or ``"lu-fallback"`` (FB did not
        converge), FB iterations, ``‖b − Zψ‖/‖b‖`` (``None`` for plain LU).
    """

    x: np.ndarray
    heights: np.ndarray
    polarization: str
    eps: object
    k: float
    theta_i: float
    taper_g: float
    psi: np.ndarray
    dpsi: np.ndarray
    theta_s: np.ndarray
    amplitude: np.ndarray
    sigma: np.ndarray
    incident_power: float
    reflected: float | None
    transmitted: float | None
    absorbed_flux: float | None
    reflection_coefficient: complex
    solver: str
    iterations: int
    residual: float | None
    info: dict = field(default_factory=dict)

    @property
    def energy_error(self) -> float:
        """``reflected + transmitted − 1`` (``reflected − 1`` for a perfect conductor)."""
        if self.reflected is None:
            raise ValueError("solve with energy=True to get the reflected power")
        return self.reflected + (self.transmitted or 0.0) - 1.0


def _check_grid(x, heights) -> tuple[np.ndarray, np.ndarray, float]:
    x = check_finite("x", x)
    h = check_finite("heights", heights)
    if np.iscomplexobj(x) or np.iscomplexobj(h):
        raise TypeError("x and heights must be real [m]")
    x = x.astype(float)
    h = h.astype(float)
    if x.ndim != 1 or h.ndim != 1:
        raise ValueError(
            f"x and heights must be 1-D arrays, got shapes x{x.shape} and heights{h.shape}"
        )
    if x.shape != h.shape:
        raise ValueError(
            f"x and heights must have the same length, got {x.size} and {h.size} points"
        )
    if x.size < 16:
        raise ValueError(f"the profile needs at least 16 points, got {x.size}")
    d = np.diff(x)
    dx = float(np.mean(d))
    if not dx > 0 or np.max(np.abs(d - dx)) > 1e-6 * dx:
        raise ValueError(
            "x must be increasing and uniformly spaced (pulse basis on a uniform grid); "
            f"spacings range over [{d.min():g}, {d.max():g}] m"
        )
    return x, h, dx


def _refractive(eps) -> complex:
    """``√ε`` with ``Im ≥ 0``."""
    n2 = np.sqrt(complex(eps))
    return -n2 if n2.imag < 0 else n2


def _n_eff(eps) -> float:
    """Index used to count points per wavelength: ``max(1, |√ε|)`` (1 for a conductor)."""
    return 1.0 if is_pec(eps) else max(1.0, abs(_refractive(eps)))


def _check_resolution(k: float, dx: float, eps, fp: np.ndarray) -> float:
    lam = 2 * math.pi / k
    neff = _n_eff(eps)
    ppw = lam / (dx * neff)
    where = "" if neff == 1 else f" in medium 2 (λ/|√ε| = {lam / neff:g} m)"
    if ppw < MIN_PPW_ERROR:
        raise ValueError(
            f"too few points per wavelength{where}: {ppw:.2f} (dx = {dx:g} m, λ = {lam:g} m); "
            f"the method of moments needs at least {MIN_PPW_ERROR:g} (10 recommended)"
        )
    if ppw < MIN_PPW_WARN:
        warnings.warn(
            f"only {ppw:.2f} points per wavelength{where} (dx = {dx:g} m); results may be "
            f"off by more than 0.1 dB, use ≥ 10",
            MomWarning,
            stacklevel=3,
        )
    gmax = float(np.sqrt(1.0 + np.max(fp * fp)))
    ppw_arc = ppw / gmax
    # isolated steep spots are common on long rough profiles: warn only when the steepest
    # one is under-resolved outright (check_validity reports the softer 3σ criterion)
    if ppw_arc < MIN_PPW_ERROR and ppw >= MIN_PPW_WARN:
        warnings.warn(
            f"steep slopes (max |f'| = {math.sqrt(gmax**2 - 1):.2f}): only {ppw_arc:.2f} "
            "points per wavelength along the arc; refine dx",
            MomWarning,
            stacklevel=3,
        )
    return ppw


def _check_taper(g: float, length: float, k: float, theta_i: float) -> None:
    if g >= length / 2:
        edge = math.exp(-((length / 2 / g) ** 2))
        raise ValueError(
            f"taper_g = {g:g} m is too wide for a surface of length L = {length:g} m: the "
            f"tapered wave would still carry exp(-(L/2g)^2) = {edge:.2f}"
            " of its amplitude at the edges. Use taper_g <= L/4 (Thorsos 1988; Tsang et al. "
            "2001 vol. II ch. 4) or a longer surface."
        )
    if g > length / 4 * (1 + 1e-9):
        warnings.warn(
            f"taper_g = {g:g} m exceeds L/4 = {length / 4:g} m: edge diffraction from the "
            "truncated surface spoils energy conservation (Thorsos 1988 and Tsang et al. "
            "2001 vol. II ch. 4 use g <= L/4)",
            MomWarning,
            stacklevel=3,
        )
    err = (1.0 + 2.0 * math.tan(theta_i) ** 2) / (2.0 * (k * g * math.cos(theta_i)) ** 2)
    if err > 0.05:
        warnings.warn(
            f"taper_g = {g:g} m is too narrow for θi = {math.degrees(theta_i):.1f}°: the "
            f"tapered wave violates the wave equation at the {err:.2f} level (Thorsos 1988 "
            "needs k g cosθi >> 1); widen the taper",
            MomWarning,
            stacklevel=3,
        )


_D1 = np.array([-1.0, 9.0, -45.0, 0.0, 45.0, -9.0, 1.0]) / 60.0  # 6th-order f'
_D2 = np.array([2.0, -27.0, 270.0, -490.0, 270.0, -27.0, 2.0]) / 180.0  # 6th-order f''


def _derivatives(h: np.ndarray, dx: float) -> tuple[np.ndarray, np.ndarray]:
    """``f'`` and ``f''`` by 6th-order central differences (2nd order within 3 points of the
    ends, where the taper has removed the field). Low-order slopes would put the normals
    (and the energy balance, for TM) off by O((dx/ℓ)²)."""
    fp = np.gradient(h, dx, edge_order=2)
    fpp = np.gradient(fp, dx, edge_order=2)
    if h.size > 7:
        fp[3:-3] = np.correlate(h, _D1, mode="valid") / dx
        fpp[3:-3] = np.correlate(h, _D2, mode="valid") / dx**2
    return fp, fpp


def _assemble(x, h, fp, fpp, dx, k, eps, pol):
    n = x.size
    if is_pec(eps):
        a = np.empty((n, n), complex)
        if pol == "h":
            fill_operators(x, h, fp, fpp, dx, k, s_out=a)
        else:
            fill_operators(x, h, fp, fpp, dx, k, d_out=a, d_scale=-1.0)
            a[np.diag_indices(n)] += 0.5
        return a
    k2 = k * _refractive(eps)
    rho = 1.0 if pol == "h" else complex(eps)
    a = np.empty((2 * n, 2 * n), complex)
    # unknowns interleaved (ψ_0, u_0, ψ_1, u_1, ...), equations (A_0, B_0, A_1, B_1, ...)
    fill_operators(x, h, fp, fpp, dx, k, s_out=a[0::2, 1::2], d_out=a[0::2, 0::2], d_scale=-1.0)
    fill_operators(x, h, fp, fpp, dx, k2, s_out=a[1::2, 1::2], s_scale=-rho, d_out=a[1::2, 0::2])
    idx = np.arange(0, 2 * n, 2)
    a[idx, idx] += 0.5
    a[idx + 1, idx] += 0.5
    return a


def _solve(a, b, solver: str, tol: float, max_iter: int):
    m = a.shape[0]
    use_fb = solver == "fb" or (solver == "auto" and m > AUTO_FB_UNKNOWNS)
    if use_fb:
        sol, ok, it, res, _ = solve_fb(a, b, tol=tol, max_iter=max_iter)
        if ok:
            return sol, "fb", it, res
        fb_iter = it
    else:
        fb_iter = 0
    work = a.copy() if use_fb else a
    sol = solve_lu(work, b)
    res = float(np.linalg.norm(a @ sol - b) / np.linalg.norm(b)) if use_fb else None
    return sol, ("lu-fallback" if use_fb else "lu"), fb_iter, res


def solve_realization(
    x,
    heights,
    eps,
    k: float,
    theta_i: float,
    *,
    polarization: str,
    taper_g: float | None = None,
    theta_s=None,
    solver: Solver = "auto",
    tol: float = 1e-6,
    max_iter: int = 60,
    energy: bool = True,
) -> MomResult:
    """Solve one surface realization.

    Parameters
    ----------
    x, heights : uniform grid and heights ``f(x)`` [m], same length (≥ 16).
    eps : ``"pec"`` or relative permittivity (``Im ε ≥ 0``).
    k : free-space wavenumber [rad/m].
    theta_i : incidence angle [rad], in ``[0, π/2)``; the wave travels towards +x.
    polarization : ``"h"`` (TE, ``ψ = E_y``) or ``"v"`` (TM, ``ψ = H_y``).
    taper_g : taper half-width ``g`` [m]; default ``L/4`` with ``L = N dx``. Error if
        ``g ≥ L/2``, :class:`MomWarning` if ``g > L/4`` or if ``k g cosθi`` is too small.
    theta_s : signed scattering angles [rad] in ``(−π/2, π/2)``, > 0 on the specular side;
        default 179 angles from −89° to 89°.
    solver : ``"lu"`` (dense LU), ``"fb"`` (forward–backward, LU fallback), ``"auto"``
        (FB above :data:`AUTO_FB_UNKNOWNS` unknowns).
    tol, max_iter : FB stopping rule on ``‖b − Zψ‖/‖b‖``.
    energy : also integrate the scattered (and transmitted) power over angles.
    """
    x, h, dx = _check_grid(x, heights)
    k = check_positive("k", k, unit="rad/m")
    theta_i = float(check_angle("theta_i", theta_i, high=math.pi / 2 - 1e-6))
    pol = check_polarization(polarization, "polarization")
    eps = check_eps(eps)
    if not is_pec(eps):
        eps = complex(np.asarray(eps).reshape(-1)[0]) if np.ndim(eps) == 0 else None
        if eps is None:
            raise ValueError("eps must be a scalar permittivity or 'pec' for the MoM solver")
    if solver not in ("auto", "lu", "fb"):
        raise ValueError(f"solver must be one of 'auto', 'lu', 'fb', got {solver!r}")
    length = x.size * dx
    g = length / 4 if taper_g is None else check_positive("taper_g", taper_g, unit="m")
    _check_taper(g, length, k, theta_i)
    fp, fpp = _derivatives(h, dx)
    ppw = _check_resolution(k, dx, eps, fp)
    if theta_s is None:
        theta_s = np.radians(np.linspace(-89.0, 89.0, 179))
    theta_s = check_angle("theta_s", theta_s, low=-math.pi / 2, high=math.pi / 2)

    n = x.size
    b_inc = tapered_wave(x, h, k, theta_i, g)
    a = _assemble(x, h, fp, fpp, dx, k, eps, pol)
    if is_pec(eps):
        b = b_inc
    else:
        b = np.zeros(2 * n, complex)
        b[0::2] = b_inc
    sol, used, it, res = _solve(a, b, solver, tol, max_iter)
    del a
    if is_pec(eps):
        zero = np.zeros(n, complex)
        psi, u = (zero, sol) if pol == "h" else (sol, zero)
    else:
        psi, u = sol[0::2], sol[1::2]

    p_inc = incident_power(k, theta_i, g)
    amp = _far_field(k, x, h, fp, psi, u, theta_s)
    sigma = 2 * math.pi * math.cos(theta_i) * np.abs(amp) ** 2 / p_inc
    # flat-surface reference: far field of the incident taper mirrored in z = 0 (module doc)
    a_ref = (
        math.sqrt(k / (2 * math.pi))
        * math.cos(theta_i)
        * np.exp(-0.25j * math.pi)
        * np.sum(tapered_wave(x, 0.0, k, theta_i, g) * np.exp(-1j * k * math.sin(theta_i) * x))
        * dx
    )
    a_spec = _far_field(k, x, h, fp, psi, u, np.array([theta_i]))[0]
    reflected = transmitted = absorbed = None
    info: dict = {"points_per_wavelength": ppw, "unknowns": int(sol.size), "dx": dx}
    if energy:
        tq, wq = _gauss_theta(_n_quad(k, length))
        aq = _far_field(k, x, h, fp, psi, u, tq)
        reflected = float(np.sum(wq * np.abs(aq) ** 2) / p_inc)
        info["quadrature_theta"] = tq
        info["quadrature_weights"] = wq
        info["quadrature_amplitude"] = aq
    if not is_pec(eps):
        absorbed = float(-np.sum(np.imag(np.conj(psi) * u)) * dx / k / p_inc)
        transmitted = absorbed
        if energy and eps.imag == 0 and eps.real > 0:
            k2 = k * math.sqrt(eps.real)
            rho = 1.0 if pol == "h" else eps.real
            tq2, wq2 = _gauss_theta(_n_quad(k2, length))
            a2 = _far_field(k2, x, h, fp, psi, u, tq2, upward=False, rho=rho)
            scale = (k2 / k) / (1.0 if pol == "h" else eps.real)
            transmitted = float(scale * np.sum(wq2 * np.abs(a2) ** 2) / p_inc)
    return MomResult(
        x=x,
        heights=h,
        polarization=pol,
        eps=eps,
        k=k,
        theta_i=theta_i,
        taper_g=g,
        psi=psi,
        dpsi=u,
        theta_s=theta_s,
        amplitude=amp,
        sigma=sigma,
        incident_power=p_inc,
        reflected=reflected,
        transmitted=transmitted,
        absorbed_flux=absorbed,
        reflection_coefficient=complex(a_spec / a_ref),
        solver=used,
        iterations=int(it),
        residual=None if res is None else float(res),
        info=info,
    )
