"""Whole Sionna scenes made rough: :mod:`.roughen` (every object's material replaced by its
emscatter equivalent, one shared material per medium, and back: ``flatten``) and
:mod:`.compare` (rough − flat path gains and radio maps in one call)."""

from .compare import MAP_DEFAULTS, PATH_DEFAULTS, compare_rough_flat, path_gains, write_comparison
from .roughen import (
    DEFAULT_ROUGHNESS,
    DEFAULT_ROUGHNESS_SOURCE,
    Assignment,
    Roughened,
    as_roughness,
    flatten,
    plan,
    roughen,
    roughened,
)

__all__ = [
    "roughen",
    "flatten",
    "roughened",
    "plan",
    "as_roughness",
    "Assignment",
    "Roughened",
    "DEFAULT_ROUGHNESS",
    "DEFAULT_ROUGHNESS_SOURCE",
    "compare_rough_flat",
    "path_gains",
    "write_comparison",
    "PATH_DEFAULTS",
    "MAP_DEFAULTS",
]
