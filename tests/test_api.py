"""Public API: dispatch, auto selection, emissivity, and every bad input with a clear error."""

import math
import warnings

import numpy as np
import pytest

import emscatter as em
from emscatter.conventions import ConventionError
from emscatter.solvers.select import ValidityError, ValidityWarning

ROUGH = em.GaussianCorrelation(sigma=0.01, length=0.5)  # kσ ≈ 0.063, kℓ ≈ 3.1 at λ = 1 m
TH = np.radians(np.linspace(0, 89.9, 7))


def test_auto_picks_spm_for_slightly_rough_and_records_it():
    res = em.bistatic(ROUGH, 17 + 2j, wavelength=1.0, theta_i=0.5, theta_s=TH, phi_s=0.0)
    assert res.method == "spm"
    assert res.sigma0.shape == (2, 2, TH.size)
    assert res.info["validity"]["valid"]


def test_auto_picks_a_kirchhoff_method_for_large_gentle_roughness():
    rough = em.GaussianCorrelation(sigma=0.5, length=5.0)  # kσ ≈ 3.1, kℓ ≈ 31, slope 0.2
    res = em.bistatic(rough, 17 + 2j, wavelength=1.0, theta_i=0.5, theta_s=TH, phi_s=0.0)
    assert res.method in ("go", "po")


def test_backscatter_is_bistatic_in_the_backward_direction():
    b = em.backscatter(ROUGH, 5 + 1j, wavelength=1.0, theta_i=TH)
    s = em.bistatic(ROUGH, 5 + 1j, wavelength=1.0, theta_i=TH, theta_s=TH, phi_s=math.pi)
    np.testing.assert_allclose(b.sigma0, s.sigma0, rtol=1e-12)


def test_frequency_and_wavelength_agree():
    a = em.bistatic(
        ROUGH, 4.0, frequency=em.constants.SPEED_OF_LIGHT, theta_i=0.3, theta_s=0.2, phi_s=1.0
    )
    b = em.bistatic(ROUGH, 4.0, wavelength=1.0, theta_i=0.3, theta_s=0.2, phi_s=1.0)
    np.testing.assert_allclose(a.sigma0, b.sigma0, rtol=1e-12)


def test_emissivity_bounds_and_flat_limit():
    e = em.emissivity(ROUGH, 17 + 2j, wavelength=1.0, theta_i=TH[:-1])
    assert np.all((e.emissivity >= 0) & (e.emissivity <= 1))
    assert np.all(e.error < 1e-4)
    flat = em.emissivity(
        em.GaussianCorrelation(1e-7, 0.5), 17 + 2j, wavelength=1.0, theta_i=TH[:-1]
    )
    np.testing.assert_allclose(
        flat.emissivity, 1 - em.fresnel.reflectivity(17 + 2j, TH[:-1]), atol=1e-8
    )


def test_out_of_range_policies():
    rough = em.GaussianCorrelation(sigma=0.3, length=0.5)  # kσ ≈ 1.9: outside SPM
    kw = dict(wavelength=1.0, theta_i=0.3, theta_s=0.3, phi_s=0.0, method="spm")
    with pytest.warns(ValidityWarning, match="spm"):
        em.bistatic(rough, 4.0, **kw)
    with pytest.raises(ValidityError, match="spm"):
        em.bistatic(rough, 4.0, out_of_range="raise", **kw)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        res = em.bistatic(rough, 4.0, out_of_range="nan", **kw)
    assert np.all(np.isnan(res.sigma0)) and res.info["out_of_range"]


BAD = [
    (dict(theta_i=-0.1), ValueError, "theta_i must be in"),
    (dict(theta_i=math.nan), ValueError, "theta_i must be finite"),
    (dict(theta_s=math.radians(91)), ValueError, "theta_s must be in"),
    (dict(theta_s=np.array([0.1, math.nan])), ValueError, "theta_s must be finite"),
    (dict(phi_s=math.inf), ValueError, "phi_s must be finite"),
    (dict(eps=17 - 2j), ConventionError, "numpy.conj"),
    (dict(eps="metallic"), ValueError, "unknown material 'metallic': use 'pec'"),
    (dict(wavelength=None), ValueError, "exactly one of frequency"),
    (dict(frequency=1e9), ValueError, "exactly one of frequency"),
    (dict(wavelength=-1.0), ValueError, "wavelength must be > 0"),
    (dict(method="ipm"), ValueError, "method must be one of"),
    (dict(out_of_range="ignore-it"), ValueError, "out_of_range must be one of"),
    (dict(theta_i=np.zeros(3), theta_s=np.zeros(4)), ValueError, "do not broadcast"),
    (dict(surface=em.FractionalBrownian(0.5)), TypeError, "roughness description"),
    (dict(surface="gaussian"), TypeError, "roughness description"),
]


@pytest.mark.parametrize("override, exc, match", BAD, ids=[b[2][:30] for b in BAD])
def test_bad_inputs_are_named(override, exc, match):
    kw = dict(surface=ROUGH, eps=4.0, wavelength=1.0, theta_i=0.2, theta_s=0.3, phi_s=0.0)
    kw.update(override)
    surface, eps = kw.pop("surface"), kw.pop("eps")
    with pytest.raises(exc, match=match):
        em.bistatic(surface, eps, **kw)


def test_unknown_polarization_pair():
    res = em.bistatic(ROUGH, 4.0, wavelength=1.0, theta_i=0.2, theta_s=0.3, phi_s=0.0)
    with pytest.raises(ValueError, match="pol must be one of"):
        res.pol("hx")


def test_emissivity_bad_tol():
    with pytest.raises(ValueError, match="tol must be"):
        em.emissivity(ROUGH, 4.0, wavelength=1.0, theta_i=0.2, tol=0)


def test_fallback_ranks_methods_by_how_far_their_limits_are_exceeded():
    from emscatter.solvers.select import select_method

    k = 2 * math.pi
    # kσ = 3, kℓ = 5.8: no method is valid. SPM is 10× past its kσ limit (17 dB off against
    # the method of moments, validation/validity_maps), geometric optics just short of kσ = √10
    # and kℓ = 6 (1.8 dB off): the fallback must be a Kirchhoff method, not SPM.
    name, reports = select_method(em.GaussianCorrelation(3 / k, 5.8 / k), k)
    assert not any(r["valid"] for r in reports.values())
    assert name in ("go", "po")
    assert reports["spm"]["excess"] > reports[name]["excess"] > 0
    # a valid report has no excess
    name, reports = select_method(em.GaussianCorrelation(0.05 / k, 2 / k), k)
    assert name == "spm" and reports["spm"]["excess"] == 0
