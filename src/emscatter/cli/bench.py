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
    p.add_argument(
        "--quiet",
        action="store_true",
        help="no progress bars in the benchmark processes (EMSCATTER_PROGRESS=0 in their "
        "environment; bars are drawn only on a terminal anyway)",
    )
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


def _bench_names(path) -> list[str]:
    """The benchmark names of ``run_all.py`` (its ``BENCHES``), read without running it."""
    import ast

    tree = ast.parse(path.read_text())
    for node in tree.body:
        target = getattr(node, "target", None) or (getattr(node, "targets", None) or [None])[0]
        if getattr(target, "id", None) == "BENCHES" and isinstance(node.value, ast.Dict):
            return [k.value for k in node.value.keys if isinstance(k, ast.Constant)]
    return []


def run(a) -> int:
    import os
    import subprocess
    import sys

    from .args import reject_unless

    path = _run_all_path()
    reject_unless(a, not a.list, ("--quick",), "to a run, not to --list")
    if a.list and a.names:
        raise ValueError(f"--list takes no benchmark names, got {' '.join(a.names)}")
    known = _bench_names(path)
    unknown = [n for n in a.names if n not in known]
    if known and unknown:
        raise ValueError(f"unknown benchmark(s) {unknown}; choose from {', '.join(known)}")
    cmd = [sys.executable, str(path), *a.names] + ["--quick"] * a.quick + ["--list"] * a.list
    env = {**os.environ, "EMSCATTER_PROGRESS": "0"} if a.quiet else None
    return subprocess.call(cmd, env=env)
