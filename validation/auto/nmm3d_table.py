"""``method="auto"``, each method alone and the peers against NMM3D at 40° (issue 20).

    PYTHONPATH=src python validation/auto/nmm3d_table.py --nmm3d LUT.dat [--peers PYTHON]
        → validation/auto/nmm3d_table.csv, nmm3d_table.md, nmm3d_table.png

Cases: the 162 rows of the NMM3D 40° look-up table (exact 3-D numerical solutions of
Maxwell's equations by Tsang's group; exponential correlation, ℓ/σ 4–15, ε 3+i … 30+4.5i,
kσ 0.13–1.32; ``validation/nmm3d_lut.py``). The table is not in the repository: ``--nmm3d``
is its path. Models, backscatter at θ = 40°, all four polarizations:

- emscatter ``auto`` through the public API (:func:`emscatter.backscatter`, default
  ``out_of_range``), with the methods it blended and their weights per case;
- each method alone: ``spm``, ``po``, ``go``, ``iem`` (``out_of_range="ignore"``, default
  options: their hv is what that solver returns in backscatter, 0 for the Kirchhoff and
  first-order SPM ones);
- ``--peers PYTHON``: an interpreter with SMRT 1.7 (``iiem_fung02`` with its cross-pol,
  ``iem_fung92`` co-pol only; ``bash benchmarks/peers/setup.sh``) and/or pyi2em
  (``pip install pyi2em`` there); a peer that does not import there is left out.

Statistics, model − NMM3D in dB: RMSE and bias per polarization over the cases where both
are finite and positive (NMM3D has no HV on 24 rows, ``-Inf``: left out of HV); the count of
cases where the model's hv is 0 (left out of its HV statistics and reported); the same per kσ
band (the table's seven σ/λ); HH − VV mean per band against NMM3D's. The Markdown's first
line is the command that made it.
"""

from __future__ import annotations

import argparse
import math
import shlex
import sys
import time
import warnings
from collections import Counter
from pathlib import Path

import numpy as np

import emscatter as em

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
from nmm3d_lut import atomic_write, read_lut, run_peers  # noqa: E402

POLS = ("vv", "hh", "hv")
METHODS = ("spm", "po", "go", "iem")


def emscatter_models(lut: np.ndarray) -> tuple[dict, list, float]:
    """``({model: (n, 3) linear σ⁰ VV, HH, HV}, auto's weights per case, auto's median
    seconds per case)`` (median: the first calls compile the kernels). Wavelength 1 m:
    σ = σ/λ, ℓ = (ℓ/σ) σ. hv is σ⁰[h, v]; hv = vh is checked."""
    out = {m: np.empty((len(lut), 3)) for m in ("auto", *METHODS)}
    weights, t_auto = [], []
    for i, (th, q, er, ei, h, *_) in enumerate(lut):
        rough = em.ExponentialCorrelation(h, q * h)
        kw = dict(wavelength=1.0, theta_i=math.radians(th))
        eps = complex(er, ei)
        t0 = time.perf_counter()
        s = em.backscatter(rough, eps, **kw)
        t_auto.append(time.perf_counter() - t0)
        w = s.info.get("blend", {}).get("weights") or {s.method: 1.0}
        weights.append({n: float(v) for n, v in w.items()})
        runs = [("auto", s)] + [
            (m, em.backscatter(rough, eps, method=m, out_of_range="ignore", **kw)) for m in METHODS
        ]
        for name, r in runs:
            s0 = np.asarray(r.sigma0, dtype=float)
            if not np.isclose(s0[0, 1], s0[1, 0], rtol=1e-9, atol=0.0):
                raise RuntimeError(f"{name}: hv {s0[0, 1]!r} != vh {s0[1, 0]!r} at row {i}")
            out[name][i] = (s0[1, 1], s0[0, 0], s0[0, 1])  # [pol_s, pol_i], index 1 = v
    return out, weights, float(np.median(t_auto))


def _db(x):
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(np.asarray(x) > 0, 10 * np.log10(np.where(x > 0, x, 1.0)), -np.inf)


def stats(model_db: np.ndarray, exact_db: np.ndarray) -> dict:
    """RMSE, bias [dB] and counts of model − exact over the finite pairs of one column."""
    ok = np.isfinite(model_db) & np.isfinite(exact_db)
    e = model_db[ok] - exact_db[ok]
    zero = int(np.sum((model_db == -np.inf) & np.isfinite(exact_db)))
    if e.size == 0:
        return {"rmse": math.nan, "bias": math.nan, "n": 0, "zero": zero}
    return {"rmse": float(np.sqrt(np.mean(e**2))), "bias": float(e.mean()), "n": int(e.size),
            "zero": zero}  # fmt: skip


def _f(x, sign=False):
    return "—" if not np.isfinite(x) else (f"{x:+.2f}" if sign else f"{x:.2f}")


def tables(lut, models_db, weights, command, t_auto, peers_missing) -> str:
    """The Markdown report."""
    exact = lut[:, 5:8]
    ks = 2 * math.pi * lut[:, 4]
    bands = sorted(set(np.round(ks, 3)))
    band = [np.isclose(ks, b, atol=1e-3) for b in bands]
    n = len(lut)
    md = [f"`{command}`", "", "# `auto`, each method and the peers against NMM3D, 40° backscatter",
          "", f"{n} cases of the NMM3D 40° table (exponential, ℓ/σ 4–15, ε 3+i … 30+4.5i, "
          f"kσ {ks.min():.2f}–{ks.max():.2f}; `validation/auto/nmm3d_table.py`). dB; "
          "bias = model − NMM3D. HV statistics over the cases where both model and NMM3D have "
          f"hv > 0 (NMM3D: {int(np.sum(~np.isfinite(exact[:, 2])))} cases without HV); "
          "\"hv = 0\": cases where the model returns 0 (and NMM3D does not).", "",
          "## Overall", "",
          "| model | VV RMSE | HH RMSE | HV RMSE | VV bias | HH bias | HV bias | hv = 0 | "
          "HH > VV |", "|---|---|---|---|---|---|---|---|---|"]  # fmt: skip
    for name, d in models_db.items():
        st = [stats(d[:, j], exact[:, j]) for j in range(3)]
        zero = None if np.all(np.isnan(d[:, 2])) else int(np.sum(d[:, 2] == -np.inf))
        hhvv = int(np.sum(d[:, 1] > d[:, 0]))
        md.append(f"| {name} | {_f(st[0]['rmse'])} | {_f(st[1]['rmse'])} | {_f(st[2]['rmse'])} "
                  f"| {_f(st[0]['bias'], 1)} | {_f(st[1]['bias'], 1)} | {_f(st[2]['bias'], 1)} "
                  f"| {'—' if zero is None else f'{zero} of {n}'} | {hhvv} of {n} |")  # fmt: skip
    md.append(f"| NMM3D | | | | | | | | {int(np.sum(exact[:, 1] > exact[:, 0]))} of {n} |")
    for j, pol in enumerate(POLS):
        md += ["", f"## {pol.upper()} RMSE (bias) per kσ band", "",
               "| model | " + " | ".join(f"kσ {b:.2f}" for b in bands) + " |",
               "|---|" + "---|" * len(bands)]  # fmt: skip
        for name, d in models_db.items():
            cells = []
            for m in band:
                s = stats(d[m, j], exact[m, j])
                z = f", hv=0 ×{s['zero']}" if j == 2 and s["zero"] else ""
                cells.append(f"{_f(s['rmse'])} ({_f(s['bias'], 1)}){z}")
            md.append(f"| {name} | " + " | ".join(cells) + " |")
    md += ["", "## HH − VV, mean per kσ band", "",
           "| model | " + " | ".join(f"kσ {b:.2f}" for b in bands) + " |",
           "|---|" + "---|" * len(bands)]  # fmt: skip
    for name, d in {"NMM3D": exact, **models_db}.items():
        md.append(f"| {name} | " + " | ".join(
            _f(np.mean(d[m, 1] - d[m, 0]), 1) for m in band) + " |")  # fmt: skip
    combo = Counter("+".join(sorted(w, key=lambda k: -w[k])) for w in weights)
    each = Counter(m for w in weights for m in w)
    md += ["", "## What `auto` blended", "",
           "Per case (methods by decreasing weight): "
           + ", ".join(f"`{c}` {k}" for c, k in combo.most_common()) + ". "
           "Cases each method takes part in: "
           + ", ".join(f"`{m}` {k}" for m, k in each.most_common()) + ". "
           f"`auto` backscatter: median {t_auto * 1e3:.1f} ms per case (this run, shared CPU)."
           ]  # fmt: skip
    if peers_missing:
        md += ["", "Peers not run: " + "; ".join(peers_missing) + "."]
    return "\n".join(md) + "\n"


def write_csv(path, lut, models_db, weights) -> None:
    head = ["l_over_sigma", "eps_re", "eps_im", "sigma_over_lambda", "k_sigma",
            "nmm3d_vv", "nmm3d_hh", "nmm3d_hv"]  # fmt: skip
    head += [f"{n}_{p}" for n in models_db for p in POLS] + ["auto_weights"]
    lines = [",".join(head)]
    for i, r in enumerate(lut):
        v = [r[1], r[2], r[3], r[4], 2 * math.pi * r[4], *r[5:8]]
        v += [x for n in models_db for x in models_db[n][i]]
        w = " ".join(f"{m}:{x:.4f}" for m, x in weights[i].items())
        lines.append(",".join(f"{x:.4f}" for x in v) + "," + w)
    atomic_write(path, "\n".join(lines) + "\n")


def plot(path, lut, models_db) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    exact = lut[:, 5:8]
    ks = 2 * math.pi * lut[:, 4]
    bands = sorted(set(np.round(ks, 3)))
    fig, axes = plt.subplots(1, 3, figsize=(14, 4.2), sharey=True)
    for j, (ax, pol) in enumerate(zip(axes, POLS, strict=True)):
        for c, (name, d) in enumerate(models_db.items()):
            y = [stats(d[np.isclose(ks, b, atol=1e-3), j], exact[np.isclose(ks, b, atol=1e-3), j])
                 ["rmse"] for b in bands]  # fmt: skip
            if np.all(np.isnan(y)):
                continue
            style = dict(lw=2.5, color="k") if name == "auto" else dict(lw=1.2, color=f"C{c}")
            ax.plot(bands, y, "o-", label=name, ms=3, **style)
        ax.set_ylim(0, 8)  # GO alone at small kσ is far above (its RMSE is in the table)
        ax.set_title(f"{pol.upper()}: RMSE against NMM3D, 40°")
        ax.set_xlabel("kσ")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("RMSE [dB] (clipped at 8)")
    axes[0].legend(fontsize=7)
    fig.tight_layout()
    tmp = path.with_name(path.stem + ".tmp.png")
    fig.savefig(tmp, dpi=110)
    plt.close(fig)
    tmp.replace(path)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--nmm3d", required=True, help="the NMM3D look-up table (8 columns)")
    ap.add_argument("--peers", default=None, help="interpreter with SMRT 1.7 and/or pyi2em")
    ap.add_argument("--out", default=str(HERE), help="output folder (default: this folder)")
    ap.add_argument("--limit", type=int, default=None, help="first N cases only (a quick look)")
    args = ap.parse_args(argv)
    out = Path(args.out)
    lut = read_lut(args.nmm3d)[: args.limit]
    warnings.simplefilter("ignore")  # out-of-range methods are run on purpose
    lin, weights, t_auto = emscatter_models(lut)
    missing = []
    if args.peers:
        cases = [(2 * math.pi * r[4], r[1] * 2 * math.pi * r[4], r[2], r[3]) for r in lut]
        peers = run_peers(args.peers, cases, theta_deg=float(lut[0, 0]))
        lin.update(peers)
        missing = [f"{p} (does not import in --peers)"
                   for p, key in (("SMRT", "smrt_iiem_fung02"), ("pyi2em", "pyi2em"))
                   if key not in peers]  # fmt: skip
    else:
        missing = ["SMRT, pyi2em (no --peers)"]
    models_db = {}
    for n, v in lin.items():
        d = _db(np.where(np.isnan(v), 1.0, v))
        models_db[n] = np.where(np.isnan(v), np.nan, d)  # NaN: the model has no such column
    cmd = "PYTHONPATH=src python validation/auto/nmm3d_table.py --nmm3d NMM3D_40.dat"
    if args.peers:
        cmd += " --peers PEERS_VENV/bin/python"
    if args.limit:
        cmd += f" --limit {args.limit}"
    if args.out != str(HERE):
        cmd += " --out " + shlex.quote(Path(args.out).name)
    md = tables(lut, models_db, weights, cmd, t_auto, missing)
    write_csv(out / "nmm3d_table.csv", lut, models_db, weights)
    atomic_write(out / "nmm3d_table.md", md)
    plot(out / "nmm3d_table.png", lut, models_db)
    print(md)


if __name__ == "__main__":
    main()
