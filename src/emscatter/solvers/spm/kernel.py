"""Compiled first-order SPM σ⁰ (2-D isotropic surfaces, one permittivity or PEC).

The same arithmetic, in the same order, as the numpy reference
:func:`emscatter.solvers.spm.model._sigma0_first` / ``_f2_factors`` (Rice 1951; Ulaby, Moore & Fung
1982 vol. II ch. 12 — equations in :mod:`emscatter.solvers.spm.model`), fused into one loop per
geometry so nothing but the four outputs touches memory; ``sin``/``cos``/``exp`` are the
vectorizable ones of :mod:`._vmath`. Agreement with numpy: tests/test_kernels.py.

Spectrum codes: 0 Gaussian ``w = e^{−q²/4}/(4π)``, 1 exponential ``w = (1+q²)^{−3/2}/(2π)``
(``q = Kℓ``, :mod:`emscatter.spectra`).
"""

from __future__ import annotations

import math

import numpy as np

from emscatter.kernels import SPM_EXPONENTIAL as EXPONENTIAL
from emscatter.kernels import SPM_GAUSSIAN as GAUSSIAN
from emscatter.kernels._runtime import inline, jit, run_fused
from emscatter.kernels._vmath import vcos, vexp, vsin


@inline
def _spm1_loop(ti, ts, dphi, pec, er, ei, kl, area, pref, spectrum, hh, hv, vh, vv):
    """σ⁰ [-] into the four 1-D outputs (contiguous, so the loop vectorizes); ``pec`` and
    ``spectrum`` are constants of each compiled copy (:data:`_KERNELS`: a loop-invariant
    ``if`` is not unswitched by LLVM here, so one loop would compute both sides)."""
    em1_2 = (er - 1.0) * (er - 1.0) + ei * ei
    for j in range(ti.size):
        si = vsin(ti[j])
        ss = vsin(ts[j])
        ci = math.sqrt(max(1.0 - si * si, 0.0))
        cs = math.sqrt(max(1.0 - ss * ss, 0.0))
        cphi = vcos(dphi[j])
        s2 = max(1.0 - cphi * cphi, 0.0)
        dk2 = ss * ss + si * si - 2.0 * ss * si * cphi
        q = kl * math.sqrt(max(dk2, 0.0))
        if spectrum == GAUSSIAN:
            w = area * (vexp(-(q * q) / 4.0) / (4.0 * math.pi))
        else:
            t = 1.0 + q * q
            w = area * (1.0 / (t * math.sqrt(t)) / (2.0 * math.pi))
        pw = pref * w
        if pec:
            a = ci * cs * cphi
            fhh = a * a
            b = si * ss - cphi
            fvv = b * b
            fhv = cs * cs * s2
            fvh = ci * ci * s2
        else:
            # _sqrt_upper(er − sin²θ, ei): √(x + i ei), Im ≥ 0
            xi = er - si * si
            ai = math.sqrt(0.5 * (math.sqrt(xi * xi + ei * ei) + abs(xi)))
            bi = 0.5 * ei / (ai if ai > 0 else 1.0)
            rir = ai if xi >= 0 else bi
            rii = bi if xi >= 0 else ai
            xs = er - ss * ss
            as_ = math.sqrt(0.5 * (math.sqrt(xs * xs + ei * ei) + abs(xs)))
            bs = 0.5 * ei / (as_ if as_ > 0 else 1.0)
            rsr = as_ if xs >= 0 else bs
            rsi = bs if xs >= 0 else as_
            cc = ci * cs
            cc2 = em1_2 * (cc * cc)
            dhi = (ci + rir) * (ci + rir) + rii * rii
            dhs = (cs + rsr) * (cs + rsr) + rsi * rsi
            dvi = (er * ci + rir) * (er * ci + rir) + (ei * ci + rii) * (ei * ci + rii)
            dvs = (er * cs + rsr) * (er * cs + rsr) + (ei * cs + rsi) * (ei * cs + rsi)
            sss = si * ss
            nr = er * sss - (rir * rsr - rii * rsi) * cphi
            ni = ei * sss - (rir * rsi + rii * rsr) * cphi
            fhh = cc2 * cphi * cphi / (dhi * dhs)
            fvv = cc2 * (nr * nr + ni * ni) / (dvi * dvs)
            fhv = cc2 * (rir * rir + rii * rii) * s2 / (dvi * dhs)
            fvh = cc2 * (rsr * rsr + rsi * rsi) * s2 / (dhi * dvs)
        hh[j] = pw * fhh
        hv[j] = pw * fhv
        vh[j] = pw * fvh
        vv[j] = pw * fvv


@jit
def _spm1_pec_gaussian(ti, ts, dphi, er, ei, kl, area, pref, hh, hv, vh, vv):
    _spm1_loop(ti, ts, dphi, True, er, ei, kl, area, pref, GAUSSIAN, hh, hv, vh, vv)


@jit
def _spm1_pec_exponential(ti, ts, dphi, er, ei, kl, area, pref, hh, hv, vh, vv):
    _spm1_loop(ti, ts, dphi, True, er, ei, kl, area, pref, EXPONENTIAL, hh, hv, vh, vv)


@jit
def _spm1_dielectric_gaussian(ti, ts, dphi, er, ei, kl, area, pref, hh, hv, vh, vv):
    _spm1_loop(ti, ts, dphi, False, er, ei, kl, area, pref, GAUSSIAN, hh, hv, vh, vv)


@jit
def _spm1_dielectric_exponential(ti, ts, dphi, er, ei, kl, area, pref, hh, hv, vh, vv):
    _spm1_loop(ti, ts, dphi, False, er, ei, kl, area, pref, EXPONENTIAL, hh, hv, vh, vv)


_KERNELS = {
    (True, GAUSSIAN): _spm1_pec_gaussian,
    (True, EXPONENTIAL): _spm1_pec_exponential,
    (False, GAUSSIAN): _spm1_dielectric_gaussian,
    (False, EXPONENTIAL): _spm1_dielectric_exponential,
}


def spm1_sigma0(
    ti: np.ndarray,
    ts: np.ndarray,
    dphi: np.ndarray,
    eps,
    *,
    k: float,
    sigma: float,
    length: float,
    spectrum: int,
    out: np.ndarray,
    threads: int | None = None,
) -> np.ndarray:
    """First-order SPM σ⁰ of an isotropic 2-D surface into ``out`` (2, 2, n) [-].

    ``ti, ts, dphi`` [rad]: flat float64 arrays of one length n (``|dphi| ≤ 1e6``);
    ``eps``: complex scalar or ``"pec"``; ``k`` [rad/m]; ``sigma``, ``length`` [m];
    ``spectrum``: :data:`GAUSSIAN` or :data:`EXPONENTIAL`."""
    pec = isinstance(eps, str)
    e = 0j if pec else complex(eps)
    pref = 16.0 * math.pi * k**4 * sigma**2  # same expression as the numpy path
    consts = (e.real, e.imag, k * length, length * length, pref)

    outs = (out[0, 0], out[0, 1], out[1, 0], out[1, 1])
    run_fused(_KERNELS[(pec, spectrum)], (ti, ts, dphi), consts, outs, threads)
    return out
