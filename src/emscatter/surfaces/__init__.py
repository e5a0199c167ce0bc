"""Rough surfaces: random realizations (:mod:`.generate`) and their measurement (:mod:`.measure`).

``generate_surface(roughness, shape, spacing, rng=seed)`` draws an exact realization
(circulant embedding, Davies–Harte, Stein 2002) or a periodic FFT one (``periodic=True``);
:mod:`.measure` works on any height array, including ones made elsewhere.
"""

from .generate import Surface, generate_batch, generate_surface
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
]
