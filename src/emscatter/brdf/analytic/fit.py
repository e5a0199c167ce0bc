"""Fit an analytic microfacet model to any emscatter table — the quick path to a Mitsuba
``roughconductor`` / ``roughdielectric`` dict.

Model (Mitsuba 3's): Cook–Torrance with a Beckmann or GGX distribution of roughness ``α``
(isotropic, one value for every wavelength — Mitsuba's ``alpha`` is not spectral), separable
Smith shadowing and the unpolarized Fresnel factor of a complex index ``n + ik`` per
wavelength (``ε = (n + ik)²``, ``exp(−iωt)``); ``kind="dielectric"`` fits one real index for
all wavelengths (Mitsuba's ``int_ior`` is a float) and returns a ``roughdielectric`` dict
(whose reflection is this model; it also transmits).

Data: the table's node values with ``θi, θo ≤ theta_max_deg`` (80° by default), at most
``max_points`` of them (an even subsample). Residuals ``(f_model − f_table) cosθo / s`` with
``s`` the table's largest ``f cosθo`` per wavelength (the radiance a renderer sees, lobe
peak weighted most), solved by :func:`scipy.optimize.least_squares` from a coarse ``α`` scan.
The reported errors are relative: ``rms`` of the residuals (fraction of the peak), and the
median / 90th percentile / max of ``|f_model − f_table| / f_table`` over the nodes where
``f cosθo`` exceeds 1 % of the peak; ``albedo_max_abs`` compares directional albedos. The
table's coherent delta lobe is not part of the fit (``coherent_max`` says how large it is).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares

from emscatter.brdf import frames
from emscatter.brdf.analytic import cook_torrance, fresnel_unpolarized, half_vector
from emscatter.brdf.analytic.distributions import GGX, Beckmann
from emscatter.brdf.table import BrdfTable

__all__ = ["FitResult", "fit_microfacet"]

_DISTRIBUTIONS = {"beckmann": Beckmann, "ggx": GGX}


@dataclass(frozen=True)
class FitResult:
    """Fitted parameters, errors and the Mitsuba dict (module docstring)."""

    distribution: str
    alpha: float
    wavelengths: np.ndarray
    eta: np.ndarray
    k: np.ndarray
    kind: str
    errors: dict
    mitsuba: dict
    info: dict = field(default_factory=dict)

    def eps(self) -> np.ndarray:
        """Fitted relative permittivity per wavelength ``(η + ik)²``."""
        return (self.eta + 1j * self.k) ** 2

    def to_mitsuba(self, mode: str = "spectrum") -> dict:
        """The Mitsuba 3 BSDF dict; ``mode="spectrum"`` (wavelength–value pairs, any variant)
        or ``"rgb"`` (three-wavelength fits: R, G, B = longest … shortest wavelength)."""
        if mode == "spectrum":
            return dict(self.mitsuba)
        if mode != "rgb":
            raise ValueError(f"mode must be 'spectrum' or 'rgb', got {mode!r}")
        if self.kind == "dielectric":
            return dict(self.mitsuba)
        if self.wavelengths.size != 3:
            raise ValueError(
                f"mode='rgb' needs a three-wavelength fit, got {self.wavelengths.size}"
            )
        out = dict(self.mitsuba)
        out["eta"] = {"type": "rgb", "value": self.eta[::-1].tolist()}
        out["k"] = {"type": "rgb", "value": self.k[::-1].tolist()}
        return out


def _spectrum(wavelengths, values):
    if wavelengths.size == 1:
        return float(values[0])
    return {
        "type": "spectrum",
        "value": [(float(w * 1e9), float(v)) for w, v in zip(wavelengths, values, strict=True)],
    }


def _samples(table: BrdfTable, theta_max: float, max_points: int):
    if table.isotropic:
        ti, to, pd = np.meshgrid(table.theta_i, table.theta_o, table.phi_d, indexing="ij")
        pi_ = np.zeros_like(ti)
        po = pd
    else:
        ti, pi_, to, po = np.meshgrid(*table.grid_axes, indexing="ij")
    keep = np.flatnonzero(((ti <= theta_max) & (to <= theta_max)).ravel())
    if keep.size > max_points:
        keep = keep[np.linspace(0, keep.size - 1, max_points).round().astype(int)]
    wi = frames.directions(ti.ravel()[keep], pi_.ravel()[keep])
    wo = frames.directions(to.ravel()[keep], po.ravel()[keep])
    data = table.values.reshape(table.wavelengths.size, -1)[:, keep]
    return wi, wo, data


def fit_microfacet(
    table: BrdfTable,
    *,
    distribution: str = "beckmann",
    kind: str = "conductor",
    theta_max_deg: float = 80.0,
    max_points: int = 6000,
) -> FitResult:
    """Fit ``α`` and the complex index to ``table`` (module docstring); returns a
    :class:`FitResult` with ``mitsuba`` = a ``roughconductor``/``roughdielectric`` dict."""
    if not isinstance(table, BrdfTable):
        raise TypeError(f"table must be a BrdfTable, got {type(table).__name__}")
    if distribution not in _DISTRIBUTIONS:
        raise ValueError(
            f"distribution must be one of {sorted(_DISTRIBUTIONS)}, got {distribution!r}"
        )
    if kind not in ("conductor", "dielectric"):
        raise ValueError(f"kind must be 'conductor' or 'dielectric', got {kind!r}")
    if not 10.0 <= float(theta_max_deg) < 90.0:
        raise ValueError(f"theta_max_deg must be in [10, 90), got {theta_max_deg!r}")
    make = _DISTRIBUTIONS[distribution]
    wi, wo, data = _samples(table, math.radians(theta_max_deg), int(max_points))
    cos_o = wo[:, 2]
    scale = np.maximum((data * cos_o).max(axis=1), 1e-300)[:, None]
    n_wl = table.wavelengths.size
    h = half_vector(wi, wo)
    cos_d = np.clip(np.sum(wi * h, axis=-1), 0, 1)  # Fresnel angle, parameter-free
    cache: dict = {}

    def lobe(alpha):
        """Fresnel-free Cook–Torrance (F = 1), cached per α (the Jacobian's n, k steps)."""
        if alpha not in cache:
            cache.clear()
            cache[alpha] = cook_torrance(wi, wo, make(alpha))
        return cache[alpha]

    def fresnel(params):
        if kind == "conductor":
            eta, kap = params[:n_wl], params[n_wl:]
            return np.stack(
                [fresnel_unpolarized((eta[j] + 1j * kap[j]) ** 2, cos_d) for j in range(n_wl)]
            )
        return np.broadcast_to(fresnel_unpolarized(params[0] ** 2, cos_d), (n_wl, cos_d.size))

    def residuals(x):
        alpha = math.exp(x[0])
        model = lobe(alpha)[None, :] * fresnel(x[1:])
        return (((model - data) * cos_o) / scale).ravel()

    # coarse α scan with the Fresnel factor fitted as one level per wavelength
    best = None
    for alpha in np.geomspace(0.02, 1.5, 25):
        shape = lobe(alpha) * cos_o
        level = (data * cos_o) @ shape / max(float(shape @ shape), 1e-300)
        err = float(np.sum(((level[:, None] * shape - data * cos_o) / scale) ** 2))
        if best is None or err < best[0]:
            best = (err, alpha)
    if kind == "conductor":
        x0 = [math.log(best[1]), *([1.0] * n_wl), *([2.0] * n_wl)]
        lo = [math.log(1e-3), *([0.01] * n_wl), *([0.0] * n_wl)]
        hi = [math.log(3.0), *([20.0] * n_wl), *([30.0] * n_wl)]
    else:
        x0, lo, hi = [math.log(best[1]), 1.5], [math.log(1e-3), 1.0001], [math.log(3.0), 10.0]
    res = least_squares(residuals, x0, bounds=(lo, hi), x_scale="jac", xtol=1e-12, ftol=1e-12)
    alpha = math.exp(res.x[0])
    if kind == "conductor":
        eta, kap = res.x[1 : 1 + n_wl], res.x[1 + n_wl :]
    else:
        eta, kap = np.full(n_wl, res.x[1]), np.zeros(n_wl)
    model = lobe(alpha)[None, :] * fresnel(res.x[1:])
    errors = _errors(table, model, data, cos_o, scale, distribution, alpha, eta, kap)
    wl = table.wavelengths
    if kind == "conductor":
        mitsuba = {
            "type": "roughconductor",
            "distribution": distribution,
            "alpha": alpha,
            "eta": _spectrum(wl, eta),
            "k": _spectrum(wl, kap),
        }
    else:
        mitsuba = {
            "type": "roughdielectric",
            "distribution": distribution,
            "alpha": alpha,
            "int_ior": float(eta[0]),
            "ext_ior": 1.0,
        }
    return FitResult(
        distribution=distribution,
        alpha=alpha,
        wavelengths=wl,
        eta=np.array(eta),
        k=np.array(kap),
        kind=kind,
        errors=errors,
        mitsuba=mitsuba,
        info={
            "points": int(data.shape[1]),
            "optimizer": res.message,
            "theta_max_deg": float(theta_max_deg),
        },
    )


def _errors(table, model, data, cos_o, scale, distribution, alpha, eta, kap) -> dict:
    sig = data * cos_o > 0.01 * scale
    rel = np.abs(model - data)[sig] / data[sig]
    from emscatter.brdf.build import fill_from_function

    make = _DISTRIBUTIONS[distribution]

    def fitted(wi, wo, lam):
        j = int(np.argmin(np.abs(table.wavelengths - lam)))
        return cook_torrance(wi, wo, make(alpha), eps=(eta[j] + 1j * kap[j]) ** 2)

    phi = table.phi_d if table.isotropic else table.phi_o
    alb = float("inf")
    if table.symmetric_grid:  # the fitted model on the table's own nodes, same quadrature
        fit_t = fill_from_function(
            fitted, table.wavelengths, table.theta_i, phi, not table.isotropic, {}
        )
        alb = float(np.max(np.abs(fit_t.albedo().incoherent - table.albedo().incoherent)))
    return {
        "rms": float(np.sqrt(np.mean(((model - data) * cos_o / scale) ** 2))),
        "median_rel": float(np.median(rel)) if rel.size else 0.0,
        "p90_rel": float(np.percentile(rel, 90)) if rel.size else 0.0,
        "max_rel": float(rel.max()) if rel.size else 0.0,
        "albedo_max_abs": alb,
        "coherent_max": float(np.max(table.coherent)),
    }
