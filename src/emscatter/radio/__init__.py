"""The bridge to Sionna RT: radio materials whose reflection, transmission and diffuse lobe come
from emscatter's rough-surface solvers.

::

    import emscatter as em
    from emscatter import radio
    wall = radio.MaterialSpec(surface=em.GaussianCorrelation(sigma=0.4e-3, length=4e-3),
                              medium="concrete", thickness=0.2)      # ITU-R P.2040 concrete
    tables = wall.tables(28e9)            # NumPy: what the material reads per ray (no Sionna)
    tables.method, tables.valid, tables.incoherent

    # in a process that runs Sionna RT (Dr.Jit variants are per process):
    mat = wall.sionna("wall")             # an EmscatterRadioMaterial (RadioMaterialBase)
    scene.get("wall").radio_material = mat

Nothing here imports Sionna, Mitsuba or Dr.Jit except :mod:`emscatter.radio.material` (and
the functions that run Sionna), so ``import emscatter.radio`` stays light. Modules:
:mod:`.medium` (what a wall is made of), :mod:`.convention` (the ``exp(±jωt)`` flip),
:mod:`.slab` (rough-slab coefficients), :mod:`.tables` (per-frequency tables from the solvers),
:mod:`.material` (the Sionna class), :mod:`.scenes` (PLY/XML scenes from NumPy),
:mod:`.roughening` (any Sionna scene rough in one call, flat again, and rough − flat path
gains and radio maps in one call: ``roughen``, ``flatten``, ``compare_rough_flat``),
:mod:`.builtin` (Sionna's built-in S, lobe and XPD fitted to the tables, and where no
built-in model stands in: ``builtin_equivalent``), :mod:`.calibration` (σ and ℓ fitted to
observed path gains, with their uncertainty: ``calibrate``), :mod:`.plate`, :mod:`.indoor` and
:mod:`.sweep` (the three cross-checks), :mod:`.demo`, :mod:`.from_map` (the roughness of a
measured height map: ``MaterialSpec.from_height_map``), :mod:`.xpd` (cross-polar
discrimination per path) and :mod:`.xpd_map` (per radio-map cell: ``polarized_radio_map``;
rough vs flat with ``compare_rough_flat(..., xpd_map=True)``).
"""

from __future__ import annotations

from dataclasses import dataclass

from .builtin import builtin_equivalent
from .calibration import calibrate
from .convention import from_sionna, sionna_eps_conductivity, sionna_permittivity, to_sionna
from .medium import ConductiveMedium, check_thickness, real_number, resolve_medium
from .roughening import (
    DEFAULT_ROUGHNESS,
    DEFAULT_ROUGHNESS_SOURCE,
    Roughened,
    compare_rough_flat,
    flatten,
    roughen,
)
from .slab import slab_coefficients
from .tables import (
    EnergyWarning,
    RadioTables,
    RadioValidityWarning,
    TableOptions,
    build_log,
    build_tables,
    reset_build_log,
)
from .xpd_map import polarized_radio_map

__all__ = [
    "MaterialSpec",
    "builtin_equivalent",
    "calibrate",
    "roughen",
    "flatten",
    "compare_rough_flat",
    "polarized_radio_map",
    "Roughened",
    "DEFAULT_ROUGHNESS",
    "DEFAULT_ROUGHNESS_SOURCE",
    "ConductiveMedium",
    "resolve_medium",
    "slab_coefficients",
    "TableOptions",
    "RadioTables",
    "build_tables",
    "build_log",
    "reset_build_log",
    "EnergyWarning",
    "RadioValidityWarning",
    "to_sionna",
    "from_sionna",
    "sionna_permittivity",
    "sionna_eps_conductivity",
]


@dataclass(frozen=True)
class MaterialSpec:
    """A radio material described without Sionna: roughness statistics (or ``None``: flat),
    a medium (ITU name, Material or permittivity; or ``eps_real`` + ``conductivity`` [S/m]),
    a slab ``thickness`` [m] (``None``: half-space), the emscatter ``method`` and grid options;
    ``texture_direction``: the world direction of the ``ℓx`` axis of anisotropic roughness
    (:mod:`emscatter.radio.texture`; required when ``length_y ≠ length``)."""

    surface: object = None
    medium: object = None
    eps_real: float | None = None
    conductivity: float | None = None
    thickness: float | None = 0.1
    method: str = "auto"
    out_of_range: str = "warn"
    options: TableOptions | None = None
    texture_direction: object = None

    def __post_init__(self):
        # checked where it enters (a wrong thickness would otherwise surface only in Sionna)
        object.__setattr__(self, "thickness", check_thickness(self.thickness))
        if self.texture_direction is not None:
            from .texture import check_direction

            object.__setattr__(self, "texture_direction", check_direction(self.texture_direction))

    @classmethod
    def from_height_map(
        cls,
        source,
        *,
        model: str = "measured",
        family: str = "best",
        segments: int = 8,
        tail: str = "none",
        unit=None,
        detrend="plane",
        holes: str = "reject",
        slope_tail: str = "gaussian",
        frequencies=None,
        **spec,
    ) -> MaterialSpec:
        """A spec whose ``surface`` is a measured height map's roughness (a file, a
        :class:`~emscatter.surfaces.heightmap.HeightMap` or an isotropic
        :class:`~emscatter.surfaces.measured.MeasuredRoughness`): the map's ring-averaged
        spectrum (``model="measured"``) or σ, ℓ of a fitted correlation ``family``
        (``model="fit"``), see :func:`emscatter.radio.from_map.surface_from_map` (which and
        why; ``frequencies`` [Hz] checks the band each needs). ``spec``: the other fields
        (``medium``, ``thickness``, …). The choices are in ``spec.map_record``."""
        from .from_map import surface_from_map

        rough, record = surface_from_map(
            source, model=model, family=family, segments=segments, tail=tail, unit=unit,
            detrend=detrend, holes=holes, slope_tail=slope_tail, frequencies=frequencies,
        )  # fmt: skip
        out = cls(surface=rough, **spec)
        object.__setattr__(out, "map_record", record)
        return out

    def material(self):
        """The :class:`~emscatter.materials.Material` (checks the inputs)."""
        return resolve_medium(self.medium, eps_real=self.eps_real, conductivity=self.conductivity)

    def tables(self, frequency: float, label: str = "material") -> RadioTables:
        """The tables at ``frequency`` [Hz] (raises out of the medium's band)."""
        frequency = real_number("frequency", frequency)
        eps = complex(self.material().eps(frequency=frequency))
        build = build_tables
        if self.texture_direction is not None or not getattr(self.surface, "is_isotropic", True):
            from .texture import build_textured_tables as build
        return build(
            self.surface,
            eps,
            frequency,
            method=self.method,
            out_of_range=self.out_of_range,
            label=label,
            options=self.options,
        )

    def sionna(self, name: str, color=None):
        """An :class:`~emscatter.radio.material.EmscatterRadioMaterial` (imports Sionna RT)."""
        from .material import EmscatterRadioMaterial

        return EmscatterRadioMaterial(
            name,
            surface=self.surface,
            medium=self.medium,
            eps_real=self.eps_real,
            conductivity=self.conductivity,
            thickness=self.thickness,
            method=self.method,
            out_of_range=self.out_of_range,
            table_options=self.options,
            texture_direction=self.texture_direction,
            color=color,
        )
