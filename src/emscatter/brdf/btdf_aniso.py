"""Anisotropic BTDF tables (GO, ``ℓx ≠ ℓy``): :class:`AnisotropicBtdfTable` and its builder.

An anisotropic surface's transmission depends on the incident azimuth as well, so the table
gains a ``φi`` axis; the outgoing azimuth is kept *relative* to it (the transmitted lobe sits
near ``Δφ = π`` at every ``φi``, which a relative axis resolves with the same nodes everywhere)::

    values[w, i, a, t, d] = f_t(λ_w; θi = theta_i[i], φi = phi_i[a],
                                θt = theta_t[t], Δφ = phi_d[d])              [1/sr]

Renderer frame as :mod:`.btdf_table`: ``wi`` above (towards the light), ``wo`` below, both
pointing away from the surface, tangent ``+x`` along ``ℓx``; ``φi = φ(wi)`` and
``Δφ = φ(wo) − φ(wi)``, both on ``[0, 2π)`` (periodic, linear interpolation with wrap);
``θt = π − θ(wo)``. Symmetry: GO's slope density is centred Gaussian along the surface axes,
so the BTDF is unchanged by the mirrors ``y → −y`` (``φi → −φi``, ``Δφ → −Δφ``) and
``x → −x`` (``φi → π − φi``, ``Δφ → −Δφ``): the table stores ``φi ∈ [0, π/2]`` only (a
quarter of the nodes for the same spacing) and :meth:`AnisotropicBtdfTable.evaluate_angles`
folds any ``φi`` into it. ``f_t`` is Walter et al.'s radiance BTDF (EGSR 2007, eq. 21) with GO's
anisotropic Beckmann slopes (:func:`emscatter.solvers.kirchhoff.transmission.go.
bistatic_transmission`), exactly :func:`.btdf.btdf_at` at the nodes. For ``ℓx = ℓy`` it equals
the isotropic :class:`~.btdf_table.BtdfTable` on the same θ and Δφ nodes (tested).

:meth:`AnisotropicBtdfTable.albedo` integrates the interpolant exactly (``T`` per θi and φi
node); :meth:`AnisotropicBtdfTable.evaluate` interpolates multilinearly in the four angles.
Storage: ``n_wl · n_θi · n_φi · n_θt · n_Δφ`` values (``dtype`` float64 or float32), checked
against the memory limit before any work.

Mueller part (``polarized=True``; ``mueller[w, :, :, i, a, t, d]``, ``(n_wl, 4, 4, …grid)``,
``[:, 0, 0] = values``): GO's facet Fresnel transmission Jones matrix
(:func:`emscatter.solvers.kirchhoff.transmission.go.transmission_jones`, emscatter's h/v
bases) as a Mueller matrix scaled to ``f_t`` — exactly :func:`.btdf.mueller_btdf_at` at the
nodes, the isotropic table's construction (:func:`.btdf_table.build_btdf_table`) with the
anisotropic slopes. :meth:`AnisotropicBtdfTable.evaluate_mueller` folds ``φi`` as
:func:`fold_phi`: the half turn leaves a matrix in h/v bases unchanged (the bases turn with
the surface), each mirror maps it to ``P M P``, ``P = diag(1, 1, −1, −1)`` (a mirror reverses
the handedness of the h/v bases; the isotropic table's rule for ``Δφ < 0``); then Mitsuba's
Stokes frames at the true (unfolded) angles (:func:`.btdf.emscatter_to_mitsuba`). Storage ×17.
Rendered by the ``emscatter_dielectric`` plugin (:mod:`emscatter.render.dielectric.aniso`; the
Mueller part in ``*_polarized`` variants: :mod:`emscatter.render.dielectric.polarized`). Not
here (yet): PO.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from ..solvers.kirchhoff.common import slope_variances
from ..solvers.kirchhoff.transmission import go as gt
from . import grid
from .btdf import checked_surface
from .btdf_table import HALF_PI, _m00, default_resolution, mueller_at, mueller_result
from .build import _check_count, _check_wavelengths, default_phi, default_theta, material_eps
from .frames import angles
from .mueller import jones_to_mueller
from .sizing import format_bytes, memory_limit
from .table import BrdfTable, _as_float_array

__all__ = ["AnisotropicBtdfTable", "build_anisotropic_btdf_table", "fold_phi"]

_CHUNK = 1 << 20  # direction pairs per solver call


@dataclass(frozen=True, eq=False)
class AnisotropicBtdfTable:
    """A tabulated anisotropic BTDF (layout: module docstring).

    Parameters
    ----------
    wavelengths : (n_wl,) [m], strictly increasing.
    theta_i, theta_t : [rad] in ``[0, π/2)``; phi_i : [rad] in ``[0, π/2]`` (folded, module
        docstring); phi_d : [rad] in ``[0, 2π)``.
    values : ``f_t`` [1/sr], ``(n_wl, n_ti, n_pi, n_tt, n_pd)``, ≥ 0 and finite.
    eps : (n_wl,) real relative permittivity of the lower medium (> 0, ≠ 1).
    metadata : dict.
    mueller : optional ``(n_wl, 4, 4, n_ti, n_pi, n_tt, n_pd)`` Mueller BTDF [1/sr] in
        emscatter's h/v bases, ``[:, 0, 0] = values`` (module docstring).
    """

    wavelengths: np.ndarray
    theta_i: np.ndarray
    phi_i: np.ndarray
    theta_t: np.ndarray
    phi_d: np.ndarray
    values: np.ndarray
    eps: np.ndarray
    metadata: dict = field(default_factory=dict)
    mueller: np.ndarray | None = None

    def __post_init__(self):
        set_ = object.__setattr__
        wl = grid.check_table_wavelengths(self.wavelengths)
        set_(self, "wavelengths", wl)
        for name in ("theta_i", "theta_t"):
            set_(self, name, grid.check_axis(name, getattr(self, name), 0, HALF_PI, high_open=True))
        set_(self, "phi_i", grid.check_axis("phi_i", self.phi_i, 0, HALF_PI))
        set_(self, "phi_d", grid.check_axis("phi_d", self.phi_d, 0, grid.TWO_PI, high_open=True))
        shape = (wl.size, self.theta_i.size, self.phi_i.size, self.theta_t.size, self.phi_d.size)
        set_(self, "values", _as_float_array("values", self.values, shape, keep32=True))
        eps = np.array(self.eps, dtype=float).reshape(-1)
        if eps.shape != wl.shape:
            raise ValueError(f"eps must have one value per wavelength {wl.shape}, got {eps.shape}")
        try:
            gt.check_transmission_eps(eps)
        except ValueError as err:
            raise ValueError(f"eps: {err}") from None
        eps.setflags(write=False)
        set_(self, "eps", eps)
        if not isinstance(self.metadata, dict):
            raise TypeError(f"metadata must be a dict, got {type(self.metadata).__name__}")
        if self.mueller is not None:
            set_(self, "mueller", _checked_mueller(self.mueller, self.values))

    def replace(self, **changes) -> AnisotropicBtdfTable:
        """A copy with some fields changed (validated again)."""
        return replace(self, **changes)

    def evaluate_angles(self, theta_i, phi_i, theta_t, phi_d, wavelength=None) -> np.ndarray:
        """``f_t`` [1/sr] at ``θi``, ``φi``, ``θt`` (from the downward normal), ``Δφ`` [rad],
        broadcast; ``wavelength`` as :meth:`.table.BrdfTable.evaluate_angles` (None: every
        table wavelength on a leading axis). Zero for ``θi`` or ``θt`` outside ``[0, π/2)``."""
        arrs = np.broadcast_arrays(
            *(np.asarray(a, dtype=float) for a in (theta_i, phi_i, theta_t, phi_d))
        )
        shape = arrs[0].shape
        ti, pi_, tt, pd = (a.reshape(-1) for a in arrs)
        names = ("theta_i", "phi_i", "theta_t", "phi_d")
        for name, a in zip(names, (ti, pi_, tt, pd), strict=True):
            if not np.all(np.isfinite(a)):
                raise ValueError(f"{name} must be finite angles [rad], got {a[~np.isfinite(a)][0]}")
        pi_, pd = fold_phi(pi_, pd)
        scalar, cols, mat = BrdfTable._wavelength_weights(self, wavelength, "raise")
        locs = [
            grid.locate_clamped(self.theta_i, ti),
            grid.locate_clamped(self.phi_i, pi_),
            grid.locate_clamped(self.theta_t, tt),
            grid.locate_periodic(self.phi_d, pd),
        ]
        out = mat @ grid.multilinear(self.values[cols], locs)
        out[:, ~((ti >= 0) & (ti < HALF_PI) & (tt >= 0) & (tt < HALF_PI))] = 0.0
        out = out.reshape((-1, *shape))
        return out[0] if scalar else out

    def evaluate(self, wi, wo, wavelength=None) -> np.ndarray:
        """``f_t(wi → wo)`` [1/sr] for renderer directions (``(..., 3)``, broadcast): ``wi``
        above (``z > 0``), ``wo`` below (``z < 0``); 0 for pairs not on opposite sides this
        way round."""
        ti, pi_ = angles(wi, "wi")
        to, po = angles(wo, "wo")
        return self.evaluate_angles(ti, pi_, math.pi - to, po - pi_, wavelength)

    def evaluate_mueller(self, wi, wo, wavelength=None, *, frame: str = "mitsuba") -> np.ndarray:
        """Mueller BTDF ``(4, 4, ...)`` [1/sr] at renderer directions (as :meth:`evaluate`;
        ``wavelength``: None → every table wavelength on a leading axis, a scalar → none), in
        Mitsuba's Stokes frames (``frame="mitsuba"``, what a ``*_polarized`` BSDF returns
        divided by ``cosθ`` of the light) or emscatter's h/v bases (``"emscatter"``), as
        :func:`.btdf.mueller_btdf_at`; the folding of ``φi``: module docstring. Needs
        ``mueller`` (``polarized=True``)."""
        if self.mueller is None:
            raise ValueError(
                "this anisotropic BTDF table has no Mueller part (build it with polarized=True)"
            )
        if frame not in ("mitsuba", "emscatter"):
            raise ValueError(f"frame must be 'mitsuba' or 'emscatter', got {frame!r}")
        ti, pi_ = angles(wi, "wi")
        to, po = angles(wo, "wo")
        ti, pi_, to, po = (a.reshape(-1) for a in np.broadcast_arrays(ti, pi_, to, po))
        shape = np.broadcast_shapes(np.shape(wi)[:-1], np.shape(wo)[:-1])
        tt = math.pi - to
        p = np.remainder(pi_, math.pi)
        flip = p > HALF_PI
        fpi, fpd = fold_phi(pi_, po - pi_)
        scalar, cols, mat = BrdfTable._wavelength_weights(self, wavelength, "raise")
        locs = [
            grid.locate_clamped(self.theta_i, ti),
            grid.locate_clamped(self.phi_i, fpi),
            grid.locate_clamped(self.theta_t, tt),
            grid.locate_periodic(self.phi_d, fpd),
        ]
        vals = mueller_at(self.mueller, cols, mat, locs)
        pp = np.array([1.0, 1.0, -1.0, -1.0])
        vals = np.where(flip, vals * np.outer(pp, pp)[:, :, None], vals)  # P M P (mirrored)
        return mueller_result(vals, ti, pi_, tt, po, frame, shape, scalar)

    def outgoing_weights(self) -> np.ndarray:
        """``W`` (``(n_tt, n_pd)``) with ``Σ W f[i, a] = ∫ f_t,interp cosθt dωt`` exactly."""
        return grid.theta_weights(self.theta_t)[:, None] * grid.periodic_weights(self.phi_d)

    def albedo(self) -> np.ndarray:
        """Transmitted fraction ``T`` [-] per wavelength, θi and φi node,
        ``(n_wl, n_ti, n_pi)``: the exact integral of the interpolant over the lower
        hemisphere."""
        return np.einsum("wiatd,td->wia", self.values.astype(float), self.outgoing_weights())

    def describe(self) -> str:
        """One-line summary."""
        dims = "×".join(str(n) for n in self.values.shape[1:])
        wl = ", ".join(f"{x * 1e9:.4g}" for x in self.wavelengths[:6])
        pol = ", Mueller" if self.mueller is not None else ""
        return (
            f"AnisotropicBtdfTable({dims} at λ = [{wl}] nm, solver=kirchhoff-go-transmission{pol})"
        )


def _checked_mueller(mueller, values) -> np.ndarray:
    m = np.asarray(mueller)
    m = np.asarray(m, dtype=np.float32 if m.dtype == np.float32 else float)
    if m.flags.writeable:  # a caller's array: copy before freezing (the builder's is frozen)
        m = m.copy()
    want = (values.shape[0], 4, 4, *values.shape[1:])
    if m.shape != want:
        raise ValueError(f"mueller must have shape {want}, got {m.shape}")
    if not np.all(np.isfinite(m)):
        raise ValueError("mueller holds NaN or inf")
    scale = max(float(np.max(values)), 1e-300)
    if np.max(np.abs(m[:, 0, 0] - values)) > 1e-6 * scale:
        raise ValueError("mueller[:, 0, 0] must equal values (the unpolarized BTDF)")
    m.setflags(write=False)
    return m


def fold_phi(phi_i, phi_d) -> tuple[np.ndarray, np.ndarray]:
    """``(φi, Δφ)`` [rad] folded by the surface's mirror symmetries into ``φi ∈ [0, π/2]``
    (module docstring): ``φi → φi mod π`` (the two mirrors together: a half turn), then
    ``φi > π/2 → (π − φi, −Δφ)``."""
    p = np.remainder(np.asarray(phi_i, float), math.pi)
    flip = p > HALF_PI
    return np.where(flip, math.pi - p, p), np.where(flip, -phi_d, phi_d)


def build_anisotropic_btdf_table(
    surface,
    material,
    wavelengths,
    *,
    n_theta: int = 30,
    n_phi_i: int = 9,
    n_theta_t: int | None = None,
    n_phi: int | None = None,
    theta_i=None,
    phi_i=None,
    theta_t=None,
    phi_d=None,
    dtype="float64",
    memory_limit_bytes: int | None = None,
    polarized: bool = False,
    **options,
) -> AnisotropicBtdfTable:
    """The GO BTDF table of a rough lossless dielectric with an anisotropic (or isotropic)
    surface: Walter et al. 2007 with GO's per-direction Beckmann slopes.

    ``surface``: a 2-D :class:`emscatter.spectra.Roughness` (``length_y`` ≠ ``length`` for an
    anisotropic one); ``material``: lossless (real ``ε > 0``, ``ε ≠ 1``, or anything
    :func:`emscatter.materials.eps_at` takes); ``wavelengths`` [m]. Grid: ``n_theta`` θi
    nodes ``k·90°/n``, ``n_phi_i`` φi nodes on ``[0, π/2]`` inclusive (the rest by symmetry;
    9: 11.25°), ``n_theta_t`` θt nodes and
    ``n_phi`` Δφ nodes on ``[0, 2π)`` (None: from the lobe width of the *larger* rms slope,
    :func:`.btdf_table.default_resolution`, Δφ doubled for the full circle), or explicit
    axes [rad]. The stored grid's bytes are checked first (``memory_limit_bytes``, else what
    the process may allocate): a ``MemoryError`` names the estimate and what reduces it.
    ``polarized=True`` adds the Mueller part (module docstring; 17× the storage, checked).
    ``options``: ``shadowing``, ``slope_variance``, ``k_max`` as the isotropic table.
    """
    rough = checked_surface(surface, options, "a BTDF table")
    if dtype not in ("float64", "float32", np.float64, np.float32):
        raise ValueError(f"dtype must be 'float64' or 'float32', got {dtype!r}")
    dt = np.dtype(dtype)
    wl = _check_wavelengths(wavelengths)
    n_theta = _check_count("n_theta", n_theta, 2)
    n_phi_i = _check_count("n_phi_i", n_phi_i, 2)
    if not isinstance(polarized, bool):
        raise ValueError(f"polarized must be True or False, got {polarized!r}")
    eps = np.empty(wl.size)
    for j, lam in enumerate(wl):
        try:
            eps[j] = float(gt.check_transmission_eps(material_eps(material, float(lam))))
        except ValueError as err:
            raise ValueError(f"material {material!r} at λ = {lam:.6g} m: {err}") from None
    if (theta_t is None and n_theta_t is None) or (phi_d is None and n_phi is None):
        sx, sy = slope_variances(
            rough, options.get("k_max"), options.get("slope_variance"), k=2 * math.pi / wl[0]
        )
        m = math.sqrt(2 * float(np.min([sx, sy])))  # the narrower direction sets the spacing
        auto_t, auto_p = default_resolution(m, float(eps[0]), n_theta)
        n_theta_t = auto_t if n_theta_t is None else n_theta_t
        n_phi = 2 * (auto_p - 1) if n_phi is None else n_phi
    ti = _axis("theta_i", theta_i, default_theta, n_theta, HALF_PI)
    if phi_i is None:
        pi_ = np.linspace(0.0, HALF_PI, n_phi_i)
    else:
        pi_ = grid.check_axis("phi_i", phi_i, 0, HALF_PI)
    if theta_t is None:
        n_theta_t = _check_count("n_theta_t", n_theta_t, 2)
    if phi_d is None:
        n_phi = _check_count("n_phi", n_phi, 4)
    tt = _axis("theta_t", theta_t, default_theta, n_theta_t, HALF_PI)
    pd = _axis("phi_d", phi_d, default_phi, n_phi, grid.TWO_PI)
    need = (17 if polarized else 1) * wl.size * ti.size * pi_.size * tt.size * pd.size
    need = need * dt.itemsize + (80 if polarized else 40) * 8 * _CHUNK
    limit, where = (
        (memory_limit_bytes, "memory_limit_bytes") if memory_limit_bytes else memory_limit()
    )
    if limit is not None and need > limit:
        raise MemoryError(
            f"the anisotropic BTDF table needs about {format_bytes(need)}, more than {where} "
            f"allows ({format_bytes(int(limit))}); use fewer nodes (n_theta, n_phi_i, "
            "n_theta_t, n_phi), fewer wavelengths, dtype='float32'"
            + (" or polarized=False (the Mueller part is 16× the table)" if polarized else "")
        )
    values = np.empty((wl.size, ti.size, pi_.size, tt.size, pd.size), dtype=dt)
    mueller = np.empty((wl.size, 4, 4, *values.shape[1:]), dtype=dt) if polarized else None
    rows = max(1, _CHUNK // (pi_.size * tt.size * pd.size))
    slopes = None
    for j, lam in enumerate(wl):
        k = 2 * math.pi / lam
        for lo in range(0, ti.size, rows):
            a, p, b, c = np.meshgrid(ti[lo : lo + rows], pi_, tt, pd, indexing="ij")
            # renderer → emscatter: φi_em = φ(wi) + π, φt = φ(wo) = φ(wi) + Δφ
            res = gt.bistatic_transmission(rough, eps[j], k, a, b, p + c, p + math.pi, **options)
            values[j, lo : lo + rows] = res.unpolarized() / (4 * math.pi * np.cos(a) * np.cos(b))
            if polarized:  # the facet's Jones matrix as a Mueller matrix (.btdf_table)
                jones = gt.transmission_jones(eps[j], a, b, p + c, p + math.pi)
                mm = jones_to_mueller(jones) * (values[j, lo : lo + rows] / _m00(jones))
                mueller[j, :, :, lo : lo + rows] = mm
                mueller[j, 0, 0, lo : lo + rows] = values[j, lo : lo + rows]
            slopes = [float(np.mean(x)) for x in res.info["slope_variance"]]
    values.setflags(write=False)
    if mueller is not None:
        mueller.setflags(write=False)
    meta = {
        "kind": "btdf-anisotropic",
        "solver": "kirchhoff-go-transmission",
        "source": "Walter, Marschner, Li & Torrance 2007 (EGSR), eqs. 16, 21, 23, 25, 27",
        "shadowing": gt.check_transmission_shadowing(options.get("shadowing", True)),
        "material": material if isinstance(material, (int, float, str)) else repr(material),
        "units": {"values": "1/sr", "angles": "rad", "wavelengths": "m"},
        "frame": "phi_i = phi(wi) folded into [0, pi/2] by the x and y mirrors, phi_d = "
        "phi(wo) - phi(wi) on [0, 2pi), tangent +x along length",
        "slope_variance": slopes,  # per direction (s_x, s_y), last wavelength
    }
    return AnisotropicBtdfTable(
        wavelengths=wl, theta_i=ti, phi_i=pi_, theta_t=tt, phi_d=pd, values=values, eps=eps,
        metadata=meta, mueller=mueller,
    )  # fmt: skip


def _axis(name, given, default, n, high):
    if given is None:
        return default(n)
    return grid.check_axis(name, given, 0, high, high_open=True)
