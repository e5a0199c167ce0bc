"""Measure the statistics of a height map or profile: any array, made here or elsewhere.

Every function takes ``heights`` — a profile ``(n,)`` or a height map ``(ny, nx)`` [m], at
least 8 samples per axis, finite — and ``spacing`` [m]: a float (same on both axes) or
``(dy, dx)`` for a map, in the array's axis order.

=========================== ===================================================================
function                    what it measures
=========================== ===================================================================
:func:`rms_height`          Rq / Sq, mean removed (seed eqs. 2.1–2.2)
:func:`rms_slope`           Rdq / Sdq per direction and total (seed eqs. 2.6–2.7)
:func:`autocorrelation`     normalized ACF by FFT (unbiased: divided by the overlap count)
:func:`correlation_length`  ℓ fitted to a Gaussian / exponential model, or the 1/e lag
:func:`psd`                 periodogram (1-D) or radially averaged PSD (2-D), ``σ² w`` normalization
:func:`hurst_exponent`      H by windowed log-periodogram (default), variogram or madogram
:func:`box_counting_dimension` D by differential box counting (Chen et al. 1993, seed ch. 5)
:func:`summarize`           all of the above in one dict (used by the CLI and ``Surface.measure``)
=========================== ===================================================================

Conventions follow :mod:`emscatter.spectra`: the PSD is two-sided and normalized so that
``∫ psd d^dK = σ²`` (``psd = σ² w``); slopes are per direction ``(⟨h_x²⟩^½, ⟨h_y²⟩^½)`` and
total ``(⟨h_x²⟩ + ⟨h_y²⟩)^½`` (Beckmann's m). The fractal dimension of a self-affine
profile is ``D = 2 − H`` and of a surface ``D = 3 − H`` (seed eq. 5.12).
"""

from __future__ import annotations

import warnings

from emscatter.surfaces.fractal import (
    BoxCountResult,
    HurstResult,
    box_counting_dimension,
    hurst_exponent,
)
from emscatter.surfaces.statistics import (
    HURST_METHODS,
    Autocorrelation,
    CorrelationLength,
    PowerSpectrum,
    RmsSlope,
    ShortRecordWarning,
    _prepare,
    autocorrelation,
    correlation_length,
    psd,
    rms_height,
    rms_slope,
)

__all__ = [
    "ShortRecordWarning",
    "RmsSlope",
    "Autocorrelation",
    "CorrelationLength",
    "PowerSpectrum",
    "HurstResult",
    "BoxCountResult",
    "rms_height",
    "rms_slope",
    "autocorrelation",
    "correlation_length",
    "psd",
    "hurst_exponent",
    "box_counting_dimension",
    "summarize",
    "HURST_METHODS",
]


# --------------------------------------------------------------------------- summary
def summarize(heights, spacing, *, hurst: bool = False, model: str = "gaussian") -> dict:
    """All statistics in one flat dict (values are floats or None).

    Keys: ``rms_height`` [m]; ``rms_slope_x``, ``rms_slope_y``, ``rms_slope`` (difference)
    and ``rms_slope_spectral`` [-]; ``correlation_length``, ``correlation_length_x``,
    ``correlation_length_y`` [m] (``model`` fit; None when the ACF does not decay; for a
    non-stationary record such as fBm a fitted value reflects the record length, not the
    surface), ``warnings`` (messages, e.g. a short record).
    With ``hurst=True``: ``hurst_<method>`` and ``hurst_<method>_stderr`` for every method,
    ``fractal_dimension_<method>`` = d + 1 − H, and ``box_counting_dimension`` (+ stderr).
    """
    h, d = _prepare(heights, spacing)
    out: dict = {"shape": tuple(h.shape), "spacing": d, "rms_height": rms_height(h)}
    sd = rms_slope(h, d, "difference")
    out.update(rms_slope_x=sd.x, rms_slope_y=sd.y, rms_slope=sd.total)
    out["rms_slope_spectral"] = rms_slope(h, d, "spectral").total
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", ShortRecordWarning)
            cl = correlation_length(h, d, model)
        out.update(
            correlation_length=cl.length,
            correlation_length_x=cl.length_x,
            correlation_length_y=cl.length_y,
            correlation_model=cl.model,
            record_correlation_lengths=cl.record_lengths,
        )
        out["warnings"] = [str(w.message) for w in caught]
    except ValueError as exc:
        out.update(correlation_length=None, correlation_length_x=None, correlation_length_y=None)
        out["warnings"] = [str(exc)]
    if hurst:
        for m in HURST_METHODS:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always", RuntimeWarning)
                r = hurst_exponent(h, d, m)
            out["warnings"] += [str(w.message) for w in caught]
            out[f"hurst_{m}"] = r.hurst
            out[f"hurst_{m}_stderr"] = r.stderr
            out[f"fractal_dimension_{m}"] = r.fractal_dimension
        b = box_counting_dimension(h, d)
        out["box_counting_dimension"] = b.dimension
        out["box_counting_dimension_stderr"] = b.stderr
    return out
