"""The main job on built-in defaults (``make demo`` / ``emscatter demo``).

Writes under ``out/`` (atomically):

* ``surfaces/<kind>.png`` + ``surfaces/stats.json`` — Gaussian, exponential and fBm
  surfaces with their spectra, target statistics beside the measured ones;
* ``figure_5_3.png`` + ``figure_5_3.csv`` — the seed's Figure 5.3 (SPM, see below);
* ``emissivity.png`` + ``emissivity.csv`` — h/v emissivity of the same surfaces;
* ``methods_comparison.png`` + ``.csv`` — SPM, physical and geometric optics side by side.

Figure 5.3 of the seed (ch. 5.4): Gaussian surface with correlation length τ = 1, relative
permittivity ε = 17 + 2i, TE (h) incidence at θi = 45°, rms height σ varied, curves over
θs ∈ (0°, 90°) in the plane φ = 0. The seed gives no wavelength; we take **λ = τ = 1 m**
(kℓ = 2π): the specular lobe is then a BRDF-like lobe of width ~2/(kℓ) in sinθ (≈ 18°), and
σ ≤ 0.045 λ keeps kσ ≤ 0.28, inside the small-perturbation method's validity.
"""

from __future__ import annotations

import math
from functools import partial
from pathlib import Path

import numpy as np
from tqdm import tqdm

from .constants import SPEED_OF_LIGHT

FIG53_SIGMAS = (0.005, 0.01, 0.02, 0.03, 0.045)  # [m], with λ = τ = 1 m: kσ ≤ 0.28
FIG53_EPS = 17 + 2j
FIG53_THETA_I = math.radians(45.0)
EMISSIVITY_SIGMAS = (0.02, 0.045)  # [m]


DEMO_SCHEMA = "emscatter.demo/1"


def _meta(figure: str, **inputs) -> dict:
    """What a demo CSV needs to be reproduced: the inputs (every demo figure uses the seed's
    ε = 17 + 2i at λ = 1 m), the version, the command."""
    from ._version import __version__

    common = {
        "eps": {"re": FIG53_EPS.real, "im": FIG53_EPS.imag},
        "wavelength_m": 1.0,
        "frequency_hz": SPEED_OF_LIGHT,
    }
    return {
        "figure": figure,
        "emscatter_version": __version__,
        "command": "emscatter demo",
        "inputs": {**common, **inputs},
    }


def _json_safe(d: dict) -> dict:
    out = {}
    for k, v in d.items():
        if isinstance(v, float) and not math.isfinite(v):
            v = None
        elif isinstance(v, tuple):
            v = list(v)
        out[k] = v
    return out


def surface_report(
    *,
    kind="fbm",
    hurst=0.7,
    size=512,
    spacing=1.0,
    sigma=1.0,
    length=16.0,
    seed=0,
    periodic=False,
    png=None,
    json_path=None,
    profile=False,
) -> dict:
    """Generate one surface, measure it, optionally draw it (PNG) and save the numbers (JSON).

    ``kind="fbm"``: ``sigma`` is the rms height increment [m] at a lag of one ``spacing``.
    Returns target and measured statistics in one dict.
    """
    from .io import save_figure, write_json
    from .plots import surface_figure
    from .spectra import FractionalBrownian, roughness
    from .surfaces.generate import generate_surface
    from .surfaces.measure import psd, summarize

    dim = 1 if profile else 2
    if kind == "fbm":
        rough = FractionalBrownian(hurst, increment_rms=sigma, lag=spacing, dimension=dim)
    else:
        extra = {"hurst": hurst} if kind == "power-law" else {}
        rough = roughness(kind, sigma=sigma, length=length, dimension=dim, **extra)
    shape = size if profile else (size, size)
    surf = generate_surface(rough, shape, spacing, periodic=periodic, rng=seed)
    model = kind if kind in ("gaussian", "exponential") else "1/e"  # fit the matching ACF
    measured = summarize(
        surf.heights, surf.spacing, hurst=(kind in ("fbm", "power-law")), model=model
    )
    stats: dict = {"description": rough.describe(), "method": surf.method, "seed": seed}
    stats.update({f"target_{k}": v for k, v in _target_stats(rough).items()})
    skip = {"shape", "spacing"}
    if kind == "fbm":  # non-stationary: no correlation length to fit
        skip |= {k for k in measured if k.startswith("correlation") or k == "warnings"}
    stats.update({f"measured_{k}": v for k, v in measured.items() if k not in skip})
    if png:
        spec = psd(surf.heights, surf.spacing)
        show = {
            k.replace("measured_", "").replace("target_", "target "): v
            for k, v in stats.items()
            if isinstance(v, float) and not k.endswith("stderr") and "spectral" not in k
        }
        fig = surface_figure(
            surf.heights,
            surf.spacing,
            title=rough.describe(),
            psd=(spec.k, spec.psd),
            stats=dict(list(show.items())[:10]),
        )
        save_figure(fig, png)
    if json_path:
        from ._version import __version__

        inputs = dict(
            kind=kind,
            hurst=hurst,
            size=size,
            spacing_m=spacing,
            sigma_m=sigma,
            length_m=length,
            seed=seed,
            periodic=periodic,
            profile=profile,
        )
        meta = {"schema": "emscatter.surface/1", "emscatter_version": __version__, "inputs": inputs}
        write_json(json_path, _json_safe({**meta, **stats}))
    return stats


def _target_stats(rough) -> dict:
    from .spectra import FractionalBrownian

    if isinstance(rough, FractionalBrownian):
        return {"hurst": rough.hurst, "fractal_dimension": rough.fractal_dimension}
    out = {"rms_height": rough.sigma, "correlation_length": rough.length}
    try:
        sx, sy = rough.mean_square_slope()
        out.update(rms_slope_x=math.sqrt(sx), rms_slope=math.sqrt(sx + sy))
    except ValueError:
        out["rms_slope"] = "infinite without a cutoff"
    return out


def figure_5_3(out: Path, *, n_theta: int = 179) -> list[Path]:
    """The seed's Figure 5.3 (module docstring): SPM σ⁰_hh and BRDF over θs, φ = 0."""
    import matplotlib.pyplot as plt

    from . import api
    from .io import save_figure, write_csv
    from .spectra import GaussianCorrelation

    th_deg = np.linspace(0.5, 89.5, n_theta)
    th = np.radians(th_deg)
    cols, labels = [th_deg], ["theta_s_deg"]
    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(11, 4.3))
    for s in FIG53_SIGMAS:
        rough = GaussianCorrelation(s, 1.0)
        res = api.bistatic(
            rough,
            FIG53_EPS,
            wavelength=1.0,
            theta_i=FIG53_THETA_I,
            theta_s=th,
            phi_s=0.0,
            method="spm",
        )
        hh = res.hh
        brdf = res.brdf()[0, 0]
        ksig = res.k * s
        ax0.plot(th_deg, 10 * np.log10(hh), label=f"σ = {s:g} m (kσ = {ksig:.2f})")
        ax1.plot(th_deg, brdf, label=f"σ = {s:g} m")
        cols += [hh, brdf]
        labels += [f"sigma0_hh_sigma{s:g}", f"brdf_hh_sigma{s:g}"]
    for ax in (ax0, ax1):
        ax.axvline(45, color="0.6", ls=":", lw=1)
        ax.set_xlabel("scattering angle θs [deg] (plane φ = 0)")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    ax0.set_ylabel("σ⁰_hh [dB]")
    ax1.set_ylabel("BRDF f_r,hh [1/sr]")
    fig.suptitle(
        "Seed Fig. 5.3 — SPM, Gaussian τ = 1 m, λ = 1 m, ε = 17 + 2i, TE, θi = 45°", fontsize=10
    )
    fig.tight_layout()
    return [
        save_figure(fig, out / "figure_5_3.png"),
        write_csv(
            out / "figure_5_3.csv",
            labels,
            cols,
            schema=DEMO_SCHEMA,
            metadata=_meta(
                "seed Figure 5.3",
                method="spm",
                roughness={"kind": "gaussian", "length_m": 1.0, "sigma_m": list(FIG53_SIGMAS)},
                theta_i_deg=45.0,
                phi_s_deg=0.0,
            ),
        ),
    ]


def emissivity_curves(out: Path, *, n_theta: int = 18) -> list[Path]:
    """h/v emissivity of the Figure 5.3 surfaces (SPM) and of the flat interface."""
    from . import api
    from .fresnel import reflectivity
    from .io import save_figure, write_csv
    from .plots import emissivity_figure
    from .spectra import GaussianCorrelation

    th_deg = np.linspace(0.0, 85.0, n_theta)
    th = np.radians(th_deg)
    flat = 1.0 - reflectivity(FIG53_EPS, th)
    series = {"flat (Fresnel)": (flat[0], flat[1])}
    cols, labels = [th_deg, flat[0], flat[1]], ["theta_deg", "e_h_flat", "e_v_flat"]
    flagged = np.zeros(th.shape, dtype=bool)
    for s in EMISSIVITY_SIGMAS:
        e = api.emissivity(
            GaussianCorrelation(s, 1.0), FIG53_EPS, wavelength=1.0, theta_i=th, method="spm"
        )
        series[f"SPM σ = {s:g} m"] = (e.h, e.v)
        flagged |= ~e.info["validity"]["angle_valid"]
        cols += [e.h, e.v, e.error.max(axis=0), e.energy_ok.astype(int)]
        labels += [
            f"e_h_sigma{s:g}",
            f"e_v_sigma{s:g}",
            f"quadrature_error_sigma{s:g}",
            f"energy_ok_sigma{s:g}",
        ]
    fig = emissivity_figure(
        th_deg,
        series,
        title="Emissivity, Gaussian ℓ = 1 m, λ = 1 m, ε = 17 + 2i",
        flagged=flagged,
    )
    meta = _meta(
        "emissivity",
        method="spm",
        roughness={"kind": "gaussian", "length_m": 1.0, "sigma_m": list(EMISSIVITY_SIGMAS)},
        theta_i_deg=th_deg.tolist(),
        tol=1e-4,
    )
    return [
        save_figure(fig, out / "emissivity.png"),
        write_csv(out / "emissivity.csv", labels, cols, schema=DEMO_SCHEMA, metadata=meta),
    ]


COMPARISON_CASES = (
    ("slightly rough: σ = 0.02 m, ℓ = 1.5 m", 0.02, 1.5),  # kσ = 0.13, kℓ = 9.4
    ("very rough: σ = 0.6 m, ℓ = 4 m", 0.6, 4.0),  # kσ = 3.8, kℓ = 25, slope 0.21
)


def methods_comparison(out: Path, *, n_theta: int = 179) -> list[Path]:
    """σ⁰_hh and σ⁰_vv over θs (θi = 30°, φ = 0, λ = 1 m, ε = 17 + 2i) by SPM, physical and
    geometric optics for two surfaces: SPM ≈ PO where the surface is slightly rough and
    PO ≈ GO where it is very rough. Each curve is labelled valid / outside validity."""
    import matplotlib.pyplot as plt

    from . import api, solvers
    from .io import save_figure, write_csv
    from .spectra import GaussianCorrelation

    th_deg = np.linspace(0.0, 89.5, n_theta)
    th = np.radians(th_deg)
    ti = math.radians(30.0)
    k = 2 * math.pi
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.3))
    cols, labels = [th_deg], ["theta_s_deg"]
    for ax, (title, sigma, ell) in zip(axes, COMPARISON_CASES, strict=True):
        rough = GaussianCorrelation(sigma, ell)
        for j, method in enumerate(("spm", "po", "go")):
            res = api.bistatic(
                rough,
                FIG53_EPS,
                wavelength=1.0,
                theta_i=ti,
                theta_s=th,
                phi_s=0.0,
                method=method,
                out_of_range="ignore",
            )
            valid = solvers.get(method).check_validity(rough, k)["valid"]
            style = "-" if valid else ":"
            tag = "valid" if valid else "outside validity"
            color = f"C{j}"
            ax.plot(
                th_deg,
                10 * np.log10(np.maximum(res.hh, 1e-30)),
                style,
                color=color,
                label=f"{method.upper()} hh ({tag})",
            )
            ax.plot(
                th_deg,
                10 * np.log10(np.maximum(res.vv, 1e-30)),
                style,
                color=color,
                alpha=0.45,
                label=f"{method.upper()} vv",
            )
            if method == "po":
                peak = float(np.max(10 * np.log10(np.maximum(res.hh, 1e-30))))
            cols += [res.hh, res.vv]
            labels += [f"{method}_hh_sigma{sigma:g}", f"{method}_vv_sigma{sigma:g}"]
        ax.set_ylim(peak - 60, peak + 10)
        ax.axvline(30, color="0.6", ls=":", lw=1)
        ax.set_title(f"{title} (kσ = {k * sigma:.2f}, kℓ = {k * ell:.1f})", fontsize=9)
        ax.set_xlabel("scattering angle θs [deg] (φ = 0, θi = 30°)")
        ax.set_ylabel("σ⁰ [dB]")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle(
        "Where approximations overlap — λ = 1 m, ε = 17 + 2i (solid: valid, dotted: "
        "outside validity)",
        fontsize=10,
    )
    fig.tight_layout()
    return [
        save_figure(fig, out / "methods_comparison.png"),
        write_csv(
            out / "methods_comparison.csv",
            labels,
            cols,
            schema=DEMO_SCHEMA,
            metadata=_meta(
                "methods comparison",
                methods=["spm", "po", "go"],
                roughness=[
                    {"kind": "gaussian", "sigma_m": sg, "length_m": ell}
                    for _, sg, ell in COMPARISON_CASES
                ],
                theta_i_deg=30.0,
                phi_s_deg=0.0,
                out_of_range="ignore",
            ),
        ),
    ]


def _surface_step(folder: Path, *, size: int, rel: Path, params: dict) -> dict:
    return _json_safe(surface_report(size=size, png=folder / rel, **params))


def _files_step(step, folder: Path, **kwargs) -> None:
    step(folder, **kwargs)


#: The bridges' demo steps: module run as ``python -m <module> <args> <folder>``. Each runs in a
#: fresh interpreter because Dr.Jit variants are per process (Mitsuba's spectral variant and
#: Sionna RT's cannot share one), and always in its quick form (a small export + render, the
#: plate check at one frequency): the full renders and radio comparisons are examples/.
BRIDGE_STEPS = {
    "brdf export + render": ("emscatter.render.demo", ["--quick"], "render", False),
    "radio plate check": ("emscatter.radio.demo", ["--quick", "--out"], "radio", True),
}


def _bridge_step(folder: Path, *, module: str, args: list[str], sub: str, out_last: bool) -> dict:
    """Run one bridge's demo in a subprocess into ``folder/sub``; a failure is one clear error."""
    import subprocess
    import sys

    target = folder / sub
    target.mkdir(parents=True, exist_ok=True)
    argv = [*args, str(target)] if out_last else [str(target), *args]
    proc = subprocess.run(
        [sys.executable, "-m", module, *argv], capture_output=True, text=True, check=False
    )
    if proc.returncode != 0:
        last = (proc.stderr.strip().splitlines() or ["(no message)"])[-1]
        raise RuntimeError(
            f"demo step {module} failed (exit {proc.returncode}): {last} — run "
            f"`python -m {module} {' '.join(argv)}` to see it in full"
        )
    return {"module": module, "stdout": proc.stdout.strip().splitlines()[-20:]}


def run_demo(out: Path, *, quick: bool = False) -> list[Path]:
    """Run every part of the demo into ``out``; returns the files written."""
    from . import cache
    from .io import write_json

    out = Path(out)
    size = 256 if quick else 512
    surf_dir = out / "surfaces"
    surfaces = {
        "gaussian": dict(kind="gaussian", sigma=1.0, length=16.0),
        "exponential": dict(kind="exponential", sigma=1.0, length=16.0),
        "fbm_H0.7": dict(kind="fbm", hurst=0.7, sigma=1.0),
    }
    written: list[Path] = []
    all_stats = {}
    steps = list(surfaces) + ["figure 5.3", "emissivity", "methods", *BRIDGE_STEPS]
    for step in tqdm(steps, desc="emscatter demo", unit="step"):
        if step in surfaces:
            rel = Path("surfaces") / f"{step}.png"
            produce = partial(_surface_step, size=size, rel=rel, params=surfaces[step])
        elif step == "figure 5.3":
            produce = partial(_files_step, figure_5_3, n_theta=89 if quick else 179)
        elif step == "emissivity":
            produce = partial(_files_step, emissivity_curves, n_theta=10 if quick else 18)
        elif step in BRIDGE_STEPS:
            module, args, sub, out_last = BRIDGE_STEPS[step]
            produce = partial(_bridge_step, module=module, args=args, sub=sub, out_last=out_last)
        else:
            produce = partial(_files_step, methods_comparison, n_theta=60 if quick else 179)
        # each step is a pure function of its parameters: cached on disk (emscatter.cache)
        key = {"step": step, "quick": quick, "size": size}
        value, files = cache.cached_step("demo", key, out, produce)
        written += files
        if step in surfaces:
            all_stats[step] = value
    written.append(write_json(surf_dir / "stats.json", all_stats))
    return written
