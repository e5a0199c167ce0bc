"""The 1-D form of the IEM against the exact 1-D method of moments, at cells where the
literature puts the IEM's strength (kσ ≈ 0.3–1, moderate kℓ; Chen & Fung 1995 and Wu & Chen
2004 compared IEM with moment-method solutions there). Few realizations so it stays fast; the
full maps are validation/validity_maps (and validation/iem/mom_cells.py for these cells with
more realizations).

Criterion: σ⁰ averaged over 30°-wide windows of the scattering angle (θi = 20°, in the plane),
windows within 15 dB of the MoM's brightest and away from the specular direction (where the
MoM's incoherent part is the difference of two large numbers), agree within 1 dB plus the
window's Monte Carlo standard error.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from emscatter.solvers.iem import model as iem
from emscatter.solvers.mom import model as mom
from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation
from emscatter.validity_maps import _points_per_wavelength

K = 2 * math.pi
SIGNED = np.arange(-75.0, 75.5, 1.0)
WINDOWS = [(-75, -45), (-45, -15), (-15, 15), (35, 65)]  # skips the specular 20° ± 15°


def _window(s, lo, hi):
    sel = (SIGNED >= lo) & (SIGNED <= hi)
    return np.trapezoid(s[..., sel], SIGNED[sel], axis=-1) / (hi - lo)


@pytest.mark.slow
@pytest.mark.parametrize(
    ("cls", "ks", "kl", "eps", "realizations", "seed", "range_db"),
    [
        (GaussianCorrelation, 0.6, 6.0, "pec", 24, 11, 15.0),
        (ExponentialCorrelation, 0.3, 3.0, "pec", 24, 12, 15.0),
        (GaussianCorrelation, 1.0, 12.0, 3.0, 8, 13, 10.0),
    ],
    ids=["gaussian-pec", "exponential-pec", "gaussian-eps3"],
)
def test_iem_within_one_db_of_the_method_of_moments(cls, ks, kl, eps, realizations, seed,
                                                      range_db):  # fmt: skip
    rough = cls(ks / K, kl / K, dimension=1)
    ti = math.radians(20.0)
    ts, ps = np.radians(np.abs(SIGNED)), np.where(SIGNED >= 0, 0.0, math.pi)
    ppw = _points_per_wavelength(ks, kl)
    if cls is ExponentialCorrelation:
        ppw = max(ppw, 20.0)  # rough down to the grid scale
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # MoM resolution notes
        ref = mom.bistatic(rough, eps, K, ti, ts, ps, realizations=realizations, seed=seed,
                           length=30.0, points_per_wavelength=ppw, progress=False)  # fmt: skip
    model = iem.bistatic(rough, eps, K, ti, ts, ps, coherent=False).sigma0
    checked = 0
    for p in (0, 1):
        means = [_window(ref.sigma0[p, p], lo, hi) for lo, hi in WINDOWS]
        top = max(means)
        for (lo, hi), m in zip(WINDOWS, means, strict=True):
            if 10 * math.log10(top / m) > range_db:
                continue
            se = _window(ref.info["standard_error"][p, p], lo, hi)
            d = 10 * math.log10(_window(model[p, p], lo, hi) / m)
            assert abs(d) < 1.0 + 10 * math.log10(1 + se / m), (p, lo, hi, d)
            checked += 1
    assert checked >= 4
