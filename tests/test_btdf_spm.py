"""First-order SPM transmission through a slightly rough dielectric
(:mod:`emscatter.solvers.spm.transmission`): the TE closed form (Rice 1951; Johnson 1999),
energy R_coh + R_diff + T_coh + T_diff = 1 to O((kσ)²), ε-weighted reciprocity, the flat and
ε → 1 limits, agreement with PO transmission where both hold, the policies, and the SPM BTDF
table (solver agreement, R + T with the SPM reflection table, Mueller part, CLI)."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from emscatter.fresnel import fresnel_cos
from emscatter.solvers.kirchhoff.transmission import po as tpo
from emscatter.solvers.spm import model as spm
from emscatter.solvers.spm import transmission as tspm
from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation
from transmission_checks import K, assert_eps_weighted_reciprocity
from transmission_checks import hemisphere as _hemisphere


def _budget(rough, eps, th, n=48):
    """(R_coh, R_diff, T_coh, T_diff) per incident polarization (h, v) at θi = ``th``."""
    eta = math.sqrt(eps)
    tt, pt, wt = _hemisphere(n, math.asin(1 / eta) if eta > 1 else None)
    res = tspm.bistatic_transmission(rough, eps, K, th, tt, pt, 0.0, out_of_range="ignore")
    t_diff = (res.sigma0.sum(axis=0) * wt).sum(axis=(-1, -2)) / (4 * math.pi * math.cos(th))
    ts, ps, ws = _hemisphere(n, math.asin(eta) if eta < 1 else None)
    s = spm.bistatic(rough, eps, K, th, ts, ps, order=0).sigma0
    r_diff = (s.sum(axis=0) * ws).sum(axis=(-1, -2)) / (4 * math.pi * math.cos(th))
    r_coh = spm.coherent_reflectivity(rough, eps, K, np.array([th]))[:, 0]
    return r_coh, r_diff, res.coherent[:, 0, 0], t_diff


def test_te_amplitude_is_the_closed_form():
    """h → h: |b_hh| = 2 k₁zi k² |ε − 1| |cos(φt − φi)| / |(k₁z + k₂z)(k₁zi + k₂zi)| (Rice 1951;
    Johnson, JOSA A 16, 1999, 2720, first-order TE: the transmitted amplitude equals the
    reflected one at the same k⊥), propagating and evanescent k₁z alike; and the broadcast
    solve equals the boundary-value solution of :mod:`.second_order` to rounding."""
    rng = np.random.default_rng(1)
    eps, th = 2.25, 0.6
    kx, ky = rng.uniform(-1.5 * K, 1.5 * K, (2, 200))
    b = tspm.transmission_amplitudes(eps, K, th, kx, ky)
    kn2 = kx**2 + ky**2
    k1z = np.sqrt((K**2 - kn2).astype(complex))
    k2z = np.sqrt((eps * K**2 - kn2).astype(complex))
    k1zi, k2zi = K * math.cos(th), math.sqrt(eps * K**2 - (K * math.sin(th)) ** 2)
    closed = 2 * k1zi * K**2 * (eps - 1) * np.abs(kx / np.sqrt(kn2))
    closed = closed / np.abs((k1z + k2z) * (k1zi + k2zi))
    np.testing.assert_allclose(np.abs(b[0, 0]), closed, rtol=1e-12)
    mixed = tspm.transmission_amplitudes(np.where(kx > 0, 4.0, eps), K, th, kx, ky)
    four = tspm.transmission_amplitudes(4.0, K, th, kx, ky)
    np.testing.assert_array_equal(mixed, np.where(kx > 0, four, b))  # per-element media
    ref = spm._first_order_amplitudes(GaussianCorrelation(0.01, 0.2), eps, K, th, kx, ky)
    for p in (0, 1):
        np.testing.assert_allclose(b[0, p], ref[p][2], rtol=1e-12, atol=1e-12 * np.abs(b).max())
        np.testing.assert_allclose(b[1, p], ref[p][3], rtol=1e-12, atol=1e-12 * np.abs(b).max())


@pytest.mark.parametrize("ks", [0.02, 0.05, 0.1])
@pytest.mark.parametrize("eps", [4.0, 1 / 2.25], ids=["into-glass", "from-inside"])
def test_energy_balance_to_second_order(ks, eps):
    """Lossless: R_coh + R_diff + T_coh + T_diff = 1 within the O((kσ)⁴) remainder (asserted
    ≤ 0.1 (kσ)⁴; measured ≤ 5e-8 (kσ = 0.1) with this quadrature, the perturbation series
    balancing exactly at O((kσ)²)), at θi up to 69° and, from the denser side, beyond the
    critical angle (T_coh = 0). The diffuse parts are not trivial: T_diff ≳ (kσ)²/10."""
    rough = GaussianCorrelation(ks / K, 1.5 / K, dimension=2)
    for th in (0.0, 0.5, 1.2):
        rc, rd, tc, td = _budget(rough, eps, th)
        np.testing.assert_array_less(np.abs(rc + rd + tc + td - 1), 0.1 * ks**4)
        assert np.all(td > 0.005 * ks**2), td
        if eps < 1 and math.sin(th) > math.sqrt(eps):
            assert np.all(tc == 0)


@pytest.mark.parametrize(
    "rough",
    [
        GaussianCorrelation(sigma=0.02, length=0.3, dimension=2),
        ExponentialCorrelation(sigma=0.01, length=0.5, dimension=2),
        GaussianCorrelation(sigma=0.02, length=0.3, length_y=0.5, dimension=2),
    ],
    ids=["gauss", "exponential", "anisotropic"],
)
def test_reciprocity_eps_weighted(rough):
    """σ⁰_t,pq(ε, k; k̂i → k̂t) = ε σ⁰_t,qp(1/ε, ηk; −k̂t → −k̂i) (as PO's; measured 2e-15)."""
    assert_eps_weighted_reciprocity(tspm.bistatic_transmission, rough, lit_share=1e-3)


def test_flat_limit_is_fresnel_transmission():
    """σ → 0: the coherent transmissivity is Fresnel's T (1 − |R|²), σ⁰_t ∝ σ² → 0; from the
    denser side 0 beyond the critical angle."""
    th = np.radians([0.0, 20.0, 45.0, 70.0, 85.0])
    rough = GaussianCorrelation(sigma=1e-7, length=0.5, dimension=2)
    rh, rv = fresnel_cos(2.25, np.cos(th))
    tc = tspm.coherent_transmissivity(rough, 2.25, K, th)
    np.testing.assert_allclose(tc, [1 - abs(rh) ** 2, 1 - abs(rv) ** 2], rtol=1e-9)
    s = tspm.bistatic_transmission(rough, 2.25, K, th, 0.3, 0.0).sigma0
    assert np.max(s) < 1e-9
    inside = tspm.coherent_transmissivity(rough, 1 / 2.25, K, np.radians([30.0, 50.0]))
    rh, rv = fresnel_cos(1 / 2.25, math.cos(math.radians(30.0)))
    np.testing.assert_allclose(inside[:, 0], [1 - abs(rh) ** 2, 1 - abs(rv) ** 2], rtol=1e-9)
    assert np.all(inside[:, 1] == 0)


def test_eps_to_one_scatters_nothing():
    """ε = 1 + δ: the contrast vanishes, σ⁰_t ∝ δ² (halving δ quarters it to 1e-3) and the
    coherent transmissivity → 1 (every polarization)."""
    rough = GaussianCorrelation(sigma=0.02, length=0.3, dimension=2)
    th, tt, pt = np.radians([10.0, 40.0]), np.radians([5.0, 30.0]), np.array([0.3, 2.0])
    s1 = tspm.bistatic_transmission(rough, 1 + 2e-4, K, th, tt, pt).sigma0
    s2 = tspm.bistatic_transmission(rough, 1 + 1e-4, K, th, tt, pt).sigma0
    diag = np.array([s1[0, 0], s1[1, 1]]), np.array([s2[0, 0], s2[1, 1]])
    np.testing.assert_allclose(diag[0] / diag[1], 4.0, rtol=1e-3)
    assert np.max(s1) < 1e-7
    np.testing.assert_allclose(tspm.coherent_transmissivity(rough, 1 + 1e-4, K, th), 1, atol=1e-8)


@pytest.mark.parametrize("kl", [12.0, 20.0])
def test_agrees_with_po_where_both_hold(kl):
    """kσ = 0.3, small slopes (√2σ/ℓ ≤ 0.035), large kℓ: SPM and PO transmission (first
    order in the slope, the Kirchhoff integral's lowest term) agree within 0.3 dB where the
    lobe is ≥ 1 % of its peak, in and out of the plane (measured ≤ 0.27 dB at kℓ = 12,
    ≤ 0.10 dB at 20), and their coherent transmissivities within 1e-3 (measured 7e-4)."""
    rough = GaussianCorrelation(0.3 / K, kl / K, dimension=2)
    th = math.radians(30.0)
    tt, pt = np.meshgrid(np.radians(np.linspace(0, 60, 121)), np.radians([0, 3, 8, 30]))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        a = tspm.bistatic_transmission(rough, 2.25, K, th, tt, pt, out_of_range="ignore")
        b = tpo.bistatic_transmission(rough, 2.25, K, th, tt, pt, out_of_range="ignore")
    au, bu = a.unpolarized(), b.unpolarized()
    sel = bu > 0.01 * bu.max()
    assert sel.sum() > 10
    assert np.max(np.abs(10 * np.log10(au[sel] / bu[sel]))) < 0.3
    np.testing.assert_allclose(
        a.coherent[:, 0, 0], tpo.coherent_transmissivity(rough, 2.25, K, th), atol=1e-3
    )


def test_policies_and_bad_inputs():
    """Outside SPM's validity (kσ = 0.6): a warning, a ValueError naming kσ, NaN blanks or
    nothing; bad inputs are clear errors."""
    rough = GaussianCorrelation(0.6 / K, 2.0 / K, dimension=2)
    with pytest.warns(tspm.SPMWarning, match="kσ"):
        tspm.bistatic_transmission(rough, 2.25, K, 0.2, 0.1, 0.0)
    with pytest.raises(ValueError, match="kσ"):
        tspm.bistatic_transmission(rough, 2.25, K, 0.2, 0.1, 0.0, out_of_range="raise")
    res = tspm.bistatic_transmission(rough, 2.25, K, 0.2, 0.1, 0.0, out_of_range="nan")
    assert np.all(np.isnan(res.sigma0)) and np.all(res.info["out_of_range"])
    ok = GaussianCorrelation(0.05 / K, 2.0 / K, dimension=2)
    with pytest.raises(ValueError, match="perfect conductor"):
        tspm.bistatic_transmission(ok, "pec", K, 0.1, 0.1, 0.0)
    with pytest.raises(ValueError, match=r"Im\(eps\) < 0"):  # lossy is allowed, gain is not
        tspm.bistatic_transmission(ok, 2.25 - 0.1j, K, 0.1, 0.1, 0.0)
    with pytest.raises(ValueError, match="!= 1 for SPM transmission"):
        tspm.coherent_transmissivity(ok, 1.0, K, 0.1)
    with pytest.raises(ValueError, match="out_of_range"):
        tspm.bistatic_transmission(ok, 2.25, K, 0.1, 0.1, 0.0, out_of_range="maybe")
    with pytest.raises(ValueError, match="theta_i"):
        tspm.bistatic_transmission(ok, 2.25, K, 2.0, 0.1, 0.0)
    with pytest.raises(ValueError, match="1-D profile"):
        tspm.bistatic_transmission(
            GaussianCorrelation(0.01, 1.0, dimension=1), 2.25, K, 0.1, 0.1, 0.0
        )
    with pytest.raises(TypeError, match="roughness"):
        tspm.bistatic_transmission(0.01, 2.25, K, 0.1, 0.1, 0.0)


# ----------------------------------------------------------------------------- SPM BTDF tables
LAM = 1e-6
POLISH = GaussianCorrelation(sigma=0.02e-6, length=1e-6, dimension=2)  # kσ 0.126, kℓ 6.3


@pytest.fixture(scope="module")
def spm_table():
    from emscatter.brdf.btdf_table import build_btdf_table

    return build_btdf_table(POLISH, 2.25, [LAM], method="spm", n_theta=30)


def test_spm_table_equals_the_solver_and_counts_the_coherent_lobe(spm_table):
    """Between the (θt, Δφ) nodes the table interpolates the SPM solver (median / p90 where
    f_t ≥ 1 % of its peak: measured 0.12 % / 0.48 % on the automatic 30 × 83 × 181 grid);
    coherent = the solver's second-order transmissivity; T(0°) = Fresnel 0.96 to 1e-4 (the
    little scattered into reflection)."""
    from emscatter.brdf import frames

    t = spm_table
    assert t.metadata["solver"] == "spm-transmission"
    # as PO and IEM tables: one validity record per wavelength, no shadowing (SPM has none)
    assert len(t.metadata["per_wavelength"]) == 1 and t.metadata["shadowing"] is None
    rng = np.random.default_rng(5)
    n = 4000
    ti = rng.choice(t.theta_i[t.theta_i < 1.2], n)
    tt = rng.uniform(0, 1.4, n)
    dp = rng.uniform(0, math.pi, n)
    got = t.evaluate(frames.directions(ti, np.zeros(n)), frames.directions(math.pi - tt, dp), LAM)
    res = tspm.bistatic_transmission(POLISH, 2.25, K / LAM, ti, tt, dp, math.pi)
    ref = res.unpolarized() / (4 * math.pi * np.cos(ti) * np.cos(tt))
    sel = ref > 0.01 * ref.max()
    err = np.abs(got[sel] / ref[sel] - 1)
    assert np.median(err) < 0.003 and np.percentile(err, 90) < 0.01, np.percentile(err, [50, 90])
    coh = tspm.coherent_transmissivity(POLISH, 2.25, K / LAM, t.theta_i).mean(axis=0)
    np.testing.assert_allclose(t.coherent[0], coh, rtol=1e-12)
    assert t.albedo()[0, 0] == pytest.approx(0.96, abs=1e-4)
    assert 1e-3 < t.incoherent_albedo()[0, 0] < 0.01


def test_spm_brdf_and_btdf_close_the_energy_budget(spm_table):
    """The SPM reflection table (its SPM2 coherent part included) and the SPM BTDF of the same
    polish: |R + T − 1| ≤ 5e-5 at every θi node to 87° (measured ≤ 1.4e-5: the grids'
    quadrature of the diffuse parts, ~0.3 % of them; the theory balances to O((kσ)⁴))."""
    from emscatter.brdf import build_table
    from emscatter.brdf.btdf_table import energy_budget

    br = build_table(
        POLISH, 2.25, [LAM], method="spm", resolution=(30, 90), energy="off", transmission="off"
    )
    b = energy_budget(br, spm_table)
    dev = np.abs(b["R"] + b["T"] - 1)[0]
    assert np.all(dev < 5e-5), dev


def test_spm_table_polarized_is_the_amplitude_products():
    """polarized=True: M₀₀ is the SPM BTDF, and the Mueller matrix's power pairs are the
    solver's σ⁰_t,pq / (4π cosθi cosθt) per polarization pair (the complex first-order
    amplitudes, not a facet's Jones matrix); the cross-pol pair vanishes in the plane."""
    from emscatter.brdf.btdf_table import build_btdf_table
    from emscatter.brdf.mueller import power_pairs

    p = build_btdf_table(
        POLISH, 2.25, [LAM], method="spm", n_theta=6, n_theta_t=24, n_phi=25, polarized=True
    )
    np.testing.assert_array_equal(p.mueller[:, 0, 0], p.values)
    a, b, c = np.meshgrid(p.theta_i, p.theta_t, p.phi_d, indexing="ij")
    s = tspm.bistatic_transmission(POLISH, 2.25, K / LAM, a, b, c, math.pi).sigma0
    ref = s / (4 * math.pi * np.cos(a) * np.cos(b))
    np.testing.assert_allclose(power_pairs(p.mueller[0]), ref, rtol=1e-9, atol=1e-12 * ref.max())
    inplane = ref[0, 1][:, :, [0, -1]]
    assert np.max(inplane) < 1e-12 * ref.max()


def test_spm_table_policies_and_cli(tmp_path):
    """Outside SPM's validity: one warning per wavelength naming the θi nodes, a ValueError
    with out_of_range='raise', unknown options refused; ``emscatter brdf --transmission
    --method spm`` writes the SPM BTDF with its coherent part."""
    from emscatter.brdf.btdf_table import build_btdf_table
    from emscatter.brdf.export_npz import read_btdf_npz
    from emscatter.cli import main

    rough = GaussianCorrelation(sigma=0.1e-6, length=1e-6, dimension=2)  # kσ 0.63
    kw = {"method": "spm", "n_theta": 6, "n_theta_t": 12, "n_phi": 13}
    with pytest.warns(UserWarning, match="small-perturbation") as rec:
        build_btdf_table(rough, 2.25, [LAM], **kw)
    assert len([w for w in rec if "small-perturbation" in str(w.message)]) == 1
    with pytest.raises(ValueError, match="kσ"):
        build_btdf_table(rough, 2.25, [LAM], out_of_range="raise", **kw)
    with pytest.raises(ValueError, match="unknown option"):
        build_btdf_table(POLISH, 2.25, [LAM], rtol=1e-6, **kw)
    with pytest.raises(ValueError, match="'go', 'po' or 'spm'"):
        build_btdf_table(POLISH, 2.25, [LAM], method="mom")
    argv = [
        "brdf", str(tmp_path / "g.npz"), "--material", "2.25", "--sigma", "2e-8", "--length",
        "1e-6", "--wavelengths-nm", "1000", "--method", "spm", "--n-theta", "12", "--n-phi",
        "25", "--transmission", "--quiet",
    ]  # fmt: skip
    assert main(argv) == 0
    bt = read_btdf_npz(tmp_path / "g_btdf.npz")
    assert bt.metadata["solver"] == "spm-transmission"
    assert bt.coherent is not None and bt.coherent[0, 0] == pytest.approx(0.956, abs=2e-3)
