"""SPM2 coherent reflectivity against its spectral cutoff k_max, and against the MoM.

Part 1 (table): r_coh (second-order SPM, :func:`emscatter.solvers.spm.model.coherent_reflectivity`)
for exponential and power-law (H = 0.7) spectra, 2-D surfaces and 1-D profiles, over a lossy
soil (ε = 17 + 2i), a lossless dielectric (ε = 3) and a perfect conductor, for
k_max/k ∈ {2, 5, 10, 100, 1e3, 1e4} and the previous hidden default (support Kℓ = 2e4).

Part 2 (MoM): emissivity e = 1 − ⟨reflected⟩/P_inc of exponential 1-D profiles over
ε = 17 + 2i from the method of moments at two grid spacings dx (its surfaces' spectrum ends
at π/dx), against the SPM emissivity (1 − SPM2 coherent − SPM1 incoherent) with the MoM's
cutoff k_max = π/dx and with the default 2k.

Run: PYTHONPATH=src python validation/spm2_cutoff/make_spm2_cutoff.py   (≈ 10 min, 2 cores;
``--plot-only`` redraws the figure from the CSV, ``--spm-only`` recomputes the SPM columns of
the stored MoM rows without running the MoM)
Writes spm2_cutoff.csv, spm2_cutoff_mom.csv, README tables (printed) and spm2_cutoff.png here.
"""

from __future__ import annotations

import csv
import math
import platform
import sys
import time
import warnings
from pathlib import Path

import numpy as np

import emscatter as em
from emscatter.solvers.mom import model as mom
from emscatter.solvers.spm import model as spm
from emscatter.spectra import ExponentialCorrelation, PowerLawCorrelation

HERE = Path(__file__).resolve().parent
K = 2 * math.pi
CUTS = (2.0, 5.0, 10.0, 100.0, 1e3, 1e4)
THETA = (0.0, 40.0, 70.0)


def part1() -> list[dict]:
    rows = []
    for name, cls, kw in (
        ("exponential", ExponentialCorrelation, {}),
        ("power-law H=0.7", PowerLawCorrelation, {"hurst": 0.7}),
    ):
        for dim in (2, 1):
            for ks, kl in ((0.1, 1.0), (0.2, 5.0)):
                rough = cls(ks / K, kl / K, dimension=dim, **kw)
                for eps in (17 + 2j, 3.0, "pec"):
                    th = np.radians(THETA)
                    vals = [spm.coherent_reflectivity(rough, eps, K, th, k_max=c * K) for c in CUTS]
                    hidden = spm._coherent(  # the former hidden default: the support, Kℓ = 2e4
                        rough, spm._eps_array(eps), K, th, th.shape, 16, 16, 0.0, None
                    )[0]
                    for it, t in enumerate(THETA):
                        for ip, p in enumerate("hv"):
                            r = {
                                "spectrum": name,
                                "dimension": dim,
                                "k_sigma": ks,
                                "k_l": kl,
                                "eps": str(eps),
                                "theta_deg": t,
                                "pol": p,
                            }
                            for c, v in zip(CUTS, vals, strict=True):
                                r[f"r_coh_kmax_{c:g}k"] = float(v[ip, it])
                            r["r_coh_support"] = float(hidden[ip, it])
                            rows.append(r)
    return rows


def part2() -> list[dict]:
    """The MoM emissivities (the expensive part); SPM columns by :func:`spm_columns`."""
    rows = []
    eps = 17 + 2j
    for ks, kl in ((0.1, 1.0), (0.2, 3.0)):
        rough = ExponentialCorrelation(ks / K, kl / K, dimension=1)
        for ppw in (10.0, 20.0):
            for tdeg in (0.0, 40.0):
                ti = math.radians(tdeg)
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    ref = mom.bistatic(
                        rough,
                        eps,
                        K,
                        ti,
                        np.array([0.0]),
                        0.0,
                        realizations=16,
                        seed=11,
                        length=max(16.0, 20 * rough.length),
                        points_per_wavelength=ppw,
                        progress=False,
                    )
                flat = 1 - np.abs(np.array(em.fresnel.fresnel(eps, ti)[:2])) ** 2
                for ip, p in enumerate("hv"):
                    pp = ref.info["per_polarization"][p]
                    rows.append(
                        {
                            "k_sigma": ks,
                            "k_l": kl,
                            "theta_deg": tdeg,
                            "pol": p,
                            "mom_ppw_in_medium": ppw,
                            "kmax_over_k": math.pi / ref.info["dx"] / K,
                            "e_mom": 1 - pp["reflected"],
                            "e_mom_se": pp["reflected_se"],
                            "e_flat": float(flat[ip]),
                            "realizations": ref.info["realizations"],
                        }
                    )
    return rows


def spm_columns(rows: list[dict]) -> list[dict]:
    """SPM emissivity (1 − SPM2 coherent − SPM1 incoherent) of each MoM row's case with the
    MoM's own cutoff π/dx, with 2k and with the whole spectrum (the default)."""
    eps = 17 + 2j
    for r in rows:
        rough = ExponentialCorrelation(float(r["k_sigma"]) / K, float(r["k_l"]) / K, dimension=1)
        ti = math.radians(float(r["theta_deg"]))
        ip = "hv".index(r["pol"])
        for col, cut in (
            ("e_spm2_kmax_mom", float(r["kmax_over_k"]) * K),
            ("e_spm2_kmax_2k", 2 * K),
            ("e_spm2_whole_spectrum", None),
        ):
            kw = {} if cut is None else {"k_max": cut}
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                e = em.emissivity(rough, eps, wavelength=1.0, theta_i=ti, method="spm", **kw)
            r[col] = float(np.ravel(e.emissivity[ip])[0])
    return rows


def write(rows, path):
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


def plot(rows, path):
    """Change of r_coh from its default cutoff 2k, against k_max/k."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    panels = (("(17+2j)", 2), ("(17+2j)", 1), ("3.0", 2), ("pec", 2))
    fig, axes = plt.subplots(1, 4, figsize=(19, 4.6), constrained_layout=True)
    for ax, (eps, dim) in zip(axes, panels, strict=True):
        for r in rows:
            if r["eps"] != eps or int(r["dimension"]) != dim or float(r["k_sigma"]) != 0.1:
                continue
            if r["spectrum"] != "exponential":
                continue
            y = [float(r[f"r_coh_kmax_{c:g}k"]) - float(r["r_coh_kmax_2k"]) for c in CUTS]
            ax.semilogx(CUTS, y, "o-", label=f"{r['pol']}, θi = {float(r['theta_deg']):g}°")
        ax.set_xlabel("k_max / k")
        ax.set_ylabel("r_coh(k_max) − r_coh(2k)")
        kind = "surface" if dim == 2 else "profile"
        ax.set_title(f"exponential {kind}, kσ = 0.1, kℓ = 1, ε = {eps}", fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle(
        "Second-order SPM coherent reflectivity against its spectral cutoff k_max "
        "(validation/spm2_cutoff/make_spm2_cutoff.py)"
    )
    fig.savefig(path, dpi=110)


def main() -> None:
    if "--plot-only" in sys.argv:
        with open(HERE / "spm2_cutoff.csv", newline="") as fh:
            plot(list(csv.DictReader(fh)), HERE / "spm2_cutoff.png")
        return
    if "--spm-only" in sys.argv:  # recompute the SPM columns of the stored MoM rows
        with open(HERE / "spm2_cutoff_mom.csv", newline="") as fh:
            rows2 = list(csv.DictReader(fh))
        keep = ("k_sigma", "k_l", "theta_deg", "pol", "mom_ppw_in_medium", "kmax_over_k",
                "e_mom", "e_mom_se", "e_flat", "realizations")  # fmt: skip
        write(spm_columns([{c: r[c] for c in keep} for r in rows2]), HERE / "spm2_cutoff_mom.csv")
        return
    t0 = time.perf_counter()
    rows1 = part1()
    write(rows1, HERE / "spm2_cutoff.csv")
    plot(rows1, HERE / "spm2_cutoff.png")
    t1 = time.perf_counter()
    rows2 = spm_columns(part2())
    write(rows2, HERE / "spm2_cutoff_mom.csv")
    print(
        f"part 1 {t1 - t0:.0f} s, part 2 {time.perf_counter() - t1:.0f} s;",
        platform.node(),
        sys.version.split()[0],
        np.__version__,
    )


if __name__ == "__main__":
    main()
