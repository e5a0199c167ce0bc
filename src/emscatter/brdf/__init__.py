"""Tabulated BRDFs from emscatter's solvers, the seed's analytic models, and exports.

* :class:`BrdfTable` (:mod:`.table`): f_r [1/sr] on (θi, θo, Δφ) or (θi, φi, θo, φo) grids in
  the renderer frame (:mod:`.frames`), per wavelength, coherent delta lobe kept apart.
* :func:`build_table` (:mod:`.build`): from any solver or ``"auto"``, energy remedy applied.
* :func:`build_tables` (:mod:`.farm`): many tables (materials × wavelengths × roughness,
  :func:`table_specs`) serially, on an Executor or a dask.distributed cluster.

* :mod:`.analytic`: the seed's analytic models (Cook–Torrance, Ward, Phong, …, ch. 2),
  their slope distributions (:mod:`.analytic.distributions`, ch. 3), roughness equivalences
  (:mod:`.analytic.equivalence`) and fits of a model to a table (:mod:`.analytic.fit`).
* exporters: :mod:`.export_rgl` (Mitsuba's ``measured``), :mod:`.export_merl`,
  :mod:`.export_npz`.

Layout, interpolation and conventions: :mod:`.table` and ``docs/brdf.md``. The 0.1 names
``emscatter.brdf.distributions``, ``.equivalence`` and ``.fit`` resolve to their homes under
:mod:`.analytic` with a ``DeprecationWarning`` (removed in 0.3).
"""

from __future__ import annotations

from .build import build_table
from .farm import build_tables, table_specs
from .table import Albedo, BrdfTable

__all__ = ["BrdfTable", "Albedo", "build_table", "build_tables", "table_specs"]

_MOVED = {
    "distributions": "emscatter.brdf.analytic.distributions",
    "equivalence": "emscatter.brdf.analytic.equivalence",
    "fit": "emscatter.brdf.analytic.fit",
}


def __getattr__(name: str):
    """The deprecated 0.1 module names (:data:`_MOVED`): the moved module, with a warning."""
    if name in _MOVED:
        import importlib
        import warnings

        warnings.warn(
            f"emscatter.brdf.{name} moved to {_MOVED[name]} in 0.2 and will be removed in 0.3",
            DeprecationWarning,
            stacklevel=2,
        )
        return importlib.import_module(_MOVED[name])
    raise AttributeError(f"module 'emscatter.brdf' has no attribute {name!r}")
