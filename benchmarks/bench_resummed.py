"""The resummed backscatter cross-pol (``solvers/iem/crosspol_resummed.py``, issue 20): CPU time
per incidence angle of the numpy reference and of the compiled kernel, one thread, against the
compiled second-order SPM backscatter hv on the same rule (the kernel's share).

Cases: 40° backscatter; exponential kσ 0.26 (kℓ 1, ε 3 + i), 0.53 (kℓ 8, ε 15 + 3.5i),
1.32 (kℓ 20, ε 30 + 3i) — NMM3D's range — and Gaussian kσ 1.3, kℓ 6, ε 15 + 2i. Rules: 16 nodes
per segment (the function's default) and 10 (``auto_crosspol.RESUMMED_NODES``). Thread CPU time
(``time.thread_time``), median of ``--repeat`` calls (numpy: of 2); the compiled and numpy
values are checked equal (≤ 1e-10 relative).

    PYTHONPATH=src python benchmarks/bench_resummed.py [--repeat 7]

writes ``benchmarks/results/resummed.json`` and ``resummed.md``.
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import RESULTS, command, machine, write  # noqa: E402

import emscatter as em  # noqa: E402
from emscatter.io import atomic_path  # noqa: E402
from emscatter.solvers.iem import crosspol_resummed as cr  # noqa: E402
from emscatter.solvers.iem.kernels import crosspol_resummed as kern  # noqa: E402
from emscatter.solvers.spm.kernel_crosspol import backscatter_hv as spm2  # noqa: E402

K = 2 * math.pi
CASES = [
    ("exponential kσ 0.26 kℓ 1 ε 3+1i", em.ExponentialCorrelation(0.26 / K, 1 / K), 3 + 1j),
    ("exponential kσ 0.53 kℓ 8 ε 15+3.5i", em.ExponentialCorrelation(0.53 / K, 8 / K), 15 + 3.5j),
    ("exponential kσ 1.32 kℓ 20 ε 30+3i", em.ExponentialCorrelation(1.32 / K, 20 / K), 30 + 3j),
    ("gaussian kσ 1.3 kℓ 6 ε 15+2i", em.GaussianCorrelation(1.3 / K, 6 / K), 15 + 2j),
]


def _cpu_ms(fn, repeat):
    fn()
    out = []
    for _ in range(repeat):
        t = time.thread_time()
        fn()
        out.append(time.thread_time() - t)
    return 1e3 * statistics.median(out)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args(argv)
    th = np.array([math.radians(40.0)])
    rows = []
    for name, r, e in CASES:
        code = kern.GAUSSIAN if isinstance(r, em.GaussianCorrelation) else kern.EXPONENTIAL
        geo = (th, e, K, r.sigma, r.length, r.length_y, 0.0, code)
        row = {"case": name}
        ref = cr._numpy(r, e, K, th, 0.0, 16)[0, 0]
        got = kern.backscatter_resummed(*geo, 16, threads=1)[0][0]
        if not abs(got - ref) <= 1e-10 * abs(ref):
            raise SystemExit(f"{name}: compiled {got!r} != numpy {ref!r}")
        row["numpy_16_ms"] = _cpu_ms(lambda r=r, e=e: cr._numpy(r, e, K, th, 0.0, 16), 2)
        for n in (16, 10):
            row[f"compiled_{n}_ms"] = _cpu_ms(
                lambda n=n, geo=geo: kern.backscatter_resummed(*geo, n, threads=1), args.repeat
            )
            row[f"spm2_compiled_{n}_ms"] = _cpu_ms(
                lambda n=n, geo=geo: spm2(*geo, n, n, threads=1), args.repeat
            )
        rows.append(row)
    head = ["case", "numpy_16_ms", "compiled_16_ms", "compiled_10_ms", "spm2_compiled_16_ms",
            "spm2_compiled_10_ms"]  # fmt: skip
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for row in rows:
        lines.append("| " + " | ".join([row["case"]] + [f"{row[h]:.3g}" for h in head[1:]]) + " |")
    print("\n".join(lines))
    cmd = command()
    write("resummed", {"machine": machine(), "command": cmd, "repeat": args.repeat, "rows": rows})
    md = ["# Resummed backscatter cross-pol: CPU ms per angle, one thread (issue 20)", "",
          f"Command: `{cmd}` (medians; machine in resummed.json)", "", *lines, ""]  # fmt: skip
    with atomic_path(RESULTS / "resummed.md") as tmp:
        Path(tmp).write_text("\n".join(md))


if __name__ == "__main__":
    main()
