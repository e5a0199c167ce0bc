"""Command-line options shared by the scripts in ``examples/render/`` (each has a quick mode
that the tests run: tiny images, few samples, coarse tables)."""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path

__all__ = ["ExampleSettings", "example_settings"]


@dataclass(frozen=True)
class ExampleSettings:
    out: Path  # the PNG to write
    quick: bool
    width: int  # image width [px]
    spp: int  # samples per pixel
    n_theta: int  # table θ nodes (Δφ nodes: 2 n_theta)
    n_wavelengths: int  # table wavelengths over the visible range

    @property
    def resolution(self) -> tuple[int, int]:
        return (self.n_theta, 2 * self.n_theta)


def example_settings(description: str, default_out: Path, argv=None) -> ExampleSettings:
    """Parse ``--quick``, ``--out``, ``--width``, ``--spp`` for an example script."""
    p = argparse.ArgumentParser(description=description)
    p.add_argument("--quick", action="store_true", help="tiny render and coarse tables (tests)")
    p.add_argument("--out", type=Path, default=None, help=f"PNG (default {default_out})")
    p.add_argument("--width", type=int, default=None, help="image width [px]")
    p.add_argument("--spp", type=int, default=None, help="samples per pixel")
    a = p.parse_args(argv)
    for name in ("width", "spp"):
        v = getattr(a, name)
        if v is not None and v < 1:
            p.error(f"--{name} must be a positive integer, got {v}")
    if a.out is not None and a.out.suffix.lower() != ".png":
        p.error(f"--out must name a .png file, got {a.out}")
    quick = bool(a.quick)
    return ExampleSettings(
        out=a.out or Path(default_out),
        quick=quick,
        width=a.width or (160 if quick else 900),
        spp=a.spp or (8 if quick else 256),
        n_theta=16 if quick else 90,
        n_wavelengths=4 if quick else 16,
    )
