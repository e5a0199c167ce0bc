"""The IEM's Fresnel transition (solvers/iem/terms.py: ``transition_factor``,
``transition_from_sums``; compiled twin ``kernels/lanes.py::transition_gamma``): Wu, Chen, Shi &
Fung (IEEE TGRS 39, 2040, 2001) with the phase variable ``Q = (kσ)²`` (issue 20).

What is checked: the ``F_t`` of the papers is the I2EM complementary coefficient at
normal-incidence reflection, with the opposite sign for h (why γ_h ≠ γ_v is one rule); the
ratio against an independent direct summation; the limits γ → 0 (SPM) and γ → 1 (physical
optics) for every correlation; continuity in θ; numpy = compiled; and the co-pol ratio it
was changed for: HH ≤ VV in backscatter past the Brewster angle of a low-ε soil (Oh,
Sarabandi & Ulaby, IEEE TGRS 30, 370, 1992: p = σhh/σvv ≤ 1 over kσ 0.1–6, θ 10–70°)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.special import gammaln

from emscatter.solvers.iem import model as iem
from emscatter.solvers.iem import terms
from emscatter.solvers.kirchhoff.po import log_nfold
from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation, PowerLawCorrelation

K0 = 2 * math.pi  # wavelength 1 m


def _i2em_f(eps, theta):
    """I2EM backscatter complementary coefficients ``(F_vv(R), F_hh(R))`` as functions of the
    reflection coefficient (Fung, Liu, Chen & Tsay, J. Electromagn. Waves Appl. 16, 689, 2002;
    the form of Ulaby & Long 2014, code 10.1): written out here from the equations."""
    c, s2 = math.cos(theta), math.sin(theta) ** 2
    sq = np.sqrt(eps - s2)

    def fvv(r):
        tp, tm = 1 + r, 1 - r
        return ((s2 / c - sq / eps) * tp**2 - 2 * s2 * tp * tm * (1 / c + 1 / sq)
                + (s2 / c + eps * (1 + s2) / sq) * tm**2)  # fmt: skip

    def fhh(r):
        tp, tm = 1 + r, 1 - r
        return (-(s2 / c - sq) * tp**2 + 2 * s2 * tp * tm * (1 / c + 1 / sq)
                - (s2 / c + (1 + s2) / sq) * tm**2)  # fmt: skip

    return fvv, fhh


@pytest.mark.parametrize("eps", [4 + 0.5j, 15 + 2j, 3.0, 80 + 40j])
@pytest.mark.parametrize("deg", [5.0, 30.0, 55.0, 70.0, 85.0])
def test_ft_is_the_i2em_complementary_coefficient_at_normal_reflection(eps, deg):
    """``F_t = 8R₀² sin²θ (cosθ + q₂)/(cosθ q₂)`` (Wu et al. 2001) equals ``2 F_vv(R_v(0))``,
    and ``2 F_hh(R_h(0)) = −F_t`` with ``R_h(0) = −R_v(0)``: against the same Kirchhoff
    coefficient (``f_hh = −2R_h/cosθ`` at ``R_h(0)`` equals ``f_vv = 2R_v/cosθ`` at
    ``R_v(0)``) the h complementary field has the opposite sign — hence the h ratio with
    ``−F_t``, one rule for both polarizations (Chen et al. 2003's AIEM code)."""
    th = math.radians(deg)
    c, s2 = math.cos(th), math.sin(th) ** 2
    r0 = (np.sqrt(eps) - 1) / (np.sqrt(eps) + 1)
    q2 = np.sqrt(eps - s2)
    ft = 8 * r0**2 * s2 * (c + q2) / (c * q2)
    fvv, fhh = _i2em_f(eps, th)
    np.testing.assert_allclose(2 * fvv(r0), ft, rtol=1e-12)
    np.testing.assert_allclose(2 * fhh(-r0), -ft, rtol=1e-12)


def _direct_gamma(eps, theta, ks, kl, kind):
    """The ratio of the papers by direct summation (no shared code): sums
    ``S(βQ) = Σ (βQ)ⁿ/n! Ŵₙ(2kℓ sinθ)`` with ``Q = (kσ)²``, the exponential (``n/(n² + K²)^{3/2}``)
    or Gaussian (``e^{−K²/4n}/n``) n-fold spectrum, up to a constant."""
    c, s2 = math.cos(theta), math.sin(theta) ** 2
    K = 2 * kl * math.sin(theta)
    n = np.arange(1.0, 4000.0)
    if kind == "exponential":
        lw = np.log(n) - 1.5 * np.log(n * n + K * K)
    else:
        lw = -np.log(n) - K * K / (4 * n)
    Q = ks * ks

    def S(b):
        t = n * math.log(b * Q) - gammaln(n + 1) + lw
        return np.exp(t - t.max()).sum() * math.exp(t.max())

    r0 = (np.sqrt(eps) - 1) / (np.sqrt(eps) + 1)
    q2 = np.sqrt(eps - s2)
    ftc = 8 * r0**2 * s2 * (c + q2) / q2
    s1, s2_, s4 = S(1), S(2), S(4)
    out = []
    for f in (-ftc, ftc):
        num = abs(f + 8 * r0) ** 2 * s1
        den = (abs(f) ** 2 * s1 + 8 * (f * np.conj(r0)).real * math.exp(-Q) * s2_
               + 16 * abs(r0) ** 2 * math.exp(-2 * Q) * s4)  # fmt: skip
        out.append(min(max(1 - num / den, 0.0), 1.0))
    return out


def _gamma(rough, eps, theta, ks):
    theta = np.atleast_1d(np.asarray(theta, float))
    kl = ks / rough.sigma * rough.length
    return terms.transition_factor(eps, np.cos(theta), ks, log_nfold(rough),
                                   2 * kl * np.sin(theta))  # fmt: skip


@pytest.mark.parametrize("kind", ["exponential", "gaussian"])
@pytest.mark.parametrize(("ks", "kl"), [(0.3, 3.0), (1.0, 6.0), (2.0, 6.0), (3.0, 3.0)])
def test_ratio_against_a_direct_summation(kind, ks, kl):
    cls = ExponentialCorrelation if kind == "exponential" else GaussianCorrelation
    rough = cls(ks / K0, kl / K0)
    th = np.radians([0.0, 20.0, 45.0, 70.0])
    gh, gv = _gamma(rough, 4 + 0.5j, th, ks)
    for i, t in enumerate(th):
        ref = _direct_gamma(4 + 0.5j, t, ks, kl, kind)
        np.testing.assert_allclose([gh[i], gv[i]], ref, rtol=1e-7, atol=1e-9)


@pytest.mark.parametrize(
    "cls", [ExponentialCorrelation, GaussianCorrelation,
            lambda s, ell: PowerLawCorrelation(s, ell, hurst=0.8)],
    ids=["exponential", "gaussian", "power-law"],
)  # fmt: skip
def test_limits_for_every_correlation(cls):
    """γ → 0 as kσ → 0 (the IEM's SPM limit keeps R(θ)) and γ → 1 as kσ grows (physical
    optics: R at the local specular angle) at every incidence angle up to 80° — with the
    published variable (kσ cosθ)² the oblique transition stalls (γ_v ≈ 0.2 at kσ = 3, 70°,
    exponential kℓ = 3, ε = 4 + 0.5i)."""
    th = np.radians([0.0, 30.0, 60.0, 70.0, 80.0])
    for eps in (4 + 0.5j, 25 + 5j):
        # kσ = 1e-4: γ = O(Q e^{K²/8}) for a Gaussian (its n = 1 spectrum at the Bragg
        # argument K = 2kℓ sinθ is e^{−K²/4}-small), O(Q) otherwise; kℓ = 3
        small = _gamma(cls(1e-4 / K0, 3.0 / K0), eps, th, 1e-4)
        assert np.all(np.concatenate(small) < 1e-3), small
        big = _gamma(cls(6.0 / K0, 20.0 / K0), eps, th, 6.0)
        assert np.all(np.concatenate(big) > 0.98), big
    gh, gv = _gamma(ExponentialCorrelation(3.0 / K0, 3.0 / K0), 4 + 0.5j, math.radians(70), 3.0)
    assert gv[0] > 0.98 and gh[0] > 0.98  # the 70° case of issue 20


def test_normal_incidence_is_polarization_free_and_the_factor_is_continuous():
    """At θ = 0 ``F_t = 0``: γ_h = γ_v (and ``Q = (kσ cosθ)² = (kσ)²``: the published
    factor). In θ the factor is continuous: over 0 … 89.9° its largest step halves with the
    grid step (0.1° → 0.05°), as for a Lipschitz function (it leaves 0 at a kink, the clip
    of the papers' 1 − S_t/S_t0 at 0)."""
    rough = ExponentialCorrelation(1.2 / K0, 5.0 / K0)
    gh, gv = _gamma(rough, 15 + 2j, 0.0, 1.2)
    assert gh[0] == pytest.approx(gv[0], abs=1e-14)
    steps = []
    for step in (0.1, 0.05):
        th = np.radians(np.arange(0.0, 89.95, step))
        gh, gv = _gamma(rough, 15 + 2j, th, 1.2)
        assert np.all((gh >= 0) & (gh <= 1) & (gv >= 0) & (gv <= 1))
        steps.append(max(np.max(np.abs(np.diff(gh))), np.max(np.abs(np.diff(gv)))))
    assert steps[0] < 0.01 and steps[1] < 0.6 * steps[0], steps


@pytest.mark.parametrize("kind", ["exponential", "gaussian"])
def test_numpy_and_compiled_backscatter_agree(kind, monkeypatch):
    """The transition enters the numpy backscatter path (terms.transition_factor) and the
    compiled kernel (kernels/lanes.py) separately: σ⁰ equal to 1e-7 at 0–89°, including the
    70° edge and grazing incidence."""
    from emscatter.solvers.iem import compiled as iem_jit

    if not iem_jit.enabled():
        pytest.skip("numba kernels off")
    cls = ExponentialCorrelation if kind == "exponential" else GaussianCorrelation
    th = np.radians(np.linspace(0.0, 89.0, 19))
    for ks, kl, eps in ((3.0, 3.0, 4 + 0.5j), (0.4, 8.0, 15 + 2j), (1.5, 4.0, 25 + 5j)):
        rough = cls(ks / K0, kl / K0)
        kw = dict(crosspol=False)
        fast = iem.bistatic(rough, eps, K0, th, th, math.pi, **kw).sigma0
        monkeypatch.setenv("EMSCATTER_KERNELS", "numpy")
        slow = iem.bistatic(rough, eps, K0, th, th, math.pi, **kw).sigma0
        monkeypatch.delenv("EMSCATTER_KERNELS")
        for p in ((0, 0), (1, 1)):
            np.testing.assert_allclose(fast[p], slow[p], rtol=1e-7)


@pytest.mark.parametrize(("ks", "kl"), [(1.0, 6.0), (1.5, 2.6), (2.0, 2.6), (2.0, 6.0),
                                        (3.0, 3.0), (4.0, 4.0)])  # fmt: skip
def test_iem_hh_below_vv_past_the_brewster_angle(ks, kl):
    """ε = 4 + 0.5i (Brewster ≈ 63°), exponential, θ 55–70°: the default IEM alone has
    σhh ≤ σvv (Oh et al. 1992's p ≤ 1). With the published (kσ cosθ)² these had
    hh − vv up to +2.1 dB (kσ = 2, kℓ = 2.6, 70°)."""
    rough = ExponentialCorrelation(ks / K0, kl / K0)
    th = np.radians([55.0, 60.0, 65.0, 70.0])
    s = iem.bistatic(rough, 4 + 0.5j, K0, th, th, math.pi, crosspol=False).sigma0
    assert np.all(s[0, 0] <= s[1, 1]), 10 * np.log10(s[0, 0] / s[1, 1])
