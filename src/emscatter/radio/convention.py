"""The one place where the time convention flips between emscatter and Sionna RT.

emscatter uses ``exp(−iωt)``: a lossy medium has ``Im ε ≥ 0`` (``ε = ε′ + iσ/(ωε₀)``) and
complex amplitudes carry phases ``e^{+ikr}``. Sionna RT (like ITU-R P.2040 and most radio
texts) uses ``exp(+jωt)``: ``η = ε′ − jσ/(ωε₀)`` and ``e^{−jkr}``. The same physical field is
the complex conjugate in the other convention, so permittivities *and* reflection or
transmission amplitudes are conjugated at this boundary — never anywhere else.

:func:`to_sionna` is that flip for amplitudes; for permittivities it is
:func:`emscatter.materials.to_engineering` (which also checks the sign of ``Im ε``), used by
:func:`sionna_permittivity`. The test suite checks the flip against Sionna's own Fresnel and
ITU slab coefficients.
"""

from __future__ import annotations

import numpy as np

__all__ = ["to_sionna", "from_sionna", "sionna_permittivity", "sionna_eps_conductivity"]


def to_sionna(amplitude):
    """emscatter amplitude (``exp(−iωt)``) → Sionna RT's ``exp(+jωt)``: the complex conjugate."""
    return np.conj(np.asarray(amplitude, dtype=complex))


def from_sionna(amplitude):
    """Sionna RT amplitude (``exp(+jωt)``) → emscatter's ``exp(−iωt)``: the complex conjugate."""
    return np.conj(np.asarray(amplitude, dtype=complex))


def sionna_permittivity(eps):
    """emscatter ``ε`` (``Im ε ≥ 0``) → Sionna's complex relative permittivity ``η``
    (``Im η ≤ 0``); raises :class:`~emscatter.ConventionError` for ``Im ε < 0``."""
    from ..materials import to_engineering

    return to_engineering(eps)


def sionna_eps_conductivity(eps, frequency: float) -> tuple[float, float]:
    """``(ε′ [-], σ [S/m])`` that Sionna's ``RadioMaterial(relative_permittivity=ε′,
    conductivity=σ)`` needs to represent emscatter's ``eps`` at ``frequency`` [Hz]."""
    from ..materials import conductivity_from_eps

    er, sig = conductivity_from_eps(eps, frequency)
    return float(np.asarray(er)), float(np.asarray(sig))
