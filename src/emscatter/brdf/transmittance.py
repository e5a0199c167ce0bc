"""The GO transmitted fraction ``T(θi)`` of a rough lossless dielectric, without a BTDF table.

:func:`build_table` caps a dielectric's reflection at ``1 − T`` (the energy remedy of
:mod:`.energy`); it needs ``T`` per incidence node only, not the BTDF, so it is integrated in
slope space (the microfacet normals), where the integrand is a Gaussian times smooth factors:

    T(ωi) = ∫ p(ζ) (i·m)⁺ / (m_z cosθi) · (1 − F(i·m)) · G(i, o(m)) · 1[o_z < 0] d²ζ

with ``ζ = (ζx, ζy)`` the facet slopes, ``p`` the Gaussian slope density of GO (variances
``sx, sy``), ``m ∝ (−ζx, −ζy, 1)`` the facet normal, ``o(m)`` the direction refracted by the
facet (Snell, index ``η = √ε``; total internal reflection gives 0), ``F`` the unpolarized
Fresnel reflectance at the local cosine ``i·m`` and ``G`` Smith's shadowing of
:mod:`emscatter.solvers.kirchhoff.transmission.go` (height-correlated by default, or
separable). This is the BTDF's own albedo ``∫ f_t cosθt dωt`` written over half vectors: the
Jacobian ``dωh/dωo = η²|o·h|/|i + ηo|²`` of Walter, Marschner, Li & Torrance (EGSR 2007,
eq. 17) cancels the BTDF's ``η²|o·h|/|i + ηo|²`` (eq. 21) and leaves Walter's eq. (8) form
``∫ (1 − F) G D(m) (i·m) / cosθi dωm`` with ``D dωm = p(ζ)/m_z d²ζ``.

Quadrature: a Gauss–Hermite product rule in each slope (``n_nodes²`` facets per incidence).
The integrand is discontinuous where a facet turns away from the light (``i·m = 0``), where the
refracted ray leaves the lower hemisphere and at the critical angle (``ε < 1``); these cuts lie
in the Gaussian's tails except near grazing incidence. Error against a 256² rule (ε 2.25,
α = √(2s) 0.1–0.5, 0° ≤ θi ≤ 89°): ≤ 9e-4 with the default 96² for ε > 1, and against the
albedo of a fine BTDF table (0.125° θt, 0.5° Δφ) within 1e-3; for ε < 1 (light inside the
denser medium) the critical-angle cut costs more: 192² gives ≤ 7e-3 (``N_NODES_TIR``).

:func:`transmission_budget` gives :func:`~.build.build_table` its ``T`` per wavelength and
incidence node: for dielectrics (:func:`is_dielectric`: ``Re ε > 0``, ``Im ε ≤ 1e-2 Re ε``,
``ε ≠ 1``; ``T`` of ``Re ε``, a weakly absorbing medium absorbs what enters it) and zero for
conductors (nothing is computed: a conductor table costs what it did).
"""

from __future__ import annotations

import math

import numpy as np
from scipy import special

from ..solvers.kirchhoff.common import _a, fast_fresnel, slope_variances, smith_lambda
from .energy import apply_energy_remedy, record_albedo

__all__ = [
    "go_transmittance",
    "transmission_budget",
    "is_dielectric",
    "remedy_with_transmission",
    "check_transmission",
    "finish_energy",
    "N_NODES",
]

#: Gauss–Hermite nodes per slope axis (ε > 1; ``N_NODES_TIR`` for ε < 1, anisotropic
#: tables ``N_NODES_ANISO`` per (θi, φi) node).
N_NODES = 96
N_NODES_TIR = 192
N_NODES_ANISO = 64
#: ``Im ε / Re ε`` up to which a material counts as a (weakly absorbing) dielectric.
LOSS_TANGENT_MAX = 1e-2
_TRANSMISSION_MODES = (True, "correlated", "separable", False, None)
_CHUNK = 1 << 21  # incidence × facet pairs per block


def _lambda(cos_t, sin_t, phi, sx, sy):
    s2 = sx * np.cos(phi) ** 2 + sy * np.sin(phi) ** 2
    return smith_lambda(_a(cos_t, sin_t, s2))


def go_transmittance(
    eps: float,
    theta_i,
    phi_i=0.0,
    *,
    slope_variance: tuple[float, float],
    shadowing: str | None = "correlated",
    n_nodes: int = N_NODES,
) -> np.ndarray:
    """``T`` [-] (the transmitted fraction of the incident power) at incidence ``theta_i``,
    ``phi_i`` [rad] (broadcast) for a real ``eps`` (> 0, ≠ 1) and GO slope variances
    ``(sx, sy)`` (module docstring); ``shadowing``: ``"correlated"``, ``"separable"`` or None."""
    e = float(eps)
    sx, sy = (float(v) for v in slope_variance)
    ti, pi_ = np.broadcast_arrays(np.asarray(theta_i, float), np.asarray(phi_i, float))
    shape = ti.shape
    ti, pi_ = ti.reshape(-1), pi_.reshape(-1)
    x, w = special.roots_hermite(int(n_nodes))
    w = w / math.sqrt(math.pi)
    zx = (math.sqrt(2 * sx) * x)[:, None] * np.ones(x.size)[None, :]
    zy = np.ones(x.size)[:, None] * (math.sqrt(2 * sy) * x)[None, :]
    ww = (w[:, None] * w[None, :]).reshape(-1)
    norm = np.sqrt(1.0 + zx * zx + zy * zy).reshape(-1)
    mx, my, mz = -zx.reshape(-1) / norm, -zy.reshape(-1) / norm, 1.0 / norm
    eta = math.sqrt(e)
    out = np.empty(ti.size)
    step = max(1, _CHUNK // ww.size)
    for a in range(0, ti.size, step):  # blocks of incidence nodes (memory), not single angles
        t, p = ti[a : a + step, None], pi_[a : a + step, None]
        st, ct = np.sin(t), np.cos(t)
        ix, iy, iz = -st * np.cos(p), -st * np.sin(p), ct  # i = −k̂_i, towards the light
        ci = ix * mx + iy * my + iz * mz
        lit = ci > 0
        cl = np.clip(ci, 0.0, 1.0)
        rh2, rv2, _ = fast_fresnel(e, cl, cross=False)
        k2 = 1.0 - (1.0 - cl * cl) / e  # cos² of the refracted angle at the facet
        ok = lit & (k2 > 0)
        c2 = np.sqrt(np.maximum(k2, 0.0))
        r = 1.0 / eta
        fac = r * cl - c2  # k̂_t = r k̂_i + (r cosθ1 − cosθ2) m
        oz = -r * iz + fac * mz
        ok &= oz < 0
        val = np.where(ok, cl / (mz * ct) * (1.0 - 0.5 * (rh2 + rv2)), 0.0)
        if shadowing is not None:
            ox, oy = -r * ix + fac * mx, -r * iy + fac * my
            ctt = np.clip(-oz, 0.0, 1.0)
            stt = np.sqrt(np.maximum(1.0 - ctt * ctt, 0.0))
            lam_i = _lambda(ct, st, p, sx, sy)
            lam_o = _lambda(ctt, stt, np.arctan2(oy, ox), sx, sy)
            if shadowing == "separable":
                g = 1.0 / ((1.0 + lam_i) * (1.0 + lam_o))
            else:  # height-correlated B(1 + Λi, 1 + Λo), Heitz 2014 eq. 102
                g = np.exp(
                    special.gammaln(1 + lam_i) + special.gammaln(1 + lam_o)
                    - special.gammaln(2 + lam_i + lam_o)
                )  # fmt: skip
            val = np.where(ok, val * g, 0.0)
        out[a : a + step] = val @ ww
    return np.clip(out, 0.0, 1.0).reshape(shape)


def is_dielectric(eps) -> bool:
    """A material whose transmission :func:`build_table` counts: ``Re ε > 0``, ``ε ≠ 1`` and
    ``Im ε ≤ LOSS_TANGENT_MAX · Re ε`` (not PEC, not a conductor or a strong absorber)."""
    if isinstance(eps, str):
        return False
    e = complex(eps)
    return e.real > 0 and e.real != 1.0 and e.imag <= LOSS_TANGENT_MAX * e.real


def transmission_budget(rough, setups, theta, phi, options) -> tuple[np.ndarray, dict]:
    """``T`` (``(n_wl, n_θ)``, or ``(n_wl, n_θ, n_φ)`` with ``phi`` renderer φ nodes [rad] of an
    anisotropic table) for ``setups = [(λ [m], ε, solver), ...]`` and a record for
    ``metadata["energy"]``. ``options``: the build's solver options (``slope_variance``,
    ``k_max`` and a transmission ``shadowing`` mode are used, other values ignored)."""
    shape = (len(setups), theta.size) + (() if phi is None else (phi.size,))
    t = np.zeros(shape)
    shadow = options.get("shadowing", True)
    if not any(shadow is m or shadow == m for m in _TRANSMISSION_MODES):
        shadow = True  # a reflection-only form ("smith", ...): the BTDF's default
    mode = {True: "correlated", False: None, None: None}.get(shadow, shadow)
    counted = []
    for j, (lam, eps, _) in enumerate(setups):
        if not is_dielectric(eps):
            continue
        e = float(np.real(eps))
        sv = slope_variances(
            rough, options.get("k_max"), options.get("slope_variance"), k=2 * math.pi / lam
        )
        counted.append(float(lam))
        if phi is None:
            n = N_NODES if e > 1 else N_NODES_TIR
            t[j] = go_transmittance(e, theta, slope_variance=sv, shadowing=mode, n_nodes=n)
        else:  # T(φ) = T(−φ) = T(π − φ) for centred Gaussian slopes: each folded φ once
            fold = np.round(np.abs(np.angle(np.exp(1j * phi))), 12)
            fold = np.minimum(fold, math.pi - fold)
            uniq, back = np.unique(fold, return_inverse=True)
            vals = go_transmittance(
                e, theta[:, None], uniq[None, :], slope_variance=sv, shadowing=mode,
                n_nodes=N_NODES_ANISO,
            )  # fmt: skip
            t[j] = vals[:, back]
    record = {
        "transmission": "GO transmitted fraction T(theta_i) of Re eps (Walter et al. 2007 "
        "microfacet refraction, Gauss-Hermite slope quadrature) for dielectric wavelengths; "
        "0 for conductors",
        "transmission_wavelengths": counted,
        "transmission_shadowing": mode,
    }
    return t, record


def remedy_with_transmission(table, rough, setups, theta, phi, options, transmission):
    """``table`` with the energy remedy of :mod:`.energy` capping the reflection at ``1 − T``:
    ``transmission`` ``"auto"`` (:func:`transmission_budget`), ``"off"`` (``R ≤ 1`` only), an
    array of ``T`` broadcasting to ``(n_wl, n_θ[, n_φ])`` or a :class:`~.btdf_table.BtdfTable`
    (its albedo, interpolated in θi). Where the coherent lobe alone leaves less than ``T``
    (PO near grazing) ``T`` is lowered to ``1 − R_coh``: recorded in ``metadata["energy"]``
    (``transmission_clipped``), the BTDF then needs :func:`~.btdf_table.cap_energy`."""
    record = {}
    if isinstance(transmission, str):
        if transmission == "off":
            return apply_energy_remedy(table)
        t, record = transmission_budget(rough, setups, theta, phi, options)
    elif hasattr(transmission, "albedo") and hasattr(transmission, "theta_t"):
        if not np.allclose(transmission.wavelengths, table.wavelengths, rtol=1e-12):
            raise ValueError(
                "transmission: the BTDF table's wavelengths "
                f"{transmission.wavelengths.tolist()} m differ from the BRDF's "
                f"{table.wavelengths.tolist()} m"
            )
        if phi is not None:
            raise ValueError("transmission: a BtdfTable is isotropic; this table is not")
        alb = transmission.albedo()
        t = np.stack([np.interp(theta, transmission.theta_i, row) for row in alb])
        record = {"transmission": "albedo of the given BtdfTable"}
    else:
        t = np.asarray(transmission, dtype=float)
        record = {"transmission": "given per node"}
    coh = np.asarray(table.coherent, dtype=float)
    t = np.broadcast_to(t, coh.shape) if t.ndim else np.full(coh.shape, float(t))
    room = np.maximum(1.0 - coh - 1e-9, 0.0)
    clipped = t > room
    t_used = np.where(clipped, room, t)
    out = apply_energy_remedy(table, transmission=t_used)
    energy = dict(out.metadata["energy"], **record)
    energy["T"] = np.asarray(t_used).tolist()
    energy["transmission_clipped"] = int(clipped.sum())
    out.metadata["energy"] = energy
    return out


def check_transmission(transmission) -> None:
    """Refuse a ``transmission=`` string other than ``"auto"`` / ``"off"`` (arrays and
    :class:`~.btdf_table.BtdfTable` objects are checked where they are used)."""
    if isinstance(transmission, str) and transmission not in ("auto", "off"):
        raise ValueError(
            f"transmission must be 'auto', 'off', a BtdfTable or T per node, got {transmission!r}"
        )


def finish_energy(table, energy, transmission, rough, setups, theta, phi, options):
    """The built table after its energy step: ``energy="rescale"`` the remedy capped at
    ``1 − T`` (:func:`remedy_with_transmission`), ``"off"`` only the albedo recorded."""
    if energy == "rescale":
        return remedy_with_transmission(table, rough, setups, theta, phi, options, transmission)
    return record_albedo(table, "off")
