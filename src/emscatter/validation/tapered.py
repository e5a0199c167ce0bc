"""An exponential spectrum with a smooth inner cutoff: the exponential maps' surfaces.

The exponential correlation ``exp(−|x|/ℓ)`` is not differentiable: a profile sampled at
spacing ``dx`` has slopes growing like ``dx^{−1/2}`` and no curvature at all, and the method of
moments (whose TM equations use the profile's curvature) then loses its own energy balance
(measured: reflected power 0.96–1.03 of the incident for a conductor already at grid-scale
slopes 0.4–1.4, and 65× at kσ = 1.5). Its answer — and the physics — depend on the inner
scale. The exponential validity maps therefore use a well-defined surface,

    w(K) ∝ ℓ/π (1 + K²ℓ²)^−1 · exp(−(K/K_c)^12),     K_c = cut/ℓ,

the exponential spectrum up to ``K_c`` (2.5 k on the maps, beyond the Bragg band ``2k``
the first-order scattering sees: the taper is below 2e-4 at the maps' largest Bragg
wavenumber 1.21 k) and smooth, so that a grid of ``dx ≤ π/(3·1.3 K_c)`` resolves it; and
**every approximation is evaluated on this same spectrum**: SPM (its spectrum), GO (its
finite slope), SPM2 (its support), PO and the IEM (their n-fold spectra ``w_n`` of ``ρⁿ``,
tabulated here and used through :func:`emscatter.solvers.kirchhoff.po.log_nfold`'s hook).

:class:`TaperedExponential` is a 1-D :class:`~emscatter.spectra.ExponentialCorrelation`
subclass (so a model's nominal exponential parameters — e.g. the IEM's nominal slope σ/ℓ —
still apply); ``sigma`` is the rms height of the tapered surface, ``untapered_sigma`` the
exponential's it was cut from.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from ..spectra import ExponentialCorrelation

__all__ = ["TaperedExponential", "TAPER_POWER", "tapered_from"]

TAPER_POWER = 12


_U_MAX = 240.0  # ρ(u) < e^{−200} beyond; long, so the q step π/_U_MAX resolves the taper
_N_TABLE = 1024  # n-fold spectra tabulated up to n = 1024, the Gaussian limit beyond


def _w_unit(q: np.ndarray, cut: float) -> np.ndarray:
    return np.exp(-((q / cut) ** TAPER_POWER)) / (math.pi * (1.0 + q * q))


@lru_cache(maxsize=64)
def _unit_tables(cut: float):
    """(normalization, m₂ = −ρ''(0), u grid, ρ(u), spline of ρ) of the unit-length spectrum:
    ρ by a DCT-I of ``w`` zero-padded to ``40·cut`` (u spacing ``π/(40 cut)``)."""
    from scipy import fft as sfft
    from scipy.interpolate import CubicSpline

    q_max = 40.0 * cut
    du = math.pi / q_max
    n = int(math.ceil(_U_MAX / du)) + 1
    q = np.arange(n) * (q_max / (n - 1))
    w = _w_unit(q, cut)
    dq = q[1] - q[0]
    wts = np.full(n, dq)
    wts[0] = wts[-1] = 0.5 * dq
    norm = 2.0 * float(np.sum(w * wts))  # ∫ over the whole line
    m2 = 2.0 * float(np.sum(q * q * w * wts)) / norm
    # DCT-I: X_j = x_0 + (−1)^j x_{N−1} + 2 Σ_{i=1}^{N−2} x_i cos(π i j/(N−1)); u_j = π j/q_max
    rho = sfft.dct(w, type=1) * dq / norm
    u = np.arange(n) * (math.pi / q_max)
    rho = rho / rho[0]
    return norm, m2, u, rho, CubicSpline(u, rho)


@dataclass(frozen=True)
class TaperedExponential(ExponentialCorrelation):
    """1-D exponential spectrum × ``exp(−(K ℓ/cut)^12)``, normalized (module docstring)."""

    cut: float = 10.0
    untapered_sigma: float | None = None
    name: str = field(default="tapered-exponential", init=False, repr=False)

    def __post_init__(self):
        super().__post_init__()
        if self.dimension != 1:
            raise ValueError("TaperedExponential is a 1-D profile roughness (dimension=1)")
        if not (isinstance(self.cut, int | float) and math.isfinite(self.cut) and self.cut > 0):
            raise ValueError(f"cut (K_c·ℓ) must be positive, got {self.cut!r}")

    def _params(self) -> dict:
        return {**super()._params(), "cut": self.cut, "untapered_sigma": self.untapered_sigma}

    def _w1_unit(self, q):
        norm = _unit_tables(float(self.cut))[0]
        return _w_unit(np.abs(np.asarray(q, dtype=float)), float(self.cut)) / norm

    def _w2_unit(self, q):
        raise TypeError("TaperedExponential is 1-D only")

    def _rho_unit(self, u):
        spline = _unit_tables(float(self.cut))[4]
        u = np.abs(np.asarray(u, dtype=float))
        return np.where(u < _U_MAX, spline(np.minimum(u, _U_MAX)), 0.0)

    def _mss_closed(self):
        return self.sigma**2 * _unit_tables(float(self.cut))[1] / self.length**2, 0.0

    def nfold_spectrum(self, n, kx, ky=0.0):
        f = self.log_nfold_table()
        n, kx = np.broadcast_arrays(np.asarray(n, float), np.asarray(kx, float))
        return self.length * np.exp(f(n, np.abs(kx) * self.length))

    @property
    def spectral_support(self) -> tuple[float, tuple[float, ...]]:
        """(support radius, breakpoints) in units of 1/ℓ for the second-order SPM quadrature."""
        c = float(self.cut)
        return 1.35 * c, tuple(sorted({1.0, 8.0, 0.5 * c, 0.85 * c, c}))

    def log_nfold_table(self):
        """``f(n, s) = log(w_n/ℓ)`` at the scaled wavenumber ``s = |q_x| ℓ`` (the hook of
        :func:`emscatter.solvers.kirchhoff.po.log_nfold`; :func:`_nfold_function`)."""
        return _nfold_function(float(self.cut))


@lru_cache(maxsize=64)
def _nfold_function(cut: float):
    """``f(n, s) = log(w_n(s))`` (unit length): DCT-I of ``ρⁿ`` on the ρ grid for
    ``n ≤ 1024`` (tabulated at n = 1…32 and log-spaced to 1024, linear in (log n, s)),
    the Gaussian limit ``exp(−s²/(2 n m₂))/√(2π n m₂)`` beyond."""
    from scipy import fft as sfft

    _, m2, u, rho, _ = _unit_tables(cut)
    m = int(np.searchsorted(u, 120.0)) + 1  # ρⁿ ≤ ρ < e^{−119} beyond u = 120
    u, rho = u[:m], rho[:m]
    du = u[1] - u[0]
    n_nodes = np.unique(
        np.round(np.concatenate([np.arange(1.0, 33.0), np.geomspace(32, _N_TABLE, 21)]))
    )
    s_all = np.arange(u.size) * (math.pi / ((u.size - 1) * du))
    keep = s_all <= 4.0 * cut  # the maps need s = |q_x| ℓ ≤ 2kℓ = 0.8 cut
    s_nodes = s_all[keep]
    log_w = np.empty((n_nodes.size, s_nodes.size))
    for i, nn in enumerate(n_nodes):
        val = sfft.dct(rho**nn, type=1)[keep] * du / (2 * math.pi)  # (1/π)∫_0^∞ ρⁿ cos
        log_w[i] = np.log(np.maximum(val, 1e-13 * val[0]))
    ln = np.log(n_nodes)
    ds = s_nodes[1] - s_nodes[0]

    def f(n, s):
        n, s = np.broadcast_arrays(np.asarray(n, float), np.abs(np.asarray(s, float)))
        nn = np.maximum(n, 1.0)
        x = np.log(nn)
        j = np.clip(np.searchsorted(ln, x) - 1, 0, ln.size - 2)
        fx = np.clip((x - ln[j]) / (ln[j + 1] - ln[j]), 0.0, 1.0)
        y = np.clip(s / ds, 0.0, s_nodes.size - 1.000001)
        i = y.astype(int)
        fy = y - i
        w0 = log_w[j, i] * (1 - fy) + log_w[j, i + 1] * fy
        w1 = log_w[j + 1, i] * (1 - fy) + log_w[j + 1, i + 1] * fy
        val = w0 * (1 - fx) + w1 * fx
        gauss = -0.5 * np.log(2 * math.pi * nn * m2) - s * s / (2 * nn * m2)
        # beyond the tabulated n or s: the Gaussian limit (for small n beyond 4·cut: ~0)
        return np.where((n > n_nodes[-1]) | (s > s_nodes[-1]), gauss, val)

    return f


def tapered_from(sigma: float, length: float, k_c: float) -> TaperedExponential:
    """The tapered profile cut from ``ExponentialCorrelation(sigma, length)`` at ``k_c``
    [rad/m]: same spectrum below the cut, ``sigma`` reduced by the variance removed."""
    cut = k_c * length
    norm = _unit_tables(float(cut))[0]
    return TaperedExponential(sigma * math.sqrt(norm), length, dimension=1, cut=cut,
                              untapered_sigma=sigma)  # fmt: skip
