"""Progress bars for long table builds (tqdm on stderr, quiet when stderr is not a terminal).

``progress`` everywhere takes ``True`` (always show), ``False`` (never) or ``None`` (the
default: show only when ``sys.stderr`` is a terminal, so tests, pipes and CI logs stay clean).
:func:`build_progress` is the hook :func:`emscatter.brdf.build_table` opens around its fill:
the bar counts wavelengths, advanced in fractions as the chunks of each wavelength finish
(:func:`tick`), so a long single-wavelength IEM table still moves. :func:`wanted` and
:func:`bar` are the package-wide ones of :mod:`emscatter.progress`.
"""

from __future__ import annotations

import contextlib
import contextvars

from ..progress import bar, wanted

__all__ = ["wanted", "bar", "build_progress", "tick"]

_CURRENT: contextvars.ContextVar = contextvars.ContextVar("emscatter_brdf_bar", default=None)


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
