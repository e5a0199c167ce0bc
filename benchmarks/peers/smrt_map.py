"""The ONE place where SMRT's conventions are mapped to emscatter's (benchmarks only).

SMRT (smrt.interface.*) returns ``diffuse_reflection_matrix`` as σ⁰ / (4π cosθi) (its
"smrt_norm / mu_i", Tsang et al. 2001 vol. III def. 2.1.125), polarizations **V first**
(index 0 = v, 1 = h), indexed [pol_s, pol_i], geometry axes (dphi, mu_s, mu_i) for the bistatic
GO; its ``mean_square_slope`` is the per-direction slope variance ⟨ζx²⟩ (2σ²/ℓ² for a Gaussian
correlation), emscatter's ``Roughness.mean_square_slope()[0]``. Permittivities: both use
Im ε ≥ 0. Shadowing: SMRT's GO uses the height-correlated ``1/(1 + Λi + Λs)`` (emscatter
``shadowing="correlated"``) with the monostatic ``1/(1 + Λ)`` exactly at dphi = π, and clips
cosθ at 0.1 (θ > 84.3° is computed at 84.3°): compare below that.
"""

from __future__ import annotations

import math

import numpy as np

C_SPEED = 299_792_458.0  # SMRT's globalconstants.C_SPEED [m/s]


def smrt_mean_square_slope(rough) -> float:
    """SMRT's ``mean_square_slope`` for an emscatter roughness (per-direction ⟨ζx²⟩)."""
    return float(rough.mean_square_slope()[0])


def to_sigma0(smrt_matrix, mu_i) -> np.ndarray:
    """SMRT's diffuse reflection (npol, npol, ...) or backscatter (npol, ...) → emscatter σ⁰
    [pol_s, pol_i] with h = 0, v = 1 (backscatter: (2, ...) hh, vv)."""
    m = np.asarray(smrt_matrix.values if hasattr(smrt_matrix, "values") else smrt_matrix)
    scale = 4.0 * math.pi * np.asarray(mu_i)
    if m.ndim >= 2 and m.shape[:2] == (2, 2) and m.ndim > 2:
        return m[::-1, ::-1] * scale  # V-first → h-first on both axes
    return m[::-1] * scale  # backscatter (npol, n): [v, h] → [h, v]
