"""``emscatter demo``: the main job on built-in defaults (figures + numbers in a folder)."""

from __future__ import annotations

from .args import OutputFolder, add_command


def register(subparsers) -> None:
    d = add_command(
        subparsers, "demo", help="the main job on built-in defaults (figures + numbers in out/)"
    )
    d.add_argument("--out", type=OutputFolder(), default="out", help="output folder")
    d.add_argument("--quick", action="store_true", help="smaller grids (for tests)")
    d.set_defaults(func=run)


def run(a) -> int:
    from pathlib import Path

    from ..demo import run_demo

    written = run_demo(Path(a.out), quick=a.quick)
    print("wrote:")
    for p in written:
        print(f"  {p}")
    return 0
