"""Emissivity speed contracts: σ⁰ evaluated in growing chunks (not one direction per call),
the multiple-scattering hv integrated to the accuracy the tolerance needs, the quadrature's
tolerance met or a warning naming the error reached."""

import math
import warnings

import numpy as np
import pytest

import emscatter as em
from emscatter.emissivity import QuadratureWarning, hemispherical_reflectivity, lobe_width

TI = np.radians([0.0, 30.0, 60.0])


def _diag(s):
    z = np.zeros_like(s)
    return np.array([[s, z], [z, s]])


def test_sigma0_chunks_grow_geometrically():
    # Each solver call has a fixed cost (checks, dispatch): one call per direction made the
    # IEM emissivity 50× slower. Chunks grow ×8 up to ~1 s of work, so a fast σ⁰ over a
    # few thousand directions is a handful of calls per estimate.
    calls = []

    def lambert(ts, ps):
        calls.append(ts.shape)
        return _diag(4 * 0.3 * np.cos(TI[:, None, None]) * np.cos(ts))

    r, err, n = hemispherical_reflectivity(lambert, TI, tol=1e-6, budget_s=None)
    np.testing.assert_allclose(r, 0.3, rtol=1e-12)
    per_angle = n // TI.size
    # 1, 8, 64, 512, ... directions per call: ≤ log8(directions) + 2 calls per estimate
    bound = 2 * (math.ceil(math.log(per_angle, 8)) + 2)
    assert len(calls) <= bound, (len(calls), bound, per_angle)
    assert sum(math.prod(s[1:]) for s in calls) == per_angle


def test_mirror_rule_equals_the_full_rule():
    # A lobe off the specular direction but even in py (mirror-symmetric in the plane of
    # incidence): evaluating 0 ≤ α ≤ π with the inner azimuths doubled is the same sum.
    def lobe(ts, ps):
        t = TI[:, None, None]
        px, py = np.sin(ts) * np.cos(ps), np.sin(ts) * np.sin(ps)
        s = np.cos(t) * np.cos(ts) * (1 + 3 * py**2 + px) * np.exp(-((px - 0.2) ** 2) / 0.05)
        return _diag(s)

    full = hemispherical_reflectivity(lobe, TI, tol=1e-8, budget_s=None)
    half = hemispherical_reflectivity(lobe, TI, tol=1e-8, budget_s=None, mirror=True)
    np.testing.assert_allclose(half[0], full[0], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(half[1], full[1], atol=1e-12)
    assert half[2] < 0.6 * full[2]


def _iem_reference(rough, eps, k, ti, tol):
    """The pre-split path: the whole σ⁰ (single + multiple scattering) on one rule, all
    azimuths, plus the coherent reflectivity."""
    from emscatter import solvers

    iem = solvers.get("iem")

    def fn(ts, ps):
        return iem.bistatic(rough, eps, k, ti[..., None, None], ts, ps, 0.0, coherent=False).sigma0

    r, err, _ = hemispherical_reflectivity(fn, ti, finest=lobe_width(rough, k), tol=tol)
    coh = iem.bistatic(rough, eps, k, ti, ti, 0.0, 0.0).coherent
    return 1.0 - coh - r, err


@pytest.mark.parametrize("sigma", [0.0025, 0.01])  # kσ = 0.28 and 1.1 at 5.3 GHz
def test_iem_split_emissivity_matches_the_single_rule(sigma):
    # The split (single scattering on its rule, hv on a coarse adaptive one, half the
    # azimuths by mirror symmetry) agrees with the one-rule integral within the tolerances.
    rough = em.GaussianCorrelation(sigma, 0.10)
    eps, f = 11.3 + 1.5j, 5.3e9
    k = 2 * math.pi * f / 299792458.0
    ti = np.radians([30.0, 60.0])
    ref, ref_err = _iem_reference(rough, eps, k, ti, tol=1e-6)
    assert np.all(ref_err <= 1e-5)  # the reference may stop short of 1e-6: its error counts
    got = em.emissivity(rough, eps, frequency=f, theta_i=ti, method="iem", tol=1e-5,
                        out_of_range="ignore")  # fmt: skip
    assert got.info["quadrature"]["converged"].all()
    assert np.all(np.abs(got.emissivity - ref) <= 1e-5 + ref_err), (got.emissivity, ref)


def _converged_or_warned(call, tol):
    """The contract: the quadrature meets ``tol`` at every angle, or a QuadratureWarning
    names the error reached (and ``info['quadrature']`` records it)."""
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        e = call()
    q = e.info["quadrature"]
    ours = [w for w in seen if issubclass(w.category, QuadratureWarning)]
    if q["converged"].all():
        assert np.all(e.error <= tol) and not ours
    else:
        assert len(ours) == 1 and f"> tol {tol:g}" in str(ours[0].message)
        assert f"{float(np.nanmax(e.error)):.2g}" in str(ours[0].message)
    return e, bool(ours)


def test_quadrature_that_stops_short_warns_with_the_error_reached():
    # tol = 1e-12 is beyond the evaluation budget (1e5 σ⁰ per angle): it must say so.
    rough = em.GaussianCorrelation(0.5, 3.0)
    with pytest.warns(QuadratureWarning, match=r"error \S+ > tol 1e-12 at θi = 60°"):
        e = em.emissivity(rough, 17 + 2j, wavelength=1.0, theta_i=np.radians(60.0),
                          method="go", tol=1e-12, out_of_range="ignore")  # fmt: skip
    assert not e.info["quadrature"]["converged"].all()
    assert np.all(np.isfinite(e.emissivity)) and float(e.error.max()) > 1e-12
    assert em.QuadratureWarning is QuadratureWarning  # public, to filter


@pytest.mark.parametrize("method", ["spm", "go"])
@pytest.mark.parametrize("tol", [1e-4, 1e-7])
def test_grazing_tolerance_met_or_warned(method, tol):
    rough = (
        em.GaussianCorrelation(0.02, 0.5) if method == "spm" else em.GaussianCorrelation(0.5, 3.0)
    )
    ti = np.radians([85.0, 87.0, 89.0])
    _converged_or_warned(
        lambda: em.emissivity(
            rough,
            17 + 2j,
            wavelength=1.0,
            theta_i=ti,
            method=method,
            tol=tol,
            out_of_range="ignore",
        ),  # fmt: skip
        tol,
    )


def test_refinements_evaluate_only_the_angles_not_yet_within_tol():
    # A narrow lobe at one incidence angle and a broad one at the others: with ``restrict``
    # only the narrow-lobe angle is refined further; every angle still meets tol.
    ti = np.radians([10.0, 30.0, 50.0])
    width = np.array([0.5, 0.5, 0.02])

    def make(sel=None):
        t, w = (ti, width) if sel is None else (ti[sel], width[sel])

        def lobe(ts, ps):
            tt, ww = t[:, None, None], w[:, None, None]
            px, py = np.sin(ts) * np.cos(ps), np.sin(ts) * np.sin(ps)
            d2 = (px - np.sin(tt)) ** 2 + py**2
            return _diag(4 * np.cos(tt) * np.cos(ts) * np.exp(-d2 / ww**2) / ww**2 / math.pi)

        return lobe

    kw = dict(finest=0.1, tol=1e-6, budget_s=None)
    full = hemispherical_reflectivity(make(), ti, **kw)
    part = hemispherical_reflectivity(make(), ti, restrict=make, **kw)
    assert np.all(full[1] <= 1e-6) and np.all(part[1] <= 1e-6)
    np.testing.assert_allclose(part[0], full[0], atol=2e-6)
    assert part[2] < 0.7 * full[2], (part[2], full[2])
