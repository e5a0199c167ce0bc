"""README/docs figure for issue 17: a measured map (generated, written to .nc, read back), its
σ⁰ by SPM and IEM against the analytic roughness it was drawn from, and po_map's grating
orders of one realization against statistical PO.

    PYTHONPATH=src .venv/bin/python validation/heightmap/make_figure.py
    # → validation/heightmap/heightmap.png (needs SurfaceTopography for the .nc round trip)
    # and then make_render.py → render.png / render.json (needs Mitsuba; --no-render skips it)

Lengths in units of the wavelength-free roughness (σ = 0.1, ℓ = 1; Δ = ℓ/10; 1024² map): SPM at
kσ = 0.2 (k = 2), IEM at kσ = 0.5 (k = 5), ε = 5 + 0.5i, θi = 30°, the incidence plane.
Panel c: one periodic 256² realization (Δ = λ/8, kσ = 0.75, kℓ = 9.4, the case of
tests/test_po_map.py), its orders in the incidence plane (n = 0) as σ⁰ equivalents, against
:func:`emscatter.solvers.kirchhoff.po.bistatic` (incoherent) at the same directions.
"""

from __future__ import annotations

import math
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1] / "src"))

import emscatter  # noqa: E402
from emscatter.io import save_figure  # noqa: E402
from emscatter.solvers.iem import model as iem  # noqa: E402
from emscatter.solvers.kirchhoff import po  # noqa: E402
from emscatter.solvers.kirchhoff.po_map import po_map  # noqa: E402
from emscatter.solvers.spm import model as spm  # noqa: E402
from emscatter.spectra import GaussianCorrelation  # noqa: E402
from emscatter.surfaces.heightmap import height_map, read_height_map, write_height_map  # noqa: E402
from emscatter.surfaces.measured import measured_roughness  # noqa: E402

EPS = 5 + 0.5j
TI = math.radians(30.0)


def _db(x):
    return 10 * np.log10(np.maximum(x, 1e-30))


def main() -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    warnings.simplefilter("ignore")
    rough = GaussianCorrelation(0.1, 1.0)
    s = emscatter.generate_surface(rough, (1024, 1024), 0.1, rng=5)
    with tempfile.TemporaryDirectory() as tmp:
        path = write_height_map(height_map(s.heights, s.spacing), Path(tmp) / "map.nc", unit="m")
        hm = read_height_map(path)
    m = measured_roughness(hm, segments=8)
    ts = np.radians(np.linspace(-70, 70, 141))
    th, ph = np.abs(ts), np.where(ts < 0, math.pi, 0.0)

    fig, ax = plt.subplots(1, 3, figsize=(15, 4.6))
    ext = [0, hm.size[1], 0, hm.size[0]]
    im = ax[0].imshow(hm.heights[:256, :256] / rough.sigma, origin="lower", cmap="gray",
                      extent=[0, ext[1] / 4, 0, ext[3] / 4])  # fmt: skip
    fig.colorbar(im, ax=ax[0], label="h / σ")
    ax[0].set_title(f"measured map (read from .nc), ¼ of {hm.shape[0]}²\nmeasured σ = "
                    f"{m.sigma:.4g}, ℓ = {m.length:.4g} (drawn from σ = {rough.sigma:g}, "
                    f"ℓ = {rough.length:g})",
                    fontsize=8)  # fmt: skip
    ax[0].set_xlabel("x / ℓ")
    ax[0].set_ylabel("y / ℓ")

    for solver, k, colour in ((spm, 2.0, "C0"), (iem, 5.0, "C3")):
        a = solver.bistatic(rough, EPS, k, TI, th, ph).sigma0
        b = solver.bistatic(m, EPS, k, TI, th, ph).sigma0
        name = solver.__name__.split(".")[-2].upper()
        for p, ls, pol in ((1, "-", "vv"), (0, "--", "hh")):
            ax[1].plot(np.degrees(ts), _db(a[p, p]), ls, color=colour, lw=2.5, alpha=0.35,
                       label=f"{name} {pol} analytic (kσ={k * rough.sigma:g})")  # fmt: skip
            ax[1].plot(np.degrees(ts), _db(b[p, p]), ls, color=colour, lw=1,
                       label=f"{name} {pol} measured map")  # fmt: skip
    ax[1].set_xlabel("θs [deg] (incidence plane, θi = 30°; < 0: back side)")
    ax[1].set_ylabel("σ⁰ [dB]")
    ax[1].set_title("σ⁰ of the measured map vs the analytic roughness", fontsize=9)
    ax[1].legend(fontsize=6.5)
    ax[1].set_ylim(-40, 5)

    lam = 1.0
    k = 2 * math.pi / lam
    r2 = GaussianCorrelation(0.12, 1.5)
    s2 = emscatter.generate_surface(r2, (256, 256), lam / 8, rng=1, periodic=True)
    orders = po_map(height_map(s2.heights, s2.spacing, detrend="none"), EPS, k, TI)
    idx = orders.select(n=0)
    idx = idx[idx != orders.specular]
    sgn = np.where(np.cos(orders.phi_s[idx]) < 0, -1.0, 1.0)
    x = np.degrees(sgn * orders.theta_s[idx])
    stat = po.bistatic(r2, EPS, k, TI, orders.theta_s[idx], orders.phi_s[idx], coherent=False)
    ax[2].plot(x, _db(orders.sigma0[1, 1, idx]), ".", ms=3, color="0.4",
               label="po_map: orders of one 256² realization (vv)")  # fmt: skip
    ax[2].plot(x, _db(stat.sigma0[1, 1]), "-", color="C2", label="statistical PO (vv)")
    ax[2].set_xlabel("θs [deg] (orders n = 0, specular left out)")
    ax[2].set_ylabel("σ⁰ [dB]")
    ax[2].set_title(f"deterministic PO on a map (kσ = {k * r2.sigma:.2f}): speckle about the "
                    "mean", fontsize=9)  # fmt: skip
    ax[2].legend(fontsize=7)
    ax[2].set_ylim(-50, 15)
    fig.text(0.01, 0.005, "$ PYTHONPATH=src python validation/heightmap/make_figure.py",
             fontsize=7, family="monospace", color="0.3")  # fmt: skip
    fig.tight_layout(rect=(0, 0.03, 1, 1))
    out = save_figure(fig, HERE / "heightmap.png")
    print(f"wrote {out}")
    return out


def render(argv=()) -> None:
    """The rendered half (``make_render.py``: Mitsuba, its own process, as Dr.Jit variants
    are per process) → render.png / render.json."""
    import subprocess

    subprocess.run([sys.executable, str(HERE / "make_render.py"), *argv], check=True)


if __name__ == "__main__":
    main()
    if "--no-render" not in sys.argv[1:]:
        render()
