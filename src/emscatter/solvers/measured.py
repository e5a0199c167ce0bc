"""Measured accuracy of auto's candidates: the validity maps as a lookup for ``method="auto"``.

The validity criteria of each solver (``check_validity``) are limits from the literature and
from the maps; near their edges, and where no method is valid, they cannot say which model is
closest to the exact answer. The validity maps (validation/validity_maps: 1-D method of
moments, θi = 20°, kσ ∈ [0.05, 3] × kℓ ∈ [0.5, 20], Gaussian and exponential correlation,
perfect conductor and ε = 3) measure it. :func:`measured_errors` returns, for a roughness in
that box, the measured σ⁰ error [dB] (larger of h and v; rms over 10° bins of θs ∈ [−60°, 60°])
of every candidate at the nearest map cell, from the map of the same correlation and medium
class (``"conductor"``: PEC, Re ε < 0 or ``|ε| ≥ 100``; ``"dielectric"`` otherwise).
:func:`emscatter.solvers.select.rank_methods` uses it to correct the criteria's ranking
(its docstring says how).

The table is ``emscatter/solvers/data/measured_errors.json``, written from the maps by
:func:`emscatter.validation.measured_table.write_measured` (the command is in
validation/validity_maps/README.md). Outside the box, for other spectra (power law, band-limited,
anisotropic) or media of unknown class the lookup returns ``None`` and the criteria decide.

**3-D cells** (:func:`measured_errors_3d`): the 3-D method of moments' validation cells
(validation/mom3d/pec_table.py: 2-D PEC surfaces, Gaussian θi ∈ {20°, 40°}, kσ ∈ {0.1, 0.3,
1}, kℓ ∈ {3, 7}; exponential band-limited at K_c = 2k on 12 points/λ, θi ∈ {20°, 40°},
kσ ∈ {0.1, 0.3}, kℓ ∈ {3, 7}, map ``pec3d_exp``; validation/mom3d/dielectric_table.py:
ε = 4 + 0.5i, θi ∈ {20°, 40°}, kσ ∈ {0.1, 0.3, 1}, kℓ = 3) measure what the 1-D maps
cannot — 2-D surfaces, where polarizations couple. Their table,
``data/measured_errors_3d.json`` (written by
:func:`emscatter.validation.measured_table_3d.write_measured_3d`), carries per cell and
candidate the error [dB] and its Monte Carlo standard error (bootstrap over the realizations)
and per pair of candidates the SE of their difference. The lookup applies to 2-D isotropic
roughness of the table's correlation and medium class only, at the nearest cell in
``(θi, log kσ, log kℓ)`` — every requested θi nearest to the same table θi, none more than
half a step beyond the ends — and returns None elsewhere (then the 1-D maps apply as before).
The 3-D maps are per medium: the conductor class as the 1-D maps', and one map per
permittivity for dielectrics. The 1-D maps give every dielectric the one ε = 3 map of its
class; the 3-D cells are narrower, since their errors are measured at one ε: a dielectric
map applies to the surface's ε only within :data:`EPS_FACTOR_3D` of the map's ``|ε|`` (for
ε = 4 + 0.5i: ``2.0 ≤ |ε| ≤ 8.1``, dry to moist soils, the 1-D map's ε = 3 included) and with
a loss tangent ``Im ε / Re ε ≤ 1`` (a dielectric, not a conductor-like medium), the map of
nearest ``log |ε|`` where several qualify. Beyond that range the models' errors move with
the Fresnel coefficients (SPM's, the IEM's) by more than the cells resolve, and the lookup
returns None.
:func:`significant_pick` is the rule the ranking applies to it (no tolerance to calibrate:
a difference counts only beyond :data:`SIGNIFICANCE` combined standard errors).

**3-D cells, interpolated** (:func:`interpolated_errors_3d`, for ``auto``'s continuous blend,
:mod:`.blend`): the same map (same applicability: correlation, medium class, ε range, 2-D
isotropic), but the errors, their SEs and the pair SEs interpolated trilinearly — linear in
θi [deg], in log kσ and in log kℓ — over the eight surrounding cells that have a value
(renormalized over those), with an availability that falls linearly from 1 at the outermost
cell centres to 0 half a step beyond, on each axis (the step: the map's smallest one on that
axis). A single-value axis (the dielectric map's kℓ = 3) has no step of its own: it takes the
smallest step of that axis over the table's maps (log(7/3) = 0.85 in log kℓ from the PEC map,
so kℓ = 3 fades to 0 at kℓ = 3 × (7/3)^{±½} = 2.0 and 4.6), else :data:`SINGLE_STEP_LOG` (log
axes) or :data:`SINGLE_STEP_DEG` (θi). The availability is continuous in (θi, kσ, kℓ) and
0 wherever :func:`measured_errors_3d` finds no cell in the roughness (it reaches a little
further on a single-value axis: the nearest-cell lookup stops at ±0.15 in log there).
:func:`support_3d` is the θi interval where it can be positive, for a cheap test.
"""

from __future__ import annotations

import json
import math
from functools import lru_cache
from pathlib import Path

import numpy as np

__all__ = [
    "TABLE_PATH",
    "TOL_DB",
    "measured_errors",
    "medium_class",
    "load_table",
    "cell_roughness",
    "interpolated_errors",
    "TABLE_3D_PATH",
    "SIGNIFICANCE",
    "load_table_3d",
    "measured_errors_3d",
    "significant_pick",
    "combined_se",
    "EPS_FACTOR_3D",
    "interpolated_errors_3d",
    "support_3d",
]

TABLE_PATH = Path(__file__).with_name("data") / "measured_errors.json"
#: A candidate is "within tolerance" where its measured error is at most this [dB].
TOL_DB = 1.0
TABLE_3D_PATH = Path(__file__).with_name("data") / "measured_errors_3d.json"
#: A 3-D cell reorders only where a difference exceeds this many combined standard errors.
SIGNIFICANCE = 2.0
#: A dielectric 3-D map applies within this factor of its ``|ε|`` (module docstring).
EPS_FACTOR_3D = 2.0
#: Step [log] of a single-value log axis when no map of the table has two values on it.
SINGLE_STEP_LOG = 0.3
#: Step [deg] of a single-value θi axis when no map of the table has two values on it.
SINGLE_STEP_DEG = 20.0


@lru_cache(maxsize=1)
def load_table(path: str | None = None) -> dict:
    """The measured table (``{"maps": [...]}``); empty when the file is missing."""
    p = Path(path) if path else TABLE_PATH
    if not p.exists():
        return {"maps": []}
    return json.loads(p.read_text())


def medium_class(eps) -> str | None:
    """``"conductor"`` (PEC, Re ε < 0 or ``|ε| ≥ 100``), ``"dielectric"``, or None when
    ``eps`` is not given or is an array of several media."""
    if eps is None:
        return None
    if isinstance(eps, str):
        return "conductor" if eps.strip().lower() == "pec" else None
    e = np.unique(np.asarray(eps, dtype=complex))
    if e.size != 1:
        return None
    e = complex(e[0])
    return "conductor" if (e.real < 0 or abs(e) >= 100.0) else "dielectric"


def _family(roughness) -> str | None:
    from ..spectra import ExponentialCorrelation, GaussianCorrelation

    kind = type(roughness)
    if kind is GaussianCorrelation:
        name = "gaussian"
    elif kind is ExponentialCorrelation:
        name = "exponential"
    else:
        return None
    if roughness.dimension == 2 and not math.isclose(roughness.length, roughness.length_y):
        return None  # anisotropic: not mapped
    return name


def _nearest(grid: np.ndarray, value: float) -> int | None:
    """Index of the nearest grid value in log scale, None beyond half a step outside."""
    lg, lv = np.log(grid), math.log(value)
    step = float(np.min(np.diff(lg))) if grid.size > 1 else 0.3
    if lv < lg[0] - step / 2 or lv > lg[-1] + step / 2:
        return None
    return int(np.argmin(np.abs(lg - lv)))


def measured_errors(roughness, k: float, eps) -> dict | None:
    """``{"errors": {method: dB or nan}, "cell": (kσ, kℓ), "map": tag}`` of the map cell
    nearest to ``(kσ, kℓ)`` for this correlation and medium class; None where not mapped
    (module docstring). ``k`` [rad/m]."""
    hit = _map_of(roughness, k, eps)
    if hit is None:
        return None
    m, ks, kl = hit
    i = _nearest(np.asarray(m["k_sigma"], dtype=float), ks)
    j = _nearest(np.asarray(m["k_l"], dtype=float), kl)
    if i is None or j is None:
        return None
    errors = {
        name: (math.nan if v[i][j] is None else float(v[i][j])) for name, v in m["errors"].items()
    }
    return {"errors": errors, "cell": (m["k_sigma"][i], m["k_l"][j]), "map": m["tag"]}


def _map_of(roughness, k: float, eps):
    """``(map, kσ, kℓ)``: the map of this roughness's correlation and medium class, or None."""
    family, medium = _family(roughness), medium_class(eps)
    if family is None or medium is None:
        return None
    for m in load_table()["maps"]:
        if m["correlation"] == family and m["medium"] == medium:
            return m, k * roughness.sigma, k * roughness.length
    return None


def cell_roughness(roughness, k: float, cell: tuple[float, float]):
    """The roughness of a map cell's centre ``(kσ, kℓ)``, of ``roughness``'s class and
    dimension (isotropic)."""
    ks, kl = cell
    return type(roughness)(ks / k, kl / k, dimension=roughness.dimension)


def _bracket(grid: np.ndarray, value: float) -> tuple[int, int, float, float]:
    """``(i0, i1, t, fade)`` in log scale: ``value`` lies a fraction ``t`` from ``grid[i0]`` to
    ``grid[i1]`` (clamped at the ends); ``fade`` is 1 inside ``[grid[0], grid[-1]]``, falling
    linearly to 0 over the half step beyond either end."""
    lg, lv = np.log(grid), math.log(value)
    step = float(np.min(np.diff(lg))) if grid.size > 1 else 0.3
    if lv <= lg[0]:
        return 0, 0, 0.0, max(0.0, 1.0 - (lg[0] - lv) / (step / 2))
    if lv >= lg[-1]:
        n = grid.size - 1
        return n, n, 0.0, max(0.0, 1.0 - (lv - lg[-1]) / (step / 2))
    i1 = int(np.searchsorted(lg, lv))
    i0 = i1 - 1
    return i0, i1, float((lv - lg[i0]) / (lg[i1] - lg[i0])), 1.0


def interpolated_errors(roughness, k: float, eps) -> dict | None:
    """The measured errors interpolated between the cells, for a blend that must be continuous
    (:mod:`.blend`): ``{"errors": {method: dB}, "availability": {method: A}, "map": tag}``.

    ``errors`` is the bilinear interpolation in ``(log kσ, log kℓ)`` over the four cells around
    the roughness that have a value for that method (renormalized; nan when none has);
    ``availability`` their interpolation weight, times a fade from 1 at the outermost cell
    centres to 0 half a step beyond (where :func:`measured_errors` stops too). None where the
    maps do not apply (another correlation, anisotropy, medium class unknown). ``k`` [rad/m]."""
    hit = _map_of(roughness, k, eps)
    if hit is None:
        return None
    m, ks, kl = hit
    i0, i1, t, fade_s = _bracket(np.asarray(m["k_sigma"], dtype=float), ks)
    j0, j1, u, fade_l = _bracket(np.asarray(m["k_l"], dtype=float), kl)
    fade = fade_s * fade_l
    if fade <= 0.0:
        return None
    corners = [(i0, j0, (1 - t) * (1 - u)), (i1, j0, t * (1 - u)),
               (i0, j1, (1 - t) * u), (i1, j1, t * u)]  # fmt: skip
    errors, avail = {}, {}
    for name, table in m["errors"].items():
        have = [(w, table[i][j]) for i, j, w in corners if w > 0 and table[i][j] is not None]
        weight = sum(w for w, _ in have)
        errors[name] = sum(w * float(e) for w, e in have) / weight if weight > 0 else math.nan
        avail[name] = fade * weight
    return {"errors": errors, "availability": avail, "map": m["tag"]}


# ----------------------------------------------------------------------------- 3-D cells
@lru_cache(maxsize=4)
def load_table_3d(path: str | None = None) -> dict:
    """The 3-D table (``{"maps": [...]}``, module docstring) at ``path`` (default
    :data:`TABLE_3D_PATH`); empty when the file is missing."""
    p = Path(path) if path else TABLE_3D_PATH
    if not p.exists():
        return {"maps": []}
    doc = json.loads(p.read_text())
    for m in doc.get("maps", []):
        for key in ("theta_i_deg", "k_sigma", "k_l", "errors", "se"):
            if key not in m:
                raise ValueError(f"measured 3-D table {str(p)!r}: map without {key!r}")
    return doc


def _nearest_linear(grid: np.ndarray, values: np.ndarray) -> int | None:
    """The one grid index nearest to every value (linear scale), None if they differ or one
    lies beyond half a step outside."""
    step = float(np.min(np.diff(grid))) if grid.size > 1 else 20.0
    if np.any(values < grid[0] - step / 2) or np.any(values > grid[-1] + step / 2):
        return None
    idx = np.unique(np.argmin(np.abs(values[:, None] - grid[None, :]), axis=1))
    return int(idx[0]) if idx.size == 1 else None


def measured_errors_3d(roughness, k: float, eps, theta_i, path: str | None = None) -> dict | None:
    """The 3-D cell for this roughness, ``k`` [rad/m], medium and incidence ``theta_i`` [rad]
    (any shape): ``{"errors", "se": {method: dB or nan}, "pair_se": {(a, b): dB},
    "cell": (θi°, kσ, kℓ), "realizations", "map"}``; None where no cell applies (module
    docstring). ``path``: another table (default :data:`TABLE_3D_PATH`)."""
    family, medium = _family(roughness), medium_class(eps)
    if family is None or medium is None or theta_i is None or roughness.dimension != 2:
        return None
    ti = np.degrees(np.ravel(np.asarray(theta_i, dtype=float)))
    if ti.size == 0 or not np.all(np.isfinite(ti)):
        return None
    maps = [m for m in load_table_3d(str(path) if path else None)["maps"]
            if m["correlation"] == family and m["medium"] == medium]  # fmt: skip
    if medium == "dielectric":
        maps = _dielectric_maps(maps, eps)
    for m in maps:
        a = _nearest_linear(np.asarray(m["theta_i_deg"], dtype=float), ti)
        i = _nearest(np.asarray(m["k_sigma"], dtype=float), k * roughness.sigma)
        j = _nearest(np.asarray(m["k_l"], dtype=float), k * roughness.length)
        if a is None or i is None or j is None:
            return None

        def at(grid, a=a, i=i, j=j):
            v = grid[a][i][j]
            return math.nan if v is None else float(v)

        errors = {n: at(g) for n, g in m["errors"].items()}
        if not any(math.isfinite(e) for e in errors.values()):
            return None  # the cell was not computed
        pairs = {}
        for key, g in m.get("pair_se", {}).items():
            x, y = key.split("|")
            pairs[(x, y)] = pairs[(y, x)] = at(g)
        real = m.get("realizations")
        return {
            "errors": errors,
            "se": {n: at(g) for n, g in m["se"].items()},
            "pair_se": pairs,
            "cell": (m["theta_i_deg"][a], m["k_sigma"][i], m["k_l"][j]),
            "realizations": None if real is None else real[a][i][j],
            "map": m["tag"],
            "eps": m.get("eps"),
        }
    return None


def _dielectric_maps(maps: list[dict], eps) -> list[dict]:
    """The one dielectric map that applies to ``eps`` (module docstring), as a list (empty
    where none does): ``|ε|`` within :data:`EPS_FACTOR_3D` of the map's, loss tangent at
    most 1, the nearest in ``log |ε|``."""
    e = complex(np.unique(np.asarray(eps, dtype=complex))[0])
    if e.imag > e.real:
        return []
    scored = []
    for m in maps:
        em = m.get("eps")
        if not isinstance(em, (list, tuple)) or len(em) != 2:
            continue
        d = abs(math.log(abs(e) / abs(complex(float(em[0]), float(em[1])))))
        if d <= math.log(EPS_FACTOR_3D) * (1 + 1e-12):
            scored.append((d, m))
    return [min(scored, key=lambda x: x[0])[1]] if scored else []


def combined_se(meas: dict, a: str, b: str) -> float:
    """The SE [dB] of ``error(a) − error(b)`` in a 3-D cell: the paired bootstrap one where
    the table has it, else ``√(se_a² + se_b²)`` (independent errors: larger)."""
    s = meas["pair_se"].get((a, b), math.nan)
    if math.isfinite(s):
        return s
    return math.hypot(meas["se"].get(a, math.nan), meas["se"].get(b, math.nan))


def significant_pick(meas: dict, first: str, candidates) -> str | None:
    """The candidate to put before ``first`` by a 3-D cell, or None: among ``candidates``
    (in order; others than ``first``) those measured lower than ``first`` by more than
    :data:`SIGNIFICANCE` combined standard errors (:func:`combined_se`), the one measured
    lowest (ties: the earlier). None where ``first`` or every other has no measurement, or
    no difference is significant. The 1-D maps' tolerance :data:`TOL_DB` applies as there:
    ``first`` keeps its place while it is measured within it, and a candidate takes it only
    when measured within it or better than ``first`` by more than it — differences below it
    are smaller than the cells' systematic errors (the 6λ beam's smoothing, the bin rule),
    which the bootstrap does not see."""
    err = meas["errors"]
    e0 = err.get(first, math.nan)
    if not math.isfinite(e0) or e0 <= TOL_DB:
        return None
    best, best_err = None, math.inf
    for n in candidates:
        e = err.get(n, math.nan)
        if n == first or not math.isfinite(e):
            continue
        s = combined_se(meas, first, n)
        material = e <= TOL_DB or e0 - e > TOL_DB  # within tolerance, or better by more
        if math.isfinite(s) and e0 - e > SIGNIFICANCE * s and material and e < best_err:
            best, best_err = n, e
    return best


# ----------------------------------------------------------------- 3-D cells, interpolated
def _map_3d_of(roughness, k: float, eps, path=None) -> dict | None:
    """The 3-D map that applies to this roughness and medium (as :func:`measured_errors_3d`
    chooses it, θi aside), or None."""
    family, medium = _family(roughness), medium_class(eps)
    if family is None or medium is None or roughness.dimension != 2:
        return None
    maps = [m for m in load_table_3d(str(path) if path else None)["maps"]
            if m["correlation"] == family and m["medium"] == medium]  # fmt: skip
    if medium == "dielectric":
        maps = _dielectric_maps(maps, eps)
    return maps[0] if maps else None


def _steps_3d(m: dict, path=None) -> tuple[float, float, float]:
    """``(θi step [deg], log kσ step, log kℓ step)`` of map ``m``: its smallest step on each
    axis; a single-value axis takes the smallest over the table's maps (module docstring)."""
    maps = load_table_3d(str(path) if path else None)["maps"]
    out = []
    for key, log, default in (("theta_i_deg", False, SINGLE_STEP_DEG),
                              ("k_sigma", True, SINGLE_STEP_LOG),
                              ("k_l", True, SINGLE_STEP_LOG)):  # fmt: skip
        steps = []
        for mm in [m] if len(m[key]) > 1 else maps:
            g = np.asarray(mm[key], dtype=float)
            if g.size > 1:
                steps.append(float(np.min(np.diff(np.log(g) if log else g))))
        out.append(min(steps) if steps else default)
    return out[0], out[1], out[2]


def _brackets(grid, x, step: float):
    """``(i0, i1, t, fade)`` arrays over ``x`` (already in the axis' scale: log or linear):
    ``x`` lies a fraction ``t`` from ``grid[i0]`` to ``grid[i1]`` (clamped at the ends);
    ``fade`` is 1 inside ``[grid[0], grid[-1]]``, falling linearly to 0 half a ``step``
    beyond either end."""
    g = np.asarray(grid, dtype=float)
    x = np.asarray(x, dtype=float)
    if g.size == 1:
        i0 = i1 = np.zeros(x.shape, dtype=int)
        t = np.zeros(x.shape)
    else:
        i1 = np.clip(np.searchsorted(g, x), 1, g.size - 1)
        i0 = i1 - 1
        t = np.clip((x - g[i0]) / (g[i1] - g[i0]), 0.0, 1.0)
    out = np.maximum(np.maximum(g[0] - x, x - g[-1]), 0.0)
    return i0, i1, t, np.clip(1.0 - out / (step / 2), 0.0, 1.0)


def _grid(values) -> np.ndarray:
    """A nested list with None as a float array with nan."""
    return np.array(
        [[[math.nan if v is None else float(v) for v in row] for row in sl] for sl in values]
    )


def support_3d(roughness, k: float, eps, path=None) -> tuple[float, float] | None:
    """The open interval ``(lo, hi)`` of θi [deg] where :func:`interpolated_errors_3d` can
    have a positive availability for this roughness, ``k`` [rad/m] and medium; None where no
    3-D map applies or the roughness lies beyond its fade in kσ or kℓ (module docstring)."""
    m = _map_3d_of(roughness, k, eps, path)
    if m is None:
        return None
    st, ss, sl = _steps_3d(m, path)
    fs = _brackets(np.log(m["k_sigma"]), math.log(k * roughness.sigma), ss)[3]
    fl = _brackets(np.log(m["k_l"]), math.log(k * roughness.length), sl)[3]
    if float(fs * fl) <= 0.0:
        return None
    ti = m["theta_i_deg"]
    return float(ti[0]) - st / 2, float(ti[-1]) + st / 2


def interpolated_errors_3d(roughness, k: float, eps, theta_i, path=None) -> dict | None:
    """The 3-D cells' errors interpolated for a continuous blend (module docstring), at
    incidence ``theta_i`` [rad] (any shape), ``k`` [rad/m]: ``{"theta_i_deg": (U,) the
    distinct angles [deg], "inverse": the index (θi's shape) taking them back to
    ``theta_i``, "errors", "se", "availability": {method: (U,)}, "pair_se": {(a, b): (U,)}
    (both orders), "map", "eps"}``. Errors and SEs [dB] are the trilinear interpolation
    (θi linear, log kσ, log kℓ) over the surrounding cells that have a value (nan where none
    has); ``availability`` their interpolation weight times the fades on the three axes.
    None where no 3-D map applies or the availability is 0 at every angle. ``path``: another
    table (default :data:`TABLE_3D_PATH`)."""
    if theta_i is None:
        return None
    ti = np.degrees(np.asarray(theta_i, dtype=float))
    if ti.size == 0 or not np.all(np.isfinite(ti)):
        return None
    m = _map_3d_of(roughness, k, eps, path)
    if m is None:
        return None
    st, ss, sl = _steps_3d(m, path)
    i0, i1, t, fs = (np.ravel(a)[0] for a in _brackets(
        np.log(m["k_sigma"]), math.log(k * roughness.sigma), ss))  # fmt: skip
    j0, j1, u, fl = (np.ravel(a)[0] for a in _brackets(
        np.log(m["k_l"]), math.log(k * roughness.length), sl))  # fmt: skip
    if fs * fl <= 0.0:
        return None
    uniq, inverse = np.unique(ti, return_inverse=True)
    a0, a1, r, fa = _brackets(m["theta_i_deg"], uniq, st)
    fade = fa * (fs * fl)
    if not np.any(fade > 0.0):
        return None
    # the eight corners: (θ index (U,), kσ index, kℓ index, weight (U,))
    corners = [(a, i, j, wa * wi * wj)
               for a, wa in ((a0, 1.0 - r), (a1, r))
               for i, wi in ((i0, 1.0 - t), (i1, t))
               for j, wj in ((j0, 1.0 - u), (j1, u))]  # fmt: skip

    def interp(values):
        g = _grid(values)
        val = np.stack([g[a, i, j] for a, i, j, _ in corners])  # (8, U)
        w = np.stack([np.broadcast_to(w, uniq.shape) for *_, w in corners])
        have = np.isfinite(val) & (w > 0)
        weight = np.where(have, w, 0.0).sum(axis=0)
        total = np.where(have, w * np.where(have, val, 0.0), 0.0).sum(axis=0)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(weight > 0, total / np.where(weight > 0, weight, 1.0), np.nan), weight

    errors, avail, se, pairs = {}, {}, {}, {}
    for name, values in m["errors"].items():
        errors[name], weight = interp(values)
        avail[name] = fade * weight
    for name, values in m["se"].items():
        se[name] = interp(values)[0]
    for key, values in m.get("pair_se", {}).items():
        x, y = key.split("|")
        pairs[(x, y)] = pairs[(y, x)] = interp(values)[0]
    if not any(np.any(a > 0) for a in avail.values()):
        return None
    return {
        "theta_i_deg": uniq,
        "inverse": inverse.reshape(ti.shape),
        "errors": errors,
        "se": se,
        "pair_se": pairs,
        "availability": avail,
        "map": m["tag"],
        "eps": m.get("eps"),
    }
