"""Sharp lobes in the Mitsuba plugin (issue 21), run for real in Mitsuba's LLVM variants.

* the plugin evaluates a table on its *own* axes, uniform or not (adaptive ``tol=`` grids, user
  axes): ``eval`` equals :meth:`BrdfTable.evaluate` to float32 precision — nothing resampled;
* GO ``m = 0.05`` with the default grid: median ≤ 0.5 %, p90 ≤ 2 % in the lobe against direct
  GO evaluation (the old plugin resampled onto 90 × 90 × 180: 2.2 % / 9.6 % there);
* float32 tables load in the plugin.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from emscatter.brdf import build_table
from emscatter.brdf.colour import spectrum_to_rgb_weights
from emscatter.render import mitsuba as em_mi
from emscatter.render.plugin_data import Axis, prepare
from emscatter.spectra import GaussianCorrelation
from render_helpers import lossy_eps, mi, mitsuba_eval, random_pairs, relative_errors, use_variant
from test_brdf_sizing import LAM, go_direct, go_table, lobe_pairs

RNG = np.random.default_rng(0)
THETA = np.sort(np.concatenate([[0.0], RNG.uniform(0.01, 1.55, 30)]))  # non-uniform
PHI_D = np.sort(np.concatenate([[0.0, math.pi], RNG.uniform(0.01, 3.1, 40)]))
PHI = np.sort(RNG.uniform(0.05, 2 * math.pi - 0.05, 20))  # periodic, not starting at 0


def _table(aniso: bool, dtype="float64"):
    rough = GaussianCorrelation(0.1e-6, 1e-6, length_y=0.6e-6 if aniso else None)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return build_table(
            rough,
            lossy_eps(550e-9),
            [500e-9, 600e-9],
            method="go",
            theta=THETA,
            phi=PHI if aniso else PHI_D,
            anisotropic=aniso,
            dtype=dtype,
        )


def test_non_uniform_axes_are_kept():
    data = prepare(_table(False), "spectral")
    assert not data.theta_i.uniform and not data.phi.uniform
    np.testing.assert_array_equal(data.theta_i.nodes, THETA)
    assert data.values.shape[:3] == (THETA.size, THETA.size, PHI_D.size)
    assert Axis.of(np.linspace(0, 1, 5)).uniform


@pytest.mark.parametrize(
    ("variant", "aniso", "dtype"),
    [
        ("llvm_ad_rgb", False, "float64"),
        ("llvm_ad_spectral", False, "float32"),
        ("llvm_ad_spectral", True, "float64"),
        ("llvm_ad_rgb", True, "float32"),
    ],
    ids=["iso-rgb", "iso-spectral-f32", "aniso-spectral", "aniso-rgb-f32"],
)
def test_eval_on_non_uniform_axes_is_the_table(variant, aniso, dtype):
    use_variant(variant)
    table = _table(aniso, dtype)
    bsdf = mi.load_dict(em_mi.bsdf_dict(table))
    wi, wo = random_pairs(np.random.default_rng(4), 20_000)
    if mi.is_rgb:
        want = (spectrum_to_rgb_weights(table.wavelengths) @ (table.evaluate(wi, wo) * wo[:, 2])).T
        got = mitsuba_eval(bsdf, wi, wo)
    else:
        got = mitsuba_eval(bsdf, wi, wo, wavelength_nm=550.0)
        want = table.evaluate(wi, wo, wavelength=550e-9)[:, None] * wo[:, 2:3]
    for c in range(got.shape[1]):
        err = relative_errors(got[:, c], want[:, c], floor=1e-4)
        assert err.max() < 5e-4, err.max()  # float32 nodes and texture vs the float64 table


@pytest.mark.slow
def test_go_m005_in_the_plugin_by_default():
    """Issue 21's target: GO m = 0.05 in the plugin, default grid: median ≤ 0.5 %, p90 ≤ 2 %."""
    use_variant("llvm_ad_spectral")
    table = go_table(0.05, energy="off")
    bsdf = mi.load_dict(em_mi.bsdf_dict(table))
    wi, wo = lobe_pairs(0.05, 20_000)
    p = table.metadata["surface_params"]
    want = go_direct(GaussianCorrelation(p["sigma"], p["length"]), wi, wo)
    got = mitsuba_eval(bsdf, wi, wo, wavelength_nm=LAM * 1e9)[:, 0] / wo[:, 2]
    err = np.abs(got - want) / want
    assert np.median(err) <= 5e-3, np.median(err)
    assert np.quantile(err, 0.9) <= 2e-2, np.quantile(err, 0.9)


def test_sampling_on_non_uniform_axes_matches_the_albedo():
    """``sample`` mixes the alias tables of the table's own (non-uniform) θi nodes: the
    sampled albedo is the table's exact albedo (2 %, Monte Carlo)."""
    from render_helpers import sampled_albedo

    use_variant("llvm_ad_spectral")
    table = _table(False)
    bsdf = mi.load_dict(em_mi.bsdf_dict(table, coherent=False))
    alb = table.albedo()
    for k in (3, 17):
        theta = float(THETA[k])
        est, _ = sampled_albedo(bsdf, theta, wavelength_nm=500.0)
        want = float(alb.incoherent[0, k])
        assert est[0] == pytest.approx(want, rel=2e-2), (theta, est, want)
