"""``emscatter surface``: generate a surface, draw it and its spectrum, measure it.

Options that do not apply to ``--kind`` are errors (``--hurst`` for gaussian/exponential,
``--length`` for fbm); output paths are checked before the surface is generated."""

from __future__ import annotations

from .args import Integer, Number, add_command, reject_unless
from .curves import FIGURE_SUFFIXES
from .paths import OutputPath, check_distinct


def register(subparsers) -> None:
    s = add_command(
        subparsers, "surface", help="generate a surface, draw it and its spectrum, measure it"
    )
    s.add_argument(
        "--kind",
        default="fbm",
        choices=["fbm", "gaussian", "exponential", "power-law"],
        help="surface model",
    )
    s.add_argument(
        "--hurst",
        type=Number(low=0, high=1),
        default=0.7,
        help="Hurst exponent (fbm and power-law)",
    )
    s.add_argument(
        "--size", type=Integer(low=8, high=16384), default=512, help="grid points per side"
    )
    s.add_argument(
        "--spacing", type=Number(low=0, unit="m"), default=1.0, metavar="M", help="grid spacing [m]"
    )
    s.add_argument(
        "--sigma",
        type=Number(low=0, unit="m"),
        default=1.0,
        metavar="M",
        help="rms height [m] (fbm: rms increment at one spacing)",
    )
    s.add_argument(
        "--length",
        type=Number(low=0, unit="m"),
        default=16.0,
        metavar="M",
        help="correlation length [m]",
    )
    s.add_argument("--seed", type=Integer(low=0), default=0, help="random seed")
    s.add_argument("--periodic", action="store_true", help="periodic FFT synthesis")
    s.add_argument("--profile", action="store_true", help="1-D profile")
    s.add_argument("--png", type=OutputPath(suffixes=FIGURE_SUFFIXES), help="figure file")
    s.add_argument("--json", type=OutputPath(suffixes=(".json",)), help="statistics as JSON")
    s.set_defaults(func=run)


def run(a) -> int:
    from ..demo import surface_report

    reject_unless(
        a, a.kind in ("fbm", "power-law"), ("--hurst",), "to --kind fbm or power-law only"
    )
    reject_unless(a, a.kind != "fbm", ("--length",), "to stationary kinds only (not --kind fbm)")
    check_distinct({"--png": a.png, "--json": a.json})
    stats = surface_report(
        kind=a.kind,
        hurst=a.hurst,
        size=a.size,
        spacing=a.spacing,
        sigma=a.sigma,
        length=a.length,
        seed=a.seed,
        periodic=a.periodic,
        png=a.png,
        json_path=a.json,
        profile=a.profile,
    )
    for k, v in stats.items():
        print(f"{k:>28}: {v:.6g}" if isinstance(v, float) else f"{k:>28}: {v}")
    return 0
