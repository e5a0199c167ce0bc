"""The stored soil-like 3-D comparison (validation/mom3d/soil_vs_models.py → .csv/.md/.png):
its format, the energy of every realization, the laws it shows, and — on tiny patches — that
the script's Monte Carlo is ``mom3d.bistatic``'s and its absorbed power is the Fresnel one
(issue 19)."""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest

from emscatter.io import read_csv
from emscatter.solvers import mom3d
from emscatter.solvers.mom3d.dielectric_model import beam_fresnel, solve_dielectric_realization

ROOT = Path(__file__).resolve().parents[1]
HERE = ROOT / "validation" / "mom3d"
CSV = HERE / "soil_vs_models.csv"


def _script():
    spec = importlib.util.spec_from_file_location("soil_vs_models", HERE / "soil_vs_models.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _db(x):
    return 10 * np.log10(x)


@pytest.fixture(scope="module")
def table():
    return read_csv(CSV)


def test_stored_table_format(table):
    header, c, meta = table
    assert meta["schema"] == "mom3d_soil/1"
    for p in ("hh", "vv", "hv", "vh"):
        assert {f"mom3d_{p}", f"mom3d_{p}_se"} <= set(header)
        for m in ("spm", "iem", "po", "go"):
            assert {f"{m}_{p}", f"{m}_{p}_beam"} <= set(header)
    assert "spm2_hv" in header
    n = c["theta_s_deg"].size
    assert n == 29 + 15 and np.sum(c["cut"] == 0) == 29  # plane −70…70°, cross plane 0…70°
    for key in header:
        assert c[key].shape == (n,) and np.all(np.isfinite(c[key])), key
    for p in ("hh", "vv"):
        assert np.all(c[f"mom3d_{p}"] > 0) and np.all(c[f"mom3d_{p}_se"] > 0)
    assert meta["realizations"] >= 8 and meta["correlation"] == "gaussian"
    assert meta["eps"][0] <= 5.0 and meta["eps"][1] >= 0.0
    assert 0.3 <= meta["k_sigma"] <= 0.5 and meta["k_ell"] == 3 and meta["theta_i_deg"] == 40
    md = (HERE / "soil_vs_models.md").read_text(encoding="utf-8").splitlines()
    assert md[0] == f"PYTHONPATH=src python validation/mom3d/soil_vs_models.py --realizations " \
                    f"{meta['realizations']}"  # fmt: skip
    assert (ROOT / "docs" / "figures" / "mom3d_soil_vs_models.png").stat().st_size > 10_000


def test_every_realization_conserves_energy(table):
    """R (far field) + A (Poynting flux into the soil) = 1 per realization within 3 %; R is
    near the beam's Fresnel reflectivity reduced by roughness (never above it)."""
    _, _, meta = table
    r = np.stack([meta["reflectivity_h"], meta["reflectivity_v"]], axis=1)
    a = np.stack([meta["absorbed_h"], meta["absorbed_v"]], axis=1)
    assert r.shape == (meta["realizations"], 2)
    assert np.all(np.abs(r + a - 1.0) < 0.03)
    assert np.all((r > 0) & (a > 0))


def test_script_monte_carlo_is_bistatics():
    """The script's realizations (same seeds, surfaces and estimator) give mom3d.bistatic's σ⁰,
    samples and reflectivity on a 1λ patch (bistatic solves to GMRES tol 1e-5, the script to
    1e-6: agreement to 1e-3 relative)."""
    s = _script()
    rough, eps, k, lam0 = s.case()
    ti = math.radians(40.0)
    ts = np.radians([10.0, 40.0, 60.0, 30.0])
    ps = np.array([math.pi, 0.0, 0.0, math.pi / 2])
    n, seed = 3, 5
    ref = mom3d.bistatic(rough, eps, k, ti, ts, ps, realizations=n, seed=seed, length=lam0,
                         points_per_wavelength=s.PPW, progress=False)  # fmt: skip
    seeds = np.random.SeedSequence(seed).spawn(n)
    res = [s.realization(rough, eps, k, lam0, ti, ts, ps, ss) for ss in seeds]
    mc = s.monte_carlo(res, k, ti)
    np.testing.assert_allclose(mc["sigma0"], ref.sigma0, rtol=1e-3)
    np.testing.assert_allclose(mc["samples"], ref.info["sigma0_samples"], rtol=1e-3, atol=1e-12)
    refl = np.array([r["reflectivity"] for r in res])
    np.testing.assert_allclose(refl, ref.info["reflectivity"], rtol=1e-4)


@pytest.mark.parametrize("eps", [4.39 + 0.363j, 4.0 + 0.0j])
def test_absorbed_power_of_a_flat_patch(eps):
    """Flat 1.5λ patch: the Poynting flux into the medium equals the far-field transmissivity
    of a lossless one (within 0.2 %) and R + A = 1 within 2 % (beam Fresnel R within 10 %)."""
    s = _script()
    k, n = 2 * math.pi, 25
    spacing = 1.5 / n
    h = np.zeros((n, n))
    out = solve_dielectric_realization(h, spacing, k, eps, math.radians(40.0), [0.5], [0.0])
    a = s.absorbed(out, h, spacing)
    r = out["reflectivity"]
    assert np.all(np.abs(r + a - 1.0) < 0.02)
    np.testing.assert_allclose(r, beam_fresnel(out["beam"], eps), rtol=0.1)
    if eps.imag == 0:
        np.testing.assert_allclose(a, out["transmissivity"], rtol=2e-3)


def test_nadir_is_one_direction_in_both_cuts(table):
    """θs = 0 in the plane (φs = 0) and in the cross plane (φs = 90°) is one direction whose
    h, v basis is turned by 90°: vv there is hv here and hh is vh — to rounding for the MoM,
    SPM, PO and GO, within 3 % for the IEM (measured 0.2–1.5 %: it is not exactly
    basis-covariant at nadir)."""
    _, c, _ = table
    p0 = np.flatnonzero((c["cut"] == 0) & (c["theta_s_deg"] == 0))[0]
    x0 = np.flatnonzero((c["cut"] == 1) & (c["theta_s_deg"] == 0))[0]
    cases = [("mom3d", "", 1e-6)] + [(m, "_beam", 1e-6) for m in ("spm", "po", "go")]
    for pre, suf, rtol in cases + [("iem", "_beam", 3e-2)]:
        for a, b in (("hv", "vv"), ("vh", "hh"), ("vv", "hv"), ("hh", "vh")):
            np.testing.assert_allclose(c[f"{pre}_{a}{suf}"][x0], c[f"{pre}_{b}{suf}"][p0],
                                       rtol=rtol, err_msg=f"{pre}{suf} {a}/{b}")  # fmt: skip


def test_models_in_their_range_agree_with_the_exact_sigma0(table):
    """kσ = 0.3, kℓ = 3 is inside first-order SPM's and the IEM's ranges. Cross-pol in the
    cross plane φs = 90° (first order, large): SPM1 and the IEM, averaged over the beam, within
    two standard errors of the MoM in the mean dB difference (measured −0.75 and −0.37 dB, SE
    0.83 dB per direction; its mean over the correlated directions is taken as the pooled SE,
    an upper bound). Co-pol in the plane, per region (backward wing θs ≤ −10°, specular ± the
    beam's spread, forward): the IEM within 2 dB and SPM1 within 2.5 dB in every region
    (16 realizations: IEM −1.0 … +1.7, SPM1 −1.3 … +2.3 dB; the backward wing reads +1.7 dB
    high for both, ≈ 2 SE, where σ⁰ is 15–25 dB under its peak and the 3λ patch's edges and
    beam weigh most). GO, a high-frequency limit far outside its range, over 10 dB off in the
    backward wing (+19.5 vv, +15.7 hh)."""
    _, c, meta = table
    deg, plane = c["theta_s_deg"], c["cut"] == 0
    lo = meta["theta_i_deg"] - meta["beam_width_deg"]
    hi = meta["theta_i_deg"] + meta["beam_width_deg"]
    back = plane & (deg <= -10)
    regions = (back, plane & (deg >= lo) & (deg <= hi), plane & (deg > hi))

    def diff(sel, p, m):
        mom = c[f"mom3d_{p}"][sel]
        se = np.mean(_db(mom + c[f"mom3d_{p}_se"][sel]) - _db(mom))
        return np.mean(_db(mom) - _db(c[f"{m}_{p}_beam"][sel])), se

    for m in ("spm", "iem"):
        d, se = diff(c["cut"] == 1, "hv", m)
        assert abs(d) < 2 * se, (m, d, se)
    for p in ("vv", "hh"):
        for sel in regions:
            assert abs(diff(sel, p, "iem")[0]) < 2.0, p
            assert abs(diff(sel, p, "spm")[0]) < 2.5, p
        assert diff(back, p, "go")[0] > 10.0
