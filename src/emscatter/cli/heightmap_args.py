"""``--height-map FILE --detrend --unit --holes --segments --tail --slope-tail``: a measured
surface in place of ``--kind --sigma --length …`` for ``emscatter brdf``, ``curves`` and
``radio``.

The file is read through SurfaceTopography's readers (:func:`emscatter.surfaces.read_height_map`:
units from the file, ``--unit`` only when it stores none) and turned into a
:class:`~emscatter.surfaces.measured.MeasuredRoughness` (Welch spectrum, n-fold spectra, slope
histogram) before any solver runs. NaN holes (unmeasured points) are an error naming the file
and the count unless ``--holes mask`` (the spectrum and slopes from the valid samples only;
the policy and the count recorded in the output's metadata). ``--slope-tail`` is the measured
slope density beyond its well-sampled slopes (``measured_roughness(slope_tail=…)``,
:mod:`emscatter.surfaces.measured.slope_tail`: ``gaussian`` by default, ``exponential`` or
``none``), recorded as ``slope_tail`` beside the other choices; it matters for GO at grazing
angles, where the steep, rarely sampled facets carry the lobe. The parametric options are
mutually exclusive with it: typing ``--sigma`` (or ``--kind``, ``--length``, ``--length-y``,
``--hurst``, ``--profile``) together with ``--height-map`` is an error naming both, and the
height-map options without ``--height-map`` are errors too — honoured or rejected, never
ignored.
"""

from __future__ import annotations

from .args import Integer, given_options, reject_unless

__all__ = [
    "add_height_map_args",
    "height_map_roughness",
    "height_map_inputs",
    "height_map_argv",
    "map_error",
    "PARAMETRIC",
    "HEIGHT_MAP_OPTIONS",
]

#: The parametric roughness options a height map replaces.
PARAMETRIC = ("--kind", "--sigma", "--length", "--length-y", "--hurst", "--profile")
#: The options that only apply with ``--height-map``.
HEIGHT_MAP_OPTIONS = ("--detrend", "--unit", "--holes", "--segments", "--tail", "--slope-tail")

_DETRENDS = ("none", "mean", "plane", "quadratic")
HOLES_API = "holes='mask'"  # the API's advice in HeightMapError, the option's name on the CLI
SLOPE_TAIL_API = "slope_tail='none'"  # likewise: ``--slope-tail none``


def add_height_map_args(p) -> None:
    """Add the height-map options to a command's parser (module docstring)."""
    from ..surfaces.heightmap import UNITS
    from ..surfaces.measured import TAILS
    from ..surfaces.measured.slope_tail import SLOPE_TAILS

    g = p.add_argument_group("measured surface (instead of --kind/--sigma/--length)")
    g.add_argument(
        "--height-map",
        default=None,
        metavar="FILE",
        help="height-map file (.x3p, .nc, .sur, .opd, .datx, ...; needs SurfaceTopography): "
        "its measured spectrum and slopes replace --kind/--sigma/--length",
    )
    g.add_argument(
        "--detrend",
        default="plane",
        choices=_DETRENDS,
        help="what to remove from the map before measuring it (with --height-map)",
    )
    g.add_argument(
        "--unit",
        default=None,
        choices=sorted(UNITS),
        help="height unit when the file stores none (with --height-map; the file's own wins)",
    )
    g.add_argument(
        "--holes",
        default="reject",
        choices=["reject", "mask"],
        help="NaN holes (unmeasured points) in the map: reject (an error naming the count) or "
        "mask (left out of the spectrum and slopes; recorded) (with --height-map)",
    )
    g.add_argument(
        "--segments",
        type=Integer(low=1, high=64),
        default=8,
        help="Welch segments per axis of the spectrum estimate (with --height-map)",
    )
    g.add_argument(
        "--tail",
        default="none",
        choices=list(TAILS),
        help="spectrum beyond the map's band π/Δ: none (zero) or a fitted power law",
    )
    g.add_argument(
        "--slope-tail",
        default="gaussian",
        choices=list(SLOPE_TAILS),
        help="measured slope density beyond its well-sampled slopes (GO, steep facets at "
        "grazing angles): gaussian (default), exponential (both fitted to the sampled tail) "
        "or none (0 beyond the histogram; recorded) (with --height-map)",
    )


def height_map_roughness(a):
    """The :class:`~emscatter.surfaces.measured.MeasuredRoughness` of ``--height-map``, or
    None without it. ValueError (naming the options) for a parametric option given with it,
    a height-map option given without it, or a file that cannot be read (the reader's
    message, which names the file)."""
    given = given_options(a)
    path = getattr(a, "height_map", None)
    reject_unless(a, path is not None, HEIGHT_MAP_OPTIONS, "only with --height-map FILE")
    if path is None:
        return None
    both = sorted(given & set(PARAMETRIC))
    if both:
        raise ValueError(
            f"--height-map and {', '.join(both)} are mutually exclusive: the map's measured "
            "spectrum and slopes replace the parametric roughness (drop one of them)"
        )
    from ..surfaces.heightmap import HeightMapError, read_height_map
    from ..surfaces.measured import measured_roughness

    try:
        hm = read_height_map(path, unit=a.unit, detrend=a.detrend, holes=a.holes)
        return measured_roughness(hm, segments=a.segments, tail=a.tail, slope_tail=a.slope_tail)
    except (HeightMapError, ImportError) as exc:
        raise map_error(path, exc) from None


def map_error(path, exc: Exception) -> ValueError:
    """The CLI's one-line error for a map that cannot be used: ``--height-map FILE: why``, the
    API's ``holes='mask'`` and ``slope_tail='none'`` advice spelled as the options
    ``--holes mask`` and ``--slope-tail none``."""
    why = str(exc).replace(HOLES_API, "--holes mask").replace(SLOPE_TAIL_API, "--slope-tail none")
    return ValueError(f"--height-map {path}: {why}")


def height_map_inputs(a, rough) -> dict:
    """The record of a measured surface for a command's metadata (file, choices, what was
    measured)."""
    return {
        "height_map": str(a.height_map),
        "detrend": a.detrend,
        "unit": a.unit,
        "holes": a.holes,
        "holes_count": int(rough.info.get("holes", {}).get("count", 0)),
        "segments": a.segments,
        "tail": a.tail,
        "slope_tail": a.slope_tail,
        "slope_tail_fit": dict((rough.info or {}).get("slope_tail") or {}),
        "sigma_m": float(rough.sigma),
        "length_m": float(rough.length),
        "length_y_m": float(rough.length_y),
        "dimension": rough.dimension,
        "description": rough.describe(),
    }


def height_map_argv(r: dict) -> list[str]:
    """The options that reproduce :func:`height_map_inputs`'s record."""
    argv = ["--height-map", r["height_map"], "--detrend", r["detrend"]]
    if r.get("unit") is not None:
        argv += ["--unit", r["unit"]]
    argv += ["--holes", r.get("holes", "reject")]
    argv += ["--segments", str(r["segments"]), "--tail", r["tail"]]
    return argv + ["--slope-tail", r.get("slope_tail", "gaussian")]
