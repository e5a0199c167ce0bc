"""Run every benchmark (``make bench`` / ``emscatter bench``) and write the summary.

    python benchmarks/run_all.py                    # all, full size
    python benchmarks/run_all.py --quick            # smaller sizes (a sanity run)
    python benchmarks/run_all.py kernels peers      # a subset by name
    python benchmarks/run_all.py --list

Each benchmark runs in its own process (with the source tree first on the path) and writes
``results/<name>.json`` (+ PNG); then ``results/SUMMARY.md`` is rebuilt from all the JSON files
there: every target against its measurement, with the command that reproduces it.
The SMRT / SurfaceTopography / tamaas comparisons run in the peers' environment
(``bash benchmarks/peers/setup.sh``; ``PEERS_PYTHON`` or /tmp/emscatter-peers/bin/python); when
it is missing, those benchmarks say so and are skipped. Timings are medians of repeats; run on
a quiet machine for the numbers to quote (the load average is recorded with each result).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
PEERS_PYTHON = os.environ.get("PEERS_PYTHON", "/tmp/emscatter-peers/bin/python")

#: name -> (script, full args, quick args, needs the peers' environment)
BENCHES = {
    "kernels": ("bench_kernels.py", [], ["--n", "200000", "--repeat", "3"], False),
    "peers": ("bench_peers.py", [], ["--repeat", "3"], True),
    "pareto": ("bench_pareto.py", [], ["--quick", "--repeat", "1"], False),
    "scaling": ("bench_scaling.py", [], ["--quick"], False),
    "demo": ("bench_demo.py", [], ["--quick"], False),
    "generate": ("bench_generate.py", ["--reps", "7"], ["--reps", "2"], True),
    "measure": ("bench_measure.py", [], [], False),
    "spm": ("bench_spm.py", [], [], False),
    "kirchhoff": (
        "bench_kirchhoff.py",
        ["--repeat", "5"],
        ["--n", "200000", "--repeat", "2"],
        False,
    ),
    "emissivity": ("bench_emissivity.py", [], [], False),
    "mom": ("bench_mom.py", [], ["--quick"], False),
    "brdf": ("bench_brdf.py", ["--repeat", "3"], ["--repeat", "1"], False),
    "render": ("bench_render.py", ["--repeat", "7"], ["--repeat", "2", "--width", "128"], False),
    "radio": ("bench_radio.py", [], ["--quick"], False),
    "radio_scenes": ("bench_radio_scenes.py", [], ["--quick"], False),
}


def _python(peers: bool) -> str | None:
    if not peers:
        return sys.executable
    return PEERS_PYTHON if Path(PEERS_PYTHON).exists() else None


def run(names: list[str], quick: bool) -> int:
    env = {
        **os.environ,
        "PYTHONPATH": str(ROOT / "src") + os.pathsep + os.environ.get("PYTHONPATH", ""),
        "MPLBACKEND": "Agg",
    }
    failed, skipped = [], []
    for name in names:
        script, full, small, peers = BENCHES[name]
        py = _python(peers)
        if py is None:
            print(
                f"=== {name}: skipped — the peers' environment is missing "
                f"(bash benchmarks/peers/setup.sh, or set PEERS_PYTHON)",
                flush=True,
            )
            skipped.append(name)
            continue
        args = small if quick else full
        print(f"\n=== {name}: {Path(py).name} benchmarks/{script} {' '.join(args)}", flush=True)
        t0 = time.perf_counter()
        rc = subprocess.call([py, str(HERE / script), *args], env=env, cwd=ROOT)
        print(f"=== {name}: exit {rc} in {time.perf_counter() - t0:.1f} s", flush=True)
        if rc:
            failed.append(name)
    from summary import write_summary

    path = write_summary()
    print(f"\nwrote {path}")
    if skipped:
        print(f"skipped: {skipped}", file=sys.stderr)
    if failed:
        print(f"failed: {failed}", file=sys.stderr)
    return 1 if failed else 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("names", nargs="*", help=f"subset of {', '.join(BENCHES)}")
    ap.add_argument("--quick", action="store_true", help="smaller sizes and fewer repeats")
    ap.add_argument("--list", action="store_true", help="list the benchmarks and exit")
    a = ap.parse_args(argv)
    if a.list:
        for n, (script, *_rest) in BENCHES.items():
            print(f"{n:12s} benchmarks/{script}")
        return 0
    unknown = [n for n in a.names if n not in BENCHES]
    if unknown:
        print(f"unknown benchmark(s) {unknown}; choose from {', '.join(BENCHES)}", file=sys.stderr)
        return 2
    sys.path.insert(0, str(HERE))
    return run(a.names or list(BENCHES), a.quick)


if __name__ == "__main__":
    raise SystemExit(main())
