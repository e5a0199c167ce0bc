"""Progress bars for long table builds (tqdm on stderr, quiet when stderr is not a terminal).

``progress`` everywhere takes ``True`` (always show), ``False`` (never) or ``None`` (the
default: show only when ``sys.stderr`` is a terminal, so tests, pipes and CI logs stay clean).
:func:`build_progress` is the hook :func:`emscatter.brdf.build_table` opens around its fill:
the bar counts wavelengths, advanced in fractions as the chunks of each wavelength finish
(:func:`tick`), so a long single-wavelength IEM table still moves.
"""

from __future__ import annotations

import contextlib
import contextvars
import sys

__all__ = ["wanted", "bar", "build_progress", "tick"]

_CURRENT: contextvars.ContextVar = contextvars.ContextVar("emscatter_brdf_bar", default=None)


def wanted(progress) -> bool:
    """Whether to draw: ``progress`` True/False, or None → stderr is a terminal."""
    if progress is None:
        stream = sys.stderr
        return bool(stream is not None and hasattr(stream, "isatty") and stream.isatty())
    if not isinstance(progress, bool):
        raise ValueError(f"progress must be True, False or None (auto), got {progress!r}")
    return progress


def bar(total: float, desc: str, progress=None, unit: str = "it"):
    """A tqdm bar on stderr (``disable=True`` when not :func:`wanted`)."""
    from tqdm.auto import tqdm

    return tqdm(
        total=total,
        desc=desc,
        unit=unit,
        disable=not wanted(progress),
        leave=False,
        delay=0.5 if progress is None else 0.0,
    )


@contextlib.contextmanager
def build_progress(n_wavelengths: int, progress=None):
    """The bar of one :func:`~emscatter.brdf.build_table` call (total: the wavelengths);
    nested builds (a farm's tables) draw no bar of their own when ``progress`` is None."""
    if _CURRENT.get() is not None or not wanted(progress):
        token = _CURRENT.set(_NULL)
        try:
            yield _NULL
        finally:
            _CURRENT.reset(token)
        return
    with bar(n_wavelengths, "BRDF table", progress, unit="λ") as b:
        token = _CURRENT.set(b)
        try:
            yield b
        finally:
            _CURRENT.reset(token)


def tick(fraction: float) -> None:
    """Advance the current build's bar by ``fraction`` of a wavelength (no bar: nothing)."""
    b = _CURRENT.get()
    if b is not None and b is not _NULL:
        b.update(fraction)


class _Null:
    def update(self, n=1):
        return None


_NULL = _Null()
