"""Atomic file output: a failed run leaves nothing half-written.

Every writer goes to a temporary file in the destination folder and is moved into place with
:func:`os.replace` (atomic on POSIX) only once it is complete.
"""

from __future__ import annotations

import csv
import json
import os
import tempfile
from collections.abc import Callable, Sequence
from contextlib import contextmanager
from pathlib import Path

import numpy as np

__all__ = [
    "atomic_path",
    "write_json",
    "write_csv",
    "read_csv",
    "jsonable",
    "save_figure",
]


@contextmanager
def atomic_path(path: str | os.PathLike, suffix: str = ""):
    """Yield a temporary path beside ``path``; on success move it onto ``path``."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(
        prefix=f".{path.name}.", suffix=suffix or path.suffix, dir=path.parent
    )
    os.close(fd)
    try:
        yield Path(tmp)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes 0600; give the file normal permissions
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _jsonable(obj):
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, complex):
        return {"re": obj.real, "im": obj.imag}
    if isinstance(obj, Path):
        return str(obj)
    raise TypeError(f"not JSON serializable: {type(obj).__name__}")


def write_json(path, data) -> Path:
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(data, indent=2, default=_jsonable, allow_nan=False) + "\n")
    return Path(path)


def write_csv(
    path,
    header: Sequence[str],
    columns: Sequence[np.ndarray],
    *,
    metadata: dict | None = None,
    schema: str | None = None,
) -> Path:
    """Columns of equal length under a header row.

    With ``schema`` / ``metadata``, two comment lines come first — ``# schema: <schema>`` and
    ``# metadata: <one-line JSON>`` (every input needed to reproduce the file) — which
    :func:`read_csv`, ``numpy.loadtxt`` and ``pandas.read_csv(comment="#")`` skip or read."""
    cols = [np.asarray(c).ravel() for c in columns]
    if len({c.size for c in cols}) > 1:
        raise ValueError(f"CSV columns differ in length: {[c.size for c in cols]}")
    with atomic_path(path) as tmp, open(tmp, "w", newline="") as fh:
        if schema is not None:
            fh.write(f"# schema: {schema}\n")
        if metadata is not None:
            fh.write(f"# metadata: {json.dumps(jsonable(metadata), allow_nan=False)}\n")
        w = csv.writer(fh)
        w.writerow(header)
        for row in zip(*cols, strict=True):
            w.writerow([f"{v:.10g}" if isinstance(v, float | np.floating) else v for v in row])
    return Path(path)


def _number_or_text(values: list[str]):
    try:
        return np.array([float(v) for v in values])
    except ValueError:
        return np.array(values, dtype=object)


def read_csv(path) -> tuple[list[str], dict[str, np.ndarray], dict]:
    """``(header, columns, metadata)`` of a file from :func:`write_csv`: numeric columns as
    float arrays (``nan`` where written so), ``metadata`` with ``"schema"`` when present."""
    meta: dict = {}
    with open(path, newline="") as fh:
        lines = fh.read().splitlines()
    body = []
    for line in lines:
        if line.startswith("# schema:"):
            meta["schema"] = line.split(":", 1)[1].strip()
        elif line.startswith("# metadata:"):
            meta.update(json.loads(line.split(":", 1)[1]))
        elif not line.startswith("#"):
            body.append(line)
    rows = list(csv.reader(body))
    if not rows:
        raise ValueError(f"{path}: no header row (not a CSV written by emscatter?)")
    header, data = rows[0], rows[1:]
    cols = {h: _number_or_text([r[i] for r in data]) for i, h in enumerate(header)}
    return header, cols, meta


def jsonable(obj):
    """``obj`` with numpy arrays/scalars, complex numbers (``{"re", "im"}``) and paths turned
    into JSON types, and non-finite floats into ``None`` (JSON has no NaN)."""
    if isinstance(obj, dict):
        return {str(k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return jsonable(obj.tolist())
    if isinstance(obj, np.generic):
        return jsonable(obj.item())
    if isinstance(obj, complex):
        return {"re": jsonable(obj.real), "im": jsonable(obj.imag)}
    if isinstance(obj, float) and not np.isfinite(obj):
        return None
    if isinstance(obj, Path):
        return str(obj)
    return obj


def save_figure(fig, path, *, dpi: int = 130, close: Callable | None = None) -> Path:
    """Save a matplotlib figure atomically (PNG by default) and close it."""
    import matplotlib.pyplot as plt

    with atomic_path(path) as tmp:
        fig.savefig(
            tmp, dpi=dpi, format=Path(path).suffix.lstrip(".") or "png", bbox_inches="tight"
        )
    plt.close(fig)
    return Path(path)
