"""Figures of the integral-equation model (validation/iem/README.md).

    PYTHONPATH=src python validation/iem/figures.py [--smrt /tmp/smrtvenv/bin/python]

writes, in validation/iem/:

* ``backscatter.png`` — σ⁰(θ) hh, vv, hv of a C-band soil (exponential, kσ = 0.44, kℓ = 3.3,
  ε = 15 + 2i) and a rougher Gaussian surface (kσ = 1.1, kℓ = 5.6): AIEM against first-order
  SPM, physical optics, the 1992 IEM configuration, and SMRT 1.7 (``iem_fung92``,
  ``iiem_fung02``; curves computed in its scratch venv when available, else the stored points
  of tests/data/iem_smrt_reference.csv);
* ``bistatic_plane.png`` — σ⁰(θs) in the plane of incidence (θi = 30°), AIEM against SPM1 and
  physical optics, for three roughnesses across the SPM → Kirchhoff transition;
* ``bistatic_hemisphere.png`` — σ⁰ hh and hv over the scattering hemisphere (θi = 30°): the
  single-scattering cross-pol out of the plane;
* ``crosspol_soil.png`` — hv backscatter of soils (C band, exponential) against SMRT's
  ``iiem_fung02`` and the cross-pol ratio of the measured-data fit of Oh et al. (1992);
* ``emissivity.png`` — e_h, e_v (θ) of a soil from the model (shared hemispherical quadrature)
  against the flat surface and second-order SPM.
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import warnings
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from emscatter import api  # noqa: E402
from emscatter.fresnel import reflectivity  # noqa: E402
from emscatter.io import save_figure  # noqa: E402
from emscatter.solvers.iem import model as iem
from emscatter.solvers.kirchhoff import po as kirchhoff_po
from emscatter.solvers.spm import model as spm
from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation  # noqa: E402

HERE = Path(__file__).resolve().parent
C = 299792458.0
FREQ = 5.3e9
KC = 2 * math.pi * FREQ / C
EPS = 15 + 2j
FUNG92 = dict(fresnel="incident", complementary="fung92", first_order="model", shadowing=False,
              crosspol=False)  # fmt: skip
SOILS = {
    "exponential, σ = 0.4 cm, ℓ = 3 cm (kσ = 0.44, kℓ = 3.3)": ("exponential", 0.004, 0.03),
    "Gaussian, σ = 1 cm, ℓ = 5 cm (kσ = 1.1, kℓ = 5.6)": ("gaussian", 0.01, 0.05),
}
SMRT_SCRIPT = r"""
import json, sys, warnings
import numpy as np
from smrt.interface.iem_fung92 import IEM_Fung92
from smrt.interface.iiem_fung02 import IIEM_Fung02
warnings.simplefilter("ignore")
acf, s, l, f, er, ei = sys.argv[1], *map(float, sys.argv[2:7])
th = np.array(json.loads(sys.argv[7])); mu = np.cos(np.radians(th)); eps = complex(er, ei)
out = {}
m = IEM_Fung92(roughness_rms=s, corr_length=l, autocorrelation_function=acf,
               series_truncation=30, warning_handling="nothing")
R = m.diffuse_reflection_matrix(f, 1, eps, mu, mu, np.pi, 2)
out["fung92_vv"], out["fung92_hh"] = (list(4*np.pi*mu*np.asarray(R[i]).ravel()) for i in (0, 1))
m = IIEM_Fung02(roughness_rms=s, corr_length=l, autocorrelation_function=acf,
                warning_handling="nothing", N_integral=60)
R = m.diffuse_reflection_matrix(f, 1, eps, mu, mu, np.pi, 3)
for key, (a, b) in (("iiem_vv", (0, 0)), ("iiem_hh", (1, 1)), ("iiem_hv", (0, 1))):
    out[key] = list(4 * np.pi * mu * np.asarray(R[a, b, 0]).diagonal())
print(json.dumps(out))
"""


def _rough(kind, s, ell, dimension=2):
    cls = GaussianCorrelation if kind == "gaussian" else ExponentialCorrelation
    return cls(s, ell, dimension=dimension)


def _db(x):
    return 10 * np.log10(np.maximum(x, 1e-300))


def _smrt(python, kind, s, ell, theta_deg):
    if not Path(python).exists():
        return None
    args = [python, "-c", SMRT_SCRIPT, kind, str(s), str(ell), str(FREQ), str(EPS.real),
            str(EPS.imag), json.dumps(list(map(float, theta_deg)))]  # fmt: skip
    res = subprocess.run(args, capture_output=True, text=True, check=True, timeout=900)
    return {k: np.array(v) for k, v in json.loads(res.stdout.strip().splitlines()[-1]).items()}


def backscatter(smrt_python):
    th_deg = np.arange(2.0, 71.0, 2.0)
    th = np.radians(th_deg)
    fig, axes = plt.subplots(1, 2, figsize=(13, 5))
    for ax, (label, (kind, s, ell)) in zip(axes, SOILS.items(), strict=True):
        rough = _rough(kind, s, ell)
        a = iem.bistatic(rough, EPS, KC, th, th, math.pi, coherent=False)
        f92 = iem.bistatic(rough, EPS, KC, th, th, math.pi, coherent=False, **FUNG92)
        b = spm.bistatic(rough, EPS, KC, th, th, math.pi, coherent=False)
        p = kirchhoff_po.bistatic(rough, EPS, KC, th, th, math.pi)
        for pol, c in (("hh", "C0"), ("vv", "C3")):
            ax.plot(th_deg, _db(a.pol(pol)), c, lw=2, label=f"AIEM {pol}")
            ax.plot(th_deg, _db(f92.pol(pol)), c, ls="--", lw=1, label=f"IEM 1992 config. {pol}")
            ax.plot(th_deg, _db(b.pol(pol)), c, ls=":", lw=1, label=f"SPM1 {pol}")
        ax.plot(th_deg, _db(p.hh), "k", ls="-.", lw=1, label="PO hh = vv")
        ax.plot(th_deg, _db(a.hv), "C2", lw=2, label="AIEM hv (multiple scattering)")
        peer = _smrt(smrt_python, kind, s, ell, th_deg)
        if peer is not None:
            ax.plot(th_deg, _db(peer["fung92_hh"]), "C0o", ms=3, mfc="none",
                    label="SMRT iem_fung92 hh")  # fmt: skip
            ax.plot(th_deg, _db(peer["fung92_vv"]), "C3o", ms=3, mfc="none",
                    label="SMRT iem_fung92 vv")  # fmt: skip
            ax.plot(th_deg, _db(peer["iiem_hh"]), "C0x", ms=4, label="SMRT iiem_fung02 hh")
            ax.plot(th_deg, _db(peer["iiem_vv"]), "C3x", ms=4, label="SMRT iiem_fung02 vv")
            ax.plot(th_deg, _db(peer["iiem_hv"]), "C2x", ms=4, label="SMRT iiem_fung02 hv")
        ax.set(title=f"{label}, ε = 15+2i, 5.3 GHz", xlabel="θi [deg]", ylabel="σ⁰ [dB]",
               ylim=(max(-60, _db(a.hv).min() - 5), 10))  # fmt: skip
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7, ncol=2)
    return save_figure(fig, HERE / "backscatter.png")


def bistatic_plane():
    k = 2 * math.pi
    ti = math.radians(30.0)
    signed = np.arange(-85.0, 86.0, 1.0)
    ts, ps = np.radians(np.abs(signed)), np.where(signed >= 0, 0.0, math.pi)
    cases = [(0.1, 1.0), (0.5, 3.0), (2.0, 12.0)]
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.6), sharey=False)
    for ax, (ks, kl) in zip(axes, cases, strict=True):
        rough = GaussianCorrelation(ks / k, kl / k)
        a = iem.bistatic(rough, EPS, k, ti, ts, ps, coherent=False)
        b = spm.bistatic(rough, EPS, k, ti, ts, ps, coherent=False)
        p = kirchhoff_po.bistatic(rough, EPS, k, ti, ts, ps)
        for pol, c in (("hh", "C0"), ("vv", "C3")):
            ax.plot(signed, _db(a.pol(pol)), c, lw=2, label=f"AIEM {pol}")
            ax.plot(signed, _db(b.pol(pol)), c, ls=":", label=f"SPM1 {pol}")
            ax.plot(signed, _db(p.pol(pol)), c, ls="--", lw=1, label=f"PO {pol}")
        top = _db(a.sigma0).max()
        ax.set(title=f"Gaussian kσ = {ks}, kℓ = {kl}, θi = 30°", xlabel="signed θs [deg] "
               "(> 0: specular side)", ylabel="σ⁰ [dB]", ylim=(top - 50, top + 5))  # fmt: skip
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    return save_figure(fig, HERE / "bistatic_plane.png")


def bistatic_hemisphere():
    k = 2 * math.pi
    rough = ExponentialCorrelation(0.5 / k, 4.0 / k)
    ts = np.radians(np.linspace(0.0, 85.0, 60))
    ps = np.linspace(0.0, 2 * math.pi, 121)
    T, P = np.meshgrid(ts, ps, indexing="ij")
    a = iem.bistatic(rough, EPS, k, math.radians(30.0), T, P, coherent=False, crosspol=False)
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.8), subplot_kw={"projection": "polar"})
    for ax, pol in zip(axes, ("hh", "vv", "hv"), strict=True):
        m = ax.pcolormesh(P, np.degrees(T), _db(a.pol(pol)), shading="auto", cmap="viridis",
                          vmin=_db(a.hh).max() - 45, vmax=_db(a.hh).max())  # fmt: skip
        ax.set_title(f"σ⁰ {pol} [dB], θi = 30° (φi = 0)", fontsize=9)
        fig.colorbar(m, ax=ax, shrink=0.7)
    fig.suptitle("AIEM bistatic, exponential kσ = 0.5, kℓ = 4, ε = 15+2i — single-scattering "
                 "cross-pol out of the plane (zero in it)", fontsize=10)  # fmt: skip
    return save_figure(fig, HERE / "bistatic_hemisphere.png")


def crosspol_soil(smrt_python):
    th_deg = np.arange(10.0, 61.0, 5.0)
    th = np.radians(th_deg)
    fig, ax = plt.subplots(figsize=(7, 5))
    g0 = abs((1 - np.sqrt(EPS)) / (1 + np.sqrt(EPS))) ** 2
    for (s, ell), c in (((0.004, 0.03), "C0"), ((0.01, 0.05), "C1"), ((0.015, 0.06), "C2")):
        rough = ExponentialCorrelation(s, ell)
        a = iem.bistatic(rough, EPS, KC, th, th, math.pi, coherent=False)
        lab = f"kσ = {KC * s:.2f}, kℓ = {KC * ell:.1f}"
        ax.plot(th_deg, _db(a.hv), c, lw=2, label=f"AIEM hv, {lab}")
        q_oh = 0.23 * math.sqrt(g0) * (1 - math.exp(-KC * s))
        ax.plot(th_deg, _db(a.vv * q_oh), c, ls=":", label="Oh et al. 1992 ratio × AIEM vv")
        peer = _smrt(smrt_python, "exponential", s, ell, th_deg)
        if peer is not None:
            ax.plot(th_deg, _db(peer["iiem_hv"]), c + "x", label="SMRT iiem_fung02 hv")
    ax.set(xlabel="θi [deg]", ylabel="σ⁰_hv [dB]", title="Cross-polarized backscatter of a soil "
           "(exponential, ε = 15+2i, 5.3 GHz)")  # fmt: skip
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    return save_figure(fig, HERE / "crosspol_soil.png")


def emissivity():
    th = np.radians(np.arange(0.0, 71.0, 5.0))
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.6))
    flat = reflectivity(EPS, th)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for ax, (kind, ks, kl) in zip(axes, (("exponential", 0.44, 3.3), ("gaussian", 1.1, 5.6)),
                                      strict=True):  # fmt: skip
            rough = _rough(kind, ks / KC, kl / KC)
            e = api.emissivity(rough, EPS, frequency=FREQ, theta_i=th, method="iem", tol=1e-3,
                               out_of_range="ignore")  # fmt: skip
            for i, (pol, c) in enumerate((("h", "C0"), ("v", "C3"))):
                ax.plot(np.degrees(th), e.emissivity[i], c, lw=2, label=f"AIEM e_{pol}")
                ax.plot(np.degrees(th), 1 - flat[i], c, ls="--", lw=1, label=f"flat e_{pol}")
            if ks < 0.5:
                s2 = api.emissivity(rough, EPS, frequency=FREQ, theta_i=th, method="spm",
                                    tol=1e-3, out_of_range="ignore")  # fmt: skip
                for i, c in ((0, "C0"), (1, "C3")):
                    ax.plot(
                        np.degrees(th), s2.emissivity[i], c, ls=":", label="SPM2" if i else None
                    )
            ax.set(title=f"{kind} kσ = {ks}, kℓ = {kl}, ε = 15+2i", xlabel="θ [deg]",
                   ylabel="emissivity", ylim=(0, 1))  # fmt: skip
            ax.grid(alpha=0.3)
            ax.legend(fontsize=7)
    return save_figure(fig, HERE / "emissivity.png")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--smrt", default="/tmp/smrtvenv/bin/python")
    args = ap.parse_args(argv)
    for path in (backscatter(args.smrt), bistatic_plane(), bistatic_hemisphere(),
                 crosspol_soil(args.smrt), emissivity()):  # fmt: skip
        print(path)


if __name__ == "__main__":
    main()
