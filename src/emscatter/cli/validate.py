"""``emscatter validate``: method-of-moments validity maps of the approximations."""

from __future__ import annotations

from .args import OutputFolder, add_command


def register(subparsers) -> None:
    v = add_command(
        subparsers, "validate", help="method-of-moments validity maps (small grid; --full)"
    )
    v.add_argument("--out", type=OutputFolder(), default="out/validation", help="output folder")
    v.add_argument("--full", action="store_true", help="the published grid (≈ 17 min, 2 cores)")
    v.add_argument(
        "--quiet",
        action="store_true",
        help="no progress bar (drawn on stderr only when it is a terminal and the work runs past "
        "2 s anyway)",
    )
    v.set_defaults(func=run)


def run(a) -> int:
    from pathlib import Path

    from ..validity_maps import run_validation

    written = run_validation(Path(a.out), full=a.full, progress=False if a.quiet else None)
    for p in written:
        print(f"  {p}")
    return 0
