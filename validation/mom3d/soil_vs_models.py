"""The exact 3-D σ⁰ of a soil-like dielectric surface beside SPM, IEM, PO and GO (issue 19).

Case: L-band (1.4 GHz, λ₀ = 0.214 m) over a dry-ish soil, Mironov et al. (2009) at 8 %
volumetric moisture and 20 % clay, ε = 4.39 + 0.363i (``MironovSoil(0.08, 0.2)``; its
ε′ ≤ 5 keeps a 3λ patch's dense Müller matrix at 1.7 GB). Gaussian correlation, kσ = 0.3,
kℓ = 3 (rms slope per axis √2σ/ℓ = 0.14), θi = 40°, a 3λ₀ × 3λ₀ patch at 8 points per
wavelength inside the soil (λ₀ / Re√ε / 8; 51² nodes, 10 404 unknowns), taper g = L/4,
Monte Carlo over ``--realizations`` surfaces (default 16, seeds ``SeedSequence(19).spawn``).

Why Gaussian, not the exponential correlation measured on many soils: an exponential
surface has no rms slope (its structure function is linear at the origin), so a sampled one
has the slope of its grid (≈ 0.5 per axis at λ₀/16 for this kσ, kℓ) and the MoM's answer
moves with the grid; the Gaussian surface is resolved (7.6 nodes per ℓ) and GO has a slope.

Each realization is solved by
:func:`emscatter.solvers.mom3d.dielectric_model.solve_dielectric_realization` on the surface
:func:`emscatter.solvers.mom3d.bistatic` draws for the same seed, and the Monte Carlo σ⁰ is
bistatic's estimator (per realization ``n/(n−1)·|A − ⟨A⟩|²`` scaled, the ``sigma0_samples``);
``tests/test_mom3d_soil.py`` checks on a tiny patch that the two agree to rounding. The loop
is here and not in ``bistatic`` for the energy check of a lossy medium: besides the
reflectivity R (far field over the upper hemisphere), the power A entering the soil is the
Poynting flux through the surface from the solved currents (``J = n̂ × H``, ``M = −n̂ × E``:
``E_t × H_t*·n̂ dS = n̂·(u* × w) dx dy / s``), and R + A = 1 per realization is the check.
Error bars: ± one standard error over the realizations.

The finite beam: the taper is a Gaussian spectrum of plane waves (:mod:`.incident`), whose
incident power spreads over ``k⊥`` with standard deviation ``1/g`` per axis, i.e. about
``1/(k g cosθi)`` rad in θi (≈ 16° here). The incoherent σ⁰ of the patch is the plane-wave
σ⁰ averaged over that spectrum (distinct ``k⊥`` of a stationary surface scatter
incoherently): ``σ⁰_beam(k_s) = cosθi Σ_j I_j σ⁰(k_j → k_s) / Σ_j I_j cosθ_j`` with
``I_j = ψ_j²``, each component taken in its own h, v basis. The ``*_beam`` columns are the
models so averaged (the figure's curves); the plain columns are the models at the nominal
incidence (thin lines). This holds for the co-pol in the plane and for hv in the cross plane
φs = 90° (first order, within the basis mismatch ~(1 − cos φ_j) ≈ 5 % in power). It does not
hold for hv in the plane (and vv, hh at φs = 90° near nadir): there first-order σ⁰ vanishes
for the nominal plane wave, and the beam's off-plane components give an hv whose value
depends on the coherent sum of their co- and cross-pol amplitudes (the beam's ê_h is not
its components' ĥ_j), which σ⁰ alone does not carry; summing σ⁰ gives ≈ −16 dB where the
MoM has −29 … −47 dB. So in the plane hv is compared with second-order SPM
(``emscatter.solvers.spm.crosspol.sigma0_22``, nominal incidence) only, as a reference.

Run: PYTHONPATH=src python validation/mom3d/soil_vs_models.py [--realizations 16]   (≈ 13 min)
     [--models-only] [--plot-only]
``--models-only`` recomputes the model columns keeping the stored MoM ones; ``--plot-only``
redraws. Writes soil_vs_models.csv/.md/.png here and docs/figures/mom3d_soil_vs_models.png.
"""

from __future__ import annotations

import argparse
import math
import platform
import shutil
import time
import warnings
from pathlib import Path

import numpy as np

import emscatter as em
from emscatter.constants import SPEED_OF_LIGHT
from emscatter.io import atomic_path, read_csv, save_figure, write_csv
from emscatter.materials.soil import MironovSoil
from emscatter.solvers.mom3d.dielectric_model import solve_dielectric_realization
from emscatter.solvers.mom3d.incident import tapered_beam
from emscatter.solvers.mom3d.operator import make_patch
from emscatter.solvers.spm.crosspol import sigma0_22
from emscatter.spectra import GaussianCorrelation
from emscatter.surfaces.generate import generate_surface

HERE = Path(__file__).resolve().parent
CSV, MD, PNG = (HERE / f"soil_vs_models.{s}" for s in ("csv", "md", "png"))
FIGURE = HERE.parents[1] / "docs" / "figures" / "mom3d_soil_vs_models.png"
COMMAND = "PYTHONPATH=src python validation/mom3d/soil_vs_models.py --realizations {n}"
FREQ = 1.4e9
MOISTURE, CLAY = 0.08, 0.2
KS, KL, THETA_I, LENGTH_WL, PPW, SEED = 0.3, 3.0, 40.0, 3.0, 8.0, 19
MODELS = ("spm", "iem", "po", "go")
POLS = {"hh": (0, 0), "vv": (1, 1), "hv": (0, 1), "vh": (1, 0)}
#: beam components whose power ψ² is below this fraction of the peak are dropped (models)
BEAM_CUT = 1e-4


def case():
    """``(roughness, eps, k, lam0)`` of the soil case [m, rad/m]."""
    lam0 = SPEED_OF_LIGHT / FREQ
    k = 2 * math.pi / lam0
    eps = complex(MironovSoil(moisture=MOISTURE, clay=CLAY).eps(frequency=FREQ))
    return GaussianCorrelation(KS / k, KL / k), eps, k, lam0


def directions():
    """``(cut, signed θs [deg], θs, φs [rad])``: the plane of incidence (θs < 0: φs = π) and
    the cross plane φs = 90°."""
    plane = np.arange(-70.0, 71.0, 5.0)
    cross = np.arange(0.0, 71.0, 5.0)
    deg = np.concatenate([plane, cross])
    cut = np.concatenate([np.zeros(plane.size), np.ones(cross.size)])
    ts = np.radians(np.abs(deg))
    ps = np.where(cut == 1, math.pi / 2, np.where(deg < 0, math.pi, 0.0))
    return cut, deg, ts, ps


def grid(eps, k, length):
    """Nodes per side and spacing [m] as :func:`emscatter.solvers.mom3d.bistatic` takes them
    (``points_per_wavelength`` inside the denser medium)."""
    lam = 2 * math.pi / k / max(1.0, np.sqrt(eps).real)
    return int(math.ceil(length / lam * PPW)), lam / PPW


def absorbed(out: dict, heights, spacing: float) -> np.ndarray:
    """Power entering the lower medium over the incident power, ``(2,)`` for h and v: the
    Poynting flux ``−Re ∫ n̂·(E_t × H_t*) dS = −Re Σ n̂·(u* × w) Δx Δy / s`` of the solved
    densities (module docstring; flux units of :mod:`.incident`, η = 1, no ½)."""
    p = make_patch(heights, spacing, spacing)
    normal = np.stack([-p.fx, -p.fy, np.ones_like(p.fx)], axis=1)
    s2 = np.sum(normal * normal, axis=1)  # s² (n̂/s = N/s²)
    flux = np.einsum("ni,pni->p", normal / s2[:, None], np.cross(np.conj(out["u"]), out["w"]))
    return -flux.real * spacing * spacing / out["power"]


def realization(rough, eps, k, length, ti, ts, ps, ss, taper_g=None) -> dict:
    """One soil realization from seed ``ss``: amplitudes, R, A, iterations, seconds."""
    n_side, spacing = grid(eps, k, length)
    surf = generate_surface(rough, (n_side, n_side), spacing, rng=np.random.default_rng(ss))
    out = solve_dielectric_realization(surf.heights, spacing, k, eps, ti, ts, ps,
                                       taper_g=taper_g)  # fmt: skip
    a = absorbed(out, surf.heights, spacing)
    return {
        "amplitude": out["amplitude"],
        "power": out["power"],
        "reflectivity": out["reflectivity"],
        "absorbed": a,
        "iterations": int(np.max(out["iterations"])),
        "seconds": out["seconds"]["total"],
        "unknowns": out["unknowns"],
        "taper_g": out["taper_g"],
        "beam": out["beam"],
    }


def monte_carlo(results: list[dict], k: float, ti: float) -> dict:
    """σ⁰ ``(2, 2, D)``, its per-realization samples ``(n, 2, 2, D)`` and standard error,
    by the estimator of :func:`emscatter.solvers.mom3d.bistatic`."""
    n = len(results)
    a = np.stack([r["amplitude"] for r in results])
    scale = 4.0 * math.pi * math.cos(ti) * k * k / (16.0 * math.pi**2) / results[0]["power"]
    samples = scale * n / (n - 1) * np.abs(a - a.mean(axis=0)) ** 2
    return {
        "sigma0": samples.mean(axis=0),
        "samples": samples,
        "se": samples.std(axis=0, ddof=1) / math.sqrt(n),
    }


def beam_components(beam):
    """``(θ_j, φ_j, weight)`` of the beam's plane waves kept for the models (power ψ² at least
    :data:`BEAM_CUT` of the peak): ``weight = cosθi I_j / Σ I_j cosθ_j`` over all of them, so
    that ``Σ weight·σ⁰_j`` is the beam's σ⁰ (module docstring)."""
    kh = beam.kvec / beam.k
    cos_t = -kh[:, 2]
    inten = np.abs(beam.weight) ** 2
    keep = inten >= BEAM_CUT * inten.max()
    th, ph = np.arccos(np.clip(cos_t, -1, 1)), np.arctan2(kh[:, 1], kh[:, 0])
    w = inten * math.cos(beam.theta_i) / np.sum(inten * cos_t)
    return th[keep], ph[keep], w[keep]


def models(rough, eps, k, ti, ts, ps, beam) -> dict:
    """Model σ⁰ columns: ``{m}_{pol}`` at nominal incidence, ``{m}_{pol}_beam`` averaged over
    the beam's spectrum, ``spm2_hv`` (second order, nominal incidence)."""
    th, ph, w = beam_components(beam)
    cols = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # PO/GO are out of range here: shown for reference
        for m in MODELS:
            kw = {"frequency": FREQ, "method": m, "out_of_range": "ignore"}
            s = em.bistatic(rough, eps, theta_i=ti, theta_s=ts, phi_s=ps, **kw).sigma0
            sb = em.bistatic(rough, eps, theta_i=th[:, None], theta_s=ts[None], phi_s=ps[None],
                             phi_i=ph[:, None], **kw).sigma0  # (2, 2, J, D)  # fmt: skip
            if not np.all(np.isfinite(sb)):
                raise FloatingPointError(f"{m}: σ⁰ not finite over the beam's components")
            avg = np.einsum("j,qpjd->qpd", w, sb)
            for p, (q, i) in POLS.items():
                cols[f"{m}_{p}"] = s[q, i]
                cols[f"{m}_{p}_beam"] = avg[q, i]
    cols["spm2_hv"] = sigma0_22(rough, eps, k, ti, ts, ps)[0, 1]
    return cols


def compute(realizations: int) -> dict:
    rough, eps, k, lam0 = case()
    cut, deg, ts, ps = directions()
    ti = math.radians(THETA_I)
    seeds = np.random.SeedSequence(SEED).spawn(realizations)  # as mom3d.bistatic draws them
    t0 = time.perf_counter()
    res = []
    for j, ss in enumerate(seeds):
        r = realization(rough, eps, k, LENGTH_WL * lam0, ti, ts, ps, ss)
        res.append(r)
        e = r["reflectivity"] + r["absorbed"]
        print(f"realization {j}: {r['seconds']:.0f} s, R = {np.round(r['reflectivity'], 4)}, "
              f"A = {np.round(r['absorbed'], 4)}, R + A = {np.round(e, 4)}",
              flush=True)  # fmt: skip
    seconds = time.perf_counter() - t0
    mc = monte_carlo(res, k, ti)
    cols = {"cut": cut, "theta_s_deg": deg, "phi_s_deg": np.degrees(ps)}
    for p, (q, i) in POLS.items():
        cols[f"mom3d_{p}"] = mc["sigma0"][q, i]
        cols[f"mom3d_{p}_se"] = mc["se"][q, i]
    refl = np.array([r["reflectivity"] for r in res])
    absb = np.array([r["absorbed"] for r in res])
    n_side, spacing = grid(eps, k, LENGTH_WL * lam0)
    g = res[0]["taper_g"]
    meta = {
        "frequency_hz": FREQ,
        "wavelength_m": lam0,
        "material": f"MironovSoil(moisture={MOISTURE}, clay={CLAY})",
        "eps": [eps.real, eps.imag],
        "correlation": "gaussian",
        "k_sigma": KS,
        "k_ell": KL,
        "theta_i_deg": THETA_I,
        "length_wavelengths": LENGTH_WL,
        "points_per_wavelength_inside": PPW,
        "nodes_per_side": n_side,
        "unknowns": res[0]["unknowns"],
        "taper_g_wavelengths": g / lam0,
        "beam_width_deg": math.degrees(1.0 / (k * g * math.cos(ti))),
        "realizations": realizations,
        "seed": SEED,
        "seconds": round(seconds, 1),
        "seconds_per_realization": round(seconds / realizations, 1),
        "reflectivity_h": refl[:, 0],
        "reflectivity_v": refl[:, 1],
        "absorbed_h": absb[:, 0],
        "absorbed_v": absb[:, 1],
        "energy_min": float((refl + absb).min()),
        "energy_max": float((refl + absb).max()),
        "iterations_max": max(r["iterations"] for r in res),
        "python": platform.python_version(),
        "emscatter": em.__version__,
    }
    cols.update(models(rough, eps, k, ti, ts, ps, res[0]["beam"]))
    write(cols, meta)
    return meta


def recompute_models() -> None:
    _, c, meta = read_csv(CSV)
    meta.pop("schema", None)
    rough, eps, k, lam0 = case()
    _, _, ts, ps = directions()
    ti = math.radians(THETA_I)
    beam = flat_beam(k, ti, meta["taper_g_wavelengths"] * lam0, lam0)
    keep = {key: v for key, v in c.items() if not key.startswith(MODELS + ("spm2",))}
    keep.update(models(rough, eps, k, ti, ts, ps, beam))
    write(keep, meta)


def flat_beam(k, ti, g, lam0):
    """The tapered beam of the patch (as the solver builds it) without solving."""
    n_side, spacing = grid(case()[1], k, LENGTH_WL * lam0)
    half = (n_side - 1) / 2 * spacing
    return tapered_beam(k, ti, 0.0, g, math.hypot(half, half))


def write(cols: dict, meta: dict) -> None:
    write_csv(CSV, list(cols), list(cols.values()), metadata=meta, schema="mom3d_soil/1")
    with atomic_path(MD) as tmp:
        Path(tmp).write_text(report(cols, meta), encoding="utf-8")
    print(f"wrote {CSV.name}, {MD.name}")


def db(x):
    return 10 * np.log10(np.maximum(np.asarray(x, float), 1e-30))


def summary(c: dict, meta: dict) -> list[str]:
    """Mean dB difference MoM − model (beam-averaged) per region, with the mean per-direction
    standard error [dB] (an upper bound of the pooled one: neighbouring directions correlate)."""
    deg, plane = c["theta_s_deg"], c["cut"] == 0
    lo, hi = (
        meta["theta_i_deg"] - meta["beam_width_deg"],
        meta["theta_i_deg"] + meta["beam_width_deg"],
    )
    regions = (
        ("vv", "backward wing θs ≤ −10°", plane & (deg <= -10)),
        ("hh", "backward wing θs ≤ −10°", plane & (deg <= -10)),
        ("vv", f"specular ± beam ({lo:.0f}°…{hi:.0f}°)", plane & (deg >= lo) & (deg <= hi)),
        ("hh", f"specular ± beam ({lo:.0f}°…{hi:.0f}°)", plane & (deg >= lo) & (deg <= hi)),
        ("vv", f"forward θs > {hi:.0f}°", plane & (deg > hi)),
        ("hh", f"forward θs > {hi:.0f}°", plane & (deg > hi)),
        ("hv", "cross plane φs = 90°", c["cut"] == 1),
    )
    out = ["| pol | region | SE [dB] | MoM − SPM | MoM − IEM | MoM − PO | MoM − GO |",
           "|---|---|---:|---:|---:|---:|---:|"]  # fmt: skip
    for p, name, sel in regions:
        mom = c[f"mom3d_{p}"][sel]
        se = np.mean(db(mom + c[f"mom3d_{p}_se"][sel]) - db(mom))
        d = [np.mean(db(mom) - db(c[f"{m}_{p}_beam"][sel])) for m in MODELS]
        out.append(f"| {p} | {name} | {se:.2f} | " + " | ".join(f"{x:+.2f}" for x in d) + " |")
    return ["Mean difference per region [dB] (models averaged over the beam):", "", *out]


def report(c: dict, meta: dict) -> str:
    """The Markdown table: per direction MoM ± SE and the beam-averaged models [dB]."""
    lines = [
        COMMAND.format(n=meta["realizations"]),
        "",
        "# Soil-like surface: exact 3-D MoM vs models (issue 19)",
        "",
        f"{meta['material']} at {meta['frequency_hz'] / 1e9:g} GHz: ε = "
        f"{meta['eps'][0]:.3f} + {meta['eps'][1]:.3f}i; Gaussian kσ = {meta['k_sigma']:g}, "
        f"kℓ = {meta['k_ell']:g}, θi = {meta['theta_i_deg']:g}°; patch "
        f"{meta['length_wavelengths']:g}λ × {meta['length_wavelengths']:g}λ, "
        f"{meta['nodes_per_side']}² nodes ({meta['unknowns']} unknowns), taper g = "
        f"{meta['taper_g_wavelengths']:.3g}λ, beam spread ≈ {meta['beam_width_deg']:.0f}° "
        "(1σ in θi); "
        f"{meta['realizations']} realizations, {meta['seconds_per_realization']:g} s each "
        f"(2 shared cores).",
        "",
        f"Energy per realization (R far field + A Poynting flux into the soil): "
        f"{meta['energy_min']:.4f} … {meta['energy_max']:.4f}.",
        "",
        *summary(c, meta),
        "",
        "| cut | θs [°] | pol | MoM [dB] | ± SE [dB] | SPM | IEM | PO | GO | SPM2 hv |",
        "|---|---:|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for p in ("vv", "hh", "hv"):
        for d in range(c["theta_s_deg"].size):
            cross = c["cut"][d] == 1
            if p == "hv" and not cross and c["theta_s_deg"][d] % 10:
                continue
            mean, se = c[f"mom3d_{p}"][d], c[f"mom3d_{p}_se"][d]
            mods = " | ".join(f"{db(c[f'{m}_{p}_beam'][d]):.1f}" for m in MODELS)
            if p == "hv" and not cross:  # beam-depolarization-limited (module docstring)
                mods = " | ".join("—" for _ in MODELS)
            s2 = f"{db(c['spm2_hv'][d]):.1f}" if p == "hv" else "—"
            lines.append(
                f"| {'φs=90°' if cross else 'plane'} | {c['theta_s_deg'][d]:g} | {p} | "
                f"{db(mean):.2f} | {db(mean + se) - db(mean):.2f} | {mods} | {s2} |"
            )
    lines += ["", "Models averaged over the beam's incident spectrum (module docstring of "
              "`soil_vs_models.py`); SPM2 hv (second order, σ⁽²²⁾) at the nominal incidence. "
              "In the plane hv is set by the beam's depolarization, which σ⁰ models cannot "
              "average (—).", ""]  # fmt: skip
    return "\n".join(lines)


def plot() -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    _, c, meta = read_csv(CSV)
    style = {"spm": ("C0", ":"), "iem": ("C1", "-."), "po": ("C2", "-"), "go": ("C3", "--")}
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.4))
    panels = (("vv", 0), ("hh", 0), ("hv", 1))
    for ax, (p, cut) in zip(axes, panels, strict=True):
        sel = c["cut"] == cut
        deg = c["theta_s_deg"][sel]
        mean, se = c[f"mom3d_{p}"][sel], c[f"mom3d_{p}_se"][sel]
        d0 = db(mean)
        lo = db(np.maximum(mean - se, 1e-3 * mean))
        ax.errorbar(deg, d0, yerr=[d0 - lo, db(mean + se) - d0], fmt="ko", ms=3.5, capsize=2,
                    label=f"mom3d (Müller, {meta['realizations']} realizations ± SE)")  # fmt: skip
        for m in MODELS:
            col, ls = style[m]
            ax.plot(deg, db(c[f"{m}_{p}_beam"][sel]), color=col, ls=ls, label=f"{m.upper()} (beam)")
            ax.plot(deg, db(c[f"{m}_{p}"][sel]), color=col, ls=ls, lw=0.6, alpha=0.6)
        if p == "hv":
            ax.plot(
                deg,
                db(c["spm2_hv"][sel]),
                color="C4",
                ls="-",
                lw=0.9,
                label="SPM2 σ⁽²²⁾ hv (nominal θi)",
            )
        if cut == 0:
            ax.axvspan(meta["theta_i_deg"] - meta["beam_width_deg"],
                       meta["theta_i_deg"] + meta["beam_width_deg"], color="0.92",
                       label="specular ± beam spread")  # fmt: skip
            ax.set_xlabel("θs [deg] in the plane of incidence (< 0: backward)")
        else:
            ax.set_xlabel("θs [deg] at φs = 90° (cross plane)")
        ax.set_title(f"{p}{' (cross plane)' if cut else ''}")
        if cut == 0:
            ax.text(0.02, 0.97, f"grey: specular ± {meta['beam_width_deg']:.0f}° (the 3λ beam's "
                    "spread in θi):\nthe comparison there is limited by the beam and by the "
                    "coherent part", transform=ax.transAxes, fontsize=7, va="top")  # fmt: skip
        ax.set_ylim(-45, 0)
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("σ⁰ [dB]")
    axes[2].legend(fontsize=7.5, loc="lower left")
    fig.suptitle(
        f"Soil (Mironov m_v = {MOISTURE:g}, {meta['frequency_hz'] / 1e9:g} GHz): ε = "
        f"{meta['eps'][0]:.2f} + {meta['eps'][1]:.2f}i, Gaussian kσ = {meta['k_sigma']:g}, "
        f"kℓ = {meta['k_ell']:g}, θi = {meta['theta_i_deg']:g}°, "
        f"{meta['length_wavelengths']:g}λ patch — models averaged over the beam "
        f"(≈ ±{meta['beam_width_deg']:.0f}° in θi; thin lines: plane wave); "
        f"R + A = {meta['energy_min']:.3f}…{meta['energy_max']:.3f}",
        fontsize=9,
    )
    fig.tight_layout()
    save_figure(fig, PNG)
    shutil.copyfile(PNG, FIGURE.with_suffix(".tmp.png"))
    FIGURE.with_suffix(".tmp.png").replace(FIGURE)
    print(f"wrote {PNG.name} and docs/figures/{FIGURE.name}")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--realizations", type=int, default=16)
    ap.add_argument("--models-only", action="store_true")
    ap.add_argument("--plot-only", action="store_true")
    args = ap.parse_args(argv)
    if args.realizations < 2:
        ap.error(f"--realizations must be ≥ 2 (a variance needs two), got {args.realizations}")
    if args.models_only:
        recompute_models()
    elif not args.plot_only:
        compute(args.realizations)
    plot()


if __name__ == "__main__":
    main()
