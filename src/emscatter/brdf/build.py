"""Build a :class:`~.table.BrdfTable` from any solver (or ``"auto"``) through
:func:`emscatter.api.bistatic`.

One solver call per wavelength, vectorized over the whole angle grid; only the reciprocal
half of the grid is computed (``θi ≤ θo`` node pairs, or ``(θi, φi) ≤ (θo, φo)`` for
anisotropic tables) and the other half is filled by reciprocity,
``σ⁰_pq(ωi → ωo) = σ⁰_qp(ωo → ωi)`` — tested against direct evaluation. The coherent
reflectivity is computed once per wavelength on the θi nodes only; the solvers' own coherent
part is skipped inside the big call where they offer ``coherent=False`` (SPM's second-order
quadrature).

Warnings: the solvers run with ``out_of_range="ignore"`` under ``"warn"``, and the table
warns once per cause when it is built — one :class:`~emscatter.solvers.select.ValidityWarning`
per solver and failed check, at the caller's line, naming the wavelengths and the θ nodes and
advising only what :func:`build_table` accepts (``out_of_range="raise"`` / ``"ignore"``). Any
other warning raised inside is passed on once per distinct message, also at the caller's line.

Geometric optics: its σ⁰ is the stationary-phase limit of the *whole* Kirchhoff intensity,
so adding the Kirchhoff coherent term would count the specular energy twice
(:mod:`emscatter.solvers.kirchhoff.go`); GO tables have ``coherent = 0`` and say so in
``metadata["coherent"]``.
"""

from __future__ import annotations

import inspect
import math
import numbers
import re
import warnings

import numpy as np

from .. import api, materials, solvers
from ..constants import SPEED_OF_LIGHT
from ..conventions import check_positive
from ..fresnel import check_eps
from ..scattering import Scattering
from ..solvers import select
from ..spectra import check_roughness
from . import chunks, frames, grid, sizing
from .energy import record_albedo
from .progress import build_progress
from .progress import tick as _tick
from .table import FORMAT_VERSION, BrdfTable
from .transmittance import check_transmission, finish_energy

__all__ = ["build_table", "default_theta", "default_phi_d", "default_phi", "material_eps"]


def default_theta(n: int) -> np.ndarray:
    """``n`` uniform θ nodes ``k·90°/n``, k = 0 … n−1 [rad] (0° … 89° for n = 90)."""
    n = _check_count("n_theta", n, 2)
    return np.arange(n) * (0.5 * math.pi / n)


def default_phi_d(n: int) -> np.ndarray:
    """``n`` uniform Δφ nodes on ``[0, π]`` inclusive [rad]."""
    n = _check_count("n_phi", n, 2)
    return np.linspace(0.0, math.pi, n)


def default_phi(n: int) -> np.ndarray:
    """``n`` uniform φ nodes ``2πk/n`` on ``[0, 2π)`` [rad] (anisotropic tables)."""
    n = _check_count("n_phi", n, 4)
    return np.arange(n) * (2 * math.pi / n)


def _check_count(name: str, n, low: int) -> int:
    if isinstance(n, bool) or not isinstance(n, numbers.Integral) or n < low:
        raise ValueError(f"{name} must be an integer ≥ {low}, got {n!r}")
    return int(n)


def material_eps(material, wavelength: float):
    """Relative permittivity (``exp(−iωt)``, ``Im ε ≥ 0``) of ``material`` at ``wavelength``
    [m]: anything :func:`emscatter.materials.eps_at` takes (a number, ``"pec"``, a material
    name like ``"Au"`` or ``"itu:concrete"``, a :class:`~emscatter.materials.Material`) or a
    callable ``eps(wavelength [m])``."""
    if callable(material) and not isinstance(material, materials.Material):
        return check_eps(np.asarray(material(wavelength)).item(), "material")
    eps = materials.eps_at(material, wavelength=wavelength)
    return eps if isinstance(eps, str) else check_eps(np.asarray(eps).item(), "material")


def _describe_material(material) -> dict | str:
    """A JSON-able description: the material's ``to_dict()`` (round-trips through
    :func:`emscatter.materials.from_dict`) or a string for callables."""
    if callable(material) and not isinstance(material, materials.Material):
        return f"callable {getattr(material, '__name__', type(material).__name__)}(wavelength)"
    return materials.as_material(material).to_dict()


def _check_wavelengths(wavelengths) -> np.ndarray:
    wl = np.atleast_1d(np.asarray(wavelengths, dtype=float))
    if wl.ndim != 1 or wl.size == 0:
        raise ValueError(f"wavelengths must be a 1-D array [m], got shape {wl.shape}")
    for x in wl:
        check_positive("wavelength", float(x), unit="m")
    if np.any(np.diff(wl) <= 0):
        raise ValueError(f"wavelengths must be strictly increasing [m], got {wl!r}")
    return wl


def _solver_name(rough, k, method, eps, out_of_range) -> str:
    name, _, _, _ = api.resolve_method(rough, k, method, "ignore", eps)
    return name


#: The API computes ``Scattering.coherent`` lazily (BOARD interface 3, reliability): then it
#: skips the solvers' coherent part by itself and must not be given ``coherent=False``.
_API_LAZY_COHERENT = hasattr(Scattering, "coherent_computed")


def _bistatic(rough, eps, wavelength, name, ti, pi_, to, po, out_of_range, options):
    """``api.bistatic`` at renderer-frame angles (converted by :func:`frames.to_emscatter`)."""
    et, es, ps, ei = frames.to_emscatter(ti, pi_, to, po)
    return api.bistatic(
        rough,
        eps,
        wavelength=wavelength,
        theta_i=et,
        theta_s=es,
        phi_s=ps,
        phi_i=ei,
        method=name,
        out_of_range=out_of_range,
        **options,
    )


def _sigma0(rough, eps, wavelength, name, ti, to, po, pi_, out_of_range, options, polarized):
    """Unpolarized (and per-pair) f_r at renderer angles: ``(f, f_pol or None, info)``."""
    opts = dict(options)
    if not _API_LAZY_COHERENT:  # an API that does not defer the coherent part itself
        module = solvers.get(name)
        if "coherent" in inspect.signature(module.bistatic).parameters:
            opts.setdefault("coherent", False)
    res = _bistatic(rough, eps, wavelength, name, ti, pi_, to, po, out_of_range, opts)
    sig = res.sigma0
    if not np.all(np.isfinite(sig)):
        raise ValueError(
            f"solver {name!r} returned NaN/inf σ⁰ at λ = {wavelength:.6g} m (out_of_range="
            f"{out_of_range!r}?): a table cannot hold them"
        )
    norm = 1.0 / (4 * math.pi * np.cos(ti) * np.cos(to))
    f_pol = sig * norm if polarized else None
    f = 0.5 * sig.sum(axis=(0, 1)) * norm
    return f, f_pol, res.info


def _coherent(rough, eps, wavelength, name, theta, phi, out_of_range, options):
    """Coherent reflectivity (h, v) on the θi nodes (× φi nodes): shape ``(2, *grid)``."""
    if name == "go":
        shape = theta.shape if phi is None else (theta.size, phi.size)
        return np.zeros((2, *shape))
    ti = theta if phi is None else theta[:, None]
    pr = np.zeros_like(ti) if phi is None else phi[None, :]
    opts = {k: v for k, v in options.items() if k != "coherent"}
    res = _bistatic(rough, eps, wavelength, name, ti, pr, ti, pr + math.pi, out_of_range, opts)
    coh = np.clip(np.asarray(res.coherent, dtype=float), 0.0, 1.0)
    if not np.all(np.isfinite(coh)):
        raise ValueError(f"solver {name!r} returned a NaN coherent part at λ = {wavelength} m")
    return coh


def build_table(
    surface,
    material,
    wavelengths,
    *,
    method: str = "auto",
    resolution: tuple[int, int] | None = None,
    theta=None,
    phi=None,
    anisotropic: bool | None = None,
    polarized: bool = False,
    energy: str = "rescale",
    transmission="auto",
    out_of_range: str = "warn",
    tol: float | None = None,
    tol_floor: float = 1e-2,
    dtype="float64",
    memory_limit: int | None = None,
    progress: bool | None = None,
    **options,
) -> BrdfTable:
    """A BRDF table of ``surface`` (2-D roughness) over ``material`` at ``wavelengths`` [m].

    Parameters
    ----------
    surface : :class:`emscatter.spectra.Roughness` with ``dimension=2`` (lengths [m]).
    material : permittivity, ``"pec"``, a material (name or :mod:`emscatter.materials`
        object) or a callable ``eps(wavelength [m])``; see :func:`material_eps`.
    wavelengths : [m], strictly increasing; only these are computed.
    method : ``"auto"`` or a solver name (``"spm"``, ``"go"``, ``"po"``, …); ``"auto"`` may
        pick a different solver per wavelength (recorded per wavelength).
    resolution : ``(n_theta, n_phi)``: θ nodes ``k·90°/n_theta`` (shared by θi and θo) and
        ``n_phi`` Δφ nodes on ``[0, π]`` (isotropic) or φ nodes on ``[0, 2π)`` (anisotropic).
        None (default): from the width of the specular lobe (:mod:`.sizing`): 90 × 180 (1°)
        unless the lobe needs finer nodes (GO ``m = 0.05``: 223 × 446), at most 256 θ nodes;
        a grid too coarse for the lobe (beyond that cap, or anisotropic tables, which keep
        90 × 180) warns with the predicted error and the resolution that meets it.
    theta, phi : explicit axes [rad] instead (θ in ``[0, π/2)``; φ as above).
    tol : target interpolation error instead of a fixed resolution: the grid is refined from
        a coarse one until the interpolant is within ``tol`` of direct evaluation at every
        interval midpoint (:mod:`.adaptive`; error relative to ``max(|f|, tol_floor · peak)``);
        the report is in ``metadata["resolution"]``.
    anisotropic : None → from the surface (``surface.is_isotropic``).
    polarized : also store ``f_r`` per polarization pair.
    energy : ``"rescale"`` (default) applies the reciprocal energy remedy
        (:mod:`.energy`) where the albedo exceeds 1; ``"off"`` only records the albedo
        (diagnostics — such a table may hand a renderer energy it does not have).
    transmission : what the reflection leaves room for, ``R ≤ 1 − T``: ``"auto"`` (default) the
        GO transmitted fraction ``T(θi)`` of dielectric wavelengths (``Re ε > 0``, loss tangent
        ≤ 1e-2; :mod:`.transmittance`, ~0.4 s per wavelength; conductors: ``T = 0``, no cost),
        ``"off"`` (``R ≤ 1``), a :class:`~.btdf_table.BtdfTable` (its albedo) or ``T`` per node;
        recorded in ``metadata["energy"]`` (``T``, ``transmission``).
    out_of_range : the solvers' validity policy (``"warn"``, ``"raise"``, ``"ignore"``).
    dtype : storage of ``values`` (and ``polarized``): ``"float64"`` or ``"float32"`` (half
        the memory; ~6e-8 relative rounding, far below any interpolation error).
    memory_limit : bytes the build may use; None → what this process may still allocate
        (``EMSCATTER_MEMORY_LIMIT`` if set, else the address-space / cgroup limit or the
        available memory, :func:`.sizing.memory_limit`). The build's peak is estimated before
        any work (:func:`.sizing.estimate_bytes`); over the limit a ``MemoryError`` names the
        estimate, the limit and what reduces it.
    progress : a tqdm bar over the wavelengths on stderr, advanced per chunk (:mod:`.progress`):
        None (default) only when stderr is a terminal, True always, False never.
    options : passed to the solver (e.g. ``shadowing=False`` for GO).
    """
    rough = check_roughness(surface, "surface")
    if rough.dimension != 2:
        raise ValueError("a BRDF table needs a 2-D surface (dimension=2), got a 1-D profile")
    wl = _check_wavelengths(wavelengths)
    if energy not in ("rescale", "off"):
        raise ValueError(f"energy must be 'rescale' or 'off', got {energy!r}")
    check_transmission(transmission)
    if out_of_range == "nan":
        raise ValueError(
            "out_of_range='nan' cannot build a table (a table holds no NaN); use 'warn' "
            "(the default), 'raise' or 'ignore'"
        )
    if out_of_range not in OUT_OF_RANGE:
        raise ValueError(f"out_of_range must be one of {OUT_OF_RANGE}, got {out_of_range!r}")
    dtype = _check_dtype(dtype)
    if memory_limit is not None and (
        isinstance(memory_limit, bool)
        or not isinstance(memory_limit, numbers.Real)
        or not memory_limit > 0
    ):
        raise ValueError(f"memory_limit must be a positive number of bytes, got {memory_limit!r}")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        args = (
            rough,
            material,
            wl,
            method,
            resolution,
            theta,
            phi,
            anisotropic,
            polarized,
            (energy, transmission),
            out_of_range,
            tol,
            tol_floor,
            options,
            dtype,
            memory_limit,
        )
        too_large = None
        try:
            with build_progress(wl.size, progress):
                table, reports = _build(*args)
        except sizing.TableTooLarge as exc:
            too_large = exc
    if too_large is not None:  # the resolution note (if any) still reaches the caller
        _pass_on(caught, stacklevel=3)
        raise too_large
    if out_of_range == "warn":
        for message in validity_messages(reports):
            warnings.warn(message, select.ValidityWarning, stacklevel=2)
    _pass_on(caught, stacklevel=3)
    return table


#: The ``out_of_range`` policies a table takes (``"nan"`` would put NaN in the table).
OUT_OF_RANGE = ("warn", "raise", "ignore")
#: Storage types of a table's values.
DTYPES = ("float64", "float32")


def _check_dtype(dtype) -> np.dtype:
    try:
        dt = np.dtype(dtype)
    except TypeError:
        dt = None
    if dt is None or dt.name not in DTYPES:
        raise ValueError(f"dtype must be one of {DTYPES}, got {dtype!r}")
    return dt


def _pass_on(caught, *, stacklevel: int) -> None:
    """Warn again, once per (category, message), every warning recorded while building."""
    seen = set()
    for w in caught:
        key = (w.category, str(w.message))
        if key in seen:
            continue
        seen.add(key)
        warnings.warn(w.message, w.category, stacklevel=stacklevel)


def _build(
    rough,
    material,
    wl,
    method,
    resolution,
    theta,
    phi,
    anisotropic,
    polarized,
    energy,
    out_of_range,
    tol,
    tol_floor,
    options,
    dtype="float64",
    memory_limit=None,
):
    """The table and ``[(wavelength [m], solver, validity report), ...]`` of its fill calls
    (``energy``: the mode or ``(mode, transmission)``);
    the solvers run with ``out_of_range="ignore"`` when the policy is ``"warn"`` (the table
    warns once per cause instead, :func:`validity_messages`)."""
    policy = "ignore" if out_of_range == "warn" else out_of_range
    energy, transmission = energy if isinstance(energy, tuple) else (energy, "off")
    if resolution is not None and not (
        isinstance(resolution, tuple | list) and len(resolution) == 2
    ):
        raise ValueError(f"resolution must be (n_theta, n_phi) or None, got {resolution!r}")
    aniso = (not rough.is_isotropic) if anisotropic is None else bool(anisotropic)
    setups = []
    for lam in wl:
        eps = material_eps(material, float(lam))
        setups.append(
            (float(lam), eps, _solver_name(rough, 2 * math.pi / lam, method, eps, out_of_range))
        )
    if resolution is None:
        explicit = theta is not None and phi is not None
        width = sizing.lobe_width(rough, wl, [name for _, _, name in setups])
        resolution, note = sizing.auto_resolution(width, aniso)
        if note is not None and tol is None and not explicit:
            warnings.warn(note, UserWarning, stacklevel=2)
    theta_ax = default_theta(resolution[0]) if theta is None else np.asarray(theta, float)
    if phi is None:
        phi_ax = default_phi(resolution[1]) if aniso else default_phi_d(resolution[1])
    else:
        phi_ax = np.asarray(phi, float)
    theta_ax = grid.check_axis("theta", theta_ax, 0.0, 0.5 * math.pi, high_open=True)
    if aniso:
        phi_ax = grid.check_axis("phi", phi_ax, 0.0, grid.TWO_PI, high_open=True)
    else:
        phi_ax = grid.check_axis("phi", phi_ax, 0.0, math.pi)
    fill = _fill_anisotropic if aniso else _fill_isotropic
    if tol is None:  # before any work (the adaptive grid is bounded by its node limits)
        sizing.check_memory(
            theta_ax.size,
            phi_ax.size,
            wl.size,
            anisotropic=aniso,
            polarized=polarized,
            dtype=dtype,
            energy=energy,
            limit=memory_limit,
        )
    resolution_report = {
        "n_theta": int(theta_ax.size),
        "n_phi": int(phi_ax.size),
        "adaptive": False,
    }
    if tol is not None:
        with _at_wavelength(None):
            theta_ax, phi_ax, resolution_report = _adaptive(
                rough, setups, aniso, tol, tol_floor, policy, options
            )
    shape = (theta_ax.size, phi_ax.size) * 2 if aniso else (theta_ax.size,) * 2 + (phi_ax.size,)
    values = np.empty((wl.size, *shape), dtype=dtype)
    pol_values = np.empty((wl.size, 2, 2, *shape), dtype=dtype) if polarized else None
    coh = []
    per_wl = []
    reports = []
    for j, (lam, eps, name) in enumerate(setups):
        with _at_wavelength(lam):
            info = fill(
                rough,
                eps,
                float(lam),
                name,
                theta_ax,
                phi_ax,
                policy,
                options,
                values[j],
                None if pol_values is None else pol_values[j],
            )
            coh.append(
                _coherent(
                    rough,
                    eps,
                    float(lam),
                    name,
                    theta_ax,
                    phi_ax if aniso else None,
                    policy,
                    options,
                )
            )
        validity = info.get("validity", {})
        reports.append((float(lam), name, validity))
        per_wl.append(
            {
                "wavelength": float(lam),
                "solver": name,
                "eps": [float(np.real(eps)), float(np.imag(eps))] if eps != "pec" else "pec",
                "valid": bool(validity.get("valid", True)),
                "reasons": list(
                    dict.fromkeys(
                        [*validity.get("reasons", []), *validity.get("angle_reasons", [])]
                    )
                ),
            }
        )
    coh = np.stack(coh, axis=1)  # (2, n_wl, ...)
    solvers = sorted({p["solver"] for p in per_wl})
    meta = {
        "format_version": FORMAT_VERSION,
        "emscatter_version": _version(),
        "solver": solvers[0] if len(solvers) == 1 else "+".join(solvers),
        "resolution": resolution_report,
        "method_requested": method,
        "per_wavelength": per_wl,
        "surface": rough.describe(),
        "surface_params": _surface_params(rough),
        "material": _describe_material(material),
        "options": {k: v for k, v in options.items() if _jsonable_scalar(v)},
        "units": {"values": "1/sr", "wavelengths": "m", "angles": "rad", "coherent": "-"},
        "frame": "renderer: wi, wo point away from the surface, normal +z, tangent +x, "
        "mirror at phi_o = phi_i + pi",
        "coherent": "zero: GO's sigma0 already holds the whole Kirchhoff intensity"
        if solvers == ["go"]
        else "solver's coherent reflectivity (delta lobe, not in values)",
    }
    grid_kw = {"phi_i": phi_ax, "phi_o": phi_ax} if aniso else {"phi_d": phi_ax}
    for arr in (values, pol_values):
        if arr is not None:
            arr.setflags(write=False)  # the table takes them without a copy
    table = BrdfTable(
        wavelengths=wl,
        theta_i=theta_ax,
        theta_o=theta_ax,
        values=values,
        coherent=0.5 * (coh[0] + coh[1]),
        coherent_polarized=coh,
        polarized=None if pol_values is None else np.moveaxis(pol_values, 0, 2),
        metadata=meta,
        **grid_kw,
    )
    phi_n = phi_ax if aniso else None
    args = (rough, setups, theta_ax, phi_n, options)
    return finish_energy(table, energy, transmission, *args), reports


class _at_wavelength:
    """Re-raise a :class:`~emscatter.solvers.select.ValidityError` (``out_of_range="raise"``)
    with the wavelength it happened at (``None``: during the adaptive refinement)."""

    def __init__(self, lam):
        self.lam = lam

    def __enter__(self):
        return self

    def __exit__(self, kind, exc, tb):
        if kind is not None and issubclass(kind, select.ValidityError):
            where = "refining the grid (tol=)" if self.lam is None else _lam_text(self.lam)
            raise select.ValidityError(
                f"build_table at {where}: {exc} (out_of_range='warn' builds the table anyway "
                "and warns, 'ignore' only records)"
            ) from None
        return False


def _lam_text(lam: float) -> str:
    """``"λ = 550 nm"`` for light, ``"λ = 0.0107 m (28 GHz)"`` for radio."""
    if lam < 1e-5:
        return f"λ = {lam * 1e9:.4g} nm"
    from ..materials.core import format_frequency

    return f"λ = {lam:.4g} m ({format_frequency(SPEED_OF_LIGHT / lam)})"


_ANGLE_REASON = re.compile(
    r"^(?P<check>[^:]+): fails for (?P<range>θi (?:∈ \[[^\]]*\]|= [^(]*?)) "
    r"\((?P<n>\d+) of (?P<m>\d+) angles\); (?P<why>.*)$"
)


def validity_messages(reports) -> list[str]:
    """One warning text per (solver, failed check) over every wavelength of a table.

    ``reports``: ``[(wavelength [m], solver, validity report), ...]`` from the fill calls.
    Each text names the solver, the check, the wavelengths with the θ nodes where it fails and
    the requirement with its worst value, and the policies :func:`build_table` takes."""
    causes: dict[tuple[str, str], list] = {}
    for lam, name, rep in reports:
        angle_reasons = list(rep.get("angle_reasons", []))
        for text in dict.fromkeys([*rep.get("reasons", []), *angle_reasons]):
            m = _ANGLE_REASON.match(text) if text in angle_reasons else None
            check = m["check"] if m else text.split(":", 1)[0]
            causes.setdefault((name, check.strip()), []).append((lam, text, m))
    out = []
    for (name, check), items in causes.items():
        if all(m is not None for _, _, m in items):
            where = ", ".join(
                f"{_lam_text(lam)} for {m['range']} ({m['n']} of {m['m']} θ nodes)"
                for lam, _, m in items
            )
            worst = max(items, key=lambda it: int(it[2]["n"]))
            why = f"{worst[2]['why']} ({_lam_text(worst[0])})"
        else:
            where = ", ".join(_lam_text(lam) for lam, _, _ in items)
            whys = [text.split(":", 1)[-1].strip() for _, text, _ in items]
            if len(items) == 1:
                why = whys[0]
            else:  # the value differs per wavelength: each one
                why = "; ".join(
                    f"{_lam_text(lam)}: {w}"
                    for (lam, _, _), w in zip(items[:4], whys, strict=False)
                ) + (f"; and {len(items) - 4} more" if len(items) > 4 else "")
        out.append(
            f"build_table: method {name!r} is outside its validity ({check}) at {where}: {why}. "
            "The table holds the values as computed (metadata['per_wavelength'] keeps the "
            "reasons); out_of_range='raise' stops instead, 'ignore' records without warning, "
            "or choose another method="
        )
    return out


def _adaptive(rough, setups, aniso, tol, floor, out_of_range, options):
    """Axes refined to ``tol`` (:func:`.adaptive.refine_axes`) from a 10 × 13 (isotropic) or
    10 × 16 (anisotropic) start."""
    from .adaptive import refine_axes

    def direct(ti, pi_, to, po):
        return np.stack(
            [
                _sigma0(rough, eps, lam, name, ti, to, po, pi_, out_of_range, options, False)[0]
                for lam, eps, name in setups
            ]
        )

    theta0 = default_theta(10)
    phi0 = default_phi(16) if aniso else default_phi_d(13)
    theta, phi, report = refine_axes(direct, theta0, phi0, anisotropic=aniso, tol=tol, floor=floor)
    return theta, phi, {**report, "adaptive": True}


def _chunked_sigma0(rough, eps, lam, name, angles, rows, out_of_range, options, polarized):
    """``_sigma0`` over ``rows`` pair rows of the angle arrays (``ti, to, po, pi_``, each of
    ``rows`` rows or broadcasting from 1), at most :data:`.sizing.CHUNK_PAIRS` points a call:
    yields ``(slice, f, f_pol, info)``."""
    width = max(int(np.broadcast_shapes(*(np.shape(a) for a in angles))[-1]), 1)
    step = max(1, sizing.CHUNK_PAIRS // width)
    for lo in range(0, rows, step):
        sl = slice(lo, min(rows, lo + step))
        part = [a[sl] if np.shape(a)[0] == rows else a for a in angles]
        yield (sl, *_sigma0(rough, eps, lam, name, *part, out_of_range, options, polarized))


def _fill_isotropic(rough, eps, lam, name, theta, phi_d, out_of_range, options, out, out_pol):
    """Fill ``out`` (n_θ, n_θ, n_Δφ) and ``out_pol`` (2, 2, …) or None; the solver info."""
    n = theta.size
    iu, ou = np.triu_indices(n)  # θi ≤ θo
    ti, to = theta[iu][:, None], theta[ou][:, None]
    pi_ = np.full((1, 1), -math.pi)  # renderer φi = −π, φo = Δφ − π: emscatter φi = 0
    angles = (ti, to, phi_d[None, :] + pi_, pi_)
    infos = []
    for sl, f, fp, info in _chunked_sigma0(
        rough, eps, lam, name, angles, iu.size, out_of_range, options, out_pol is not None
    ):
        out[iu[sl], ou[sl]] = f
        out[ou[sl], iu[sl]] = f
        if out_pol is not None:
            out_pol[:, :, iu[sl], ou[sl]] = fp
            out_pol[:, :, ou[sl], iu[sl]] = fp.transpose(1, 0, 2, 3)  # f_pq(ωi→ωo) = f_qp(ωo→ωi)
        infos.append(chunks.slim(info))
        _tick((sl.stop - sl.start) / iu.size)  # one wavelength = 1 on the bar
    return chunks.merge_info(infos, theta)


def _fill_anisotropic(rough, eps, lam, name, theta, phi, out_of_range, options, out, out_pol):
    """Fill ``out`` (n_θ, n_φ, n_θ, n_φ) and ``out_pol`` (2, 2, …) or None; the solver info."""
    nt, npf = theta.size, phi.size
    nd = nt * npf
    th, ph = np.meshgrid(theta, phi, indexing="ij")
    th, ph = th.ravel(), ph.ravel()
    f2 = out.reshape(nd, nd)
    p2 = None if out_pol is None else out_pol.reshape(2, 2, nd, nd)
    infos = []
    pol = p2 is not None
    for aa, bb in chunks.upper_pairs(nd, sizing.CHUNK_PAIRS):
        f, fp, info = _sigma0(
            rough, eps, lam, name, th[aa], th[bb], ph[bb], ph[aa], out_of_range, options, pol
        )
        f2[aa, bb] = f
        f2[bb, aa] = f
        if p2 is not None:
            p2[:, :, aa, bb] = fp
            p2[:, :, bb, aa] = fp.transpose(1, 0, 2)
        infos.append(chunks.slim(info))
        _tick(2 * aa.size / (nd * (nd + 1)))
    return chunks.merge_info(infos, theta)


def _jsonable_scalar(v) -> bool:
    return isinstance(v, bool | int | float | str) or v is None


def _surface_params(rough) -> dict:
    out = {"type": type(rough).__name__}
    for key in ("sigma", "length", "length_y", "hurst", "dimension"):
        if hasattr(rough, key):
            val = getattr(rough, key)
            if _jsonable_scalar(val):
                out[key] = val
    return out


def _version() -> str:
    from .._version import __version__

    return __version__


def fill_from_function(brdf, wavelengths, theta, phi, anisotropic: bool, metadata: dict):
    """A table of ``brdf(wi, wo, wavelength)`` on the full node grid (no reciprocity assumed;
    :meth:`BrdfTable.reciprocity_error` tells), ``coherent = 0``, albedo recorded."""
    wl = _check_wavelengths(wavelengths)
    if anisotropic:
        ti, pi_, to, po = np.meshgrid(theta, phi, theta, phi, indexing="ij")
        grid_kw = {"phi_i": phi, "phi_o": phi}
    else:
        ti, to, po = np.meshgrid(theta, theta, phi, indexing="ij")
        pi_ = np.zeros_like(ti)
        grid_kw = {"phi_d": phi}
    wi, wo = frames.directions(ti, pi_), frames.directions(to, po)
    values = np.stack([np.asarray(brdf(wi, wo, float(lam)), dtype=float) for lam in wl])
    meta = {
        "format_version": FORMAT_VERSION,
        "emscatter_version": _version(),
        "solver": "analytic",
        "units": {"values": "1/sr", "wavelengths": "m", "angles": "rad", "coherent": "-"},
        "coherent": "none (analytic model)",
        **metadata,
    }
    table = BrdfTable(
        wavelengths=wl, theta_i=theta, theta_o=theta, values=values, metadata=meta, **grid_kw
    )
    return record_albedo(table, "off (analytic model)")
