"""Sionna RT's built-in scattering parameters fitted to emscatter's tables, for users who cannot
ship the emscatter material (other ray tracers, other Sionna versions, GPU pipelines).

Sionna's model (Degli-Esposti et al., IEEE TAP 55 (2007) 143; Sionna RT "Scattering" docs): a
reflected ray of Fresnel (or slab) coefficient ``R`` keeps ``√(1 − S²) R`` specularly and sends
``S² Γ² f_s(k̂i, k̂s)`` per steradian diffusely (``Γ² = |R|²``, ``∫ f_s dΩ = 1``); the diffuse
field's polarization is rotated by the cross-polarization matrix ``[[√(1−K_x), −√K_x],
[√K_x, √(1−K_x)]]``. The lobes ``f_s``: Lambertian ``cosθs/π``, ``DirectivePattern(α_R)``
``∝ ((1 + k̂r·k̂s)/2)^α_R`` and ``BackscatteringPattern(α_R, α_I, Λ)`` (k̂r: the specular
direction; α integers ≥ 1).

From :class:`~emscatter.radio.tables.RadioTables` (coherent power ``|r_coh|²``, incoherent
reflectivity ``r_incoh``, the lobe ``σ⁰/(4π cosθi)`` [1/sr] per ``[pol_s, pol_i]``), per incidence
angle θi and summed over polarizations (Sionna's S is one number for both):

* ``S(θi)² = r_incoh / (|r_coh|² + r_incoh)`` — the diffusely scattered share of reflected power;
* the lobe: the emscatter lobe normalized to ``∫ f dΩ = 1``; each built-in pattern is normalized
  on the same quadrature and the **misplaced power** ``½ ∫ |f_emscatter − f_s| dΩ`` (the share of
  diffuse power the built-in sends into the wrong directions, 0…1) is minimized over its integers;
* ``K_x(θi) = (∫ lobe_vh + ∫ lobe_hv) / (r_incoh,h + r_incoh,v)``, the cross-polarized share of
  diffuse power; XPD = ``10 log10((1 − K_x)/K_x)`` [dB];
* the **reflected-power error** ``10 log10((|r_coh|² + r_incoh) / |R_Fresnel|²)`` [dB]: the S model
  conserves ``|R|²`` and cannot lose reflected power, emscatter's rough face sends that power into
  the medium (transmission and absorption). Where it exceeds ``transmission_tolerance_db`` in the
  fitted angle range, no built-in model can stand in and the result says so (``"valid": False``,
  ``"flags"``).

* the **diffuse polarization error** ``10 log10(S² |R_p|² / r_incoh,p)`` [dB] per incident
  polarization: Sionna scatters ``S² Γ²`` with Fresnel's h/v ratio, emscatter another (first-order
  small-perturbation lobes put more into v than h). Beyond ``polarization_tolerance_db`` at the
  fit angle it is flagged too: one S cannot serve both polarizations (the error grows towards
  Brewster's angle, where ``|R_v|² → 0``; its worst value in range is reported).

One set of built-in values (what Sionna takes) is fitted at ``fit_angle_deg`` (S, K_x) and over
the angle range (the lobe's integers: least mean misplaced power); the per-angle values and their
spread are reported beside it. :func:`builtin_equivalent` returns plain JSON types;
:func:`write_json` and :func:`read_json` store and read them (atomic write, schema checked).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from .. import io
from ..fresnel import fresnel_cos
from .convention import sionna_eps_conductivity
from .medium import real_number
from .tables import RadioTables, lobe_directions

__all__ = [
    "SCHEMA",
    "builtin_equivalent",
    "lobe_weights",
    "pattern_values",
    "sionna_material_kwargs",
    "write_json",
    "read_json",
]

SCHEMA = "emscatter.builtin_equivalent/1"
PATTERNS = ("directive", "lambertian", "backscattering")
_ALPHA_I = (1, 2, 3, 5, 8, 12, 20, 30, 50)
_LAMBDAS = tuple(np.round(np.arange(0.5, 1.0001, 0.05), 2))


def lobe_weights(tables: RadioTables) -> np.ndarray:
    """Quadrature weights ``dΩ`` [sr] of the lobe grid, shape ``(n_theta, n_alpha, n_s)``, both
    azimuth halves included: ``Σ w · lobe`` is the tables' ``r_incoh`` per channel (the rule of
    :mod:`emscatter.radio.tables`: trapezoid in ``s`` and ``α``, the grazing edge node left out)."""
    p0 = np.sin(tables.theta_nodes)[:, None, None]
    a = tables.alpha_nodes[None, :, None]
    s = tables.s_nodes[None, None, :]
    q = tables.grading
    rmax = -p0 * np.cos(a) + np.sqrt(np.maximum(1.0 - (p0 * np.sin(a)) ** 2, 0.0))
    rho = rmax * s**q
    drho = rmax * q * s ** (q - 1.0)
    px, py = p0 + rho * np.cos(a), rho * np.sin(a)
    cos_s = np.sqrt(np.maximum(1.0 - px * px - py * py, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        jac = np.where(cos_s > 1e-9, rho * drho / cos_s, 0.0)
    ws = np.full(tables.s_nodes.size, tables.s_nodes[1] - tables.s_nodes[0])
    ws[0] *= 0.5
    ws[-1] = 0.0
    wa = np.full(tables.alpha_nodes.size, tables.alpha_nodes[1] - tables.alpha_nodes[0])
    wa[[0, -1]] *= 0.5
    return 2.0 * jac * wa[None, :, None] * ws[None, None, :]


def _cosines(tables: RadioTables, idx):
    """``cos ψ_r = k̂r·k̂s`` and ``cos ψ_i = −k̂i·k̂s`` on the lobe grid at θ indices ``idx``."""
    th = tables.theta_nodes[idx]
    ts, ps = lobe_directions(th, tables.alpha_nodes, tables.s_nodes, tables.grading)
    ko = np.stack([np.sin(ts) * np.cos(ps), np.sin(ts) * np.sin(ps), np.cos(ts)])
    si, ci = np.sin(th)[:, None, None], np.cos(th)[:, None, None]
    cos_r = si * ko[0] + ci * ko[2]  # k̂r = (sinθi, 0, cosθi)
    cos_i = -(si * ko[0] - ci * ko[2])  # k̂i = (sinθi, 0, −cosθi)
    return cos_r, cos_i, ko[2]


def pattern_values(tables: RadioTables, idx, name: str, **params) -> np.ndarray:
    """A built-in pattern on the lobe grid at θ indices ``idx``, normalized to ``∫ f dΩ = 1`` on
    the grid's quadrature (:func:`lobe_weights`) [1/sr]. ``name``: ``"lambertian"``,
    ``"directive"`` (``alpha_r``) or ``"backscattering"`` (``alpha_r, alpha_i, lambda_``)."""
    cos_r, cos_i, cos_s = _cosines(tables, idx)
    if name == "lambertian":
        f = cos_s / math.pi
    elif name == "directive":
        f = (0.5 * (1.0 + cos_r)) ** int(params["alpha_r"])
    elif name == "backscattering":
        lam = float(params["lambda_"])
        f = lam * (0.5 * (1.0 + cos_r)) ** int(params["alpha_r"]) + (1.0 - lam) * (
            0.5 * (1.0 + cos_i)
        ) ** int(params["alpha_i"])
    else:
        raise ValueError(f"pattern must be one of {PATTERNS}, got {name!r}")
    w = lobe_weights(tables)[idx]
    norm = np.einsum("tas,tas->t", f, w)
    return f / norm[:, None, None]


def _misplaced(f_ref, f_fit, w):
    """``½ Σ w |f_ref − f_fit|`` per leading index (both normalized on ``w``)."""
    return 0.5 * np.einsum("...tas,tas->...t", np.abs(f_ref - f_fit), w)


def _fit_lobe(tables, idx, f_em, w, alpha_max):
    """Best integers of each pattern (least mean misplaced power over ``idx``) and the
    per-angle best ``α_R`` of the directive pattern."""
    cos_r, cos_i, cos_s = _cosines(tables, idx)
    alphas = np.arange(1, alpha_max + 1)
    base_r = 0.5 * (1.0 + cos_r)
    mis = np.empty((alphas.size, idx.size))
    vr = {}
    for j, a in enumerate(alphas):  # over integers, each step vectorized over all angles
        f = base_r**a
        f = f / np.einsum("tas,tas->t", f, w)[:, None, None]
        mis[j] = _misplaced(f_em, f, w)
        vr[int(a)] = f
    j = int(np.argmin(mis.mean(axis=1)))
    out = {
        "directive": {
            "params": {"alpha_r": int(alphas[j])},
            "misplaced": mis[j],
        }
    }
    lam_f = cos_s / math.pi
    lam_f = lam_f / np.einsum("tas,tas->t", lam_f, w)[:, None, None]
    out["lambertian"] = {"params": {}, "misplaced": _misplaced(f_em, lam_f, w)}
    # backscattering: α_R near the directive optimum, α_I and Λ on coarse grids
    best = (math.inf, None, None)
    base_i = 0.5 * (1.0 + cos_i)
    near = sorted({int(a) for a in np.unique(np.round(alphas[j] * np.geomspace(0.5, 2.0, 7)))})
    near = [a for a in near if 1 <= a <= alpha_max]
    for ai in _ALPHA_I:
        gi = base_i**ai
        fi_norm = np.einsum("tas,tas->t", gi, w)
        for ar in near:
            gr = vr.get(ar)
            if gr is None:
                gr = base_r**ar
                gr = gr / np.einsum("tas,tas->t", gr, w)[:, None, None]
            # Sionna: f = (Λ v_r + (1−Λ) v_i) / (Λ F_r + (1−Λ) F_i); vr[ar] holds v_r / F_r
            fr_norm = np.einsum("tas,tas->t", base_r**ar, w)
            for lam in _LAMBDAS:
                num = lam * gr * fr_norm[:, None, None] + (1.0 - lam) * gi
                den = (lam * fr_norm + (1.0 - lam) * fi_norm)[:, None, None]
                m = _misplaced(f_em, num / den, w)
                if m.mean() < best[0]:
                    best = (float(m.mean()), {"alpha_r": ar, "alpha_i": ai, "lambda_": lam}, m)
    out["backscattering"] = {"params": best[1], "misplaced": best[2]}
    per_angle_alpha = alphas[np.argmin(mis, axis=0)]
    return out, per_angle_alpha


def builtin_equivalent(
    spec,
    frequency: float,
    *,
    fit_angle_deg: float = 45.0,
    angle_range_deg: tuple[float, float] = (30.0, 60.0),
    alpha_max: int = 200,
    transmission_tolerance_db: float = 0.5,
    polarization_tolerance_db: float = 1.0,
    tables: RadioTables | None = None,
) -> dict:
    """Sionna's built-in parameters equivalent to ``spec`` (a
    :class:`~emscatter.radio.MaterialSpec`) at ``frequency`` [Hz] (module docstring).

    Returns a JSON-ready dict: ``schema``, ``frequency_hz``, the medium as Sionna takes it
    (``relative_permittivity``, ``conductivity`` [S/m], ``thickness`` [m]),
    ``scattering_coefficient`` S, ``xpd_coefficient`` K_x and ``xpd_db`` at ``fit_angle_deg``,
    ``scattering_pattern``
    (``{"name", params}``, the pattern with the least mean misplaced power over
    ``angle_range_deg``), ``patterns`` (every pattern's fit), ``per_angle`` (θ [deg], S, S_h, S_v,
    K_x, best α_R, misplaced power, reflected-power and per-polarization diffuse errors [dB]),
    ``error`` (misplaced power at the fit angle and worst in range, S spread in range, worst
    reflected-power and diffuse polarization errors), ``valid``
    and ``flags`` (why no built-in model stands in, when it does not), and the emscatter
    ``method`` that made the tables. ``alpha_max`` bounds the lobes' integers α_R (Sionna's
    normalization sums ``α`` terms per ray: large values cost time there)."""
    if not all(hasattr(spec, a) for a in ("tables", "material", "surface", "thickness")):
        raise TypeError(f"spec must be a radio.MaterialSpec, got {type(spec).__name__}")
    frequency = real_number("frequency", frequency)
    if not frequency > 0:
        raise ValueError(f"frequency must be > 0 Hz, got {frequency!r}")
    fit_angle_deg = real_number("fit_angle_deg", fit_angle_deg)
    lo, hi = (real_number("angle_range_deg", x) for x in angle_range_deg)
    if not 0.0 <= lo < hi < 90.0 or not lo <= fit_angle_deg <= hi:
        raise ValueError(
            f"angle_range_deg must satisfy 0 <= low < high < 90 with fit_angle_deg inside, got "
            f"{angle_range_deg!r} and fit_angle_deg={fit_angle_deg!r}"
        )
    if isinstance(alpha_max, bool) or not isinstance(alpha_max, int) or alpha_max < 1:
        raise ValueError(f"alpha_max must be an integer >= 1, got {alpha_max!r}")
    tol = real_number("transmission_tolerance_db", transmission_tolerance_db)
    pol_tol = real_number("polarization_tolerance_db", polarization_tolerance_db)
    for pname, v in (("transmission_tolerance_db", tol), ("polarization_tolerance_db", pol_tol)):
        if not v > 0:
            raise ValueError(f"{pname} must be > 0 dB, got {v!r}")
    tab = tables if tables is not None else spec.tables(frequency, label="builtin-fit")
    eps = complex(spec.material().eps(frequency=frequency))
    er, sig = sionna_eps_conductivity(eps, frequency)
    th_deg = np.degrees(tab.theta_nodes)
    idx = np.flatnonzero((th_deg >= lo - 1e-9) & (th_deg <= hi + 1e-9))
    if idx.size < 2:
        raise ValueError(
            f"angle_range_deg {angle_range_deg!r} holds {idx.size} table angle(s); widen it or "
            "refine TableOptions.n_theta"
        )
    base = {
        "schema": SCHEMA,
        "frequency_hz": frequency,
        "medium": str(spec.medium if spec.medium is not None else "eps/conductivity"),
        "roughness": None if spec.surface is None else repr(spec.surface),
        "relative_permittivity": er,
        "conductivity": sig,
        "thickness": spec.thickness,
        "method": tab.method,
        "emscatter_valid": bool(tab.valid),
        "fit_angle_deg": fit_angle_deg,
        "angle_range_deg": [lo, hi],
    }
    cp, inc = tab.coherent_power, tab.incoherent  # (2, n_theta)
    rh, rv = fresnel_cos(eps, np.cos(tab.theta_nodes))
    fres = np.abs(rh) ** 2 + np.abs(rv) ** 2
    refl = cp.sum(axis=0) + inc.sum(axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        s2 = np.where(refl > 0, inc.sum(axis=0) / refl, 0.0)
        s2_p = np.where(cp + inc > 0, inc / (cp + inc), 0.0)
        err_db = 10.0 * np.log10(refl / fres)
    # Sionna's diffuse power per incident polarization is S² |R_p|² (its XPD matrix is unitary)
    fres_p = np.stack([np.abs(rh) ** 2, np.abs(rv) ** 2])
    with np.errstate(divide="ignore", invalid="ignore"):
        pol_db = 10.0 * np.log10((s2 * fres_p) / inc)
    pol_db = np.where(np.isfinite(pol_db), pol_db, 0.0)
    w = lobe_weights(tab)
    ch = np.einsum("tasc,tas->ct", tab.lobe, w)  # (4, n_theta) per [pol_s, pol_i] channel
    with np.errstate(divide="ignore", invalid="ignore"):
        kx = np.where(ch.sum(axis=0) > 0, (ch[1] + ch[2]) / ch.sum(axis=0), 0.0)
    per = {
        "theta_deg": th_deg[idx].tolist(),
        "S": np.sqrt(s2[idx]).tolist(),
        "S_h": np.sqrt(s2_p[0, idx]).tolist(),
        "S_v": np.sqrt(s2_p[1, idx]).tolist(),
        "xpd_coefficient": kx[idx].tolist(),
        "reflected_power_error_db": err_db[idx].tolist(),
        "diffuse_error_db_h": pol_db[0, idx].tolist(),
        "diffuse_error_db_v": pol_db[1, idx].tolist(),
    }

    def at_fit(x):
        return float(np.interp(fit_angle_deg, th_deg, x))

    s_fit = math.sqrt(max(at_fit(s2), 0.0))
    kx_fit = min(max(at_fit(kx), 0.0), 1.0)
    flags = []
    if not tab.valid:
        flags.append(
            f"emscatter's method {tab.method!r} is outside its validity range here: "
            + "; ".join(tab.reasons)
        )
    worst_db = float(np.max(np.abs(err_db[idx])))
    if worst_db > tol:
        k = idx[int(np.argmax(np.abs(err_db[idx])))]
        flags.append(
            f"reflected power differs from Fresnel by {err_db[k]:+.2f} dB at θi = {th_deg[k]:.0f}° "
            f"(> {tol:g} dB): emscatter's rough face sends that power into the medium "
            "(transmission, absorption), which the built-in S model (it conserves |R|²) cannot "
            "represent; "
            "no built-in model stands in here — ship the emscatter material"
        )
    pol_fit = np.array([np.interp(fit_angle_deg, th_deg, pol_db[p]) for p in (0, 1)])
    worst_pol = float(np.max(np.abs(pol_fit))) if np.any(inc[:, idx] > 0) else 0.0
    if worst_pol > pol_tol:
        p = int(np.argmax(np.abs(pol_fit)))
        flags.append(
            f"diffuse power of incident {'hv'[p]} differs by {pol_fit[p]:+.2f} dB at the fit angle "
            f"θi = {fit_angle_deg:g}° (> {pol_tol:g} dB): the built-in model scatters S² |R_p|² "
            "per polarization (Fresnel's h/v ratio), emscatter's rough face another ratio "
            "(e.g. small-perturbation lobes, v above h); no single S stands in for both"
        )
    result = {
        **base,
        "scattering_coefficient": s_fit,
        "xpd_coefficient": kx_fit,
        "xpd_db": (
            10.0 * math.log10((1.0 - kx_fit) / kx_fit)
            if 0.0 < kx_fit < 1.0
            else (math.inf if kx_fit == 0.0 else -math.inf)
        ),  # fmt: skip
        "per_angle": per,
    }
    if tab.flat or not np.any(inc[:, idx] > 0):
        result.update(
            scattering_pattern={"name": "lambertian"},
            patterns={},
            error={"lobe_misplaced_at_fit": 0.0, "lobe_misplaced_max": 0.0, "S_spread": 0.0,
                   "reflected_power_error_db_max": worst_db,
                   "diffuse_polarization_error_db_at_fit": worst_pol},
            valid=not flags, flags=flags,
        )  # fmt: skip
        per["alpha_r"], per["lobe_misplaced"] = [], []
        result["xpd_db"] = None if not math.isfinite(result["xpd_db"]) else result["xpd_db"]
        return result
    lobe = tab.lobe[idx]
    tot = lobe.sum(axis=-1)  # both incident pols, all scattered pols
    f_em = tot / np.einsum("tas,tas->t", tot, w[idx])[:, None, None]
    fits, alpha_per = _fit_lobe(tab, idx, f_em, w[idx], alpha_max)
    name = min(fits, key=lambda n: float(np.mean(fits[n]["misplaced"])))
    mis = fits[name]["misplaced"]
    th_i = th_deg[idx]
    per["alpha_r"] = alpha_per.tolist()
    per["lobe_misplaced"] = mis.tolist()
    result.update(
        scattering_pattern={"name": name, **fits[name]["params"]},
        patterns={
            n: {
                **v["params"],
                "misplaced_mean": float(np.mean(v["misplaced"])),
                "misplaced_max": float(np.max(v["misplaced"])),
            }
            for n, v in fits.items()
        },  # fmt: skip
        error={
            "lobe_misplaced_at_fit": float(np.interp(fit_angle_deg, th_i, mis)),
            "lobe_misplaced_max": float(np.max(mis)),
            "S_spread": float(np.ptp(np.sqrt(s2[idx]))),
            "reflected_power_error_db_max": worst_db,
            "diffuse_polarization_error_db_at_fit": worst_pol,
            "diffuse_polarization_error_db_max": float(np.max(np.abs(pol_db[:, idx]))),
        },
        valid=not flags,
        flags=flags,
    )
    if not math.isfinite(result["xpd_db"]):
        result["xpd_db"] = None
    return result


def sionna_material_kwargs(eq: dict) -> dict:
    """Keyword arguments of ``sionna.rt.RadioMaterial(name, **kwargs)`` for a fit of
    :func:`builtin_equivalent` (the pattern's integers included)."""
    pat = dict(eq["scattering_pattern"])
    kw = {
        "relative_permittivity": float(eq["relative_permittivity"]),
        "conductivity": float(eq["conductivity"]),
        "scattering_coefficient": float(eq["scattering_coefficient"]),
        "xpd_coefficient": float(eq["xpd_coefficient"]),
        "scattering_pattern": pat.pop("name"),
        **pat,
    }
    if eq.get("thickness") is not None:
        kw["thickness"] = float(eq["thickness"])
    return kw


def write_json(path, fits) -> Path:
    """Write one fit or a list of fits as JSON (atomic); returns the path."""
    items = fits if isinstance(fits, list) else [fits]
    for i, f in enumerate(items):
        if not isinstance(f, dict) or f.get("schema") != SCHEMA:
            raise ValueError(f"fits[{i}] is not a builtin_equivalent result (schema {SCHEMA!r})")
    return io.write_json(Path(path), {"schema": SCHEMA, "materials": items})


def read_json(path) -> list[dict]:
    """The fits written by :func:`write_json` (schema checked)."""
    data = json.loads(Path(path).read_text())
    if not isinstance(data, dict) or data.get("schema") != SCHEMA:
        raise ValueError(f"{path}: not an emscatter built-in equivalent file (schema {SCHEMA!r})")
    return list(data["materials"])
