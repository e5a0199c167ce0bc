"""The measured-error table auto reads (emscatter.solvers.measured) and its use in rank_methods."""

from __future__ import annotations

import math

import numpy as np
import pytest

from emscatter.solvers import measured, select
from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation, PowerLawCorrelation
from emscatter.validation.tapered import tapered_from

K = 2 * math.pi


@pytest.mark.parametrize(
    ("eps", "expected"),
    [("pec", "conductor"), (3.0, "dielectric"), (17 + 2j, "dielectric"), (-20 + 1j, "conductor"),
     (200.0, "conductor"), (None, None), (np.array([3.0, 5.0]), None)],
)  # fmt: skip
def test_medium_class(eps, expected):
    assert measured.medium_class(eps) == expected


def test_lookup_nearest_cell_of_the_matching_map():
    got = measured.measured_errors(GaussianCorrelation(0.4 / K, 0.9 / K, dimension=1), K, "pec")
    assert got["map"] == "pec" and got["cell"] == (0.3873, 0.9247)
    assert set(got["errors"]) == {"spm", "go", "po", "iem"}
    exp = measured.measured_errors(ExponentialCorrelation(0.1 / K, 10 / K), K, 17 + 2j)
    assert exp["map"] == "exp_eps3+0j" and exp["cell"] == (0.0989, 10.8148)


@pytest.mark.parametrize(
    "rough",
    [
        GaussianCorrelation(10 / K, 10 / K),  # kσ beyond the box
        GaussianCorrelation(0.1 / K, 100 / K),  # kℓ beyond the box
        GaussianCorrelation(0.1 / K, 5 / K, 10 / K),  # anisotropic
        PowerLawCorrelation(0.1 / K, 5 / K),  # not mapped
        tapered_from(0.1 / K, 5 / K, 2.5 * K),  # a subclass with another spectrum
    ],
)
def test_lookup_outside_the_maps_is_none(rough):
    assert measured.measured_errors(rough, K, "pec") is None


def test_rank_methods_takes_the_measured_choice_where_the_criteria_miss():
    # Gaussian PEC, kσ = 0.39, kℓ = 0.92: no method is valid; the criteria rank the IEM first
    # (smallest excess) but the map measures it 1.6 dB off and SPM1 within 1 dB.
    rough = GaussianCorrelation(0.3873 / K, 0.9247 / K, dimension=1)
    ranked = select.rank_methods(rough, K, eps="pec", theta_i=math.radians(20))
    name, rep = ranked[0]
    assert name == "spm" and rep["picked_by"] == "measured" and not rep["valid"]
    assert rep["measured_error_dB"] <= 1.0
    assert dict(ranked)["iem"]["measured_error_dB"] > 1.0
    # without a medium the table does not apply: the criteria decide
    assert select.rank_methods(rough, K, theta_i=math.radians(20))[0][0] == "iem"


def test_measured_choice_respects_angle_checks():
    # At 89° SPM fails its scattered-fraction check on a conductor: never picked by the table.
    rough = GaussianCorrelation(0.3873 / K, 0.9247 / K, dimension=1)
    name, rep = select.rank_methods(rough, K, eps="pec", theta_i=math.radians(89))[0]
    assert name != "spm"


def test_valid_and_measured_within_tolerance_keeps_the_criteria():
    rough = GaussianCorrelation(0.05 / K, 5.848 / K, dimension=1)
    name, rep = select.rank_methods(rough, K, eps="pec", theta_i=math.radians(20))[0]
    assert name == "spm" and rep["valid"] and rep["picked_by"] == "criteria"


def test_a_limit_between_the_roughness_and_the_cell_centre_keeps_its_say():
    # kσ = 0.29 (SPM valid, kσ ≤ 0.3) is nearest to the cell kσ = 0.39, kℓ = 3.2 of the ε = 3
    # map, where SPM is invalid and measured 1.06 dB off: the criteria's choice stands.
    rough = GaussianCorrelation(0.29 / K, 3.67 / K)
    name, rep = select.rank_methods(rough, K, eps=5.3 + 0.2j, theta_i=math.radians(30))[0]
    assert name == "spm" and rep["valid"]
    assert "picked_by" not in rep
