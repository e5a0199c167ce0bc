"""The HTSG section of ``catalogue.md`` (called by ``make_catalogue.py``): He–Torrance–Sillion–
Greenberg 1991 against emscatter's physical optics in dB, its albedo (directional diffuse +
specular), reciprocity and Beckmann equivalent."""

from __future__ import annotations

import math

import numpy as np

from emscatter import api, spectra
from emscatter.brdf import frames
from emscatter.brdf.analytic import directional_albedo
from emscatter.brdf.analytic.htsg import htsg, htsg_equivalent_beckmann, htsg_specular
from emscatter.brdf.analytic.stam import stam, stam_specular
from emscatter.solvers.kirchhoff import po

LAM = 0.55e-6
K = 2 * math.pi / LAM
GOLD = 0.2 + 3.0j
M_GRID = (0.1, 0.2, 0.3, 0.5)
KS_GRID = (0.3, 0.5, 1.0, 2.0)
THETA_DEG = np.array([0.0, 30, 60, 75, 85, 89])


def _grid(tmax_deg):
    t = np.radians(np.arange(0.0, tmax_deg + 0.1, 5.0))
    p = np.radians(np.arange(0.0, 180.1, 10.0))
    ti, to, pd = np.meshgrid(t, t, p, indexing="ij")
    return ti, to, pd


def _db(m, ks, tmax_deg):
    s0 = ks / K
    tau = 2 * s0 / m
    ti, to, pd = _grid(tmax_deg)
    wi, wo = frames.directions(ti, 0 * ti), frames.directions(to, pd)
    f = htsg(wi, wo, LAM, s0, tau, GOLD)
    a, b, c, d = frames.to_emscatter(ti, 0 * ti, to, pd)
    res = po.bistatic(spectra.GaussianCorrelation(s0, tau), GOLD**2, K, a, b, c, d, coherent=False)
    fpo = res.unpolarized() / (4 * math.pi * np.cos(a) * np.cos(b))
    lobe = fpo > 1e-3 * fpo.max()
    db = np.abs(10 * np.log10(f[lobe] / fpo[lobe]))
    return float(np.median(db)), float(np.max(db))


def _albedo(n):
    worst, where = 0.0, ""
    for m in (0.1, 0.3, 0.5, 1.0):
        for ks in (0.3, 1.0, 3.0):
            s0 = ks / K
            tau = 2 * s0 / m
            th = np.radians(THETA_DEG)
            alb = directional_albedo(
                lambda wi, wo, s0=s0, tau=tau: htsg(wi, wo, LAM, s0, tau, n),
                th,
                n_theta=128,
                n_phi=128,
            ) + htsg_specular(th, LAM, s0, tau, n)
            j = int(np.argmax(alb))
            if alb[j] > worst:
                worst, where = float(alb[j]), f"θi = {THETA_DEG[j]:g}°, m = {m:g}, kσ = {ks:g}"
    return worst, where


def _reciprocity():
    rng = np.random.default_rng(7)
    c = rng.uniform(math.cos(math.radians(89)), 1.0, (2, 4000))
    p = rng.uniform(0, 2 * math.pi, (2, 4000))
    s = np.sqrt(1 - c * c)
    w = np.stack([s * np.cos(p), s * np.sin(p), c], -1)
    worst = 0.0
    for m, ks in ((0.1, 0.3), (0.5, 1.0), (1.0, 3.0)):
        s0 = ks / K
        a = htsg(w[0], w[1], LAM, s0, 2 * s0 / m, GOLD)
        b = htsg(w[1], w[0], LAM, s0, 2 * s0 / m, GOLD)
        worst = max(worst, float(np.max(np.abs(a - b) / np.maximum(np.maximum(a, b), 1e-300))))
    return worst


def section() -> list[str]:
    lines = [
        "## He–Torrance–Sillion–Greenberg 1991 (seed §2.3.2) — `emscatter.brdf.analytic.htsg`",
        "",
        "Kirchhoff wave optics: specular |F|² e^{−g} S², directional diffuse (the Kirchhoff series",
        "with the effective roughness σ_eff, G = (v·v/v_z)², Smith shadowing S of Beckmann",
        "m = 2σ₀/τ, Fresnel at the bisector), optional uniform diffuse a/π. With S and σ_eff off",
        "it *is* emscatter's PO (`solvers/kirchhoff/po.py`, Gaussian correlation, ℓ = τ) as a",
        "BRDF f = σ⁰/(4π cosθi cosθo): equal to 1e-6 (tested, `tests/test_brdf_htsg.py`).",
        "",
        "### Full HTSG against emscatter's PO, where both hold (gold n = 0.2 + 3i, λ = 550 nm)",
        "",
        "|10 log10(f_HTSG/f_PO)| over θi, θo on a 5° grid × Δφ on a 10° grid, inside the lobe",
        "(f_PO > 1e-3 of its maximum); m = 2σ₀/τ, τ = 2σ₀/m:",
        "",
        "| m | kσ | kτ | θ ≤ 60°: median / max [dB] | θ ≤ 80°: median / max [dB] |",
        "|---|---|---|---|---|",
    ]
    for m in M_GRID:
        for ks in KS_GRID:
            a60 = _db(m, ks, 60)
            a80 = _db(m, ks, 80)
            lines.append(
                f"| {m:g} | {ks:g} | {2 * ks / m:.1f} | {a60[0]:.4f} / {a60[1]:.4f} | "
                f"{a80[0]:.4f} / {a80[1]:.4f} |"
            )
    gold, gwhere = _albedo(GOLD)
    pec, pwhere = _albedo("pec")
    flag = " **> 1: the model's own**" if pec > 1 else ""
    lines += [
        "",
        "The two differ only by S and σ_eff/σ₀, which fade at moderate angles and slopes (kσ does",
        "not enter them): below 60° and m ≤ 0.3 they agree within 0.032 dB (median 0.0000 dB);",
        "at m = 0.5 within 0.66 dB; toward grazing HTSG's shadowing removes the PO excess",
        "(2–3 dB at 80° for m = 0.2, up to 13 dB for m = 0.5).",
        "",
        "### Albedo (directional diffuse + specular) and reciprocity",
        "",
        f"m ∈ {{0.1, 0.3, 0.5, 1}} × kσ ∈ {{0.3, 1, 3}}, θi = "
        f"{', '.join(f'{t:g}' for t in THETA_DEG)}° (quadrature 128 × 128, converged to 1e-5):",
        "",
        "| material | max albedo | where |",
        "|---|---|---|",
        f"| gold (n = 0.2 + 3i) | {gold:.4f} | {gwhere} |",
        f"| perfect conductor | {pec:.4f}{flag} | {pwhere} |",
        "",
        "With a perfect conductor the albedo exceeds 1 by up to a few percent: the model's own",
        "(single-scattering Kirchhoff with the tangent-plane Fresnel is not energy conserving;",
        "the excess is converged in the quadrature). HTSG's shadowing keeps the grazing albedo",
        "bounded, where PO without it reaches 1.8–17 at 89° on the same grid.",
        f"Reciprocity: max |f(wi, wo) − f(wo, wi)|/f = {_reciprocity():.1e} over 4000 pairs",
        "to 89° (every factor is symmetric: σ_eff through K_i + K_r, S(θi)S(θo), F at wi·h).",
        "",
        "### Beckmann equivalent",
        "",
        "m = 2σ₀/τ (seed eq. 3.1) is the m of HTSG's shadowing and the kσ → ∞ limit of its",
        "lobe G·D; the seed's criterion (`equivalence.FIT_CRITERION`) applied to G·D in the",
        "backscatter geometry (wi = wo = h(γ), σ = σ₀, no shadowing) gives, for 2σ₀/τ = 0.2:",
        "",
        "| kσ | fitted Beckmann m | rms difference |",
        "|---|---|---|",
    ]
    for ks in (0.3, 1.0, 3.0, 10.0, 30.0):
        s0 = ks / K
        eq = htsg_equivalent_beckmann(s0, 10 * s0, wavelength=LAM)
        lines.append(f"| {ks:g} | {eq.value:.4f} | {eq.error:.4f} |")
    lines += [
        "",
        "At small kσ the incoherent lobe is the first-order spectrum's (its width set by kτ, not",
        "by the slopes): wider than 2σ₀/τ at kσ = 0.3, narrower near kσ = 1 (the low orders of",
        "the series); it tends to 2σ₀/τ from kσ ≈ 3 (2 %) and is exact as kσ → ∞.",
        "",
    ]
    return lines


def _stam_spm(ks, tmax_deg):
    s, tau = ks / K, 6.0 / K
    t = np.radians(np.arange(0.0, tmax_deg + 0.1, 5.0))
    p = np.radians(np.arange(0.0, 180.1, 15.0))
    ti, to, pd = np.meshgrid(t, t, p, indexing="ij")
    f = stam(frames.directions(ti, 0 * ti), frames.directions(to, pd), LAM, s, tau, None, GOLD)
    a, b, c, d = frames.to_emscatter(ti, 0 * ti, to, pd)
    rough = spectra.GaussianCorrelation(s, tau)
    # out_of_range="ignore": SPM's validity is what this row measures (in dB); its check
    # would integrate the hemispherical reflectivity at every incidence (hours here)
    res = api.bistatic(
        rough, GOLD**2, theta_i=a, theta_s=b, phi_s=c, phi_i=d, wavelength=LAM, method="spm",
        out_of_range="ignore",
    )  # fmt: skip
    fs = res.unpolarized() / (4 * math.pi * np.cos(a) * np.cos(b))
    db = np.abs(10 * np.log10(f / fs))
    return float(np.median(db)), float(np.max(db))


def stam_section() -> list[str]:
    th = np.radians(THETA_DEG)
    s, t = 0.3 / K, 6.0 / K
    alb = directional_albedo(
        lambda wi, wo: stam(wi, wo, LAM, s, t, None, "pec"), th, n_theta=128, n_phi=128
    ) + stam_specular(th, LAM, s, "pec")
    lines = [
        "## Stam 1999 diffraction shader, Gaussian surface (seed §2.3.3) — `analytic.stam`",
        "",
        "f = k² F² G ⟨|P(ku, kv)|²⟩/(4π² w²), G = (1 + wi·wo)²/(cosθi cosθo), anisotropic",
        "Gaussian correlation (τ_x, τ_y) (seed eq. 2.4). Term by term HTSG without shadowing and",
        "effective roughness, hence emscatter's PO: equal to 1e-6 for anisotropic (τ_x, τ_y)",
        "(tested, `tests/test_brdf_stam.py`). Reciprocal (tested to 1e-12). Beckmann",
        "equivalent (m_x, m_y) = (2σ/τ_x, 2σ/τ_y).",
        "",
        "Against first-order SPM (gold, kτ = 6, θi, θo on a 5° grid × Δφ on 15°), |dB|:",
        "",
        "| kσ | θ ≤ 20°: median / max | θ ≤ 40°: median / max |",
        "|---|---|---|",
    ]
    for ks in (0.05, 0.1):
        a20, a40 = _stam_spm(ks, 20), _stam_spm(ks, 40)
        lines.append(f"| {ks:g} | {a20[0]:.3f} / {a20[1]:.3f} | {a40[0]:.3f} / {a40[1]:.3f} |")
    lines += [
        "",
        "Near the normal the tangent-plane polarization factors equal SPM's α_pq to first order",
        "in the slopes; away from it they part, by up to 10 dB at 40° — the known limit of the",
        "Kirchhoff (tangent-plane) amplitudes at small kσ, where SPM is the reference.",
        "",
        "Albedo (perfect conductor, kσ = 0.3, m = 2σ/τ = 0.1, diffuse + specular) at θi = "
        f"{', '.join(f'{x:g}' for x in THETA_DEG)}°: "
        f"{', '.join(f'{x:.4f}' for x in alb)} — without shadowing it exceeds 1 toward",
        "grazing: the model's own (as PO's).",
        "",
    ]
    return lines
