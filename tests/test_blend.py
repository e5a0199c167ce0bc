"""auto's blend weights (emscatter.solvers.blend): continuous by construction, pure away from
every limit, the hard ranking's rule in the limit, and the interpolated measured errors."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from emscatter.solvers import blend, measured, select
from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation, PowerLawCorrelation

K = 2 * math.pi
CLASSES = {"gaussian": GaussianCorrelation, "exponential": ExponentialCorrelation}


def _weights(rough, eps, monostatic=False):
    w = blend.blend_weights(rough, K, eps=eps, monostatic=monostatic)["weights"]
    return np.array([w.get(n, 0.0) for n in ("spm", "go", "po", "iem")])


@settings(max_examples=60, deadline=None)
@given(
    kind=st.sampled_from(sorted(CLASSES)),
    log_ks=st.floats(math.log10(0.02), math.log10(30.0)),
    log_kl=st.floats(math.log10(0.3), math.log10(300.0)),
    eps=st.sampled_from([None, "pec", 3.0, 17 + 2j]),
    axis=st.sampled_from([0, 1]),
    monostatic=st.booleans(),
)
def test_weights_are_continuous_everywhere(kind, log_ks, log_kl, eps, axis, monostatic):
    """A relative step of 1e-7 in kσ or kℓ moves no weight by more than 1e-5 (the smoothsteps'
    slope is at most 1.5/δ per unit log, the interpolation's bounded by the map's steps):
    the limits' corners, the measured maps' cells and their edges included."""
    ks, kl = 10.0**log_ks, 10.0**log_kl
    sides = []
    for f in (1 - 1e-7, 1 + 1e-7):
        s, l_ = (ks * f, kl) if axis == 0 else (ks, kl * f)
        sides.append(_weights(CLASSES[kind](s / K, l_ / K), eps, monostatic))
    assert np.all(sides[0] >= 0) and math.isclose(sides[0].sum(), 1.0, rel_tol=1e-12)
    np.testing.assert_allclose(sides[0], sides[1], atol=1e-5)


@pytest.mark.parametrize(
    ("ks", "kl", "eps"),
    [
        (0.3, 30.0, None),  # SPM's kσ limit, far from every other limit; no map (no medium)
        (0.3, 30.0, 3.0),  # the same beyond the maps' kℓ = 20 (+ half a step)
        (0.3, 400.0, "pec"),
    ],
)
def test_half_and_half_on_a_limit_pure_a_blend_factor_away(ks, kl, eps):
    at = blend.blend_weights(GaussianCorrelation(ks / K, kl / K), K, eps=eps)
    assert at["weights"] == pytest.approx({"spm": 0.5, "po": 0.5}, abs=1e-9)
    for f, name in ((1 / blend.BLEND_FACTOR, "spm"), (blend.BLEND_FACTOR, "po")):
        pure = blend.blend_weights(GaussianCorrelation(ks * f / K, kl / K), K, eps=eps)
        assert pure["weights"] == {name: 1.0}


@pytest.mark.parametrize(
    "rough",
    [
        GaussianCorrelation(0.05 / K, 2 / K),  # SPM deep inside
        GaussianCorrelation(5.0 / K, 30 / K),  # GO deep inside
        PowerLawCorrelation(0.05 / K, 5 / K, hurst=0.8),  # no map for power laws
        ExponentialCorrelation(0.02 / K, 50 / K),
    ],
)
@pytest.mark.parametrize("eps", [None, "pec", 17 + 2j])
def test_away_from_every_transition_the_blend_is_the_hard_choice(rough, eps):
    w = blend.blend_weights(rough, K, eps=eps)
    hard = select.rank_methods(rough, K, eps=eps)[0][0]
    if len(w["weights"]) == 1:
        assert w["weights"] == {hard: 1.0} and w["pick"] == hard
    else:  # near a measured tolerance: the hard choice is one of the blend's
        assert hard in w["weights"]


def test_measured_choice_at_a_cell_centre_is_the_hard_rule():
    """Gaussian PEC, kσ = 0.39, kℓ = 0.92 (a map cell): no method valid, the criteria rank the
    IEM first (measured 1.6 dB off), SPM measured within 1 dB: both rules give SPM alone."""
    rough = GaussianCorrelation(0.3873 / K, 0.9247 / K, dimension=1)
    assert select.rank_methods(rough, K, eps="pec")[0][0] == "spm"
    assert blend.blend_weights(rough, K, eps="pec")["weights"] == {"spm": 1.0}


def test_interpolated_errors_equal_the_cells_at_their_centres_and_fade_outside():
    table = measured.load_table()["maps"][0]
    fam = {"gaussian": GaussianCorrelation, "exponential": ExponentialCorrelation}
    cls = fam[table["correlation"]]
    eps = "pec" if table["medium"] == "conductor" else 3.0
    for i, ks in enumerate(table["k_sigma"]):
        for j, kl in enumerate(table["k_l"]):
            got = measured.interpolated_errors(cls(ks / K, kl / K), K, eps)
            for name, cells in table["errors"].items():
                if cells[i][j] is None:
                    assert got["availability"][name] == 0.0
                else:
                    assert got["errors"][name] == pytest.approx(cells[i][j], abs=1e-12)
                    assert got["availability"][name] == pytest.approx(1.0)
    # half a step beyond the last kℓ the maps stop, as the nearest-cell lookup does
    lg = np.log(table["k_l"])
    beyond = math.exp(lg[-1] + 0.5 * float(np.min(np.diff(lg))) * 1.01)
    assert measured.interpolated_errors(cls(0.1 / K, beyond / K), K, eps) is None
    assert measured.measured_errors(cls(0.1 / K, beyond / K), K, eps) is None
    midway = math.exp(lg[-1] + 0.25 * float(np.min(np.diff(lg))))
    got = measured.interpolated_errors(cls(table["k_sigma"][1] / K, midway / K), K, eps)
    assert got["availability"]["po"] == pytest.approx(0.5)


# ----------------------------------------------------------------- backscatter of a dielectric
@pytest.mark.parametrize(
    ("eps", "monostatic", "order"),
    [
        (15 + 3.5j, True, ("spm", "go", "iem", "po")),
        (np.array([3.0, 15 + 3.5j]), True, ("spm", "go", "iem", "po")),
        (15 + 3.5j, False, ("spm", "go", "po", "iem")),  # bistatic: BRDF, emissivity
        ("pec", True, ("spm", "go", "po", "iem")),  # R_h = −R_v at every angle
        (-20 + 5j, True, ("spm", "go", "po", "iem")),  # a metal (Re ε < 0)
        (300 + 100j, True, ("spm", "go", "po", "iem")),  # |ε| ≥ 100: the maps' conductor
        (np.array([3.0, -20 + 5j]), True, ("spm", "go", "po", "iem")),  # not all dielectric
        (None, True, ("spm", "go", "po", "iem")),
    ],
)
def test_backscatter_of_a_dielectric_puts_the_iem_before_po(eps, monostatic, order):
    assert blend.auto_order(eps, monostatic=monostatic) == order


#: NMM3D 40° table (Tsang's group, exact 3-D solutions; exponential, ℓ/σ = 15, ε = 15 + 3.5i,
#: σ/λ = 0.084, kσ = 0.528): σhh − σvv = −2.85 dB. PO, valid there, gives hh = vv exactly.
NMM3D_CASE = (ExponentialCorrelation(0.5278 / K, 15 * 0.5278 / K), 15 + 3.5j, -2.85)


def test_a_dielectric_in_backscatter_gets_the_iem_where_po_also_holds():
    """Where PO and the IEM both hold, a dielectric's backscatter takes the IEM (PO's
    stationary-phase hh = vv, blend module docstring); bistatic geometries keep PO (cheapest
    valid first), and a conductor's order is not changed."""
    rough, eps, _ = NMM3D_CASE
    reports = select.validity(rough, K, ("po", "iem"), eps=eps)
    assert reports["po"]["valid"] and reports["iem"]["valid"]
    assert blend.blend_weights(rough, K, eps=eps, monostatic=True)["weights"] == {"iem": 1.0}
    assert blend.blend_weights(rough, K, eps=eps)["weights"] == {"po": 1.0}
    for conductor in ("pec", -20 + 5j):  # the order is AUTO_ORDER's: the same weights
        mono = blend.blend_weights(rough, K, eps=conductor, monostatic=True)["weights"]
        assert mono == blend.blend_weights(rough, K, eps=conductor)["weights"]


def test_auto_backscatter_hh_below_vv_where_po_would_give_hh_equal_vv():
    """The case above through the API: HH − VV within 1 dB of NMM3D's −2.85 dB (PO: 0 dB),
    while a bistatic geometry off backscatter keeps PO's answer."""
    import emscatter as em

    rough, eps, exact = NMM3D_CASE
    ti = math.radians(40)
    res = em.backscatter(rough, eps, wavelength=1.0, theta_i=ti, out_of_range="ignore")
    assert res.method == "iem"
    ratio = 10 * math.log10(float(res.pol("hh")) / float(res.pol("vv")))
    assert ratio < -1.0 and abs(ratio - exact) < 1.0, ratio
    po = em.backscatter(rough, eps, wavelength=1.0, theta_i=ti, method="po")
    assert float(po.pol("hh")) == pytest.approx(float(po.pol("vv")), rel=1e-9)
    bis = em.bistatic(rough, eps, wavelength=1.0, theta_i=ti, theta_s=ti, phi_s=0.0,
                      out_of_range="ignore")  # fmt: skip
    assert bis.method == "po"


@settings(max_examples=40, deadline=None)
@given(
    kind=st.sampled_from(sorted(CLASSES)),
    log_ks=st.floats(math.log10(0.02), math.log10(30.0)),
    log_kl=st.floats(math.log10(0.3), math.log10(300.0)),
    eps=st.sampled_from([None, "pec", 3.0, 17 + 2j]),
    monostatic=st.booleans(),
)
def test_methods_after_a_fully_valid_one_are_not_checked_and_change_nothing(
    kind, log_ks, log_kl, eps, monostatic
):
    """The blend stops checking after the first method valid a factor BLEND_FACTOR inside its
    limits: the weights are those of the blend with every method checked."""
    rough = CLASSES[kind](10.0**log_ks / K, 10.0**log_kl / K)
    fast = blend.blend_weights(rough, K, eps=eps, monostatic=monostatic)
    full_margins = blend.margins
    try:  # the reference: every method checked
        blend.margins = lambda *a, stop_below=None, **kw: full_margins(*a, **kw)
        full = blend.blend_weights(rough, K, eps=eps, monostatic=monostatic)
    finally:
        blend.margins = full_margins
    assert fast["weights"] == pytest.approx(full["weights"], abs=1e-15)
    assert set(fast["margins"]) <= set(full["margins"])
    assert all(fast["margins"][n] == full["margins"][n] for n in fast["margins"])
