"""emscatter — electromagnetic scattering from rough surfaces, carried to renderers and radio.

A short tour (SI units, radians, ``exp(-iωt)`` so lossy media have ``Im ε ≥ 0``)::

    import numpy as np, emscatter as em
    rough = em.GaussianCorrelation(sigma=0.01, length=0.1)         # σ, ℓ [m]
    th = np.radians(np.linspace(0, 89, 90))
    s = em.bistatic(rough, 17 + 2j, frequency=1e9, theta_i=np.radians(45),
                    theta_s=th, phi_s=0.0)                           # method="auto"
    s.hh, s.vv, s.hv, s.method, s.coherent                           # σ⁰ [pol_s, pol_i], linear
    em.backscatter(rough, 17 + 2j, frequency=1e9, theta_i=th).vv
    em.emissivity(rough, 17 + 2j, frequency=1e9, theta_i=th).h       # 1 − r_coh − r_incoh
    surf = em.generate_surface(rough, (512, 512), spacing=0.005, rng=0)  # a realization
    surf.measure()                                                   # σ, slopes, ℓ, ...
    hm = em.surfaces.height_map(surf.heights, surf.spacing)          # or read_height_map(f)
    em.po_map(hm, 17 + 2j, k=2 * np.pi / 0.3, theta_i=0.5).efficiency  # its grating orders

See ``README.md`` for conventions and the command-line tool (``emscatter --help``).
"""

from __future__ import annotations

from . import constants, fresnel
from ._version import __version__
from .api import backscatter, bistatic, emissivity
from .conventions import ConventionError, PlausibilityWarning
from .emissivity import QuadratureWarning
from .fresnel import PEC
from .scattering import Scattering
from .solvers.select import ValidityError, ValidityWarning
from .spectra import (
    ExponentialCorrelation,
    FractionalBrownian,
    GaussianCorrelation,
    PowerLawCorrelation,
    roughness,
)

__all__ = [
    "bistatic",
    "backscatter",
    "emissivity",
    "generate_surface",
    "po_map",
    "materials",
    "Scattering",
    "GaussianCorrelation",
    "ExponentialCorrelation",
    "PowerLawCorrelation",
    "FractionalBrownian",
    "roughness",
    "fresnel",
    "constants",
    "PEC",
    "ConventionError",
    "PlausibilityWarning",
    "ValidityWarning",
    "ValidityError",
    "QuadratureWarning",
    "OutOfBandError",
    "__version__",
]


def __getattr__(name):  # lazy: keep `import emscatter` light
    if name == "materials":
        import importlib

        return importlib.import_module(".materials", __name__)
    if name == "OutOfBandError":
        from .materials import OutOfBandError

        return OutOfBandError
    if name == "generate_surface":
        from .surfaces.generate import generate_surface

        return generate_surface
    if name == "po_map":  # PO on a height map itself (emscatter.solvers.kirchhoff.po_map)
        from .solvers.kirchhoff.po_map import po_map

        return po_map
    raise AttributeError(f"module 'emscatter' has no attribute {name!r}")
