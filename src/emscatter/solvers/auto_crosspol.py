"""Backscatter cross-polarization for the closed-form branches of ``method="auto"``.

In backscatter (``θs = θi``, ``φs = φi + π``) the single-scattering cross-polarized σ⁰ of every
closed-form method vanishes: first-order SPM (its ``f_hv ∝ sin(φs − φi)``, Rice 1951), and the
Kirchhoff methods PO and GO (the facet that reflects back is normal to the incident direction,
so ``R_h`` and ``R_v`` act on one polarization each, no mixing; Ulaby, Moore & Fung 1982 vol. II
§12-4). A radar user's ``hv`` there is a second-order effect, which these branches add:

* ``spm`` on a dielectric Gaussian or exponential surface: the second-order SPM cross-pol
  σ⁰⁽²²⁾ (:func:`emscatter.solvers.spm.crosspol.sigma0_22`), which in the plane of incidence —
  backscatter
  included — *is* the whole fourth-order (``σ⁴``) hv of perturbation theory (the exact
  small-roughness limit). Nodes ``6 × 6`` per segment: within 0.002 dB of the ``16 × 16``
  default (Gaussian kσ = 0.3, kℓ = 3, ε = 3, 40°: −49.405 vs −49.407 dB), ~6 ms per angle.
  For a conductor (PEC, Re ε < 0, ``|ε| ≥ 100``; SPM2's TM kernel is singular at the horizon)
  or a power-law spectrum the IEM term below is used instead.
* ``po``, ``go`` (and ``spm`` where SPM2 cannot): the IEM's multiple-scattering cross-pol
  (:func:`emscatter.solvers.iem.crosspol.multiple_scattering`, Fung, Li & Chen 1992 appendix; Fung
  1994; in
  backscatter the form of Ulaby & Long 2014 code 10.1 and SMRT's ``iiem_fung02``). Why it
  belongs to the Kirchhoff regimes: it is the second bounce of the same tangent-plane field
  (Kirchhoff field at an arbitrary intermediate direction, then re-radiated), and its spectral
  weights are the physical-optics series ``T(Q, K) = e^{−Q} Σ Qⁿ⁻¹/n! wₙ(K)`` that
  :mod:`emscatter.solvers.kirchhoff.po` sums — at large kσ that series tends to the slope density of
  geometric optics (stationary phase), so the term becomes a double-bounce facet model,
  with the intermediate wave's shadowing ``S_m``. Beyond the IEM's own ``kσ ≤ 3`` it is that
  extrapolation (the term used is named in ``info["crosspol_added"]``); at kσ ≳ 10 it
  grows to within ~3 dB of the co-pol (ε = 15 + 2i) and above it for a PEC (kσ = 10,
  kℓ = 50): not checked against exact solutions there. It is 4–5 dB below exact 3-D solutions on
  published comparisons
  (issue 20: emscatter IEM −4.4 dB bias, SMRT −5.1, pyi2em −4.6): a lower bound.

What stays zero, by physics: a 1-D profile (a 2-D problem has no cross-polarization), a flat
surface (σ = 0), and bistatic geometries in the plane of incidence for these branches'
single scattering (first-order SPM, PO, GO: the in-plane first-order terms vanish; the
second-order terms above are added in backscatter only — SPM2 costs ~6 ms per geometry). Out
of the plane the branches' own single-scattering cross-pol is returned unchanged.
"""

from __future__ import annotations

import math

import numpy as np

from ..fresnel import is_pec

__all__ = ["backscatter_mask", "supplement"]

_BACK_TOL = 1e-9
SPM2_NODES = 6


def backscatter_mask(ti, ts, ps, pi_) -> np.ndarray:
    """True where ``θs = θi`` and ``φs = φi + π`` (to 1e-9 rad), broadcast shape."""
    ti, ts, ps, pi_ = np.broadcast_arrays(ti, ts, ps, pi_)
    d = np.mod(ps - pi_, 2 * math.pi)
    return (np.abs(ti - ts) <= 1e-12) & (np.abs(d - math.pi) <= _BACK_TOL)


def _spm2_ok(rough, eps) -> bool:
    from ..spectra import ExponentialCorrelation, GaussianCorrelation
    from .measured import medium_class

    if type(rough) not in (GaussianCorrelation, ExponentialCorrelation):
        return False
    return not is_pec(eps) and np.ndim(eps) == 0 and medium_class(eps) == "dielectric"


def _iem_term(rough, eps, k, ti, pi_):
    """The IEM multiple-scattering hv (= vh) in backscatter at flat angles ``ti``, ``pi_``."""
    from .iem import model as iem
    from .kirchhoff.common import geometry

    g = geometry(ti, ti, pi_ + math.pi, pi_, eps, 2, checked=True)
    sig = np.zeros((2, 2, g.size))
    iem._add_crosspol(sig, rough, g, k, iem.nominal_rms_slope(rough), 8)
    return sig[0, 1]


def supplement(name: str, rough, eps, k: float, ti, ts, ps, pi_):
    """``(hv, label)``: the backscatter cross-pol σ⁰ [-] to add to method ``name``'s hv and vh,
    in the broadcast shape of the angles [rad] (0 away from backscatter), or ``(None, None)``
    where nothing is added (module docstring). ``eps`` complex scalar or array, or "pec"."""
    if name not in ("spm", "po", "go") or rough.dimension != 2 or rough.sigma == 0:
        return None, None
    back = backscatter_mask(ti, ts, ps, pi_)
    if not back.any():
        return None, None
    shape = back.shape
    tb = np.broadcast_to(ti, shape)[back]
    pb = np.broadcast_to(pi_, shape)[back]
    out = np.zeros(shape)
    if name == "spm" and _spm2_ok(rough, eps):
        from .spm.crosspol import sigma0_22

        uniq, inv = np.unique(tb, return_inverse=True)  # σ⁰⁽²²⁾ does not depend on φi
        s = sigma0_22(rough, complex(eps), k, uniq, uniq, math.pi, 0.0,
                      n_radial=SPM2_NODES, n_azimuth=SPM2_NODES)  # fmt: skip
        hv = 0.5 * (s[0, 1] + s[1, 0])  # equal in backscatter (reciprocity), to rounding
        out[back] = hv[inv.reshape(-1)]
        return out, "second-order SPM σ⁰⁽²²⁾ (backscatter)"
    e = eps if is_pec(eps) or np.ndim(eps) == 0 else np.broadcast_to(eps, shape)[back]
    out[back] = _iem_term(rough, e, k, tb, pb)
    return out, "IEM multiple scattering (Fung et al. 1992; backscatter)"
