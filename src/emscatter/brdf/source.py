"""BRDFs as the exporters and the Mitsuba plugin take them: :class:`BrdfFunction`.

An emscatter :class:`~emscatter.brdf.table.BrdfTable` or any vectorized ``f_r(wi, wo)`` in the
renderer frame (normal +z, both directions pointing away from the surface, mirror at
φo = φi + π; :mod:`emscatter.brdf.frames`) becomes one object with ``evaluate(wi, wo)`` →
``(..., n_channels)`` [1/sr], ``wavelengths`` [m] (or ``None`` for linear-sRGB channels),
``isotropic`` and ``coherent(theta_i)`` (the delta lobe's R_coh, kept apart).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

__all__ = ["BrdfFunction", "as_brdf_source", "check_wavelengths"]


class BrdfFunction:
    """A BRDF given as a vectorized function, for the exporters and the Mitsuba plugin.

    Parameters
    ----------
    fr : callable ``fr(wi, wo) -> ndarray (..., n_wavelengths)`` [1/sr]; ``wi``, ``wo`` are
        unit vectors ``(..., 3)`` in the renderer frame (normal +z, pointing away).
    wavelengths : the wavelengths [m] of the last axis of ``fr``'s result (``None`` when
        the channels are already linear sRGB, three of them).
    isotropic : whether ``fr`` depends on the azimuths only through φo − φi.
    coherent : optional ``R_coh(theta_i) -> (..., n_wavelengths)`` [-], the specular
        (delta) reflectivity kept apart from ``fr``.
    name : a short description written into exported files.
    """

    def __init__(
        self,
        fr: Callable[[np.ndarray, np.ndarray], np.ndarray],
        wavelengths=None,
        *,
        isotropic: bool = True,
        coherent: Callable[[np.ndarray], np.ndarray] | None = None,
        name: str = "emscatter BRDF",
    ):
        if not callable(fr):
            raise TypeError(f"fr must be a callable fr(wi, wo), got {type(fr).__name__}")
        self._fr = fr
        self.wavelengths = None if wavelengths is None else check_wavelengths(wavelengths)
        self.isotropic = bool(isotropic)
        self._coherent = coherent
        self.name = str(name)
        self.table = None  # the BrdfTable this wraps, if any

    @property
    def n_channels(self) -> int:
        return 3 if self.wavelengths is None else self.wavelengths.size

    def evaluate(self, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
        """f_r [1/sr], shape ``(..., n_channels)``."""
        out = np.asarray(self._fr(wi, wo), dtype=float)
        want = np.broadcast_shapes(wi.shape, wo.shape)[:-1] + (self.n_channels,)
        if out.shape != want:
            raise ValueError(f"fr(wi, wo) returned shape {out.shape}, expected {want}")
        return out

    def coherent(self, theta_i: np.ndarray) -> np.ndarray:
        """R_coh [-], shape ``theta_i.shape + (n_channels,)`` (zero when none was given)."""
        theta_i = np.asarray(theta_i, dtype=float)
        if self._coherent is None:
            return np.zeros(theta_i.shape + (self.n_channels,))
        return np.broadcast_to(
            np.asarray(self._coherent(theta_i), dtype=float), theta_i.shape + (self.n_channels,)
        )


def as_brdf_source(brdf) -> BrdfFunction:
    """A :class:`BrdfFunction` from a :class:`BrdfFunction` or an emscatter
    :class:`~emscatter.brdf.table.BrdfTable` (kept as ``.table``)."""
    if isinstance(brdf, BrdfFunction):
        return brdf
    if not (hasattr(brdf, "evaluate") and hasattr(brdf, "coherent_reflectance")):
        raise TypeError(
            "brdf must be an emscatter BrdfTable or a BrdfFunction, got " + type(brdf).__name__
        )

    def fr(wi, wo):  # BrdfTable.evaluate puts wavelengths first
        return np.moveaxis(brdf.evaluate(wi, wo), 0, -1)

    def coherent(theta_i):
        return np.moveaxis(brdf.coherent_reflectance(theta_i), 0, -1)

    describe = getattr(brdf, "describe", None)
    out = BrdfFunction(
        fr,
        brdf.wavelengths,
        isotropic=bool(brdf.isotropic),
        coherent=coherent,
        name=describe() if callable(describe) else type(brdf).__name__,
    )
    out.table = brdf
    return out


def check_wavelengths(wavelengths) -> np.ndarray:
    lam = np.atleast_1d(np.asarray(wavelengths, dtype=float))
    if lam.ndim != 1 or lam.size == 0 or not np.all(np.isfinite(lam)) or np.any(lam <= 0):
        raise ValueError(f"wavelengths must be a 1-D array of positive values [m], got {lam!r}")
    if np.any(np.diff(lam) <= 0):
        raise ValueError(f"wavelengths must increase strictly, got {lam!r} [m]")
    return lam
