"""The backscatter cross-pol that ``method="auto"`` adds (issue 20), at its new speed: the
fast SPM2 backscatter path against the general σ⁰⁽²²⁾ on the same nodes, and the caches
returning the values they were given."""

from __future__ import annotations

import math

import numpy as np
import pytest

from emscatter.solvers import auto_crosspol
from emscatter.solvers.spm.crosspol import backscatter_hv, sigma0_22
from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation

K = 2 * math.pi


@pytest.mark.parametrize(
    "rough, eps, phi_i",
    [
        (GaussianCorrelation(0.1 / K, 3 / K), 3.0, 0.0),  # half plane (mirror symmetry)
        (ExponentialCorrelation(0.2 / K, 10 / K), 10 + 1j, 0.0),
        (GaussianCorrelation(0.1 / K, 1 / K, length_y=2 / K), 3 + 0.5j, 0.4),  # whole plane
    ],
)
def test_backscatter_hv_is_sigma0_22_on_the_same_nodes(rough, eps, phi_i):
    """The backscatter symmetries (crossed kernel = ladder kernel at −p; g_vh(−p) = −g_hv(p);
    g_hv odd under the plane-of-incidence mirror) are exact: the same value to rounding."""
    theta = np.radians([20.0, 55.0])
    fast = backscatter_hv(rough, eps, K, theta, phi_i, n_radial=6, n_azimuth=6)
    ref = sigma0_22(rough, eps, K, theta, theta, phi_i + math.pi, phi_i, n_radial=6, n_azimuth=6)
    np.testing.assert_allclose(fast, ref[0, 1], rtol=1e-10)
    np.testing.assert_allclose(fast, ref[1, 0], rtol=1e-10)  # reciprocity: hv = vh


def test_supplement_caches_return_what_they_computed():
    from emscatter.solvers.iem.crosspol_resummed import backscatter_resummed

    rough = ExponentialCorrelation(0.2 / K, 5 / K)
    ti = np.radians([30.0, 40.0, 30.0])
    pi_ = np.zeros(3)
    auto_crosspol.clear_cache()
    first, how = auto_crosspol.supplement("spm", rough, 10 + 1j, K, ti, ti, pi_ + math.pi, pi_)
    again, _ = auto_crosspol.supplement("spm", rough, 10 + 1j, K, ti, ti, pi_ + math.pi, pi_)
    assert how == auto_crosspol.RESUMMED and first[0] == first[2] > 0
    np.testing.assert_array_equal(first, again)
    again[0] = -1.0  # a fresh array each call: the cache is not touched
    np.testing.assert_array_equal(auto_crosspol.supplement(
        "spm", rough, 10 + 1j, K, ti, ti, pi_ + math.pi, pi_)[0], first)  # fmt: skip
    direct = backscatter_resummed(
        rough,
        10 + 1j,
        K,
        ti[:2],
        n_nodes=auto_crosspol.RESUMMED_NODES,
        n_azimuth=auto_crosspol.RESUMMED_AZIMUTH_NODES,
    )
    np.testing.assert_allclose(first[:2], direct, rtol=1e-12)
    # the branch's own SPM2 term, stored per unit σ⁴: twice σ reuses the angles' values, × 16
    own, how = auto_crosspol._today("spm", rough, 10 + 1j, K, ti, pi_)
    assert how == auto_crosspol.SPM2_LABEL
    double = ExponentialCorrelation(0.4 / K, 5 / K)
    own2, _ = auto_crosspol._today("spm", double, 10 + 1j, K, ti, pi_)
    np.testing.assert_allclose(own2, 16 * own, rtol=1e-12)
    direct = backscatter_hv(double, 10 + 1j, K, ti[:2], n_radial=6, n_azimuth=6)
    np.testing.assert_allclose(own2[:2], direct, rtol=1e-12)
    auto_crosspol.clear_cache()
    fresh, how = auto_crosspol.supplement("po", rough, "pec", K, ti, ti, pi_ + math.pi, pi_)
    assert how == auto_crosspol.IEM_LABEL  # a conductor: the IEM term
    np.testing.assert_allclose(fresh, auto_crosspol._iem_term(rough, "pec", K, ti, pi_))


@pytest.mark.parametrize(
    "rough",
    [
        ExponentialCorrelation(0.6 / K, 3 / K),
        GaussianCorrelation(0.3 / K, 2 / K, length_y=4 / K),  # anisotropic slopes: Λ(φ)
    ],
)
@pytest.mark.parametrize("eps", [10 + 1j, "pec", "per-angle"])
def test_iem_backscatter_entry_is_the_bistatic_solver_term(rough, eps):
    """``iem.crosspol.backscatter`` (no bistatic geometry, the reversed path's coefficients
    reused) adds exactly what the IEM solver's ``_add_crosspol`` adds in backscatter, and
    hv = vh there."""
    from emscatter.solvers.iem import crosspol as iem_crosspol
    from emscatter.solvers.iem import model as iem
    from emscatter.solvers.kirchhoff.common import geometry

    ti = np.radians([0.0, 10.0, 40.0, 40.0, 70.0, 89.0])
    pi_ = np.array([0.0, 0.3, 1.0, 2.0, 4.0, 6.0])
    if eps == "per-angle":
        eps = np.array([3, 5, 10 + 1j, 20, 30 + 3j, 80 + 40j], dtype=complex)
    g = geometry(ti, ti, pi_ + math.pi, pi_, eps, 2, checked=True)
    sig = np.zeros((2, 2, g.size))
    slope = iem.nominal_rms_slope(rough)
    iem._add_crosspol(sig, rough, g, K, slope, 8)
    fast = iem_crosspol.backscatter(rough, eps, K, ti, pi_, slope=slope, order=8)
    np.testing.assert_allclose(fast, sig[0, 1], rtol=1e-13, atol=0.0)
    np.testing.assert_array_equal(sig[0, 1], sig[1, 0])
    assert np.all(fast > 0)


@pytest.mark.parametrize(
    "cols",
    [
        np.array([[0.7, 0.0, 3.0, 0.1]]),  # one angle
        np.array([[0.7, 0.0, 3.0, 0.1]] * 3),  # one distinct row
        np.array([[0.7, 0.0], [0.2, 0.0], [0.7, 0.0], [-0.0, 1.0]]),  # θ and φ vary
        np.array([[0.7, 0.0, 3.0, 0.1], [0.2, 1.0, 3.0, 0.1], [0.7, 0.0, 3.0, 0.1]]),
        np.array([[0.7, 0.0, 3.0, 0.1], [0.2, 1.0, 4.0, 0.1], [0.2, 1.0, 3.0, 0.2]]),  # 4 vary
    ],
)
def test_unique_rows_is_numpys(cols):
    uniq, inv = auto_crosspol._unique_rows(cols)
    ref, ref_inv = np.unique(cols, axis=0, return_inverse=True)
    np.testing.assert_array_equal(uniq, ref)
    np.testing.assert_array_equal(uniq[inv], cols)
    np.testing.assert_array_equal(inv, ref_inv.reshape(-1))


@pytest.mark.parametrize("eps", [15 + 3.5j, np.array([5 + 1j, 10 + 2j, 20 + 3j])])
def test_auto_iem_in_backscatter_takes_the_remembered_term(eps):
    """``auto``'s IEM branch in backscatter runs the IEM with ``crosspol=False`` and adds the
    per-angle-remembered hv (:data:`auto_crosspol.IEM_BACKSCATTER`): co-pol as
    ``method="iem"``; hv the resummed term for one dielectric ε, the IEM's own
    multiple-scattering term (``method="iem"``'s) for ε given per angle."""
    import emscatter as em
    from emscatter.solvers.iem.crosspol_resummed import backscatter_resummed

    rough = em.roughness("exponential", sigma=0.53 / K, length=8.0 / K)  # NMM3D-like soil
    th = np.radians([20.0, 40.0, 60.0])
    kw = dict(wavelength=2 * math.pi / K, theta_i=th, out_of_range="ignore")
    auto = em.backscatter(rough, eps, **kw)
    assert auto.method == "iem"
    assert auto.info["crosspol"].startswith("multiple scattering (backscatter")
    own = em.backscatter(rough, eps, method="iem", **kw)
    np.testing.assert_allclose(auto.sigma0[[0, 1], [0, 1]], own.sigma0[[0, 1], [0, 1]],
                               rtol=1e-12, atol=0.0)  # fmt: skip
    if np.ndim(eps) == 0:
        ref = backscatter_resummed(
            rough,
            eps,
            K,
            th,
            n_nodes=auto_crosspol.RESUMMED_NODES,
            n_azimuth=auto_crosspol.RESUMMED_AZIMUTH_NODES,
        )
        np.testing.assert_allclose(auto.sigma0[0, 1], ref, rtol=1e-12, atol=0.0)
        assert np.all(auto.sigma0[0, 1] > own.sigma0[0, 1])  # the IEM term is low (issue 20)
    else:
        np.testing.assert_allclose(auto.sigma0, own.sigma0, rtol=1e-12, atol=0.0)
    np.testing.assert_array_equal(auto.sigma0[0, 1], auto.sigma0[1, 0])
    assert np.all(auto.sigma0[0, 1] > 0)
    again = em.backscatter(rough, eps, **kw)  # answered from the per-angle memory
    np.testing.assert_array_equal(again.sigma0, auto.sigma0)


@pytest.mark.parametrize("kind", ["gaussian", "exponential"])
def test_spm_branch_hv_tends_to_sigma0_22(kind):
    """At small kσ the resummed hv ``auto`` adds on its ``spm`` branch is second-order SPM's
    σ⁰⁽²²⁾ (the exact fourth-order hv; relative O((kσ cosθ)²), by construction) — the value
    that branch added before — to 0.05 dB (nodes 10 vs 6)."""
    import emscatter as em

    rough = em.roughness(kind, sigma=0.05 / K, length=3.0 / K)
    th = np.radians([20.0, 40.0, 60.0])
    res = em.backscatter(rough, 9 + 1j, wavelength=2 * math.pi / K, theta_i=th)
    assert res.method == "spm" and res.info["crosspol_added"] == auto_crosspol.RESUMMED
    ref = backscatter_hv(rough, 9 + 1j, K, th, n_radial=16, n_azimuth=16)
    np.testing.assert_allclose(res.sigma0[0, 1], ref, rtol=0.012)
    np.testing.assert_array_equal(res.sigma0[0, 1], res.sigma0[1, 0])


@pytest.mark.parametrize("name", ["spm", "po", "go", auto_crosspol.IEM_BACKSCATTER])
def test_every_branch_adds_the_same_resummed_hv_faded_at_its_limit(name):
    """One hv on every branch (so none steps at a method switch); between
    kσ cosθ = 2.5 and 3 it fades linearly into the branch's own term, which alone holds
    beyond: continuous in θ at both ends; a conductor keeps the branch's own term."""
    from emscatter.solvers.iem.crosspol_resummed import backscatter_resummed

    rough = GaussianCorrelation(3.2 / K, 12.0 / K)
    c = np.array([3.0 + 1e-9, 3.0 - 1e-9, 2.75, 2.5 + 1e-9, 2.5 - 1e-9, 1.0]) / 3.2
    ti = np.arccos(c)
    pi_ = np.zeros_like(ti)
    auto_crosspol.clear_cache()
    hv, how = auto_crosspol.supplement(name, rough, 15 + 2j, K, ti, ti, pi_ + math.pi, pi_)
    assert how.startswith(auto_crosspol.RESUMMED) and "faded" in how
    own, _ = auto_crosspol._today(name, rough, 15 + 2j, K, ti, pi_)
    ok = ti > np.arccos(3.0 / 3.2)  # kσ cosθ < 3
    res = np.zeros_like(ti)
    res[ok] = backscatter_resummed(
        rough,
        15 + 2j,
        K,
        ti[ok],
        n_nodes=auto_crosspol.RESUMMED_NODES,
        n_azimuth=auto_crosspol.RESUMMED_AZIMUTH_NODES,
    )
    np.testing.assert_allclose(hv[0], own[0], rtol=1e-12)  # beyond: the branch's own
    np.testing.assert_allclose(hv[[1, 4, 5]], [own[1], res[4], res[5]], rtol=1e-6)  # ends
    np.testing.assert_allclose(hv[2], 0.5 * (own[2] + res[2]), rtol=1e-12)  # halfway
    pec, how = auto_crosspol.supplement(name, rough, "pec", K, ti, ti, pi_ + math.pi, pi_)
    assert how == auto_crosspol.IEM_LABEL and np.all(pec > 0)


def test_bistatic_and_backscatter_agree_at_a_backscatter_geometry():
    """A bistatic grid through the backscatter direction gets there the hv ``backscatter``
    gives (the IEM branch, run with its own cross-pol in a bistatic call, has its term
    replaced by the resummed one there); with an IEM cross-pol option the solver's own stays."""
    import emscatter as em

    rough = em.roughness("exponential", sigma=0.5 / K, length=3.0 / K)
    th = 0.7
    ts = np.array([0.6, 0.7, 0.8])
    kw = dict(wavelength=2 * math.pi / K, out_of_range="ignore")
    mono = em.backscatter(rough, 15 + 3.5j, theta_i=th, **kw)
    bi = em.bistatic(rough, 15 + 3.5j, theta_i=th, theta_s=ts, phi_s=math.pi, **kw)
    assert bi.method == mono.method == "iem"
    np.testing.assert_allclose(bi.sigma0[[0, 1], [1, 0], 1], mono.sigma0[[0, 1], [1, 0]], rtol=1e-9)
    # (co-pol: the IEM's bistatic and exact-backscatter paths, ~1e-9 apart)
    np.testing.assert_allclose(bi.sigma0[[0, 1], [0, 1], 1], mono.sigma0[[0, 1], [0, 1]], rtol=1e-7)
    assert bi.info["crosspol_added"].startswith(auto_crosspol.RESUMMED)
    own = em.bistatic(rough, 15 + 3.5j, theta_i=th, theta_s=ts, phi_s=math.pi, method="iem", **kw)
    np.testing.assert_array_equal(bi.sigma0[:, :, [0, 2]], own.sigma0[:, :, [0, 2]])
    assert bi.sigma0[0, 1, 1] > own.sigma0[0, 1, 1]
    opt = em.bistatic(rough, 15 + 3.5j, theta_i=th, theta_s=ts, phi_s=math.pi,
                      crosspol_order=4, **kw)  # fmt: skip
    ref = em.bistatic(rough, 15 + 3.5j, theta_i=th, theta_s=ts, phi_s=math.pi, method="iem",
                      crosspol_order=4, **kw)  # fmt: skip
    np.testing.assert_allclose(opt.sigma0, ref.sigma0, rtol=1e-12)


@pytest.mark.parametrize(
    "rough, eps",
    [
        (ExponentialCorrelation(1.32 / K, 0.5 / K), 30 + 3j),  # issue 20's grid corners
        (ExponentialCorrelation(0.13 / K, 20 / K), 3 + 0j),
        (GaussianCorrelation(2.5 / K, 20 / K), 3 + 1j),  # the box's rough corner
        (GaussianCorrelation(0.13 / K, 0.5 / K), 30 + 3j),
        (ExponentialCorrelation(2.5 / K, 3.0 / K), 3 + 1j),
    ],
)
def test_auto_node_rule_converged(rough, eps):
    """``auto``'s RESUMMED_NODES × RESUMMED_AZIMUTH_NODES rule within 0.05 dB of the 16 × 16
    default (measured max over the 1176-angle box: 0.046 dB), at 10–70°."""
    from emscatter.solvers.iem.crosspol_resummed import backscatter_resummed

    th = np.radians(np.linspace(10.0, 70.0, 7))
    th = th[K * rough.sigma * np.cos(th) <= 3.0]
    fast = backscatter_resummed(rough, eps, K, th, n_nodes=auto_crosspol.RESUMMED_NODES,
                                n_azimuth=auto_crosspol.RESUMMED_AZIMUTH_NODES)  # fmt: skip
    ref = backscatter_resummed(rough, eps, K, th, n_nodes=16)
    assert np.max(np.abs(10 * np.log10(fast / ref))) <= 0.05
