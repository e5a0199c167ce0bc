"""Run every benchmark in turn (``make bench``); each writes its own JSON in results/.

    .venv/bin/python benchmarks/run_all.py            # all
    .venv/bin/python benchmarks/run_all.py spm go     # a subset by name

Run on a quiet machine: the numbers in results/ are wall-clock medians, and the 2-core CI
machine is noisy when anything else runs. See README.md here for the last results.
"""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
BENCHES = {
    "generate": ["bench_generate.py", "--reps", "7"],
    "measure": ["bench_measure.py"],
    "spm": ["bench_spm.py"],
    "kirchhoff": ["bench_kirchhoff.py", "--repeat", "5"],
    "emissivity": ["bench_emissivity.py"],
    "mom": ["bench_mom.py"],
}


def main(names: list[str]) -> int:
    unknown = [n for n in names if n not in BENCHES]
    if unknown:
        print(f"unknown benchmark(s) {unknown}; choose from {sorted(BENCHES)}", file=sys.stderr)
        return 2
    failed = []
    for name in names or list(BENCHES):
        script, *args = BENCHES[name]
        print(f"\n=== {name}: {script} {' '.join(args)}", flush=True)
        t0 = time.perf_counter()
        rc = subprocess.call([sys.executable, str(HERE / script), *args])
        print(f"=== {name}: exit {rc} in {time.perf_counter() - t0:.1f} s", flush=True)
        if rc:
            failed.append(name)
    if failed:
        print(f"failed: {failed}", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
