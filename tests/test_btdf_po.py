"""PO (Kirchhoff) transmission through a rough dielectric
(:mod:`emscatter.solvers.kirchhoff.transmission.po`): the flat limit (Fresnel T), the large-kσ
limit (Walter et al. 2007 without shadowing, :mod:`.transmission.go`), R + T with the
reflection PO where PO is valid, the out-of-range policies, reciprocity, and the PO BTDF
table."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from emscatter.fresnel import fresnel_cos
from emscatter.solvers.kirchhoff import po as rpo
from emscatter.solvers.kirchhoff.transmission import go as tgo
from emscatter.solvers.kirchhoff.transmission import po as tpo
from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation
from transmission_checks import K, assert_eps_weighted_reciprocity, gauss_legendre


def _hemisphere(n_theta=240, n_phi=192):
    """Quadrature over the lower hemisphere (θt, φt) with dΩ weights."""
    t, wt = gauss_legendre(n_theta, 0.0, 0.5 * math.pi)
    p = np.linspace(-math.pi, math.pi, n_phi, endpoint=False)
    tt, pp = np.meshgrid(t, p, indexing="ij")
    return tt, pp, np.sin(tt) * wt[:, None] * (2 * math.pi / n_phi)


def _fresnel_t(eps, theta):
    rh, rv = fresnel_cos(eps, np.cos(theta))
    return 1 - abs(rh) ** 2, 1 - abs(rv) ** 2


def _incoherent_t(rough, eps, theta_i, fn=tpo.bistatic_transmission, **kw):
    """Incoherent transmitted fraction per incident polarization (h, v), and the result."""
    tt, pp, w = _hemisphere()
    res = fn(rough, eps, K, theta_i, tt, pp, 0.0, **kw)
    per_pol = res.sigma0.sum(axis=0)  # summed over the transmitted polarization
    return (per_pol * w).sum(axis=(1, 2)) / (4 * math.pi * math.cos(theta_i)), res


def test_flat_limit_is_fresnel_transmission():
    """σ → 0: the coherent transmissivity is Fresnel's T per polarization, nothing incoherent."""
    rough = GaussianCorrelation(sigma=1e-6, length=2.0, dimension=2)
    th = np.radians([0.0, 20.0, 45.0, 70.0, 85.0])
    res = tpo.bistatic_transmission(rough, 2.25, K, th, 0.3, 0.0, 0.0, out_of_range="ignore")
    th_h, tv = _fresnel_t(2.25, th)
    np.testing.assert_allclose(res.coherent[0], th_h, rtol=1e-9)
    np.testing.assert_allclose(res.coherent[1], tv, rtol=1e-9)
    assert np.max(res.sigma0) < 1e-8  # O((kσ)² (kℓ)²) = 6e-9 here
    # from the denser side (ε < 1): Fresnel T below the critical angle, 0 beyond it
    inside = tpo.coherent_transmissivity(rough, 1 / 2.25, K, np.radians([10.0, 30.0, 50.0]))
    ref = _fresnel_t(1 / 2.25 + 0j, np.radians([10.0, 30.0]))
    np.testing.assert_allclose(inside[:, :2], np.array(ref), rtol=1e-9)
    assert np.all(inside[:, 2] == 0)  # 50° > the critical angle 41.8°


def test_coherent_factor_is_kirchhoff_mean_field():
    """T_coh = T_F · exp(−σ²(k₁cosθi − k₂cosθt)²) (module docstring)."""
    sig = 0.05
    rough = GaussianCorrelation(sigma=sig, length=2.0, dimension=2)
    th = np.radians([0.0, 30.0, 60.0])
    ct = np.sqrt(1 - np.sin(th) ** 2 / 2.25)
    att = np.exp(-((K * sig * (np.cos(th) - 1.5 * ct)) ** 2))
    got = tpo.coherent_transmissivity(rough, 2.25, K, th)
    np.testing.assert_allclose(got, np.array(_fresnel_t(2.25, th)) * att, rtol=1e-12)


@pytest.mark.parametrize("theta_deg", [0.0, 40.0])
def test_slightly_rough_total_equals_fresnel(theta_deg):
    """kσ 0.31, kℓ 12.6: coherent + incoherent T = Fresnel T within 1e-3 (the roughness
    redistributes the transmitted power, the Kirchhoff total keeps it: measured 0.95998 vs
    0.96000 at 0°, 0.95413 vs 0.95413 at 40°)."""
    th = math.radians(theta_deg)
    rough = GaussianCorrelation(sigma=0.05, length=2.0, dimension=2)
    inc, res = _incoherent_t(rough, 2.25, th, out_of_range="ignore")
    total = inc + res.coherent[:, 0, 0]
    np.testing.assert_allclose(total, _fresnel_t(2.25, th), atol=1e-3)
    assert np.all(inc > 0.01)  # really rough enough to scatter


def test_large_k_sigma_tends_to_go_walter():
    """kσ 12.6 → 25 (same slopes, α = 0.2): σ⁰_t against Walter et al.'s BTDF without
    shadowing, where GO ≥ 1 % of its peak. Measured median / p90: kσ 6.3: 5.6 % / 9.3 %,
    12.6: 1.4 % / 2.5 %, 25: 0.36 % / 0.64 % — falling as 1/(kσ)² (a PO → GO limit)."""
    rng = np.random.default_rng(1)
    ti = rng.uniform(0, 1.2, 4000)
    tt = rng.uniform(0, 1.2, 4000)
    pt = rng.uniform(-math.pi, math.pi, 4000)
    errs = []
    for sig in (2.0, 4.0):
        rough = GaussianCorrelation(sigma=sig, length=10 * sig, dimension=2)
        a = tpo.bistatic_transmission(rough, 2.25, K, ti, tt, pt, 0.0, out_of_range="ignore")
        b = tgo.bistatic_transmission(rough, 2.25, K, ti, tt, pt, 0.0, shadowing=False)
        ua, ub = a.unpolarized(), b.unpolarized()
        sel = ub > 0.01 * ub.max()
        assert sel.sum() > 100
        errs.append(np.abs(ua[sel] / ub[sel] - 1))
    assert np.median(errs[0]) < 0.02 and np.percentile(errs[0], 90) < 0.04
    assert np.median(errs[1]) < 0.6 * np.median(errs[0])
    # the incoherent total equals GO's (no shadowing) within 1e-3 at normal incidence
    rough = GaussianCorrelation(sigma=2.0, length=20.0, dimension=2)
    t_po, _ = _incoherent_t(rough, 2.25, 0.0, out_of_range="ignore")
    t_go, _ = _incoherent_t(rough, 2.25, 0.0, fn=tgo.bistatic_transmission, shadowing=False)
    np.testing.assert_allclose(t_po, t_go, atol=1e-3)


@pytest.mark.parametrize("theta_deg", [0.0, 30.0, 60.0])
def test_reflection_plus_transmission_at_most_one_where_valid(theta_deg):
    """R (reflection PO, coherent + incoherent) + T (PO transmission) ≤ 1 + 2e-3 (the
    quadrature's error, checked by the Fresnel totals above) where PO is valid (kσ 1.9,
    kℓ 18.8, rms slope 0.2, lossless ε 2.25), and within 1.5 % of 1 (the Kirchhoff
    approximation's energy error: no multiple scattering, no shadowing; measured R + T =
    0.9999 at 0°, 0.989 (h) / 0.997 (v) at 60°)."""
    th = math.radians(theta_deg)
    rough = GaussianCorrelation(sigma=0.3, length=3.0, dimension=2)
    assert rpo.check_validity(rough, K, eps=2.25, theta_i=th)["valid"]
    t_inc, tres = _incoherent_t(rough, 2.25, th)
    t = t_inc + tres.coherent[:, 0, 0]
    tt, pp, w = _hemisphere()  # the upper hemisphere: same angles, θs from the upward normal
    rres = rpo.bistatic(rough, 2.25, K, th, tt, pp, 0.0)
    r = (rres.sigma0.sum(axis=0) * w).sum(axis=(1, 2)) / (4 * math.pi * math.cos(th))
    r = r + rres.coherent[:, 0, 0]
    total = r + t
    assert np.all(total <= 1 + 2e-3), total
    assert np.all(np.abs(total - 1) < 0.015), total


def test_out_of_range_policies():
    """Grazing incidence on a rough surface is outside PO's validity: a warning naming it by
    default, a ValueError with 'raise', NaN at exactly those angles with 'nan', and the mask
    in ``info["out_of_range"]``."""
    rough = GaussianCorrelation(sigma=0.3, length=1.5, dimension=2)  # rms slope 0.4
    th = np.radians([20.0, 88.0])
    args = (rough, 2.25, K, th, 0.5, 0.0, 0.0)
    with pytest.warns(tpo.POWarning, match="grazing"):
        res = tpo.bistatic_transmission(*args)
    assert res.info["out_of_range"].tolist() == [False, True]
    assert np.all(np.isfinite(res.sigma0))
    with pytest.raises(ValueError, match="grazing"):
        tpo.bistatic_transmission(*args, out_of_range="raise")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        blank = tpo.bistatic_transmission(*args, out_of_range="nan")
        tpo.bistatic_transmission(*args, out_of_range="ignore")
    assert np.all(np.isfinite(blank.sigma0[..., 0])) and np.all(np.isnan(blank.sigma0[..., 1]))
    assert np.isnan(blank.coherent[:, 1]).all() and np.isfinite(blank.coherent[:, 0]).all()


@pytest.mark.parametrize(
    "rough",
    [
        GaussianCorrelation(sigma=0.2, length=1.5, dimension=2),
        ExponentialCorrelation(sigma=0.1, length=2.0, dimension=2),
        GaussianCorrelation(sigma=0.2, length=1.5, length_y=2.5, dimension=2),
    ],
    ids=["gauss", "exponential", "anisotropic"],
)
def test_reciprocity_n_squared_weighted(rough):
    """σ⁰_t,pq(ε, k; k̂i → k̂t) = ε σ⁰_t,qp(1/ε, ηk; −k̂t → −k̂i) (measured 1e-15 relative)."""
    assert_eps_weighted_reciprocity(tpo.bistatic_transmission, rough, lit_share=1e-6)


def test_bad_inputs_are_clear_errors():
    rough = GaussianCorrelation(sigma=0.1, length=1.0, dimension=2)
    with pytest.raises(ValueError, match="perfect conductor"):
        tpo.bistatic_transmission(rough, "pec", K, 0.1, 0.1, 0.0)
    with pytest.raises(ValueError, match=r"Im\(eps\) < 0"):  # lossy is allowed, gain is not
        tpo.bistatic_transmission(rough, 2.25 - 0.1j, K, 0.1, 0.1, 0.0)
    with pytest.raises(ValueError, match="out_of_range"):
        tpo.bistatic_transmission(rough, 2.25, K, 0.1, 0.1, 0.0, out_of_range="maybe")
    with pytest.raises(ValueError, match="theta_i"):
        tpo.bistatic_transmission(rough, 2.25, K, 2.0, 0.1, 0.0)
    with pytest.raises(ValueError, match="1-D profile"):
        profile = GaussianCorrelation(0.1, 1.0, dimension=1)
        tpo.bistatic_transmission(profile, 2.25, K, 0.1, 0.1, 0.0)


# ----------------------------------------------------------------------------- PO BTDF tables
LAM = 1e-6
GLASS_PO = GaussianCorrelation(sigma=0.3e-6, length=3e-6, dimension=2)  # kσ 1.9, kℓ 18.8


@pytest.fixture(scope="module")
def po_table():
    from emscatter.brdf.btdf_table import build_btdf_table

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the grazing θi nodes are outside PO: tested below
        return build_btdf_table(GLASS_PO, 2.25, [LAM], method="po", n_theta=30, n_phi=121)


def test_po_table_equals_the_solver_and_counts_the_coherent_lobe(po_table):
    """At the θi nodes, between the (θt, Δφ) nodes, the table interpolates the PO solver
    (median / p90 where f_t ≥ 1 % of its peak: measured 0.15 % / 0.71 % on 30 × 262 × 121 nodes);
    its albedo adds the coherent transmissivity,
    and at normal incidence T = Fresnel 0.96 within the grid's quadrature error (3e-3)."""
    from emscatter.brdf import frames

    t = po_table
    assert t.metadata["solver"] == "kirchhoff-po-transmission"
    rng = np.random.default_rng(5)
    n = 4000
    ti = rng.choice(t.theta_i[t.theta_i < 1.0], n)
    tt = np.clip(np.arcsin(np.sin(ti) / 1.5) + rng.normal(0, 0.1, n), 0, 1.4)
    dp = math.pi - np.abs(rng.normal(0, 0.3, n))
    wi = frames.directions(ti, np.zeros(n))
    wo = frames.directions(math.pi - tt, dp)
    got = t.evaluate(wi, wo, LAM)
    res = tpo.bistatic_transmission(
        GLASS_PO, 2.25, 2 * math.pi / LAM, ti, tt, dp, math.pi, out_of_range="ignore"
    )
    ref = res.unpolarized() / (4 * math.pi * np.cos(ti) * np.cos(tt))
    sel = ref > 0.01 * ref.max()
    err = np.abs(got[sel] / ref[sel] - 1)
    assert np.median(err) < 0.005 and np.percentile(err, 90) < 0.02
    np.testing.assert_allclose(
        t.coherent[0], tpo.coherent_transmissivity(GLASS_PO, 2.25, 2 * math.pi / LAM, t.theta_i)
        .mean(axis=0), rtol=1e-12,
    )  # fmt: skip
    assert t.albedo()[0, 0] == pytest.approx(0.96, abs=3e-3)
    np.testing.assert_allclose(t.albedo() - t.incoherent_albedo(), t.coherent)


def test_po_brdf_and_btdf_close_the_energy_budget(po_table):
    """A PO reflection table and the PO BTDF of the same glass: R + T within 1.5 % of 1 at
    θi ≤ 60° (Kirchhoff's own energy error plus the grids'; measured 0.9999–1.0025)."""
    from emscatter.brdf import build_table
    from emscatter.brdf.btdf_table import energy_budget

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        br = build_table(
            GLASS_PO, 2.25, [LAM], method="po", resolution=(30, 90), energy="off",
            transmission="off",
        )  # fmt: skip
    b = energy_budget(br, po_table)
    ok = b["theta_i_deg"] <= 60
    assert np.all(np.abs(b["R"] + b["T"] - 1)[0, ok] < 0.015), (b["R"] + b["T"])[0, ok]


def test_po_table_policies_and_npz_round_trip(tmp_path, po_table):
    """Outside PO's validity: one warning per wavelength naming the θi nodes, or a ValueError
    with out_of_range='raise'; the coherent part survives the .npz file."""
    from emscatter.brdf.btdf_table import build_btdf_table
    from emscatter.brdf.export_npz import read_btdf_npz, write_btdf_npz

    kw = {"method": "po", "n_theta": 10, "n_theta_t": 20, "n_phi": 21}
    with pytest.warns(UserWarning, match="outside the Kirchhoff") as rec:
        build_btdf_table(GLASS_PO, 2.25, [LAM], **kw)
    assert len([w for w in rec if "Kirchhoff" in str(w.message)]) == 1
    with pytest.raises(ValueError, match="grazing"):
        build_btdf_table(GLASS_PO, 2.25, [LAM], out_of_range="raise", **kw)
    with pytest.raises(ValueError, match="method must be 'go', 'po' or 'spm'"):
        build_btdf_table(GLASS_PO, 2.25, [LAM], method="mom")
    with pytest.raises(ValueError, match="unknown option"):
        build_btdf_table(GLASS_PO, 2.25, [LAM], method="po", shadowing=True)
    per = po_table.metadata["per_wavelength"][0]
    assert per["theta_i_out_of_range_deg"] and min(per["theta_i_out_of_range_deg"]) > 60
    back = read_btdf_npz(write_btdf_npz(po_table, tmp_path / "po.npz"))
    np.testing.assert_array_equal(back.coherent, po_table.coherent)
    np.testing.assert_array_equal(back.values, po_table.values)


def test_cli_brdf_transmission_method_po(tmp_path):
    """``emscatter brdf --transmission --method po`` writes a PO BTDF (with its coherent part)."""
    from emscatter.brdf.export_npz import read_btdf_npz
    from emscatter.cli import main

    argv = [
        "brdf", str(tmp_path / "g.npz"), "--material", "2.25", "--sigma", "3e-7", "--length",
        "3e-6", "--wavelengths-nm", "1000", "--method", "po", "--n-theta", "12", "--n-phi",
        "25", "--out-of-range", "ignore", "--transmission", "--quiet",
    ]  # fmt: skip
    assert main(argv) == 0
    bt = read_btdf_npz(tmp_path / "g_btdf.npz")
    assert bt.metadata["solver"] == "kirchhoff-po-transmission"
    assert bt.coherent is not None and bt.coherent[0, 0] > 0.3


def test_po_table_polarized_is_the_facet_jones_matrix():
    """polarized=True: M₀₀ is the PO BTDF, and M/M₀₀ is the stationary-phase facet's Mueller
    matrix, the same as GO's at the same direction pair (Kirchhoff's polarization factor is
    the local Fresnel transmission; only the scalar integral differs)."""
    from emscatter.brdf.btdf_table import build_btdf_table

    kw = {"n_theta": 6, "n_theta_t": 24, "n_phi": 25, "polarized": True}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        p = build_btdf_table(GLASS_PO, 2.25, [LAM], method="po", **kw)
    g = build_btdf_table(GLASS_PO, 2.25, [LAM], shadowing=False, **kw)
    np.testing.assert_array_equal(p.mueller[:, 0, 0], p.values)
    ok = (g.values > 1e-6 * g.values.max()) & (p.values > 1e-6 * p.values.max())
    assert ok.sum() > 100
    ratio_p = p.mueller[0][:, :, ok[0]] / p.values[0][ok[0]]
    ratio_g = g.mueller[0][:, :, ok[0]] / g.values[0][ok[0]]
    np.testing.assert_allclose(ratio_p, ratio_g, atol=1e-10)


def test_po_tables_in_the_dielectric_plugin():
    """The PO BRDF and BTDF go through ``emscatter_dielectric`` exactly as GO's do: per
    direction pair the plugin's ``eval`` over the table value is the same (geometric,
    convention) factor for both (Mitsuba run for real in a worker process; float32 textures).
    This checks the glossy lobes (their choice uses :meth:`BtdfTable.incoherent_albedo`); the
    coherent parts are the plugin's delta lobes (tests/test_render_dielectric_delta.py)."""
    import importlib.util
    import sys
    from pathlib import Path

    here = Path(__file__).parent
    sys.path.insert(0, str(here))
    try:
        from test_render_dielectric import _llvm_rgb, _pairs, _worker
    finally:
        sys.path.remove(str(here))
    if not _llvm_rgb():
        pytest.skip("needs Mitsuba's llvm_ad_rgb")
    spec = importlib.util.spec_from_file_location("dpw", here / "dielectric_plugin_worker.py")
    dpw = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(dpw)
    v, l = _pairs(n=200)
    ratios = {}
    for method in ("go", "po"):
        out, bt, _ = dpw.tables(24, (550e-9,), method)
        em = np.array(_worker(v=v, l=l, n_theta=24, method=method)["em"])
        t_in = (v[:, 2] < 0) & (l[:, 2] > 0)  # light outside, viewer inside: the BTDF itself
        r_out = (v[:, 2] > 0) & (l[:, 2] > 0)
        f_t = bt.evaluate(l[t_in], v[t_in], 550e-9)
        f_r = out.evaluate(l[r_out], v[r_out], 550e-9)
        ratios[method] = (
            em[t_in] / np.where(f_t > 0, f_t, np.nan),
            f_t > 0.01 * f_t.max(),
            em[r_out] / np.where(f_r > 0, f_r, np.nan),
            f_r > 0.01 * f_r.max(),
        )
    for a, b in ((0, 1), (2, 3)):
        ok = ratios["go"][b] & ratios["po"][b]
        assert ok.sum() > 20
        np.testing.assert_allclose(ratios["po"][a][ok], ratios["go"][a][ok], rtol=2e-3)
