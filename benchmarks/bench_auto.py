"""``method="auto"`` backscatter, all four polarizations: time per case before and after the
blend and the closed-form branches' cross-pol (issue 20), in one run.

Cases: issue 20's grid — exponential correlation, θi = 40°, kσ 0.13–1.32 (6, log-spaced),
kℓ 0.5–20 (9), ε ∈ {3, 10 + 1i, 30 + 3i}: 162 cases. "before" is the path without the blend:
the method ``auto`` ranks first, called explicitly (no cross-pol added, hv = 0 on the spm and
po branches); "after" is ``method="auto"``. Per case, medians of ``--repeat`` calls:

* ``after`` — a repeated call (ranking, blend and the cross-pol values remembered, as for a
  repeated scene);
* ``after_hv`` — the cross-pol recomputed each call: every memory of
  :mod:`emscatter.solvers.auto_crosspol` cleared (``clear_cache()``: the hv values and the
  resummed term's σ-independent node parts), the ranking and blend remembered — what an
  entirely new (ε, θ) costs, the honest per-case figure;
* ``after_hv_sigma`` — the hv values cleared, the node parts kept
  (``clear_cache(nodes=False)``): what a new σ at a known (ε, θ, ℓ) costs (the node rule
  and the kernel products do not depend on σ: ``iem.crosspol_resummed._PREP``);
* ``cold`` — the first call of a fresh roughness (the blend's switch search and everything),
  one call.

    PYTHONPATH=src python benchmarks/bench_auto.py [--repeat 5]

writes ``benchmarks/results/auto.json`` and ``auto.md``.
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import RESULTS, command, machine, write  # noqa: E402

import emscatter as em  # noqa: E402
from emscatter import method_resolution as dispatch  # noqa: E402
from emscatter.io import atomic_path  # noqa: E402
from emscatter.solvers import auto_crosspol  # noqa: E402

K = 2 * math.pi


def _time(fn, repeat, before=None):
    fn()
    out = []
    for _ in range(repeat):
        if before is not None:
            before()
        t0 = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t0)
    return statistics.median(out)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore")
    ti = math.radians(40)
    rows = []
    for ks in np.geomspace(0.13, 1.32, 6):
        for kl in np.geomspace(0.5, 20, 9):
            for eps in (3.0, 10 + 1j, 30 + 3j):
                rough = em.ExponentialCorrelation(ks / K, kl / K)
                kw = dict(wavelength=1.0, theta_i=ti, out_of_range="ignore")
                t0 = time.perf_counter()
                after = em.backscatter(rough, eps, **kw)
                cold = time.perf_counter() - t0
                hard = dispatch.rank_methods(rough, K, eps=eps)[0][0]
                t_before = _time(lambda r=rough, e=eps, m=hard, kw=kw:
                                 em.backscatter(r, e, method=m, **kw), args.repeat)  # fmt: skip
                auto = lambda r=rough, e=eps, kw=kw: em.backscatter(r, e, **kw)  # noqa: E731
                t_after = _time(auto, args.repeat)
                t_hv = _time(auto, args.repeat, before=auto_crosspol.clear_cache)
                t_sig = _time(auto, args.repeat,
                              before=lambda: auto_crosspol.clear_cache(nodes=False))  # fmt: skip
                rows.append({"k_sigma": float(ks), "k_l": float(kl), "eps": str(eps),
                             "picked": hard, "method": after.method, "before_s": t_before,
                             "after_s": t_after, "after_hv_s": t_hv, "after_hv_sigma_s": t_sig,
                             "cold_s": cold,
                             "hv": float(after.sigma0[0, 1])})  # fmt: skip
    names = ("before_s", "after_s", "after_hv_s", "after_hv_sigma_s", "cold_s")
    col = {n: np.array([r[n] for r in rows]) for n in names}
    mean = {n: 1e3 * float(v.mean()) for n, v in col.items()}
    by = {}
    for m in sorted({r["picked"] for r in rows}):
        sel = np.array([r["picked"] == m for r in rows])
        by[m] = {"cases": int(sel.sum()), **{n: 1e3 * float(v[sel].mean()) for n, v in col.items()}}
    blended = sum("+" in r["method"] for r in rows)
    zero = sum(not r["hv"] > 0 for r in rows)
    lines = [
        f"{len(rows)} cases; mean time per case [ms]: before {mean['before_s']:.3f}, after "
        f"{mean['after_s']:.3f} (×{mean['after_s'] / mean['before_s']:.2f}), after with hv "
        f"recomputed {mean['after_hv_s']:.3f} (×{mean['after_hv_s'] / mean['before_s']:.2f}; "
        f"every hv memory cleared), new σ at a known (ε, θ, ℓ) {mean['after_hv_sigma_s']:.3f} "
        f"(×{mean['after_hv_sigma_s'] / mean['before_s']:.2f}), cold {mean['cold_s']:.3f}",
    ]
    for m, b in by.items():
        lines.append(
            f"  picked {m:4s} ({b['cases']:3d} cases): before {b['before_s']:.3f} ms, after "
            f"{b['after_s']:.3f} ms (×{b['after_s'] / b['before_s']:.2f}), hv recomputed "
            f"{b['after_hv_s']:.3f} ms (×{b['after_hv_s'] / b['before_s']:.2f}), new σ "
            f"{b['after_hv_sigma_s']:.3f} ms (×{b['after_hv_sigma_s'] / b['before_s']:.2f}), cold "
            f"{b['cold_s']:.3f} ms"
        )
    lines.append(f"  blended cases: {blended}; hv = 0 after: {zero} of {len(rows)}")
    print("\n".join(lines))
    cmd = command()
    write("auto", {"machine": machine(), "command": cmd, "repeat": args.repeat,
                   "mean_ms": mean, "by_branch_ms": by, "blended": blended, "hv_zero": zero,
                   "rows": rows})  # fmt: skip
    md = ["# `auto` backscatter with cross-pol: time per case (issue 20)", "",
          f"Command: `{cmd}` (medians of {args.repeat}; machine in auto.json)", "", "```",
          *lines, "```", ""]  # fmt: skip
    with atomic_path(RESULTS / "auto.md") as tmp:
        Path(tmp).write_text("\n".join(md))


if __name__ == "__main__":
    main()
