"""Tabulated BRDFs from emscatter's solvers, the seed's analytic models, and exports.

* :class:`BrdfTable` (:mod:`.table`): f_r [1/sr] on (θi, θo, Δφ) or (θi, φi, θo, φo) grids in
  the renderer frame (:mod:`.frames`), per wavelength, coherent delta lobe kept apart.
* :func:`build_table` (:mod:`.build`): from any solver or ``"auto"``, energy remedy applied.

Layout, interpolation and conventions: :mod:`.table` and ``/work/notes/brdf.md``.
"""

from __future__ import annotations

from .build import build_table
from .table import Albedo, BrdfTable

__all__ = ["BrdfTable", "Albedo", "build_table"]
