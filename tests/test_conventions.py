import math

import numpy as np
import pytest

from emscatter import conventions as cv
from emscatter.constants import SPEED_OF_LIGHT


def test_wavenumber_from_frequency_or_wavelength():
    assert cv.wavenumber(frequency=SPEED_OF_LIGHT) == pytest.approx(2 * math.pi)
    assert cv.wavenumber(wavelength=0.5) == pytest.approx(4 * math.pi)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({}, "exactly one of frequency"),
        ({"frequency": 1e9, "wavelength": 0.3}, "exactly one of frequency"),
        ({"frequency": -1.0}, "frequency must be > 0"),
        ({"wavelength": 0.0}, "wavelength must be > 0"),
        ({"wavelength": float("nan")}, "wavelength must be finite"),
    ],
)
def test_wavenumber_errors(kwargs, match):
    with pytest.raises(ValueError, match=match):
        cv.wavenumber(**kwargs)


def test_negative_imaginary_permittivity_names_convention_and_fix():
    with pytest.raises(cv.ConventionError, match=r"exp\(-i omega t\).*numpy.conj"):
        cv.check_permittivity(17 - 2j)
    assert cv.check_permittivity(17 + 2j) == 17 + 2j


@pytest.mark.parametrize("bad", [-0.1, math.nan, math.inf, math.pi / 2 + 1e-6])
def test_check_angle_rejects(bad):
    with pytest.raises(ValueError, match="theta_i"):
        cv.check_angle("theta_i", bad)


def test_polarization_names():
    assert cv.check_polarization("TE") == "h"
    assert cv.check_polarization("tm") == "v"
    assert cv.check_pol_pair("hv") == (0, 1)
    with pytest.raises(ValueError, match="pol"):
        cv.check_pol_pair("xy")


def test_broadcast_error_names_arrays():
    with pytest.raises(ValueError, match=r"theta_i\(3,\).*theta_s\(4,\)"):
        cv.broadcast_angles(theta_i=np.zeros(3), theta_s=np.zeros(4))
