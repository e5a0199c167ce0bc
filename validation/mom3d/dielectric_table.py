"""The 3-D dielectric method of moments against SPM, PO, GO, the IEM and ``auto`` over
kσ × kℓ × θi at one permittivity: the dielectric cells beside pec_table.py's (issue 19).

Dielectric ``--eps`` (default ``4+0.5j``, soil-like; ``Im ε ≥ 0``) under air, Gaussian
correlation, kσ ∈ ``--k-sigma`` (default 0.1 0.3), kℓ ∈ ``--k-l`` (3), θi ∈ ``--theta-i``
(20° 40°); per cell ``--realizations`` surfaces (default 16, seeds
``SeedSequence(seed).spawn`` as ``emscatter.solvers.mom3d.bistatic`` draws them) on a
``--length`` λ square patch (default 3) at 8 points per wavelength **inside** the medium
(``λ / Re √ε``, as mom3d grids a dielectric: 49² nodes, 9 604 unknowns at 3λ, ε = 4 + 0.5i),
each solved by :func:`emscatter.solvers.mom3d.dielectric_model.solve_dielectric_realization`
(the dielectric SMCG product above 256 nodes) through soil_vs_models.py's ``realization``.

Energy per realization (lossy medium: the transmitted power is not a far field): ``R + A``,
the reflectivity plus the Poynting flux into the medium from the solved surface fields
(soil_vs_models.py's ``absorbed``); ``energy_min`` is the smallest over the cell's
realizations and both polarizations, and the samples file keeps each (``energy[j][pol]``).
A realization with ``|R + A − 1|`` over :data:`ENERGY_TOL` stops the run (no broken
solution is stored).

Metric, bins, columns and the models' comparison are pec_table.py's (imported, not copied:
``directions``, ``binned``, ``compare``): co-pol σ⁰ in 10° bins of signed θs ∈ [−60°, 60°]
pooled over three k_y rows, :func:`emscatter.validation.maps._sigma0_error` per pol. Extra
columns ``eps_real``, ``eps_imag``; an extra row per cell ``method = "auto"``:
``emscatter.bistatic(method="auto")`` with θi given, i.e. the ranking as the package stood
when the cell ran (its pick in ``status``); it is not a candidate for the cell's ``auto``
column (the smallest error among SPM1, PO, GO, IEM). Schema ``mom3d_dielectric_table/1``;
per-realization data in ``dielectric_table_samples.json`` (schema
``mom3d_dielectric_samples/1``: pec_table's per-cell fields plus ``eps`` ``[re, im]``,
``energy`` and ``auto``), from which
:func:`emscatter.validation.measured_table_3d.write_measured_3d` writes auto's 3-D table.

Run: PYTHONPATH=src python validation/mom3d/dielectric_table.py [--eps 4+0.5j]
     [--theta-i 20 40] [--k-sigma 0.1 0.3] [--k-l 3] [--realizations 16] [--length 3]
≈ 17 s per realization at 3λ on 2 loaded cores (≈ 5 min per cell of 16). Rows (and samples)
of the cells run are replaced, others kept: run one cell per command to keep each short.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))  # the sibling scripts (not a package)

import pec_table as pt  # noqa: E402
import soil_vs_models as sv  # noqa: E402

import emscatter as em  # noqa: E402
from emscatter.io import atomic_path, write_csv  # noqa: E402
from emscatter.spectra import GaussianCorrelation  # noqa: E402

CSV, MD = HERE / "dielectric_table.csv", HERE / "dielectric_table.md"
SAMPLES = HERE / "dielectric_table_samples.json"
SCHEMA, SAMPLES_SCHEMA = "mom3d_dielectric_table/1", "mom3d_dielectric_samples/1"
HEADER = [*pt.HEADER, "eps_real", "eps_imag"]
#: Largest accepted ``|R + A − 1|`` of one realization.
ENERGY_TOL = 0.03
K = pt.K


def key(d) -> tuple:
    """Cell key: ε (re, im), θi, kσ, kℓ."""
    if "eps" in d:
        re, im = (float(x) for x in d["eps"])
    else:
        re, im = float(d["eps_real"]), float(d["eps_imag"])
    return (re, im, float(d["theta_i_deg"]), float(d["k_sigma"]), float(d["k_l"]))


def cell(eps: complex, ks, kl, tdeg, realizations, length, seed):
    """Rows and the samples entry of one cell (module docstring)."""
    rough = GaussianCorrelation(ks / K, kl / K)
    ti = math.radians(tdeg)
    ts, ps = pt.directions()
    seeds = np.random.SeedSequence(seed).spawn(realizations)
    t0 = time.perf_counter()
    res = []
    for j, ss in enumerate(seeds):
        r = sv.realization(rough, eps, K, length, ti, ts.ravel(), ps.ravel(), ss)
        e = r["reflectivity"] + r["absorbed"]
        if not np.all(np.abs(e - 1.0) <= ENERGY_TOL):
            raise FloatingPointError(
                f"ε={eps} kσ={ks:g} kℓ={kl:g} θi={tdeg:g}° realization {j}: R + A = "
                f"{np.round(e, 4)}, off 1 by more than {ENERGY_TOL}"
            )
        res.append(r)
        print(f"  realization {j}: {r['seconds']:.0f} s, R + A = {np.round(e, 4)}", flush=True)
    seconds = time.perf_counter() - t0
    mc = sv.monte_carlo(res, K, ti)
    per = pt.binned(mc["samples"].reshape(realizations, 2, 2, *ts.shape))
    energy = np.array([r["reflectivity"] + r["absorbed"] for r in res])  # (n, 2)
    sample = {"eps": [eps.real, eps.imag], "correlation": "gaussian", "theta_i_deg": tdeg,
              "k_sigma": ks, "k_l": kl, "realizations": realizations, "seed": seed,
              "length_wavelengths": length, "energy": pt._g(energy)}  # fmt: skip
    base = {"k_sigma": ks, "k_l": kl, "rms_slope": math.sqrt(2) * ks / kl,
            "realizations": realizations, "unknowns": res[0]["unknowns"], "seconds": seconds,
            "theta_i_deg": tdeg, "correlation": "gaussian", "dimension": 2,
            "length_wavelengths": length, "energy_min": float(energy.min()),
            "eps_real": eps.real, "eps_imag": eps.imag}  # fmt: skip
    out = pt.compare(rough, eps, ti, ts, ps, per, base, sample, auto_row=True)
    best = out[0]["auto"]
    worst = max(r["error_dB"] for r in out if r["method"] == best)
    print(f"ε={eps} kσ={ks:g} kℓ={kl:g} θi={tdeg:g}°: {seconds:.0f} s, "
          f"R + A ∈ [{energy.min():.4f}, {energy.max():.4f}], best {best} {worst:.2f} dB, "
          f"auto = {sample['auto']['method']}", flush=True)  # fmt: skip
    return out, sample


def save(rows, meta) -> None:
    cols = [np.array([r[h] for r in rows], dtype=object if h in pt.TEXT else float)
            for h in HEADER]  # fmt: skip
    write_csv(CSV, HEADER, cols, metadata=meta, schema=SCHEMA)
    names = [*pt.MODELS, "auto"]
    lines = [
        "# mom3d (dielectric, 3-D) vs SPM1 / PO / GO / IEM and `auto` — Gaussian correlation",
        "",
        "rms dB error of each model against the exact 3-D σ⁰ (co-pol, 10° bins of θs ∈ "
        "[−60°, 60°] in the plane of incidence, pooled over k_y/k ∈ {−0.14, 0, 0.14}); "
        "h / v; * = the smallest error of the cell among the four models (larger of h, v); "
        "(x) = outside the model's validity criteria; `auto` = `method=\"auto\"` as the "
        "package ranked when the cell ran (its pick after the arrow). 8 points per wavelength "
        "inside the medium; energy = R + A per realization (reflected + absorbed). Made by "
        "`PYTHONPATH=src python validation/mom3d/dielectric_table.py` (see its docstring); "
        "data in dielectric_table.csv.",
        "",
        "Read with the Monte Carlo noise in mind: the last column is the rms standard error "
        "of mom3d's bins (dB). The 3λ patch's beam (taper g = 0.75λ) spreads ≈ 2/(kg) ≈ 25°: "
        "mom3d's σ⁰ is the true one smoothed over that width, the models' are not.",
        "",
        "| ε | θi | kσ | kℓ | slope | real. | L/λ | R + A ≥ | s | " + " | ".join(names)
        + " | mom3d SE dB |",
        "|---" * (10 + len(names)) + "|",
    ]  # fmt: skip
    for k in sorted({key(r) for r in rows}):
        re, im, t, ks, kl = k
        sub = [r for r in rows if key(r) == k]
        r0 = sub[0]
        cells = []
        for m in names:
            e = {r["pol"]: float(r["error_dB"]) for r in sub if r["method"] == m}
            mine = [r for r in sub if r["method"] == m]
            if not mine:
                cells.append("—")
                continue
            txt = f"{e['h']:.2f} / {e['v']:.2f}"
            txt = f"**{txt}**\\*" if r0["auto"] == m else txt
            txt = txt if str(mine[0]["valid"]) == "True" else f"({txt})"
            if m == "auto":
                txt += " → " + str(mine[0]["status"]).split("auto = ")[-1].rstrip(")")
            cells.append(txt)
        lines.append(pt.table_row(f"{re:g}+{im:g}i | {t:g}° | {ks:g} | {kl:g}", sub, cells))
    with atomic_path(MD) as tmp:
        Path(tmp).write_text("\n".join(lines) + "\n")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--eps", type=complex, default=4 + 0.5j)
    ap.add_argument("--theta-i", type=float, nargs="+", default=[20.0, 40.0])
    ap.add_argument("--k-sigma", type=float, nargs="+", default=[0.1, 0.3])
    ap.add_argument("--k-l", type=float, nargs="+", default=[3.0])
    ap.add_argument("--realizations", type=int, default=16)
    ap.add_argument("--length", type=float, default=3.0)
    ap.add_argument("--seed", type=int, default=19)
    args = ap.parse_args(argv)
    eps = complex(args.eps)
    if not (eps.real > 1.0 and eps.imag >= 0.0):
        ap.error(f"--eps must have Re ε > 1 and Im ε ≥ 0 (exp(-iωt)), got {args.eps}")
    if args.realizations < 2:
        ap.error(f"--realizations must be at least 2, got {args.realizations}")
    rows = pt._load(CSV)[0]
    meta = {"points_per_wavelength_inside": pt.PPW, "seed": args.seed,
            "emscatter": em.__version__, "models": pt.MODELS, "ky_rows": pt.KY,
            "bins_deg": pt.EDGES.tolist(), "energy": "R + A (reflected + absorbed)"}  # fmt: skip
    samples = pt.load_samples(SAMPLES)
    for tdeg in args.theta_i:
        for ks in args.k_sigma:
            for kl in args.k_l:
                new, sample = cell(eps, ks, kl, tdeg, args.realizations, args.length, args.seed)
                rows = [r for r in rows if key(r) != key(sample)] + new
                samples = [c for c in samples if key(c) != key(sample)] + [sample]
                pt.save_samples(samples, SAMPLES, schema=SAMPLES_SCHEMA,
                                table="dielectric_table", key=key)  # fmt: skip
                save(rows, meta)


if __name__ == "__main__":
    main()
