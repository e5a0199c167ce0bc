"""Validity maps: where each approximation agrees with the method of moments (1-D profiles).

For a grid of roughness cells ``(kσ, kℓ)`` (Gaussian ``exp(−x²/ℓ²)`` or exponential
``exp(−|x|/ℓ)`` correlation, 1-D profiles, 2-D scattering problem), a fixed incidence ``θi``
and a permittivity, every approximation is compared with the Monte Carlo method of moments
(:func:`emscatter.solvers.mom.model.bistatic`, the exact reference). The run has two stages:

1. **references** (:func:`references`): the MoM σ⁰ on signed ``θs ∈ [−60°, 60°]`` every 1°,
   its standard errors and the coherent/incoherent reflectivities of every cell, written to a
   JSON store (``mom_<tag>.json``) after each cell, so a run can be stopped and resumed and the
   approximations re-evaluated without the MoM (the expensive part: minutes per cell);
2. **evaluation** (:func:`evaluate_cell`, cheap): the approximations on the same angles.

Approximations (rows ``method``):

* ``spm1`` — first-order SPM incoherent σ⁰ (:mod:`emscatter.solvers.spm.model`);
* ``po`` — Kirchhoff physical optics σ⁰ (:mod:`emscatter.solvers.kirchhoff.po`);
* ``go`` — Kirchhoff geometric optics σ⁰ with Smith shadowing and the slope ``auto`` would use
  (for the exponential: its spectrum below ``2k``, :mod:`emscatter.solvers.validity`);
* ``go_surface`` (exponential maps) — GO with the full slope of the map's surface;
* ``iem`` — the integral-equation model (1-D form, AIEM: what ``method="iem"`` and ``auto``
  use), when registered;
* ``iem92`` — the same solver in its 1992 configuration (``complementary="fung92",
  fresnel="incident"``; Fung et al. 1992), a diagnostic row (not a candidate of ``auto``);
* ``spm2`` — second-order SPM **coherent reflectivity** against the MoM coherent reflectivity.

Exponential maps: a sampled exponential profile is not differentiable, and the MoM (whose TM
equations use the curvature) loses its own energy balance on it; the answer also depends on
the inner scale. Their surfaces are the exponential spectrum with a smooth inner cutoff at
``taper · k`` (:class:`.tapered.TaperedExponential`, 2.5 k: beyond the Bragg band), resolved
by the MoM grid (``π/dx ≥ 3.9 · taper · k``), and **every approximation is evaluated on that
same spectrum** (SPM, GO, SPM2, PO and IEM through their spectra / n-fold spectra); the cell
labels ``(kσ, kℓ)`` are those of the exponential the surface was cut from, and ``auto`` and
the validity flags are evaluated for that exponential (what a user has).

Error metric for σ⁰: the angles are grouped into 12 bins of 10°; in each bin the σ⁰ of the
approximation and of the MoM are averaged (trapezoid rule). Bins whose MoM mean is more than
20 dB below the strongest bin, or whose MoM standard error exceeds half the mean, are left out.
The error is the **rms over the kept bins of** ``10 log10(σ_approx/σ_MoM)`` [dB] (each bin
capped at ±30 dB); the largest bin difference is also stored. ``mom_se_dB`` is the rms over
the kept bins of ``10 log10(1 + SE/σ)`` (an upper bound of the bin noise). For ``spm2`` the
error is ``|10 log10(r_SPM2/r_MoM)|``, kept where the MoM coherent reflectivity stands above
its Monte Carlo noise (``√(r_incoh/(N r_coh)) < 0.25``).

A polarization of a cell is left out ("MoM energy balance off") where the MoM's own energy
balance, reflected + transmitted = incident power (conductor, lossless dielectric), is off by
more than :data:`ENERGY_TOL` = 2 %: the TM (Neumann-type) equations use the profile's
curvature, which finite differences of a sampled exponential (non-differentiable) profile do
not give accurately once its grid-scale slopes approach one.

The ``auto`` choice (:func:`emscatter.solvers.select.select_method` at the map's ε and θi) is
recorded per cell; a *selector failure* is a cell where auto's method has σ⁰ error (larger of
h and v) above 1 dB while another candidate of ``auto`` is within 1 dB.

Units: wavelength 1 m (``k = 2π`` rad/m); only ``kσ``, ``kℓ`` and ``θi`` matter.
"""

from __future__ import annotations

import concurrent.futures as cf
import json
import math
import time
import warnings
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np

__all__ = [
    "MapConfig",
    "SMALL",
    "FULL",
    "FULL_DIELECTRIC",
    "EXP_PEC",
    "EXP_DIELECTRIC",
    "PUBLISHED",
    "TINY",
    "rough_of",
    "surface_of",
    "cell_slope",
    "mom_reference",
    "references",
    "evaluate_cell",
    "compute_map",
    "selector_failures",
    "auto_choice",
    "refresh_auto",
    "tag_of",
]

K = 2 * math.pi  # wavelength 1 m
AUTO_TO_MAP = {"spm": "spm1", "go": "go", "po": "po", "iem": "iem"}
#: The IEM's 1992 configuration (map row ``iem92``).
IEM92 = {"complementary": "fung92", "fresnel": "incident"}
CAP_DB = 30.0
DYNAMIC_RANGE_DB = 20.0
TOL_DB = 1.0
CORRELATIONS = ("gaussian", "exponential")
#: A polarization's MoM reference is used only where its own energy balance (reflected +
#: transmitted power = incident, for a conductor or a lossless dielectric) holds to this.
ENERGY_TOL = 0.02


@dataclass(frozen=True)
class MapConfig:
    """A validity-map run.

    k_sigma, k_l : grid values of ``kσ`` and ``kℓ`` [-].
    theta_i_deg : incidence angle [deg].
    eps : ``"pec"`` or a complex relative permittivity.
    correlation : ``"gaussian"`` or ``"exponential"``.
    realizations : MoM surfaces per cell; seed : root seed (cell ``(i, j)`` uses
        ``SeedSequence([seed, i, j])``).
    max_slope : cells whose rms slope (:func:`cell_slope`) exceeds this are not computed
        (the MoM grid they need is beyond the run's budget); blank on the maps.
    min_length_wl : shortest surface [wavelengths] (also ≥ 20 ℓ); taper ``g = L/4``.
    workers : processes over cells (1 = serial in this process).
    theta_max_deg, bin_deg : angular range and bin width of the σ⁰ metric [deg].
    taper : inner cutoff of the exponential maps' spectrum, in units of ``k``.
    """

    k_sigma: tuple[float, ...]
    k_l: tuple[float, ...]
    theta_i_deg: float = 20.0
    eps: object = "pec"
    correlation: str = "gaussian"
    realizations: int = 64
    seed: int = 2024
    max_slope: float = 1.2
    min_length_wl: float = 32.0
    workers: int = 2
    theta_max_deg: float = 60.0
    bin_deg: float = 10.0
    taper: float = 2.5

    def __post_init__(self):
        if len(self.k_sigma) < 1 or len(self.k_l) < 1:
            raise ValueError(f"k_sigma and k_l need ≥ 1 value, got {self.k_sigma}, {self.k_l}")
        for name in ("k_sigma", "k_l"):
            v = np.asarray(getattr(self, name), dtype=float)
            if not np.all(np.isfinite(v) & (v > 0)):
                raise ValueError(f"{name} must be positive and finite, got {v.tolist()}")
        if not (isinstance(self.realizations, int) and self.realizations >= 2):
            raise ValueError(f"realizations must be an integer ≥ 2, got {self.realizations!r}")
        if not (isinstance(self.workers, int) and self.workers >= 1):
            raise ValueError(f"workers must be a positive integer, got {self.workers!r}")
        if not 0 <= self.theta_i_deg < 60:
            raise ValueError(f"theta_i_deg must be in [0, 60), got {self.theta_i_deg!r}")
        if self.correlation not in CORRELATIONS:
            raise ValueError(f"correlation must be one of {CORRELATIONS}, got {self.correlation!r}")


def _grid(lo: float, hi: float, n: int) -> tuple[float, ...]:
    return tuple(float(v) for v in np.round(np.geomspace(lo, hi, n), 4))


_KS7, _KL7 = _grid(0.05, 3.0, 7), _grid(0.5, 20.0, 7)
#: The published maps (``emscatter validate --full``): Gaussian PEC, Gaussian ε = 3,
#: exponential PEC, exponential ε = 3; kσ ∈ [0.05, 3] × kℓ ∈ [0.5, 20], 7 × 7.
FULL = MapConfig(k_sigma=_KS7, k_l=_KL7, realizations=128)
FULL_DIELECTRIC = MapConfig(k_sigma=_KS7, k_l=_KL7, eps=3.0, realizations=64, min_length_wl=24.0)
EXP_PEC = replace(FULL, correlation="exponential", realizations=64)
EXP_DIELECTRIC = replace(FULL_DIELECTRIC, correlation="exponential")
PUBLISHED = (FULL, FULL_DIELECTRIC, EXP_PEC, EXP_DIELECTRIC)
#: The default of ``emscatter validate``: a 4×4 PEC grid, about a minute on two cores.
SMALL = MapConfig(
    k_sigma=(0.05, 0.2, 0.8, 2.0), k_l=(1.0, 3.0, 8.0, 16.0), realizations=32, min_length_wl=24.0
)
#: Smallest useful run (tests).
TINY = MapConfig(k_sigma=(0.1, 1.0), k_l=(8.0,), realizations=6, min_length_wl=16.0, workers=1)


def tag_of(cfg: MapConfig) -> str:
    """File tag: ``pec`` / ``eps3+0j`` (Gaussian, as before) or ``exp_pec`` / ``exp_eps3+0j``."""
    if isinstance(cfg.eps, str):
        t = str(cfg.eps)
    else:
        e = complex(cfg.eps)
        t = f"eps{e.real:g}{e.imag:+g}j"
    return t if cfg.correlation == "gaussian" else f"exp_{t}"


def rough_of(ks: float, kl: float, correlation: str = "gaussian"):
    """The nominal 1-D roughness of a cell (what a user describes): Gaussian or exponential."""
    from ..spectra import ExponentialCorrelation, GaussianCorrelation

    cls = GaussianCorrelation if correlation == "gaussian" else ExponentialCorrelation
    return cls(ks / K, kl / K, dimension=1)


def surface_of(ks: float, kl: float, correlation: str = "gaussian", taper: float = 2.5):
    """The surface the MoM solves and the approximations are evaluated on: the nominal
    Gaussian, or the exponential cut smoothly at ``taper · k`` (module docstring)."""
    if correlation == "gaussian":
        return rough_of(ks, kl, correlation)
    from .tapered import tapered_from

    return tapered_from(ks / K, kl / K, taper * K)


def cell_slope(ks: float, kl: float, correlation: str = "gaussian", taper: float = 2.5) -> float:
    """The rms slope [-] of a cell's surface: ``√2 σ/ℓ`` (Gaussian), the tapered exponential's
    (finite) slope."""
    return math.sqrt(surface_of(ks, kl, correlation, taper).mean_square_slope()[0])


def _points_per_wavelength(
    ks: float, kl: float, correlation: str = "gaussian", taper: float = 2.5, eps="pec"
) -> float:
    """Points per wavelength *in the denser medium* (as :func:`emscatter.solvers.mom.model.bistatic`
    counts them): ≥ 10 and ≥ 8 along the arc at 3 rms slopes (the fields), and the geometry
    in free-space units divided by the index: Gaussian ≥ 5 points per correlation length;
    tapered exponential ``π/dx ≥ 3 × 1.3 K_c`` (its spectrum is below 1e-10 beyond
    ``1.3 K_c``), i.e. ``7.8·taper`` points per free-space wavelength."""
    from emscatter.solvers.mom.solve import _n_eff

    m = cell_slope(ks, kl, correlation, taper)
    arc = 8.2 * math.sqrt(1 + 9 * m * m)
    if correlation == "gaussian":
        geometry = 5 * 2 * math.pi / kl
    else:
        geometry = math.ceil(7.8 * taper)
    return float(max(10.0, arc, geometry / _n_eff(eps)))


def _angles(cfg: MapConfig):
    signed = np.arange(-cfg.theta_max_deg, cfg.theta_max_deg + 0.5, 1.0)
    edges = np.arange(-cfg.theta_max_deg, cfg.theta_max_deg + cfg.bin_deg / 2, cfg.bin_deg)
    return signed, edges, np.radians(np.abs(signed)), np.where(signed >= 0, 0.0, math.pi)


def _bin_means(theta_deg: np.ndarray, values: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Trapezoid mean of ``values`` (…, n) over each ``[edges[j], edges[j+1]]``."""
    out = []
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        sel = (theta_deg >= a - 1e-9) & (theta_deg <= b + 1e-9)
        out.append(np.trapezoid(values[..., sel], theta_deg[sel], axis=-1) / (b - a))
    return np.stack(out, axis=-1)


def _sigma0_error(mom_bins, se_bins, approx_bins) -> dict:
    """rms / max dB difference over the kept bins (module docstring)."""
    keep = (mom_bins >= 10 ** (-DYNAMIC_RANGE_DB / 10) * np.max(mom_bins)) & (
        se_bins < 0.5 * mom_bins
    )
    if not np.any(keep):
        return {"error_dB": math.nan, "max_error_dB": math.nan, "n_bins": 0, "se_dB": math.nan}
    with np.errstate(divide="ignore", invalid="ignore"):
        d = 10 * np.log10(np.maximum(approx_bins[keep], 1e-300) / mom_bins[keep])
    d = np.clip(np.nan_to_num(d, nan=CAP_DB), -CAP_DB, CAP_DB)
    se_db = 10 * np.log10(1 + se_bins[keep] / mom_bins[keep])
    return {
        "error_dB": float(np.sqrt(np.mean(d * d))),
        "max_error_dB": float(np.max(np.abs(d))),
        "n_bins": int(np.count_nonzero(keep)),
        "se_dB": float(np.sqrt(np.mean(se_db * se_db))),
    }


# ----------------------------------------------------------------------------- stage 1: MoM
def mom_reference(ks: float, kl: float, cfg: MapConfig, index: tuple[int, int] = (0, 0)) -> dict:
    """The MoM reference of one cell (JSON-able dict; ``status`` says if it was skipped)."""
    from emscatter.solvers.mom import model as mom

    t0 = time.perf_counter()
    rough = surface_of(ks, kl, cfg.correlation, cfg.taper)
    slope = cell_slope(ks, kl, cfg.correlation, cfg.taper)
    base = {"k_sigma": ks, "k_l": kl, "rms_slope": slope, "index": list(index)}
    if slope > cfg.max_slope:
        return {**base, "status": f"not computed: rms slope {slope:.2f} > {cfg.max_slope}"}
    _, _, ts, ps = _angles(cfg)
    ppw = _points_per_wavelength(ks, kl, cfg.correlation, cfg.taper, cfg.eps)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # resolution/validity notes: the map reports them
        ref = mom.bistatic(
            rough,
            cfg.eps,
            K,
            math.radians(cfg.theta_i_deg),
            ts,
            ps,
            realizations=cfg.realizations,
            seed=np.random.SeedSequence([cfg.seed, *index]),
            length=max(cfg.min_length_wl, 20 * rough.length),
            points_per_wavelength=ppw,
            progress=False,
        )
    per = ref.info["per_polarization"]
    return {
        **base,
        "status": "ok",
        "realizations": int(ref.info["realizations"]),
        "unknowns": int(ref.info["unknowns"]),
        "dx": float(ref.info["dx"]),
        "points_per_wavelength": ppw,
        "sigma0": [_sig(ref.sigma0[p, p]) for p in (0, 1)],
        "standard_error": [_sig(ref.info["standard_error"][p, p]) for p in (0, 1)],
        "coherent": [float(per[p]["coherent_reflectivity"]) for p in "hv"],
        "incoherent": [float(per[p]["incoherent_reflectivity"]) for p in "hv"],
        "reflected": [float(per[p]["reflected"]) for p in "hv"],
        "transmitted": [float(per[p].get("transmitted", 0.0) or 0.0) for p in "hv"],
        "seconds": time.perf_counter() - t0,
    }


def _sig(a) -> list[float]:
    """Values rounded to 6 significant digits (the store stays small and diffable)."""
    return [float(f"{v:.6g}") for v in np.asarray(a, dtype=float).ravel()]


def _ref_job(args):
    ks, kl, cfg, index = args
    return mom_reference(ks, kl, cfg, index)


def _store_key(cfg: MapConfig) -> dict:
    d = asdict(cfg)
    for k in ("workers",):
        d.pop(k)
    d["eps"] = str(cfg.eps)
    return json.loads(json.dumps(d))  # tuples → lists, as read back


def _same_config(stored, key: dict, cfg: MapConfig) -> bool:
    """A store's configuration matches ``key``; ``taper`` may be missing from a Gaussian
    map's store (written before the field existed; it applies to exponential maps only)."""
    if not isinstance(stored, dict):
        return False
    if cfg.correlation == "gaussian" and "taper" not in stored:
        stored = {**stored, "taper": key["taper"]}
    return stored == key


def references(cfg: MapConfig, store: Path | None = None, *, progress: bool | None = None) -> dict:
    """MoM references of every cell, ``{(i, j): reference}``; with ``store`` (a JSON path)
    cells already there (same configuration) are reused and each new cell is written as soon
    as it is done (atomically), so a long run can be resumed. ``progress``: a tqdm bar over
    the cells (:mod:`emscatter.progress`: ``None`` auto, on a terminal past 2 s)."""
    from ..io import atomic_path
    from ..progress import bar as progress_bar

    done: dict = {}
    key = _store_key(cfg)
    if store is not None and Path(store).exists():
        data = json.loads(Path(store).read_text())
        if not _same_config(data.get("config"), key, cfg):
            raise ValueError(
                f"{store} holds references for another configuration: {data.get('config')}; "
                "remove it or pass another store"
            )
        done = {tuple(c["index"]): c for c in data["cells"]}
    jobs = [
        (float(ks), float(kl), cfg, (i, j))
        for i, ks in enumerate(cfg.k_sigma)
        for j, kl in enumerate(cfg.k_l)
        if (i, j) not in done
    ]

    def cost(a):  # ~ (unknowns)²: the dense cells first for load balance
        ppw = _points_per_wavelength(a[0], a[1], cfg.correlation, cfg.taper, cfg.eps)
        return -(max(cfg.min_length_wl, 20 * a[1] / K) * ppw)

    jobs.sort(key=cost)

    def save():
        if store is None:
            return
        cells = [done[i] for i in sorted(done)]
        with atomic_path(Path(store)) as tmp:
            tmp.write_text(json.dumps({"config": key, "cells": cells}, indent=0))

    with progress_bar(len(jobs), f"MoM cells {tag_of(cfg)}", progress, unit="cell") as bar:
        if cfg.workers == 1:
            for a in jobs:
                done[a[3]] = _ref_job(a)
                save()
                bar.update(1)
        else:
            with cf.ProcessPoolExecutor(max_workers=cfg.workers) as pool:
                futures = [pool.submit(_ref_job, a) for a in jobs]
                for fut in cf.as_completed(futures):
                    r = fut.result()
                    done[tuple(r["index"])] = r
                    save()
                    bar.update(1)
    return done


# ----------------------------------------------------------------------------- stage 2
def sigma0_methods(cfg: MapConfig) -> tuple[str, ...]:
    """The σ⁰ rows of a map: auto's candidates, plus GO on the grid's slope (exponential)."""
    from .. import solvers

    base = ["spm1", "go", "po"]
    if "iem" in solvers.available():
        base += ["iem", "iem92"]
    if cfg.correlation != "gaussian":
        base.append("go_surface")
    return tuple(base)


def map_methods(cfg: MapConfig) -> tuple[str, ...]:
    return (*sigma0_methods(cfg), "spm2")


def _approximations(rough, nominal, cfg: MapConfig) -> tuple[dict, float]:
    """σ⁰ (2, n) of every approximation on the map angles for the cell's surface ``rough``,
    and SPM2's coherent reflectivity; ``go`` with the slope auto would use for ``nominal``."""
    from emscatter.solvers.kirchhoff import go as kirchhoff_go
    from emscatter.solvers.kirchhoff import po as kirchhoff_po
    from emscatter.solvers.spm import model as spm

    from .. import solvers
    from ..solvers.validity import wave_slope_variances

    _, _, ts, ps = _angles(cfg)
    ti = math.radians(cfg.theta_i_deg)
    out = {
        "spm1": spm.bistatic(rough, cfg.eps, K, ti, ts, ps, coherent=False).sigma0,
        "po": kirchhoff_po.bistatic(rough, cfg.eps, K, ti, ts, ps, threads=1).sigma0,
    }
    sv = wave_slope_variances(nominal, K)[0]
    out["go"] = kirchhoff_go.bistatic(
        rough, cfg.eps, K, ti, ts, ps, threads=1, slope_variance=sv, coherent=False
    ).sigma0
    if cfg.correlation != "gaussian":
        out["go_surface"] = kirchhoff_go.bistatic(
            rough, cfg.eps, K, ti, ts, ps, threads=1, coherent=False
        ).sigma0
    if "iem" in solvers.available():
        iem = solvers.get("iem")
        out["iem"] = iem.bistatic(rough, cfg.eps, K, ti, ts, ps, coherent=False).sigma0
        out["iem92"] = iem.bistatic(rough, cfg.eps, K, ti, ts, ps, coherent=False, **IEM92).sigma0
    r2 = spm.bistatic(rough, cfg.eps, K, ti, 0.0, 0.0, order=2).coherent
    return {m: np.stack([v[0, 0], v[1, 1]]) for m, v in out.items()}, r2


def evaluate_cell(ref: dict, cfg: MapConfig) -> list[dict]:
    """All rows (method × polarization) of one cell from its MoM reference."""
    from ..solvers import get
    from ..solvers.select import select_method

    ks, kl = ref["k_sigma"], ref["k_l"]
    rough = rough_of(ks, kl, cfg.correlation)
    ti = math.radians(cfg.theta_i_deg)
    auto, reports = select_method(rough, K, eps=cfg.eps, theta_i=ti)
    methods = map_methods(cfg)
    solver_of = {"spm1": "spm", "spm2": "spm", "go": "go", "go_surface": "go", "po": "po"}
    solver_of["iem"] = solver_of["iem92"] = "iem"
    valid = {}
    for m in methods:
        name = solver_of[m]
        rep = reports.get(name) or get(name).check_validity(rough, K, eps=cfg.eps, theta_i=ti)
        valid[m] = bool(rep["valid"])
    base = {"k_sigma": ks, "k_l": kl, "rms_slope": ref["rms_slope"], "auto": AUTO_TO_MAP[auto]}
    if ref["status"] != "ok":
        empty = {**base, "realizations": 0, "unknowns": 0, "seconds": 0.0}
        return [r for p in "hv" for r in _blank_rows(empty, p, methods, valid, ref["status"])]
    signed, edges, _, _ = _angles(cfg)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        surface = surface_of(ks, kl, cfg.correlation, cfg.taper)
        approx, r2 = _approximations(surface, rough, cfg)
    n = ref["realizations"]
    common = {**base, "realizations": n, "unknowns": ref["unknowns"], "seconds": ref["seconds"]}
    balance = _energy_balance(ref, cfg)
    rows = []
    for ip, p in enumerate("hv"):
        if balance[ip] is not None and abs(balance[ip] - 1.0) > ENERGY_TOL:
            why = f"MoM energy balance off: R + T = {balance[ip]:.3f} (tolerance {ENERGY_TOL})"
            rows += _blank_rows(common, p, methods, valid, why)
            continue
        mom_b = _bin_means(signed, np.asarray(ref["sigma0"][ip]), edges)
        se_b = _bin_means(signed, np.asarray(ref["standard_error"][ip]), edges)
        for m in sigma0_methods(cfg):
            e = _sigma0_error(mom_b, se_b, _bin_means(signed, approx[m][ip], edges))
            rows.append(
                {
                    **common,
                    "method": m,
                    "pol": p,
                    "error_dB": e["error_dB"],
                    "max_error_dB": e["max_error_dB"],
                    "n_bins": e["n_bins"],
                    "mom_se_dB": e["se_dB"],
                    "valid": valid[m],
                    "status": "ok" if e["n_bins"] else "no MoM bin above noise",
                }
            )
        r_coh, r_inc = ref["coherent"][ip], ref["incoherent"][ip]
        rel = math.sqrt(max(r_inc, 0.0) / (n * r_coh)) if r_coh > 0 else math.inf
        spm2 = float(np.ravel(r2[ip])[0])
        if rel < 0.25:
            err = min(abs(10 * math.log10(max(spm2, 1e-300) / r_coh)), CAP_DB)
            status = "ok"
        else:
            err, status = math.nan, "MoM coherent reflectivity below its noise"
        rows.append(
            {
                **common,
                "method": "spm2",
                "pol": p,
                "error_dB": err,
                "max_error_dB": err,
                "n_bins": 1 if status == "ok" else 0,
                "mom_se_dB": 10 * math.log10(1 + rel) if math.isfinite(rel) else math.nan,
                "valid": valid["spm2"],
                "status": status,
            }
        )
    return rows


def _blank_rows(common: dict, pol: str, methods, valid: dict, status: str) -> list[dict]:
    """Rows without an error (cell not computed, or its MoM reference rejected)."""
    nan = math.nan
    return [
        {**common, "method": m, "pol": pol, "error_dB": nan, "max_error_dB": nan, "n_bins": 0,
         "mom_se_dB": nan, "valid": valid[m], "status": status}
        for m in methods
    ]  # fmt: skip


def _energy_balance(ref: dict, cfg: MapConfig) -> list:
    """``R + T`` of the MoM per polarization where it must be 1 (conductor, lossless), else
    None (lossy medium, or an old store without the transmitted power)."""
    lossless = isinstance(cfg.eps, str) or complex(cfg.eps).imag == 0
    if not lossless or ("transmitted" not in ref and not isinstance(cfg.eps, str)):
        return [None, None]
    t = ref.get("transmitted", [0.0, 0.0])
    return [ref["reflected"][i] + t[i] for i in (0, 1)]


def compute_map(cfg: MapConfig, *, store: Path | None = None, progress: bool | None = None) -> list:
    """Rows of :func:`evaluate_cell` over the whole grid (MoM references from ``store``
    where present, computed otherwise, :func:`references`)."""
    refs = references(cfg, store, progress=progress)
    rows: list[dict] = []
    for idx in sorted(refs):
        rows.extend(evaluate_cell(refs[idx], cfg))
    order = {m: i for i, m in enumerate(map_methods(cfg))}
    rows.sort(key=lambda r: (r["k_sigma"], r["k_l"], order[r["method"]], r["pol"]))
    return rows


def selector_failures(rows: list[dict], tol_db: float = TOL_DB) -> list[dict]:
    """Cells where ``auto``'s method has σ⁰ error (max over h, v) > ``tol_db`` while another
    of auto's candidates stays within ``tol_db``; each entry names the cell and the errors."""
    candidates = set(AUTO_TO_MAP.values())
    cells: dict[tuple[float, float], dict] = {}
    for r in rows:
        if r["method"] not in candidates:
            continue
        c = cells.setdefault((float(r["k_sigma"]), float(r["k_l"])), {"auto": r["auto"]})
        e = float(r["error_dB"])
        c[r["method"]] = max(c.get(r["method"], -math.inf), e if math.isfinite(e) else math.nan)
    bad = []
    for (ks, kl), c in cells.items():
        errs = {m: v for m, v in c.items() if m != "auto"}
        if any(math.isnan(v) for v in errs.values()) or c["auto"] not in errs:
            continue  # not computed
        good = [m for m, v in errs.items() if v <= tol_db]
        if errs[c["auto"]] > tol_db and good:
            bad.append({"k_sigma": ks, "k_l": kl, "auto": c["auto"], "errors": errs})
    return bad


def auto_choice(k_sigma: float, k_l: float, cfg: MapConfig = FULL) -> str:
    """The map name of ``method="auto"``'s choice for a cell (at the map's ε and θi)."""
    from ..solvers.select import select_method

    rough = rough_of(k_sigma, k_l, cfg.correlation)
    ti = math.radians(cfg.theta_i_deg)
    return AUTO_TO_MAP[select_method(rough, K, eps=cfg.eps, theta_i=ti)[0]]


def refresh_auto(rows: list[dict], cfg: MapConfig) -> list[dict]:
    """Set every row's ``auto`` to today's choice (after the measured table changed)."""
    choice: dict = {}
    for r in rows:
        key = (r["k_sigma"], r["k_l"])
        if key not in choice:
            choice[key] = auto_choice(*key, cfg)
        r["auto"] = choice[key]
    return rows
