"""Rough surfaces: random realizations (:mod:`.generate`) and their measurement (:mod:`.measure`).

``generate_surface(roughness, shape, spacing, rng=seed)`` draws an exact realization
(circulant embedding, Davies–Harte, Stein 2002) or a periodic FFT one (``periodic=True``);
:mod:`.measure` works on any height array, including ones made elsewhere; :mod:`.heightmap`
reads measured maps (files through SurfaceTopography, or arrays) and :mod:`.measured` turns
one into a roughness the solvers take (SPM, GO with the measured slope density).
"""

from .generate import Surface, generate_batch, generate_surface
from .heightmap import HeightMap, HeightMapError, height_map, read_height_map, write_height_map
from .measure import (
    ShortRecordWarning,
    autocorrelation,
    box_counting_dimension,
    correlation_length,
    hurst_exponent,
    psd,
    rms_height,
    rms_slope,
    summarize,
)
from .measured import BandWarning, MeasuredRoughness, measured_roughness

__all__ = [
    "Surface",
    "generate_surface",
    "generate_batch",
    "rms_height",
    "rms_slope",
    "autocorrelation",
    "correlation_length",
    "psd",
    "hurst_exponent",
    "box_counting_dimension",
    "summarize",
    "ShortRecordWarning",
    "HeightMap",
    "HeightMapError",
    "height_map",
    "read_height_map",
    "write_height_map",
    "MeasuredRoughness",
    "measured_roughness",
    "BandWarning",
]
