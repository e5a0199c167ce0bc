"""Validation against the method of moments: validity maps and the emissivity table.

* :mod:`.maps` — the maps' configurations, MoM references (stored, resumable), evaluation of
  every approximation, ``auto``'s selector failures;
* :mod:`.tapered` — the exponential maps' surface: the exponential spectrum with a smooth
  inner cutoff, with the n-fold spectra PO and the IEM need;
* :mod:`.map_files` — CSV / JSON / PNG / Markdown;
* :mod:`.emissivity_table` — MoM vs SPM2 emissivity of a lossy dielectric.

:func:`run_validation` is ``emscatter validate``.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

from .maps import FULL, PUBLISHED, SMALL, MapConfig, compute_map, tag_of

__all__ = ["run_validation", "reselect", "reselect_all"]


def run_validation(
    out: Path,
    *,
    full: bool = False,
    config: MapConfig | None = None,
    progress: bool | None = None,
    plots: bool = True,
) -> list[Path]:
    """Compute and write the validity maps (``emscatter validate``): the small PEC grid
    (:data:`.maps.SMALL`) by default, the four published maps (:data:`.maps.PUBLISHED`:
    Gaussian and exponential, PEC and ε = 3) and the emissivity table with ``full=True``,
    or ``config``. MoM references go to ``out/mom_<tag>.json`` as each cell finishes and
    are reused by a later run (resume, or re-evaluation after a model change). Writes
    ``validity_<tag>.csv/.json/.md`` and ``validity_<tag>_{h,v}.png``; with ``full=True``
    also ``measured_errors.json`` (the table ``auto`` reads, :mod:`emscatter.solvers.measured`;
    :func:`reselect_all` installs it) and ``validity_iem.png``; ``plots=False`` skips the
    PNGs (tests); ``progress``: the tqdm bar over the MoM cells (``None``: on a terminal past
    2 s, :mod:`emscatter.progress`); returns the paths."""
    from .emissivity_table import emissivity_table
    from .map_files import write_map
    from .measured_table import write_measured

    configs = [config] if config is not None else (list(PUBLISHED) if full else [SMALL])
    out = Path(out)
    paths: list[Path] = []
    maps = []
    for cfg in configs:
        store = out / f"mom_{tag_of(cfg)}.json"
        t0 = time.perf_counter()
        rows = compute_map(cfg, store=store, progress=progress)
        seconds = _mom_seconds(store) or time.perf_counter() - t0
        paths.extend(write_map(rows, cfg, out, seconds=seconds, plots=plots))
        paths.append(store)
        maps.append((cfg, rows))
    if full and config is None:
        paths.append(write_measured(maps, out / "measured_errors.json"))
        paths.extend(_model_figures(maps, out))
        paths.append(emissivity_table(out))
    return paths


def _model_figures(maps, out: Path) -> list[Path]:
    """``validity_iem.png``: the IEM's own map over every published map (when registered)."""
    from .. import solvers
    from .map_files import plot_method

    if "iem" not in solvers.available():
        return []
    return [plot_method(maps, "iem", Path(out) / "validity_iem.png")]


def _mom_seconds(store: Path) -> float:
    """Sum of the per-cell MoM times recorded in a reference store (CPU-seconds of cells)."""
    if not store.exists():
        return 0.0
    cells = json.loads(store.read_text())["cells"]
    return float(sum(c.get("seconds", 0.0) for c in cells))


def _store(out: Path, cfg: MapConfig) -> Path:
    store = Path(out) / f"mom_{tag_of(cfg)}.json"
    if not store.exists():
        raise FileNotFoundError(f"{store} missing: run `emscatter validate --full --out {out}`")
    return store


def reselect(out: Path, cfg: MapConfig = FULL) -> list[Path]:
    """Re-evaluate every approximation and the ``auto`` choice of a map from its stored MoM
    references (no MoM run) and rewrite its files — after a model or criterion change
    (``auto`` reads the installed measured table; :func:`reselect_all` renews it)."""
    from .map_files import write_map

    store = _store(out, cfg)
    rows = compute_map(cfg, store=store, progress=False)
    return write_map(rows, cfg, out, seconds=_mom_seconds(store))


def reselect_all(out: Path, *, install_table: bool = True) -> list[Path]:
    """Every published map from its stored MoM references: evaluate the approximations,
    write the measured-error table (``out/measured_errors.json`` and, with
    ``install_table``, the one the package reads), then ``auto``'s choice with that table,
    and the map files and model figures. The command is in validation/validity_maps/README.md."""
    from ..solvers.measured import TABLE_PATH
    from .map_files import write_map
    from .maps import refresh_auto
    from .measured_table import write_measured

    maps = []
    for cfg in PUBLISHED:
        maps.append((cfg, compute_map(cfg, store=_store(out, cfg), progress=False)))
    paths = [write_measured(maps, Path(out) / "measured_errors.json")]
    if install_table:
        paths.append(write_measured(maps, TABLE_PATH))
    for cfg, rows in maps:
        refresh_auto(rows, cfg)
        paths += write_map(rows, cfg, out, seconds=_mom_seconds(_store(out, cfg)))
    return paths + _model_figures(maps, out)
