"""The ``emscatter_dielectric`` Mitsuba plugin: a rough dielectric interface from emscatter
tables (reflection outside and inside, transmission through it).

:mod:`.plugin` holds the plugin (scalar, RGB, mono and spectral variants), :mod:`.delta` the
coherent (delta) lobes, :mod:`.polarized` the ``*_polarized`` variants. ``from emscatter.render
import dielectric as em_d`` then ``em_d.bsdf_dict(...)`` works as before the package split.
"""

from .plugin import PLUGIN_NAME, bsdf_dict, register, register_dielectric

__all__ = ["PLUGIN_NAME", "bsdf_dict", "register", "register_dielectric"]
