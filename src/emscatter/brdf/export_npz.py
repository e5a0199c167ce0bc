"""``.npz`` export of a :class:`~.table.BrdfTable` with its full metadata, and the reader.

The file (``numpy.savez_compressed``, no pickles) holds every array field of the table under
its own name (``wavelengths``, ``theta_i``, ``theta_o``, ``values``, ``phi_d`` or
``phi_i``/``phi_o``, ``coherent``, ``coherent_polarized``, optionally ``polarized``), plus
``format`` = ``"emscatter-brdf"``, ``format_version`` and ``metadata_json`` (the metadata
dict as JSON: solver, surface, material, units, version, energy flags, ...), and
``checksum`` = SHA-256 (hex) of every other member (name, dtype, shape and bytes, in name
order). Written atomically (:func:`emscatter.io.atomic_path`).

On read, a file that is not a readable ``.npz`` (truncated, foreign, damaged compressed data:
the zip CRC-32 and the SHA-256 both fail) or whose checksum does not match its members is
rejected with a ``ValueError`` naming the file and what is wrong; so is one whose arrays break
the table's physical checks (finite, ``f_r ≥ 0``, coherent reflectivity in ``[0, 1]``, axes
in range; :class:`~.table.BrdfTable`). Files written before the checksum existed have none:
they are read with the physical checks only.

The transmission part of a BSDF (:class:`~.btdf_table.BtdfTable`) has its own file kind,
``format`` = ``"emscatter-btdf"`` (members ``wavelengths``, ``theta_i``, ``theta_t``,
``phi_d``, ``values``, ``eps``, optionally ``mueller``, ``metadata_json``, the same checksum
and checks):
:func:`write_btdf_npz` / :func:`read_btdf_npz`; each reader refuses the other kind by name.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

import numpy as np

from ..io import _jsonable, atomic_path
from .btdf_table import BtdfTable
from .table import FORMAT_VERSION, BrdfTable

__all__ = ["write_npz", "read_npz", "write_btdf_npz", "read_btdf_npz", "NPZ_FORMAT", "BTDF_FORMAT"]

NPZ_FORMAT = "emscatter-brdf"
BTDF_FORMAT = "emscatter-btdf"
_BTDF_ARRAYS = (
    "wavelengths",
    "theta_i",
    "theta_t",
    "phi_d",
    "values",
    "eps",
    "mueller",
    "coherent",
)
_ARRAYS = ("wavelengths", "theta_i", "theta_o", "values", "phi_d", "phi_i", "phi_o",
           "coherent", "coherent_polarized", "polarized")  # fmt: skip
_CHECKSUM = "checksum"


def _checksum(members: dict[str, np.ndarray]) -> str:
    """SHA-256 (hex) of the members (name, dtype, shape, bytes), in name order."""
    h = hashlib.sha256()
    for name in sorted(members):
        a = np.ascontiguousarray(members[name])
        h.update(f"{name}:{a.dtype.str}:{a.shape};".encode())
        h.update(a.reshape(-1).view(np.uint8))
    return h.hexdigest()


def write_npz(table: BrdfTable, path: str | os.PathLike, *, compress: bool = True) -> Path:
    """Write ``table`` to ``path`` (``.npz``) atomically; returns the path."""
    if not isinstance(table, BrdfTable):
        raise TypeError(f"table must be a BrdfTable, got {type(table).__name__}")
    path = Path(path)
    if path.suffix != ".npz":
        raise ValueError(f"path must end in .npz, got {str(path)!r}")
    arrays = {k: getattr(table, k) for k in _ARRAYS if getattr(table, k) is not None}
    return _write(path, NPZ_FORMAT, arrays, table.metadata, compress)


def write_btdf_npz(table, path: str | os.PathLike, *, compress: bool = True) -> Path:
    """Write a :class:`~.btdf_table.BtdfTable` to ``path`` (``.npz``) atomically."""
    if not isinstance(table, BtdfTable):
        raise TypeError(f"table must be a BtdfTable, got {type(table).__name__}")
    path = Path(path)
    if path.suffix != ".npz":
        raise ValueError(f"path must end in .npz, got {str(path)!r}")
    arrays = {k: getattr(table, k) for k in _BTDF_ARRAYS if getattr(table, k) is not None}
    return _write(path, BTDF_FORMAT, arrays, table.metadata, compress)


def _write(path: Path, fmt: str, arrays: dict, metadata: dict, compress: bool) -> Path:
    meta = json.dumps(metadata, default=_jsonable, allow_nan=False)
    save = np.savez_compressed if compress else np.savez
    members = {
        "format": np.array(fmt),
        "format_version": np.array(FORMAT_VERSION),
        "metadata_json": np.array(meta),
        **{k: np.asarray(v) for k, v in arrays.items()},
    }
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:
        save(fh, **members, **{_CHECKSUM: np.array(_checksum(members))})
    return path


def read_npz(path: str | os.PathLike) -> BrdfTable:
    """Read a table written by :func:`write_npz`; a ``ValueError`` naming the file and what is
    wrong for a foreign, truncated or damaged file (module docstring)."""
    name, metadata, fields = _read(path, NPZ_FORMAT, _ARRAYS)
    try:
        return BrdfTable(metadata=metadata, **fields)
    except (ValueError, TypeError) as exc:
        raise ValueError(f"{name} is damaged: {exc}") from None


def read_btdf_npz(path: str | os.PathLike):
    """Read a :class:`~.btdf_table.BtdfTable` written by :func:`write_btdf_npz` (errors as
    :func:`read_npz`)."""
    name, metadata, fields = _read(path, BTDF_FORMAT, _BTDF_ARRAYS)
    try:
        return BtdfTable(metadata=metadata, **fields)
    except (ValueError, TypeError) as exc:
        raise ValueError(f"{name} is damaged: {exc}") from None


def _read(path, kind: str, names: tuple) -> tuple[str, dict, dict]:
    """``(quoted name, metadata, arrays)`` of a checked file of format ``kind``."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no such BRDF file: {str(path)!r}")
    name = repr(str(path))
    with open(path, "rb") as fh:  # ours to close, whatever np.load makes of the bytes
        try:
            data = np.load(fh, allow_pickle=False)
        except Exception as exc:  # noqa: BLE001 — any damage of the archive: one clear error
            raise ValueError(
                f"{name} is not a readable .npz file (truncated, damaged or another format: {exc})"
            ) from None
        if not isinstance(data, np.lib.npyio.NpzFile):
            raise ValueError(f"{name} is a bare .npy array, not an emscatter BRDF table (.npz)")
        with data:
            try:
                members = {k: np.array(data[k]) for k in data.files}
            except Exception as exc:  # noqa: BLE001 — zlib, CRC, zip flags, npy header...
                raise ValueError(f"{name} is damaged: {type(exc).__name__}: {exc}") from None
    fmt = members.get("format")
    what = "BTDF" if kind == BTDF_FORMAT else "BRDF"
    if fmt is None or fmt.dtype.kind != "U" or str(fmt) != kind:
        other = ""
        if fmt is not None and fmt.dtype.kind == "U" and str(fmt) in (NPZ_FORMAT, BTDF_FORMAT):
            reader = "read_btdf_npz" if str(fmt) == BTDF_FORMAT else "read_npz"
            other = f"; it holds format={str(fmt)!r}: read it with {reader}"
        raise ValueError(
            f"{name} is not an emscatter {what} table (no format={kind!r} entry{other})"
        )
    stored = members.pop(_CHECKSUM, None)
    if stored is not None and str(stored) != _checksum(members):
        raise ValueError(
            f"{name} is damaged: its SHA-256 checksum does not match its contents (the file "
            "was altered or corrupted after it was written)"
        )
    required = {"format_version", "metadata_json", "wavelengths", "theta_i", "values"}
    required |= {"theta_o"} if kind == NPZ_FORMAT else set(_BTDF_ARRAYS) - {"mueller", "coherent"}
    missing = required - set(members)
    if missing:
        raise ValueError(
            f"{name} is damaged or not an emscatter table: it lacks the entries {sorted(missing)}"
        )
    try:
        version = int(members["format_version"])
    except (TypeError, ValueError):
        raise ValueError(f"{name} has an unreadable format_version entry") from None
    if version > FORMAT_VERSION:
        raise ValueError(
            f"{name} has table format version {version}; this emscatter reads up to "
            f"{FORMAT_VERSION} — upgrade emscatter"
        )
    try:
        metadata = json.loads(str(members["metadata_json"]))
    except ValueError as exc:
        raise ValueError(f"{name} is damaged: its metadata is not JSON ({exc})") from None
    return name, metadata, {k: members[k] for k in names if k in members}
