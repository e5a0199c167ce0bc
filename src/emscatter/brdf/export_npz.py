"""``.npz`` export of a :class:`~.table.BrdfTable` with its full metadata, and the reader.

The file (``numpy.savez_compressed``, no pickles) holds every array field of the table under
its own name (``wavelengths``, ``theta_i``, ``theta_o``, ``values``, ``phi_d`` or
``phi_i``/``phi_o``, ``coherent``, ``coherent_polarized``, optionally ``polarized``), plus
``format`` = ``"emscatter-brdf"``, ``format_version`` and ``metadata_json`` (the metadata
dict as JSON: solver, surface, material, units, version, energy flags, ...). Written
atomically (:func:`emscatter.io.atomic_path`).
"""

from __future__ import annotations

import json
import os
import zipfile
from pathlib import Path

import numpy as np

from ..io import _jsonable, atomic_path
from .table import FORMAT_VERSION, BrdfTable

__all__ = ["write_npz", "read_npz", "NPZ_FORMAT"]

NPZ_FORMAT = "emscatter-brdf"
_ARRAYS = ("wavelengths", "theta_i", "theta_o", "values", "phi_d", "phi_i", "phi_o",
           "coherent", "coherent_polarized", "polarized")  # fmt: skip


def write_npz(table: BrdfTable, path: str | os.PathLike, *, compress: bool = True) -> Path:
    """Write ``table`` to ``path`` (``.npz``) atomically; returns the path."""
    if not isinstance(table, BrdfTable):
        raise TypeError(f"table must be a BrdfTable, got {type(table).__name__}")
    path = Path(path)
    if path.suffix != ".npz":
        raise ValueError(f"path must end in .npz, got {str(path)!r}")
    arrays = {k: getattr(table, k) for k in _ARRAYS if getattr(table, k) is not None}
    meta = json.dumps(table.metadata, default=_jsonable, allow_nan=False)
    save = np.savez_compressed if compress else np.savez
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:
        save(
            fh,
            format=np.array(NPZ_FORMAT),
            format_version=np.array(FORMAT_VERSION),
            metadata_json=np.array(meta),
            **arrays,
        )
    return path


def read_npz(path: str | os.PathLike) -> BrdfTable:
    """Read a table written by :func:`write_npz`; clear errors for other files."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no such BRDF file: {str(path)!r}")
    try:
        data = np.load(path, allow_pickle=False)
    except (ValueError, OSError, zipfile.BadZipFile, EOFError) as exc:
        raise ValueError(f"{str(path)!r} is not a readable .npz file ({exc})") from None
    with data:
        keys = set(data.files)
        if "format" not in keys or str(data["format"]) != NPZ_FORMAT:
            raise ValueError(
                f"{str(path)!r} is not an emscatter BRDF table (no format={NPZ_FORMAT!r} entry)"
            )
        version = int(data["format_version"])
        if version > FORMAT_VERSION:
            raise ValueError(
                f"{str(path)!r} has table format version {version}; this emscatter reads up to "
                f"{FORMAT_VERSION} — upgrade emscatter"
            )
        missing = {"wavelengths", "theta_i", "theta_o", "values", "metadata_json"} - keys
        if missing:
            raise ValueError(f"{str(path)!r} lacks the entries {sorted(missing)}")
        try:
            fields = {k: np.array(data[k]) for k in _ARRAYS if k in keys}
            metadata = json.loads(str(data["metadata_json"]))
        except (ValueError, OSError, zipfile.BadZipFile, EOFError) as exc:
            raise ValueError(f"{str(path)!r} is damaged ({exc})") from None
    return BrdfTable(metadata=metadata, **fields)
