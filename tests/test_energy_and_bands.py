"""Energy as a checked law at run time, per-angle validity policy, frequency bands, materials,
the lazy coherent part and cached validity reports (issues 8, 10, 11 — API side)."""

import math
import warnings

import numpy as np
import pytest

import emscatter as em
from emscatter import materials
from emscatter import method_resolution as dispatch
from emscatter.emissivity import energy_balance
from emscatter.solvers.select import ValidityError, ValidityWarning

K = 2 * math.pi  # λ = 1 m
GRAZING = np.radians([0.0, 30.0, 60.0, 80.0, 85.0, 88.0, 89.0])
# issue 11: SPM, PEC, kσ = 0.2, kℓ = 1 — emissivity −2.2 at 89° (incoherent reflectivity 3.2)
SPM_PEC = em.GaussianCorrelation(0.2 / K, 1.0 / K)
# issue 11: GO, σ = 0.6, ℓ = 4, λ = 1, ε = 17+2i — outside GO's angle range at grazing (its
# e_h = −0.268 at 85° was the Kirchhoff coherent term added on top of GO's σ⁰, fixed in issue 21;
# tests/test_go_emissivity_grazing.py)
GO_CASE = em.GaussianCorrelation(0.6, 4.0)


def test_energy_balance_flags_exactly_the_broken_angles():
    r_coh = np.array([[0.5, 0.2, 0.0], [0.5, 0.2, 0.0]])
    r_inc = np.array([[0.4, 0.9, 0.0], [0.4, 0.7, -0.1]])
    err = np.full((2, 3), 1e-3)
    bal = energy_balance(r_coh, r_inc, err, np.radians([10.0, 80.0, 85.0]))
    assert bal["ok"].tolist() == [True, False, False]
    assert bal["ok_pol"].tolist() == [[True, False, True], [True, True, False]]
    text = " ".join(bal["reasons"])
    assert "e_h = -0.1 at θi = 80°" in text and "r_coh + r_incoh = 1.1" in text
    # within the quadrature error is not a violation
    assert energy_balance([[0.5], [0.5]], [[0.5005], [0.4]], [[1e-3], [1e-3]], [0.1])["ok"][0]
    assert not energy_balance([[np.nan], [0.5]], [[0.1], [0.1]], [[1e-3], [1e-3]], [0.1])["ok"][0]


def test_no_emissivity_outside_0_1_without_a_flag_and_a_warning():
    with pytest.warns(ValidityWarning) as rec:
        e = em.emissivity(SPM_PEC, "pec", wavelength=1.0, theta_i=GRAZING, method="spm")
    broken = (e.emissivity < -e.error - 1e-9).any(axis=0)
    assert broken[-1] and e.emissivity[1, -1] < -2  # the issue's −2.2
    assert np.all(~e.energy_ok[broken]) and np.all(~e.info["validity"]["angle_valid"][broken])
    msg = " ".join(str(w.message) for w in rec)
    assert "89°" in msg and "energy not conserved" in msg and "e_v = " in msg
    assert "rad" not in msg.split("energy")[1]  # degrees, not radians
    assert not e.info["validity"]["valid"]


def test_out_of_range_nan_blanks_only_the_failing_angles():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        e = em.emissivity(
            GO_CASE, 17 + 2j, wavelength=1.0, theta_i=GRAZING, method="go", out_of_range="nan"
        )
    bad = ~e.info["validity"]["angle_valid"]
    assert bad[-1] and not bad[0]
    assert np.all(np.isnan(e.emissivity[:, bad])) and np.all(np.isfinite(e.emissivity[:, ~bad]))
    np.testing.assert_array_equal(e.info["out_of_range"], bad)


def test_out_of_range_raise_names_angles_in_degrees():
    with pytest.raises(ValidityError, match=r"θi = .*89°"):
        em.emissivity(
            GO_CASE, 17 + 2j, wavelength=1.0, theta_i=GRAZING, method="go", out_of_range="raise"
        )


def test_ignore_records_without_warning():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        e = em.emissivity(
            SPM_PEC, "pec", wavelength=1.0, theta_i=GRAZING, method="spm", out_of_range="ignore"
        )
    assert not e.energy_ok.all() and e.info["energy"]["reasons"]
    assert not e.info["validity"]["angle_valid"].all()  # recorded, not warned


def test_auto_replaces_the_method_only_where_it_fails_and_stays_continuous():
    # kσ = 1.9, kℓ = 38, slope 0.1: GO is valid for the roughness but its stationary phase fails
    # from θi ≈ 34° ((2kσ cosθi)² < 10): e_h 0.240 at 80° against PO's 0.153; PO holds there.
    rough = em.GaussianCorrelation(0.3, 6.0)
    th = np.radians(np.arange(0.0, 90.0, 10.0))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        e = em.emissivity(rough, 17 + 2j, wavelength=1.0, theta_i=th)
    methods = list(e.info["methods"])
    assert methods[:4] == ["go"] * 4 and methods[4:] == ["po"] * 5 and e.method == "go+po"
    assert e.energy_ok.all() and np.all((e.emissivity >= 0) & (e.emissivity <= 1))
    go = em.emissivity(
        rough, 17 + 2j, wavelength=1.0, theta_i=th, method="go", out_of_range="ignore"
    )
    po = em.emissivity(
        rough, 17 + 2j, wavelength=1.0, theta_i=th, method="po", out_of_range="ignore"
    )
    # what auto avoided: GO outside its angle range, off PO by > 0.05 at 80°
    assert not go.info["validity"]["angle_valid"][4:].any() and go.h[-1] - po.h[-1] > 0.05
    np.testing.assert_allclose(e.emissivity[:, 4:], po.emissivity[:, 4:], atol=1e-12)
    np.testing.assert_allclose(e.emissivity[:, :4], go.emissivity[:, :4], atol=1e-12)
    # at the switch the two methods agree within their quadrature errors and 1e-3
    assert np.max(np.abs(go.emissivity[:, 3:5] - po.emissivity[:, 3:5])) < 2e-2


def test_auto_never_trades_for_a_method_further_outside_its_validity():
    # kℓ = 1: GO and PO are far outside their roughness validity; SPM stays (flagged at grazing)
    with pytest.warns(ValidityWarning, match="spm"):
        e = em.emissivity(SPM_PEC, "pec", wavelength=1.0, theta_i=GRAZING)
    assert set(e.info["methods"]) == {"spm"}


def test_band_equals_separate_calls_and_runs_the_solver_once_per_frequency(monkeypatch):
    from emscatter.solvers.spm import model as spm

    rough = em.GaussianCorrelation(0.004, 0.05)
    f = np.array([1e9, 2e9, 1e9, 3e9])  # 1 GHz twice: 3 distinct frequencies
    th = np.radians([10.0, 30.0, 50.0])
    concrete = materials.itu("concrete")
    calls = []
    real = spm.bistatic

    def spy(*a, **kw):  # the API's σ⁰ calls (the validity check makes its own, elsewhere)
        if np.all(np.asarray(a[4]) == 0.2):
            calls.append(a[2])
        return real(*a, **kw)

    monkeypatch.setattr(spm, "bistatic", spy)
    band = em.bistatic(
        rough, concrete, frequency=f[:, None], theta_i=th, theta_s=0.2, phi_s=0.0, method="spm"
    )
    assert len(calls) == 3 and band.k.shape == (4, 3)
    # the spy hides spm's `coherent` option, so each frequency's coherent part came with σ⁰:
    # the band keeps it (no lazy wrapper around values already computed)
    assert band.coherent_computed
    for j, fj in enumerate(f):
        one = em.bistatic(
            rough,
            concrete.eps(frequency=fj),
            frequency=fj,
            theta_i=th,
            theta_s=0.2,
            phi_s=0.0,
            method="spm",
        )
        np.testing.assert_allclose(band.sigma0[:, :, j], one.sigma0, rtol=1e-13)
        np.testing.assert_allclose(band.coherent[:, j], one.coherent, rtol=1e-13)
        np.testing.assert_allclose(band.k[j], one.k, rtol=1e-15)
    assert np.ndim(one.k) == 0  # scalar k stays scalar
    e_band = em.emissivity(rough, "pec", frequency=f[:2], theta_i=0.3, method="spm")
    for j in range(2):
        e1 = em.emissivity(rough, "pec", frequency=f[j], theta_i=0.3, method="spm")
        np.testing.assert_allclose(e_band.emissivity[:, j], e1.emissivity, atol=1e-15)


def test_a_duck_typed_material_and_a_material_name_work():
    class Linear:  # anything with .eps(frequency=...)
        name = "linear"

        def eps(self, frequency=None, wavelength=None):
            return 3.0 + 1e-10j * np.asarray(frequency)

    rough = em.GaussianCorrelation(0.004, 0.05)
    f = np.array([1e9, 2e9])
    a = em.backscatter(rough, Linear(), frequency=f, theta_i=0.3, method="spm")
    b = em.backscatter(rough, 3.0 + 0.2j, frequency=2e9, theta_i=0.3, method="spm")
    np.testing.assert_allclose(a.sigma0[..., 1], b.sigma0, rtol=1e-13)
    gold = em.emissivity(rough, "Au", wavelength=550e-9, theta_i=0.2)
    direct = em.emissivity(
        rough, materials.metal("Au").eps(wavelength=550e-9), wavelength=550e-9, theta_i=0.2
    )
    np.testing.assert_allclose(gold.emissivity, direct.emissivity, rtol=1e-13)
    with pytest.raises(materials.OutOfBandError):
        em.emissivity(rough, "Au", frequency=1e9, theta_i=0.2)


def test_coherent_part_is_computed_only_when_read(monkeypatch):
    from emscatter.solvers.spm import model as spm

    seen = []
    real = spm._coherent
    monkeypatch.setattr(spm, "_coherent", lambda *a, **kw: seen.append(1) or real(*a, **kw))
    rough = em.GaussianCorrelation(0.01, 0.1)
    th = np.radians(np.linspace(0, 89, 90))
    s = em.backscatter(rough, 17 + 2j, frequency=1e9, theta_i=th, method="spm")
    assert s.vv.shape == (90,) and not seen and not s.coherent_computed
    import pickle

    copy = pickle.loads(pickle.dumps(s))  # a lazy result still pickles (computed on the way)
    assert copy.coherent_computed and seen
    eager = spm.bistatic(rough, 17 + 2j, s.k, th, th, math.pi, 0.0)
    np.testing.assert_allclose(s.coherent, eager.coherent, rtol=1e-14)
    assert s.coherent_computed and s.coherent.shape == (2, 90)
    np.testing.assert_array_equal(copy.coherent, s.coherent)
    np.testing.assert_allclose(s.coherent_pol("TE"), eager.coherent[0], rtol=1e-14)
    np.testing.assert_allclose(s.coherent_pol("v"), eager.coherent[1], rtol=1e-14)


def test_a_caller_may_ask_for_the_coherent_part_eagerly():
    """``coherent=True`` through the API is the solver's option, not a clash with the lazy one."""
    rough = em.GaussianCorrelation(0.01, 0.1)
    th = np.radians([10.0, 40.0, 70.0])
    eager = em.backscatter(rough, 17 + 2j, frequency=1e9, theta_i=th, method="spm", coherent=True)
    lazy = em.backscatter(rough, 17 + 2j, frequency=1e9, theta_i=th, method="spm")
    assert eager.coherent_computed and not lazy.coherent_computed
    np.testing.assert_allclose(eager.coherent, lazy.coherent, rtol=1e-14)
    band = em.backscatter(  # a band takes the option at every frequency
        rough,
        17 + 2j,
        frequency=np.array([0.5e9, 1e9, 1e9]),
        theta_i=0.4,
        method="spm",
        coherent=True,
    )
    assert band.coherent_computed  # eager at every frequency: the band result is eager too
    lazy_band = em.backscatter(rough, 17 + 2j, frequency=np.array([0.5e9, 1e9]), theta_i=0.4,
                               method="spm")  # fmt: skip
    assert not lazy_band.coherent_computed
    one = em.backscatter(rough, 17 + 2j, frequency=1e9, theta_i=0.4, method="spm")
    np.testing.assert_allclose(band.coherent[:, 2], one.coherent, rtol=1e-13)
    np.testing.assert_allclose(lazy_band.coherent[:, 1], one.coherent, rtol=1e-13)


def test_validity_reports_are_cached_per_roughness(monkeypatch):
    dispatch.clear_cache()
    count = []
    real = dispatch._call_check
    monkeypatch.setattr(dispatch, "_call_check", lambda *a: count.append(1) or real(*a))
    rough = em.ExponentialCorrelation(0.002, 0.05)
    for _ in range(5):
        em.backscatter(rough, 5 + 1j, frequency=1e9, theta_i=0.3, method="spm")
    first = len(count)
    for _ in range(5):
        em.backscatter(rough, 5 + 1j, frequency=1e9, theta_i=0.3, method="spm")
    assert 0 < first <= 2 and len(count) == first  # nothing recomputed for the same inputs
    report = dispatch.validity_report("spm", rough, 2 * math.pi * 1e9 / em.constants.SPEED_OF_LIGHT)
    report["valid"] = "mutated"
    again = dispatch.validity_report("spm", rough, 2 * math.pi * 1e9 / em.constants.SPEED_OF_LIGHT)
    assert again["valid"] != "mutated"  # callers get copies


def test_bistatic_angle_policy_blanks_only_invalid_incidence_angles():
    th = np.radians([20.0, 89.0])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        s = em.bistatic(
            SPM_PEC,
            "pec",
            wavelength=1.0,
            theta_i=th,
            theta_s=0.3,
            phi_s=0.0,
            method="spm",
            out_of_range="nan",
        )
    assert np.isfinite(s.sigma0[..., 0]).all() and np.isnan(s.sigma0[..., 1]).all()
    assert np.isnan(s.coherent[:, 1]).all() and np.isfinite(s.coherent[:, 0]).all()


def test_lazy_coherent_follows_an_array_permittivity():
    rough = em.GaussianCorrelation(0.005, 0.05)
    eps = np.array([3 + 0.1j, 10 + 1j, 20 + 2j])
    s = em.bistatic(
        rough,
        eps,
        frequency=1e9,
        theta_i=0.3,
        theta_s=np.array([0.1, 0.2, 0.3]),
        phi_s=0.0,
        method="spm",
    )
    for j, e in enumerate(eps):
        one = em.bistatic(
            rough, e, frequency=1e9, theta_i=0.3, theta_s=0.1, phi_s=0.0, method="spm"
        )
        np.testing.assert_allclose(s.coherent[:, j], one.coherent, rtol=1e-13)


def test_the_warnings_and_errors_a_caller_filters_are_public():
    """The classes the API raises are importable from the package itself (to filter or catch)."""
    rough = em.GaussianCorrelation(0.01, 0.1)
    with pytest.warns(em.PlausibilityWarning, match="did you mean"):
        em.backscatter(rough, 3.0, frequency=5.4, theta_i=0.3, method="go", out_of_range="ignore")
    with pytest.warns(em.ValidityWarning):
        em.backscatter(rough, 3.0, frequency=1e9, theta_i=0.3, method="go")
    with pytest.raises(em.ValidityError):
        em.backscatter(rough, 3.0, frequency=1e9, theta_i=0.3, method="go", out_of_range="raise")
    with pytest.raises(em.OutOfBandError):
        em.emissivity(rough, "Au", frequency=1e9, theta_i=0.2)
    assert em.ValidityWarning is ValidityWarning and em.ValidityError is ValidityError
    assert em.OutOfBandError is materials.OutOfBandError


@pytest.mark.parametrize("method", ["spm", "go", "po", "iem", "auto"])
def test_backscatter_at_one_scalar_angle_equals_the_array_call(method):
    """A plain float θi (0-d) gives the same σ⁰ as a one-element array (GO's closed-form
    backscatter path once raised a TypeError on 0-d input)."""
    rough = em.GaussianCorrelation(0.03, 0.3)
    kw = dict(frequency=3e9, method=method, out_of_range="ignore")
    one = em.backscatter(rough, 5 + 1j, theta_i=0.3, **kw)
    arr = em.backscatter(rough, 5 + 1j, theta_i=np.array([0.3]), **kw)
    assert np.shape(one.vv) == () and np.shape(arr.vv) == (1,)
    np.testing.assert_allclose(one.sigma0[..., None], arr.sigma0, rtol=1e-12)


def test_validity_warnings_of_a_band_point_at_the_callers_line():
    """A ValidityWarning names the user's line (not a library frame) for one frequency and for
    a band, in bistatic, backscatter and emissivity."""
    rough = em.GaussianCorrelation(0.05, 0.1)  # kσ ≈ 1–2 at 1–2 GHz: SPM out of its range
    f = np.array([1e9, 2e9])
    calls = (
        lambda: em.bistatic(rough, 5 + 1j, frequency=1e9, theta_i=0.3, theta_s=0.3, phi_s=0.0,
                            method="spm"),
        lambda: em.bistatic(rough, 5 + 1j, frequency=f, theta_i=0.3, theta_s=0.3, phi_s=0.0,
                            method="spm"),
        lambda: em.backscatter(rough, 5 + 1j, frequency=f, theta_i=0.3, method="spm"),
        lambda: em.emissivity(rough, 5 + 1j, frequency=f, theta_i=0.3, method="spm"),
    )  # fmt: skip
    for call in calls:
        with warnings.catch_warnings(record=True) as rec:
            warnings.simplefilter("always")
            call()
        found = [w for w in rec if issubclass(w.category, ValidityWarning)]
        assert found and all(w.filename == __file__ for w in found), [
            (w.filename, w.lineno) for w in found
        ]
