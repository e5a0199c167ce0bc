"""Host side of :mod:`emscatter.radio.material`: the Dr.Jit textures of one frequency's tables
(``_Slice``; with the diffuse-transmission tables of :mod:`emscatter.radio.transmission_tables`
the lobe texture stacks two blocks along its θ axis — the reflection lobe with the internal
light added, and the transmitted lobe on the same ``(n_alpha, n_s)`` grid read as ``(φ, μ)`` —
so that one texture lookup per ray serves either hemisphere) and the keyword arguments of an
XML ``<bsdf type="emscatter-radio-material">`` (``_parse_props``). Imports Dr.Jit and Mitsuba."""

from __future__ import annotations

import mitsuba as mi
import numpy as np

from ..spectra import ExponentialCorrelation, GaussianCorrelation
from .convention import to_sionna
from .texture_jit import opaque_float, texture
from .transmission_tables import internal_on_lobe_grid, transmitted_block


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
        self.n_psi = 0
        self.stacked = transmission is not None
        if self.stacked:  # [reflection + internal light; transmission] along θ (module doc)
            lobe = np.concatenate(
                [tables.lobe + internal_on_lobe_grid(transmission, tables),
                 transmitted_block(transmission, tables)], axis=0,
            )  # fmt: skip
            self.lobe = texture(lobe, 3)
        else:
            self.lobe = texture(tables.lobe, 3)


def _parse_props(props: mi.Properties) -> dict:
    """Keyword arguments from an XML ``<bsdf type="emscatter-radio-material">``."""
    out: dict = {}

    def take(key):
        v = props[key]
        del props[key]
        return v

    for key in (
        "medium",
        "method",
        "correlation",
        "texture_direction",
        "transmission",
        "transmission_face",
    ):
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
