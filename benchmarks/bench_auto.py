"""``method="auto"`` backscatter, all four polarizations: time per case before and after the
blend and the closed-form branches' cross-pol (issue 20), in one run.

Cases: issue 20's grid — exponential correlation, θi = 40°, kσ 0.13–1.32 (6, log-spaced),
kℓ 0.5–20 (9), ε ∈ {3, 10 + 1i, 30 + 3i}: 162 cases. "before" is today's path without
the blend: the method ``auto`` ranks first, called explicitly (no cross-pol added, hv = 0 on
the spm and po branches); "after" is ``method="auto"``. Each case: one warm call each, then the
median of ``--repeat`` calls (ranking cached, as for a curve or a repeated scene); ``cold`` is
the first call of a fresh roughness (the blend's switch search included).

    PYTHONPATH=src python benchmarks/bench_auto.py [--repeat 5]
"""

from __future__ import annotations

import argparse
import math
import statistics
import time
import warnings

import numpy as np

import emscatter as em
from emscatter import method_resolution as dispatch

K = 2 * math.pi


def _time(fn, repeat):
    fn()
    out = []
    for _ in range(repeat):
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
                t_after = _time(lambda r=rough, e=eps, kw=kw: em.backscatter(r, e, **kw),
                                args.repeat)  # fmt: skip
                rows.append((hard, after.method, t_before, t_after, cold, after.sigma0[0, 1]))
    tb = np.array([r[2] for r in rows])
    ta = np.array([r[3] for r in rows])
    tc = np.array([r[4] for r in rows])
    print(f"{len(rows)} cases; mean time per case [ms]: before {1e3 * tb.mean():.3f}, "
          f"after {1e3 * ta.mean():.3f} (×{ta.mean() / tb.mean():.2f}), "
          f"after cold {1e3 * tc.mean():.3f}")  # fmt: skip
    for m in sorted({r[0] for r in rows}):
        sel = np.array([r[0] == m for r in rows])
        print(
            f"  picked {m:4s} ({sel.sum():3d} cases): before {1e3 * tb[sel].mean():.3f} ms, "
            f"after {1e3 * ta[sel].mean():.3f} ms (×{ta[sel].mean() / tb[sel].mean():.2f})"
        )
    blended = sum("+" in r[1] for r in rows)
    zero = sum(not r[5] > 0 for r in rows)
    print(f"  blended cases: {blended}; hv = 0 after: {zero} of {len(rows)}")


if __name__ == "__main__":
    main()
