"""Validity maps: where each approximation agrees with the method of moments (1-D profiles).

For a grid of roughness cells ``(kσ, kℓ)`` (Gaussian correlation ``exp(−x²/ℓ²)``, 1-D
profiles, 2-D scattering problem), a fixed incidence ``θi`` and a permittivity, every
approximation of :mod:`emscatter.solvers` is compared with the Monte Carlo method of moments
(:func:`emscatter.solvers.mom.bistatic`, the exact reference):

* ``spm1`` — first-order SPM incoherent σ⁰ (:mod:`emscatter.solvers.spm`);
* ``po`` — Kirchhoff physical optics σ⁰ (:mod:`emscatter.solvers.kirchhoff_po`);
* ``go`` — Kirchhoff geometric optics σ⁰ with Smith shadowing
  (:mod:`emscatter.solvers.kirchhoff_go`);
* ``spm2`` — second-order SPM **coherent reflectivity** ``|R⁽⁰⁾|² + 2 Re(R⁽⁰⁾*R⁽²⁾)``
  against the MoM coherent reflectivity ``∫|⟨A⟩|² dθs / P_inc``.

Error metric for σ⁰ (``spm1``, ``po``, ``go``): the signed scattering angles
``θs ∈ [−60°, 60°]`` are sampled every 1° and grouped into 12 bins of 10°; in each bin the
σ⁰ of the approximation and of the MoM are averaged (trapezoid rule). Bins whose MoM mean is
more than 20 dB below the strongest bin, or whose MoM standard error exceeds half the mean,
are left out. The error is the **rms over the kept bins of** ``10 log10(σ_approx/σ_MoM)``
[dB] (each bin difference capped at ±30 dB); the largest bin difference is also stored.
Binning averages the speckle of the finite Monte Carlo (the angular coherence of the tapered
beam is ``≈ λ/(2g)``, a few degrees) so that the metric measures the model, not the noise.
``mom_se_dB`` is the rms over the kept bins of ``10 log10(1 + SE/σ)`` with the per-angle
standard errors averaged over the bin — an upper bound of the bin noise (it assumes the
angles in a bin fully correlated).

For ``spm2`` the error is ``|10 log10(r_SPM2/r_MoM)|`` of the coherent reflectivity, kept
only where the MoM coherent reflectivity stands above its Monte Carlo noise
(``√(r_incoh/(N r_coh)) < 0.25`` with ``N`` realizations); elsewhere it is NaN.

The ``auto`` selector (:func:`emscatter.solvers.select.select_method`) is evaluated in each
cell; a cell is a *selector failure* when the chosen method's σ⁰ error (the larger of h and
v) exceeds 1 dB while another method stays within 1 dB.

Units: the wavelength is 1 m (``k = 2π`` rad/m); only ``kσ``, ``kℓ`` and ``θi`` matter.
Run with ``emscatter validate [--full] [--out DIR]`` (:func:`run_validation`).
"""

from __future__ import annotations

import concurrent.futures as cf
import math
import time
import warnings
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from .io import save_figure, write_csv, write_json

__all__ = [
    "MapConfig",
    "SMALL",
    "FULL",
    "FULL_DIELECTRIC",
    "TINY",
    "compute_cell",
    "compute_map",
    "selector_failures",
    "mom_emissivity",
    "emissivity_table",
    "plot_map",
    "write_map",
    "run_validation",
    "read_map",
    "reselect",
    "auto_choice",
]

K = 2 * math.pi  # wavelength 1 m
SIGMA0_METHODS = ("spm1", "go", "po")
METHODS = ("spm1", "spm2", "po", "go")
AUTO_TO_MAP = {"spm": "spm1", "go": "go", "po": "po"}
CAP_DB = 30.0
DYNAMIC_RANGE_DB = 20.0
TOL_DB = 1.0


@dataclass(frozen=True)
class MapConfig:
    """A validity-map run.

    k_sigma, k_l : grid values of ``kσ`` and ``kℓ`` [-].
    theta_i_deg : incidence angle [deg].
    eps : ``"pec"`` or a complex relative permittivity.
    realizations : MoM surfaces per cell; seed : root seed (cell ``(i, j)`` uses
        ``SeedSequence([seed, i, j])``).
    max_slope : cells whose rms slope ``√2 σ/ℓ`` exceeds this are not computed (the MoM
        grid they need is beyond the run's budget); they appear blank on the maps.
    min_length_wl : shortest surface [wavelengths] (also ≥ 20 ℓ); taper ``g = L/4``.
    workers : processes over cells (1 = serial in this process).
    theta_max_deg, bin_deg : angular range and bin width of the σ⁰ metric [deg].
    """

    k_sigma: tuple[float, ...]
    k_l: tuple[float, ...]
    theta_i_deg: float = 20.0
    eps: object = "pec"
    realizations: int = 64
    seed: int = 2024
    max_slope: float = 1.2
    min_length_wl: float = 32.0
    workers: int = 2
    theta_max_deg: float = 60.0
    bin_deg: float = 10.0

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


def _grid(lo: float, hi: float, n: int) -> tuple[float, ...]:
    return tuple(float(v) for v in np.round(np.geomspace(lo, hi, n), 4))


#: The published maps (``emscatter validate --full``).
FULL = MapConfig(k_sigma=_grid(0.05, 3.0, 7), k_l=_grid(0.5, 20.0, 7), realizations=128)
#: The published lossless-dielectric map (ε = 3): a smaller grid (the two-medium MoM has
#: 2 × √ε times the unknowns).
FULL_DIELECTRIC = MapConfig(
    k_sigma=(0.05, 0.1957, 0.3873, 0.7663, 1.5162),
    k_l=(1.71, 3.1623, 5.848, 10.8148),
    eps=3.0,
    realizations=128,
    min_length_wl=24.0,
)
#: The default of ``emscatter validate``: a 4×4 grid, about a minute on two cores.
SMALL = MapConfig(
    k_sigma=(0.05, 0.2, 0.8, 2.0), k_l=(1.0, 3.0, 8.0, 16.0), realizations=32, min_length_wl=24.0
)
#: Smallest useful run (tests).
TINY = MapConfig(k_sigma=(0.1, 1.0), k_l=(8.0,), realizations=6, min_length_wl=16.0, workers=1)


def _rough(ks: float, kl: float):
    from .spectra import GaussianCorrelation

    return GaussianCorrelation(ks / K, kl / K, dimension=1)


def _points_per_wavelength(ks: float, kl: float) -> float:
    """≥ 10 per wavelength, ≥ 8 along the arc at 3 rms slopes, ≥ 5 per correlation length."""
    m = math.sqrt(2) * ks / kl
    return float(max(10.0, 8.2 * math.sqrt(1 + 9 * m * m), 5 * 2 * math.pi / kl))


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
    with np.errstate(divide="ignore"):
        d = 10 * np.log10(np.maximum(approx_bins[keep], 1e-300) / mom_bins[keep])
    d = np.clip(d, -CAP_DB, CAP_DB)
    se_db = 10 * np.log10(1 + se_bins[keep] / mom_bins[keep])
    return {
        "error_dB": float(np.sqrt(np.mean(d * d))),
        "max_error_dB": float(np.max(np.abs(d))),
        "n_bins": int(np.count_nonzero(keep)),
        "se_dB": float(np.sqrt(np.mean(se_db * se_db))),
    }


def compute_cell(
    ks: float, kl: float, cfg: MapConfig, index: tuple[int, int] = (0, 0)
) -> list[dict]:
    """All rows (method × polarization) of one cell ``(kσ, kℓ)`` — see the module docstring.

    Returns a list of dicts with keys ``k_sigma, k_l, rms_slope, method, pol, error_dB,
    max_error_dB, n_bins, mom_se_dB, valid, auto, status, realizations, unknowns, seconds``.
    """
    from .solvers import kirchhoff_go, kirchhoff_po, mom, spm
    from .solvers.select import select_method

    t0 = time.perf_counter()
    rough = _rough(ks, kl)
    slope = math.sqrt(2) * ks / kl
    ti_cell = math.radians(cfg.theta_i_deg)
    auto, _ = select_method(rough, K, eps=cfg.eps, theta_i=ti_cell)
    valid = {
        m: mod.check_validity(rough, K, eps=cfg.eps, theta_i=ti_cell)["valid"]
        for m, mod in (("spm1", spm), ("spm2", spm), ("po", kirchhoff_po), ("go", kirchhoff_go))
    }
    base = {"k_sigma": ks, "k_l": kl, "rms_slope": slope, "auto": AUTO_TO_MAP[auto]}
    if slope > cfg.max_slope:
        return [
            {
                **base,
                "method": m,
                "pol": p,
                "error_dB": math.nan,
                "max_error_dB": math.nan,
                "n_bins": 0,
                "mom_se_dB": math.nan,
                "valid": valid[m],
                "status": f"not computed: rms slope {slope:.2f} > {cfg.max_slope}",
                "realizations": 0,
                "unknowns": 0,
                "seconds": 0.0,
            }
            for m in METHODS
            for p in "hv"
        ]
    ti = math.radians(cfg.theta_i_deg)
    tmax, step = cfg.theta_max_deg, 1.0
    signed = np.arange(-tmax, tmax + step / 2, step)
    edges = np.arange(-tmax, tmax + cfg.bin_deg / 2, cfg.bin_deg)
    ts = np.radians(np.abs(signed))
    ps = np.where(signed >= 0, 0.0, math.pi)
    ppw = _points_per_wavelength(ks, kl)
    length = max(cfg.min_length_wl, 20 * rough.length)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # resolution/validity notes: the map reports them
        ref = mom.bistatic(
            rough,
            cfg.eps,
            K,
            ti,
            ts,
            ps,
            realizations=cfg.realizations,
            seed=np.random.SeedSequence([cfg.seed, *index]),
            length=length,
            points_per_wavelength=ppw,
            progress=False,
        )
        approx = {
            "spm1": spm.bistatic(rough, cfg.eps, K, ti, ts, ps, coherent=False).sigma0,
            "po": kirchhoff_po.bistatic(rough, cfg.eps, K, ti, ts, ps, threads=1).sigma0,
            "go": kirchhoff_go.bistatic(rough, cfg.eps, K, ti, ts, ps, threads=1).sigma0,
        }
        r2 = spm.bistatic(rough, cfg.eps, K, ti, 0.0, 0.0, order=2).coherent
    seconds = time.perf_counter() - t0
    rows = []
    n = ref.info["realizations"]
    common = {
        **base,
        "realizations": n,
        "unknowns": ref.info["unknowns"],
        "seconds": seconds,
    }
    for ip, p in enumerate("hv"):
        mom_b = _bin_means(signed, ref.sigma0[ip, ip], edges)
        se_b = _bin_means(signed, ref.info["standard_error"][ip, ip], edges)
        for m in ("spm1", "po", "go"):
            e = _sigma0_error(mom_b, se_b, _bin_means(signed, approx[m][ip, ip], edges))
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
        pp = ref.info["per_polarization"][p]
        r_coh, r_inc = pp["coherent_reflectivity"], pp["incoherent_reflectivity"]
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


def _cell_job(args):
    ks, kl, cfg, index = args
    return compute_cell(ks, kl, cfg, index)


def compute_map(cfg: MapConfig, *, progress: bool = True) -> list[dict]:
    """Rows of :func:`compute_cell` over the whole grid, cells spread over
    ``cfg.workers`` processes (:class:`concurrent.futures.ProcessPoolExecutor`), most
    expensive cells first; a tqdm bar counts cells."""
    from tqdm.auto import tqdm

    jobs = [
        (float(ks), float(kl), cfg, (i, j))
        for i, ks in enumerate(cfg.k_sigma)
        for j, kl in enumerate(cfg.k_l)
    ]
    # cost ~ (unknowns)² ~ (L · ppw)²: submit the dense cells first for load balance
    jobs.sort(
        key=lambda a: -(max(cfg.min_length_wl, 20 * a[1] / K) * _points_per_wavelength(a[0], a[1]))
    )
    rows: list[dict] = []
    with tqdm(total=len(jobs), desc="validity-map cells", disable=not progress) as bar:
        if cfg.workers == 1:
            for a in jobs:
                rows.extend(_cell_job(a))
                bar.update(1)
        else:
            with cf.ProcessPoolExecutor(max_workers=cfg.workers) as pool:
                futures = [pool.submit(_cell_job, a) for a in jobs]
                for fut in cf.as_completed(futures):
                    rows.extend(fut.result())
                    bar.update(1)
    order = {m: i for i, m in enumerate(METHODS)}
    rows.sort(key=lambda r: (r["k_sigma"], r["k_l"], order[r["method"]], r["pol"]))
    return rows


def selector_failures(rows: list[dict], tol_db: float = TOL_DB) -> list[dict]:
    """Cells where ``auto``'s method has σ⁰ error (max over h, v) > ``tol_db`` while another
    of spm1/go/po stays within ``tol_db``; each entry names the cell and the errors."""
    cells: dict[tuple[float, float], dict] = {}
    for r in rows:
        if r["method"] not in SIGMA0_METHODS:
            continue
        c = cells.setdefault((float(r["k_sigma"]), float(r["k_l"])), {"auto": r["auto"]})
        e = float(r["error_dB"])
        c[r["method"]] = max(c.get(r["method"], -math.inf), e if math.isfinite(e) else math.nan)
    bad = []
    for (ks, kl), c in cells.items():
        errs = {m: c.get(m, math.nan) for m in SIGMA0_METHODS}
        if any(math.isnan(v) for v in errs.values()):
            continue  # not computed
        good = [m for m, v in errs.items() if v <= tol_db]
        if errs[c["auto"]] > tol_db and good:
            bad.append({"k_sigma": ks, "k_l": kl, "auto": c["auto"], "errors": errs})
    return bad


# ----------------------------------------------------------------------------- emissivity
def mom_emissivity(
    k_sigma: float,
    k_l: float,
    eps,
    theta_i_deg: float,
    *,
    realizations: int = 8,
    seed: int = 7,
    length_wl: float = 24.0,
    points_per_wavelength: float = 10.0,
    executor=None,
) -> dict:
    """Emissivity of a 1-D Gaussian profile: MoM ``e = 1 − ⟨P_reflected⟩/P_inc`` (mean over
    realizations, with its standard error) and the second-order SPM emissivity
    (:func:`emscatter.emissivity`, ``method="spm"``: 1 − SPM2 coherent − SPM1 incoherent).

    Returns ``{"h": {...}, "v": {...}}`` with ``mom``, ``mom_se``, ``spm``, ``fresnel`` (flat
    surface), ``difference`` (MoM − SPM), and the MoM discretization.
    """
    from . import emissivity
    from .fresnel import fresnel
    from .solvers import mom

    rough = _rough(k_sigma, k_l)
    ti = math.radians(theta_i_deg)
    ref = mom.bistatic(
        rough,
        eps,
        K,
        ti,
        np.array([0.0]),
        0.0,
        realizations=realizations,
        seed=seed,
        length=max(length_wl, 20 * rough.length),
        points_per_wavelength=points_per_wavelength,
        progress=False,
        executor=executor,
    )
    e_spm = emissivity(rough, eps, wavelength=1.0, theta_i=ti, method="spm")
    rh, rv = fresnel(eps, ti)[:2]
    flat = {"h": 1 - abs(rh) ** 2, "v": 1 - abs(rv) ** 2}
    out = {}
    for ip, p in enumerate("hv"):
        pp = ref.info["per_polarization"][p]
        e_m = 1.0 - pp["reflected"]
        e_s = float(np.ravel(e_spm.emissivity[ip])[0])
        out[p] = {
            "mom": e_m,
            "mom_se": pp["reflected_se"],
            "spm": e_s,
            "fresnel": float(flat[p]),
            "difference": e_m - e_s,
            "transmitted": pp["transmitted"],
        }
    out["unknowns"] = ref.info["unknowns"]
    out["realizations"] = ref.info["realizations"]
    return out


EMISSIVITY_CASES = (
    (0.1, 1.0, 5 + 0.5j, 0.0),
    (0.1, 1.0, 5 + 0.5j, 40.0),
    (0.1, 1.0, 17 + 2j, 0.0),
    (0.1, 1.0, 17 + 2j, 40.0),
    (0.2, 2.0, 17 + 2j, 0.0),
    (0.2, 2.0, 17 + 2j, 40.0),
)


def emissivity_table(out: Path, cases=EMISSIVITY_CASES, *, realizations: int = 8) -> Path:
    """MoM vs second-order SPM emissivity for ``cases`` of ``(kσ, kℓ, ε, θi [deg])``,
    written as ``emissivity_mom_spm2.csv`` under ``out``."""
    cols: dict[str, list] = {
        h: []
        for h in (
            "k_sigma",
            "k_l",
            "eps",
            "theta_i_deg",
            "pol",
            "e_mom",
            "e_mom_se",
            "e_spm2",
            "e_flat",
            "difference",
            "realizations",
            "unknowns",
        )
    }
    for ks, kl, eps, tdeg in cases:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            r = mom_emissivity(
                ks,
                kl,
                eps,
                tdeg,
                realizations=realizations,
                length_wl=16.0,
                points_per_wavelength=15.0,
            )
        for p in "hv":
            vals = (
                ks,
                kl,
                str(complex(eps)),
                tdeg,
                p,
                r[p]["mom"],
                r[p]["mom_se"],
                r[p]["spm"],
                r[p]["fresnel"],
                r[p]["difference"],
                r["realizations"],
                r["unknowns"],
            )
            for h, v in zip(cols, vals, strict=True):
                cols[h].append(v)
    return write_csv(
        Path(out) / "emissivity_mom_spm2.csv",
        tuple(cols),
        [np.array(v, dtype=object) for v in cols.values()],
    )


# ----------------------------------------------------------------------------- plots / files
def _edges(v: np.ndarray) -> np.ndarray:
    lv = np.log(v)
    if v.size == 1:
        return np.exp([lv[0] - 0.3, lv[0] + 0.3])
    mid = 0.5 * (lv[1:] + lv[:-1])
    return np.exp(np.concatenate([[2 * lv[0] - mid[0]], mid, [2 * lv[-1] - mid[-1]]]))


def _matrix(rows, method, pol, ks, kl, key="error_dB"):
    z = np.full((ks.size, kl.size), np.nan)
    for r in rows:
        if r["method"] == method and r["pol"] == pol:
            i = int(np.argmin(np.abs(ks - r["k_sigma"])))
            j = int(np.argmin(np.abs(kl - r["k_l"])))
            z[i, j] = r[key]
    return z


def plot_map(rows: list[dict], cfg: MapConfig, pol: str, path) -> Path:
    """Four heat maps (SPM1, SPM2 coherent, PO, GO) of the error [dB] for ``pol``, values
    printed, the 1 dB contour, and the ``auto`` choice (letter) in every cell."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm
    from matplotlib.ticker import FuncFormatter

    ks = np.asarray(cfg.k_sigma, dtype=float)
    kl = np.asarray(cfg.k_l, dtype=float)
    auto = {(r["k_sigma"], r["k_l"]): r["auto"] for r in rows}
    letters = {"spm1": "S", "go": "G", "po": "P"}
    titles = {
        "spm1": "SPM1 σ⁰",
        "spm2": "SPM2 coherent reflectivity",
        "po": "Kirchhoff PO σ⁰",
        "go": "Kirchhoff GO σ⁰ (shadowed)",
    }
    fig, axes = plt.subplots(2, 2, figsize=(12, 10), constrained_layout=True)
    norm = LogNorm(vmin=0.05, vmax=CAP_DB)
    xe, ye = _edges(kl), _edges(ks)
    mesh = None
    for ax, m in zip(axes.ravel(), METHODS, strict=True):
        z = _matrix(rows, m, pol, ks, kl)
        mesh = ax.pcolormesh(
            xe, ye, np.clip(np.ma.masked_invalid(z), 0.05, CAP_DB), norm=norm, cmap="viridis_r"
        )
        nc = np.zeros_like(z)
        for r in rows:
            if r["method"] == m and r["pol"] == pol and r["status"].startswith("not computed"):
                nc[
                    int(np.argmin(np.abs(ks - r["k_sigma"]))), int(np.argmin(np.abs(kl - r["k_l"])))
                ] = 1
        ax.pcolormesh(xe, ye, np.ma.masked_equal(nc, 0), cmap="Greys", vmin=0, vmax=4)
        ax.set_xscale("log")
        ax.set_yscale("log")
        for axis in (ax.xaxis, ax.yaxis):
            axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
            axis.set_minor_formatter(FuncFormatter(lambda v, _: ""))
        ax.set_xticks(kl)
        ax.set_yticks(ks)
        finite = np.isfinite(z)
        if finite.sum() >= 4 and ks.size > 1 and kl.size > 1:
            zc = np.where(finite, z, CAP_DB)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                ax.contour(kl, ks, zc, levels=[TOL_DB], colors="red", linewidths=2)
        for i in range(ks.size):
            for j in range(kl.size):
                txt = "—" if not np.isfinite(z[i, j]) else f"{z[i, j]:.2g}"
                a = letters.get(auto.get((float(ks[i]), float(kl[j])), ""), "")
                color = "white" if np.isfinite(z[i, j]) and z[i, j] > 3 else "black"
                ax.text(kl[j], ks[i], txt, ha="center", va="center", fontsize=8, color=color)
                if m != "spm2":
                    ax.text(
                        kl[j] * 1.12,
                        ks[i] * 1.12,
                        a,
                        ha="left",
                        va="bottom",
                        fontsize=7,
                        color="red" if letters.get(m) == a else "grey",
                    )
        ax.set_xlabel("kℓ")
        ax.set_ylabel("kσ")
        ax.set_title(titles[m])
    eps = cfg.eps if isinstance(cfg.eps, str) else f"ε = {complex(cfg.eps)}"
    fig.suptitle(
        f"Error vs method of moments [dB], pol {pol} ({'TE' if pol == 'h' else 'TM'}), "
        f"{eps}, θi = {cfg.theta_i_deg:g}°, Gaussian 1-D; red line: 1 dB; "
        "letters: auto choice (S/G/P)\ngrey: not computed (rms slope too steep); "
        "'—' in SPM2: MoM coherent reflectivity below its noise"
    )
    fig.colorbar(mesh, ax=axes, shrink=0.6, label="error [dB]")
    return save_figure(fig, path)


CSV_HEADER = (
    "k_sigma",
    "k_l",
    "rms_slope",
    "method",
    "pol",
    "error_dB",
    "max_error_dB",
    "n_bins",
    "mom_se_dB",
    "valid",
    "auto",
    "status",
    "realizations",
    "unknowns",
    "seconds",
)


def _tag(cfg: MapConfig) -> str:
    if isinstance(cfg.eps, str):
        return str(cfg.eps)
    e = complex(cfg.eps)
    return f"eps{e.real:g}{e.imag:+g}j"


def write_map(rows: list[dict], cfg: MapConfig, out: Path, *, seconds: float = 0.0) -> list[Path]:
    """CSV (all numbers), JSON (configuration, selector failures) and one PNG per pol."""
    out = Path(out)
    tag = _tag(cfg)
    cols = [np.array([r[h] for r in rows], dtype=object) for h in CSV_HEADER]
    paths = [write_csv(out / f"validity_{tag}.csv", CSV_HEADER, cols)]
    meta = {
        "config": {**asdict(cfg), "eps": str(cfg.eps)},
        "wavelength_m": 1.0,
        "seconds": seconds,
        "selector_failures": selector_failures(rows),
    }
    paths.append(write_json(out / f"validity_{tag}.json", meta))
    for p in "hv":
        paths.append(plot_map(rows, cfg, p, out / f"validity_{tag}_{p}.png"))
    return paths


def markdown_table(rows: list[dict]) -> str:
    """The map as a Markdown table: one line per cell, errors h/v per method."""
    cells: dict = {}
    for r in rows:
        c = cells.setdefault((r["k_sigma"], r["k_l"]), {"auto": r["auto"], "m": r["rms_slope"]})
        c[(r["method"], r["pol"])] = r["error_dB"]
    head = "| kσ | kℓ | slope | auto | " + " | ".join(f"{m} h/v" for m in METHODS) + " |"
    lines = [head, "|" + "---|" * (4 + len(METHODS))]

    def f(v):
        return "—" if not np.isfinite(v) else f"{v:.2f}"

    for (ks, kl), c in sorted(cells.items()):
        vals = " | ".join(f"{f(c[(m, 'h')])} / {f(c[(m, 'v')])}" for m in METHODS)
        lines.append(f"| {ks:g} | {kl:g} | {c['m']:.2f} | {c['auto']} | {vals} |")
    return "\n".join(lines) + "\n"


def auto_choice(k_sigma: float, k_l: float, cfg: MapConfig = FULL) -> str:
    """The map name (``spm1``/``go``/``po``) of ``method="auto"``'s choice for a cell (at the
    map's ε and θi)."""
    from .solvers.select import select_method

    ti = math.radians(cfg.theta_i_deg)
    return AUTO_TO_MAP[select_method(_rough(k_sigma, k_l), K, eps=cfg.eps, theta_i=ti)[0]]


_NUMERIC = ("k_sigma", "k_l", "rms_slope", "error_dB", "max_error_dB", "mom_se_dB", "seconds")


def read_map(path) -> list[dict]:
    """Rows of a map CSV written by :func:`write_map` (numbers parsed)."""
    import csv

    with open(path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    for r in rows:
        for key in _NUMERIC:
            r[key] = float(r[key])
        for key in ("n_bins", "realizations", "unknowns"):
            r[key] = int(r[key])
        r["valid"] = r["valid"] == "True"
    return rows


def reselect(out: Path, cfg: MapConfig = FULL) -> list[Path]:
    """Re-evaluate the ``auto`` choice (and each method's ``valid`` flag) of a written map
    with the current validity criteria, without recomputing the method of moments (its
    numbers do not depend on the selector); rewrites the CSV, JSON, PNGs and table."""
    import json

    from .io import atomic_path
    from .solvers import kirchhoff_go, kirchhoff_po, spm

    out = Path(out)
    tag = _tag(cfg)
    rows = read_map(out / f"validity_{tag}.csv")
    checks = {"spm1": spm, "spm2": spm, "po": kirchhoff_po, "go": kirchhoff_go}
    for r in rows:
        r["auto"] = auto_choice(r["k_sigma"], r["k_l"], cfg)
        r["valid"] = checks[r["method"]].check_validity(
            _rough(r["k_sigma"], r["k_l"]),
            K,
            eps=cfg.eps,
            theta_i=math.radians(cfg.theta_i_deg),
        )["valid"]
    old = json.loads((out / f"validity_{tag}.json").read_text())
    paths = write_map(rows, cfg, out, seconds=float(old.get("seconds", 0.0)))
    md = out / f"validity_{tag}.md"
    with atomic_path(md) as tmp:
        tmp.write_text(markdown_table(rows))
    return [*paths, md]


def run_validation(
    out: Path, *, full: bool = False, config: MapConfig | None = None, progress: bool = True
) -> list[Path]:
    """Compute and write the validity maps (``emscatter validate``): the small grid
    (:data:`SMALL`) by default, the published grids (:data:`FULL`, PEC, and
    :data:`FULL_DIELECTRIC`, ε = 3) and the emissivity table with ``full=True``, or
    ``config``. Writes ``validity_<eps>.csv/.json``, ``validity_<eps>_{h,v}.png`` and
    ``validity_<eps>.md`` under ``out``; returns the paths."""
    from .io import atomic_path

    if config is not None:
        configs = [config]
    else:
        configs = [FULL, FULL_DIELECTRIC] if full else [SMALL]
    out = Path(out)
    paths: list[Path] = []
    for cfg in configs:
        t0 = time.perf_counter()
        rows = compute_map(cfg, progress=progress)
        seconds = time.perf_counter() - t0
        paths.extend(write_map(rows, cfg, out, seconds=seconds))
        md = out / f"validity_{_tag(cfg)}.md"
        with atomic_path(md) as tmp:
            tmp.write_text(markdown_table(rows))
        paths.append(md)
    if full and config is None:
        paths.append(emissivity_table(out))
    return paths
