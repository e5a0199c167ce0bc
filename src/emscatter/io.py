"""Atomic file output: a failed run leaves nothing half-written.

Every writer goes to a temporary file in the destination folder and is moved into place with
:func:`os.replace` (atomic on POSIX) only once it is complete. A destination that cannot be
written (a folder, a path under a file, a read-only or virtual folder such as procfs) is an
:class:`OutputPathError` naming the destination — never the temporary file — and what to do;
:func:`output_problem` says the same *before* any work, which is how the command line checks
every output path up front.
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
    "OutputPathError",
    "output_problem",
    "check_output",
    "atomic_path",
    "write_json",
    "write_csv",
    "read_csv",
    "jsonable",
    "save_figure",
]


class OutputPathError(OSError, ValueError):
    """An output path that cannot be written; the message names the path and the fix.

    Both an :class:`OSError` (what a failed write is) and a :class:`ValueError` (a bad
    argument), so either ``except`` catches it."""

    def __init__(self, path, problem: str | None = None):
        # one argument: the whole message (how pickle rebuilds the error in another process)
        message = str(path) if problem is None else f"cannot write {str(path)!r}: {problem}"
        super().__init__(message)
        self.path = None if problem is None else Path(path)
        self.problem = problem

    def __str__(self) -> str:  # OSError's two-argument form would print a tuple
        return self.args[0]


def _probe(folder: Path) -> str | None:
    """``None`` when a file can be created in the existing ``folder``, else why not.

    Creates and removes one empty temporary file: ``os.access`` says yes to root everywhere
    and to read-only or virtual file systems (procfs), so only a real attempt is sure."""
    try:
        fd, tmp = tempfile.mkstemp(prefix=".emscatter-probe-", dir=folder)
    except OSError as exc:
        why = exc.strerror or type(exc).__name__
        return f"folder {str(folder)!r} does not take new files ({why}); choose another folder"
    os.close(fd)
    Path(tmp).unlink(missing_ok=True)
    return None


def output_problem(
    path, suffixes: Sequence[str] = (), *, folder: bool = False, probe: bool = True
) -> str | None:
    """``None`` when ``path`` can be written, else one line saying why and what to do.

    ``path`` is a file to write (``folder=False``: not an existing folder; its extension one of
    ``suffixes`` when given, compared case-insensitively) or a folder to write into
    (``folder=True``: not an existing file). Missing parent folders are fine when the nearest
    existing one takes new files (they are created at write time); ``probe=False`` skips the
    write test (then only ``os.access`` is asked). Nothing is left behind."""
    path = Path(path).expanduser()
    if not str(path) or str(path) == ".":
        return "the path is empty; give a file name" if not folder else None
    if not folder and path.is_dir():
        return "it is a folder; give a file name inside it"
    if folder and path.exists() and not path.is_dir():
        return "it is an existing file, not a folder; give a folder path"
    if suffixes and not folder and path.suffix.lower() not in tuple(s.lower() for s in suffixes):
        return f"unknown extension {path.suffix or '(none)'!r}; use one of {', '.join(suffixes)}"
    existing = path if folder else path.parent
    while not existing.is_dir():
        if existing.is_symlink() and not existing.exists():
            return f"{str(existing)!r} is a broken link; remove it or choose another folder"
        if existing.exists():
            return f"{str(existing)!r} is a file, not a folder; choose another folder"
        existing = existing.parent
    if not os.access(existing, os.W_OK | os.X_OK):
        return f"folder {str(existing)!r} is not writable; choose another folder or fix its rights"
    return _probe(existing) if probe else None


def check_output(path, suffixes: Sequence[str] = (), *, folder: bool = False) -> Path:
    """``path`` as a :class:`~pathlib.Path` when it can be written (:func:`output_problem`),
    else :class:`OutputPathError`."""
    problem = output_problem(path, suffixes, folder=folder)
    if problem:
        raise OutputPathError(path, problem)
    return Path(path).expanduser()


@contextmanager
def atomic_path(path: str | os.PathLike, suffix: str = ""):
    """Yield a temporary path beside ``path``; on success move it onto ``path``.

    Missing parent folders are created. A destination that cannot be written raises
    :class:`OutputPathError` naming ``path`` (not the temporary file)."""
    path = Path(path)
    if path.is_dir():
        raise OutputPathError(path, "it is a folder; give a file name inside it")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(
            prefix=f".{path.name}.", suffix=suffix or path.suffix, dir=path.parent
        )
    except OSError as exc:
        raise OutputPathError(path, output_problem(path) or _os_reason(exc)) from None
    os.close(fd)
    try:
        yield Path(tmp)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes 0600; give the file normal permissions
        os.replace(tmp, path)
    except OSError as exc:
        Path(tmp).unlink(missing_ok=True)
        if isinstance(exc, OutputPathError) or str(exc.filename or "") != str(tmp):
            raise
        raise OutputPathError(path, _os_reason(exc)) from None
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _os_reason(exc: OSError) -> str:
    why = exc.strerror or type(exc).__name__
    return f"{why}; choose another path or fix its rights"


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
