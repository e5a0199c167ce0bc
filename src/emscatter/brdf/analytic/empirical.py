"""The rest of the seed's chapter-2 catalogue of empirical BRDFs, on the footing of
:mod:`emscatter.brdf.analytic` (renderer frame, ``wi``/``wo`` unit vectors ``(..., 3)``
pointing away from the surface, normal ``+z``, tangent ``+x``; ``f_r`` [1/sr], 0 below the
horizon; vectorized over directions).

* :func:`lafortune` — generalized cosine lobes ``Σ_k [C_x wi_x wo_x + C_y wi_y wo_y +
  C_z wi_z wo_z]^{n_k}`` (Lafortune, Foo, Torrance & Greenberg, "Non-linear approximation
  of reflectance functions", SIGGRAPH 1997; the seed's §2.6.2 "function family" model);
  :func:`lafortune_phong_lobe` gives the lobe equal to the normalized Phong lobe.
* :func:`strauss` — Strauss 1990 (IEEE CG&A 10(6), 56–64; seed §2.5.4, eqs. 2.25–2.29):
  smoothness ``s``, metalness ``m``, transparency ``t``, colour ``c``.
* :func:`neumann` — the compact metallic models of Neumann, Neumann & Szirmay-Kalos 1999
  (Computer Graphics Forum 18(3), 161–172; seed §2.5.5, eq. 2.30): a Phong or Blinn lobe over
  ``max(cosθi, cosθo)``, reciprocal, with a constant that bounds the albedo by 1.
* :func:`~.cylinders.poulin_fournier` — Poulin & Fournier 1990's parallel cylinders (seed
  §2.6.1), single scattering with exact 2-D shadowing and masking.
* :func:`~.htsg.htsg` — He, Torrance, Sillion & Greenberg 1991 (seed §2.3.2), Kirchhoff wave
  optics with shadowing and an effective roughness; emscatter's PO when both are off.
* :func:`~.stam.stam` — Stam 1999's diffraction shader for a Gaussian surface (seed §2.3.3),
  anisotropic ``(τ_x, τ_y)``; HTSG without shadowing and effective roughness.
* :func:`evaluate` — any catalogue model (these and the ones of :mod:`.analytic`) by name;
  :func:`equivalent_beckmann` — the chapter-3 "general roughness" of each model (its Beckmann
  ``m``, by :mod:`.equivalence`'s criterion).

Properties (tested in ``tests/test_brdf_catalogue.py``, tabulated in
``validation/brdf/catalogue.md``):

* Lafortune — reciprocal (the lobe sum is symmetric in ``wi``, ``wo``). Albedo ≤ 1 for the
  Phong-shaped lobe ``−C_x = −C_y = C_z``, ``C_z^n ≤ (n+2)/(2π)``; the model has no energy
  bound: off-specular lobes ``|C_x| = |C_y| = r C_z``, ``r > 1`` keep the normal-incidence
  albedo and exceed 1 toward grazing (``n = 20``: ``r = 1.05`` → 1.10 at 30°, ``r = 1.2`` →
  7.5 at 60°).
* Strauss — not reciprocal (``F(θi)``, ``c_s(θi)`` and ``1/cosθi`` depend on the incidence
  alone). Albedo ≤ 1 on the tested grid for a coloured (``c = 0.2``) or half-transparent
  (``t = 0.5``) surface up to 89°, and for any ``c``, ``t`` with ``s ≥ 0.3`` up to 60°. The
  model breaks it for a white opaque surface toward grazing (``s = 0.05``: 1.009 at 75°;
  ``s = 0.3``: 1.35, ``s = 0.6``: 1.54 at 89°): the diffuse ``(1 − ms)(1 − s³)`` and specular
  ``r_s`` are not bounded jointly, and ``Q_s/(π cosθi)`` has no ``cosθi`` to cancel.
* Neumann et al. (NNSK) — reciprocal; albedo ≤ 1 for every ``n`` and direction when
  ``k_s + k_d ≤ 1`` (proof in :func:`neumann`).
* Poulin–Fournier 1990 (seed §2.6.1, :mod:`.cylinders`) — reciprocal; albedo ≤ ``k_s + k_d``
  (single scattering over the lit, visible profile).
"""

from __future__ import annotations

import math

import numpy as np

from emscatter.brdf.analytic import (
    _dot,
    _fresnel,
    _upper,
    ashikhmin_shirley,
    blinn_phong,
    cook_torrance,
    half_vector,
    phong,
    ward,
)
from emscatter.brdf.analytic.cylinders import poulin_fournier, poulin_fournier_rms_slope
from emscatter.brdf.analytic.equivalence import (
    Equivalence,
    ashikhmin_from_ward,
    beckmann_from_blinn,
    beckmann_from_phong,
    blinn_from_beckmann,
    phong_from_beckmann,
)
from emscatter.brdf.analytic.htsg import htsg, htsg_equivalent_beckmann
from emscatter.brdf.analytic.stam import stam, stam_equivalent_beckmann
from emscatter.conventions import check_in_range, check_positive

__all__ = [
    "lafortune",
    "lafortune_phong_lobe",
    "strauss",
    "strauss_fresnel",
    "strauss_shadow",
    "strauss_exponent",
    "neumann",
    "MODELS",
    "RECIPROCAL",
    "evaluate",
    "equivalent_beckmann",
    "from_beckmann",
]

INV_PI = 1.0 / math.pi


def _lobes(lobes) -> np.ndarray:
    arr = np.asarray(lobes, dtype=float)
    if arr.ndim == 1:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != 4 or arr.shape[0] == 0:
        raise ValueError(
            "lobes must be (C_x, C_y, C_z, n) or a (K, 4) array of such rows, "
            f"got shape {np.shape(lobes)}"
        )
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"lobes must be finite, got {arr.tolist()}")
    if np.any(arr[:, 3] <= 0):
        raise ValueError(f"lobe exponents n (column 4) must be > 0, got {arr[:, 3].tolist()}")
    return arr


def lafortune_phong_lobe(n: float, rho: float = 1.0) -> tuple[float, float, float, float]:
    """The lobe ``(C_x, C_y, C_z, n)`` with ``−C_x = −C_y = C_z = (ρ (n+2)/(2π))^{1/n}``:
    Lafortune's specular lobe equal to the normalized Phong ``ρ (n+2)/(2π) cosⁿα`` (α from
    the mirror direction; :func:`emscatter.brdf.analytic.phong`), albedo ``ρ`` at normal
    incidence (Lafortune et al. 1997: −C_x = −C_y > C_z gives off-specular lobes,
    ``C_x = C_y > 0`` retro-reflection)."""
    n = check_positive("n", n)
    rho = check_in_range("rho", rho, 0.0, 1.0, low_open=False, high_open=False)
    c = (rho * (n + 2.0) / (2.0 * math.pi)) ** (1.0 / n)
    return (-c, -c, c, n)


def lafortune(wi, wo, lobes, *, kd: float = 0.0) -> np.ndarray:
    """Lafortune et al. 1997: ``f = k_d/π + Σ_k max(0, C_x,k wi_x wo_x + C_y,k wi_y wo_y
    + C_z,k wi_z wo_z)^{n_k}`` [1/sr]. ``lobes``: one ``(C_x, C_y, C_z, n)`` or a ``(K, 4)``
    array (``C`` absorbs the lobe's albedo, as in the paper; ``n > 0``). Reciprocal by
    construction. The model has no energy constraint: a lobe's albedo at normal incidence is
    ``C_z^n 2π/(n+2)`` and grows toward grazing when ``|C_x|`` or ``|C_y|`` exceed ``C_z``
    (off-specular lobes) — :func:`emscatter.brdf.analytic.directional_albedo` checks it."""
    arr = _lobes(lobes)
    kd = check_in_range("kd", kd, 0.0, 1.0, low_open=False, high_open=False)
    wi, wo, up = _upper(wi, wo)
    prod = wi * wo
    f = np.full(up.shape, kd * INV_PI)
    for cx, cy, cz, n in arr:  # a few lobes; every direction pair at once
        d = cx * prod[..., 0] + cy * prod[..., 1] + cz * prod[..., 2]
        f = f + np.maximum(d, 0.0) ** n
    return np.where(up, f, 0.0)


def strauss_fresnel(x, kf: float = 1.12) -> np.ndarray:
    """Strauss's Fresnel-like ``F(x) = (1/(x−k_f)² − 1/k_f²)/(1/(1−k_f)² − 1/k_f²)`` (seed eq.
    2.28) of the normalized angle ``x = θ/(π/2) ∈ [0, 1]``: ``F(0) = 0``, ``F(1) = 1``."""
    x = np.asarray(x, dtype=float)
    return (1 / (x - kf) ** 2 - 1 / kf**2) / (1 / (1 - kf) ** 2 - 1 / kf**2)


def strauss_shadow(x, kg: float = 1.01) -> np.ndarray:
    """Strauss's shadowing ``G(x) = (1/(1−k_g)² − 1/(x−k_g)²)/(1/(1−k_g)² − 1/k_g²)`` (seed
    eq. 2.29) of ``x = θ/(π/2)``: ``G(0) = 1``, ``G(1) = 0``."""
    x = np.asarray(x, dtype=float)
    return (1 / (1 - kg) ** 2 - 1 / (x - kg) ** 2) / (1 / (1 - kg) ** 2 - 1 / kg**2)


def strauss_exponent(s: float) -> float:
    """Strauss's Phong exponent ``h = 3/(1 − s)`` (seed eq. 2.27) for smoothness ``s ∈ [0, 1)``."""
    s = check_in_range("s", s, 0.0, 1.0, low_open=False, high_open=True)
    return 3.0 / (1.0 - s)


def strauss(
    wi,
    wo,
    s: float,
    *,
    m: float = 0.0,
    t: float = 0.0,
    color: float = 1.0,
    kf: float = 1.12,
    kg: float = 1.01,
    kj: float = 0.1,
) -> np.ndarray:
    """Strauss 1990 (seed eqs. 2.25–2.29) as a BRDF [1/sr]: smoothness ``s ∈ [0, 1)``,
    metalness ``m ∈ [0, 1]``, transparency ``t ∈ [0, 1]``, surface colour ``color ∈ [0, 1]``
    (one channel), Strauss's constants ``k_f = 1.12``, ``k_g = 1.01``, ``k_j = 0.1``.

    Strauss gives reflected intensities per unit irradiance, ``Q_d = cosθi d r_d c`` with
    ``d = 1 − m s``, ``r_d = (1 − s³)(1 − t)``, and ``Q_s = (R·V)^h r_s c_s`` with
    ``h = 3/(1 − s)``, ``r_n = (1 − t) − r_d``, ``j = F(θi) G(θi) G(θo)``,
    ``r_s = min(1, r_n + (r_n + k_j) j)``, ``c_s = 1 + m (1 − F(θi)) (c − 1)`` (``R`` the
    mirror of ``wi``; ``F``, ``G`` of ``θ/(π/2)``: :func:`strauss_fresnel`,
    :func:`strauss_shadow`). Here ``f = (Q_d + Q_s)/(π cosθi)``, so that the diffuse part is
    Lambertian with albedo ``d r_d c``. Not reciprocal (``F(θi)``, ``c_s`` and the
    ``1/cosθi`` depend on the incidence alone; Strauss designed it for direct lighting). The
    seed prints ``ρ_s = −(R·V)^h …`` with Strauss's incident vector pointing *toward* the
    surface; with both vectors pointing away it is ``+(R·V)^h``."""
    h = strauss_exponent(s)
    m = check_in_range("m", m, 0.0, 1.0, low_open=False, high_open=False)
    t = check_in_range("t", t, 0.0, 1.0, low_open=False, high_open=False)
    c = check_in_range("color", color, 0.0, 1.0, low_open=False, high_open=False)
    kf = check_in_range("kf", kf, 1.0, math.inf)
    kg = check_in_range("kg", kg, 1.0, math.inf)
    kj = check_in_range("kj", kj, 0.0, math.inf, low_open=False)
    wi, wo, up = _upper(wi, wo)
    ci, co = np.clip(wi[..., 2], 0, 1), np.clip(wo[..., 2], 0, 1)
    xi = np.arccos(ci) / (0.5 * math.pi)
    xo = np.arccos(co) / (0.5 * math.pi)
    rd = (1.0 - s**3) * (1.0 - t)
    qd = ci * (1.0 - m * s) * rd * c
    fi = strauss_fresnel(xi, kf)
    rn = (1.0 - t) - rd
    j = fi * strauss_shadow(xi, kg) * strauss_shadow(xo, kg)
    rs = np.minimum(1.0, rn + (rn + kj) * j)
    cs = 1.0 + m * (1.0 - fi) * (c - 1.0)
    r = wi * np.array([-1.0, -1.0, 1.0])
    qs = np.clip(_dot(r, wo), 0.0, 1.0) ** h * rs * cs
    den = math.pi * np.where(up, ci, 1.0)
    return np.where(up, (qd + qs) / den, 0.0)


def neumann(
    wi,
    wo,
    n: float,
    *,
    variant: str = "blinn",
    ks: float = 1.0,
    kd: float = 0.0,
    eps=None,
    f0: float | None = None,
) -> np.ndarray:
    """Neumann, Neumann & Szirmay-Kalos 1999's compact metallic BRDF (seed eq. 2.30)
    ``f = k_s C_n F(wi·h) L / max(cosθi, cosθo) + k_d/π`` [1/sr], with the lobe ``L`` Blinn's
    ``(N·H)ⁿ`` (``variant="blinn"``, the seed's form) or Phong's ``max(0, R·V)ⁿ``
    (``"phong"``); ``F`` from a permittivity ``eps`` (or ``"pec"``), Schlick's ``f0``, or 1.

    Reciprocal (``max`` and ``wi·h = wo·h`` are symmetric). ``C_n`` is the constant that makes
    the albedo ≤ 1 for every ``n`` and direction: since ``cosθo/max(cosθi, cosθo) ≤ 1`` and
    ``F ≤ 1``, the specular albedo is at most ``C_n ∫ L dωo``; for Phong that is
    ``C_n 2π/(n+1)``, so ``C_n = (n+1)/(2π)``; for Blinn ``dωo = 4 (wi·h) dωh ≤ 4 dωh`` gives
    ``C_n 8π/(n+1)``, so ``C_n = (n+1)/(8π)`` (NNSK 1999's point: the ``max`` denominator
    keeps the metallic brightening at grazing angles while staying energy conserving). The
    albedo at normal incidence is then ``(n+1)/(n+2)`` (Phong) and tends to 1 for large ``n``.
    ``k_s + k_d ≤ 1`` is required for the total albedo ≤ 1."""
    n = check_positive("n", n)
    ks = check_in_range("ks", ks, 0.0, 1.0, low_open=False, high_open=False)
    kd = check_in_range("kd", kd, 0.0, 1.0, low_open=False, high_open=False)
    if ks + kd > 1.0 + 1e-12:
        raise ValueError(f"ks + kd must be ≤ 1 for energy conservation, got {ks + kd:g}")
    if variant not in ("blinn", "phong"):
        raise ValueError(f"variant must be 'blinn' or 'phong', got {variant!r}")
    wi, wo, up = _upper(wi, wo)
    h = half_vector(wi, wo)
    if variant == "blinn":
        lobe = (n + 1.0) / (8.0 * math.pi) * np.clip(h[..., 2], 0.0, 1.0) ** n
    else:
        r = wi * np.array([-1.0, -1.0, 1.0])
        lobe = (n + 1.0) / (2.0 * math.pi) * np.clip(_dot(r, wo), 0.0, 1.0) ** n
    den = np.maximum(np.maximum(wi[..., 2], wo[..., 2]), 1e-300)
    spec = lobe * _fresnel(np.clip(_dot(wi, h), 0, 1), eps, f0) / den
    return np.where(up, ks * spec + kd * INV_PI, 0.0)


#: every catalogue model by name (chapter 2 of the seed); ``evaluate(name, wi, wo, **params)``
MODELS = {
    "cook-torrance": cook_torrance,
    "ward": ward,
    "phong": phong,
    "blinn-phong": blinn_phong,
    "ashikhmin-shirley": ashikhmin_shirley,
    "lafortune": lafortune,
    "strauss": strauss,
    "neumann": neumann,
    "poulin-fournier": poulin_fournier,
    "htsg": htsg,
    "stam": stam,
}

#: whether ``f(wi, wo) = f(wo, wi)`` holds for the model (tested both ways)
RECIPROCAL = {
    "cook-torrance": True,
    "ward": True,
    "phong": True,
    "blinn-phong": True,
    "ashikhmin-shirley": True,
    "lafortune": True,
    "strauss": False,  # F(θi), c_s(θi) and 1/cosθi: Strauss 1990 is a direct-lighting model
    "neumann": True,
    "poulin-fournier": True,
    "htsg": True,
    "stam": True,
}


def evaluate(model: str, wi, wo, **params) -> np.ndarray:
    """``f_r(wi, wo)`` [1/sr] of the catalogue model ``model`` (a key of :data:`MODELS`)."""
    if model not in MODELS:
        raise ValueError(f"model must be one of {sorted(MODELS)}, got {model!r}")
    return MODELS[model](wi, wo, **params)


def equivalent_beckmann(model: str, **params) -> Equivalence:
    """The seed's chapter-3 "general roughness" of a catalogue model: the Beckmann rms slope
    ``m`` whose distribution ``exp(−tan²γ/m²)/cos⁴γ`` is closest to the model's lobe, by the
    criterion of :data:`~.equivalence.FIT_CRITERION` (Table 3.1's roughness column):

    * ``phong`` (``n``), ``neumann`` with ``variant="phong"``, ``lafortune`` (a lobe's ``n``;
      its ``(R·V)ⁿ`` shape for ``−C_x = −C_y = C_z``), ``strauss`` (``h = 3/(1 − s)``, Table
      3.1's ``(R·V)^h``) — the Phong equivalence;
    * ``blinn-phong`` and ``neumann`` (Blinn variant, ``n``) — the Blinn equivalence.

    ``lafortune`` takes ``lobes`` and uses the first lobe (it must be Phong-shaped:
    ``−C_x = −C_y = C_z``); ``ward``/``cook-torrance`` are Beckmann already; for
    ``ashikhmin-shirley`` use :func:`~.equivalence.ashikhmin_from_ward`; ``poulin-fournier``
    (``d``, ``h``) returns the anisotropic ``(m_x, m_y) = (rms slope across the cylinders, 0)``
    of its profile (exact, ``error = 0``; :func:`~.cylinders.poulin_fournier_rms_slope`);
    ``htsg`` (``sigma0``, ``tau``, optional ``wavelength``) returns ``m = 2σ₀/τ`` or the fit
    to its lobe at that wavelength (:func:`~.htsg.htsg_equivalent_beckmann`)."""
    if model == "htsg":
        return htsg_equivalent_beckmann(
            params["sigma0"], params["tau"], wavelength=params.get("wavelength")
        )
    if model == "stam":
        return stam_equivalent_beckmann(params["sigma"], params["tau_x"], params.get("tau_y"))
    if model == "poulin-fournier":
        mx = poulin_fournier_rms_slope(params.get("d", 2.5), params.get("h", -0.3))
        return Equivalence((mx, 0.0), 0.0, "rms slope of the cylinder profile (seed eq. 3.1)")
    if model in ("phong", "strauss", "lafortune") or (
        model == "neumann" and params.get("variant", "blinn") == "phong"
    ):
        if model == "strauss":
            n = strauss_exponent(params["s"])
        elif model == "lafortune":
            cx, cy, cz, n = _lobes(params["lobes"])[0]
            if not (np.isclose(-cx, cz) and np.isclose(-cy, cz) and cz > 0):
                raise ValueError(
                    "the Beckmann equivalence of a Lafortune lobe needs a Phong-shaped lobe "
                    f"-C_x = -C_y = C_z > 0, got ({cx:g}, {cy:g}, {cz:g})"
                )
        else:
            n = params["n"]
        return beckmann_from_phong(n)
    if model in ("blinn-phong", "neumann"):
        return beckmann_from_blinn(params["n"])
    raise ValueError(
        f"equivalent_beckmann takes one of ['blinn-phong', 'htsg', 'lafortune', 'neumann', "
        f"'phong', 'poulin-fournier', 'stam', 'strauss'], got {model!r} (ward and "
        "cook-torrance are Beckmann; for ashikhmin-shirley use equivalence.ashikhmin_from_ward)"
    )


def from_beckmann(model: str, m: float, **params) -> dict:
    """The inverse: the model's roughness parameters equivalent to Beckmann ``m`` (same
    criterion), e.g. ``{"s": …}`` for Strauss (``s = 1 − 3/n``, ``n`` the Phong equivalent;
    ``s`` clipped at 0 when ``n < 3``: Strauss's lobe cannot be wider than ``(R·V)³``),
    ``{"n": …}`` for Phong/Blinn/NNSK, ``{"lobes": …}`` for Lafortune (``rho`` in params),
    ``{"nu", "nv"}`` for Ashikhmin–Shirley from ``(m, m_y)``, plus ``"error"``."""
    m = check_positive("m", m)
    if model in ("phong", "strauss", "lafortune") or (
        model == "neumann" and params.get("variant", "blinn") == "phong"
    ):
        eq = phong_from_beckmann(m)
        if model == "strauss":
            return {"s": max(0.0, 1.0 - 3.0 / eq.value), "error": eq.error}
        if model == "lafortune":
            lobe = lafortune_phong_lobe(eq.value, params.get("rho", 1.0))
            return {"lobes": [lobe], "error": eq.error}
        return {"n": eq.value, "error": eq.error}
    if model in ("blinn-phong", "neumann"):
        eq = blinn_from_beckmann(m)
        return {"n": eq.value, "error": eq.error}
    if model == "ashikhmin-shirley":
        eq = ashikhmin_from_ward(m, params.get("m_y", m), ratio=params.get("ratio", "slope"))
        return {"nu": eq.value[0], "nv": eq.value[1], "error": eq.error}
    raise ValueError(
        f"from_beckmann takes one of ['ashikhmin-shirley', 'blinn-phong', 'lafortune', "
        f"'neumann', 'phong', 'strauss'], got {model!r}"
    )
