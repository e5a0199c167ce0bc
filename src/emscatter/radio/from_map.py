"""The roughness of a radio material from a measured height map (issue 17).

:func:`surface_from_map` turns a height-map file, a
:class:`~emscatter.surfaces.heightmap.HeightMap` or a
:class:`~emscatter.surfaces.measured.MeasuredRoughness` into the isotropic 2-D roughness a
:class:`~emscatter.radio.MaterialSpec` takes (``MaterialSpec.from_height_map`` calls it):

* ``model="measured"`` (default): the map's own Welch spectrum averaged over rings
  (``measured_roughness(hm, isotropic=True)``), its n-fold spectra and measured slopes. This is
  the default because the radio lobe is set by the spectrum's *shape* near ``|K| ≈ 2k sinθ``
  (first-order SPM σ⁰ ∝ w(k_s⊥ − k_i⊥); the PO/IEM series by its n-fold powers), and a wall's
  measured spectrum is rarely one of the two textbook families: a fit moves the lobe's level
  where the shapes differ.
* ``model="fit"``: ``σ`` (the map's rms height) and ``ℓ`` of a correlation family fitted to the
  map's measured correlation ρ (the inverse transform of the same ring-averaged spectrum):
  ``family="gaussian"`` ``exp(−r²/ℓ²)``, ``"exponential"`` ``exp(−r/ℓ)``, or ``"best"`` (the
  default) the one of the two whose fitted ρ is closer to the measured ρ in rms over
  ``0 < r ≤ 3ℓ_{1/e}``. ``ℓ`` is fitted by least squares on ``−ln ρ`` through the origin over
  the lags where ``ρ ≥ 0.2`` (as :func:`emscatter.surfaces.correlation_length`). Use it to
  compare with parametric materials, or where the smooth closed forms are wanted.

Sionna's interaction frame has no surface orientation, so the radio roughness is isotropic:
an anisotropic map is ring-averaged (its spectrum over rings, ``ℓ`` the geometric mean). With
``frequencies`` the band each one needs (``|K| ≤ 2k``) is checked against the map's
``[2π/L, π/Δ]``: part of it beyond ``π/Δ`` with ``tail="none"``, or a map whose Welch patch is
shorter than ``1/max_below`` half-wavelengths, is a :class:`ValueError` naming the map, the
frequency and the spacing or size it needs.
"""

from __future__ import annotations

import math
import os

import numpy as np

from ..constants import SPEED_OF_LIGHT as C0
from ..spectra import ExponentialCorrelation, GaussianCorrelation, Roughness
from ..surfaces.heightmap import HeightMap, HeightMapError, read_height_map
from ..surfaces.measured import MeasuredRoughness, measured_roughness

__all__ = ["surface_from_map", "MODELS", "FAMILIES"]

MODELS = ("measured", "fit")
FAMILIES = ("best", "gaussian", "exponential")
_FIT_RHO_MIN = 0.2


def _radial_rho(m: MeasuredRoughness, r: np.ndarray) -> np.ndarray:
    """The measured correlation averaged over 16 directions at radii ``r`` [m]."""
    ph = np.linspace(0.0, math.pi, 16, endpoint=False)
    x = r[:, None] * np.cos(ph)[None, :]
    y = r[:, None] * np.sin(ph)[None, :]
    return np.asarray(m.correlation(x, y)).mean(axis=1)


def _fit(m: MeasuredRoughness, family: str) -> tuple[Roughness, dict]:
    ell_e = math.sqrt(m.length * m.length_y)  # 1/e lag (ring average of the two axes)
    step = min(m.info["spacing"])
    r = np.arange(1, max(8, int(math.ceil(3 * ell_e / step))) + 1) * step
    rho = _radial_rho(m, r)
    below = np.nonzero(rho < _FIT_RHO_MIN)[0]
    j = int(below[0]) if below.size else rho.size
    if j < 2:
        raise HeightMapError(
            f"the map from {m.source} is too coarse for a correlation fit: ρ falls to "
            f"{rho[0]:.3g} at one spacing ({step:.4g} m); use model='measured' or a finer map"
        )
    rr, y = r[:j], -np.log(np.clip(rho[:j], 1e-300, None))
    fits = {
        "gaussian": float(math.sqrt(np.sum(rr**4) / np.sum(rr**2 * y))),
        "exponential": float(np.sum(rr**2) / np.sum(rr * y)),
    }
    model_rho = {
        "gaussian": lambda ell: np.exp(-((r / ell) ** 2)),
        "exponential": lambda ell: np.exp(-r / ell),
    }
    rms = {f: float(np.sqrt(np.mean((model_rho[f](ell) - rho) ** 2))) for f, ell in fits.items()}
    chosen = min(rms, key=rms.get) if family == "best" else family
    cls = GaussianCorrelation if chosen == "gaussian" else ExponentialCorrelation
    rough = cls(float(m.sigma), fits[chosen])
    return rough, {"family": chosen, "length_m": fits, "rho_rms_misfit": rms}


def _band(m: MeasuredRoughness, frequencies, max_below: float) -> list[dict]:
    out = []
    for f in np.atleast_1d(np.asarray(frequencies, dtype=float)):
        if not (np.isfinite(f) and f > 0):
            raise ValueError(f"frequencies must be positive finite [Hz], got {f!r}")
        k = 2 * math.pi * f / C0
        rep = m.band_check(k)
        if not rep["ok"]:
            raise ValueError(f"the map from {m.source} at {f / 1e9:g} GHz: {rep['message']}")
        if rep["fraction_below"] > max_below:
            lam = C0 / f
            patch = 2 * math.pi / m.band_lo
            raise ValueError(
                f"the map from {m.source} is too small for {f / 1e9:g} GHz: its Welch patch "
                f"({patch:.4g} m) resolves |K| ≥ {m.band_lo:.4g} rad/m, "
                f"{100 * rep['fraction_below']:.0f}% of the band |K| ≤ 2k = {2 * k:.4g} rad/m "
                f"(allowed {100 * max_below:.0f}%); it needs a patch of at least "
                f"{lam / (2 * max_below):.4g} m (a larger map or fewer segments)"
            )
        out.append({"frequency_hz": float(f), **{k_: rep[k_] for k_ in
                    ("k_needed", "fraction_above", "fraction_below")}})  # fmt: skip
    return out


def surface_from_map(
    source,
    *,
    model: str = "measured",
    family: str = "best",
    segments: int = 8,
    tail: str = "none",
    unit: str | None = None,
    detrend="plane",
    holes: str = "reject",
    slope_tail: str = "gaussian",
    frequencies=None,
    max_below: float = 0.25,
) -> tuple[Roughness, dict]:
    """``(roughness, record)`` for a radio material from a height map (module docstring).

    Parameters
    ----------
    source : a file path (read by :func:`~emscatter.surfaces.read_height_map` with ``unit``,
        ``detrend``, ``holes``), a :class:`HeightMap` (2-D), or an isotropic
        :class:`MeasuredRoughness`.
    model : ``"measured"`` (the map's ring-averaged spectrum) or ``"fit"`` (σ, ℓ of
        ``family``).
    family : ``"best"``, ``"gaussian"`` or ``"exponential"`` (``model="fit"`` only).
    segments, tail : Welch segments per axis and the spectrum beyond ``π/Δ``
        (:func:`~emscatter.surfaces.measured.measured_roughness`).
    slope_tail : the measured slope density beyond its well-sampled slopes (``"gaussian"``,
        ``"exponential"`` or ``"none"``; ``measured_roughness``'s, recorded).
    frequencies : [Hz], optional: the band check per frequency (module docstring).
    max_below : the largest fraction of ``[0, 2k]`` allowed below the map's ``2π/L``.

    Returns the roughness and a record: the model, family and fitted lengths, the map's
    ``σ``, ``ℓx``, ``ℓy``, its source and the band checks.
    """
    if model not in MODELS:
        raise ValueError(f"model must be one of {MODELS}, got {model!r}")
    if family not in FAMILIES:
        raise ValueError(f"family must be one of {FAMILIES}, got {family!r}")
    if model == "measured" and family != "best":
        raise ValueError(f"family={family!r} applies only with model='fit' (model='measured')")
    if not (isinstance(max_below, int | float) and 0 < max_below < 1):
        raise ValueError(f"max_below must be in (0, 1), got {max_below!r}")
    if isinstance(source, str | os.PathLike):
        source = read_height_map(source, unit=unit, detrend=detrend, holes=holes)
    if isinstance(source, HeightMap):
        if source.dimension != 2:
            raise HeightMapError(
                f"a radio material needs a 2-D height map; the one from {source.source} is a "
                f"profile of shape {source.shape}"
            )
        source = measured_roughness(
            source, segments=segments, tail=tail, slope_tail=slope_tail, isotropic=True
        )
    if not isinstance(source, MeasuredRoughness):
        raise TypeError(
            "source must be a height-map file, a HeightMap or a MeasuredRoughness, got "
            f"{type(source).__name__}"
        )
    m = source
    if m.dimension != 2 or not m.is_isotropic:
        raise ValueError(
            f"a radio material needs an isotropic 2-D measured roughness (Sionna's frame has "
            f"no surface orientation); {m.describe()} is not: pass the HeightMap or file, or "
            "measured_roughness(hm, isotropic=True)"
        )
    record = {
        "model": model,
        "source": m.source,
        "sigma_m": float(m.sigma),
        "length_1_over_e_m": float(m.length),
        "segments": m.info.get("segments"),
        "tail": m.tail,
        "holes": dict(m.info.get("holes") or {}),
        "slope_tail": (m.info.get("slope_tail") or {}).get("shape", "none"),
    }
    if frequencies is not None:
        record["band"] = _band(m, frequencies, float(max_below))
    if model == "measured":
        return m, record
    rough, fit = _fit(m, family)
    record.update(fit)
    return rough, record
