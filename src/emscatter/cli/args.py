"""Argument helpers shared by every ``emscatter`` command.

Each helper is an argparse ``type=`` callable (or adds a group of options) that turns text into
a checked value or raises :class:`argparse.ArgumentTypeError` with a one-line message naming
what was given and what is allowed. Degrees at this edge, radians inside; SI units otherwise.

* :class:`Angles` — ``'a'`` | ``'a,b,c'`` | ``'start:stop:count'`` in degrees, within bounds;
* :func:`add_frequency_args` / :func:`frequency_kwargs` — ``--frequency`` [Hz] or
  ``--wavelength`` [m], with the "did you mean GHz?" hint for implausible values;
* :func:`parse_eps` — a complex permittivity (``17+2j``, ``17+2i``) or ``pec``;
* :class:`Number` / :class:`Integer` — a number within a range (``Number(low=0, unit="m")``);
* :class:`OutputPath` / :class:`OutputFolder` — from :mod:`.paths` (every output path is
  checked there, before anything is computed);
* :func:`add_roughness_args` / :func:`roughness_from_args` — ``--kind --sigma --length ...``;
* :func:`add_command` — a sub-command parser with the shared help formatter.
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from ..conventions import fmt  # a number as a person writes it (0.5, 1e+09, (17+2j))
from .paths import OutputFolder, OutputPath, check_output_path  # noqa: F401 - re-exported

__all__ = [
    "HelpFormatter",
    "add_command",
    "add_roughness_args",
    "roughness_from_args",
    "Angles",
    "Number",
    "Integer",
    "parse_eps",
    "MaterialName",
    "add_frequency_args",
    "frequency_kwargs",
    "OutputPath",
    "OutputFolder",
    "check_output_path",
    "given_options",
    "reject_unless",
    "FREQUENCY_RANGE",
    "WAVELENGTH_RANGE",
]

#: Plausible frequencies [Hz]: 1 MHz (radio) to 3e16 Hz (10 nm, far UV).
FREQUENCY_RANGE = (1e6, 3e16)
#: Plausible wavelengths [m]: 10 nm to 1 km.
WAVELENGTH_RANGE = (1e-8, 1e3)


class HelpFormatter(argparse.HelpFormatter):
    """Appends ``(default: X)`` to every option that has a meaningful default."""

    def _get_help_string(self, action):
        text = action.help or ""
        default = action.default
        if (
            "%(default)" not in text
            and default not in (None, False, argparse.SUPPRESS)
            and action.option_strings
            and not isinstance(action, argparse._VersionAction | argparse._HelpAction)
        ):
            text += " (default: %(default)s)"
        return text


def add_command(subparsers, name: str, *, help: str, description: str | None = None):
    """Add the sub-command ``name`` with the shared formatter; returns its parser."""
    return subparsers.add_parser(
        name, help=help, description=description or help, formatter_class=HelpFormatter
    )


def _float(text: str) -> float:
    try:
        v = float(text)
    except (TypeError, ValueError):
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(v):
        raise argparse.ArgumentTypeError(f"must be a finite number, got {text!r}")
    return v


def _interval(low, high, low_open, high_open, unit="") -> str:
    u = f" {unit}" if unit else ""
    if high is None:
        return f"{'>' if low_open else '≥'} {fmt(low)}{u}"
    if low is None:
        return f"{'<' if high_open else '≤'} {fmt(high)}{u}"
    lb, hb = ("(" if low_open else "["), (")" if high_open else "]")
    return f"in {lb}{fmt(low)}, {fmt(high)}{hb}{u}"


class Number:
    """``type=`` for a real number in ``(low, high)`` (bounds open unless ``*_open=False``).

    ``Number(low=0, unit="m")`` rejects ``0`` and ``-1`` with "must be > 0 m, got -1"
    (argparse prefixes the option: "argument --sigma: ...").
    """

    def __init__(
        self,
        *,
        low: float | None = None,
        high: float | None = None,
        low_open: bool = True,
        high_open: bool = True,
        unit: str = "",
    ):
        self.low, self.high, self.unit = low, high, unit
        self.low_open, self.high_open = low_open, high_open

    def __call__(self, text: str) -> float:
        v = _float(text)
        lo, hi = self.low, self.high
        bad_lo = lo is not None and (v <= lo if self.low_open else v < lo)
        bad_hi = hi is not None and (v >= hi if self.high_open else v > hi)
        if bad_lo or bad_hi:
            rng = _interval(lo, hi, self.low_open, self.high_open, self.unit)
            raise argparse.ArgumentTypeError(f"must be {rng}, got {text}")
        return v


class Integer(Number):
    """``type=`` for an integer in ``[low, high]`` (closed bounds)."""

    def __init__(self, *, low: int | None = None, high: int | None = None):
        super().__init__(low=low, high=high, low_open=False, high_open=False)

    def __call__(self, text: str) -> int:
        try:
            v = int(text)
        except (TypeError, ValueError):
            raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
        super().__call__(str(v))
        return v


class Angles:
    """``type=`` for angles in degrees: ``'45'``, ``'10,20,30'`` or ``'start:stop:count'``.

    Returns a 1-D float array in degrees (callers convert with ``np.radians``), every value in
    ``[low, high]``.
    """

    def __init__(self, *, low: float = 0.0, high: float = 90.0):
        self.low, self.high = low, high

    def __call__(self, text: str) -> np.ndarray:
        form = "'a', 'a,b,c' or 'start:stop:count' in degrees"
        t = str(text).strip()
        try:
            if ":" in t:
                parts = t.split(":")
                if len(parts) != 3:
                    raise ValueError
                a, b, n = float(parts[0]), float(parts[1]), int(parts[2])
                if n < 1:
                    raise argparse.ArgumentTypeError(
                        f"range {t!r}: the count must be ≥ 1, got {parts[2]}"
                    )
                vals = np.linspace(a, b, n)
            else:
                vals = np.array([float(v) for v in t.split(",")])
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be {form}, got {text!r}") from None
        if vals.size == 0 or not np.all(np.isfinite(vals)):
            raise argparse.ArgumentTypeError(f"must be finite angles in degrees, got {text!r}")
        bad = vals[(vals < self.low) | (vals > self.high)]
        if bad.size:
            raise argparse.ArgumentTypeError(
                f"must be in [{fmt(self.low)}, {fmt(self.high)}] degrees, got {fmt(bad[0])}"
            )
        return vals


class MaterialName(str):
    """A material name from ``--eps`` (``Au``, ``concrete``, ``itu:glass``), checked to exist;
    the API takes it as ``eps`` and evaluates it at the frequency of the call."""


def parse_eps(text: str):
    """A complex relative permittivity (``exp(-iωt)``, ``Im ε ≥ 0``), ``"pec"``, or a material
    name (:class:`MaterialName`: a Mitsuba metal such as ``Au``, an ITU-R P.2040 material such
    as ``concrete``).

    Accepts ``17``, ``17+2j``, ``17+2i``, ``(17+2j)``, ``-5+1j``, ``pec`` (any case), ``Au``.
    """
    t = str(text).strip().lower().replace(" ", "")
    if t == "pec":
        return "pec"
    try:
        try:  # "inf", "nan" first: "i" → "j" would turn them into names
            value = complex(t)
        except ValueError:
            value = complex(t.replace("i", "j"))
    except ValueError:
        if t[:1].isalpha():
            from ..materials import as_material

            try:
                as_material(str(text).strip())
            except (ValueError, TypeError) as exc:
                raise argparse.ArgumentTypeError(
                    f"expected a complex permittivity like 17+2j (exp(-iωt): Im ≥ 0), 'pec' or a "
                    f"material name; {exc}"
                ) from None
            return MaterialName(str(text).strip())
        raise argparse.ArgumentTypeError(
            f"expected a complex permittivity like 17+2j (exp(-iωt): Im ≥ 0) or 'pec', got {text!r}"
        ) from None
    if not (math.isfinite(value.real) and math.isfinite(value.imag)):
        raise argparse.ArgumentTypeError(f"permittivity must be finite, got {text!r}")
    if value == 0:
        raise argparse.ArgumentTypeError("permittivity must be nonzero, got 0")
    if value.imag < 0:
        raise argparse.ArgumentTypeError(
            f"permittivity {text!r} has Im < 0; emscatter uses exp(-iωt), where a lossy medium "
            f"has Im ≥ 0: give {fmt(value.real)}+{fmt(-value.imag)}j"
        )
    return value


def _hint_frequency(v: float) -> str:
    if 0 < v < FREQUENCY_RANGE[0]:
        return f"; did you mean {fmt(v)} GHz = {fmt(v * 1e9)} Hz?"
    return ""


def _hint_wavelength(v: float) -> str:
    if v > WAVELENGTH_RANGE[1]:
        return (
            f"; did you mean GHz? a frequency goes in --frequency [Hz], e.g. --frequency {fmt(v)}"
        )
    return ""


class _Plausible:
    """``type=`` for a value in a closed plausible range, with a hint for likely unit slips."""

    def __init__(self, bounds: tuple[float, float], unit: str, hint):
        self.bounds, self.unit, self.hint = bounds, unit, hint

    def __call__(self, text: str) -> float:
        v = _float(text)
        lo, hi = self.bounds
        if not lo <= v <= hi:
            raise argparse.ArgumentTypeError(
                f"must be in [{fmt(lo)}, {fmt(hi)}] {self.unit}, got {text}{self.hint(v)}"
            )
        return v


#: ``type=`` for ``--frequency`` [Hz] within :data:`FREQUENCY_RANGE`.
frequency_hz = _Plausible(FREQUENCY_RANGE, "Hz", _hint_frequency)
#: ``type=`` for ``--wavelength`` [m] within :data:`WAVELENGTH_RANGE`.
wavelength_m = _Plausible(WAVELENGTH_RANGE, "m", _hint_wavelength)


def add_frequency_args(parser, *, default_wavelength: float = 1.0) -> None:
    """``--frequency`` [Hz] | ``--wavelength`` [m], mutually exclusive; read them back with
    :func:`frequency_kwargs`."""
    g = parser.add_mutually_exclusive_group()
    g.add_argument("--frequency", type=frequency_hz, metavar="HZ", help="frequency [Hz]")
    g.add_argument(
        "--wavelength",
        type=wavelength_m,
        metavar="M",
        help=f"wavelength [m] (default {fmt(default_wavelength)} when neither is given)",
    )
    parser.set_defaults(_default_wavelength=default_wavelength)


def frequency_kwargs(args) -> dict:
    """``{"frequency": f}`` or ``{"wavelength": λ}`` for the API, from the parsed options."""
    if getattr(args, "frequency", None) is not None:
        return {"frequency": args.frequency}
    lam = getattr(args, "wavelength", None)
    return {"wavelength": lam if lam is not None else args._default_wavelength}


def add_roughness_args(p, *, sigma: float = 0.03, length: float = 1.0) -> None:
    """``--kind --sigma --length --length-y --hurst --profile``."""
    p.add_argument(
        "--kind",
        default="gaussian",
        choices=["gaussian", "exponential", "power-law"],
        help="correlation function",
    )
    p.add_argument(
        "--sigma", type=Number(low=0, unit="m"), default=sigma, metavar="M", help="rms height [m]"
    )
    p.add_argument(
        "--length",
        type=Number(low=0, unit="m"),
        default=length,
        metavar="M",
        help="correlation length [m]",
    )
    p.add_argument(
        "--length-y",
        type=Number(low=0, unit="m"),
        default=None,
        metavar="M",
        help="correlation length along y [m] (default: --length)",
    )
    p.add_argument(
        "--hurst",
        type=Number(low=0, high=1),
        default=0.5,
        help="Hurst exponent (power-law kind only)",
    )
    p.add_argument(
        "--profile",
        action="store_true",
        help="1-D profile (2-D scattering problem) instead of a 2-D surface",
    )


def roughness_from_args(a):
    """The :class:`emscatter.spectra.Roughness` the options describe."""
    from ..spectra import roughness

    reject_unless(a, a.kind == "power-law", ("--hurst",), "to --kind power-law only")
    reject_unless(a, not a.profile, ("--length-y",), "to 2-D surfaces only (not with --profile)")
    params = {"sigma": a.sigma, "length": a.length, "dimension": 1 if a.profile else 2}
    if a.length_y is not None:
        params["length_y"] = a.length_y
    if a.kind == "power-law":
        params["hurst"] = a.hurst
    return roughness(a.kind, **params)


def given_options(args) -> set[str]:
    """The options typed on the command line (``{"--sigma", "--png", ...}``), from the argv
    that :func:`emscatter.cli.main` keeps in ``args._argv``."""
    out = set()
    for tok in getattr(args, "_argv", []) or []:
        if tok.startswith("--") and len(tok) > 2:
            out.add(tok.split("=", 1)[0])
    return out


def reject_unless(args, condition: bool, options: tuple[str, ...], why: str) -> None:
    """ValueError when any of ``options`` was given but does not apply (``condition`` False):
    an option is honoured or rejected, never ignored."""
    used = sorted(given_options(args) & set(options))
    if used and not condition:
        shown = []
        for opt in used:
            value = getattr(args, opt.lstrip("-").replace("-", "_"), None)
            text = "" if value is None or isinstance(value, bool) else f" {_shown(value)}"
            shown.append(f"{opt}{text}")
        verb = "applies" if len(used) == 1 else "apply"
        raise ValueError(
            f"{', '.join(used)} {verb} {why} (got {', '.join(shown)}); drop it or change the "
            "other options"
        )


def _shown(value) -> str:
    if isinstance(value, np.ndarray):
        return ",".join(fmt(float(v)) for v in value.ravel()[:8])
    if isinstance(value, float):
        return fmt(value)
    return str(value)
