"""Porous, wet and polluted surfaces: the seed's chapter 4 as a transform of a BrdfTable.

After Mérillou, Dischler & Ghazanfarpour, "A BRDF post-process to integrate porosity on rendered
surfaces", IEEE TVCG 6 (2000) 306, as the seed thesis writes it (§4.3 eqs. 4.1–4.3, §4.4 eq. 4.4,
§4.5 eq. 4.5, §4.6 eqs. 4.6–4.7) and implements it (Annexe A, pixel shaders A.1 and A.3).

The seed post-processes a BRDF split as ``f_r = k_s F_s + k_d F_d``. Here:

* the table is the whole specular part, ``k_s F_s = T`` (its incoherent ``values`` and its
  coherent delta lobe ``coherent``), and ``k_s`` is the table's own reflectance: by default its
  bihemispherical albedo per wavelength (cosine-weighted mean of the directional albedo over θi),
  one number per wavelength so that the transform stays reciprocal; a user value overrides it;
* ``F_d = 1/π`` (Lambertian), ``k_d`` a user albedo (default 0, per wavelength allowed); the
  shaders' ``diff = N·L`` is exactly ``k_d F_d`` with ``F_d = 1/π`` once the cosine is taken out.

The output table (same axes) is

``f = (1 − α G_p) T + k_d,poro / π``                                 (seed §4.3, shader A.1)

``k_d,poro = k_d (1 − α G_p) + (k_d + k_s) α G_p (1 − A_p) (1 − P) + k_d,f α G_p P``   (4.4)

``R_coh = (1 − α G_p) R_coh,T + k_s,f α G_p P``  (the foreign material's mirror, eq. 4.7)

with the pore filling ``P`` (0 = empty pores: the generic model of §4.3) and a foreign material
of diffuse albedo ``k_d,f`` and mirror reflectance ``k_s,f``;

``G_p = c_i/(c_i − k c_i + k) · c_o/(c_o − k c_o + k)``, ``k = √(2m²/π)``, ``c = cosθ``   (4.1)

``A_p = k_a (1 − (1 − k_a)^{n_b}) / (1 − (1 − k_a)) = 1 − (1 − k_a)^{n_b}``,
``k_a = 1 − k_s − k_d``                                                               (4.2)

``n_b = s_p [3.7 − 2 ((θi + θo)/2 − 2π/(s_p + 6))²]``                                 (4.3)

Readings taken where the printed text and the shader differ (the shader is what made the seed's
figures):

* eq. 4.1: ``k = √(2m²/π)`` (shader), not ``2m²/π`` (text): it is Schlick's (1994) approximation
  of Smith's masking for a Beckmann surface of rms slope ``m``; ``2m²/π`` has the wrong dimension
  for that fit.
* eq. 4.3: the bracket is squared (shader). ``−2 (x − x₀)²`` is a parabola with its vertex at
  ``x₀ = 2π/(s_p + 6)``; unsquared, the shift ``x₀`` would only add a constant to 3.7, so writing
  it at all means the square. For ``s_p ∈ [1, 10]`` (the shader's range) ``n_b > 0`` everywhere.
* §4.3: ``k_s,poro = k_s (1 − α G_p)`` and ``k_d,poro = k_d (1 − α G_p A_p) + k_s α G_p (1 − A_p)``
  (shader); the text swaps the two labels, which would contradict its own principles (specular
  light entering a pore leaves it diffuse) and eq. 4.4 at ``P = 0``.
* eq. 4.4–4.5: the foreign material's diffuse term is ``k_d,f α G_p P``, without the text's
  ``(1 − A_p)`` (shader A.3): a filled pore has no depth left to lose light in, and the text's own
  check "with P = 1 the model becomes a simple linear combination in α of the chosen BRDF" holds
  only without it.
* eq. 4.7: water in the pores is "close to a perfect mirror" (seed §4.6; shader A.1 reflects the
  environment map): its specular term goes into the table's coherent (delta) lobe, with water's
  Fresnel reflectance at θi by default (``ks_water="fresnel"``, n = 1.333).

Energy: the transform never caps. If a parameter choice gives a directional albedo above 1 at any
node, or ``k_s + k_d > 1`` (a negative absorption ``k_a``), it raises ``ValueError`` naming the
parameters and the node: a capped table would no longer be the seed's model.
"""

from __future__ import annotations

import math

import numpy as np

from . import grid
from .table import BrdfTable

__all__ = [
    "PLUGIN_PARAMS",
    "WATER_N",
    "from_plugin_params",
    "fill_fraction",
    "polluted",
    "pore_bounces",
    "pore_loss",
    "pore_masking",
    "porous",
    "water_fresnel",
    "wet",
]

#: Refractive index of water in the visible (used for the wet pores' mirror Fresnel term).
WATER_N = 1.333

_ALBEDO_TOL = 1e-9


def pore_masking(theta_i, theta_o, m):
    """Pore shadowing/masking ``G_p`` [-] (seed eq. 4.1, shader A.1): Schlick's Smith form with
    ``k = √(2m²/π)``; ``theta_i``, ``theta_o`` [rad] in ``[0, π/2)``, ``m`` rms slope [-]."""
    k = math.sqrt(2.0 * m * m / math.pi)
    ci, co = np.cos(theta_i), np.cos(theta_o)
    return ci / (ci - k * ci + k) * (co / (co - k * co + k))


def pore_bounces(theta_i, theta_o, pore_shape):
    """Mean number of bounces in a pore ``n_b`` [-] (seed eq. 4.3, squared bracket as in the
    shader); ``pore_shape`` s_p = depth / diameter of the mean pore."""
    x = 0.5 * (np.asarray(theta_i) + np.asarray(theta_o)) - 2.0 * math.pi / (pore_shape + 6.0)
    return pore_shape * (3.7 - 2.0 * x * x)


def pore_loss(ka, n_b):
    """Light lost in a pore ``A_p`` [-] (seed eq. 4.2): the absorbed fraction after ``n_b``
    bounces of absorption ``k_a``; ``k_a (1−(1−k_a)^n)/(1−(1−k_a))`` written as ``1 − (1−k_a)^n``
    (equal for ``k_a > 0``; the limit 0 at ``k_a = 0``)."""
    return 1.0 - np.power(1.0 - np.asarray(ka, dtype=float), n_b)


def _check_unit(name, value, n_wl, *, low=0.0, high=1.0):
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 0:
        arr = np.full(n_wl, float(arr))
    if arr.shape != (n_wl,):
        raise ValueError(f"{name} must be a number or one per wavelength ({n_wl}), got {value!r}")
    if not np.all(np.isfinite(arr)) or np.any(arr < low) or np.any(arr > high):
        raise ValueError(f"{name} must lie in [{low}, {high}], got {value!r}")
    return arr


def _bihemispherical(table: BrdfTable) -> np.ndarray:
    """Cosine-weighted mean over θi (and φi) of the directional albedo (+ coherent), per λ."""
    a = table.albedo().total
    w = 2.0 * grid.theta_weights(table.theta_i)  # Σ w = 1: 2∫ cosθ sinθ dθ
    if table.isotropic:
        return a @ w
    wp = grid.periodic_weights(table.phi_i)
    return np.einsum("wia,i,a->w", a, w, wp / wp.sum())


def porous(
    table: BrdfTable,
    alpha: float,
    *,
    pore_shape: float = 2.0,
    m: float = 0.08,
    kd=0.0,
    ks=None,
    filling: float = 0.0,
    kd_foreign=0.0,
    ks_foreign=0.0,
) -> BrdfTable:
    """The seed's porosity post-process (module docstring, eqs. 4.1–4.4) applied to ``table``.

    Parameters
    ----------
    alpha : porosity α_poro ∈ [0, 1], the fraction of the surface covered by pores.
    pore_shape : s_p ∈ [1, 10], mean pore depth / diameter (seed and shader default 2).
    m : rms slope of the surface for the pore masking G_p, ∈ [0, 1] (shader A.1: 0.08).
    kd : Lambertian albedo k_d of the base material (number or one per wavelength), ∈ [0, 1].
    ks : the specular part's reflectance k_s; None → the table's bihemispherical albedo per λ.
    filling : P_rem ∈ [0, 1], the filled fraction of the mean pore's volume.
    kd_foreign, ks_foreign : the foreign material's diffuse albedo and mirror reflectance
        (numbers or one per wavelength; ks_foreign may also be an array ``(n_wl, n_ti)`` or, with
        polarization, ``(2, n_wl, n_ti)`` for h, v — isotropic tables).

    Returns a new BrdfTable on the same axes; ``alpha = 0`` with ``kd = 0`` returns values equal
    to the input bit for bit. Raises ``ValueError`` for out-of-range parameters or when the result's
    directional albedo exceeds 1 at a node.
    """
    if not isinstance(table, BrdfTable):
        raise TypeError(f"table must be a BrdfTable, got {type(table).__name__}")
    n_wl = table.wavelengths.size
    for name, val, lo, hi in (
        ("alpha", alpha, 0.0, 1.0),
        ("pore_shape", pore_shape, 1.0, 10.0),
        ("m", m, 0.0, 1.0),
        ("filling", filling, 0.0, 1.0),
    ):
        if not isinstance(val, (int, float)) or not math.isfinite(val) or not lo <= val <= hi:
            raise ValueError(f"{name} must be a number in [{lo}, {hi}], got {val!r}")
    kd_w = _check_unit("kd", kd, n_wl)
    kdf_w = _check_unit("kd_foreign", kd_foreign, n_wl)
    ks_w = _bihemispherical(table) if ks is None else _check_unit("ks", ks, n_wl)
    ka = 1.0 - ks_w - kd_w
    if np.any(ka < -1e-12):
        w = int(np.argmax(-ka))
        raise ValueError(
            f"ks + kd must be ≤ 1 (the pore absorption k_a = 1 − ks − kd ≥ 0, seed eq. 4.2); got "
            f"ks = {ks_w[w]:.6g} ({'table albedo' if ks is None else 'given'}) + kd = "
            f"{kd_w[w]:.6g} at λ = {table.wavelengths[w]:.6g} m: lower kd"
        )
    ka = np.clip(ka, 0.0, 1.0)
    iso = table.isotropic
    ti, to = table.theta_i, table.theta_o
    gp = pore_masking(ti[:, None], to[None, :], m)  # (n_ti, n_to)
    nb = pore_bounces(ti[:, None], to[None, :], pore_shape)
    ap = pore_loss(ka[:, None, None], nb[None])  # (n_wl, n_ti, n_to)
    ag = alpha * gp
    kd_poro = (
        kd_w[:, None, None] * (1.0 - ag)
        + (kd_w + ks_w)[:, None, None] * ag * (1.0 - ap) * (1.0 - filling)
        + kdf_w[:, None, None] * ag * filling
    )  # (n_wl, n_ti, n_to)
    spec = 1.0 - ag
    if iso:
        spec_g, diff_g = spec[None, :, :, None], kd_poro[..., None] / math.pi
    else:
        spec_g, diff_g = spec[None, :, None, :, None], kd_poro[:, :, None, :, None] / math.pi
    values = table.values * spec_g + diff_g
    polarized = None
    if table.polarized is not None:
        polarized = table.polarized * spec_g[None, None] + 0.5 * diff_g[None, None]
    # coherent (mirror) lobe: θo = θi
    ag_m = alpha * pore_masking(ti, ti, m)  # (n_ti,)
    ksf = _foreign_mirror(ks_foreign, n_wl, ti.size)  # (2, n_wl, n_ti)
    add = ksf * (ag_m * filling)[None, None]
    if iso:
        coh_pol = table.coherent_polarized * (1.0 - ag_m) + add
        coh = table.coherent * (1.0 - ag_m) + add.mean(axis=0)
    else:
        coh_pol = table.coherent_polarized * (1.0 - ag_m)[:, None] + add[..., None]
        coh = table.coherent * (1.0 - ag_m)[:, None] + add.mean(axis=0)[..., None]
    meta = dict(table.metadata)
    meta["porosity"] = {
        "model": "Mérillou, Dischler & Ghazanfarpour, IEEE TVCG 6 (2000); seed ch. 4, Annexe A",
        "alpha": float(alpha),
        "pore_shape": float(pore_shape),
        "m": float(m),
        "kd": kd_w.tolist(),
        "ks": ks_w.tolist(),
        "ks_source": "table bihemispherical albedo" if ks is None else "given",
        "filling": float(filling),
        "kd_foreign": kdf_w.tolist(),
    }
    out = table.replace(
        values=values.astype(table.values.dtype, copy=False),
        polarized=None if polarized is None else polarized.astype(table.polarized.dtype),
        coherent=coh,
        coherent_polarized=coh_pol,
        metadata=meta,
    )
    _check_energy(out, alpha, pore_shape, m, kd_w, ks_w, filling, kdf_w)
    return out


def _foreign_mirror(ks_foreign, n_wl, n_ti) -> np.ndarray:
    arr = np.asarray(ks_foreign, dtype=float)
    if arr.ndim <= 1:
        arr = _check_unit("ks_foreign", arr, n_wl)[:, None] * np.ones(n_ti)
    if arr.shape == (n_wl, n_ti):
        arr = np.stack([arr, arr])
    if arr.shape != (2, n_wl, n_ti) or not np.all(np.isfinite(arr)):
        raise ValueError(
            f"ks_foreign must be a number, one per wavelength, or (2,) {n_wl}×{n_ti}, got shape "
            f"{arr.shape}"
        )
    if np.any(arr < 0) or np.any(arr > 1):
        raise ValueError("ks_foreign must lie in [0, 1]")
    return arr


def _check_energy(out, alpha, pore_shape, m, kd_w, ks_w, filling, kdf_w) -> None:
    tot = out.albedo().total
    if np.any(tot > 1.0 + _ALBEDO_TOL):
        idx = np.unravel_index(int(np.argmax(tot)), tot.shape)
        w, i = idx[0], idx[1]
        raise ValueError(
            f"porosity parameters give a directional albedo {tot[idx]:.6g} > 1 at "
            f"λ = {out.wavelengths[w]:.6g} m, θi = {math.degrees(out.theta_i[i]):.4g}°: "
            f"alpha = {alpha}, pore_shape = {pore_shape}, m = {m}, kd = {kd_w[w]:.6g}, "
            f"ks = {ks_w[w]:.6g}, filling = {filling}, kd_foreign = {kdf_w[w]:.6g}; "
            "lower kd (or kd_foreign)"
        )


def water_fresnel(theta_i, n: float = WATER_N) -> np.ndarray:
    """Water's mirror reflectance ``(R_h, R_v)`` [-] at ``theta_i`` [rad] (Fresnel, real index)."""
    from ..fresnel import reflectivity

    return reflectivity(complex(n * n), np.asarray(theta_i, dtype=float))


def wet(table: BrdfTable, alpha: float, wetness: float, *, ks_water="fresnel", **kw) -> BrdfTable:
    """Wet porous surface (seed §4.6, eqs. 4.6–4.7, shader A.1): pores filled with water to
    ``wetness`` = Δt/t_fill ∈ [0, 1]; the water is a mirror of reflectance ``ks_water``
    (``"fresnel"``: water's h/v Fresnel at each θi node, :data:`WATER_N`; or a number). The pores'
    diffuse contribution fades with the filling: the surface gets darker and more specular.
    Other keywords as :func:`porous` (``kd``, ``ks``, ``pore_shape``, ``m``)."""
    if isinstance(ks_water, str):
        if ks_water != "fresnel":
            raise ValueError(f"ks_water must be 'fresnel' or a number in [0, 1], got {ks_water!r}")
        if not table.isotropic:
            raise ValueError("ks_water='fresnel' needs an isotropic table; give a number")
        r = water_fresnel(table.theta_i)  # (2, n_ti)
        ks_water = np.repeat(r[:, None, :], table.wavelengths.size, axis=1)
    return porous(table, alpha, filling=wetness, kd_foreign=0.0, ks_foreign=ks_water, **kw)


def fill_fraction(t: float, t0: float = 0.0, t_fill: float = 0.3) -> float:
    """``P = clamp((t − t0)/t_fill, 0, 1)`` (seed §4.5.2 and the Δt table of §4.6.1); t_fill = 0
    fills at once (a step at t0)."""
    for name, val in (("t", t), ("t0", t0), ("t_fill", t_fill)):
        if not isinstance(val, (int, float)) or not math.isfinite(val):
            raise ValueError(f"{name} must be a finite number, got {val!r}")
    if t_fill < 0:
        raise ValueError(f"t_fill must be ≥ 0, got {t_fill!r}")
    if t_fill == 0:
        return 1.0 if t >= t0 else 0.0
    return min(1.0, max(0.0, (t - t0) / t_fill))


def polluted(
    table: BrdfTable,
    alpha: float,
    t: float,
    *,
    t0: float = 0.0,
    t_fill: float = 0.3,
    kd_pollution=0.08,
    **kw,
) -> BrdfTable:
    """Pores filled by carbon deposit over time (seed §4.5.2, eq. 4.5, shader A.3): filling
    ``P = clamp((t − t0)/t_fill, 0, 1)``; the deposit is purely diffuse with albedo
    ``kd_pollution`` (shader A.3's black zone: 0.8 × 0.1 = 0.08). The surface darkens with ``t``
    and faster with ``alpha``. Other keywords as :func:`porous`."""
    p = fill_fraction(t, t0, t_fill)
    return porous(table, alpha, filling=p, kd_foreign=kd_pollution, ks_foreign=0.0, **kw)


#: Parameters of the Mitsuba plugin ``"emscatter"`` that apply this transform at load time.
PLUGIN_PARAMS = (
    "porosity",
    "pore_shape",
    "pore_slope",
    "diffuse_albedo",
    "specular_albedo",
    "wetness",
    "pollution_time",
    "pollution_fill_time",
    "pollution_albedo",
)


def from_plugin_params(table: BrdfTable, params: dict) -> BrdfTable:
    """The transform the plugin parameters ask for (names in :data:`PLUGIN_PARAMS`): ``porosity``
    α (required once any is given), ``pore_shape`` s_p, ``pore_slope`` m, ``diffuse_albedo`` k_d,
    ``specular_albedo`` k_s (default: the table's own albedo, :func:`porous`),
    and either ``wetness`` (:func:`wet`) or ``pollution_time`` with ``pollution_fill_time`` and
    ``pollution_albedo`` (:func:`polluted`, t0 = 0), or neither (:func:`porous`)."""
    unknown = sorted(set(params) - set(PLUGIN_PARAMS))
    if unknown:
        raise ValueError(f"unknown porosity parameters {unknown}; allowed: {list(PLUGIN_PARAMS)}")
    if "porosity" not in params:
        raise ValueError(f"give 'porosity' (α ∈ [0, 1]) with {sorted(params)}")
    p = {k: float(v) for k, v in params.items()}
    kw = {
        "pore_shape": p.get("pore_shape", 2.0),
        "m": p.get("pore_slope", 0.08),
        "kd": p.get("diffuse_albedo", 0.0),
    }
    if "specular_albedo" in p:
        kw["ks"] = p["specular_albedo"]
    if "wetness" in p and "pollution_time" in p:
        raise ValueError("give 'wetness' or 'pollution_time', not both")
    if "wetness" in p:
        return wet(table, p["porosity"], p["wetness"], **kw)
    if "pollution_time" in p:
        return polluted(
            table,
            p["porosity"],
            p["pollution_time"],
            t_fill=p.get("pollution_fill_time", 0.3),
            kd_pollution=p.get("pollution_albedo", 0.08),
            **kw,
        )
    if "pollution_fill_time" in p or "pollution_albedo" in p:
        raise ValueError("'pollution_fill_time' and 'pollution_albedo' need 'pollution_time'")
    return porous(table, p["porosity"], **kw)
