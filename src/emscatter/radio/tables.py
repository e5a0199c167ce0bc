"""Tables a radio material reads per ray: built once per (material, frequency) from emscatter.

For one surface, one medium and one frequency:

* **coherent** — the front face's complex coherent reflection ``r_coh,p`` (h, v) on a grid
  uniform in ``cosθi`` (:func:`emscatter.coherent.coherent_amplitude`), stored with
  the flat Fresnel coefficient beside it: the material evaluates Fresnel (and the slab) exactly
  per ray and interpolates only the smooth roughness correction ``r_coh − r_Fresnel``;
* **lobe** — ``σ⁰_qp(θi, θs, φs) / (4π cosθi)`` [1/sr] for the four pairs ``hh, hv, vh, vv``
  (``[pol_s, pol_i]``): the power scattered diffusely into ``dΩ`` per unit incident power is
  ``lobe dΩ``. This is the product ``S² Γ² f_s`` of Sionna's model (``∫ f_s dΩ = 1``), so its
  hemispherical integral is the incoherent reflectivity ``r_incoh,p`` (``incoherent``), the
  diffuse share of the ray. Grid: ``θi`` uniform; scattered directions in polar coordinates
  ``(ρ, α)`` around the specular point of the transverse unit vector ``k̂s⊥`` (where lobes
  concentrate), ``ρ = ρmax(α) s^q`` with ``s`` uniform and the grading ``q`` set from the
  narrowest lobe (:func:`emscatter.emissivity.lobe_width`), ``α ∈ [0, π]`` (isotropic
  roughness is mirror-symmetric about the plane of incidence).

Which solver made each table, whether it was inside its validity range there (and per angle,
when the solver reports it), and how many solver evaluations it cost are recorded on the table
(:class:`RadioTables`) and in a process-wide log (:func:`build_log`) that tests read to check that
only the materials and frequency a scene uses are computed.
"""

from __future__ import annotations

import inspect
import math
import numbers
import time
import warnings
from collections import OrderedDict
from dataclasses import dataclass, field

import numpy as np

from ..conventions import wavenumber
from ..emissivity import lobe_width
from ..fresnel import fresnel_cos
from ..progress import task
from ..spectra import Roughness, check_roughness
from .medium import real_number

__all__ = [
    "TableOptions",
    "RadioTables",
    "build_tables",
    "lobe_directions",
    "lobe_coordinates",
    "interpolate_lobe",
    "build_log",
    "reset_build_log",
    "clear_cache",
    "RadioValidityWarning",
    "EnergyWarning",
]

#: Channels of the lobe table, ``[pol_s, pol_i]`` order.
PAIRS = ("hh", "hv", "vh", "vv")


class RadioValidityWarning(UserWarning):
    """The solver feeding a radio material is outside its validity range there."""


class EnergyWarning(UserWarning):
    """A table's coherent + incoherent reflectivity exceeds 1 by more than the tolerance."""


@dataclass(frozen=True)
class TableOptions:
    """Grid sizes of the tables (defaults: ~0.16 M scattered directions per frequency).

    ``n_cos`` nodes in ``cosθi`` for the coherent correction (SPM's costly second-order term
    on ``n_cos_spm`` of them, spline-interpolated: it is smooth in ``cosθ``); ``n_theta``
    incidence angles on ``[0, theta_max_deg]`` for the lobe; ``n_alpha`` azimuths on
    ``[0, π]`` and ``n_s`` radial nodes around the specular point; ``n_psi`` incidence
    azimuths on ``[0, π/2]`` for a textured (anisotropic) surface only
    (:mod:`emscatter.radio.texture`). Where
    ``r_coh + r_incoh > 1 + energy_tolerance`` the lobe is scaled down to conserve energy
    (recorded in ``RadioTables.energy_scale``), with an :class:`EnergyWarning` when that
    starts below ``energy_warn_below_deg`` (a solver far out of its range, not only the usual
    first-order excess near grazing)."""

    n_cos: int = 257
    n_cos_spm: int = 33
    n_theta: int = 46
    n_alpha: int = 37
    n_s: int = 96
    n_psi: int = 7
    theta_max_deg: float = 89.0
    energy_tolerance: float = 0.01
    energy_warn_below_deg: float = 60.0

    def __post_init__(self):
        for name in ("n_cos", "n_cos_spm", "n_theta", "n_alpha", "n_s"):
            v = getattr(self, name)
            if isinstance(v, bool | np.bool_) or not isinstance(v, numbers.Integral) or v < 4:
                raise ValueError(f"TableOptions.{name} must be an integer >= 4, got {v!r}")
            object.__setattr__(self, name, int(v))  # np.int64 too; one key for the cache
        v = self.n_psi
        if isinstance(v, bool | np.bool_) or not isinstance(v, numbers.Integral) or v < 2:
            raise ValueError(f"TableOptions.n_psi must be an integer >= 2, got {v!r}")
        object.__setattr__(self, "n_psi", int(v))
        for name in ("theta_max_deg", "energy_tolerance", "energy_warn_below_deg"):
            object.__setattr__(self, name, real_number(f"TableOptions.{name}", getattr(self, name)))
        if not 10.0 <= self.theta_max_deg < 90.0:
            raise ValueError(f"theta_max_deg must be in [10, 90), got {self.theta_max_deg!r}")
        if self.energy_tolerance < 0:
            raise ValueError(
                f"TableOptions.energy_tolerance must be >= 0, got {self.energy_tolerance!r}"
            )


@dataclass
class RadioTables:
    """What :func:`build_tables` returns (module docstring). Angles [rad], ``exp(−iωt)``."""

    label: str
    frequency: float
    eps: complex
    method: str | None
    valid: bool
    reasons: list
    cos_nodes: np.ndarray
    coherent: np.ndarray  # (2, n_cos) complex r_coh of the front face
    fresnel: np.ndarray  # (2, n_cos) complex flat-interface Fresnel
    theta_nodes: np.ndarray
    alpha_nodes: np.ndarray
    s_nodes: np.ndarray
    grading: float
    lobe: np.ndarray  # (n_theta, n_alpha, n_s, 4) [1/sr]
    incoherent: np.ndarray  # (2, n_theta) r_incoh per incident polarization
    coherent_power: np.ndarray  # (2, n_theta) |r_coh|² on the lobe's θ grid
    angle_valid: np.ndarray | None = None
    energy_excess: float = 0.0
    energy_scale: np.ndarray | None = None  # (2, n_theta) factor applied to the lobe (1: none)
    evaluations: dict = field(default_factory=dict)
    seconds: float = 0.0
    flat: bool = False

    def incoherent_on_cos(self) -> np.ndarray:
        """``r_incoh,p`` (2, n_cos) carried to the coherent part's ``cosθi`` grid (linear in
        ``cosθi``; held at ``theta_max`` beyond it), so the material reads both at once."""
        c = np.cos(self.theta_nodes)[::-1]
        return np.stack([np.interp(self.cos_nodes, c, self.incoherent[p][::-1]) for p in (0, 1)])

    @property
    def delta(self) -> np.ndarray:
        """``r_coh − r_Fresnel`` (2, n_cos), the smooth part the material interpolates."""
        return self.coherent - self.fresnel

    def describe(self) -> str:
        if self.flat:
            return f"{self.label}: flat surface (Fresnel / ITU slab only)"
        state = "valid" if self.valid else "OUTSIDE validity: " + "; ".join(self.reasons)
        return (
            f"{self.label} at {self.frequency / 1e9:g} GHz: method {self.method!r} ({state}); "
            f"max r_coh + r_incoh before energy scaling = {1.0 + self.energy_excess:.3f}"
        )


_LOG: list[dict] = []


_CACHE: OrderedDict = OrderedDict()
_CACHE_SIZE = 64


def clear_cache() -> None:
    """Forget the tables kept for reuse (:func:`build_tables` reuses identical requests)."""
    _CACHE.clear()


def build_log() -> list[dict]:
    """Every table built in this process: ``{"label", "frequency", "method", "bistatic_points",
    "coherent_points", "seconds"}`` (flat surfaces cost no solver evaluation and are not
    logged; reused tables are not logged again)."""
    return list(_LOG)


def reset_build_log() -> None:
    _LOG.clear()


def _grading(rough: Roughness, k: float, n_s: int) -> float:
    """``q`` such that the narrowest lobe spans ≈ 6 radial cells (1 ≤ q ≤ 4)."""
    w = lobe_width(rough, k)
    return float(np.clip(math.log(w) / math.log(6.0 / n_s), 1.0, 4.0))


def _rho_max(p0, cos_a, sin_a):
    return -p0 * cos_a + np.sqrt(np.maximum(1.0 - (p0 * sin_a) ** 2, 0.0))


def lobe_directions(theta_nodes, alpha_nodes, s_nodes, grading):
    """Scattered directions of the lobe grid: ``(theta_s, phi_s)`` [rad], shape
    ``(n_theta, n_alpha, n_s)``, in the frame where the incidence azimuth is 0."""
    p0 = np.sin(np.asarray(theta_nodes))[:, None, None]
    a = np.asarray(alpha_nodes)[None, :, None]
    s = np.asarray(s_nodes)[None, None, :]
    rho = _rho_max(p0, np.cos(a), np.sin(a)) * s**grading
    px = p0 + rho * np.cos(a)
    py = rho * np.sin(a)
    sin_s = np.minimum(np.hypot(px, py), 1.0)
    theta_s = np.arcsin(sin_s)
    phi_s = np.arctan2(py, px)
    return theta_s, phi_s


def lobe_coordinates(theta_i, theta_s, phi_s, grading):
    """Inverse of :func:`lobe_directions`: ``(alpha, s)`` of scattered directions (NumPy
    reference of the lookup the Sionna material does in Dr.Jit); ``phi_s`` relative to φi."""
    p0 = np.sin(theta_i)
    px = np.sin(theta_s) * np.cos(phi_s) - p0
    py = np.abs(np.sin(theta_s) * np.sin(phi_s))
    rho = np.hypot(px, py)
    safe = np.where(rho > 0, rho, 1.0)
    cos_a = np.where(rho > 0, px / safe, 1.0)
    sin_a = np.where(rho > 0, py / safe, 0.0)
    alpha = np.arctan2(sin_a, cos_a)
    t = np.clip(rho / np.maximum(_rho_max(p0, cos_a, sin_a), 1e-12), 0.0, 1.0)
    return alpha, t ** (1.0 / grading)


def interpolate_lobe(tables: RadioTables, theta_i, theta_s, phi_s) -> np.ndarray:
    """Trilinear interpolation of the lobe (NumPy reference), shape ``(4, *shape)`` [1/sr]."""
    from scipy.interpolate import RegularGridInterpolator

    alpha, s = lobe_coordinates(theta_i, theta_s, phi_s, tables.grading)
    th = np.clip(theta_i, tables.theta_nodes[0], tables.theta_nodes[-1])
    interp = RegularGridInterpolator(
        (tables.theta_nodes, tables.alpha_nodes, tables.s_nodes), tables.lobe
    )
    pts = np.stack(np.broadcast_arrays(th, alpha, s), axis=-1)
    return np.moveaxis(interp(pts), -1, 0)


def _lobe_integral(lobe, theta_nodes, alpha_nodes, s_nodes, grading):
    """``r_incoh,p = Σ_q ∫ lobe_qp dΩ`` on the grid, (2, n_theta) for incident h, v.

    ``dΩ = d²p / cosθs``, ``d²p = ρ dρ dα`` with ``ρ = ρmax s^q``; trapezoid in ``s`` and ``α``
    (both halves of the azimuth), the edge node ``cosθs = 0`` left out (an integrable
    ``1/cosθs`` singularity: a few-per-cent effect at most for lobes that reach grazing)."""
    p0 = np.sin(theta_nodes)[:, None, None]
    a = alpha_nodes[None, :, None]
    s = s_nodes[None, None, :]
    rmax = _rho_max(p0, np.cos(a), np.sin(a))
    rho = rmax * s**grading
    drho_ds = rmax * grading * s ** (grading - 1.0)
    px, py = p0 + rho * np.cos(a), rho * np.sin(a)
    cos_s = np.sqrt(np.maximum(1.0 - px * px - py * py, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        jac = np.where(cos_s > 1e-9, rho * drho_ds / cos_s, 0.0)
    ws = np.full(s_nodes.size, s_nodes[1] - s_nodes[0])
    ws[0] *= 0.5
    ws[-1] = 0.0
    wa = np.full(alpha_nodes.size, alpha_nodes[1] - alpha_nodes[0])
    wa[[0, -1]] *= 0.5
    w = 2.0 * jac * wa[None, :, None] * ws[None, None, :]
    per_pair = np.einsum("tasc,tas->ct", lobe, w)  # (4, n_theta)
    # incident h: hh + vh (channels 0, 2); incident v: hv + vv (1, 3)
    return np.stack([per_pair[0] + per_pair[2], per_pair[1] + per_pair[3]])


def _coherent_on_grid(rough, eps, k, method, cos_nodes, fres, n_spm):
    """Front-face ``r_coh`` (2, n_cos) on the ``cosθ`` grid, and the solver points it cost.

    Kirchhoff-type mean fields are cheap: every node is computed. SPM's second-order term costs a
    spectral quadrature per angle and is smooth in ``cosθ``: it is computed on ``n_spm`` nodes
    and the correction ``r_coh − r_Fresnel`` is carried to the grid by a cubic spline."""
    from scipy.interpolate import CubicSpline

    from ..coherent import coherent_amplitude

    def amp(c):
        th = np.arccos(np.clip(c, 1e-4, 1.0))
        return coherent_amplitude(rough, eps, k, th, method=method, out_of_range="ignore")

    if method != "spm" or n_spm >= cos_nodes.size:
        res = amp(cos_nodes)
        return res.amplitude, int(res.info["evaluations"])
    coarse = np.linspace(0.0, 1.0, n_spm)
    res = amp(coarse)
    rh, rv = fresnel_cos(eps, coarse)
    delta = res.amplitude - np.stack([rh, rv])
    fine = np.stack(
        [
            CubicSpline(coarse, delta[p].real)(cos_nodes)
            + 1j * CubicSpline(coarse, delta[p].imag)(cos_nodes)
            for p in (0, 1)
        ]
    )
    return fres + fine, int(res.info["evaluations"])


def _validity_flags(module, rough, k, eps, theta):
    """Per-angle validity from the solver's own check when it accepts ``theta_i``."""
    params = inspect.signature(module.check_validity).parameters
    if "theta_i" not in params:
        return None
    extra = {"eps": eps} if "eps" in params else {}
    rep = module.check_validity(rough, k, theta_i=theta, **extra)
    flags = rep.get("angle_valid")
    return None if flags is None else np.asarray(flags, dtype=bool)


def check_surface(surface) -> Roughness:
    """Roughness the radio bridge can use: 2-D and isotropic (else a clear error)."""
    rough = check_roughness(surface, "surface")
    if rough.dimension != 2 or not rough.is_isotropic:
        raise ValueError(
            f"radio materials need isotropic 2-D roughness (Sionna's interaction frame has no "
            f"surface orientation), got {rough.describe()}"
        )
    return rough


def check_policy(out_of_range):
    allowed = ("warn", "raise", "ignore")
    if out_of_range not in allowed:
        raise ValueError(
            f"out_of_range must be one of {allowed} for a radio material (NaN would reach the "
            f"ray tracer), got {out_of_range!r}"
        )
    return out_of_range


def _describe_regime(rough, k):
    return (
        f"rms height {rough.sigma * 1e3:g} mm, correlation length {rough.length * 1e3:g} mm "
        f"(kσ = {k * rough.sigma:.3g}, kℓ = {k * rough.length:.3g})"
    )


def build_tables(
    surface: Roughness | None,
    eps: complex,
    frequency: float,
    *,
    method: str = "auto",
    out_of_range: str = "warn",
    label: str = "material",
    options: TableOptions | None = None,
    progress: bool | None = None,
) -> RadioTables:
    """The tables of one material at one frequency [Hz] (module docstring).

    ``surface`` — isotropic 2-D roughness statistics, or ``None`` for a flat face (no solver
    call). ``eps`` — the medium's permittivity at ``frequency`` (``Im ε ≥ 0``). ``method`` —
    ``"auto"`` or a solver name; ``out_of_range`` — ``"warn"`` (default), ``"raise"`` or
    ``"ignore"`` when that solver is outside its validity range here.

    Identical requests (same roughness, permittivity, frequency, method and grid) reuse the
    tables already built in this process (several walls of one material cost one build); only
    real builds enter :func:`build_log`. ``progress``: a tqdm bar over the build's three
    stages (coherent amplitude, lobe, its integral) on stderr — ``None`` (auto) on a terminal
    past 2 s, ``True`` always, ``False`` never (:mod:`emscatter.progress`).
    """
    opts = options or TableOptions()
    key = (repr(surface), complex(np.asarray(eps)), float(frequency), method, out_of_range, opts)
    hit = _CACHE.get(key)
    if hit is not None:
        _CACHE.move_to_end(key)
        return hit
    desc = f"radio tables {label} {float(frequency) / 1e9:g} GHz"
    with task(desc, 3, progress, unit="stage") as bar:
        tables = _build(surface, eps, frequency, method, out_of_range, label, opts, bar)
    _CACHE[key] = tables
    while len(_CACHE) > _CACHE_SIZE:
        _CACHE.popitem(last=False)
    return tables


def _build(surface, eps, frequency, method, out_of_range, label, opts, bar) -> RadioTables:
    from .. import api, solvers

    policy = check_policy(out_of_range)
    k = wavenumber(frequency=frequency)
    eps = complex(np.asarray(eps))
    t0 = time.perf_counter()
    cos_nodes = np.linspace(0.0, 1.0, opts.n_cos)
    rh, rv = fresnel_cos(eps, cos_nodes)
    fres = np.stack([rh, rv])
    theta_nodes = np.radians(np.linspace(0.0, opts.theta_max_deg, opts.n_theta))
    alpha_nodes = np.linspace(0.0, math.pi, opts.n_alpha)
    s_nodes = np.linspace(0.0, 1.0, opts.n_s)
    n_lobe = (opts.n_theta, opts.n_alpha, opts.n_s, 4)
    if surface is None:  # no solver call, nothing to log
        rt, rvt = fresnel_cos(eps, np.cos(theta_nodes))
        return RadioTables(
            label=label,
            frequency=float(frequency),
            eps=eps,
            method=None,
            valid=True,
            reasons=[],
            cos_nodes=cos_nodes,
            coherent=fres.copy(),
            fresnel=fres,
            theta_nodes=theta_nodes,
            alpha_nodes=alpha_nodes,
            s_nodes=s_nodes,
            grading=1.0,
            lobe=np.zeros(n_lobe),
            incoherent=np.zeros((2, opts.n_theta)),
            coherent_power=np.stack([np.abs(rt) ** 2, np.abs(rvt) ** 2]),
            flat=True,
        )
    rough = check_surface(surface)
    name, module, report, _ = api.resolve_method(rough, k, method, "ignore", eps)
    if not report.get("valid", True):
        why = "; ".join(report.get("reasons", [])) or "outside its validity range"
        msg = (
            f"radio material {label!r} at {frequency / 1e9:g} GHz: {_describe_regime(rough, k)}; "
            f"method {name!r} is outside its validity range ({why}). To change: pick another "
            f"method= ({', '.join(solvers.available())}), a roughness inside a method's range, "
            "or out_of_range='raise' to make this an error."
        )
        if method == "auto":
            msg = msg.replace(f"method {name!r} is", f"no method is valid; 'auto' took {name!r},")
        if policy == "raise":
            raise solvers.select.ValidityError(msg)
        if policy == "warn":
            warnings.warn(msg, RadioValidityWarning, stacklevel=3)
    coherent, n_coh = _coherent_on_grid(rough, eps, k, name, cos_nodes, fres, opts.n_cos_spm)
    bar.update(1)
    grading = _grading(rough, k, opts.n_s)
    theta_s, phi_s = lobe_directions(theta_nodes, alpha_nodes, s_nodes, grading)
    ti = np.broadcast_to(theta_nodes[:, None, None], theta_s.shape)
    skip = (
        {"coherent": False} if "coherent" in inspect.signature(module.bistatic).parameters else {}
    )
    res = module.bistatic(rough, eps, k, ti, theta_s, phi_s, 0.0, **skip)
    bar.update(1)
    sig = np.nan_to_num(np.asarray(res.sigma0, dtype=float), nan=0.0, posinf=0.0)
    sig = np.maximum(sig, 0.0)
    cos_i = np.cos(theta_nodes)[:, None, None]
    lobe = np.stack([sig[0, 0], sig[0, 1], sig[1, 0], sig[1, 1]], axis=-1) / (
        4.0 * math.pi * cos_i[..., None]
    )
    incoherent = _lobe_integral(lobe, theta_nodes, alpha_nodes, s_nodes, grading)
    power = np.abs(coherent) ** 2
    cp = np.stack([np.interp(np.cos(theta_nodes), cos_nodes, power[p]) for p in (0, 1)])
    # Energy: a first-order solver can put more than 1 − r_coh into its lobe (e.g. physical
    # optics without shadowing near grazing). The lobe is scaled down there so that
    # r_coh + r_incoh ≤ 1 per incident polarization; where and by how much is recorded.
    room = np.maximum(1.0 - cp, 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = np.where(incoherent > room, room / np.where(incoherent > 0, incoherent, 1.0), 1.0)
    excess = float(np.max(cp + incoherent) - 1.0)
    # channels 0, 2 carry incident h; 1, 3 incident v
    lobe = lobe * np.stack([scale[0], scale[1], scale[0], scale[1]], axis=-1)[:, None, None, :]
    incoherent = incoherent * scale
    scaled = scale < 1.0 - opts.energy_tolerance
    if np.any(scaled):
        first = float(np.degrees(theta_nodes[np.any(scaled, axis=0)].min()))
        if first < opts.energy_warn_below_deg:
            warnings.warn(
                f"radio material {label!r} at {frequency / 1e9:g} GHz (method {name!r}): coherent "
                f"+ incoherent reflectivity reaches {1 + excess:.3f} > 1 from θi = {first:.0f}°; "
                "the diffuse lobe is scaled down there to conserve energy. Pick another method= "
                "or check the roughness.",
                EnergyWarning,
                stacklevel=3,
            )
    seconds = time.perf_counter() - t0
    bar.update(1)
    evals = {"bistatic_points": int(theta_s.size), "coherent_points": n_coh}
    _LOG.append(
        {"label": label, "frequency": float(frequency), "method": name, **evals, "seconds": seconds}
    )
    return RadioTables(
        label=label,
        frequency=float(frequency),
        eps=eps,
        method=name,
        valid=bool(report.get("valid", True)),
        reasons=list(report.get("reasons", [])),
        cos_nodes=cos_nodes,
        coherent=coherent,
        fresnel=fres,
        theta_nodes=theta_nodes,
        alpha_nodes=alpha_nodes,
        s_nodes=s_nodes,
        grading=grading,
        lobe=lobe,
        incoherent=incoherent,
        coherent_power=cp,
        angle_valid=_validity_flags(module, rough, k, eps, theta_nodes),
        energy_excess=max(excess, 0.0),
        energy_scale=scale,
        evaluations=evals,
        seconds=seconds,
    )
