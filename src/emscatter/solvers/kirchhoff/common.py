"""Shared pieces of the Kirchhoff (tangent-plane) solvers: geometry, local-specular
polarization factors, slope statistics, Smith shadowing and the coherent reflectivity.

Geometry (see :mod:`emscatter.conventions`): ``k_i = k (sinθi cosφi, sinθi sinφi, −cosθi)``,
``k_s = k (sinθs cosφs, sinθs sinφs, cosθs)`` and the scattering vector ``q = k_s − k_i``.
Lengths below are in units of ``k`` (``q̃ = q / k``, dimensionless).

Local specular facet (stationary phase)
---------------------------------------
The facets that reflect ``k_i`` into ``k_s`` have the normal ``n̂ = q/|q|``, the slopes
``(ζx, ζy) = (−qx/qz, −qy/qz)`` and the local incidence cosine ``cosθl = −k̂_i·n̂ = |q|/(2k)``
(Tsang, Kong & Ding 2001, vol. III, ch. 2; Ulaby, Moore & Fung 1982, vol. II, §12-4).

Polarization factors. With the facet's TE unit vector ``t̂ ∝ k̂_i × k̂_s`` and TM vectors
``d̂_i = t̂ × k̂_i``, ``d̂_s = t̂ × k̂_s``, the reflected field is
``E_r = R_h(θl) (E_i·t̂) t̂ + R_v(θl) (E_i·d̂_i) d̂_s`` (``R_v`` the ratio of magnetic fields,
as in :mod:`emscatter.fresnel`), so the amplitude for scattered ``p̂_s`` from incident ``q̂_i`` is

    F_pq = R_h (p̂_s·t̂)(q̂_i·t̂) + R_v (p̂_s·d̂_s)(q̂_i·d̂_i).

With ``ĥ = ẑ × k̂/|ẑ × k̂|`` and ``v̂ = ĥ × k̂`` (Tsang's basis) the four projections on
``τ = k̂_i × k̂_s`` are, with ``Δ = φs − φi`` (common sign dropped, it cancels in products),

    h_i·τ = cosθi sinθs cosΔ + sinθi cosθs      v_i·τ = sinθs sinΔ
    h_s·τ = sinθi cosθs cosΔ + cosθi sinθs      v_s·τ = sinθi sinΔ

and ``(p̂_s·d̂_s)``, ``(q̂_i·d̂_i)`` follow from ``ĥ·d̂ = −v̂·t̂``, ``v̂·d̂ = ĥ·t̂``. In the plane of
incidence ``F_hh = R_h(θl)``, ``F_vv = R_v(θl)`` and the cross terms vanish; out of the plane
they do not. Since the basis changes are rotations, ``Σ_pq |F_pq|² = |R_h|² + |R_v|²`` — the
unpolarized Fresnel factor of the Cook–Torrance model. At exact backscatter ``τ = 0``; there
``R_v(0) = −R_h(0)`` and ``E_r = R_h(0) E_i`` for any ``t̂`` (``t̂ = ĥ_i`` is used).
"""

from __future__ import annotations

import math
import os

import numpy as np
from scipy import special

from emscatter.conventions import (
    broadcast_shape,
    broadcast_view,
    check_angle,
    check_finite,
    check_positive,
)
from emscatter.fresnel import PEC, check_eps, is_pec
from emscatter.solvers.validity import Check, angle_lower, build_report, lower, wave_slope_variances
from emscatter.spectra import Roughness, check_roughness

__all__ = [
    "Geometry",
    "geometry",
    "coherent_reflectivity",
    "fresnel_factors",
    "slope_variances",
    "smith_lambda",
    "shadowing_factor",
    "check_roughness",
    "tangent_plane_checks",
    "illuminated_fraction",
    "shadowing_angle_check",
    "grazing_parameter",
    "validity_report",
]

_TAU_EPS = 1e-28  # |k̂_i × k̂_s|² below this is treated as exact backscatter
_CPUS = os.cpu_count() or 1


class Geometry:
    """Checked, broadcast angles; trigonometry flattened to 1-D (kept 0-d when scalar).

    The flat arrays (``ti_flat``, ``ts_flat``, ``dphi``, ``phi_i_flat``, ``phi_s_flat``,
    ``eps_flat``) are made on first use from the checked, unbroadcast inputs in
    ``compact`` (θi, θs, φs − φi, φi, φs, ε): a compiled kernel working on a grid of angles
    reads those directly and never pays for the copies."""

    __slots__ = (
        "theta_i", "theta_s", "phi_s", "phi_i", "_eps", "shape", "size", "phi_i_zero",
        "dimension", "compact", "_flats",
    )  # fmt: skip

    @property
    def eps(self):
        """``"pec"`` or the permittivity broadcast to ``shape`` (read-only; made on first use)."""
        if self._eps is None:
            self._eps = _broadcast(self.compact[5], self.shape)
        return self._eps

    def _flat_input(self, i: int):
        flats = self._flats
        if flats[i] is None:
            a = self.compact[i]
            flats[i] = a if isinstance(a, str) else _flat(a, self.shape)
        return flats[i]

    ti_flat = property(lambda self: self._flat_input(0))
    ts_flat = property(lambda self: self._flat_input(1))
    dphi = property(lambda self: self._flat_input(2))
    phi_i_flat = property(lambda self: self._flat_input(3))
    phi_s_flat = property(lambda self: self._flat_input(4))
    eps_flat = property(lambda self: self._flat_input(5))

    def chunk(self, sl: slice | None = None, *, signed_azimuth: bool = False) -> Local:
        """Derived vectors (``q`` in units of k) for the flat index range ``sl`` (all if None).

        ``signed_azimuth=False`` computes ``|sin Δφ|`` (cheaper), enough where only
        ``sin²Δφ`` enters (isotropic slopes)."""
        sl = slice(None) if sl is None else sl

        def take(a):
            return a if np.ndim(a) == 0 else a[sl]

        loc = Local()
        loc.n = len(range(*sl.indices(self.size)))
        loc.si, loc.ci = _trig(take(self.ti_flat))
        loc.ss, loc.cs = _trig(take(self.ts_flat))
        dphi = take(self.dphi)
        loc.cd = np.cos(dphi)
        if signed_azimuth:
            loc.sd = np.sin(dphi)
        else:
            loc.sd = np.sqrt(np.maximum((1.0 - loc.cd) * (1.0 + loc.cd), 0.0))
        loc.eps = self.eps if isinstance(self.eps, str) else take(self.eps_flat)
        loc.phi_i, loc.phi_s = take(self.phi_i_flat), take(self.phi_s_flat)
        self._lateral_q(loc)
        loc.qz = loc.cs + loc.ci
        # |q|²/k² = 2 (1 − k̂i·k̂s) = 2 (1 + cosθi cosθs − sinθi sinθs cosΔφ)
        loc.q2 = np.maximum(2.0 * (1.0 + loc.ci * loc.cs - loc.si * loc.ss * loc.cd), 0.0)
        loc.cos_l = np.minimum(0.5 * np.sqrt(loc.q2), 1.0)  # cosθl = |q|/(2k)
        return loc

    def backscatter_chunk(self, tol: float) -> Local | None:
        """The whole geometry as one :class:`Local` when every geometry is exact backscatter
        — θs is θi (the same checked array) and φs − φi ≡ π to ``tol`` rad — else None.

        Computes only what backscatter needs (``si, ci, ss = si, cs = ci, cd, sd, qx, qy, eps,
        phi_i, phi_s``, with :meth:`chunk`'s formulas and ``signed_azimuth=True``, so the
        values are the same); ``qz, q2, cos_l`` are left unset."""
        ti, ts, dphi = self.compact[0], self.compact[1], self.compact[2]
        if ts is not ti:
            return None
        if dphi.ndim == 0:  # one azimuth difference (the usual call): no ufunc round trips
            if not abs(float(dphi) % (2 * math.pi) - math.pi) <= tol:
                return None
        elif not np.all(np.abs(np.mod(dphi, 2 * math.pi) - math.pi) <= tol):
            return None
        loc = Local()
        loc.n = self.size
        loc.si, loc.ci = _trig(self.ti_flat)
        loc.ss, loc.cs = loc.si, loc.ci
        dphi = self.dphi
        loc.cd, loc.sd = np.cos(dphi), np.sin(dphi)
        e = self.compact[5]  # (not self.eps: that broadcasts a scalar ε to the full shape)
        loc.eps = e if isinstance(e, str) else self.eps_flat
        loc.phi_i, loc.phi_s = self.phi_i_flat, self.phi_s_flat
        self._lateral_q(loc)
        return loc

    def _lateral_q(self, loc: Local) -> None:
        """``loc.qx, loc.qy`` (units of k) from the trigonometry in ``loc``: the scattering
        plane's components, rotated by φi unless φi = 0 or the profile is 1-D."""
        qxp = loc.ss * loc.cd - loc.si
        qyp = loc.ss * loc.sd
        if self.phi_i_zero or self.dimension == 1:
            loc.qx, loc.qy = qxp, qyp
        else:
            cpi, spi = np.cos(loc.phi_i), np.sin(loc.phi_i)
            loc.qx = qxp * cpi - qyp * spi
            loc.qy = qxp * spi + qyp * cpi


class Local:
    """Per-chunk derived quantities (``q`` in units of ``k``)."""

    __slots__ = (
        "si", "ci", "ss", "cs", "cd", "sd", "eps", "qx", "qy", "qz", "q2", "cos_l",
        "phi_i", "phi_s", "n",
    )  # fmt: skip


def _flat(a: np.ndarray, shape) -> np.ndarray:
    if a.ndim == 0:
        return a
    if a.shape == shape:
        return a.reshape(-1)
    out = np.empty(shape, dtype=a.dtype)  # a broadcast copy (faster than reshaping a view)
    out[...] = a
    return out.reshape(-1)


def _broadcast(a: np.ndarray, shape) -> np.ndarray:
    """``np.broadcast_to(a, shape)`` (read-only); cheaper when ``a`` has the shape, or is a
    number spread over a small shape (a read-only copy then)."""
    if a.shape != shape:
        if a.ndim == 0 and len(shape) == 1 and shape[0] <= 4096:
            view = np.full(shape, a)
            view.flags.writeable = False
            return view
        return broadcast_view(a, shape)
    view = a.view()
    view.flags.writeable = False
    return view


def _trig(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(sinθ, cosθ)`` for θ ∈ [0, π/2] with ``cos = √((1−s)(1+s))`` (exactly 0 at π/2)."""
    s = np.sin(x)
    return s, np.sqrt((1.0 - s) * (1.0 + s))


def geometry(
    theta_i, theta_s, phi_s, phi_i, eps, dimension: int, *, checked: bool = False
) -> Geometry:
    """Check and broadcast the angles [rad] and ``eps`` (complex or "pec").

    For ``dimension=1`` the profile lies in the plane of incidence (whatever φi) and
    ``φs ∈ {φi, φi + π}`` (mod 2π); ``q_x`` is then measured along that plane.
    ``checked=True``: the inputs were checked as here already (float arrays, angles in
    range, ``eps`` "pec" or complex) — the public API's entry; only broadcasting is done.
    """
    if checked:
        ti, ts, ps, pi_ = theta_i, theta_s, phi_s, phi_i
        eps = PEC if is_pec(eps) else np.asarray(eps, dtype=complex)
    else:
        ti = check_angle("theta_i", theta_i)
        ts = ti if theta_s is theta_i else check_angle("theta_s", theta_s)  # backscatter: once
        ps = check_finite("phi_s", phi_s)
        pi_ = check_finite("phi_i", phi_i)
        for name, arr in (("phi_s", ps), ("phi_i", pi_)):
            if np.iscomplexobj(arr):
                raise TypeError(f"{name} must be real (radians), got a complex array")
        ps = ps.astype(float)
        pi_ = pi_.astype(float)
        eps = check_eps(eps)
    arrays = {"theta_i": ti, "theta_s": ts, "phi_s": ps, "phi_i": pi_}
    if not is_pec(eps):
        arrays["eps"] = eps
    try:
        shape = broadcast_shape(*(np.shape(a) for a in arrays.values()))
    except ValueError:
        desc = ", ".join(f"{k}{np.shape(v)}" for k, v in arrays.items())
        raise ValueError(f"angle arrays (and eps) do not broadcast together: {desc}") from None
    if dimension == 1:
        sin_d = np.abs(np.sin(ps - pi_))
        if np.any(sin_d > 1e-9):
            bad = np.broadcast_to(ps, sin_d.shape)[sin_d > 1e-9].ravel()[0]
            raise ValueError(
                f"phi_s must equal phi_i or phi_i + π (mod 2π) for a 1-D profile (scattering "
                f"in the plane of incidence, which contains the profile), got {bad!r} rad"
            )
    g = Geometry()
    g.shape = shape
    g.size = math.prod(shape)
    g.theta_i = _broadcast(ti, shape)
    g.theta_s = g.theta_i if ts is ti else _broadcast(ts, shape)  # backscatter: one view
    g.phi_s, g.phi_i = _broadcast(ps, shape), _broadcast(pi_, shape)
    g._eps = PEC if is_pec(eps) else None  # (broadcast on first use)
    g.phi_i_zero = bool(pi_.ndim == 0 and float(pi_) == 0.0)
    # φi = +0.0 (the usual call): φs − φi is φs bit for bit (x − 0.0 = x, also for −0.0), so
    # no n-element difference is made; φi = −0.0 would turn −0.0 into +0.0, it subtracts.
    same = g.phi_i_zero and math.copysign(1.0, float(pi_)) > 0
    g.compact = (ti, ts, ps if same else ps - pi_, pi_, ps, PEC if is_pec(eps) else eps)
    g._flats = [None] * 6
    g.dimension = dimension
    return g


def fast_fresnel(eps, c: np.ndarray, cross: bool = True):
    """``(|R_h|², |R_v|², Re(R_h R_v*))`` at incidence cosine ``c``, in real arithmetic (stable
    complex square root, branch ``Im ≥ 0, Re ≥ 0`` as :mod:`emscatter.fresnel`; tested against
    :func:`emscatter.fresnel.fresnel_cos`). ``cross=False`` returns ``None`` for the third."""
    if isinstance(eps, str):
        one = np.ones_like(c)
        return one, one, (-one if cross else None)
    er, ei = np.real(eps), np.imag(eps)
    a = er - (1.0 - c * c)
    b = ei + 0.0 * c
    big = np.sqrt(0.5 * (np.sqrt(a * a + b * b) + np.abs(a)))  # valid for |ε| < 1e150
    small = 0.5 * b / np.maximum(big, 1e-300)
    pos = a >= 0
    u = np.where(pos, big, small)  # Re √(ε − sin²θ)
    v = np.where(pos, small, big)  # Im √(ε − sin²θ) ≥ 0 (b = Im ε ≥ 0)
    hn_r, hd_r = c - u, c + u  # R_h = (c − w)/(c + w), imaginary parts −v, +v
    ec_r, ec_i = er * c, ei * c
    vn_r, vn_i, vd_r, vd_i = ec_r - u, ec_i - v, ec_r + u, ec_i + v  # R_v = (εc − w)/(εc + w)
    v2 = v * v
    hd2 = np.maximum(hd_r * hd_r + v2, 1e-300)  # 0 only with a 0/0 limit (ε = 1, grazing)
    vd2 = np.maximum(vd_r * vd_r + vd_i * vd_i, 1e-300)
    rh2 = (hn_r * hn_r + v2) / hd2
    rv2 = (vn_r * vn_r + vn_i * vn_i) / vd2
    if not cross:
        return rh2, rv2, None
    # R_h ∝ hn·conj(hd), R_v ∝ vn·conj(vd); Re(R_h R_v*) = Re(h · conj(v)) / (|hd|²|vd|²)
    h_r, h_i = hn_r * hd_r - v2, -v * (hd_r + hn_r)
    w_r, w_i = vn_r * vd_r + vn_i * vd_i, vn_i * vd_r - vn_r * vd_i
    return rh2, rv2, (h_r * w_r + h_i * w_i) / (hd2 * vd2)


def coherent_local(g: Local, sigma: float, k: float) -> np.ndarray:
    """:func:`coherent_reflectivity` on a checked chunk, shape ``(2, n)``."""
    rh2, rv2, _ = fast_fresnel(g.eps, g.ci, cross=False)
    att = np.exp(-((2.0 * k * sigma * g.ci) ** 2))
    return np.stack([np.broadcast_to(rh2 * att, (g.n,)), np.broadcast_to(rv2 * att, (g.n,))])


def fresnel_factors(g: Local, dimension: int, scale=1.0, out=None) -> np.ndarray:
    """``scale · |F_pq|²`` (module docstring), shape ``(2, 2, n)`` indexed ``[pol_s, pol_i]``,
    written into ``out`` if given."""
    n = g.n
    a_h, a_v, cross = (np.broadcast_to(x * scale, (n,)) for x in fast_fresnel(g.eps, g.cos_l))
    if out is None:
        out = np.empty((2, 2, n))
    if dimension == 1:
        out[0, 1] = out[1, 0] = 0.0
        out[0, 0] = a_h
        out[1, 1] = a_v
        return out
    hi = g.ci * g.ss * g.cd + g.si * g.cs
    vi = g.ss * g.sd
    hs = g.si * g.cs * g.cd + g.ci * g.ss
    vs = g.si * g.sd
    d = hi * hi + vi * vi
    degenerate = d < _TAU_EPS
    if np.any(degenerate):  # exact backscatter (or q = 0): t̂ = ĥ_i, see module docstring
        hi = np.where(degenerate, 1.0, hi)
        vi = np.where(degenerate, 0.0, vi)
        hs = np.where(degenerate, -1.0, hs)
        vs = np.where(degenerate, 0.0, vs)
        d = np.where(degenerate, 1.0, d)
    inv = 1.0 / (d * d)
    ah, av, cr = a_h * inv, a_v * inv, 2.0 * cross * inv
    # F_pq = (R_h a_pq + R_v b_pq)/|τ|² with (a, b): hh (hs·hi, vs·vi), vv (vs·vi, hs·hi),
    # hv (hs·vi, −vs·hi), vh (vs·hi, −hs·vi)
    p, m, x, y = hs * hi, vs * vi, hs * vi, vs * hi
    out[0, 0] = ah * p * p + av * m * m + cr * p * m
    out[1, 1] = ah * m * m + av * p * p + cr * p * m
    out[0, 1] = ah * x * x + av * y * y - cr * x * y
    out[1, 0] = ah * y * y + av * x * x - cr * x * y
    np.maximum(out, 0.0, out=out)  # rounding of the cross term (exact zeros in the plane)
    return out


def coherent_reflectivity(roughness, eps, k: float, theta_i) -> np.ndarray:
    """Kirchhoff coherent reflectivity ``|R_p(θi)|² exp(−(2kσ cosθi)²)`` [-], shape
    ``(2, *shape)`` (h, v) — Ulaby, Moore & Fung (1982) vol. II eq. 12.x; Tsang et al. (2001)
    vol. III ch. 2 (the Kirchhoff mean field is ``R exp(−2k²σ²cos²θi)``).

    ``theta_i`` [rad] broadcasts with ``eps``; ``k`` [rad/m]."""
    rough = check_roughness(roughness)
    k = check_positive("k", k, unit="rad/m")
    ti = check_angle("theta_i", theta_i)
    eps = check_eps(eps)
    if not is_pec(eps):
        ti, eps = np.broadcast_arrays(ti, eps)
    ci = np.cos(ti)
    rh2, rv2, _ = fast_fresnel(eps, ci)
    att = np.exp(-((2.0 * k * rough.sigma * ci) ** 2))
    return np.stack([rh2 * att, rv2 * att])


def slope_variances(
    roughness: Roughness, k_max=None, slope_variance=None, k=None
) -> tuple[float, float]:
    """Per-direction slope variances ``(⟨ζx²⟩, ⟨ζy²⟩)`` [-] (``⟨ζy²⟩ = 0`` for a profile).

    ``slope_variance`` overrides: a float (the per-direction variance, isotropic) or a pair.
    Otherwise ``roughness.mean_square_slope()`` for a differentiable (Gaussian) correlation;
    exponential and power-law correlations have an infinite slope variance and use the
    spectrum below ``k_max`` [rad/m], by default ``2k`` (the spectrum the wave sees,
    :mod:`emscatter.solvers.validity`; ``k`` [rad/m] must then be given).
    """
    if slope_variance is not None:
        sv = np.atleast_1d(check_finite("slope_variance", slope_variance))
        if (
            np.iscomplexobj(sv)
            or sv.ndim != 1
            or sv.size not in (1, 2)
            or np.any(sv.astype(float) <= 0)
        ):
            raise ValueError(
                "slope_variance must be a positive float (per-direction ⟨ζx²⟩ = ⟨ζy²⟩) or a "
                f"pair (⟨ζx²⟩, ⟨ζy²⟩), got {slope_variance!r}"
            )
        sv = sv.astype(float)
        sx = float(sv[0])
        sy = float(sv[-1])
    elif roughness._mss_closed() is not None and k_max is None:
        sx, sy = roughness.mean_square_slope()
    else:
        if k_max is not None:
            k_max = check_positive("k_max", k_max, unit="rad/m")
        elif k is None:
            raise ValueError(
                f"{type(roughness).__name__} has an infinite slope variance: give k_max "
                "[rad/m] (the spectral cutoff) or slope_variance=(⟨ζx²⟩, ⟨ζy²⟩)"
            )
        sx, sy, _ = wave_slope_variances(roughness, k, k_max)
    if roughness.dimension == 1:
        sy = 0.0
    return sx, sy


def smith_lambda(a: np.ndarray) -> np.ndarray:
    """Smith's ``Λ(a) = [exp(−a²)/(a√π) − erfc(a)] / 2`` for Gaussian slopes (Smith 1967,
    IEEE TAP 15, 668; Walter et al. 2007, eq. 27; ``G1 = 1/(1+Λ)``), ``a = cotθ/(√2 s)``.
    ``Λ < 1e-17`` (so ``G1 = 1`` in double precision) for ``a > 6``: not evaluated there."""
    a = np.asarray(a, dtype=float)
    need = a < 6.0
    if a.ndim and need.all():  # near grazing (the angles a validity check is left with)
        an = np.maximum(a, 1e-300)
        lam = 0.5 * (np.exp(-an * an) / (an * math.sqrt(math.pi)) - special.erfc(an))
        return np.maximum(lam, 0.0)
    out = np.zeros(a.shape)
    if np.any(need):
        an = np.maximum(a[need], 1e-300)
        lam = 0.5 * (np.exp(-an * an) / (an * math.sqrt(math.pi)) - special.erfc(an))
        out[need] = np.maximum(lam, 0.0)
    return out


def _a(cos_t, sin_t, s2_dir):
    """``a = cotθ/(√2 s)`` (∞ at θ = 0, 0 at θ = π/2), clipped to [0, 1e300]."""
    den = sin_t * np.sqrt(2.0 * s2_dir)
    big = den > cos_t * 1e-300  # else a ≥ 1e300: no division (a subnormal θ overflowed)
    return np.where(big, cos_t / np.where(big, den, 1.0), 1e300)


def shadowing_factor(g: Local, sx: float, sy: float, mode="direction-correlated") -> np.ndarray:
    """Shadowing/masking factor [-], with Smith's ``Λ(a)`` (Smith 1967) per direction.

    ``"direction-correlated"`` (default): direction-and-height-correlated Smith form
    ``1/(1 + max(Λi, Λs) + λ(ψ) min(Λi, Λs))``, ``λ(ψ) = 4.41ψ/(4.41ψ + 1)`` (Ginneken,
    Stavridi & Koenderink 1998, Appl. Opt. 37, 130; Heitz 2014, JCGT 3(2) §6), ψ the azimuth
    between the directions to the source and to the receiver (renderer frame ``wi``, ``wo``):
    continuous, the monostatic ``1/(1+Λ)`` at backscatter (ψ = 0: one event, not two;
    Sancer 1969; SMRT's ``geometrical_optics_backscatter``), near height-correlated at ψ = π.
    ``"separable"``: ``G1(θi) G1(θs)`` everywhere (Mitsuba 3's microfacet models, Walter et al.
    2007 eqs. 23–27); ``"smith"``: separable, monostatic only in the exact backscatter
    direction (the previous default: a one-point step); ``"correlated"``: height-correlated
    ``1/(1+Λi+Λs)`` (Sancer 1969, IEEE TAP 17, 577; Heitz 2014). The slope variance along each
    direction's azimuth is ``sx cos²φ + sy sin²φ`` (anisotropic Gaussian slopes); for a profile
    it is ``sx``.
    """
    if sy > 0 and sx != sy:
        s2i = sx * np.cos(g.phi_i) ** 2 + sy * np.sin(g.phi_i) ** 2
        s2s = sx * np.cos(g.phi_s) ** 2 + sy * np.sin(g.phi_s) ** 2
    else:
        s2i = s2s = sx
    lam_i = np.broadcast_to(smith_lambda(_a(g.ci, g.si, s2i)), (g.n,))
    lam_s = np.broadcast_to(smith_lambda(_a(g.cs, g.ss, s2s)), (g.n,))
    if mode == "direction-correlated":
        psi = np.arccos(np.clip(-g.cd, -1.0, 1.0))  # φs − (φi + π), folded to [0, π]
        corr = 4.41 * psi / (4.41 * psi + 1.0)
        return 1.0 / (1.0 + np.maximum(lam_i, lam_s) + corr * np.minimum(lam_i, lam_s))
    if mode == "correlated":
        return 1.0 / (1.0 + lam_i + lam_s)
    out = (1.0 / (1.0 + lam_i)) * (1.0 / (1.0 + lam_s))
    if mode == "smith":
        back = is_backscatter(g)
        if np.any(back):
            out = np.where(back, 1.0 / (1.0 + lam_i), out)
    return out


def is_backscatter(g: Local) -> np.ndarray:
    """Exact monostatic directions (``k_s = −k_i``): ``|q|² = 4k²`` to rounding."""
    return np.broadcast_to(g.q2 > 4.0 * (1.0 - 1e-12), (g.n,))


def check_flag(name: str, value) -> bool:
    """A boolean option, or a ValueError naming it."""
    if not isinstance(value, bool | np.bool_):
        raise ValueError(f"{name} must be True or False, got {value!r}")
    return bool(value)


SHADOWING_CHOICES = ("direction-correlated", "separable", "correlated", "smith", False)


def check_shadowing(shadowing_opt) -> str | None:
    """The shadowing mode (:func:`shadowing_factor`): True → ``"direction-correlated"``."""
    if shadowing_opt is True or shadowing_opt == "direction-correlated":
        return "direction-correlated"
    if shadowing_opt is False or shadowing_opt is None:
        return None
    if shadowing_opt in ("correlated", "separable", "smith"):
        return shadowing_opt
    raise ValueError(
        "shadowing must be True/'direction-correlated' (continuous, monostatic at "
        "backscatter), 'separable' (Mitsuba's form), 'correlated' (height-correlated), "
        f"'smith' (separable, monostatic only at exact backscatter) or False/None, "
        f"got {shadowing_opt!r}"
    )


def workers_for(threads, n_chunks: int) -> int:
    """Number of worker threads: ``threads`` (None → CPU count, at most 8, or the cap of
    :func:`emscatter.kernels.default_threads`), ≤ ``n_chunks``."""
    if threads is None:
        from emscatter.kernels import default_threads

        threads = default_threads()
    if isinstance(threads, bool) or not isinstance(threads, int | np.integer) or threads < 1:
        raise ValueError(f"threads must be a positive integer or None, got {threads!r}")
    return int(min(threads, n_chunks))


_SRC_TP = "Ulaby, Moore & Fung 1982 vol. II §12-4, Table 12.2"


def tangent_plane_checks(rough: Roughness, k: float, validity: dict) -> list[Check]:
    """The Kirchhoff tangent-plane criteria shared by GO and PO (Ulaby, Moore & Fung 1982
    vol. II §12-4): ``kℓ ≥ k_l_min`` and radius of curvature ``ℓ² ≥ curvature_factor · σλ``
    with the shorter correlation length."""
    kl = k * min(rough.length, rough.length_y)
    ell2 = min(rough.length, rough.length_y) ** 2
    return [
        lower("k_l", kl, validity["k_l_min"], "kℓ (tangent plane)", _SRC_TP),
        lower(
            "curvature",
            ell2 / (rough.sigma * 2 * math.pi / k),
            validity["curvature_factor"],
            "ℓ²/(σλ) (radius of curvature)",
            _SRC_TP,
        ),
    ]


def illuminated_fraction(theta_i, s2: float) -> np.ndarray:
    """Smith's illuminated fraction ``G1(θi) = 1/(1 + Λ(cotθi/√(2 s2)))`` [-] for the
    per-direction slope variance ``s2`` (Smith 1967)."""
    ti = np.asarray(theta_i, dtype=float)
    s, c = np.sin(ti), np.cos(ti)
    return 1.0 / (1.0 + smith_lambda(_a(c, s, s2)))


def grazing_parameter(theta_i, s2: float) -> np.ndarray:
    """Smith's ``a = cotθi/(√2 s)`` [-] (∞ at normal incidence) for the per-direction slope
    variance ``s2 = s²``."""
    ti = np.asarray(theta_i, dtype=float)
    return _a(np.cos(ti), np.sin(ti), s2)


def shadowing_angle_check(name, theta_i, sx, sy, limit, what, source):
    """Per-angle ``G1(θi) ≥ limit`` with the larger per-direction slope variance (G1 falls as
    θi grows: an ``increasing`` check, decided by a threshold at many angles)."""
    g1 = illuminated_fraction(theta_i, max(sx, sy))
    return angle_lower(name, g1, limit, what, source, increasing=True)


def validity_report(roughness: Roughness, k: float, checks: list[tuple]) -> dict:
    """Compatibility wrapper: a report (:func:`emscatter.solvers.validity.build_report`) from
    ``(name, ok, text[, ratio])`` tuples; prefer :mod:`emscatter.solvers.validity`'s
    ``upper``/``lower`` checks, which also record the value and the limit."""
    out = []
    for c in checks:
        ratio = c[3] if len(c) > 3 else (1.0 if c[1] else math.inf)
        out.append(Check(c[0], bool(c[1]), math.nan, math.nan, float(ratio), c[2]))
    return build_report(roughness, k, out)
