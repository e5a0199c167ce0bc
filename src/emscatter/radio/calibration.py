"""Calibration: the rms height σ and correlation length ℓ of a rough medium fitted to observed
path gains, with their uncertainty.

::

    geo = radio.calibration.PlateGeometry(tx=(-2, 0, 2), rx=[(2, 0, 2), (3, 1, 1), ...], size=6)
    obs = {"specular": {"VV": db, "HH": db}, "diffuse": {"VV": db, "HH": db}}   # (n_rx,) [dB]
    fit = radio.calibrate(obs, geo, 28e9, medium="concrete", x0=(0.3e-3, 3e-3), noise_db=0.3)
    fit["sigma_m"], fit["sigma_std_m"], fit["length_m"], fit["length_std_m"], fit["correlation"]

Forward model (no Sionna; the two predictions that Sionna RT with the emscatter material was
checked against, :mod:`.plate`): a square plate in ``z = 0`` of a half-space medium, a
transmitter and receivers above it, isotropic antennas of unit gain, ``V``/``H`` = local TM/TE;

* **specular** — the image path ``|r_coh,p(θ)|² (λ / 4πL)²`` (:func:`emscatter.coherent.
  coherent_amplitude`) for receivers whose specular point lies on the plate;
* **diffuse** — the bistatic radar equation ``∫ λ² σ⁰_qp / ((4π)³ r₁² r₂²) dA`` over the plate
  (Gauss–Legendre panels graded around each receiver's specular point).

The fit is weighted least squares in dB (``scipy.optimize.least_squares``, trust region,
parameters ``log σ`` and ``log ℓ``), residual ``(model − observed) / noise_db``. The
uncertainty is the Gauss–Newton covariance ``C = s² (JᵀJ)⁻¹`` at the optimum (``J`` the
Jacobian in the log parameters; ``s² = χ²/(n − 2)`` when ``noise_db`` is not given, 1 when it
is) mapped to σ and ℓ (``std σ ≈ σ·√C₀₀``), with the correlation ``C₀₁/√(C₀₀C₁₁)``
(Press et al., *Numerical Recipes*, 3rd ed., §15.5; Bates & Watts, *Nonlinear Regression
Analysis*, 1988, §2.3).

The solver (SPM, PO, GO, …) is chosen at ``x0`` (``method="auto"``) and kept for the fit, so the
objective is smooth; when the method that ``"auto"`` picks at the fitted roughness differs, the
fit is repeated once with that method (reported as ``"method"``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..constants import SPEED_OF_LIGHT
from ..conventions import wavenumber
from .medium import real_number, resolve_medium

__all__ = ["PlateGeometry", "predict", "calibrate", "KINDS", "PAIRS"]

KINDS = ("specular", "diffuse")
#: (rx antenna, tx antenna) → σ⁰ index [pol_s, pol_i].
PAIRS = {"VV": (1, 1), "HH": (0, 0), "HV": (0, 1), "VH": (1, 0)}


@dataclass(frozen=True)
class PlateGeometry:
    """A square plate of side ``size`` [m] in ``z = 0`` centred on the origin, a transmitter
    ``tx`` (3,) and receivers ``rx`` (n, 3) [m] above it."""

    tx: tuple
    rx: tuple
    size: float = 6.0

    def __post_init__(self):
        tx = np.asarray(self.tx, dtype=float)
        rx = np.atleast_2d(np.asarray(self.rx, dtype=float))
        if tx.shape != (3,) or rx.ndim != 2 or rx.shape[1] != 3 or len(rx) == 0:
            raise ValueError(
                f"tx must be (x, y, z) and rx (n, 3) [m], got shapes {tx.shape}, {rx.shape}"
            )
        if tx[2] <= 0 or np.any(rx[:, 2] <= 0):
            raise ValueError(f"tx and rx must lie above the plate (z > 0), got tx={tx.tolist()}")
        if not (math.isfinite(self.size) and self.size > 0):
            raise ValueError(f"size must be a positive plate side [m], got {self.size!r}")
        object.__setattr__(self, "tx", tx)
        object.__setattr__(self, "rx", rx)

    def specular_points(self) -> np.ndarray:
        """(n, 3) where each receiver's image path meets ``z = 0`` [m]."""
        img = self.tx * np.array([1.0, 1.0, -1.0])
        t = self.rx[:, 2:3] / (self.rx[:, 2:3] + self.tx[2])
        return self.rx + (img - self.rx) * t

    def on_plate(self) -> np.ndarray:
        """(n,) True where the specular point lies on the plate (an image path exists)."""
        p = self.specular_points()
        return np.all(np.abs(p[:, :2]) < self.size / 2, axis=1)


def _graded(lo: float, hi: float, centre: float, finest: float, cap: float, order: int):
    """Gauss–Legendre nodes/weights on [lo, hi], panels growing ×2 from ``finest`` away from
    ``centre`` (clipped to the interval) up to ``cap``."""
    c = min(max(centre, lo), hi)
    edges = [c]
    for sign, end in ((1.0, hi), (-1.0, lo)):
        x, w = c, finest
        while sign * (end - x) > 1e-12:
            w = min(2.0 * w, cap)
            x = end if sign * (end - (x + sign * w)) < 0 else x + sign * w
            edges.append(x)
    e = np.unique(edges)
    xg, wg = np.polynomial.legendre.leggauss(order)
    a, b = e[:-1, None], e[1:, None]
    return (0.5 * (b - a) * xg + 0.5 * (a + b)).ravel(), (0.5 * (b - a) * wg).ravel()


def _diffuse(geo: PlateGeometry, module, surface, eps, k, lam, order: int) -> np.ndarray:
    """(n_rx, 2, 2) radar-equation path gain [pol_s, pol_i] [linear]."""
    import inspect

    skip = (
        {"coherent": False} if "coherent" in inspect.signature(module.bistatic).parameters else {}
    )
    half = geo.size / 2
    cap = min(geo.tx[2], float(geo.rx[:, 2].min())) / 4
    out = []
    for rx, sp in zip(geo.rx, geo.specular_points(), strict=True):
        xs, wx = _graded(-half, half, sp[0], 0.005, cap, order)
        ys, wy = _graded(-half, half, sp[1], 0.005, cap, order)
        X, Y = np.meshgrid(xs, ys, indexing="ij")
        p = np.stack([X, Y, np.zeros_like(X)], axis=-1)
        d1, d2 = p - geo.tx, rx - p
        r1, r2 = np.linalg.norm(d1, axis=-1), np.linalg.norm(d2, axis=-1)
        ti = np.arccos(np.clip(-d1[..., 2] / r1, 0.0, 1.0))
        ts = np.arccos(np.clip(d2[..., 2] / r2, 0.0, 1.0))
        pi, ps = np.arctan2(d1[..., 1], d1[..., 0]), np.arctan2(d2[..., 1], d2[..., 0])
        sig = module.bistatic(surface, eps, k, ti, ts, ps, pi, **skip).sigma0
        w = (wx[:, None] * wy[None, :]) / ((4 * math.pi) ** 3 * r1**2 * r2**2)
        out.append(lam**2 * np.einsum("psxy,xy->ps", np.nan_to_num(sig, nan=0.0), w))
    return np.asarray(out)


def predict(geo: PlateGeometry, frequency, surface, *, medium="concrete", method="auto",
            order: int = 6) -> dict:  # fmt: skip
    """``{"specular": {pair: (n_rx,)}, "diffuse": {pair: (n_rx,)}, "method"}`` path gains
    [linear] (module docstring); specular is 0 where the specular point is off the plate and
    is co-polar only (``VV``, ``HH``; cross-polar 0 on a plate)."""
    from .. import api
    from ..coherent import coherent_amplitude
    from ..solvers import get

    f = real_number("frequency", frequency)
    k = wavenumber(frequency=f)
    lam = SPEED_OF_LIGHT / f
    eps = complex(np.asarray(resolve_medium(medium).eps(frequency=f)))
    name = api.resolve_method(surface, k, method, "ignore", eps)[0]
    sp = geo.specular_points()
    r1 = np.linalg.norm(sp - geo.tx, axis=1)
    r2 = np.linalg.norm(geo.rx - sp, axis=1)
    theta = np.arccos(np.clip(geo.tx[2] / r1, 0.0, 1.0))
    coh = coherent_amplitude(surface, eps, k, theta, method=name, out_of_range="ignore")
    power = np.asarray(coh.power, dtype=float).reshape(2, -1)  # [h, v]
    free = (lam / (4 * math.pi * (r1 + r2))) ** 2 * geo.on_plate()
    dif = _diffuse(geo, get(name), surface, eps, k, lam, order)
    return {
        "specular": {"VV": power[1] * free, "HH": power[0] * free,
                     "HV": 0.0 * free, "VH": 0.0 * free},
        "diffuse": {pair: dif[:, s, i] for pair, (s, i) in PAIRS.items()},
        "method": name,
    }  # fmt: skip


def _flatten_obs(observed: dict):
    """Observed dB as a flat vector and the (kind, pair, index) it came from."""
    if not isinstance(observed, dict) or not observed:
        raise ValueError(
            "observed must be {'specular'|'diffuse': {pair: path gains [dB] per receiver}}"
        )
    keys, values = [], []
    for kind, per in observed.items():
        if kind not in KINDS:
            raise ValueError(f"observed kind {kind!r} is not one of {list(KINDS)}")
        for pair, v in per.items():
            if pair not in PAIRS:
                raise ValueError(f"observed[{kind!r}] pair {pair!r} is not one of {list(PAIRS)}")
            v = np.asarray(v, dtype=float).ravel()
            for i, x in enumerate(v):
                if not np.isnan(x):
                    if not np.isfinite(x):
                        raise ValueError(
                            f"observed[{kind!r}][{pair!r}][{i}] = {x}: a path gain must be a "
                            "finite number of dB (NaN: not observed)"
                        )
                    keys.append((kind, pair, i))
                    values.append(x)
    return keys, np.asarray(values)


def calibrate(observed: dict, geometry: PlateGeometry, frequency, *, medium="concrete",
              x0=(0.5e-3, 5e-3), noise_db=None, method="auto", correlation="gaussian",
              bounds=((1e-5, 1e-4), (2e-2, 0.2))) -> dict:  # fmt: skip
    """Fit σ and ℓ [m] of ``correlation`` (``"gaussian"`` or ``"exponential"``) roughness on
    ``medium`` to ``observed`` path gains [dB] (module docstring).

    ``noise_db``: the observations' standard deviation [dB] (then the covariance is absolute;
    otherwise scaled by the residual variance); ``bounds``: ``((σ_min, ℓ_min), (σ_max, ℓ_max))``
    [m]. Returns ``{"sigma_m", "length_m", "sigma_std_m", "length_std_m", "correlation"
    (between the two estimates), "covariance_log" (2×2, of log σ and log ℓ), "chi2", "dof",
    "rms_residual_db", "residual_db", "method", "nfev", "success", "message"}``."""
    from scipy.optimize import least_squares

    from ..spectra import ExponentialCorrelation, GaussianCorrelation

    kinds = {"gaussian": GaussianCorrelation, "exponential": ExponentialCorrelation}
    if correlation not in kinds:
        raise ValueError(f"correlation must be one of {sorted(kinds)}, got {correlation!r}")
    make = kinds[correlation]
    keys, y = _flatten_obs(observed)
    if len(y) < 3:
        raise ValueError(f"calibrate needs at least 3 observed path gains, got {len(y)}")
    n_rx = len(geometry.rx)
    if any(i >= n_rx for _, _, i in keys):
        raise ValueError(f"observed has more entries per pair than the {n_rx} receivers")
    if noise_db is not None and not (np.isfinite(noise_db) and noise_db > 0):
        raise ValueError(f"noise_db must be a positive standard deviation [dB], got {noise_db!r}")
    (smin, lmin), (smax, lmax) = bounds
    if not (0 < smin < smax and 0 < lmin < lmax):
        raise ValueError(f"bounds must be ((σ_min, ℓ_min), (σ_max, ℓ_max)) > 0, got {bounds!r}")
    s0, l0 = (float(v) for v in x0)
    if not (smin <= s0 <= smax and lmin <= l0 <= lmax):
        raise ValueError(f"x0 = {x0!r} lies outside bounds {bounds!r}")
    scale = 1.0 if noise_db is None else float(noise_db)

    def model_db(p, name):
        pred = predict(geometry, frequency, make(sigma=math.exp(p[0]), length=math.exp(p[1])),
                       medium=medium, method=name)  # fmt: skip
        g = np.array([pred[kind][pair][i] for kind, pair, i in keys])
        if np.any(g <= 0) or not np.all(np.isfinite(g)):
            bad = [keys[j] for j in np.flatnonzero(~(g > 0))]
            raise ValueError(
                f"the model predicts no power for observed {bad[:3]} (a specular path whose "
                "specular point is off the plate, or a cross-polar specular pair): drop them"
            )
        return 10.0 * np.log10(g)

    def fit(name, start):
        res = least_squares(
            lambda p: (model_db(p, name) - y) / scale, start, method="trf", x_scale="jac",
            bounds=(np.log([smin, lmin]), np.log([smax, lmax])), diff_step=1e-3,
        )  # fmt: skip
        return res

    from .. import api

    f = real_number("frequency", frequency)
    k = wavenumber(frequency=f)
    eps = complex(np.asarray(resolve_medium(medium).eps(frequency=f)))

    def auto(s, length):
        return api.resolve_method(make(sigma=s, length=length), k, method, "ignore", eps)[0]

    name = auto(s0, l0)
    res = fit(name, np.log([s0, l0]))
    again = auto(*np.exp(res.x))
    if again != name:  # the fitted roughness lies in another solver's regime
        name = again
        res = fit(name, res.x)
    r = res.fun
    dof = len(y) - 2
    chi2 = float(r @ r)
    jtj = res.jac.T @ res.jac
    try:
        cov = np.linalg.inv(jtj)
    except np.linalg.LinAlgError:
        cov = np.full((2, 2), np.inf)
    if noise_db is None:
        cov = cov * (chi2 / dof if dof > 0 else np.inf)
    sig, length = np.exp(res.x)
    std = np.sqrt(np.diag(cov))
    return {
        "sigma_m": float(sig),
        "length_m": float(length),
        "sigma_std_m": float(sig * std[0]),
        "length_std_m": float(length * std[1]),
        "correlation": float(cov[0, 1] / (std[0] * std[1])) if np.all(std > 0) else math.nan,
        "covariance_log": cov.tolist(),
        "chi2": chi2,
        "dof": dof,
        "rms_residual_db": float(np.sqrt(np.mean((r * scale) ** 2))),
        "residual_db": (r * scale).tolist(),
        "observations": [list(key) for key in keys],
        "method": name,
        "nfev": int(res.nfev),
        "success": bool(res.success),
        "message": str(res.message),
    }


def sionna_gains(geometry: PlateGeometry, frequency, surface, *, medium="concrete",
                 method="auto", samples: int = 300_000, seed: int = 1,
                 table_options=None) -> dict:  # fmt: skip
    """Sionna RT's path gains on the plate of ``geometry`` with the emscatter material
    (half-space): ``{"specular": {pair: (n_rx,)}, "diffuse": {pair: (n_rx,)}}`` [linear], one
    specular-only solve (image paths, no LoS) and one diffuse-only solve, ``V``/``H`` antennas
    (imports Sionna RT: run it in a process of its own, Dr.Jit variants are per process)."""
    import sionna.rt as rt

    from . import scenes
    from .material import EmscatterRadioMaterial

    def make(name, med, thickness):
        return EmscatterRadioMaterial(f"cal-{name}", surface=surface, medium=medium,
                                      thickness=None, method=method,
                                      table_options=table_options)  # fmt: skip

    scene = scenes.load(scenes.plate(geometry.size), real_number("frequency", frequency), make)
    arr = rt.PlanarArray(num_rows=1, num_cols=1, pattern="iso", polarization="VH")
    scene.tx_array = scene.rx_array = arr
    scene.add(rt.Transmitter("tx", position=geometry.tx.tolist()))
    for i, p in enumerate(geometry.rx):
        scene.add(rt.Receiver(f"rx{i}", position=p.tolist()))
    ant = {"V": 0, "H": 1}
    out = {}
    for kind, diffuse in (("specular", False), ("diffuse", True)):
        n = int(samples) if diffuse else 10_000
        # every diffuse hit is a candidate path to every receiver: a buffer of n per receiver
        paths = rt.PathSolver()(
            scene, max_depth=1, samples_per_src=n, max_num_paths_per_src=n * len(geometry.rx),
            los=False,
            specular_reflection=not diffuse, diffuse_reflection=diffuse, refraction=False,
            seed=int(seed),
        )  # fmt: skip
        re, im = (np.asarray(x.numpy(), dtype=np.float64) for x in paths.a)
        power = re**2 + im**2  # [rx, rx_ant, tx, tx_ant, path]
        if not np.all(np.isfinite(power)):
            raise FloatingPointError(f"{kind}: Sionna returned non-finite path powers")
        out[kind] = {
            pair: np.sort(power[:, ant[pair[0]], 0, ant[pair[1]]], axis=-1).sum(axis=-1)
            for pair in PAIRS
        }
    return out
