"""The ``emscatter`` command line: one sub-command per module in this package.

Degrees at this edge (``--theta-i-deg``), radians inside; SI units otherwise.

Every module ``emscatter/cli/<name>.py`` (other than :mod:`.args` and names starting with
``_``) that defines ``register(subparsers) -> None`` adds one command; :func:`main` finds them
with :mod:`pkgutil`, so a new command is a new file and nothing else. Errors reach the user as
one line (``emscatter <command>: error: ...``) with exit status 2 — never a traceback; an
unexpected failure is reported the same way with status 1 (``EMSCATTER_DEBUG=1`` shows the
traceback). Warnings print as ``emscatter <command>: warning: ...``.
"""

from __future__ import annotations

import argparse
import importlib
import os
import pkgutil
import re
import sys
import warnings

__all__ = ["main", "build_parser", "command_modules"]

#: Modules of this package that are not commands.
_NOT_COMMANDS = {"args", "paths"}
_NUMBER_LIKE = re.compile(r"^-(\d|\.\d|inf|nan)", re.IGNORECASE)


class Parser(argparse.ArgumentParser):
    """argparse with one-line errors that point to ``--help``; no abbreviated options (an
    abbreviation that silently picks an option is a guess, not an input)."""

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("allow_abbrev", False)
        super().__init__(*args, **kwargs)

    def error(self, message):  # noqa: D102 - argparse hook
        self.exit(2, f"{self.prog}: error: {message} (see '{self.prog} --help')\n")


def command_modules() -> tuple[list, dict[str, str]]:
    """``(modules, broken)``: the command modules of this package, sorted by name, and
    ``{name: error}`` for those that failed to import."""
    modules, broken = [], {}
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
        if info.name.startswith("_") or info.name in _NOT_COMMANDS:
            continue
        try:
            mod = importlib.import_module(f"{__name__}.{info.name}")
        except Exception as exc:  # a broken command must not take the others down
            broken[info.name] = f"{type(exc).__name__}: {exc}"
            continue
        if callable(getattr(mod, "register", None)):
            modules.append(mod)
    return modules, broken


def build_parser() -> argparse.ArgumentParser:
    """The parser with every command found by :func:`command_modules`."""
    from .._version import __version__
    from .args import HelpFormatter

    p = Parser(
        prog="emscatter",
        description="Electromagnetic scattering from rough surfaces, on the command line.",
        formatter_class=HelpFormatter,
    )
    p.add_argument("--version", action="version", version=f"emscatter {__version__}")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")
    modules, broken = command_modules()
    for mod in modules:
        mod.register(sub)
    p.set_defaults(_broken=broken)
    return p


def _join_negative_values(argv: list[str]) -> list[str]:
    """``--frequency -1e9`` → ``--frequency=-1e9``: argparse takes ``-1e9`` for an option, so a
    negative number would otherwise be "expected one argument" instead of our range message."""
    out: list[str] = []
    for tok in argv:
        prev = out[-1] if out else ""
        if _NUMBER_LIKE.match(tok) and prev.startswith("--") and "=" not in prev and prev != "--":
            out[-1] = f"{prev}={tok}"
        else:
            out.append(tok)
    return out


def _show_warning(command: str):
    def show(message, category, filename, lineno, file=None, line=None):
        print(f"emscatter {command}: warning: {message}", file=sys.stderr)

    return show


def main(argv: list[str] | None = None) -> int:
    """Run one command; returns the exit status (0 ok, 2 bad input, 1 unexpected failure)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser()
    broken = parser.get_default("_broken") or {}
    if argv and argv[0] in broken:
        print(
            f"emscatter {argv[0]}: error: this command failed to load ({broken[argv[0]]})",
            file=sys.stderr,
        )
        return 1
    try:
        args = parser.parse_args(_join_negative_values(argv))
    except SystemExit as exc:  # --help, --version, or a usage error already printed
        return int(exc.code or 0) if not isinstance(exc.code, str) else 2
    command = getattr(args, "_command_name", None) or args.command  # 'farm brdf'
    args._argv = argv  # what was typed: commands check which options were given
    with warnings.catch_warnings():
        warnings.simplefilter("always")
        warnings.showwarning = _show_warning(command)
        try:
            return int(args.func(args) or 0)
        except BrokenPipeError:  # e.g. `emscatter curves | head`: stop quietly
            sys.stdout = open(os.devnull, "w")  # noqa: SIM115 - keep Python from flushing
            return 141
        except (ValueError, TypeError, OSError, argparse.ArgumentTypeError) as exc:
            if os.environ.get("EMSCATTER_DEBUG"):
                raise
            print(f"emscatter {command}: error: {_one_line(exc)}", file=sys.stderr)
            return 2
        except KeyboardInterrupt:
            print(f"emscatter {command}: interrupted", file=sys.stderr)
            return 130
        except Exception as exc:  # never a traceback for the user
            if os.environ.get("EMSCATTER_DEBUG"):
                raise
            print(
                f"emscatter {command}: internal error: {type(exc).__name__}: {_one_line(exc)} "
                "(please report it; EMSCATTER_DEBUG=1 shows the traceback)",
                file=sys.stderr,
            )
            return 1


def _one_line(exc: BaseException) -> str:
    if isinstance(exc, OSError) and exc.filename is not None:
        what = exc.strerror or str(exc)
        return f"{exc.filename!s}: {what} (check the path and its rights)"
    return " ".join(str(exc).split()) or type(exc).__name__
