"""Media whose permittivity depends on frequency or wavelength — shared by the BRDF bridge
(metals at visible wavelengths) and the radio bridge (building materials at GHz).

::

    from emscatter import materials as mat
    gold = mat.metal("Au")                       # Mitsuba 3's own η/k data (mitsuba/data/ior)
    gold.eps(wavelength=[450e-9, 550e-9, 650e-9])
    concrete = mat.itu("concrete")               # ITU-R P.2040, Sionna RT's table and bands
    concrete.eps(frequency=3.5e9), concrete.conductivity(3.5e9)
    mat.eps_from_conductivity(5.24, 0.12, 3.5e9) # ε′ + iσ/(ωε₀)   (exp(−iωt), Im ε ≥ 0)
    mat.to_engineering(eps)                      # the exp(+jωt) form Sionna uses (conjugate)
    mat.as_material(17 + 2j), mat.as_material("Au"), mat.as_material("itu:concrete")
    soil = mat.MironovSoil(moisture=0.25, clay=0.3)  # or mat.DobsonSoil(moisture, sand, clay, ...)
    sea = mat.MeissnerWentzWater(temperature=293.15, salinity=35)  # or KleinSwiftWater
    mat.as_material("soil"), mat.as_material("soil:dobson"), mat.as_material("sea_water")

Every material says where its numbers come from (``.source``) and where they hold (``.band``
[Hz]); asking outside the band raises :class:`OutOfBandError` naming the band and the ways out.
"""

from __future__ import annotations

import numbers

import numpy as np

from .core import (
    ComplexIndex,
    Constant,
    Drude,
    Material,
    OutOfBandError,
    PerfectConductor,
    Tabulated,
    conductivity_from_eps,
    eps_from_conductivity,
    eps_from_nk,
    format_frequency,
    frequency_array,
    from_engineering,
    nk_from_eps,
    to_engineering,
)
from .itu import ITU_P2040, ItuMaterial, available_itu, itu
from .metals import available_metals, metal
from .soil import DobsonSoil, MironovSoil, soil
from .water import KleinSwiftWater, MeissnerWentzWater, sea_water

__all__ = [
    "Material",
    "Constant",
    "ComplexIndex",
    "Drude",
    "Tabulated",
    "PerfectConductor",
    "ItuMaterial",
    "DobsonSoil",
    "MironovSoil",
    "KleinSwiftWater",
    "MeissnerWentzWater",
    "soil",
    "sea_water",
    "NATURAL_MEDIA",
    "OutOfBandError",
    "metal",
    "itu",
    "available_metals",
    "available_itu",
    "ITU_P2040",
    "as_material",
    "eps_at",
    "from_dict",
    "eps_from_nk",
    "nk_from_eps",
    "eps_from_conductivity",
    "conductivity_from_eps",
    "to_engineering",
    "from_engineering",
    "frequency_array",
    "format_frequency",
]


#: Names of the natural media (:mod:`.soil`, :mod:`.water`) with their default parameters:
#: ``"soil"`` is Mironov's model at moisture 0.2 m³/m³ and clay 0.2; ``"soil:dobson"`` Dobson's
#: at moisture 0.2, sand 0.4, clay 0.2, bulk density 1400 kg/m³, 20 °C; ``"sea_water"``
#: Meissner–Wentz at 20 °C and 35 psu (``"sea_water:klein-swift"`` Klein–Swift's);
#: ``"fresh_water"`` Meissner–Wentz at 20 °C and 0 psu. Other moistures, textures,
#: temperatures and salinities: build the class (``MironovSoil(moisture=0.3, clay=0.1)``).
NATURAL_MEDIA = {
    "soil": lambda: soil("mironov"),
    "soil:mironov": lambda: soil("mironov"),
    "soil:dobson": lambda: soil("dobson"),
    "sea_water": lambda: sea_water("meissner-wentz"),
    "sea_water:meissner-wentz": lambda: sea_water("meissner-wentz"),
    "sea_water:klein-swift": lambda: sea_water("klein-swift"),
    "fresh_water": lambda: MeissnerWentzWater(salinity=0.0, name="fresh water (Meissner-Wentz)"),
}


def _natural_medium(low: str):
    key = low.replace(" ", "_").replace("seawater", "sea_water")
    if key in NATURAL_MEDIA:
        return NATURAL_MEDIA[key]()
    if key.startswith(("soil", "sea_water")):
        raise ValueError(
            f"unknown material {low!r}: the natural media are {sorted(NATURAL_MEDIA)}; for "
            "other parameters build one, e.g. emscatter.materials.MironovSoil(moisture=0.3, "
            "clay=0.1), DobsonSoil(moisture, sand, clay, bulk_density [kg/m³], temperature "
            "[K]) or MeissnerWentzWater(temperature [K], salinity [psu])"
        )
    return None


def as_material(value, *, extrapolate: bool = False) -> Material:
    """A :class:`Material` from a Material (returned as is), a number (``Constant``), ``"pec"``,
    a Mitsuba metal name (``"Au"``, or ``"mitsuba:Au"``), an ITU-R P.2040 name
    (``"concrete"``, or ``"itu:concrete"``) or a natural medium (:data:`NATURAL_MEDIA`:
    ``"soil"``, ``"soil:dobson"``, ``"sea_water"``, ...)."""
    if isinstance(value, Material):
        return value
    if isinstance(value, bool) or value is None:
        raise TypeError(
            f"eps must be a complex permittivity, 'pec', a material name or a "
            f"emscatter.materials.Material, got {value!r}"
        )
    if isinstance(value, numbers.Number) or (
        isinstance(value, np.ndarray | np.generic) and np.ndim(value) == 0
    ):
        return Constant(complex(value))
    if isinstance(value, str):
        text = value.strip()
        low = text.lower()
        if low == "pec":
            return PerfectConductor()
        if low.startswith("itu:"):
            return itu(low[4:], extrapolate=extrapolate)
        if low.startswith("mitsuba:"):
            return metal(text[len("mitsuba:") :], extrapolate=extrapolate)
        if low in ITU_P2040:
            return itu(low, extrapolate=extrapolate)
        medium = _natural_medium(low)
        if medium is not None:
            return medium
        try:
            names = available_metals()
        except (ModuleNotFoundError, FileNotFoundError):
            names = []
        if text in names:
            return metal(text, extrapolate=extrapolate)
        number = _as_number_text(text)
        if number is not None:
            raise TypeError(
                f"eps={value!r} is a string; pass a complex number instead: eps={number!r} "
                "(a string names a material such as 'concrete' or 'Au', or 'pec')"
            )
        raise ValueError(_unknown_material(value, names))
    raise TypeError(
        f"eps must be a complex permittivity, 'pec', a material name or a "
        f"emscatter.materials.Material, got {type(value).__name__}"
    )


def _as_number_text(text: str):
    """The complex number a string like ``"17+2j"``, ``"17+2i"`` or ``"(4)"`` spells, else None."""
    t = text.strip().lower().replace(" ", "").replace("i", "j")
    if not t or not (t[0].isdigit() or t[0] in "+-.("):
        return None
    try:
        z = complex(t)
    except ValueError:
        return None
    return z.real if z.imag == 0 else z


def _unknown_material(value, metals: list[str]) -> str:
    """ "unknown material" with the closest names (not every name: there are ~90)."""
    import difflib

    itu_names = list(available_itu())
    every = ["pec", *itu_names, *NATURAL_MEDIA, *metals]
    lower = {n.lower(): n for n in every}
    close = difflib.get_close_matches(str(value).strip().lower(), list(lower), n=3, cutoff=0.6)
    hint = f"; did you mean {', '.join(repr(lower[c]) for c in close)}?" if close else ""
    where = (
        f"{len(metals)} Mitsuba metals (materials.available_metals())"
        if metals
        else "the Mitsuba metals (Mitsuba not installed)"
    )
    return (
        f"unknown material {value!r}: use 'pec', one of {len(itu_names)} ITU-R P.2040 names "
        f"(materials.available_itu(), e.g. 'concrete'), a natural medium "
        f"(materials.NATURAL_MEDIA, e.g. 'soil') or one of {where}, e.g. 'Au'; a "
        f"permittivity is a complex number (eps=17+2j), not a string{hint}"
    )


def eps_at(value, frequency=None, wavelength=None):
    """What the solvers take: ``"pec"`` for a perfect conductor, else the complex ε array of
    ``value`` (anything :func:`as_material` accepts) at ``frequency`` [Hz] or ``wavelength`` [m]."""
    mat = as_material(value)
    if isinstance(mat, PerfectConductor):
        frequency_array(frequency, wavelength)  # still check the frequency
        return "pec"
    return mat.eps(frequency=frequency, wavelength=wavelength)


def from_dict(d: dict) -> Material:
    """Rebuild a material from :meth:`Material.to_dict` (metadata round trip)."""
    if not isinstance(d, dict) or "type" not in d:
        raise ValueError(f"not a material description (needs a 'type' key): {d!r}")
    kind = d["type"]
    if kind == "Constant":
        return Constant(complex(d["eps"]["re"], d["eps"]["im"]), name=d["name"], source=d["source"])
    if kind == "ComplexIndex":
        return ComplexIndex(d["n"], d["k"], name=d["name"], source=d["source"])
    if kind == "Drude":
        return Drude(
            d["plasma_angular_frequency"],
            d["collision_rate"],
            d["eps_inf"],
            name=d["name"],
            source=d["source"],
        )
    if kind == "PerfectConductor":
        return PerfectConductor()
    if kind == "ItuMaterial":
        return itu(d["name"], extrapolate=d.get("extrapolate", False))
    if kind in _NATURAL_TYPES:
        cls = _NATURAL_TYPES[kind]
        fields = {k: d[k] for k in cls.__dataclass_fields__ if k in d}
        return cls(**fields)
    if kind == "Tabulated":
        common = {"name": d["name"], "source": d["source"], "extrapolate": d["extrapolate"]}
        if "n" in d:
            return Tabulated(
                np.array(d["wavelength"]), n=np.array(d["n"]), k=np.array(d["k"]), **common
            )
        eps = np.array(d["eps_re"]) + 1j * np.array(d["eps_im"])
        return Tabulated(np.array(d["wavelength"]), eps, **common)
    raise ValueError(f"unknown material type {kind!r} in {d!r}")


_NATURAL_TYPES = {
    c.__name__: c for c in (DobsonSoil, MironovSoil, KleinSwiftWater, MeissnerWentzWater)
}
