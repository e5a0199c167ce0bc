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
  default (Gaussian kσ = 0.3, kℓ = 3, ε = 3, 40°: −49.405 vs −49.407 dB), evaluated by
  :func:`emscatter.solvers.spm.crosspol.backscatter_hv` (the backscatter symmetries: an
  eighth of the general kernel work, same value to rounding): compiled
  (:mod:`emscatter.solvers.spm.kernel_crosspol`) ≈ 0.13 ms per angle, numpy ≈ 1.5 ms.
  For a conductor (PEC, Re ε < 0, ``|ε| ≥ 100``; SPM2's TM kernel is singular at the horizon)
  or a power-law spectrum the IEM term below is used instead.
* ``po``, ``go`` (and ``spm`` where SPM2 cannot): the IEM's multiple-scattering cross-pol
  (:func:`emscatter.solvers.iem.crosspol.backscatter`, Fung, Li & Chen 1992 appendix; Fung
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

* ``iem`` picked by ``auto`` in backscatter: the IEM's own multiple-scattering hv is this same
  term (:func:`emscatter.solvers.iem.crosspol.backscatter`, equal to the solver's to 1e-13), so
  the API runs the IEM with ``crosspol=False`` and adds it from here (:data:`IEM_BACKSCATTER`).

Both terms are remembered per (roughness, ε, k, θi, φi) — SPM2's per unit σ⁴, since
σ⁰⁽²²⁾/σ⁴ depends on ℓ, ε, k and the angles only — so a repeated scene, a σ sweep or the
blend's second method pays once (:func:`clear_cache`).

What stays zero, by physics: a 1-D profile (a 2-D problem has no cross-polarization), a flat
surface (σ = 0), and bistatic geometries in the plane of incidence for these branches'
single scattering (first-order SPM, PO, GO: the in-plane first-order terms vanish; the
second-order terms above are added in backscatter only — SPM2 costs ms per geometry). Out
of the plane the branches' own single-scattering cross-pol is returned unchanged.
"""

from __future__ import annotations

import math
from collections import OrderedDict

import numpy as np

from ..fresnel import is_pec

__all__ = ["backscatter_mask", "supplement", "takes_iem_term", "clear_cache", "IEM_BACKSCATTER"]

_BACK_TOL = 1e-9
#: The ``name`` under which :func:`supplement` gives the IEM's own backscatter hv (for ``auto``'s
#: IEM run with ``crosspol=False``: the same term, remembered per angle).
IEM_BACKSCATTER = "iem (backscatter)"
SPM2_NODES = 6
#: Backscatter hv values remembered (per method family, roughness, ε, k and angle); SPM2's
#: are stored divided by σ⁴ (σ⁰⁽²²⁾/σ⁴ depends on ℓ, ε, k, θ only), so a σ sweep reuses them.
_CACHE: OrderedDict = OrderedDict()
_CACHE_SIZE = 4096


def clear_cache() -> None:
    """Forget the remembered backscatter cross-pol values."""
    _CACHE.clear()


def _cached(keys, compute):
    """Values for ``keys`` (a list of hashables): remembered ones, the rest by
    ``compute(indices of the missing keys)`` (an array, one value each), remembered."""
    out = np.empty(len(keys))
    missing = []
    for i, key in enumerate(keys):
        hit = _CACHE.get(key)
        if hit is None:
            missing.append(i)
        else:
            _CACHE.move_to_end(key)
            out[i] = hit
    if missing:
        vals = np.asarray(compute(np.asarray(missing)), dtype=float).reshape(-1)
        for i, v in zip(missing, vals, strict=True):
            out[i] = v
            _CACHE[keys[i]] = float(v)
        while len(_CACHE) > _CACHE_SIZE:
            _CACHE.popitem(last=False)
    return out


def _unique_rows(cols: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``np.unique(cols, axis=0, return_inverse=True)`` (rows of a 2-D float array) without
    its per-call cost where it is not needed: one row (a single backscatter angle, the usual
    call) is its own unique row, and at most two varying columns are made unique as one
    complex column (lexicographic order, as ``axis=0``)."""
    n = cols.shape[0]
    if n == 1:
        return cols, np.zeros(1, dtype=np.intp)
    varying = [j for j in range(cols.shape[1]) if not np.all(cols[:, j] == cols[0, j])]
    if not varying:
        return cols[:1], np.zeros(n, dtype=np.intp)
    if len(varying) <= 2:
        z = cols[:, varying[0]] + (1j * cols[:, varying[1]] if len(varying) == 2 else 0j)
        _, first, inv = np.unique(z, return_index=True, return_inverse=True)
        return cols[first], inv.reshape(-1)
    uniq, inv = np.unique(cols, axis=0, return_inverse=True)
    return uniq, inv.reshape(-1)


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
    from .iem import crosspol
    from .iem.model import nominal_rms_slope

    return crosspol.backscatter(rough, eps, k, ti, pi_, slope=nominal_rms_slope(rough), order=8)


def takes_iem_term(name: str, rough, options: dict) -> bool:
    """Whether ``auto``'s ``name`` branch in backscatter runs the IEM with ``crosspol=False``
    and takes its multiple-scattering hv from here (:data:`IEM_BACKSCATTER`): the IEM on a 2-D
    surface with the cross-pol options at their defaults (the term here is the solver's own
    at ``crosspol_order=8`` and the nominal rms slope, to 1e-13: tests/test_auto_crosspol.py),
    so a repeated scene pays the ×3–6-the-co-pol term once."""
    return (
        name == "iem"
        and rough.dimension == 2
        and not {"crosspol", "crosspol_order", "rms_slope"} & options.keys()
    )


def supplement(name: str, rough, eps, k: float, ti, ts, ps, pi_):
    """``(hv, label)``: the backscatter cross-pol σ⁰ [-] to add to method ``name``'s hv and vh,
    in the broadcast shape of the angles [rad] (0 away from backscatter), or ``(None, None)``
    where nothing is added (module docstring). ``eps`` complex scalar or array, or "pec".
    A repeated call (same inputs) is answered from the cache (a fresh array)."""
    args = (ti, ts, ps, pi_) if is_pec(eps) else (ti, ts, ps, pi_, eps)
    arrays = [np.asarray(a) for a in args]
    key = None
    if all(a.size <= 4096 and a.dtype != object for a in arrays):
        key = ("call", name, rough, float(k), "pec" if is_pec(eps) else "eps",
               *((a.dtype.str, a.shape, a.tobytes()) for a in arrays))  # fmt: skip
        hit = _CACHE.get(key)
        if hit is not None:
            _CACHE.move_to_end(key)
            hv, how = hit
            return (None, None) if hv is None else (hv.copy(), how)
    hv, how = _supplement(name, rough, eps, k, ti, ts, ps, pi_)
    if key is not None:
        _CACHE[key] = (None if hv is None else hv.copy(), how)
        while len(_CACHE) > _CACHE_SIZE:
            _CACHE.popitem(last=False)
    return hv, how


def _supplement(name: str, rough, eps, k: float, ti, ts, ps, pi_):
    """:func:`supplement` without its per-call cache (per-angle values still remembered)."""
    if name not in ("spm", "po", "go", IEM_BACKSCATTER) or rough.dimension != 2 or rough.sigma == 0:
        return None, None
    back = backscatter_mask(ti, ts, ps, pi_)
    if not back.any():
        return None, None
    shape = back.shape
    tb = np.broadcast_to(ti, shape)[back]
    pb = np.broadcast_to(pi_, shape)[back]
    out = np.zeros(shape)
    if name == "spm" and _spm2_ok(rough, eps):
        from .spm.crosspol import backscatter_hv

        # σ⁰⁽²²⁾ depends on φi only through an anisotropic spectrum's axes
        iso = rough.length == rough.length_y
        pairs = np.stack([tb, np.zeros_like(pb) if iso else np.mod(pb, 2 * math.pi)], -1)
        uniq, inv = _unique_rows(pairs)
        e = complex(eps)
        base = ("spm2", type(rough), rough.length, rough.length_y, e, float(k))
        keys = [(*base, float(t), float(f)) for t, f in uniq]

        def spm2(idx):
            vals = np.empty(idx.size)
            for f in np.unique(uniq[idx, 1]):  # one pass per azimuth: every angle at once
                sel = idx[uniq[idx, 1] == f]
                unit = rough.sigma**4  # (stored per unit σ⁴)
                vals[np.searchsorted(idx, sel)] = (
                    backscatter_hv(
                        rough, e, k, uniq[sel, 0], f, n_radial=SPM2_NODES, n_azimuth=SPM2_NODES
                    )
                    / unit
                )
            return vals

        out[back] = rough.sigma**4 * _cached(keys, spm2)[inv.reshape(-1)]
        return out, "second-order SPM σ⁰⁽²²⁾ (backscatter)"
    e = eps if is_pec(eps) or np.ndim(eps) == 0 else np.broadcast_to(eps, shape)[back]
    ea = np.broadcast_to(np.asarray(e if not is_pec(e) else 0.0, dtype=complex), tb.shape)
    cols = np.stack([tb, np.mod(pb, 2 * math.pi), ea.real, ea.imag], -1)
    uniq, inv = _unique_rows(cols)
    tag = "pec" if is_pec(e) else "eps"
    keys = [("iem", tag, rough, float(k), *map(float, row)) for row in uniq]

    def iem(idx):
        rows = uniq[idx]
        ee = e if is_pec(e) or np.ndim(e) == 0 else rows[:, 2] + 1j * rows[:, 3]
        return _iem_term(rough, ee, k, rows[:, 0], rows[:, 1])

    out[back] = _cached(keys, iem)[inv.reshape(-1)]
    return out, "IEM multiple scattering (Fung et al. 1992; backscatter)"
