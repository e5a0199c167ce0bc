"""Backscatter cross-polarization with the exact second-order kernel and the IEM's height series
(issue 20: the IEM multiple-scattering hv is 4–5 dB below exact 3-D solutions).

Why the IEM term is low
-----------------------
The multiple-scattering hv of :mod:`emscatter.solvers.iem.crosspol` (Fung, Li & Chen 1992
appendix; Ulaby & Long 2014 code 10.1; SMRT ``iiem_fung02``) has the structure

    σ⁰_hv = (1/16π) ∫∫_{|r|<1} [L(r) + X(r)] |F_hv(r)|² S_m(r) d²r,
    L → (kσ)⁴ cos⁴θ w(k_s⊥ − p) w(p − k_i⊥)   (kσ → 0),

the same as second-order perturbation theory's σ⁰⁽²²⁾ (:mod:`emscatter.solvers.spm.crosspol`,
the exact small-roughness limit), but with the 1992 kernel ``F_hv`` in place of the exact
second-order kernel ``g₂`` and the intermediate wave restricted to the propagating disc
``|p| < k``. Measured on the 138 NMM3D 40° cases with HV (exponential correlation, kσ
0.26–1.32, kℓ 1–20; ``validation/auto/hv_resummed.py``): σ⁰⁽²²⁾ restricted to ``|p| < k`` is
5–9 dB below the full σ⁰⁽²²⁾ (the evanescent intermediate waves carry most of the
fourth-order hv), and the IEM term is 2.1–3.5 dB below the full σ⁰⁽²²⁾ in every kσ band, 5.5–7 dB
at kℓ ≈ 1. No factor (2 vs 4, hv vs hv + vh, 4π) explains it: the gap depends on kℓ and ε.

The resummed term
-----------------
Keep the IEM's Gaussian height averaging (Fung et al. 1992: the Kirchhoff phase series of both
scattering points) and use the exact kernel over the whole spectral plane::

    σ⁰_hv = 4π k² cos²θ σ⁴ ∫ T̂(Q, k_s⊥ − p) T̂(Q, p − k_i⊥) g₂(p)[g₂*(p) + g₂*(−p)] d²p,
    T̂(Q, κ) = ℓₓℓᵧ e^{−Q} Σ_{n≥1} Qⁿ⁻¹/n! wₙ(κ),   Q = (kσ cosθ)²,

``wₙ`` the n-fold spectrum of :func:`emscatter.solvers.kirchhoff.po.log_nfold` (the series of
the IEM term, ``T̂ → w`` as ``Q → 0``). So:

* at small kσ it *is* σ⁰⁽²²⁾ (relative difference O(Q); tested to 1e-3 at kσ = 0.02);
* at larger kσ the height series acts as in the IEM term (the factor ``e^{−Q}`` and the
  broadening of ``wₙ``): for exponential surfaces it saturates perturbation theory's σ⁴ growth
  (below σ⁰⁽²²⁾, increasingly with kσ; tested); for Gaussian ones with large kℓ it fills the
  spectral tail σ⁰⁽²²⁾ lacks, and in that Kirchhoff regime it meets the IEM term (kσ = 1.3,
  kℓ = 6, ε = 15 + 2i: within 0.13 dB at 20° and 40°; tested to 0.5 dB) — two kernels, one
  height series.

This is a hybrid, not a published model: the kernel is second-order perturbation theory's,
the height factors the IEM's (it has the form of the small-slope approximation's lowest order —
perturbation kernels with a Kirchhoff-type phase average — not Voronovich's full SSA2).
Against NMM3D at 40° (138 cases, ``validation/auto/hv_resummed.md``): RMSE 3.24 dB, bias
−2.10 dB, against 5.23 / −4.44 for the IEM term and 3.12 / −1.71 for σ⁰⁽²²⁾ used beyond its
validity; the residual is mostly ε = 3 + i (−6.6 dB, where σ⁰⁽²²⁾ is −6.2 dB too, already at
kσ = 0.26). Validity as the IEM's (kσ cosθ ≲ 3; the node rule of σ⁰⁽²²⁾ covers the broadened
spectra there, tested against a finer rule), dielectrics only (σ⁰⁽²²⁾'s kernel is singular at
the horizon for a conductor), Gaussian or exponential 2-D surfaces.

Cost: one σ⁰⁽²²⁾ node set per incidence angle (16 × 16 nodes per segment), the series summed at
every node. Compiled (:mod:`emscatter.solvers.iem.kernels.crosspol_resummed`, the default where
numba imports; equal to the numpy reference to ≤ 1e-10 relative, seen ≤ 5e-14): ≈ 0.12 ms
of CPU per angle at the 10 radial × 8 azimuth that ``auto`` uses (issue 20's 162-case 40°
grid, exponential; shared 2-core machine; 0.34 ms before the kernel's Fourier form, 0.15 ms
before its real form and grouped divisions), of which ≈ 0.045 ms is the height series — all
a new σ at a known (ε, θ, ℓ) costs, the rest
remembered (:data:`_PREP`) —, against 100–250 ms for numpy (``EMSCATTER_KERNELS=numpy``).
``method="auto"`` adds it in backscatter on every branch
(:mod:`emscatter.solvers.auto_crosspol`); the IEM solver keeps the published IEM term.
"""

from __future__ import annotations

import math
import os
from collections import OrderedDict

import numpy as np

from emscatter.conventions import check_angle, check_positive
from emscatter.fresnel import check_eps, is_pec
from emscatter.solvers.kirchhoff.po import log_nfold, series_sum
from emscatter.solvers.spm import crosspol as spm2
from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation, check_roughness

__all__ = ["backscatter_resummed", "MAX_KSIGMA_COS"]

#: Largest ``kσ cosθ`` accepted (the IEM's own range, Fung 1994: kσ ≲ 3).
MAX_KSIGMA_COS = 3.0


def _check(roughness, eps, k, theta, n_nodes):
    rough = check_roughness(roughness)
    if type(rough) not in (GaussianCorrelation, ExponentialCorrelation) or rough.dimension != 2:
        raise ValueError(
            "roughness must be a 2-D GaussianCorrelation or ExponentialCorrelation for the "
            f"resummed cross-pol, got {rough!r}"
        )
    eps = check_eps(eps)
    if is_pec(eps) or np.ndim(eps) != 0 or complex(eps).real <= 0:
        raise ValueError(
            f"eps must be one dielectric permittivity (complex, Re eps > 0), got {eps!r}"
        )
    k = check_positive("k", k, unit="rad/m")
    th = np.asarray(check_angle("theta", theta), dtype=float)
    if np.any(th >= 0.5 * math.pi):
        raise ValueError(f"theta must be below pi/2 rad (grazing excluded), got {theta!r}")
    if not isinstance(n_nodes, int | np.integer) or n_nodes < 4:
        raise ValueError(f"n_nodes must be an integer >= 4, got {n_nodes!r}")
    kc = k * rough.sigma * np.cos(th)
    if np.any(kc > MAX_KSIGMA_COS):
        raise ValueError(
            f"k*sigma*cos(theta) must be <= {MAX_KSIGMA_COS} (the IEM's range), got "
            f"{float(np.max(kc)):.4g}"
        )
    return rough, complex(eps), k, th


def backscatter_resummed(roughness, eps, k: float, theta, phi_i: float = 0.0, *,
                         n_nodes: int = 16, n_azimuth: int | None = None,
                         both: bool = False) -> np.ndarray:  # fmt: skip
    """Backscatter cross-polarized σ⁰_hv [-] (``θs = θi``, ``φs = φi + π``) at incidence angles
    ``theta`` [rad] (any shape, each ``< π/2``), azimuth ``phi_i`` [rad]: the exact second-order
    kernel with the IEM's height series (module docstring; equation there).

    ``roughness`` a 2-D Gaussian or exponential surface, ``eps`` one dielectric permittivity,
    ``k`` [rad/m], ``kσ cosθ ≤ 3``; ``n_nodes`` Gauss–Legendre nodes per radial segment of the
    σ⁰⁽²²⁾ rule, ``n_azimuth`` per azimuth segment (default ``n_nodes``). ``both=True``
    returns ``(hv, vh)`` stacked on a leading axis (equal in backscatter by reciprocity;
    tested). Raises ``ValueError`` naming the parameter."""
    rough, eps, k, th = _check(roughness, eps, k, theta, n_nodes)
    n_az = n_nodes if n_azimuth is None else n_azimuth
    if not isinstance(n_az, int | np.integer) or n_az < 4:
        raise ValueError(f"n_azimuth must be an integer >= 4, got {n_azimuth!r}")
    d = float(phi_i)
    if not math.isfinite(d):
        raise ValueError(f"phi_i must be a finite angle [rad], got {phi_i!r}")
    uniq, inv = np.unique(th.ravel(), return_inverse=True)
    out = _values(rough, eps, k, uniq, d, int(n_nodes), int(n_az))
    res = out[:, inv].reshape((2, *th.shape))
    return res if both else res[0]


def _values(rough, eps: complex, k: float, uniq, d: float, n_nodes: int, n_azimuth: int):
    """``(hv, vh)`` (2, n) at distinct flat angles ``uniq`` [rad] (1-D), azimuth ``d`` [rad],
    inputs already checked (:func:`backscatter_resummed`; ``auto``'s supplement calls this
    directly, its inputs validated by the API): compiled, the numpy reference where the rule
    lacks the point symmetry or numba is absent; raises where a value is not finite/positive."""
    out = _compiled(rough, eps, k, uniq, d, n_nodes, n_azimuth)
    if out is None:
        out = _numpy(rough, eps, k, uniq, d, n_nodes, n_azimuth)
    elif np.isnan(out[0]).any():  # angles whose node rule lacks the point symmetry
        miss = np.isnan(out[0])
        out[:, miss] = _numpy(rough, eps, k, uniq[miss], d, n_nodes, n_azimuth)
    if not np.all(np.isfinite(out)) or np.any(out < 0):
        raise FloatingPointError(f"resummed cross-pol not finite/positive at theta={uniq!r}")
    return out


#: The σ-independent part of the compiled rule per (spectrum kind, ℓₓ, ℓᵧ, ε, k, θ, φ, nodes)
#: — exact floats — (:func:`emscatter.solvers.iem.kernels.crosspol_resummed.prepare_one`:
#: the node weights times the kernel products, the nodes' ``(Kℓ)²``; ≤ 20 400 nodes, ≤ 0.4 MB
#: each, ~0.1 MB on issue 20's grid), so a new σ at a known (ε, θ, ℓ) costs only the height
#: series; least recently used first out beyond :data:`_PREP_SIZE`.
_PREP: OrderedDict = OrderedDict()
_PREP_SIZE = 64


def clear_memory() -> None:
    """Forget the remembered σ-independent node parts (:data:`_PREP`)."""
    _PREP.clear()


def _value_one(rough, eps: complex, k: float, theta: float, d: float, n_nodes: int,
               n_azimuth: int) -> float:  # fmt: skip
    """``hv`` at one flat angle ``theta`` [rad] (inputs checked, as :func:`_values`, whose
    value it is to the bit: the same compiled arithmetic, tested), without the array path's
    wrapping: compiled where numba is there and the rule has the point symmetry — its
    σ-independent part from :data:`_PREP` where known —, else :func:`_values`."""
    from emscatter.kernels import backend

    if backend() == "numba":
        from emscatter.solvers.iem.kernels import crosspol_resummed as kern

        code = kern.GAUSSIAN if type(rough) is GaussianCorrelation else kern.EXPONENTIAL
        lx, ly = rough.length, rough.length_y
        key = (code, lx, ly, eps, k, theta, d, n_nodes, n_azimuth)
        prep = _PREP.get(key, False)
        if prep is False:  # (prepare and evaluate in one compiled call: the same double)
            v, prep = kern.value_one(theta, eps, k, rough.sigma, lx, ly, d, code, n_nodes,
                                     n_azimuth)  # fmt: skip
            _PREP[key] = prep
            while len(_PREP) > _PREP_SIZE:
                _PREP.popitem(last=False)
        else:
            _PREP.move_to_end(key)
            if prep is not None:
                v = kern.evaluate_one(prep, theta, k, rough.sigma, lx, ly, code)
        if prep is not None:  # (None: no point symmetry, the numpy reference)
            if not (math.isfinite(v) and v >= 0):
                raise FloatingPointError(
                    f"resummed cross-pol not finite/positive at theta={theta!r}"
                )
            return v
    return float(_values(rough, eps, k, np.array([theta]), d, n_nodes, n_azimuth)[0, 0])


def _compiled(rough, eps, k, uniq, d, n_nodes, n_azimuth):
    """``(hv, vh)`` (2, n) from the compiled kernel (:mod:`.kernels.crosspol_resummed`;
    ``vh = hv`` there: reciprocity, tested on the numpy path), NaN where an angle's rule lacks
    the point symmetry, or None where the numpy reference runs (backend numpy). Any call takes it
    when numba is there (no size gate: one angle costs 0.1–0.3 s in numpy, more than loading
    the kernels)."""
    from emscatter.kernels import backend

    if uniq.size == 0 or backend() != "numba":
        return None
    from emscatter.solvers.iem.kernels import crosspol_resummed as kern

    code = kern.GAUSSIAN if type(rough) is GaussianCorrelation else kern.EXPONENTIAL
    vals, done = kern.backscatter_resummed(
        uniq, eps, k, rough.sigma, rough.length, rough.length_y, d, code, int(n_nodes),
        threads=min(os.cpu_count() or 1, 8), n_azimuth=int(n_azimuth),
    )  # fmt: skip
    vals[~done] = np.nan
    return np.stack([vals, vals])


def _numpy(rough, eps, k, uniq, d, n_nodes, n_azimuth):
    """The numpy reference of :func:`backscatter_resummed`: ``(hv, vh)`` (2, n) at the
    distinct angles ``uniq`` [rad], azimuth ``d`` [rad] (the whole-plane σ⁰⁽²²⁾ rule, both
    polarizations of the kernel, the series by
    :func:`emscatter.solvers.kirchhoff.po.series_sum`)."""
    log_w = log_nfold(rough)
    lx, ly = rough.length, rough.length_y
    cr, sr = math.cos(d), math.sin(d)
    out = np.empty((2, uniq.size))
    for j, t in enumerate(uniq):  # one node set per angle, as σ⁰⁽²²⁾'s reference
        si, ci = math.sin(t), math.cos(t)
        kis, ksv = (k * si, 0.0), (-k * si, 0.0)
        px, py, wt = spm2._nodes(rough, eps, k, kis, ksv, n_nodes, n_azimuth)
        Q = (k * rough.sigma * ci) ** 2

        def w_hat(x, y, Q=Q):  # ℓₓℓᵧ T(Q, κ) of the surface-frame wavevector
            X, Y = cr * x - sr * y, sr * x + cr * y
            K = np.sqrt((X * lx) ** 2 + (Y * ly) ** 2)
            return lx * ly * np.exp(series_sum(log_w, np.full(K.size, Q), K, rtol=1e-10))

        wt = wt * w_hat(ksv[0] - px, ksv[1] - py) * w_hat(px - kis[0], py - kis[1])
        g = spm2._kernel(eps, k, si, ci, si, ci, -1.0, 0.0, px, py)
        gp = spm2._kernel(eps, k, si, ci, si, ci, -1.0, 0.0, -px, -py)  # k_s⊥ + k_i⊥ − p
        acc = (g * np.conj(g + gp)).real @ wt
        scale = 4.0 * math.pi * k * k * ci * ci * rough.sigma**4
        out[0, j], out[1, j] = scale * acc[0, 1], scale * acc[1, 0]
    return out
