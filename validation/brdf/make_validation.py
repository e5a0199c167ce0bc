"""BRDF validation tables and figures (issue 8).

    PYTHONPATH=src .venv/bin/python validation/brdf/make_validation.py

Writes, next to this script:
* ``energy.md`` / ``energy.csv`` / ``energy.png`` — the energy remedy's effect (directional
  albedo before/after, where and by how much, reciprocity after);
* ``equivalences.md`` / ``equivalences.csv`` / ``equivalences.png`` — the seed's chapter-3
  roughness equivalences reproduced, with the fit criterion.
"""

from __future__ import annotations

import math
import warnings
from pathlib import Path

import numpy as np

from emscatter.brdf import build_table
from emscatter.brdf.analytic import equivalence as E
from emscatter.io import atomic_path, save_figure, write_csv
from emscatter.spectra import GaussianCorrelation

HERE = Path(__file__).resolve().parent
LAM = 0.5e-6

ENERGY_CASES = [
    # (label, surface, material, method, options, resolution)
    ("GO, PEC, m = 0.6, no shadowing", GaussianCorrelation(0.3e-6, 1e-6), "pec", "go",
     {"shadowing": False}, (45, 61)),
    ("GO, PEC, m = 0.6, Smith shadowing", GaussianCorrelation(0.3e-6, 1e-6), "pec", "go", {},
     (45, 61)),
    ("PO, PEC, kσ = 1.26, m = 0.25", GaussianCorrelation(0.1e-6, 0.8e-6), "pec", "po", {},
     (45, 61)),
    ("SPM, PEC, kσ = 0.25, m = 0.08", GaussianCorrelation(0.02e-6, 0.5e-6), "pec", "spm", {},
     (45, 61)),
    ("GO, PEC, m = 0.3, Smith, coarse 8 x 9 grid", GaussianCorrelation(0.15e-6, 1e-6), "pec",
     "go", {}, (8, 9)),
    ("GO, PEC, m_x = 0.6, m_y = 0.24 (anisotropic)",
     GaussianCorrelation(0.3e-6, 1e-6, length_y=2.5e-6), "pec", "go", {}, (10, 12)),
]  # fmt: skip


def _ranges(deg: np.ndarray, mask: np.ndarray) -> str:
    """Contiguous runs of node angles where ``mask`` holds, e.g. ``0–8°, 66–88°``."""
    if not mask.any():
        return "none"
    runs, start = [], None
    for j, m in enumerate(np.append(mask, False)):
        if m and start is None:
            start = j
        if not m and start is not None:
            a, b = deg[start], deg[j - 1]
            runs.append(f"{a:.0f}°" if start == j - 1 else f"{a:.0f}–{b:.0f}°")
            start = None
    return ", ".join(runs)


def energy_table():
    rows, curves = [], []
    for label, rough, mat, method, opts, res in ENERGY_CASES:
        kw = dict(method=method, resolution=res, out_of_range="ignore", **opts)
        raw = build_table(rough, mat, [LAM], energy="off", **kw)
        fixed = build_table(rough, mat, [LAM], **kw)
        a0 = raw.albedo().total[0].reshape(raw.theta_i.size, -1).max(axis=1)
        a1 = fixed.albedo().total[0].reshape(fixed.theta_i.size, -1).max(axis=1)
        e = fixed.metadata["energy"]
        s = np.asarray(e["scale"][0]).reshape(fixed.theta_i.size, -1).min(axis=1)
        th = np.degrees(fixed.theta_i)
        low = fixed.theta_i <= math.radians(60)
        rows.append(
            {
                "case": label,
                "max_albedo_before": float(a0.max()),
                "max_albedo_after": float(a1.max()),
                "theta_i_exceeding_deg": _ranges(th, a0 > 1),
                "min_scale": float(s.min()),
                "theta_scaled_deg": _ranges(th, s < 1),
                "max_albedo_change_theta_le_60": float(np.max(np.abs(a1 - a0)[low])),
                "reciprocity_error_after": fixed.reciprocity_error(),
            }
        )
        curves.append((label, th, a0, a1))
    return rows, curves


def energy_outputs(rows, curves):
    keys = list(rows[0])
    write_csv(HERE / "energy.csv", keys, [[r[k] for r in rows] for k in keys])
    lines = [
        "# Energy remedy: directional albedo before and after",
        "",
        "Made by `PYTHONPATH=src .venv/bin/python validation/brdf/make_validation.py`.",
        "Remedy (`emscatter.brdf.energy`): `f'(wi, wo) = s(wi) f(wi, wo) s(wo)`, `s ≤ 1` per",
        "direction node, the smallest reduction that brings every directional albedo (coherent +",
        "incoherent, exact integral of the interpolated table) to ≤ 1. Reciprocal by construction",
        f"(symmetric product). λ = {LAM * 1e9:.0f} nm; albedo per θi node (max over φi when",
        "anisotropic).",
        "",
        "| case | max albedo before | after | θi exceeding 1 | min s | θ where s < 1 | "
        "max change at θi ≤ 60° | reciprocity error after |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['case']} | {r['max_albedo_before']:.4f} | {r['max_albedo_after']:.6f} | "
            f"{r['theta_i_exceeding_deg']} | {r['min_scale']:.3f} | {r['theta_scaled_deg']} | "
            f"{r['max_albedo_change_theta_le_60']:.2e} | {r['reciprocity_error_after']:.1e} |"
        )
    lines += [
        "",
        "Reading: GO without shadowing and PO over a perfect conductor reflect up to 5× and 2× the",
        "incident power at grazing; the remedy scales the grazing directions (incident *and*",
        "outgoing, which keeps reciprocity) and leaves moderate angles nearly untouched. GO with",
        "Smith shadowing loses energy (no multiple scattering) and is not touched. SPM over a PEC",
        "exceeds 1 by O((kσ)⁴) at normal incidence (second-order coherent + first-order",
        "incoherent). The coarse 8 × 9 GO table shows the other source of excess: the piecewise-",
        "linear interpolant of a narrow lobe integrates to more than the lobe; the remedy",
        "corrects what the renderer would actually see.",
        "",
        "![albedo before/after](energy.png)",
        "",
    ]
    (HERE / "energy.md").write_text("\n".join(lines))
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.2))
    for (label, th, a0, a1), col in zip(curves, plt.cm.tab10.colors, strict=False):
        ax.plot(th, a0, "--", color=col, lw=1)
        ax.plot(th, a1, "-", color=col, lw=1.5, label=label)
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_ylim(0.6, 1.6)
    ax.set_xlabel("θi [deg]")
    ax.set_ylabel("directional albedo (dashed: before)")
    ax.legend(fontsize=7, loc="upper left")
    ax.set_title("Reciprocal energy remedy")
    save_figure(fig, HERE / "energy.png")


def equivalences():
    b32p = E.phong_from_beckmann(0.32)
    b32b = E.blinn_from_beckmann(0.32)
    p1 = E.beckmann_from_phong(1.0)
    n4 = E.beckmann_from_blinn(4.0)
    wa = E.ashikhmin_from_ward(0.1, 0.8)
    wf = E.ashikhmin_from_ward(0.1, 0.8, ratio=None)
    g, p = np.meshgrid(E._GAMMA[::4], E._PHI, indexing="ij")
    ref = E.ward_shape(g, p, 0.1, 0.8)
    seed_err = E.fit_error(ref, E.ashikhmin_shape(g, p, 187, 10))
    seed100 = E.fit_error(ref, E.ashikhmin_shape(g, p, 100, 100))
    ws = E.ashikhmin_from_ward(0.1, 0.8, ratio="seed")
    sec = E.ward_section_exponent(0.1, 0.8)
    gs = E._GAMMA
    sref = E.ward_shape(gs, E.SEED_SECTION_PHI, 0.1, 0.8)

    def sec_err(nu, nv):
        return E.fit_error(sref, E.ashikhmin_shape(gs, E.SEED_SECTION_PHI, nu, nv))

    r_seed = 187 / 10
    rows = [
        ("Beckmann m = 0.32 → Phong n", "4 (Fig. 3.4)", f"{b32p.value:.2f}", b32p.error),
        ("Beckmann m = 0.32 → Blinn n_B", "17 (Fig. 3.6)", f"{b32b.value:.2f}", b32b.error),
        ("Phong n = 1 → Beckmann m_max", "0.51 (Fig. 3.5)", f"{p1.value:.3f}", p1.error),
        ("Blinn n_B = 4 → Beckmann m", "0.54 (Fig. 3.7, 'not a good approximation')",
         f"{n4.value:.3f}", n4.error),
        ("Ward (0.1, 0.8), section φ = π/4 → n_u + n_v = 2N [section rms]",
         "10 + 187 = 197 (Fig. 3.8), 100 + 100 = 200 (Fig. 3.9)",
         f"{2 * sec.value:.1f}", sec.error),
        ("Ward (0.1, 0.8) → Ashikhmin, the seed's criterion (section π/4, n_u/n_v = m_y/m_x) "
         "[section rms]", "(10, 187) (Fig. 3.8, its axes: n_u with m_y)",
         f"({ws.value[0]:.1f}, {ws.value[1]:.2f})", ws.error),
        ("  seed's pair (187, 10) in our axes [section rms]", "Fig. 3.8", "—",
         sec_err(187, 10)),
        ("  seed's pair (100, 100) [section rms]", "Fig. 3.9", "—", sec_err(100, 100)),
        ("  the seed's criterion's pair on the full (γ, φ) grid", "—",
         f"({ws.value[0]:.1f}, {ws.value[1]:.2f})",
         E.ward_ashikhmin_grid_error(0.1, 0.8, *ws.value)),
        ("Ward (0.1, 0.8) → Ashikhmin (n_u, n_v), n_u/n_v = (m_y/m_x)² (full grid)",
         "—", f"({wa.value[0]:.1f}, {wa.value[1]:.2f})", wa.error),
        ("Ward (0.1, 0.8) → Ashikhmin, free fit (full grid)", "—",
         f"({wf.value[0]:.1f}, {wf.value[1]:.2f})", wf.error),
        ("  seed's pair (187, 10) in our axes (full grid)", "Fig. 3.8", "—", seed_err),
        ("  seed's pair (100, 100) (full grid)", "Fig. 3.9", "—", seed100),
    ]  # fmt: skip
    write_csv(
        HERE / "equivalences.csv",
        ["equivalence", "seed", "emscatter", "rms_error"],
        [[r[i] for r in rows] for i in range(4)],
    )
    lines = [
        "# The seed's roughness equivalences (chapter 3, §3.2) reproduced",
        "",
        "Made by `PYTHONPATH=src .venv/bin/python validation/brdf/make_validation.py`",
        "(functions in `emscatter.brdf.analytic.equivalence`).",
        "",
        f"**Fit criterion** (the seed's §3.2.2 made precise): {E.FIT_CRITERION}.",
        "Distributions compared: Beckmann/Ward `exp(−tan²γ/m²)/cos⁴γ` (Table 3.1 × 4m²),",
        "Phong `cosⁿ(2γ)` (eq. 3.3, ν = 2γ), Blinn `cos^{n_B}γ`, Ashikhmin",
        "`cos^(n_u cos²φ + n_v sin²φ)γ`.",
        "",
        "| equivalence | seed | emscatter | rms difference (peak = 1) |",
        "|---|---|---|---|",
        *[f"| {a} | {b} | {c} | {d:.4f} |" for a, b, c, d in rows],
        "",
        "Notes: the seed's n_B = 4 ↔ m = 0.54 sits in a flat error valley (0.54 costs",
        f"{E.fit_error(E.beckmann_shape(E._GAMMA, 0.54), E.blinn_shape(E._GAMMA, 4)):.4f} against",
        f"{n4.error:.4f} at the optimum), as the seed says ('clearly not a good approximation').",
        "The seed's worked example of eq. 3.1 prints m = 2·0.2/0.8 = 0.32; the arithmetic gives",
        "0.5 (its figures then use m = 0.32, as here).",
        "",
        "**Ward ↔ Ashikhmin, the seed's criterion as it states it** (`ratio='seed'`).",
        "The seed's figures are curves of γ alone and it finds the fit 'not unique':",
        "(10, 187) in Fig. 3.8 and (100, 100) in Fig. 3.9 both fit. On the full (γ, φ) grid",
        f"they do not (rms {seed_err:.3f} and {seed100:.3f}, against {wf.error:.3f} at the free",
        "optimum); on one section they do, and the one section on which both printed pairs fit",
        "is the diagonal φ = π/4, where Ashikhmin's exponent is (n_u + n_v)/2 and Ward is a",
        "Beckmann lobe of 1/m² = (1/m_x² + 1/m_y²)/2: the best single exponent is",
        f"N = {sec.value:.2f}, so n_u + n_v = {2 * sec.value:.1f}; the seed's pairs sum to 197",
        f"(−{100 * (1 - 197 / (2 * sec.value)):.1f} %) and 200",
        f"(+{100 * (200 / (2 * sec.value) - 1):.1f} %), with section rms",
        f"{sec_err(187, 10):.4f} and {sec_err(100, 100):.4f} against {sec.error:.4f} at the",
        "line (peak = 1). The section cannot tell u from v (cos²π/4 = sin²π/4), which is why",
        "the seed's pair has n_u paired with m_y without showing it. The section fixes the sum",
        "only; the seed then keeps 'a constant ratio between the two parameters' using",
        f"m_x/m_y: n_u/n_v = m_y/m_x = 8 in our axes gives ({ws.value[0]:.1f}, {ws.value[1]:.2f}).",
        f"The seed's own split 187/10 = {r_seed:.1f} is",
        "neither m_y/m_x = 8 nor (m_y/m_x)² = 64 (it is (m_y/m_x)^"
        f"{np.log(r_seed) / np.log(8.0):.2f}), so the seed's sum follows from its stated",
        "criterion and its split does not. The text introduces the ratio after both figures, as",
        "the remedy for the non-uniqueness, so Fig. 3.8's pair need not be the criterion's.",
        "",
        "![distributions](equivalences.png)",
        "",
    ]
    with atomic_path(HERE / "equivalences.md") as tmp:
        tmp.write_text("\n".join(lines))
    import matplotlib.pyplot as plt

    gam = E._GAMMA
    deg = np.degrees(gam)
    fig, axs = plt.subplots(1, 4, figsize=(14.5, 3.3))
    axs[0].plot(deg, E.beckmann_shape(gam, 0.32), label="Beckmann m = 0.32")
    axs[0].plot(deg, E.phong_shape(gam, b32p.value), "--", label=f"Phong n = {b32p.value:.2f}")
    axs[0].plot(deg, E.blinn_shape(gam, b32b.value), ":", label=f"Blinn n_B = {b32b.value:.1f}")
    axs[0].set_title("Figs. 3.4, 3.6")
    axs[1].plot(deg, E.phong_shape(gam, 1.0), "--", label="Phong n = 1")
    axs[1].plot(deg, E.beckmann_shape(gam, p1.value), label=f"Beckmann m = {p1.value:.3f}")
    axs[1].set_title("Fig. 3.5")
    axs[2].plot(deg, E.blinn_shape(gam, 4.0), ":", label="Blinn n_B = 4")
    axs[2].plot(deg, E.beckmann_shape(gam, n4.value), label=f"Beckmann m = {n4.value:.3f}")
    axs[2].plot(deg, E.beckmann_shape(gam, 0.54), lw=0.8, label="Beckmann m = 0.54 (seed)")
    axs[2].set_title("Fig. 3.7")
    ph = E.SEED_SECTION_PHI
    axs[3].plot(deg, E.ward_shape(gam, ph, 0.1, 0.8), label="Ward (0.1, 0.8), φ = π/4")
    axs[3].plot(deg, E.ashikhmin_shape(gam, ph, 10, 187), "--", label="AS (10, 187) (Fig. 3.8)")
    axs[3].plot(deg, E.ashikhmin_shape(gam, ph, 100, 100), ":", label="AS (100, 100) (Fig. 3.9)")
    axs[3].plot(deg, E.ashikhmin_shape(gam, ph, *ws.value), "-.", lw=0.8,
                label=f"AS ({ws.value[0]:.1f}, {ws.value[1]:.1f}) (criterion)")  # fmt: skip
    axs[3].set_title("Figs. 3.8–3.9 (section φ = π/4)")
    for ax in axs:
        ax.set_xlabel("γ (half angle) [deg]")
        ax.set_xlim(0, 70 if ax is not axs[3] else 25)
        ax.legend(fontsize=7)
    axs[0].set_ylabel("distribution at level 1 for γ = 0")
    save_figure(fig, HERE / "equivalences.png")


def main():
    warnings.simplefilter("ignore")
    rows, curves = energy_table()
    energy_outputs(rows, curves)
    equivalences()
    for r in rows:
        print(r)


if __name__ == "__main__":
    main()
