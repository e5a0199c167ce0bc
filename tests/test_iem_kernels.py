"""IEM internals against literal references: the simplified complementary coefficients against
the full appendix expressions of Chen et al. (2003) (written out here as the reference), the
backscatter closed forms against the general terms, the Kirchhoff coefficient against
physical optics, the compiled kernels against the numpy path, the series against brute force."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from scipy import special

from emscatter.fresnel import fresnel_cos
from emscatter.solvers.iem import compiled as iem_jit
from emscatter.solvers.iem import model as iem
from emscatter.solvers.iem import series as iem_series
from emscatter.solvers.iem import terms as kern
from emscatter.solvers.kirchhoff import common as kc
from emscatter.solvers.kirchhoff.po import log_nfold
from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation

K = 2 * math.pi


def _appendix_C(si, cs, ss, css, sf, cf, u, v, q, zx, zy, zxp, zyp):
    """C₁…C₆ of Chen et al. (2003), appendix C, with both slope pairs (literal)."""
    C1 = -cf * (-1 - zx * zxp) + sf * zxp * zy
    C2 = -cf * (-cs * q - cs * u * zx - q * si * zxp - si * u * zx * zxp - cs * v * zyp
                - si * v * zx * zyp) + sf * (cs * u * zy + si * u * zxp * zy + q * si * zyp
                                             - cs * u * zyp + si * v * zy * zyp)  # fmt: skip
    C3 = -cf * (si * u - q * si * zx - cs * u * zxp + cs * q * zx * zxp) + sf * (
        -si * v + cs * v * zxp + q * si * zy - cs * q * zxp * zy)  # fmt: skip
    C4 = (-css * sf * (-si * zyp + cs * zx * zyp) - cf * css * (-cs - si * zxp - cs * zy * zyp)
          + ss * (-cs * zx - si * zx * zxp - si * zy * zyp))  # fmt: skip
    C5 = (-css * sf * (-v * zx + v * zxp) - cf * css * (q + u * zxp + v * zy)
          + ss * (q * zx + u * zx * zxp + v * zxp * zy))  # fmt: skip
    C6 = (-css * sf * (-u * zyp + q * zx * zyp) - cf * css * (v * zyp - q * zy * zyp)
          + ss * (v * zx * zyp - u * zy * zyp))  # fmt: skip
    return C1, C2, C3, C4, C5, C6


def _appendix_B(si, cs, ss, css, sf, cf, u, v, q, zx, zy, zxp, zyp):
    """B₁…B₆ (cross-pol), literal."""
    b1 = -css * sf * (-1.0 - zx * zxp) - ss * zy - cf * css * zxp * zy
    b2 = (-css * sf * (-cs * q - cs * u * zx - q * si * zxp - si * u * zx * zxp - cs * v * zyp
                       - si * v * zx * zyp)
          + ss * (-cs * q * zy - q * si * zxp * zy + q * si * zx * zyp - cs * u * zx * zyp
                  - cs * v * zy * zyp)
          - cf * css * (cs * u * zy + si * u * zxp * zy + q * si * zyp - cs * u * zyp
                        + si * v * zy * zyp))  # fmt: skip
    b3 = (-css * sf * (si * u - q * si * zx - cs * u * zxp + cs * q * zx * zxp)
          - cf * css * (-si * v + cs * v * zxp + q * si * zy - cs * q * zxp * zy)
          + ss * (-si * v * zx + cs * v * zx * zxp + si * u * zy - cs * u * zxp * zy))  # fmt: skip
    b4 = -cf * (-si * zyp + cs * zx * zyp) + sf * (-cs - si * zxp - cs * zy * zyp)
    b5 = -cf * (-v * zx + v * zxp) + sf * (q + u * zxp + v * zy)
    b6 = -cf * (-u * zyp + q * zx * zyp) + sf * (v * zyp - q * zy * zyp)
    return b1, b2, b3, b4, b5, b6


def test_reduced_coefficients_match_the_appendix():
    """α × (appendix coefficient at the stationary slopes) = the reduced coefficient, for all
    eight terms and four polarizations, at random bistatic geometries (to rounding)."""
    rng = np.random.default_rng(1)
    eps = 15 + 2j
    for _ in range(30):
        ti, ts = rng.uniform(0.05, 1.4, 2)
        ph = rng.uniform(0, 2 * math.pi)
        si, cs, ss, css, sf, cf = (np.sin(ti), np.cos(ti), np.sin(ts), np.cos(ts), np.sin(ph),
                                   np.cos(ph))  # fmt: skip
        rh, rv = fresnel_cos(eps, cs)
        qt, qts = kern.branch_root(eps - si**2), kern.branch_root(eps - ss**2)
        for name, F, qph, side in kern.complementary_terms(si, cs, ss, css, sf, cf, eps, rh, rv):
            lower = name.startswith("G")
            q = {"up_i": cs, "dn_i": -cs, "up_s": css, "dn_s": -css, "Gup_i": qt, "Gdn_i": -qt,
                 "Gup_s": qts, "Gdn_s": -qts}[name]  # fmt: skip
            qfix = (qt if side == "i" else qts) if lower else (cs if side == "i" else css)
            if side == "i":
                u, v, alpha = -si, 0.0, css - qph
                zx, zy, zxp, zyp = -(ss * cf + u) / alpha, -(ss * sf + v) / alpha, 0.0, 0.0
            else:
                u, v, alpha = -ss * cf, -ss * sf, cs + qph
                zx, zy, zxp, zyp = 0.0, 0.0, (si + u) / alpha, v / alpha
            C = _appendix_C(si, cs, ss, css, sf, cf, u, v, q, zx, zy, zxp, zyp)
            B = _appendix_B(si, cs, ss, css, sf, cf, u, v, q, zx, zy, zxp, zyp)
            ref = kern._combine(C[:5], B, (rh, rv), 0.5 * (rv - rh), qfix, eps, lower)
            for got, want in zip(F, ref, strict=True):
                assert abs(got - alpha * want) <= 1e-9 * (abs(alpha * want) + 1.0)


def test_backscatter_closed_forms_match_the_general_terms():
    th = np.radians(np.linspace(1.0, 85.0, 12))
    si, cs = np.sin(th), np.cos(th)
    for eps, phase in itertools.product((15 + 2j, 3.0 + 0j, -20 + 1j), ("aiem", "aiem-upper")):
        rh, rv = fresnel_cos(eps, cs)
        (u_h, u_v), (gp_h, gp_v, a_p, gm_h, gm_v, a_m) = kern.backscatter_terms(
            si, cs, eps, rh, rv, phase=phase
        )
        terms = kern.complementary_terms(si, cs, si, cs, 0 * si, -1 + 0 * si, eps, rh, rv,
                                         phase=phase)  # fmt: skip
        t = {n: F for n, F, _, _ in terms}
        qph = {n: q for n, _, q, _ in terms}
        # bases: kz ± (the lower-medium height phase): 2kz and 0 with the upper-medium phase
        a = kern.branch_root(eps - si * si).real if phase == "aiem" else cs
        np.testing.assert_allclose(a_p, cs + a, rtol=1e-12)
        np.testing.assert_allclose(a_m, cs - a, atol=1e-12)
        np.testing.assert_allclose(qph["Gdn_s"], -a, rtol=1e-12)
        np.testing.assert_allclose(u_h, 0.25 * (t["up_i"][0] + t["dn_s"][0]), rtol=1e-10)
        np.testing.assert_allclose(u_v, 0.25 * (t["up_i"][3] + t["dn_s"][3]), rtol=1e-10)
        np.testing.assert_allclose(gp_h, 0.25 * (t["Gdn_i"][0] + t["Gup_s"][0]), rtol=1e-10)
        np.testing.assert_allclose(gm_v, 0.25 * t["Gdn_s"][3], rtol=1e-10)
        np.testing.assert_allclose(t["dn_i"][0], -t["up_s"][0], rtol=1e-10)  # they cancel
        np.testing.assert_allclose(np.abs(t["Gup_i"][0]), 0.0, atol=1e-12)  # it vanishes


def test_vector_kirchhoff_coefficient_is_physical_optics_at_the_local_angle():
    """With R at the local specular angle, |(ksz + kz) f_pq|² = |q|⁴ |F_pq|² / k² ×
    (kz + ksz)²/qz² … i.e. (k²/2)|f|² = |q|⁴|F|²/(2 qz²) — the physical-optics amplitude of
    kirchhoff_common (tested there against Mitsuba's roughconductor)."""
    rng = np.random.default_rng(2)
    ti, ts, ps = rng.uniform(0, 1.4, 200), rng.uniform(0, 1.4, 200), rng.uniform(0, 6.28, 200)
    g = kc.geometry(ti, ts, ps, 0.0, 15 + 2j, 2).chunk(signed_azimuth=True)
    rh, rv = fresnel_cos(15 + 2j, g.cos_l)
    xf = kern.kirchhoff_vector(g.si, g.ci, g.ss, g.cs, g.sd, g.cd, rh, rv)
    F2 = kc.fresnel_factors(g, 2)
    for (p, q), f in zip(((0, 0), (0, 1), (1, 0), (1, 1)), xf, strict=True):
        np.testing.assert_allclose(np.abs(f) ** 2, g.q2**2 * F2[p, q], rtol=1e-9, atol=1e-12)


def test_series_equals_brute_force_sum():
    """iem_series against a plain 200-term sum (Q ≤ 7.5 here: the tail beyond is < 1e-100),
    random components, Gaussian and exponential spectra."""
    rng = np.random.default_rng(4)
    for rough in (GaussianCorrelation(0.1, 0.5), ExponentialCorrelation(0.1, 0.5)):
        lw = log_nfold(rough)
        N, J = 40, 4
        la, lx = rng.normal(0, 1, (N, J)), np.log(rng.uniform(0.05, 2.5, (N, J)))
        ph, sx = (
            np.exp(1j * rng.uniform(0, 6.3, (N, J))),
            np.where(rng.random((N, J)) < 0.4, -1.0, 1.0),
        )
        d, K, pref = rng.normal(size=N) + 0j, rng.uniform(0, 15, N), np.zeros(N)
        log_ks2 = math.log(1.2)
        got, _ = iem_series.iem_series(la, lx, ph, sx, d, log_ks2, lw, K, pref, rtol=1e-12)
        n = np.arange(1, 201, dtype=float)
        lnorm = n * log_ks2 - special.gammaln(n + 1) + lw(n[None, :], K[:, None])
        amp = np.einsum("rj,rjn->rn", np.exp(la) * ph,
                        np.where(sx[:, :, None] < 0, (-1.0) ** (n - 1), 1.0)
                        * np.exp((n - 1) * lx[:, :, None]))  # fmt: skip
        amp[:, 0] += d
        ref = np.log(np.sum(np.exp(lnorm) * np.abs(amp) ** 2, axis=1))
        np.testing.assert_allclose(got, ref, rtol=1e-10, atol=1e-10)


@pytest.mark.skipif(
    not iem_jit.enabled(),
    reason="numba kernels off (EMSCATTER_KERNELS=numpy) or numba not installed",
)
@pytest.mark.parametrize(
    "rough",
    [GaussianCorrelation(0.1, 0.5), ExponentialCorrelation(0.2, 0.6),
     GaussianCorrelation(0.3, 0.5, dimension=1)],
    ids=["gaussian", "exponential", "profile"],
)  # fmt: skip
def test_compiled_kernels_agree_with_numpy(rough, monkeypatch):
    """Same σ⁰ (to the series tolerance) from the numba kernels and the numpy reference, for
    bistatic, backscatter (its end-to-end kernel) and the cross-pol integral."""
    rng = np.random.default_rng(5)
    dim = rough.dimension
    ti, ts = rng.uniform(0, 1.4, 60), rng.uniform(0, 1.4, 60)
    ps = rng.uniform(0, 6.28, 60) if dim == 2 else rng.integers(0, 2, 60) * math.pi
    th = np.radians([5.0, 25.0, 45.0, 65.0])
    cases = [(ti, ts, ps), (th, th, math.pi)]
    out = {}
    for mode in ("numba", "numpy"):
        monkeypatch.setenv("EMSCATTER_KERNELS", mode)
        out[mode] = [iem.bistatic(rough, eps, K, *c, coherent=False, rtol=1e-10).sigma0
                     for c in cases for eps in (15 + 2j, "pec")]  # fmt: skip
    for a, b in zip(out["numba"], out["numpy"], strict=True):
        scale = np.max(b, axis=(0, 1), keepdims=True) + 1e-300
        assert np.max(np.abs(a - b) / scale) < 1e-8
