"""Cross-check 3: how much the specular path of one wall loses to roughness, 1–300 GHz.

Loss = coherent reflectivity of the rough wall over the flat wall's Fresnel reflectivity,
``L_p(f) = r_coh,p / |R_p|²`` [dB], at a fixed incidence angle, from

* emscatter (``method="auto"`` per frequency: the second-order small-perturbation mean field
  at low ``kσ``, the Kirchhoff mean field of physical / geometric optics above), with the method
  and its validity recorded per frequency;
* the Ament (1953) / Rayleigh factor ``exp(−2(kσ cosθ)²)`` on the field — squared for power;
* the Boithias (1987) factor ``exp(−g/2) I₀(g/2)``, ``g = (2kσ cosθ)²``, on the field — squared.

Why they differ: Ament's factor is the Kirchhoff mean field ``⟨e^{2ik_z h}⟩`` for Gaussian
heights, so it is exactly emscatter's result wherever a Kirchhoff method is chosen. At small
``kℓ`` the small-perturbation mean field loses *less*: only the roughness spectrum inside the
propagating band (``|K| < 2k``) scatters power out of the specular direction, the rest merely
loads the interface reactively — Ament (which assumes every height fluctuation dephases the
field, ``kℓ → ∞``) over-predicts the loss there. Boithias' factor was derived (Miller, Brown &
Vegh 1984) for a sea surface of sinusoidal swell, whose height distribution has no Gaussian
tails: for ``g ≳ 1`` it decays like ``1/√(πg)`` instead of exponentially, so it keeps far more
specular power at millimetre waves than any Gaussian-surface model.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from ..coherent import ament_factor, boithias_factor, coherent_amplitude
from ..conventions import wavenumber
from ..fresnel import fresnel
from ..progress import task
from .medium import resolve_medium

__all__ = ["sweep", "write_outputs", "DEFAULT_WALL"]


def DEFAULT_WALL():  # noqa: N802  (a constant that needs an import)
    """The swept wall: plastered concrete, σ = 0.4 mm, ℓ = 4 mm (indoor.ROUGHNESS)."""
    from .indoor import ROUGHNESS

    return ROUGHNESS["concrete"]


def sweep(
    surface, medium="concrete", *, theta_deg: float = 30.0, frequencies=None, progress=None
) -> dict:
    """Specular loss to roughness [dB] (module docstring) per frequency [Hz].

    ``progress``: a tqdm bar over the frequencies on stderr — ``None`` (auto) on a terminal
    past 2 s, ``True`` always, ``False`` never (:mod:`emscatter.progress`). The ITU medium is
    used with its documented extrapolation where a frequency falls between or beyond its bands
    (concrete has none at 100–110 GHz and above 330 GHz)."""
    from .. import materials

    f = np.geomspace(1e9, 300e9, 60) if frequencies is None else np.asarray(frequencies, float)
    med = resolve_medium(medium)
    if isinstance(med, materials.ItuMaterial) and not med.extrapolate:
        med = materials.itu(med.name, extrapolate=True)
    th = math.radians(theta_deg)
    out = {k: [] for k in ("frequency_ghz", "method", "valid", "k_sigma", "k_length")}
    for key in ("emscatter_h_db", "emscatter_v_db", "ament_db", "boithias_db"):
        out[key] = []
    with task("frequency sweep", f.size, progress, unit="f") as bar:
        for fi in f:
            _sweep_row(out, surface, med, th, float(fi))
            bar.update(1)
    return {k: np.asarray(v) for k, v in out.items()} | {"theta_deg": theta_deg}


def _sweep_row(out: dict, surface, med, th: float, fi: float) -> None:
    """One frequency's row of :func:`sweep`, appended to ``out``."""
    k = wavenumber(frequency=float(fi))
    eps = complex(np.asarray(med.eps(frequency=float(fi))))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # validity is recorded per row instead
        c = coherent_amplitude(surface, eps, k, th, out_of_range="ignore")
    rh, rv = fresnel(eps, th)
    out["frequency_ghz"].append(fi / 1e9)
    out["method"].append(c.method)
    out["valid"].append(bool(c.validity.get("valid", True)))
    out["k_sigma"].append(k * surface.sigma)
    out["k_length"].append(k * surface.length)
    out["emscatter_h_db"].append(10 * math.log10(max(float(c.power[0]) / abs(rh) ** 2, 1e-300)))
    out["emscatter_v_db"].append(10 * math.log10(max(float(c.power[1]) / abs(rv) ** 2, 1e-300)))
    out["ament_db"].append(20 * math.log10(max(float(ament_factor(k, surface.sigma, th)), 1e-150)))
    out["boithias_db"].append(20 * math.log10(float(boithias_factor(k, surface.sigma, th))))


def write_outputs(results: list, out_dir, stem: str = "frequency_sweep") -> list:
    """CSV (all rows, all angles) and PNG (loss vs frequency, one panel per angle)."""
    from pathlib import Path

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..io import save_figure, write_csv

    out = Path(out_dir)
    cols = ["theta_deg", "frequency_ghz", "method", "valid", "k_sigma", "k_length",
            "emscatter_h_db", "emscatter_v_db", "ament_db", "boithias_db"]  # fmt: skip
    data = {c: np.concatenate([np.broadcast_to(r[c], r["frequency_ghz"].shape) for r in results])
            for c in cols}  # fmt: skip
    csv_path = write_csv(out / f"{stem}.csv", cols, [data[c] for c in cols])
    fig, axes = plt.subplots(
        1, len(results) + 1, figsize=(5.0 * (len(results) + 1), 4.2), squeeze=False
    )
    for ax, r in zip(axes[0], results, strict=False):
        f = r["frequency_ghz"]
        ax.semilogx(f, r["ament_db"], "k--", label="Ament exp(−2(kσcosθ)²)²")
        ax.semilogx(f, r["boithias_db"], "k:", label="Boithias [exp(−g/2) I₀(g/2)]²")
        for m, style in (("spm", "o"), ("po", "s"), ("go", "^")):
            sel = r["method"] == m
            if np.any(sel):
                ax.semilogx(f[sel], r["emscatter_h_db"][sel], style, ms=4, mfc="none", color="C0",
                            label=f"emscatter h ({m})")  # fmt: skip
                ax.semilogx(f[sel], r["emscatter_v_db"][sel], style, ms=3, color="C3",
                            label=f"emscatter v ({m})")  # fmt: skip
        bad = ~r["valid"]
        if np.any(bad):
            ax.semilogx(
                f[bad], r["emscatter_h_db"][bad], "x", color="0.4", label="outside validity"
            )
        top = max(1.0, float(np.nanmax(np.r_[r["emscatter_h_db"], r["emscatter_v_db"]])) + 0.5)
        ax.set_ylim(max(-40.0, float(np.nanmin(r["ament_db"])) - 3), top)
        ax.set_xlabel("frequency [GHz]")
        ax.set_ylabel("specular loss to roughness [dB]")
        ax.set_title(f"θi = {r['theta_deg']:g}°")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7, loc="lower left")
    ax = axes[0, -1]
    for i, r in enumerate(results):
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = r["emscatter_h_db"] / r["ament_db"]
        ax.semilogx(
            r["k_length"], ratio, "o-", ms=3, color=f"C{i}", label=f"h, θi = {r['theta_deg']:g}°"
        )
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_xlabel("kℓ")
    ax.set_ylabel("emscatter loss / Ament loss (dB / dB)")
    ax.set_title("small kℓ: transition layer, not dephasing")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.suptitle("One wall (concrete, σ = 0.4 mm, ℓ = 4 mm): coherent reflectivity / Fresnel")
    png = save_figure(fig, out / f"{stem}.png")
    return [csv_path, png]
