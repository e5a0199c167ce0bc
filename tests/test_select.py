"""The method ranking behind method="auto" (BOARD interface 2) and the option mapping."""

from __future__ import annotations

import math

import numpy as np
import pytest

from emscatter.solvers import AUTO_ORDER, select
from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation, PowerLawCorrelation

K = 2 * math.pi


def test_rank_methods_valid_first_then_by_excess():
    ranked = select.rank_methods(GaussianCorrelation(0.05 / K, 2 / K), K)
    assert [n for n, _ in ranked][0] == "spm" and ranked[0][1]["valid"]
    assert sorted(n for n, _ in ranked) == sorted(AUTO_ORDER)
    invalid = [r["excess"] for _, r in ranked if not r["valid"]]
    assert invalid == sorted(invalid)
    name, reports = select.select_method(GaussianCorrelation(0.05 / K, 2 / K), K)
    assert name == "spm" and set(reports) == set(AUTO_ORDER)


@pytest.mark.parametrize("cls", [ExponentialCorrelation, PowerLawCorrelation])
def test_auto_leaves_spm_for_rough_algebraic_spectra(cls):
    """Issue 7: GO/PO reported an infinite excess for exponential/power-law roughness without
    a cutoff, so auto never left SPM (8–36 dB off at kσ = 3). With the slope of the spectrum
    the wave sees (|K| ≤ 2k) the Kirchhoff methods are ranked on their real excess."""
    rough = cls(3.0 / K, 20.0 / K)
    ranked = select.rank_methods(rough, K)
    assert ranked[0][0] in ("po", "go", "iem")
    assert all(math.isfinite(r["excess"]) for _, r in ranked)


def test_rank_methods_angles_prefer_the_method_valid_there():
    # SPM on a PEC at kσ = 0.2, kℓ = 1 is valid at 30° but not near grazing (TM)
    rough = GaussianCorrelation(0.2 / K, 1.0 / K)
    at30 = select.rank_methods(rough, K, eps="pec", theta_i=math.radians(30))
    assert at30[0][0] == "spm" and at30[0][1]["valid"]
    curve = select.rank_methods(rough, K, eps="pec", theta_i=np.radians([30.0, 88.0]))
    spm = dict(curve)["spm"]
    assert spm["angle_valid"].tolist() == [True, False] and not spm["valid"]
    for _, rep in curve:
        assert rep["angle_valid"].shape == (2,)


def test_unsupported_method_is_ranked_last(monkeypatch):
    from emscatter.solvers.spm import model as spm

    def broken(*a, **kw):
        raise ValueError("cannot take this roughness")

    monkeypatch.setattr(spm, "check_validity", broken)
    select._takes.cache_clear()
    ranked = select.rank_methods(GaussianCorrelation(0.05 / K, 2 / K), K)
    assert ranked[-1][0] == "spm" and ranked[-1][1]["unsupported"]
    with pytest.raises(ValueError, match="no solver supports"):
        select.rank_methods(GaussianCorrelation(0.05 / K, 2 / K), K, methods=("spm",))
    select._takes.cache_clear()


def test_check_options_maps_or_rejects():
    assert select.check_options("go", {"shadowing": False}, picked_by_auto=True) == {
        "shadowing": False
    }
    # knobs a closed-form method satisfies anyway are dropped when auto picked it
    assert select.check_options("spm", {"threads": 2, "rtol": 1e-6}, picked_by_auto=True) == {}
    assert select.check_options("po", {"shadowing": False}, picked_by_auto=True) == {}
    with pytest.raises(ValueError, match=r"shadowing=True.*method='auto' picked 'po'"):
        select.check_options("po", {"shadowing": True}, picked_by_auto=True)
    with pytest.raises(
        ValueError, match=r"slope_variance.*picked 'spm'.*\['coherent', 'k_max', 'order'\]"
    ):
        select.check_options("spm", {"slope_variance": 0.1}, picked_by_auto=True)
    with pytest.raises(ValueError, match="method 'spm', which takes"):
        select.check_options("spm", {"threads": 2}, picked_by_auto=False)
    assert "points_per_wavelength" in select.solver_options("mom")
