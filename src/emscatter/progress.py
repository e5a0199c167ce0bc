"""Progress bars for long calls and commands (tqdm on stderr), one policy for the package.

Every public call that can run longer than a few seconds takes ``progress``:

* ``None`` (the default, "auto"): a bar only when ``sys.stderr`` is a terminal **and** the
  work runs past :data:`AUTO_SECONDS` — tqdm's ``delay``, so a short call draws nothing and a
  call whose cost is estimated up front below that draws no bar at all; pipes, tests and CI
  logs stay clean;
* ``True``: always draw (from the start); ``False``: never.

A command's ``--quiet`` (and ``EMSCATTER_PROGRESS=0`` in the environment, which
``emscatter bench --quiet`` sets for its benchmark processes) turns the auto default off:
:func:`silenced` is the block form the CLI wraps a command in. An explicit ``True`` still
draws.

A bar counts what the caller knows up front (realizations, frequencies, table stages, σ⁰
evaluations), so tqdm's rate gives the remaining-time estimate; it is advanced once per chunk
of work, never per angle or grid point. :func:`task` opens the bar of one call; work nested
inside it (an emissivity inside a sweep, a table inside a farm) draws no bar of its own while
``progress`` is None, and :func:`advance` / :func:`expect` move the innermost open task.
"""

from __future__ import annotations

import contextlib
import contextvars
import os
import sys

__all__ = ["AUTO_SECONDS", "wanted", "bar", "task", "advance", "expect", "silenced"]

#: Auto mode draws a bar only for work that runs (or is estimated to run) past this [s].
AUTO_SECONDS = 2.0

_CURRENT: contextvars.ContextVar = contextvars.ContextVar("emscatter_bar", default=None)
_SILENT: contextvars.ContextVar = contextvars.ContextVar("emscatter_silent", default=False)
_OFF = ("0", "off", "false", "no", "quiet")
_AUTO = ("", "1", "on", "true", "yes", "auto")


def _check(progress) -> None:
    if progress is not None and not isinstance(progress, bool):
        raise ValueError(f"progress must be True, False or None (auto), got {progress!r}")


def _env_silent() -> bool:
    value = os.environ.get("EMSCATTER_PROGRESS", "").strip().lower()
    if value in _OFF:
        return True
    if value not in _AUTO:
        raise ValueError(
            f"EMSCATTER_PROGRESS must be one of {', '.join(repr(v) for v in _OFF + _AUTO[1:])}, "
            f"got {os.environ['EMSCATTER_PROGRESS']!r}"
        )
    return False


def wanted(progress, estimate_s: float | None = None) -> bool:
    """Whether to draw: ``progress`` True/False, or None → stderr is a terminal, not
    silenced (:func:`silenced`, ``EMSCATTER_PROGRESS=0``) and ``estimate_s`` [s] (when the
    cost is known up front) above :data:`AUTO_SECONDS`."""
    _check(progress)
    if progress is not None:
        return progress
    if _SILENT.get() or _env_silent():
        return False
    if estimate_s is not None and estimate_s <= AUTO_SECONDS:
        return False
    stream = sys.stderr
    return bool(stream is not None and hasattr(stream, "isatty") and stream.isatty())


def bar(total, desc: str, progress=None, unit: str = "it", estimate_s: float | None = None):
    """A tqdm bar on stderr (``disable=True`` when not :func:`wanted`). In auto mode it
    appears only after :data:`AUTO_SECONDS` (tqdm ``delay``) unless ``estimate_s`` says the
    work is long, in which case it is drawn at once."""
    from tqdm.auto import tqdm

    long = estimate_s is not None and estimate_s > AUTO_SECONDS
    return tqdm(
        total=total,
        desc=desc,
        unit=unit,
        disable=not wanted(progress, estimate_s),
        leave=False,
        delay=AUTO_SECONDS if progress is None and not long else 0.0,
        file=sys.stderr,
    )


@contextlib.contextmanager
def task(desc: str, total=None, progress=None, unit: str = "it", estimate_s=None):
    """The bar of one call, yielded (a no-op object when not drawn). Inside an open task a
    nested one with ``progress=None`` draws nothing and its :func:`advance` calls are
    dropped (the outer task counts its own units)."""
    _check(progress)
    nested = _CURRENT.get() is not None and progress is None
    if nested or not wanted(progress, estimate_s):
        token = _CURRENT.set(_NULL)
        try:
            yield _NULL
        finally:
            _CURRENT.reset(token)
        return
    with bar(total, desc, progress, unit=unit, estimate_s=estimate_s) as b:
        token = _CURRENT.set(b)
        try:
            yield b
        finally:
            _CURRENT.reset(token)


def advance(n: float = 1) -> None:
    """Advance the innermost open task by ``n`` units (no task: nothing)."""
    b = _CURRENT.get()
    if b is not None and b is not _NULL:
        b.update(n)


def expect(n: float) -> None:
    """Add ``n`` units of work to the innermost open task's total (work found as it goes,
    e.g. a quadrature refinement)."""
    b = _CURRENT.get()
    if b is not None and b is not _NULL:
        b.total = (b.total or 0) + n
        b.refresh()


@contextlib.contextmanager
def silenced(quiet: bool = True):
    """Within the block, ``progress=None`` draws no bar (a command's ``--quiet``)."""
    token = _SILENT.set(bool(quiet) or _SILENT.get())
    try:
        yield
    finally:
        _SILENT.reset(token)


class _Null:
    total = None

    def update(self, n=1):
        return None

    def refresh(self):
        return None

    def set_postfix_str(self, s="", refresh=True):
        return None


_NULL = _Null()
