"""Cross-check 1: a large rough plate, a transmitter and a receiver above it.

What Sionna RT computes with the emscatter material is compared with what emscatter predicts
without Sionna:

* **specular** — the image path: ``|a|² = |r_coh,p(θ)|² (λ / 4πL)²`` with ``L = r₁ + r₂`` and
  ``r_coh`` from :func:`emscatter.coherent.coherent_amplitude` at the exact incidence
  angle (the material interpolates a table; Sionna works in float32);
* **diffuse** — the bistatic radar equation integrated over the plate,
  ``P_r / P_t = ∫ λ² σ⁰_qp(θi, θs, φ) / ((4π)³ r₁² r₂²) dA`` (isotropic antennas of unit gain),
  with σ⁰ from the same solver at the exact angles, on graded Gauss–Legendre panels around the
  specular point (error from one refinement). Sionna's estimate is a sum over the diffuse hits of
  its ray lattice; its sampling noise is estimated from the spread of the per-hit
  contributions (the Monte Carlo standard error, conservative for Sionna's quasi-random
  Fibonacci lattice) and shown beside the difference.

The plate lies in ``z = 0``, so the antennas' ``V`` (θ̂) and ``H`` (φ̂) polarizations are the
local TM (``v``) and TE (``h``) ones at every point of it: ``VV ↔ σ⁰_vv``, ``HH ↔ σ⁰_hh``,
``(rx H, tx V) ↔ σ⁰_hv`` (scattered h from incident v).
"""

from __future__ import annotations

import inspect
import math
from dataclasses import dataclass

import numpy as np

from ..constants import SPEED_OF_LIGHT
from ..conventions import wavenumber
from .medium import resolve_medium

__all__ = ["PlateCase", "specular_prediction", "diffuse_prediction", "sionna_plate", "POL_PAIRS"]

#: (rx antenna, tx antenna) → emscatter σ⁰ index [pol_s, pol_i].
POL_PAIRS = {"VV": (1, 1), "HH": (0, 0), "HV": (0, 1), "VH": (1, 0)}
_ANT = {"V": 0, "H": 1}  # antenna index in Sionna's "VH" polarization model


@dataclass(frozen=True)
class PlateCase:
    """One configuration: frequency [Hz], roughness, medium, geometry [m]."""

    frequency: float
    surface: object
    medium: object = "concrete"
    theta_deg: float = 60.0
    height: float = 2.0
    size: float = 40.0
    method: str = "auto"

    @property
    def tx(self) -> np.ndarray:
        x0 = self.height * math.tan(math.radians(self.theta_deg))
        return np.array([-x0, 0.0, self.height])

    @property
    def rx(self) -> np.ndarray:
        return self.tx * np.array([-1.0, 1.0, 1.0])

    @property
    def eps(self) -> complex:
        return complex(np.asarray(resolve_medium(self.medium).eps(frequency=self.frequency)))


def specular_prediction(case: PlateCase) -> dict:
    """Image-path gain per co-polarization (``"VV"`` → v, ``"HH"`` → h) [linear], and the
    method used."""
    from ..coherent import coherent_amplitude

    k = wavenumber(frequency=case.frequency)
    lam = SPEED_OF_LIGHT / case.frequency
    length = float(np.linalg.norm(case.tx - case.rx * np.array([1.0, 1.0, -1.0])))
    coh = coherent_amplitude(
        case.surface,
        case.eps,
        k,
        math.radians(case.theta_deg),
        method=case.method,
        out_of_range="ignore",
    )
    free = (lam / (4 * math.pi * length)) ** 2
    return {
        "VV": float(coh.power[1]) * free,
        "HH": float(coh.power[0]) * free,
        "method": coh.method,
    }


def _graded_nodes(half: float, finest: float, near: float, width: float, order: int):
    """Gauss–Legendre nodes/weights on [−half, half]: panels start at ``finest`` around 0 (the
    specular point), grow ×2 up to ``width`` while ``|x| < near`` (the antennas' nadir region,
    where ``1/r²`` varies on the height scale), then up to ``|x|/4`` further out."""
    edges = [0.0]
    w = finest
    while edges[-1] < half:
        x = edges[-1]
        cap = width if x < near else max(width, 0.25 * x)
        w = min(2.0 * w, cap)
        edges.append(min(x + w, half))
    xg, wg = np.polynomial.legendre.leggauss(order)
    e = np.asarray(edges)
    a, b = e[:-1, None], e[1:, None]
    n = (0.5 * (b - a) * xg + 0.5 * (a + b)).ravel()
    wt = (0.5 * (b - a) * wg).ravel()
    return np.concatenate([-n[::-1], n]), np.concatenate([wt[::-1], wt])


def _radar_integral(case: PlateCase, method: str, order: int) -> np.ndarray:
    from ..solvers import get

    k = wavenumber(frequency=case.frequency)
    lam = SPEED_OF_LIGHT / case.frequency
    x0, h, half = float(case.rx[0]), case.height, case.size / 2
    xs, wx = _graded_nodes(half, 0.005, 2 * x0 + 2 * h, h / 4, order)
    ys, wy = _graded_nodes(half, 0.005, 2 * h, h / 4, order)
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    W = wx[:, None] * wy[None, :]
    p = np.stack([X, Y, np.zeros_like(X)], axis=-1)
    d1 = p - case.tx  # propagation towards the plate
    d2 = case.rx - p  # propagation towards the receiver
    r1, r2 = np.linalg.norm(d1, axis=-1), np.linalg.norm(d2, axis=-1)
    theta_i = np.arccos(np.clip(-d1[..., 2] / r1, 0.0, 1.0))
    theta_s = np.arccos(np.clip(d2[..., 2] / r2, 0.0, 1.0))
    phi_i = np.arctan2(d1[..., 1], d1[..., 0])
    phi_s = np.arctan2(d2[..., 1], d2[..., 0])
    module = get(method)
    skip = (
        {"coherent": False} if "coherent" in inspect.signature(module.bistatic).parameters else {}
    )
    sig = module.bistatic(case.surface, case.eps, k, theta_i, theta_s, phi_s, phi_i, **skip).sigma0
    integrand = lam**2 * sig / ((4 * math.pi) ** 3 * r1**2 * r2**2)
    return np.einsum("psxy,xy->ps", integrand, W)


def diffuse_prediction(case: PlateCase, order: int = 6) -> dict:
    """Radar-equation path gain per antenna pair (``"VV"``, ``"HH"``, ``"HV"``, ``"VH"``,
    rx then tx) [linear], with ``"error"``: relative change from ``order`` to ``2·order``."""
    from .. import api

    name, _, _, _ = api.resolve_method(
        case.surface, wavenumber(frequency=case.frequency), case.method, "ignore", case.eps
    )
    coarse = _radar_integral(case, name, order)
    fine = _radar_integral(case, name, 2 * order)
    out = {pair: float(fine[s, i]) for pair, (s, i) in POL_PAIRS.items()}
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.abs(fine - coarse) / np.where(fine > 0, fine, 1.0)
    out["error"] = {pair: float(rel[s, i]) for pair, (s, i) in POL_PAIRS.items()}
    out["method"] = name
    return out


def sionna_plate(
    case: PlateCase, *, samples: int, diffuse: bool, seed: int = 1, table_options=None
):
    """Sionna RT on the plate with the emscatter material (half-space).

    Returns ``{"VV", "HH", "HV", "VH": path gain [linear], "noise": {pair: relative MC standard
    error}, "paths": n, "tables": RadioTables}``: specular only (image path, no LoS) when
    ``diffuse`` is False, diffuse reflection only when True."""
    import sionna.rt as rt

    from . import scenes
    from .material import EmscatterRadioMaterial

    def make(name, medium, thickness):
        return EmscatterRadioMaterial(
            f"em-{name}",
            surface=case.surface,
            medium=case.medium,
            thickness=None,
            method=case.method,
            table_options=table_options,
        )

    scene = scenes.load(scenes.plate(case.size), case.frequency, make)
    arr = rt.PlanarArray(num_rows=1, num_cols=1, pattern="iso", polarization="VH")
    scene.tx_array = arr
    scene.rx_array = arr
    scene.add(rt.Transmitter("tx", position=case.tx.tolist()))
    scene.add(rt.Receiver("rx", position=case.rx.tolist()))
    solver = rt.PathSolver()
    paths = solver(
        scene,
        max_depth=1,
        samples_per_src=int(samples),
        max_num_paths_per_src=int(samples),
        los=False,
        specular_reflection=not diffuse,
        diffuse_reflection=diffuse,
        refraction=False,
        seed=seed,
    )
    re, im = (np.asarray(x.numpy()) for x in paths.a)
    power = re**2 + im**2  # [rx, rx_ant, tx, tx_ant, path]
    out: dict = {"paths": int(power.shape[-1]), "noise": {}}
    for pair in POL_PAIRS:
        contrib = power[0, _ANT[pair[0]], 0, _ANT[pair[1]]]
        total = float(contrib.sum())
        out[pair] = total
        n = max(int(np.count_nonzero(contrib)), 1)
        out["noise"][pair] = float(math.sqrt(n) * contrib.std() / total) if total > 0 else math.nan
    mat = scene.get("em-plate")
    out["tables"] = mat.active_tables
    return out


#: The published cross-check: frequencies [Hz] and two roughnesses (Gaussian correlation).
FREQUENCIES = (3.5e9, 28e9, 140e9)
TOLERANCE_DB = {"specular": 0.01, "diffuse": 0.2}


def roughnesses() -> dict:
    """The two roughnesses of the cross-check: σ = 0.2 mm, ℓ = 5 mm and σ = 1 mm, ℓ = 10 mm."""
    from ..spectra import GaussianCorrelation

    return {
        "sigma0.2mm_l5mm": GaussianCorrelation(sigma=0.2e-3, length=5e-3),
        "sigma1mm_l10mm": GaussianCorrelation(sigma=1e-3, length=10e-3),
    }


def check(cases: dict, *, samples: int, pairs=("VV", "HH", "HV"), table_options=None) -> list:
    """Run Sionna and the predictions for ``{name: PlateCase}``; one row per comparison:
    ``case, frequency_ghz, kind, pair, sionna_db, emscatter_db, diff_db, tolerance_db,
    noise_db, method, valid, ok``."""
    rows = []

    def db(x):
        return 10.0 * math.log10(x) if x > 0 else -math.inf

    for name, case in cases.items():
        spec_pred = specular_prediction(case)
        spec = sionna_plate(case, samples=10_000, diffuse=False, table_options=table_options)
        dif_pred = diffuse_prediction(case)
        dif = sionna_plate(case, samples=samples, diffuse=True, table_options=table_options)
        tab = dif["tables"]
        common = {
            "case": name,
            "frequency_ghz": case.frequency / 1e9,
            "method": tab.method,
            "valid": bool(tab.valid),
        }
        for pair in ("VV", "HH"):
            d = db(spec[pair]) - db(spec_pred[pair])
            rows.append(
                {**common, "kind": "specular", "pair": pair, "sionna_db": db(spec[pair]),
                 "emscatter_db": db(spec_pred[pair]), "diff_db": d,
                 "tolerance_db": TOLERANCE_DB["specular"], "noise_db": 0.0,
                 "ok": abs(d) <= TOLERANCE_DB["specular"]}
            )  # fmt: skip
        for pair in pairs:
            d = db(dif[pair]) - db(dif_pred[pair])
            noise = 10.0 * math.log10(1.0 + dif["noise"][pair])
            rows.append(
                {**common, "kind": "diffuse", "pair": pair, "sionna_db": db(dif[pair]),
                 "emscatter_db": db(dif_pred[pair]), "diff_db": d,
                 "tolerance_db": TOLERANCE_DB["diffuse"], "noise_db": noise,
                 "ok": abs(d) <= TOLERANCE_DB["diffuse"]}
            )  # fmt: skip
    return rows


def write_outputs(rows: list, out_dir, stem: str = "plate_check") -> list:
    """``<stem>.csv`` and ``<stem>.png`` (difference per comparison, tolerance and noise)."""
    from pathlib import Path

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..io import save_figure, write_csv

    out = Path(out_dir)
    keys = list(rows[0])
    csv_path = write_csv(out / f"{stem}.csv", keys, [np.array([r[k] for r in rows]) for k in keys])
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), sharey=False)
    for ax, kind in zip(axes, ("specular", "diffuse"), strict=True):
        sel = [r for r in rows if r["kind"] == kind]
        labels = [f"{r['frequency_ghz']:g} GHz\n{r['case'].split('_')[0]} {r['pair']}" for r in sel]
        x = np.arange(len(sel))
        ax.axhspan(-TOLERANCE_DB[kind], TOLERANCE_DB[kind], color="0.9", label="tolerance")
        ax.errorbar(
            x, [r["diff_db"] for r in sel], yerr=[r["noise_db"] for r in sel], fmt="o",
            color="C0" if kind == "specular" else "C1", label="Sionna − emscatter (± noise)",
        )  # fmt: skip
        ax.axhline(0, color="k", lw=0.6)
        ax.set_xticks(x, labels, rotation=90, fontsize=7)
        ax.set_ylabel("difference [dB]")
        ax.set_title(
            "specular: image path × coherent reflection"
            if kind == "specular"
            else "diffuse: bistatic radar equation over the plate"
        )
        ax.legend(fontsize=8, loc="upper right")
    fig.suptitle("Large plate, Sionna RT with the emscatter material vs emscatter alone")
    png = save_figure(fig, out / f"{stem}.png")
    return [csv_path, png]
