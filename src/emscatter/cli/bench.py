"""``emscatter bench``: run the benchmarks (the same as ``make bench``)."""

from __future__ import annotations

from .args import add_command


def register(subparsers) -> None:
    p = add_command(
        subparsers,
        "bench",
        help="run the benchmarks into benchmarks/results/ (needs a source checkout)",
    )
    p.add_argument("names", nargs="*", help="a subset (default: all; see --list)")
    p.add_argument("--quick", action="store_true", help="smaller sizes and fewer repeats")
    p.add_argument("--list", action="store_true", help="list the benchmarks and exit")
    p.set_defaults(func=run)


def _run_all_path():
    from pathlib import Path

    root = Path(__file__).resolve().parents[3]  # src/emscatter/cli/bench.py -> checkout
    path = root / "benchmarks" / "run_all.py"
    if not path.exists():
        raise OSError(
            "the benchmarks live in the source tree (benchmarks/run_all.py), not in the "
            f"installed package: run 'emscatter bench' from a checkout (looked in {root})"
        )
    return path


def run(a) -> int:
    import subprocess
    import sys

    path = _run_all_path()
    cmd = [sys.executable, str(path), *a.names] + ["--quick"] * a.quick + ["--list"] * a.list
    return subprocess.call(cmd)
