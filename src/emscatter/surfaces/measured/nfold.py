"""Tabulated n-fold spectra ``w_n`` of a measured correlation, for the PO and IEM series.

The Kirchhoff (PO) and IEM series need ``w_n``, the normalized transform of ``ρⁿ``
(:mod:`emscatter.solvers.kirchhoff.po`: ``∫ρⁿ e^{iK·r} d^d r = (2π)^d w_n``). For a measured
roughness (:mod:`emscatter.surfaces.measured`) ``ρ`` is the inverse transform of the Welch
spectrum on the lag grid of a Welch patch (lag 0 at the centre, ``ρ(0) = 1``). This module
builds, once per roughness, the table the series read through
:func:`emscatter.solvers.kirchhoff.po.log_nfold`:

* ``n = 1 … n_tab``: ``w_n`` by FFT of the sampled ``ρⁿ`` (``Δx Δy/(2π)² Σ ρⁿ e^{iK·r}``),
  averaged over **ellipses** ``s = √((Kx ℓx)² + (Ky ℓy)²)`` (the solvers' scaled wavenumber,
  ``ℓx, ℓy`` the 1/e lags): exact for an isotropic or elliptically anisotropic correlation
  (Gaussian, exponential, Matérn with ``ℓx ≠ ℓy``), the elliptic mean of the spectrum
  otherwise (a brushed map whose correlation is not elliptic: stated in ``info``). A
  profile keeps ``s = |Kx| ℓ``. Stored as ``log(w_n / (ℓx ℓy))`` (``/ℓ`` in 1-D) on a
  uniform grid of ``s``, the convention of ``log_nfold``;
* ``n_tab`` is the largest ``n`` whose ``ρⁿ`` still spans two lag cells to ``1/e`` along the
  steeper axis (``ρ(2Δ)ⁿ ≥ e^{−1}``; at most :data:`N_TAB_MAX`): beyond it the map does not
  resolve ``ρⁿ``, and the table continues with the differentiable scaling
  ``w_n(s) = (n_tab/n)^{d/2} w_{n_tab}(s √(n_tab/n))`` (``1 − ρ ≈ ½ rᵀ M r`` at lags below
  the spacing: the solvers treat the measured surface as smooth at its own resolution, as its
  finite-difference slopes do; exact for the Gaussian at every ``n``);
* ``n`` between integers ``j < n < j + 1``: the two orders carried to ``n`` by the same
  scaling, mixed linearly (the series' continuum sum and peak search ask for real ``n``);
* beyond the grid's ellipse (``s`` above the inscribed Nyquist ellipse) ``w_n`` is zero
  (``log`` floor :data:`LOG_FLOOR`, also for negative FFT noise), or for ``n = 1`` the tail.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["nfold_table", "N_TAB_MAX", "LOG_FLOOR"]

#: Most orders tabulated by FFT; beyond them the differentiable scaling (module docstring).
N_TAB_MAX = 512

#: log w_n where the map has no spectrum (beyond the grid, or a non-positive estimate).
LOG_FLOOR = -700.0


def _orders(rho: np.ndarray) -> int:
    """``n_tab`` (module docstring): ``ρ(2Δ)ⁿ ≥ 1/e`` along the steeper axis."""
    c = tuple(m // 2 for m in rho.shape)
    r2 = min(float(rho[c[:ax] + (c[ax] + 2,) + c[ax + 1 :]]) for ax in range(rho.ndim))
    if not 0 < r2 < 1:
        return 1 if r2 <= 0 else N_TAB_MAX
    return int(np.clip(math.floor(-1.0 / math.log(r2)), 1, N_TAB_MAX))


def nfold_table(rho: np.ndarray, spacing: tuple, lengths: tuple, tail=None):
    """The callable ``f(n, s) = log(w_n(s)/L)`` of a sampled correlation (module docstring).

    ``rho``: ρ on the lag grid (fftshifted, lag 0 at ``shape // 2``, axes (y, x)); ``spacing``
    [m] per axis of ``rho``; ``lengths`` ``(ℓx, ℓy)`` or ``(ℓ,)`` [m], the scale of ``s``;
    ``tail``: None or ``w₁(|K|)`` [m^d] beyond the grid for ``n = 1`` (``|K| = s/√(ℓxℓy)``).
    Returns ``(f, info)``; ``info`` names ``n_tab``, the grid of ``s`` and the averaging.
    """
    d = rho.ndim
    shape = rho.shape
    cell = float(np.prod(spacing))
    n_tab = _orders(rho)
    ell = tuple(reversed(lengths))  # per axis of rho: (ℓy, ℓx) or (ℓ,)
    dks = [2 * math.pi / (m * sp) * e for m, sp, e in zip(shape, spacing, ell, strict=True)]
    comps = np.meshgrid(*[(np.arange(m) - m // 2) * q for m, q in zip(shape, dks, strict=True)],
                        indexing="ij")  # fmt: skip
    s_grid = np.sqrt(sum(c * c for c in comps))
    ds = min(dks)
    s_max = min((m // 2) * q for m, q in zip(shape, dks, strict=True))
    norm = float(np.prod(lengths))
    nb = int(s_max / ds) + 1
    idx = np.rint(s_grid / ds).astype(np.intp).ravel()
    keep = idx < nb
    idx = idx[keep]
    cnt = np.maximum(np.bincount(idx, minlength=nb), 1)
    table = np.empty((n_tab + 1, nb))
    rn = np.fft.ifftshift(rho)
    power = np.ones_like(rn)
    scale = cell / ((2 * math.pi) ** d * norm)
    for n in range(1, n_tab + 1):  # orders, not angles: one FFT each
        power = power * rn
        w = np.real(np.fft.fftn(power)) * scale
        ring = np.bincount(idx, np.fft.fftshift(w).ravel()[keep], minlength=nb) / cnt
        table[n] = np.log(np.maximum(ring, math.exp(LOG_FLOOR)))

    def at(row, n, sa):
        """Order ``row`` carried to ``n``: log w_row(s √(row/n)) + (d/2) log(row/n)."""
        ratio = row / n
        fs = sa * np.sqrt(ratio) / ds
        inside = fs <= nb - 1
        fs = np.minimum(fs, nb - 1)
        i = np.minimum(np.floor(fs).astype(np.intp), nb - 2)
        u = fs - i
        v = table[row, i] * (1 - u) + table[row, i + 1] * u + 0.5 * d * np.log(ratio)
        return v, inside

    def f(n, s):
        n, s = np.broadcast_arrays(np.asarray(n, dtype=float), np.asarray(s, dtype=float))
        n = np.maximum(n, 1.0)
        sa = np.abs(s)
        ne = np.minimum(n, float(n_tab))
        j = np.clip(np.floor(ne).astype(np.intp), 1, max(n_tab - 1, 1))
        t = np.clip(ne - j, 0.0, 1.0) if n_tab > 1 else np.zeros(n.shape)
        lo, in_lo = at(j, n, sa)
        hi, in_hi = at(np.minimum(j + 1, n_tab), n, sa)
        inside = np.where(t < 1, in_lo, True) & np.where(t > 0, in_hi, True)
        val = np.where(inside, lo * (1 - t) + hi * t, LOG_FLOOR)
        if tail is not None:
            one = (~inside) & (n == 1)
            if np.any(one):
                w1 = tail(np.abs(s[one]) / math.sqrt(norm)) / norm
                val = val.copy()
                val[one] = np.log(np.maximum(w1, math.exp(LOG_FLOOR)))
        return val

    info = {"n_tab": n_tab, "s_step": ds, "s_max": (nb - 1) * ds,
            "average": "ellipses s = √((Kx ℓx)² + (Ky ℓy)²)" if d == 2 else "|Kx| ℓ",
            "beyond_n_tab": "scaling (n_tab/n)^(d/2) w_n_tab(s √(n_tab/n))"}  # fmt: skip
    return f, info
