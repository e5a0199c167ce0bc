"""Output paths of every ``emscatter`` command, checked before anything is computed.

One place for the rules (the command modules and :mod:`emscatter.cli.radio` call these):

* :class:`OutputPath` / :class:`OutputFolder` — argparse ``type=`` callables: a file the
  command writes (not a folder, its nearest existing folder takes new files — tried with a
  real temporary file, since ``os.access`` says yes to root and to the kernel's virtual file
  systems (procfs) — and, with ``suffixes``, a known extension) or a folder it writes into;
* :func:`check_format` — the extension agrees with ``--format`` (``x.npz --format rgl`` is an
  error, never an RGL tensor in a ``.npz``);
* :func:`check_distinct` — two options never name the same file.

The checks themselves are :func:`emscatter.io.output_problem`, which the API's writers use too,
so a path the command line accepts is one the writers can write. Errors are
:class:`argparse.ArgumentTypeError` (parse time) or :class:`ValueError` (after parsing);
:func:`emscatter.cli.main` prints either as one line with exit status 2.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from ..io import output_problem

__all__ = ["OutputPath", "OutputFolder", "check_output_path", "check_format", "check_distinct"]


def check_output_path(path, suffixes: tuple[str, ...] = (), *, folder: bool = False):
    """``None`` when ``path`` can be written, else one line saying why and what to do
    (:func:`emscatter.io.output_problem`)."""
    return output_problem(Path(path), suffixes, folder=folder)


class OutputPath:
    """``type=`` for a file the command writes, checked at parse time (before any work):
    not a folder, its folder creatable and taking new files, and (``suffixes``) a known
    extension. Returns a :class:`pathlib.Path`; missing folders are created when the file is
    written."""

    def __init__(self, *, suffixes: tuple[str, ...] = ()):
        self.suffixes = suffixes

    def __call__(self, text: str) -> Path:
        path = Path(text).expanduser()
        problem = check_output_path(path, self.suffixes)
        if problem:
            raise argparse.ArgumentTypeError(f"cannot write {text!r}: {problem}")
        return path


class OutputFolder(OutputPath):
    """``type=`` for a folder the command writes into (created when missing)."""

    def __call__(self, text: str) -> Path:
        path = Path(text).expanduser()
        problem = check_output_path(path, folder=True)
        if problem:
            raise argparse.ArgumentTypeError(f"cannot write into {text!r}: {problem}")
        return path


def check_format(path: Path, fmt_name: str | None, formats: dict[str, str], option: str) -> str:
    """The format to write ``path`` in: the one its extension names (``formats``: suffix →
    format), which ``--format`` (``fmt_name``), when given, must agree with. ValueError naming
    the path, the format and the extension that would fit."""
    by_suffix = formats.get(Path(path).suffix.lower())
    if fmt_name is None:
        if by_suffix is None:
            raise ValueError(
                f"{option} {str(path)!r}: unknown extension {Path(path).suffix or '(none)'!r}; "
                f"use one of {', '.join(formats)}"
            )
        return by_suffix
    if fmt_name != by_suffix:
        fits = [s for s, f in formats.items() if f == fmt_name]
        raise ValueError(
            f"--format {fmt_name} does not match {option} {str(path)!r} (a "
            f"{Path(path).suffix or 'no-extension'} file is {by_suffix or 'no known format'}); "
            f"name the file with {' or '.join(fits)} or drop --format"
        )
    return fmt_name


def check_distinct(paths: dict[str, Path | None]) -> None:
    """ValueError when two options (``{"--csv": path, ...}``) name the same file."""
    seen: dict[Path, str] = {}
    for option, path in paths.items():
        if path is None:
            continue
        key = Path(path).expanduser().resolve()
        if key in seen:
            raise ValueError(
                f"{seen[key]} and {option} both name {str(path)!r}; give each output its own file"
            )
        seen[key] = option
