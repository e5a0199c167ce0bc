"""Backscatter HV against NMM3D at 40°: the IEM term, second-order SPM, and the resummed term
(issue 20: every IEM's HV is 4–5 dB low).

    PYTHONPATH=src python validation/auto/hv_resummed.py --nmm3d LUT.dat
        → validation/auto/hv_resummed.csv, hv_resummed.md

Per NMM3D case with HV (138 of the 162 rows of the 40° table, ``validation/nmm3d_lut.py``;
exponential correlation, wavelength 1 m, σ = σ/λ, ℓ = (ℓ/σ) σ), σ⁰_hv in dB of:

- ``iem``: the IEM multiple-scattering term (:func:`emscatter.solvers.iem.crosspol.backscatter`,
  what ``method="iem"`` and ``auto``'s IEM branch return);
- ``spm2``: second-order SPM σ⁰⁽²²⁾ (:func:`emscatter.solvers.spm.crosspol.backscatter_hv`, the
  exact small-roughness limit, here also beyond its validity);
- ``spm2_prop``: σ⁰⁽²²⁾ with the intermediate wave restricted to ``|p| < k`` (``sigma0_22(...,
  propagating=True)``), the domain of the IEM term: how much of the hv is evanescent;
- ``resummed``: :func:`emscatter.solvers.iem.crosspol_resummed.backscatter_resummed`.

RMSE and bias (model − NMM3D, dB) overall, per kσ band, per ε. The Markdown's first line is the
command that made it.
"""

from __future__ import annotations

import argparse
import math
import shlex
import sys
from pathlib import Path

import numpy as np

import emscatter as em
from emscatter.solvers.iem import crosspol
from emscatter.solvers.iem.crosspol_resummed import backscatter_resummed
from emscatter.solvers.iem.model import nominal_rms_slope
from emscatter.solvers.spm.crosspol import backscatter_hv, sigma0_22

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
from nmm3d_lut import atomic_write, read_lut  # noqa: E402

MODELS = ("iem", "spm2", "spm2_prop", "resummed")


def models(lut: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(rows with HV, {model: dB})`` over the NMM3D cases that have HV."""
    k = 2.0 * math.pi
    rows = lut[np.isfinite(lut[:, 7])]
    out = np.empty((len(rows), len(MODELS)))
    for i, (th, q, er, ei, h, *_) in enumerate(rows):
        rough = em.ExponentialCorrelation(h, q * h)
        eps, t = complex(er, ei), np.array([math.radians(th)])
        vals = (
            crosspol.backscatter(rough, eps, k, t, 0.0 * t, slope=nominal_rms_slope(rough))[0],
            backscatter_hv(rough, eps, k, t)[0],
            sigma0_22(rough, eps, k, t[0], t[0], math.pi, 0.0, propagating=True)[0, 1],
            backscatter_resummed(rough, eps, k, t)[0],
        )
        out[i] = [10.0 * math.log10(v) for v in vals]
    return rows, out


def _stats(d):
    return f"{np.sqrt(np.mean(d**2)):.2f} ({np.mean(d):+.2f})"


def report(rows, out, command: str) -> str:
    ks = np.round(2 * math.pi * rows[:, 4], 2)
    er = rows[:, 2]
    d = out - rows[:, 7:8]
    lines = [f"`{command}`", "", "# Backscatter HV at 40° against NMM3D: IEM term, SPM2, resummed",
             "", f"{len(rows)} NMM3D cases with HV (exponential correlation; "
             "`validation/auto/hv_resummed.py`). RMSE (bias) in dB, model − NMM3D.", "",
             "## Overall", "", "| model | RMSE (bias) |", "|---|---|"]  # fmt: skip
    lines += [f"| {m} | {_stats(d[:, j])} |" for j, m in enumerate(MODELS)]
    for title, key in (("kσ band", ks), ("ε′", er)):
        vals = np.unique(key)
        lines += ["", f"## Per {title}", "",
                  "| model | " + " | ".join(f"{title} {v:g}" for v in vals) + " |",
                  "|---|" + "---|" * len(vals)]  # fmt: skip
        for j, m in enumerate(MODELS):
            cells = [_stats(d[key == v, j]) for v in vals]
            lines.append(f"| {m} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--nmm3d", required=True, help="path of the NMM3D 40° look-up table")
    ap.add_argument("--out", default=str(HERE), help="folder for hv_resummed.csv / .md")
    a = ap.parse_args(argv)
    try:
        lut = read_lut(a.nmm3d)
    except (OSError, ValueError) as exc:
        print(f"error: --nmm3d: {exc}", file=sys.stderr)
        return 2
    rows, out = models(lut)
    out_dir = Path(a.out)
    head = "theta_deg,l_over_sigma,eps_re,eps_im,sigma_over_lambda,nmm3d_hv," + ",".join(MODELS)
    pairs = zip(rows, out, strict=True)
    body = [",".join(f"{x:.6g}" for x in (*r[:5], r[7], *o)) for r, o in pairs]
    atomic_write(out_dir / "hv_resummed.csv", "\n".join([head, *body]) + "\n")
    cmd = "PYTHONPATH=src python validation/auto/hv_resummed.py --nmm3d NMM3D_40.dat"
    if a.out != str(HERE):
        cmd += f" --out {shlex.quote(Path(a.out).name)}"
    atomic_write(out_dir / "hv_resummed.md", report(rows, out, cmd))
    print(report(rows, out, cmd))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
