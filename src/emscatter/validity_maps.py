"""Compatibility module: the validity maps now live in :mod:`emscatter.validation`
(``emscatter validate`` calls :func:`run_validation` from here)."""

from __future__ import annotations

from .validation import reselect, run_validation
from .validation.emissivity_table import EMISSIVITY_CASES, emissivity_table, mom_emissivity
from .validation.map_files import CSV_HEADER, markdown_table, plot_map, read_map, write_map
from .validation.maps import (
    EXP_DIELECTRIC,
    EXP_PEC,
    FULL,
    FULL_DIELECTRIC,
    PUBLISHED,
    SMALL,
    TINY,
    MapConfig,
    _bin_means,
    _points_per_wavelength,
    _sigma0_error,
    auto_choice,
    compute_map,
    evaluate_cell,
    map_methods,
    mom_reference,
    references,
    rough_of,
    selector_failures,
    sigma0_methods,
    surface_of,
    tag_of,
)

__all__ = [
    "CSV_HEADER",
    "EMISSIVITY_CASES",
    "EXP_DIELECTRIC",
    "EXP_PEC",
    "FULL",
    "FULL_DIELECTRIC",
    "PUBLISHED",
    "SMALL",
    "TINY",
    "MapConfig",
    "_bin_means",
    "_points_per_wavelength",
    "_sigma0_error",
    "auto_choice",
    "compute_map",
    "emissivity_table",
    "evaluate_cell",
    "map_methods",
    "markdown_table",
    "mom_emissivity",
    "mom_reference",
    "plot_map",
    "read_map",
    "references",
    "reselect",
    "rough_of",
    "run_validation",
    "selector_failures",
    "sigma0_methods",
    "surface_of",
    "tag_of",
    "write_map",
]
