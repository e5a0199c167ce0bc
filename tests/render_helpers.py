"""Shared helpers for the rendering tests (RGL export, Mitsuba plugin, renders).

Mitsuba runs for real. Variants are per process; every test sets the one it needs (pytest-xdist
workers run many files, so nothing here assumes a variant was left set).
"""

from __future__ import annotations

import functools
import math
import warnings

import numpy as np
import pytest

from emscatter.brdf import build_table
from emscatter.spectra import GaussianCorrelation

mi = pytest.importorskip("mitsuba")
import drjit as dr  # noqa: E402  (after the importorskip)

ALPHA = 0.2  # Beckmann α = 2σ/ℓ of the test surfaces
ETA, KAPPA = 0.2, 3.0  # a silver-like conductor
WAVELENGTHS = np.array([450e-9, 550e-9, 650e-9])
LENGTH = 10e-6  # ℓ [m]: GO holds (ℓ ≫ λ)


def use_variant(name: str) -> None:
    """Set a Mitsuba variant, or skip the test when this machine lacks it."""
    try:
        mi.set_variant(name)
        mi.load_dict({"type": "diffuse"})
    except Exception as exc:  # e.g. no libLLVM for the llvm_* variants
        pytest.skip(f"Mitsuba variant {name} unavailable: {exc}")


def lossy_eps(wavelengths):
    """A dispersive conductor: index η + iκ drifting with λ (so channels differ)."""
    lam = np.asarray(wavelengths) / 550e-9
    return (ETA * lam + 1j * KAPPA * lam**0.5) ** 2


@functools.lru_cache(maxsize=8)
def go_table(alpha=ALPHA, resolution=(45, 90), aspect=1.0, material="lossy", wavelengths=None):
    """A geometric-optics BrdfTable (cached per worker): α = 2σ/ℓ along x, ``aspect`` = ℓx/ℓy."""
    lam = WAVELENGTHS if wavelengths is None else np.asarray(wavelengths)
    if material == "lossy":
        eps_of = dict(zip(lam.tolist(), lossy_eps(lam).tolist(), strict=True))

        def material_fn(wl):
            return eps_of[float(wl)]

    else:
        from emscatter.materials import metal

        material_fn = metal(material)
    rough = GaussianCorrelation(alpha / 2 * LENGTH, LENGTH, length_y=LENGTH / aspect)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # validity notes of the solver are not the subject here
        return build_table(
            rough,
            material_fn,
            lam,
            method="go",
            resolution=resolution,
            anisotropic=aspect != 1.0,
        )


def random_pairs(rng, n: int, max_deg: float = 80.0):
    """``n`` (wi, wo) pairs, θ uniform in cosθ up to ``max_deg``, random azimuths: (n, 3) each."""
    out = []
    for _ in range(2):
        c = rng.uniform(math.cos(math.radians(max_deg)), 1.0, n)
        p = rng.uniform(0, 2 * math.pi, n)
        s = np.sqrt(1 - c * c)
        out.append(np.stack([s * np.cos(p), s * np.sin(p), c], -1))
    return out[0], out[1]


def interaction(wi: np.ndarray, wavelength_nm: float | None = None):
    si = dr.zeros(mi.SurfaceInteraction3f, len(wi))
    si.wi = mi.Vector3f(*(mi.Float(c.astype(np.float32)) for c in np.asarray(wi).T))
    if wavelength_nm is not None and mi.is_spectral:
        si.wavelengths = mi.Spectrum(float(wavelength_nm))
    return si


def mitsuba_eval(bsdf, wi, wo, wavelength_nm=None, ctx=None) -> np.ndarray:
    """``bsdf.eval`` (= f_r cosθo) as (n, channels): 3 in RGB variants, 1 in spectral ones
    (all four sampled wavelengths set to ``wavelength_nm``)."""
    si = interaction(wi, wavelength_nm)
    val = bsdf.eval(ctx or mi.BSDFContext(), si, mi.Vector3f(*(mi.Float(c) for c in wo.T)))
    arr = np.array(val, dtype=float)
    arr = arr.T if arr.ndim == 2 else arr[:, None]
    return arr[:, :1] if wavelength_nm is not None and mi.is_spectral else arr


def sampled_albedo(bsdf, theta_i: float, n: int = 200_000, wavelength_nm=None, seed=0, ctx=None):
    """Monte Carlo directional albedo E[weight] from ``bsdf.sample`` at incidence ``theta_i``."""
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f(math.sin(theta_i), 0.0, math.cos(theta_i))
    if wavelength_nm is not None and mi.is_spectral:
        si.wavelengths = mi.Spectrum(float(wavelength_nm))
    rng = mi.PCG32(n, seed)
    bs, w = bsdf.sample(
        ctx or mi.BSDFContext(),
        si,
        rng.next_float32(),
        mi.Point2f(rng.next_float32(), rng.next_float32()),
    )
    arr = np.array(w, dtype=float)
    arr = arr.T if arr.ndim == 2 else arr[:, None]
    return arr.mean(axis=0), bs


def relative_errors(got: np.ndarray, want: np.ndarray, floor: float = 1e-3) -> np.ndarray:
    """|got − want| / want where ``want`` ≥ ``floor`` × its maximum (the lobe that carries the
    energy; far tails are below float32 resolution of a renderer anyway)."""
    sig = want >= floor * want.max()
    assert sig.sum() > 100, "too few significant points"
    return np.abs(got[sig] - want[sig]) / want[sig]
