"""Co-polarized ratio HH − VV of the IEM in backscatter (issue 20), before/after, against peers.

    PYTHONPATH=src python validation/iem/copol_ratio.py [--nmm3d LUT.dat] [--smrt PYTHON]
        → validation/iem/copol_ratio.csv, copol_ratio.md

Grid: the NMM3D 40° look-up table of Tsang's group (exact 3-D solutions of Maxwell's
equations; exponential correlation, ℓ/σ ∈ {4, 7, 10, 15}, rms height 0.021–0.21 λ,
ε ∈ {3+i, 5.5+2i, 9+2.5i, 15+3.5i, 22+4i, 30+4.5i}: 162 cases, kσ 0.13–1.32). ``--nmm3d``: that
table (8 columns: θ, ℓ/σ, Re ε, Im ε, σ/λ, VV, HH, HV dB) for the exact columns; without it the
same grid is built and the exact columns are left empty. ``--smrt``: an interpreter with SMRT
1.7 (``iiem_fung02`` without cross-pol, ``iem_fung92``; 30 series terms). Models: emscatter
``iem`` default (``complementary="aiem-faded"``, since issue 20), the published AIEM
(``"aiem"``, the default before), ``"aiem-upper"`` and the 1992 configuration.
"""

from __future__ import annotations

import argparse
import math
import sys
import warnings
from pathlib import Path

import numpy as np

from emscatter.solvers import iem
from emscatter.spectra import ExponentialCorrelation

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
from nmm3d_lut import atomic_write as _atomic  # noqa: E402
from nmm3d_lut import grid, read_lut, run_peers  # noqa: E402

THETA = math.radians(40.0)
MODELS = {
    "aiem_faded": {},
    "aiem": dict(complementary="aiem"),
    "aiem_upper": dict(complementary="aiem-upper"),
    "fung92": dict(fresnel="incident", complementary="fung92", first_order="model",
                   shadowing=False),
}  # fmt: skip


def _grid(nmm3d):
    t = read_lut(nmm3d) if nmm3d else grid()
    return [(r[1], r[2], r[3], r[4], r[5], r[6]) for r in t]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--nmm3d", default=None)
    ap.add_argument("--smrt", default=None)
    args = ap.parse_args()
    rows = _grid(args.nmm3d)
    warnings.simplefilter("ignore")
    cols = {}
    for name, kw in MODELS.items():
        vals = []
        for ratio, er, ei, h, *_ in rows:
            ks = 2 * math.pi * h
            r = ExponentialCorrelation(ks, ratio * ks)
            s = iem.bistatic(r, complex(er, ei), 1.0, THETA, THETA, math.pi, crosspol=False,
                             coherent=False, **kw).sigma0  # fmt: skip
            vals.append((10 * math.log10(s[1, 1]), 10 * math.log10(s[0, 0])))
        cols[name] = np.array(vals)
    if args.smrt:
        cases = [
            (2 * math.pi * h, ratio * 2 * math.pi * h, er, ei) for ratio, er, ei, h, *_ in rows
        ]
        peers = run_peers(args.smrt, cases, want=("smrt",), crosspol=False)
        for n in ("smrt_iiem_fung02", "smrt_iem_fung92"):
            cols[n] = 10 * np.log10(peers[n][:, :2])
    exact = np.array([(r[4], r[5]) for r in rows])
    names = list(cols)
    head = ["l_over_sigma", "eps_re", "eps_im", "k_sigma", "nmm3d_vv", "nmm3d_hh"]
    head += [f"{n}_{p}" for n in names for p in ("vv", "hh")]
    lines = [",".join(head)]
    for i, (ratio, er, ei, h, vv, hh) in enumerate(rows):
        v = [ratio, er, ei, 2 * math.pi * h, vv, hh]
        v += [x for n in names for x in cols[n][i]]
        lines.append(",".join(f"{x:.4f}" for x in v))
    _atomic(HERE / "copol_ratio.csv", "\n".join(lines) + "\n")
    ks = np.array([2 * math.pi * r[3] for r in rows])
    box = (ks > 0.6) & (ks < 1.4)
    md = ["# IEM co-pol ratio in backscatter, 40°, exponential (issue 20)", "",
          "Made by `PYTHONPATH=src python validation/iem/copol_ratio.py --nmm3d LUT "
          "--smrt SMRT_PYTHON` (module docstring). dB; bias = model − NMM3D.", "",
          "| model | VV RMSE | HH RMSE | VV bias | HH bias "
          "| HH−VV, kσ 0.79–1.32: mean (min … max) |",
          "|---|---|---|---|---|---|"]  # fmt: skip
    have = np.all(np.isfinite(exact))
    if have:
        d = exact[:, 1] - exact[:, 0]
        md.append(f"| NMM3D (exact) | — | — | — | — | {d[box].mean():+.2f} "
                  f"({d[box].min():+.2f} … {d[box].max():+.2f}) |")  # fmt: skip
    for n in names:
        c = cols[n]
        d = c[:, 1] - c[:, 0]
        ratio_txt = f"{d[box].mean():+.2f} ({d[box].min():+.2f} … {d[box].max():+.2f})"
        if have:
            e = c - exact
            rm = np.sqrt(np.mean(e**2, axis=0))
            b = e.mean(axis=0)
            md.append(
                f"| {n} | {rm[0]:.2f} | {rm[1]:.2f} | {b[0]:+.2f} | {b[1]:+.2f} | {ratio_txt} |"
            )
        else:
            md.append(f"| {n} | | | | | {ratio_txt} |")
    if have:
        md += ["", "Bias per kσ (VV / HH), dB:", "",
               "| model | " + " | ".join(f"{k:.2f}" for k in sorted(set(np.round(ks, 2)))) + " |",
               "|---|" + "---|" * len(set(np.round(ks, 2)))]  # fmt: skip
        for n in names:
            e = cols[n] - exact
            cells = [f"{e[np.isclose(ks, k, atol=5e-3), 0].mean():+.2f} / "
                     f"{e[np.isclose(ks, k, atol=5e-3), 1].mean():+.2f}"
                     for k in sorted(set(np.round(ks, 2)))]  # fmt: skip
            md.append(f"| {n} | " + " | ".join(cells) + " |")
    _atomic(HERE / "copol_ratio.md", "\n".join(md) + "\n")
    print("\n".join(md))


if __name__ == "__main__":
    main()
