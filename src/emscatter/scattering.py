"""The one solver output: bistatic scattering coefficients and coherent reflectivity."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields

import numpy as np

from .constants import SPEED_OF_LIGHT
from .conventions import check_pol_pair, pol_index

__all__ = ["Scattering"]


class _LazyCoherent:
    """The :attr:`Scattering.coherent` field: a zero-argument callable stored there is called
    on first read and replaced by its array. A data descriptor on this one field, so that
    reading every other attribute costs a plain lookup (no ``__getattribute__`` override)."""

    def __get__(self, obj, owner=None):
        if obj is None:
            return self
        value = obj.__dict__["coherent"]
        if callable(value):
            value = np.asarray(value())
            obj.__dict__["coherent"] = value
        return value

    def __set__(self, obj, value):  # the dataclass __init__ (object.__setattr__) lands here
        obj.__dict__["coherent"] = value


@dataclass(frozen=True, eq=False)
class Scattering:
    """Result of every solver.

    Attributes
    ----------
    sigma0 : ndarray, shape ``(2, 2, *shape)``
        Incoherent bistatic scattering coefficient σ⁰, linear, indexed ``[pol_s, pol_i]``
        with 0 = h, 1 = v (``sigma0[0, 1]`` is "hv": scattered h from incident v).
        Dimensionless; per unit area for 2-D surfaces,
        ``σ⁰ = 4π R² ⟨|E_s|²⟩_incoh / (A |E_i|²)``, so that the incoherent reflectivity is
        ``r_p = 1/(4π cosθi) Σ_q ∫ σ⁰_qp dΩs``. For 1-D profiles it is per unit length,
        ``σ⁰ = 2π ρ ⟨|E_s|²⟩_incoh / (L |E_i|²)`` and ``r_p = 1/(2π cosθi) Σ_q ∫ σ⁰_qp dθs``
        over signed ``θs ∈ (−π/2, π/2)``.
    coherent : ndarray, shape ``(2, *shape)``
        Coherent (specular) power reflectivity for incident h and v [-]. May be given as a
        zero-argument callable: it is then computed on first access and kept (the public API
        does this, so a bistatic or backscatter curve never pays for it unless it is read).
    method : str
        The solver that produced it (after ``"auto"`` selection); ``"a+b"`` when ``auto``
        used several (per frequency), with the method of each element in ``info["methods"]``.
    theta_i, theta_s, phi_s, phi_i : ndarray, broadcast to ``shape`` [rad].
    k : free-space wavenumber [rad/m]: a float, or an ndarray of ``shape`` when the call
        had several frequencies.
    dimension : 1 or 2.
    info : dict of extra details (validity report, series terms, ...).
    """

    sigma0: np.ndarray
    coherent: np.ndarray
    method: str
    theta_i: np.ndarray
    theta_s: np.ndarray
    phi_s: np.ndarray
    phi_i: np.ndarray
    k: float | np.ndarray
    dimension: int = 2
    info: dict = field(default_factory=dict)

    def __getstate__(self):  # pickling (e.g. to a worker process) computes a lazy part first
        state = dict(self.__dict__)
        state["coherent"] = self.coherent
        return state

    @classmethod
    def _of(cls, **fields) -> Scattering:
        """A result from all ten fields by keyword, without the frozen ``__init__``'s one
        ``object.__setattr__`` per field (the API builds one per call; same object)."""
        obj = object.__new__(cls)
        if len(fields) != len(_FIELDS) or fields.keys() != _FIELDS:
            raise TypeError(f"Scattering._of needs exactly the fields {sorted(_FIELDS)}")
        obj.__dict__.update(fields)
        return obj

    @classmethod
    def from_geometry(
        cls, geometry, *, sigma0, coherent, method: str, k, dimension: int | None = None,
        info: dict | None = None,
    ) -> Scattering:  # fmt: skip
        """A solver's result on a checked, broadcast geometry (the ``Geometry`` of
        :func:`emscatter.solvers.kirchhoff.common.geometry`, or any object with the same
        attributes).

        From ``geometry`` it fills :attr:`theta_i`, :attr:`theta_s`, :attr:`phi_s`,
        :attr:`phi_i` (its arrays broadcast to ``geometry.shape`` [rad], stored as they are: no
        copy) and :attr:`dimension` (``geometry.dimension`` unless ``dimension`` is given).
        ``sigma0`` must have the shape ``(2, 2, *geometry.shape)`` (ValueError naming both
        shapes otherwise); ``coherent`` is an array ``(2, *geometry.shape)`` or a zero-argument
        callable (lazy, class docstring); ``k`` [rad/m]; ``info`` defaults to an empty dict.
        """
        shape = tuple(geometry.shape)
        if np.shape(sigma0) != (2, 2, *shape):
            raise ValueError(
                f"sigma0 must have the shape (2, 2, *geometry.shape) = {(2, 2, *shape)} "
                f"(indexed [pol_s, pol_i]), got {np.shape(sigma0)}"
            )
        return cls(
            sigma0=sigma0,
            coherent=coherent,
            method=method,
            theta_i=geometry.theta_i,
            theta_s=geometry.theta_s,
            phi_s=geometry.phi_s,
            phi_i=geometry.phi_i,
            k=k,
            dimension=geometry.dimension if dimension is None else dimension,
            info={} if info is None else info,
        )

    @property
    def coherent_computed(self) -> bool:
        """Whether :attr:`coherent` has been computed (False while it is still lazy)."""
        return not callable(self.__dict__["coherent"])

    @property
    def frequency(self):
        """Frequency [Hz] (``c k / 2π``), a float or an ndarray like :attr:`k`."""
        return self.k * SPEED_OF_LIGHT / (2 * math.pi)

    @property
    def wavelength(self):
        """Free-space wavelength [m] (``2π / k``)."""
        return 2 * math.pi / self.k

    @property
    def shape(self) -> tuple[int, ...]:
        return self.sigma0.shape[2:]

    def pol(self, pair: str) -> np.ndarray:
        """σ⁰ for one pair, e.g. ``"hv"`` (scattered h, incident v)."""
        s, i = check_pol_pair(pair)
        return self.sigma0[s, i]

    hh = property(lambda self: self.sigma0[0, 0])
    hv = property(lambda self: self.sigma0[0, 1])
    vh = property(lambda self: self.sigma0[1, 0])
    vv = property(lambda self: self.sigma0[1, 1])

    def coherent_pol(self, pol: str) -> np.ndarray:
        """Coherent reflectivity for incident ``pol``: ``"h"``/``"TE"`` or ``"v"``/``"TM"``
        (case-insensitive)."""
        return self.coherent[pol_index(pol)]

    def db(self, pair: str, floor: float = 1e-30) -> np.ndarray:
        """σ⁰ of one pair in dB (``10 log10``, floored at ``floor`` to stay finite)."""
        return 10.0 * np.log10(np.maximum(self.pol(pair), floor))

    def gamma(self) -> np.ndarray:
        """``γ = σ⁰ / cosθi``, shape like :attr:`sigma0`."""
        return self.sigma0 / np.cos(self.theta_i)

    def brdf(self) -> np.ndarray:
        """BRDF ``f_r = σ⁰ / (4π cosθi cosθs)`` [1/sr] (2-D surfaces), per polarization pair.

        Infinite at grazing angles (cos → 0) by definition; see :mod:`emscatter.brdf`.
        """
        if self.dimension != 2:
            raise ValueError("brdf() is defined for 2-D surfaces (dimension=2)")
        return self.sigma0 / (4 * math.pi * np.cos(self.theta_i) * np.cos(self.theta_s))

    def unpolarized(self) -> np.ndarray:
        """σ⁰ for unpolarized incidence summed over received polarizations:
        ``(hh + vh + hv + vv) / 2``."""
        return 0.5 * self.sigma0.sum(axis=(0, 1))


Scattering.coherent = _LazyCoherent()  # after @dataclass: the field stays required
_FIELDS = frozenset(f.name for f in fields(Scattering))
