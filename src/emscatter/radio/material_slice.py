"""Host side of :mod:`emscatter.radio.material`: the Dr.Jit textures of one frequency's tables
(``_Slice``, with the diffuse-transmission tables of :mod:`emscatter.radio.transmission_tables`
when asked for), their per-ray lookup of the transmission lobe (``transmission_lobe``) and the
keyword arguments of an XML ``<bsdf type="emscatter-radio-material">`` (``_parse_props``).
Imports Dr.Jit and Mitsuba."""

from __future__ import annotations

import math

import drjit as dr
import mitsuba as mi
import numpy as np

from ..spectra import ExponentialCorrelation, GaussianCorrelation
from .convention import to_sionna
from .texture_jit import opaque_float, tex_coord, texture


class _Slice:
    """Dr.Jit textures of one frequency's tables (host object)."""

    def __init__(self, tables, transmission=None):
        self.tables = tables
        self.transmission = transmission  # TransmissionTables or None
        delta = to_sionna(tables.delta)  # (2, n_cos)
        inc = tables.incoherent_on_cos()
        zero = np.zeros_like(inc[0])
        through, internal = zero, zero
        if transmission is not None:  # channels 6, 7: T_diff and R_int (h + v) on cosθi
            c = np.cos(tables.theta_nodes)[::-1]
            through, internal = (
                np.interp(tables.cos_nodes, c, x.sum(0)[::-1])
                for x in (transmission.t_diff, transmission.r_internal)
            )
        # 8 channels: Dr.Jit pads other counts with a copy kernel, which fails when the table is
        # first built inside a solver's symbolic loop (drjit 1.5: undefined '%mask').
        per_cos = np.stack(
            [
                delta[0].real,
                delta[0].imag,
                delta[1].real,
                delta[1].imag,
                inc[0],
                inc[1],
                through,
                internal,
            ],
            axis=-1,
        )
        self.n_cos = tables.cos_nodes.size
        self.per_cos = texture(per_cos, 1)  # roughness correction + diffuse share, on cosθi
        self.n_theta = tables.theta_nodes.size
        self.inv_theta_max = opaque_float(1.0 / float(tables.theta_nodes[-1]))
        self.n_alpha = tables.alpha_nodes.size
        self.n_s = tables.s_nodes.size
        self.linear_s = tables.grading == 1.0
        self.inv_grading = opaque_float(1.0 / tables.grading)
        self.lobe = texture(tables.lobe, 3)
        self.n_psi = 0
        self.through = None
        if transmission is not None:
            self.through = texture(transmission.lobe, 3)  # (θi, φ, μ, 4)
            self.n_tmu = transmission.mu_nodes.size
            self.n_tphi = transmission.phi_nodes.size


def transmission_lobe(ki, ko, sl: _Slice, active):
    """``(T_h, T_v, R_int,h, R_int,v)`` [1/sr] of the diffuse-transmission tables for local
    directions ``ki`` (incident, propagating, ``ki.z < 0``) and ``ko`` (either hemisphere):
    ``μ = |ko.z|``, ``φ`` the angle between the transverse parts of ``ki`` and ``ko``."""
    cos_i = -ki.z
    ti = dr.sqrt(ki.x * ki.x + ki.y * ki.y)
    to = dr.sqrt(ko.x * ko.x + ko.y * ko.y)
    den = ti * to
    cos_phi = dr.select(
        den > 1e-9, (ki.x * ko.x + ki.y * ko.y) * dr.rcp(dr.maximum(den, 1e-9)), 1.0
    )
    phi = dr.safe_acos(dr.clip(cos_phi, -1.0, 1.0)) * (1.0 / math.pi)
    th = dr.clip(dr.safe_acos(cos_i) * sl.inv_theta_max, 0.0, 1.0)
    pos = mi.Point3f(
        tex_coord(dr.clip(dr.abs(ko.z), 0.0, 1.0), sl.n_tmu),
        tex_coord(phi, sl.n_tphi),
        tex_coord(th, sl.n_theta),
    )
    return [dr.maximum(x, 0.0) for x in sl.through.eval(pos, active)]


def _parse_props(props: mi.Properties) -> dict:
    """Keyword arguments from an XML ``<bsdf type="emscatter-radio-material">``."""
    out: dict = {}

    def take(key):
        v = props[key]
        del props[key]
        return v

    for key in ("medium", "method", "correlation", "texture_direction", "transmission"):
        if key in props:
            out[key] = str(take(key))
    floats = ("eps_real", "conductivity", "thickness", "rms_height", "correlation_length")
    for key in (*floats, "correlation_length_y"):
        if key in props:
            out[key] = float(take(key))
    if "half_space" in props and bool(take("half_space")):
        out["thickness"] = None
    if "rms_height" in out or "correlation_length" in out:
        if "rms_height" not in out or "correlation_length" not in out:
            raise ValueError(
                f"emscatter-radio-material {props.id()!r}: give both rms_height [m] and "
                "correlation_length [m] (or neither, for a flat surface)"
            )
        kind = out.pop("correlation", "gaussian").lower()
        cls = {"gaussian": GaussianCorrelation, "exponential": ExponentialCorrelation}.get(kind)
        if cls is None:
            raise ValueError(
                f"emscatter-radio-material {props.id()!r}: correlation must be 'gaussian' or "
                f"'exponential', got {kind!r}"
            )
        out["surface"] = cls(sigma=out.pop("rms_height"), length=out.pop("correlation_length"),
                             length_y=out.pop("correlation_length_y", None))  # fmt: skip
    if "texture_direction" in out:  # "0 0 1" or "0, 0, 1"
        text = out["texture_direction"]
        try:
            out["texture_direction"] = [float(v) for v in text.replace(",", " ").split()]
        except ValueError:
            raise ValueError(
                f"emscatter-radio-material {props.id()!r}: texture_direction must be three "
                f"numbers (e.g. '0 0 1'), got {text!r}"
            ) from None
    return out
