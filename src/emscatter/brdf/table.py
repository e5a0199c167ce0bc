"""Tabulated BRDFs in the renderer frame: :class:`BrdfTable`.

Layout (the interface the Mitsuba plugin, the exporters and the radio bridge rely on; changes
are announced in ``docs/brdf.md``). All angles [rad] in the *renderer frame*
(:mod:`emscatter.brdf.frames`: ``wi``, ``wo`` point away from the surface, normal ``+z``,
tangent ``+x``, mirror direction at ``φo = φi + π``); wavelengths [m]; BRDF values [1/sr].

Isotropic table (``table.isotropic``)::

    values[w, i, o, d] = f_r(λ_w; θi = theta_i[i], θo = theta_o[o], Δφ = phi_d[d])

with ``Δφ = φo − φi`` folded into ``[0, π]`` (``f`` is even in Δφ for an isotropic surface);
``Δφ = π`` is the mirror (specular) half-plane, ``Δφ = 0`` the backscatter one.

Anisotropic table::

    values[w, i, a, o, b] = f_r(λ_w; θi = theta_i[i], φi = phi_i[a], θo = theta_o[o],
                                φo = phi_o[b])

with ``phi_i``, ``phi_o`` in ``[0, 2π)`` (periodic), measured from the tangent ``+x``.

* ``values`` is the unpolarized *incoherent* BRDF: mean over the two incident polarizations,
  sum over the two scattered ones, ``f = Σ_pq σ⁰_pq / (8π cosθi cosθo)``.
* ``polarized`` (optional), shape ``(2, 2, *values.shape)``, indexed ``[pol_s, pol_i]`` with
  0 = h (TE), 1 = v (TM) in emscatter's basis (h ⟂ the plane through the normal and each
  direction): ``polarized[s, i] = σ⁰_si / (4π cosθi cosθo)``; ``values = ½ Σ polarized``.
* ``coherent``: the specular delta lobe, *not* in ``values``: the coherent power
  reflectivity ``R_coh`` (unpolarized mean ``(R_h + R_v)/2``), shape ``(n_wl, n_ti)``
  (isotropic) or ``(n_wl, n_ti, n_pi)`` on the table's θi (and φi) nodes; radiance
  ``L_o(mirror(wi)) = R_coh(θi) L_i(wi)``. ``coherent_polarized``: ``(2, …)`` for h, v.

Interpolation (:meth:`BrdfTable.evaluate`): multilinear in the grid angles (θi, θo, Δφ) or
(θi, φi, θo, φo) and linear in wavelength between table wavelengths; constant beyond the first
and last θ nodes (the builders' last node is below 90°: the value there holds up to grazing);
zero when either direction is on or below the horizon (``z ≤ 0``), as Mitsuba does. When the
θi and θo axes are equal the interpolant is exactly reciprocal, ``f(wi, wo) = f(wo, wi)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from ..conventions import check_pol_pair
from . import grid
from .frames import angles, fold_dphi

__all__ = ["BrdfTable", "Albedo", "FORMAT_VERSION"]

#: Version of the table layout (bumped on any incompatible change; stored in exports).
FORMAT_VERSION = 1

HALF_PI = 0.5 * math.pi


@dataclass(frozen=True)
class Albedo:
    """Directional albedo ``∫ f_r cosθo dωo`` (+ coherent) of a table, per wavelength and θi
    node (and φi node for anisotropic tables): arrays of shape ``(n_wl, n_ti[, n_pi])``."""

    wavelengths: np.ndarray
    theta_i: np.ndarray
    incoherent: np.ndarray
    coherent: np.ndarray
    phi_i: np.ndarray | None = None

    @property
    def total(self) -> np.ndarray:
        """Coherent + incoherent directional albedo [-]."""
        return self.incoherent + self.coherent


def _as_float_array(name: str, value, shape: tuple[int, ...], keep32: bool = False) -> np.ndarray:
    """A read-only float64 copy (float32 kept as float32 when ``keep32``), checked."""
    dt = np.float32 if keep32 and np.asarray(value).dtype == np.float32 else float
    if isinstance(value, np.ndarray) and value.dtype == dt and not value.flags.writeable:
        arr = value  # already a read-only array (the builders'): no copy of a large grid
    else:
        arr = np.array(value, dtype=dt)
    if arr.shape != shape:
        raise ValueError(f"{name} must have shape {shape}, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        where = tuple(int(i[0]) for i in np.nonzero(~np.isfinite(arr)))
        raise ValueError(f"{name} holds NaN or inf (first at index {where})")
    if np.any(arr < 0):
        where = tuple(int(i[0]) for i in np.nonzero(arr < 0))
        raise ValueError(f"{name} must be ≥ 0, got {arr[where]!r} at index {where}")
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class BrdfTable:
    """A tabulated BRDF (layout and interpolation: module docstring).

    Parameters
    ----------
    wavelengths : (n_wl,) [m], strictly increasing.
    theta_i, theta_o : θ nodes [rad] in ``[0, π/2)``, strictly increasing.
    values : unpolarized incoherent ``f_r`` [1/sr], ``(n_wl, n_ti, n_to, n_pd)`` or
        ``(n_wl, n_ti, n_pi, n_to, n_po)``; stored as float64, or as float32 when given float32
        (``build_table(dtype="float32")``: half the memory; evaluation is in float64).
    phi_d : isotropic tables: Δφ nodes [rad] in ``[0, π]``.
    phi_i, phi_o : anisotropic tables: φ nodes [rad] in ``[0, 2π)``.
    coherent, coherent_polarized : coherent reflectivity (module docstring); None → 0.
    polarized : optional ``(2, 2, *values.shape)`` per ``[pol_s, pol_i]``.
    metadata : dict (solver, surface, material, units, version, energy, ...).
    """

    wavelengths: np.ndarray
    theta_i: np.ndarray
    theta_o: np.ndarray
    values: np.ndarray
    phi_d: np.ndarray | None = None
    phi_i: np.ndarray | None = None
    phi_o: np.ndarray | None = None
    coherent: np.ndarray | None = None
    coherent_polarized: np.ndarray | None = None
    polarized: np.ndarray | None = None
    metadata: dict = field(default_factory=dict)

    def __post_init__(self):
        set_ = object.__setattr__
        wl = grid.check_table_wavelengths(self.wavelengths)
        set_(self, "wavelengths", wl)
        set_(self, "theta_i", grid.check_axis("theta_i", self.theta_i, 0, HALF_PI, high_open=True))
        set_(self, "theta_o", grid.check_axis("theta_o", self.theta_o, 0, HALF_PI, high_open=True))
        iso = self.phi_d is not None
        if iso and (self.phi_i is not None or self.phi_o is not None):
            raise ValueError("give phi_d (isotropic) or phi_i and phi_o (anisotropic), not both")
        if iso:
            set_(self, "phi_d", grid.check_axis("phi_d", self.phi_d, 0, math.pi))
            grid_shape = (self.theta_i.size, self.theta_o.size, self.phi_d.size)
            inc_shape = (wl.size, self.theta_i.size)
        else:
            if self.phi_i is None or self.phi_o is None:
                raise ValueError("an anisotropic table needs both phi_i and phi_o (or give phi_d)")
            for name in ("phi_i", "phi_o"):
                ax = grid.check_axis(name, getattr(self, name), 0, grid.TWO_PI, high_open=True)
                set_(self, name, ax)
            grid_shape = (self.theta_i.size, self.phi_i.size, self.theta_o.size, self.phi_o.size)
            inc_shape = (wl.size, self.theta_i.size, self.phi_i.size)
        shape = (wl.size, *grid_shape)
        set_(self, "values", _as_float_array("values", self.values, shape, keep32=True))
        if self.polarized is not None:
            pol = _as_float_array("polarized", self.polarized, (2, 2, *shape), keep32=True)
            set_(self, "polarized", pol)
        for name, lead in (("coherent", ()), ("coherent_polarized", (2,))):
            val = getattr(self, name)
            if val is None:
                val = np.zeros(lead + inc_shape)
            set_(self, name, _as_float_array(name, val, lead + inc_shape))
        if np.any(self.coherent > 1) or np.any(self.coherent_polarized > 1):
            raise ValueError("coherent reflectivity must be ≤ 1")
        if not isinstance(self.metadata, dict):
            raise TypeError(f"metadata must be a dict, got {type(self.metadata).__name__}")

    # ---------------------------------------------------------------- layout helpers
    @property
    def isotropic(self) -> bool:
        """True for (θi, θo, Δφ) tables, False for (θi, φi, θo, φo) ones."""
        return self.phi_d is not None

    @property
    def grid_axes(self) -> tuple[np.ndarray, ...]:
        """The grid axes in the order of ``values``' trailing dimensions."""
        if self.isotropic:
            return self.theta_i, self.theta_o, self.phi_d
        return self.theta_i, self.phi_i, self.theta_o, self.phi_o

    @property
    def symmetric_grid(self) -> bool:
        """θi and θo (and φi and φo) axes are identical: reciprocity holds node by node."""
        same = np.array_equal(self.theta_i, self.theta_o)
        if not self.isotropic:
            same = same and np.array_equal(self.phi_i, self.phi_o)
        return bool(same)

    def replace(self, **changes) -> BrdfTable:
        """A copy with some fields changed (validated again)."""
        return replace(self, **changes)

    # ---------------------------------------------------------------- evaluation
    def _wavelength_weights(self, wavelength, out_of_range: str):
        """``(scalar, columns, matrix)``: requested rows as combinations of table columns.

        ``columns`` is a slice (the contiguous range of table wavelengths the request touches),
        so that ``values[columns]`` is a view: a copy of a large table on every call cost the
        anisotropic RGL export most of its time."""
        wl = self.wavelengths
        if wavelength is None:
            return False, slice(0, wl.size), np.eye(wl.size)
        req = np.asarray(wavelength, dtype=float)
        scalar = req.ndim == 0
        req = req.reshape(-1)
        if not np.all(np.isfinite(req)) or np.any(req <= 0):
            raise ValueError(f"wavelength must be positive finite [m], got {wavelength!r}")
        lo, hi = wl[0] * (1 - 1e-12), wl[-1] * (1 + 1e-12)
        outside = (req < lo) | (req > hi)
        if np.any(outside) and out_of_range != "clamp":
            raise ValueError(
                f"wavelength {req[outside][0]!r} m is outside the table's range "
                f"[{wl[0]:.6g}, {wl[-1]:.6g}] m; build the table for it, or pass "
                "wavelength_out_of_range='clamp'"
            )
        i0, i1, t = grid.locate_clamped(wl, req)
        mat = np.zeros((req.size, wl.size))
        rows = np.arange(req.size)
        np.add.at(mat, (rows, i0), 1 - t)
        np.add.at(mat, (rows, i1), t)
        used = np.flatnonzero(np.any(mat != 0, axis=0))
        cols = slice(int(used[0]), int(used[-1]) + 1)
        return scalar, cols, mat[:, cols]

    def _grid_values(self, pol):
        if pol is None:
            return self.values
        s, i = check_pol_pair(pol)
        if self.polarized is None:
            raise ValueError(f"pol={pol!r} needs a polarized table (build it with polarized=True)")
        return self.polarized[s, i]

    def evaluate_angles(
        self,
        theta_i,
        phi_i,
        theta_o,
        phi_o,
        wavelength=None,
        *,
        pol: str | None = None,
        wavelength_out_of_range: str = "raise",
    ) -> np.ndarray:
        """``f_r`` [1/sr] at renderer-frame angles [rad] (arrays broadcast).

        ``wavelength`` [m]: None → every table wavelength (leading axis ``n_wl``); an array →
        leading axis of its length; a scalar → no leading axis. Between table wavelengths the
        values are interpolated linearly; outside them an error (or ``"clamp"``).
        ``pol``: None (unpolarized) or a pair like ``"hv"`` (needs ``polarized``).
        θ > π/2 (below the horizon) gives 0.
        """
        if wavelength_out_of_range not in ("raise", "clamp"):
            raise ValueError(
                "wavelength_out_of_range must be 'raise' or 'clamp', "
                f"got {wavelength_out_of_range!r}"
            )
        ti, pi_, to, po = np.broadcast_arrays(
            *(np.asarray(a, dtype=float) for a in (theta_i, phi_i, theta_o, phi_o))
        )
        shape = ti.shape
        ti, pi_, to, po = (a.reshape(-1) for a in (ti, pi_, to, po))
        for name, a in (("theta_i", ti), ("phi_i", pi_), ("theta_o", to), ("phi_o", po)):
            if not np.all(np.isfinite(a)):
                bad = a[~np.isfinite(a)][0]
                raise ValueError(
                    f"{name} must be finite angles [rad], got {bad} "
                    f"({int(np.sum(~np.isfinite(a)))} of {a.size} values)"
                )
        scalar, cols, mat = self._wavelength_weights(wavelength, wavelength_out_of_range)
        vals = self._grid_values(pol)[cols]
        if self.isotropic:
            locs = [
                grid.locate_clamped(self.theta_i, ti),
                grid.locate_clamped(self.theta_o, to),
                grid.locate_clamped(self.phi_d, fold_dphi(po - pi_)),
            ]
        else:
            locs = [
                grid.locate_clamped(self.theta_i, ti),
                grid.locate_periodic(self.phi_i, pi_),
                grid.locate_clamped(self.theta_o, to),
                grid.locate_periodic(self.phi_o, po),
            ]
        out = mat @ grid.multilinear(vals, locs)
        out[:, ~((ti < HALF_PI) & (to < HALF_PI) & (ti >= 0) & (to >= 0))] = 0.0
        out = out.reshape((-1, *shape))
        return out[0] if scalar else out

    def evaluate(
        self,
        wi,
        wo,
        wavelength=None,
        *,
        pol: str | None = None,
        wavelength_out_of_range: str = "raise",
    ) -> np.ndarray:
        """``f_r(wi, wo)`` [1/sr] for renderer-frame direction arrays ``wi``, ``wo`` (shape
        ``(..., 3)``, broadcast together, any nonzero length): interpolated as in the module
        docstring; 0 when ``wi.z ≤ 0`` or ``wo.z ≤ 0``. Excludes the coherent delta lobe
        (:meth:`coherent_reflectance`). Output shape: ``(n, *broadcast)`` for
        ``wavelength=None`` (n = n_wl) or a 1-D array (its length), ``broadcast`` for a scalar.
        """
        ti, pi_ = angles(wi, "wi")
        to, po = angles(wo, "wo")
        return self.evaluate_angles(
            ti, pi_, to, po, wavelength, pol=pol, wavelength_out_of_range=wavelength_out_of_range
        )

    def coherent_reflectance(
        self,
        theta_i,
        phi_i=0.0,
        wavelength=None,
        *,
        pol: str | None = None,
        wavelength_out_of_range: str = "raise",
    ) -> np.ndarray:
        """Coherent (delta-lobe) power reflectivity ``R_coh`` [-] at incidence ``theta_i``
        [rad] (renderer φi for anisotropic tables), interpolated like :meth:`evaluate`;
        ``pol`` None (unpolarized mean) or ``"h"`` / ``"v"``; 0 below the horizon."""
        ti, pi_ = np.broadcast_arrays(np.asarray(theta_i, float), np.asarray(phi_i, float))
        shape = ti.shape
        ti, pi_ = ti.reshape(-1), pi_.reshape(-1)
        for name, a in (("theta_i", ti), ("phi_i", pi_)):
            if not np.all(np.isfinite(a)):
                bad = a[~np.isfinite(a)][0]
                raise ValueError(
                    f"{name} must be finite angles [rad], got {bad} "
                    f"({int(np.sum(~np.isfinite(a)))} of {a.size} values)"
                )
        scalar, cols, mat = self._wavelength_weights(wavelength, wavelength_out_of_range)
        if pol is None:
            vals = self.coherent
        elif pol in ("h", "v"):
            vals = self.coherent_polarized[0 if pol == "h" else 1]
        else:
            raise ValueError(f"pol must be None, 'h' or 'v', got {pol!r}")
        locs = [grid.locate_clamped(self.theta_i, ti)]
        if not self.isotropic:
            locs.append(grid.locate_periodic(self.phi_i, pi_))
        out = mat @ grid.multilinear(vals[cols], locs)
        out[:, ~((ti >= 0) & (ti < HALF_PI))] = 0.0
        out = out.reshape((-1, *shape))
        return out[0] if scalar else out

    # ---------------------------------------------------------------- energy, reciprocity
    def outgoing_weights(self) -> np.ndarray:
        """Quadrature weights ``W`` over the outgoing grid (shape ``(n_to, n_pd)`` or
        ``(n_to, n_po)``) with ``Σ W·f[i, …] = ∫ f_interp cosθo dωo`` exactly for the
        interpolant."""
        wt = grid.theta_weights(self.theta_o)
        if self.isotropic:
            return wt[:, None] * grid.phi_d_weights(self.phi_d)[None, :]
        return wt[:, None] * grid.periodic_weights(self.phi_o)[None, :]

    def albedo(self) -> Albedo:
        """Directional albedo per wavelength and θi node (φi node): the incoherent part is the
        exact hemispherical integral of the interpolated table (linear in θi between nodes,
        like the table), the coherent part is ``coherent``."""
        w = self.outgoing_weights().reshape(-1)
        flat = self.values.reshape(-1, w.size)
        inc = np.empty(flat.shape[0])
        step = max(1, (1 << 22) // w.size)  # float64 blocks: a float32 table is not copied whole
        for lo in range(0, flat.shape[0], step):
            inc[lo : lo + step] = flat[lo : lo + step].astype(float) @ w
        inc = inc.reshape(self.values.shape[:-2])
        return Albedo(
            wavelengths=self.wavelengths,
            theta_i=self.theta_i,
            phi_i=self.phi_i,
            incoherent=inc,
            coherent=np.array(self.coherent),
        )

    def reciprocity_error(self) -> float:
        """Largest ``|f(wi, wo) − f(wo, wi)| / max f`` over the nodes (needs a symmetric
        grid); for polarized tables ``f_pq(wi, wo)`` is compared with ``f_qp(wo, wi)``."""
        if not self.symmetric_grid:
            raise ValueError("reciprocity at nodes needs equal θi/θo (and φi/φo) axes")
        v = self.values
        scale = max(float(v.max()), 1e-300)
        swap = (0, 2, 1, 3) if self.isotropic else (0, 3, 4, 1, 2)
        err = float(np.max(np.abs(v - v.transpose(swap)))) / scale
        if self.polarized is not None:
            p = self.polarized
            pswap = (1, 0, *(2 + s for s in swap))
            err = max(err, float(np.max(np.abs(p - p.transpose(pswap)))) / scale)
        return err

    def describe(self) -> str:
        """One-line summary: grid, wavelengths, solver, energy flags."""
        kind = "isotropic" if self.isotropic else "anisotropic"
        dims = "×".join(str(n) for n in self.values.shape[1:])
        wl = ", ".join(f"{x * 1e9:.4g}" for x in self.wavelengths[:6])
        more = "…" if self.wavelengths.size > 6 else ""
        solver = self.metadata.get("solver", "?")
        energy = self.metadata.get("energy", {}).get("remedy_applied", False)
        return (
            f"BrdfTable({kind} {dims} at λ = [{wl}{more}] nm, solver={solver}, "
            f"energy remedy applied={energy})"
        )
