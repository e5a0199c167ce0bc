"""Spectra to linear sRGB for reflectance-like quantities (BRDF values, reflectivities).

``rgb = W @ values`` with :func:`spectrum_to_rgb_weights`: the CIE 1931 observer under the D65
illuminant, XYZ → linear sRGB (ITU-R BT.709), each row scaled so a flat spectrum stays grey.
Used by the RGB ``.bsdf`` export and by the Mitsuba plugin in Mitsuba's RGB variants.
"""

from __future__ import annotations

import math

import numpy as np

from .source import check_wavelengths

__all__ = [
    "cie1931_xyz",
    "colour_error",
    "normal_reflectance",
    "spectrum_to_rgb_weights",
    "wavelengths_for",
    "RGB_LUMINANCE",
    "VISIBLE_NM",
    "COLOUR_TOL",
]

#: Default tolerance of :func:`wavelengths_for`: the largest relative error of a linear-sRGB
#: channel of the reflectance, 0.5 % (about a third of a just-noticeable difference in
#: lightness at mid grey; the issue-21 16-wavelength gold tables were off by 1–2 %).
COLOUR_TOL = 0.005

#: Wavelengths [nm] of the dense reference of :func:`colour_error` (1 nm steps).
_DENSE_NM = np.linspace(360.0, 830.0, 471)

#: The wavelength range [nm] of the CIE 1931 tables and of Mitsuba's spectral sampling.
VISIBLE_NM = (360.0, 830.0)

#: Luminance Y of linear sRGB (ITU-R BT.709 second row).
RGB_LUMINANCE = np.array([0.212671, 0.715160, 0.072169])


def _cie_lobe(lam_nm, mu, s1, s2):
    s = np.where(lam_nm < mu, s1, s2)
    return np.exp(-0.5 * ((lam_nm - mu) / s) ** 2)


def cie1931_xyz(lam_nm: np.ndarray) -> np.ndarray:
    """CIE 1931 colour matching functions, shape ``(3, ...)``: the multi-lobe fit of Wyman,
    Sloan & Shirley, JCGT 2(2), 2013 (their eq. 2; within ~1 % of the tabulated CIE data)."""
    x = (
        1.056 * _cie_lobe(lam_nm, 599.8, 37.9, 31.0)
        + 0.362 * _cie_lobe(lam_nm, 442.0, 16.0, 26.7)
        - 0.065 * _cie_lobe(lam_nm, 501.1, 20.4, 26.2)
    )
    y = 0.821 * _cie_lobe(lam_nm, 568.8, 46.9, 40.5) + 0.286 * _cie_lobe(lam_nm, 530.9, 16.3, 31.1)
    z = 1.217 * _cie_lobe(lam_nm, 437.0, 11.8, 36.0) + 0.681 * _cie_lobe(lam_nm, 459.0, 26.0, 13.8)
    return np.stack([x, y, z])


# CIE standard illuminant D65, relative spectral power at 360, 365, ..., 830 nm (CIE 15:2004)
_D65 = np.array(
    [46.6383, 49.3637, 52.0891, 51.0323, 49.9755, 52.3118, 54.6482, 68.7015, 82.7549, 87.1204,
     91.486, 92.4589, 93.4318, 90.057, 86.6823, 95.7736, 104.865, 110.936, 117.008, 117.41,
     117.812, 116.336, 114.861, 115.392, 115.923, 112.367, 108.811, 109.082, 109.354, 108.578,
     107.802, 106.296, 104.79, 106.239, 107.689, 106.047, 104.405, 104.225, 104.046, 102.023,
     100.0, 98.1671, 96.3342, 96.0611, 95.788, 92.2368, 88.6856, 89.3459, 90.0062, 89.8026,
     89.5991, 88.6489, 87.6987, 85.4936, 83.2886, 83.4939, 83.6992, 81.863, 80.0268, 80.1207,
     80.2146, 81.2462, 82.2778, 80.281, 78.2842, 74.0027, 69.7213, 70.6652, 71.6091, 72.979,
     74.349, 67.9765, 61.604, 65.7448, 69.8856, 72.4863, 75.087, 69.3398, 63.5927, 55.0054,
     46.4182, 56.6118, 66.8054, 65.0941, 63.3828, 63.8434, 64.304, 61.8779, 59.4519, 55.7054,
     51.959, 54.6998, 57.4406, 58.8765, 60.3125]
)  # fmt: skip
# XYZ -> linear sRGB (ITU-R BT.709 primaries, D65 white)
_XYZ_TO_SRGB = np.array(
    [[3.240479, -1.537150, -0.498535], [-0.969256, 1.875991, 0.041556],
     [0.055648, -0.204043, 1.057311]]
)  # fmt: skip


def spectrum_to_rgb_weights(wavelengths) -> np.ndarray:
    """Weights ``W`` (3, n) with ``rgb = W @ values`` for a reflectance-like quantity known at
    ``wavelengths`` [m] (linear in λ between them, constant beyond): CIE 1931 under D65 to
    linear sRGB, each row scaled to sum to 1 so that a flat spectrum maps to grey. Saturated
    spectra can give negative components (outside the sRGB gamut); callers clip them at 0."""
    lam = check_wavelengths(wavelengths) * 1e9
    if lam.size == 1:
        return np.ones((3, 1))
    if lam[0] > VISIBLE_NM[1] or lam[-1] < VISIBLE_NM[0]:
        raise ValueError(
            f"wavelengths {lam[0]:.4g}–{lam[-1]:.4g} nm do not reach the visible range "
            f"{VISIBLE_NM[0]:g}–{VISIBLE_NM[1]:g} nm, so they have no sRGB colour"
        )
    grid = np.linspace(*VISIBLE_NM, _D65.size)
    rgb_cmf = _XYZ_TO_SRGB @ (cie1931_xyz(grid) * _D65)  # (3, 95)
    hat = np.stack([np.interp(grid, lam, np.eye(lam.size)[k]) for k in range(lam.size)])
    w = rgb_cmf @ hat.T  # (3, n): weight of each table wavelength
    return w / w.sum(axis=1, keepdims=True)


def normal_reflectance(material, wavelengths) -> np.ndarray:
    """Normal-incidence Fresnel reflectance ``|(√ε − 1)/(√ε + 1)|²`` [-] of ``material`` at
    ``wavelengths`` [m] (Born & Wolf §1.5.2; ``exp(−iωt)``, ``Im ε ≥ 0``): anything
    :func:`emscatter.materials.eps_at` takes, or a callable ``eps(wavelength [m])``; ``"pec"``
    reflects 1."""
    from .. import materials

    lam = np.atleast_1d(np.asarray(wavelengths, dtype=float))
    if callable(material) and not isinstance(material, materials.Material):
        eps = np.array([complex(np.asarray(material(x)).item()) for x in lam])
    else:
        eps = materials.eps_at(material, wavelength=lam)
        if isinstance(eps, str):  # "pec"
            return np.ones(lam.shape)
        eps = np.broadcast_to(np.asarray(eps, dtype=complex), lam.shape)
    n = np.sqrt(eps)
    return np.abs((n - 1.0) / (n + 1.0)) ** 2


def colour_error(material, wavelengths) -> float:
    """Largest relative error [-] of a linear-sRGB channel of ``material``'s normal-incidence
    reflectance (:func:`normal_reflectance`) seen through a table at ``wavelengths`` [m]
    (linear in λ between them, constant beyond: :func:`spectrum_to_rgb_weights`) against a
    dense 1-nm reference over 360–830 nm. Channels are compared relative to the largest one
    (a channel near 0 has no relative colour error of its own)."""
    lam = check_wavelengths(np.atleast_1d(np.asarray(wavelengths, dtype=float)))
    dense = _DENSE_NM * 1e-9
    ref = spectrum_to_rgb_weights(dense) @ normal_reflectance(material, dense)
    got = spectrum_to_rgb_weights(lam) @ normal_reflectance(material, lam)
    scale = np.maximum(np.abs(ref), 0.05 * np.abs(ref).max())
    return float(np.max(np.abs(got - ref) / scale))


def wavelengths_for(material, tol: float = COLOUR_TOL, *, n_max: int = 128) -> np.ndarray:
    """The fewest wavelengths ``n`` [m], uniform over 360–830 nm (``np.linspace``, the tables'
    convention), whose :func:`colour_error` is ≤ ``tol``: every ``n' < n`` is above it.
    ``ValueError`` naming the error reached when even ``n_max`` does not meet ``tol``.

    A grey material (a constant ε) needs 1; gold ~30 at 0.5 %, silver fewer (its reflectance
    is flat above 400 nm) — the counts are the material's spectral variation, measured."""
    if isinstance(tol, bool) or not (isinstance(tol, int | float) and 0 < tol < 1):
        raise ValueError(f"tol must be a number in (0, 1) (relative sRGB error), got {tol!r}")
    if isinstance(n_max, bool) or not isinstance(n_max, int) or n_max < 1:
        raise ValueError(f"n_max must be an integer ≥ 1, got {n_max!r}")
    err = math.inf
    for n in range(1, n_max + 1):
        lam = np.array([550e-9]) if n == 1 else np.linspace(360e-9, 830e-9, n)
        err = colour_error(material, lam)
        if err <= tol:
            return lam
    raise ValueError(
        f"no wavelength count up to n_max = {n_max} meets tol = {tol:g} for this material "
        f"(error {err:.3g} at {n_max}); raise n_max or tol"
    )
