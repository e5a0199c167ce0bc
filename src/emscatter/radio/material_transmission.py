"""Transmission events of :class:`emscatter.radio.material.EmscatterRadioMaterial`: the
``transmission=`` option and its checks (:func:`check_transmission`), the diffuse-transmission
tables of one frequency (:func:`diffuse_tables`, from
:func:`emscatter.radio.transmission_tables.build_transmission_tables`), whether a solver call can
sample diffuse transmission (:func:`through_on`: not Sionna's PathSolver, which warns once with
:class:`~emscatter.radio.transmission_tables.DiffuseTransmissionWarning`) and the event
probabilities of specular reflection, diffuse reflection, coherent and diffuse transmission
(:func:`event_probabilities`, Dr.Jit, per ray).

The model is described in :mod:`emscatter.radio.material`'s docstring (``R_coh + R_diff + T_coh
+ T_diff + A = 1`` per incidence). Imports Dr.Jit and Sionna RT."""

from __future__ import annotations

import warnings

import drjit as dr
from sionna.rt.constants import NO_JONES_MATRIX, InteractionType

from .transmission_tables import DiffuseTransmissionWarning, build_transmission_tables

__all__ = ["TRANSMISSION_MODES", "check_transmission", "diffuse_tables", "event_probabilities",
           "through_on"]  # fmt: skip

TRANSMISSION_MODES = ("coherent", "diffuse")


def check_transmission(transmission, thickness, texture=None) -> str:
    """``transmission`` checked: one of :data:`TRANSMISSION_MODES`; ``"diffuse"`` needs a slab
    (``thickness`` [m] not ``None``) and no ``texture`` direction (ValueError otherwise)."""
    allowed = TRANSMISSION_MODES
    if transmission not in allowed:
        raise ValueError(f"transmission must be one of {allowed}, got {transmission!r}")
    if transmission == "diffuse":
        if thickness is None:
            raise ValueError(
                "transmission='diffuse' needs a slab: thickness=None is a half-space, which "
                "transmits nothing; give thickness [m] > 0"
            )
        if texture is not None:
            raise ValueError(
                "transmission='diffuse' needs isotropic roughness without texture_direction "
                "(the slab transport of emscatter.radio.slab_diffuse is isotropic), got "
                f"texture_direction={tuple(texture)!r}"
            )
    return transmission


def diffuse_tables(material, tables):
    """The diffuse-transmission tables of ``material`` at its current frequency for its
    reflection ``tables`` (host side, trace time), or ``None`` (``transmission="coherent"`` or
    a wall treated as a half-space)."""
    if material._transmission != "diffuse" or material._opaque_wall:
        return None
    return build_transmission_tables(
        material._surface, material._eps, material._frequency, material._thickness, tables,
        out_of_range=material._out_of_range, face=material._face,
    )  # fmt: skip


def event_probabilities(coefs, enabled, through_on=False):
    """Probabilities of specular reflection, diffuse reflection, transmission and (with
    ``through_on``) diffuse transmission, in proportion to their powers (mean of the two
    polarizations) among the enabled events (diffuse transmission: diffuse and refraction
    both enabled); ``coefs`` as the material's ``_coefficients``. Returns ``(p_spec, p_diff,
    p_trans, p_diff_trans, none)``, ``none`` where no event carries power."""
    r_te, r_tm, t_te, t_tm, diffuse_power, through = coefs
    r = dr.squared_norm(r_te) + dr.squared_norm(r_tm)
    t = dr.squared_norm(t_te) + dr.squared_norm(t_tm)
    prs = dr.select((enabled & InteractionType.SPECULAR) > 0, r, 0.0)
    prd = dr.select((enabled & InteractionType.DIFFUSE) > 0, diffuse_power, 0.0)
    pt = dr.select((enabled & InteractionType.REFRACTION) > 0, t, 0.0)
    both = InteractionType.DIFFUSE | InteractionType.REFRACTION
    pdt = dr.select((enabled & both) == both, through, 0.0) if through_on else 0.0
    total = prs + prd + pt + pdt
    none = total <= 0.0
    norm = dr.select(none, 1.0, dr.rcp(total))
    return prs * norm, prd * norm, pt * norm, pdt * norm, none


def through_on(material, sl, ctx=None) -> bool:
    """Whether diffuse transmission can be sampled in this call of ``material`` with the
    tables ``sl`` (host side, trace time).

    Sionna's PathSolver samples with ``NO_JONES_MATRIX`` and connects a diffuse event only
    to receivers on the incident side of the surface (``sionna.rt`` ``sb_candidate_generator``):
    it cannot carry diffusely transmitted power, so there the material samples as with
    ``transmission="coherent"`` (the internal light out of the front face stays in the
    diffuse reflection) and warns once per material (call it from the material's ``sample``:
    the warning points at the solver's line)."""
    if sl is None or sl.n_psi or not sl.stacked:
        return False
    if ctx is not None and (ctx.component & NO_JONES_MATRIX) != 0:
        if not material._path_warned:
            material._path_warned = True
            warnings.warn(
                "radio materials with transmission='diffuse' are carried by "
                "RadioMapSolver only; Sionna's PathSolver connects diffuse events to "
                "receivers on the incident side, so its paths hold no diffusely transmitted "
                "power (coherent transmission and diffuse reflection are complete)",
                DiffuseTransmissionWarning,
                stacklevel=3,
            )
        return False
    return True
