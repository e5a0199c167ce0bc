"""IEM transmission (:mod:`emscatter.solvers.iem.transmission`): the flat limit (Fresnel T), the
small-kσ limit (first-order SPM transmission), the large-kσ limit (PO / Walter GO), R + T with
the IEM reflection, ε-weighted reciprocity, the policies and the IEM BTDF table."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from emscatter.solvers.iem import model as iem
from emscatter.solvers.iem import transmission as tiem
from emscatter.solvers.kirchhoff.transmission import go as tgo
from emscatter.solvers.kirchhoff.transmission import po as tpo
from emscatter.solvers.spm import transmission as tspm
from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation
from transmission_checks import K, assert_eps_weighted_reciprocity
from transmission_checks import fresnel_t as _fresnel_t
from transmission_checks import hemisphere as _hemisphere


def test_flat_limit_is_fresnel_transmission():
    """σ → 0: coherent = Fresnel T per polarization (both first_order modes), σ⁰_t → 0."""
    rough = GaussianCorrelation(sigma=1e-6, length=2.0, dimension=2)
    th = np.radians([0.0, 20.0, 45.0, 65.0])
    for fo in ("spm", "kirchhoff"):
        res = tiem.bistatic_transmission(rough, 2.25, K, th, 0.3, 0.2, 0.0, first_order=fo)
        np.testing.assert_allclose(res.coherent, _fresnel_t(2.25, th), rtol=1e-9)
        assert np.max(res.sigma0) < 1e-8
    inside = tiem.coherent_transmissivity(rough, 1 / 2.25, K, np.radians([10.0, 30.0, 50.0]))
    np.testing.assert_allclose(inside[:, :2], _fresnel_t(1 / 2.25 + 0j, np.radians([10, 30])),
                               rtol=1e-9)  # fmt: skip
    assert np.all(inside[:, 2] == 0)  # beyond the critical angle 41.8°


@pytest.mark.parametrize("ks", [0.05, 0.1])
def test_small_k_sigma_is_first_order_spm(ks):
    """kσ 0.05–0.1, kℓ 6.3: σ⁰_t equals first-order SPM transmission within 0.5 dB (measured
    0.005 / 0.02 dB) where SPM ≥ 1 % of its peak, all four polarizations, out of the plane too;
    the Kirchhoff series alone (first_order="kirchhoff") is not SPM there (> 2 dB somewhere),
    so the first-order term is what makes the limit."""
    rough = GaussianCorrelation(sigma=ks / K, length=1.0, dimension=2)
    rng = np.random.default_rng(2)
    n = 3000
    ti, tt = rng.uniform(0, 1.2, n), rng.uniform(0, 1.3, n)
    pt = rng.uniform(-math.pi, math.pi, n)
    a = tiem.bistatic_transmission(rough, 2.25, K, ti, tt, pt, 0.0).sigma0
    b = tspm.bistatic_transmission(rough, 2.25, K, ti, tt, pt, 0.0).sigma0
    c = tiem.bistatic_transmission(rough, 2.25, K, ti, tt, pt, 0.0, first_order="kirchhoff")
    sel = b > 0.01 * b.max()
    assert sel.sum() > 1000
    assert np.max(np.abs(10 * np.log10(a[sel] / b[sel]))) < 0.5
    with np.errstate(divide="ignore"):
        assert np.max(np.abs(10 * np.log10(c.sigma0[sel] / b[sel]))) > 2.0


def test_large_k_sigma_tends_to_po_and_go():
    """kσ 6.3, kℓ 63 (rms slope 0.14): σ⁰_t equals PO within 1 dB in the lobe (where PO ≥ 1 %
    of its peak; measured max 1e-6 dB: the first-order term carries e^{−Q}, Q ≈ 10) and
    Walter et al.'s GO (no shadowing) within 1 dB in the median (measured 0.2 dB)."""
    rough = GaussianCorrelation(sigma=1.0, length=10.0, dimension=2)
    rng = np.random.default_rng(4)
    n = 3000
    ti = rng.uniform(0, 1.0, n)
    tt = np.clip(np.arcsin(np.sin(ti) / 1.5) + rng.normal(0, 0.1, n), 0, 1.4)
    pt = rng.normal(0, 0.3, n)  # around the refracted direction (φt = φi)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # kσ 6.3 > 3: outside the IEM's report, on purpose
        a = tiem.bistatic_transmission(rough, 2.25, K, ti, tt, pt, 0.0).unpolarized()
        b = tpo.bistatic_transmission(rough, 2.25, K, ti, tt, pt, 0.0).unpolarized()
    g = tgo.bistatic_transmission(rough, 2.25, K, ti, tt, pt, 0.0, shadowing=False).unpolarized()
    sel = b > 0.01 * b.max()
    assert sel.sum() > 200
    assert np.max(np.abs(10 * np.log10(a[sel] / b[sel]))) < 1.0
    sel = g > 0.01 * g.max()
    assert np.median(np.abs(10 * np.log10(a[sel] / g[sel]))) < 1.0


def test_middle_range_moves_from_spm_to_po():
    """The middle range at fixed rms slope (σ/ℓ = 0.16, θi = 30°, co-pol near the refracted
    direction): at kσ 1 the IEM is neither SPM nor PO (> 0.3 dB from each), and its largest
    distance to PO shrinks monotonically as kσ grows 1 → 2 → 4 (the first-order term fades as
    e^{−Q}); measured 2.2, 0.36, 0.005 dB."""
    ti = math.radians(30)
    tt = np.radians(np.linspace(2, 40, 20))
    pt = np.radians([0.0, 40.0])[:, None]
    kw = {"out_of_range": "ignore"}
    dist = []
    for ks in (1.0, 2.0, 4.0):
        rough = GaussianCorrelation(sigma=ks / K, length=ks / K / 0.16, dimension=2)
        a = tiem.bistatic_transmission(rough, 2.25, K, ti, tt, pt, 0.0, **kw).sigma0
        p = tpo.bistatic_transmission(rough, 2.25, K, ti, tt, pt, 0.0, **kw).sigma0
        co = np.stack([a[0, 0], a[1, 1]]), np.stack([p[0, 0], p[1, 1]])
        ok = co[1] > 1e-3 * co[1].max()
        dist.append(np.max(np.abs(10 * np.log10(co[0][ok] / co[1][ok]))))
        if ks == 1.0:
            s = tspm.bistatic_transmission(rough, 2.25, K, ti, tt, pt, 0.0, **kw).sigma0
            cs = np.stack([s[0, 0], s[1, 1]])
            assert np.max(np.abs(10 * np.log10(co[0][ok] / cs[ok]))) > 0.3
            assert dist[0] > 0.3
    assert dist[0] > dist[1] > dist[2]


def _budget(rough, th, n=48):
    """(R, T) per incident polarization: the IEM reflection (coherent + σ⁰, cross-pol
    included) and this transmission (coherent + σ⁰_t), Gauss–Legendre hemispheres."""
    tt, pt, wt = _hemisphere(n, math.asin(1 / 1.5))
    res = tiem.bistatic_transmission(rough, 2.25, K, th, tt, pt, 0.0, out_of_range="ignore")
    t = (res.sigma0.sum(axis=0) * wt).sum(axis=(-1, -2)) / (4 * math.pi * math.cos(th))
    ts, ps, ws = _hemisphere(n)
    rr = iem.bistatic(rough, 2.25, K, th, ts, ps, 0.0)
    r = (rr.sigma0.sum(axis=0) * ws).sum(axis=(-1, -2)) / (4 * math.pi * math.cos(th))
    return r + rr.coherent[:, 0, 0], t + res.coherent[:, 0, 0]


@pytest.mark.parametrize("ks, kl", [(0.3, 6.3), (1.0, 12.6), (1.9, 18.8)])
def test_reflection_plus_transmission_with_the_iem_reflection(ks, kl):
    """ε = 2.25, θi 0/30/60°: R + T ≤ 1 + 3e-3 (quadrature error < 1e-4: n = 96 gives the same
    to 1e-4) and |1 − (R + T)| ≤ 1.5e-2. Measured residual 1 − (R + T) (h, v):
    kσ 0.3: ≤ 8e-4; kσ 1.0: 0°/30° ≤ 2e-4, 60° +6.8e-3 / −8e-4; kσ 1.9: 60° +9.5e-3 / −1.9e-3.
    Without the first-order term in the mean field T_v alone reached 1.022 (kσ 1, 60°)."""
    rough = GaussianCorrelation(sigma=ks / K, length=kl / K, dimension=2)
    for deg in (0.0, 30.0, 60.0):
        r, t = _budget(rough, math.radians(deg))
        total = r + t
        assert np.all(total <= 1 + 3e-3), (deg, total)
        assert np.all(np.abs(1 - total) <= 1.5e-2), (deg, total)
        assert np.all(t <= 1)


def test_energy_exponential_spectrum():
    """Exponential, kσ 0.3, kℓ 3, θi 0/40/60°: |1 − (R + T)| ≤ 1.5e-2 (measured −6.9e-3 …
    +9e-4; the exponential IEM reflection's and the first-order term's own energy errors)."""
    rough = ExponentialCorrelation(sigma=0.3 / K, length=3 / K, dimension=2)
    for deg in (0.0, 40.0, 60.0):
        r, t = _budget(rough, math.radians(deg))
        assert np.all(np.abs(1 - (r + t)) <= 1.5e-2), (deg, r + t)


@pytest.mark.parametrize(
    "rough",
    [
        GaussianCorrelation(sigma=0.1, length=1.0, dimension=2),
        ExponentialCorrelation(sigma=0.05, length=1.0, dimension=2),
        GaussianCorrelation(sigma=0.1, length=1.0, length_y=1.6, dimension=2),
    ],
    ids=["gauss", "exponential", "anisotropic"],
)
def test_reciprocity_eps_weighted(rough):
    """σ⁰_t,pq(ε, k; k̂i → k̂t) = ε σ⁰_t,qp(1/ε, ηk; −k̂t → −k̂i) (the radiance BTDF's η² law,
    Walter et al. 2007 eq. 21; PO, SPM and e^{−Q} obey it term by term)."""
    assert_eps_weighted_reciprocity(tiem.bistatic_transmission, rough, lit_share=1e-6,
                                    theta_i_max=1.1)  # fmt: skip


def test_policies_and_bad_inputs():
    rough = GaussianCorrelation(sigma=0.1, length=1.0, dimension=2)
    with pytest.raises(ValueError, match="perfect conductor"):
        tiem.bistatic_transmission(rough, "pec", K, 0.1, 0.1, 0.0)
    with pytest.raises(ValueError, match="eps must be real"):
        tiem.bistatic_transmission(rough, 2.25 + 0.1j, K, 0.1, 0.1, 0.0)
    with pytest.raises(ValueError, match="out_of_range"):
        tiem.bistatic_transmission(rough, 2.25, K, 0.1, 0.1, 0.0, out_of_range="maybe")
    with pytest.raises(ValueError, match="first_order"):
        tiem.bistatic_transmission(rough, 2.25, K, 0.1, 0.1, 0.0, first_order="exact")
    with pytest.raises(ValueError, match="complementary must be None"):
        tiem.bistatic_transmission(rough, 2.25, K, 0.1, 0.1, 0.0, complementary="aiem")
    with pytest.raises(ValueError, match="theta_i"):
        tiem.bistatic_transmission(rough, 2.25, K, 2.0, 0.1, 0.0)
    with pytest.raises(ValueError, match="1-D profile"):
        tiem.bistatic_transmission(GaussianCorrelation(0.1, 1.0, dimension=1), 2.25, K, 0, 0, 0)
    th = np.radians([10.0, 80.0])  # 80° > the IEM's 70°
    with pytest.warns(tiem.IEMWarning, match="IEM"):
        tiem.bistatic_transmission(rough, 2.25, K, th, 0.3, 0.0)
    with pytest.raises(ValueError, match="theta_i"):
        tiem.bistatic_transmission(rough, 2.25, K, th, 0.3, 0.0, out_of_range="raise")
    res = tiem.bistatic_transmission(rough, 2.25, K, th, 0.3, 0.0, out_of_range="nan")
    assert np.all(np.isfinite(res.sigma0[..., 0])) and np.all(np.isnan(res.sigma0[..., 1]))
    assert np.isnan(res.coherent[0, 1]) and list(res.info["out_of_range"]) == [False, True]


# ----------------------------------------------------------------------------- IEM BTDF tables
LAM = 1e-6
GLASS = GaussianCorrelation(sigma=0.16e-6, length=1.6e-6, dimension=2)  # kσ 1.0, kℓ 10


@pytest.fixture(scope="module")
def iem_table():
    from emscatter.brdf.btdf_table import build_btdf_table

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # θi nodes > 70° are outside the IEM: tested below
        return build_btdf_table(GLASS, 2.25, [LAM], method="iem", n_theta=18, n_phi=91)


def test_iem_table_equals_the_solver_at_nodes(iem_table):
    """At the (θi, θt, Δφ) nodes the table holds bistatic_transmission's f_t exactly (1e-12),
    its coherent part is coherent_transmissivity, and albedo = incoherent + coherent."""
    from emscatter.brdf import frames

    t = iem_table
    assert t.metadata["solver"] == "iem-transmission"
    i, jt, jp = np.meshgrid([0, 3, 7], [5, 20, 40], [0, 45, 90], indexing="ij")
    ti, tt, dp = t.theta_i[i.ravel()], t.theta_t[jt.ravel()], t.phi_d[jp.ravel()]
    res = tiem.bistatic_transmission(GLASS, 2.25, 2 * math.pi / LAM, ti, tt, dp, math.pi)
    ref = res.unpolarized() / (4 * math.pi * np.cos(ti) * np.cos(tt))
    np.testing.assert_allclose(t.values[0, i.ravel(), jt.ravel(), jp.ravel()], ref, rtol=1e-12)
    wi = frames.directions(ti, np.zeros(ti.size))
    wo = frames.directions(math.pi - tt, dp)
    np.testing.assert_allclose(t.evaluate(wi, wo, LAM), ref, rtol=1e-6, atol=1e-12 * ref.max())
    coh = tiem.coherent_transmissivity(GLASS, 2.25, 2 * math.pi / LAM, t.theta_i).mean(axis=0)
    np.testing.assert_allclose(t.coherent[0], coh, rtol=1e-9)
    np.testing.assert_allclose(t.albedo() - t.incoherent_albedo(), t.coherent)


def test_iem_brdf_and_btdf_energy(iem_table):
    """An IEM reflection table and this BTDF (kσ 1, kℓ 10): R + T ≤ 1 + 3e-3 (the grids'
    quadrature error) and ≥ 0.99 at every θi ≤ 60° node (measured 0.9963–1.0012)."""
    from emscatter.brdf import build_table
    from emscatter.brdf.btdf_table import energy_budget

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        br = build_table(
            GLASS, 2.25, [LAM], method="iem", resolution=(18, 72), energy="off",
            transmission="off",
        )  # fmt: skip
    b = energy_budget(br, iem_table)
    ok = b["theta_i_deg"] <= 60
    total = (b["R"] + b["T"])[0, ok]
    assert np.all(total <= 1 + 3e-3), total
    assert np.all(total >= 0.99), total


def test_iem_table_policies_and_cli(tmp_path):
    """Bad options are clear errors; the IEM validity warns once per wavelength naming the
    θi nodes; ``emscatter brdf --transmission --method iem`` writes an IEM BTDF."""
    from emscatter.brdf.btdf_table import build_btdf_table
    from emscatter.brdf.export_npz import read_btdf_npz
    from emscatter.cli import main

    kw = {"method": "iem", "n_theta": 6, "n_theta_t": 12, "n_phi": 13}
    with pytest.raises(ValueError, match="polarized=True is not available"):
        build_btdf_table(GLASS, 2.25, [LAM], polarized=True, **kw)
    with pytest.raises(ValueError, match="unknown option"):
        build_btdf_table(GLASS, 2.25, [LAM], shadowing=True, **kw)
    with pytest.raises(ValueError, match="first_order"):
        build_btdf_table(GLASS, 2.25, [LAM], first_order="exact", **kw)
    with pytest.warns(UserWarning, match="outside the IEM's") as rec:
        build_btdf_table(GLASS, 2.25, [LAM], **kw)
    assert len([w for w in rec if "IEM's" in str(w.message)]) == 1
    with pytest.raises(ValueError, match="theta_i"):
        build_btdf_table(GLASS, 2.25, [LAM], out_of_range="raise", **kw)
    argv = [
        "brdf", str(tmp_path / "g.npz"), "--material", "2.25", "--sigma", "1.6e-7", "--length",
        "1.6e-6", "--wavelengths-nm", "1000", "--method", "iem", "--n-theta", "8", "--n-phi",
        "25", "--out-of-range", "ignore", "--transmission", "--quiet",
    ]  # fmt: skip
    assert main(argv) == 0
    bt = read_btdf_npz(tmp_path / "g_btdf.npz")
    assert bt.metadata["solver"] == "iem-transmission"
    assert bt.coherent is not None and bt.coherent[0, 0] > 0.3
    assert main([*argv, "--polarized"]) != 0  # a clear error, not a traceback
