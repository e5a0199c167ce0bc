"""``emscatter brdf``: build a BRDF table from a surface and a material, and export it.

Formats from the output's extension (or ``--format``): ``.npz`` (the table with its full
metadata), ``.binary`` (MERL), ``.bsdf`` (RGL, Mitsuba's ``measured``; the render bridge's
exporter), ``.pbsdf`` (a Mueller table for Mitsuba's ``measured_polarized``,
:mod:`emscatter.brdf.export_pbsdf`: ``--method go`` or ``spm`` only — the formulations whose
amplitudes give the phase between polarizations, :mod:`emscatter.brdf.mueller` — exactly five
whole-nanometre wavelengths, default 450,500,550,600,650; ``--anisotropic``, ``--tol`` and
``--float32`` do not apply to it). ``--fit`` also fits a Beckmann/GGX microfacet model and
prints (or writes) the Mitsuba dict — the quick path when a dict is all you need.

``--height-map FILE`` (with ``--detrend``, ``--unit``, ``--segments``, ``--tail``;
:mod:`.heightmap_args`) takes the surface from a measured height map instead of
``--kind/--sigma/--length``. Every input is checked before the table is built: the output
paths (:mod:`.paths`), the format against the extension, the height map (read and measured),
the material at every wavelength, the method name, and options that do not apply
(``--fit-json`` without ``--fit``, ``--rgl-channels`` for a non-RGL file,
``--n-theta``/``--n-phi`` with ``--tol``) are errors, never ignored.

A progress bar over the wavelengths (advanced per chunk) is drawn on stderr when it is a
terminal; ``--quiet`` turns it off. Many tables (materials × wavelength sets × roughness) on a
dask cluster: ``emscatter farm brdf`` (:mod:`emscatter.cli.farm`) or the Python entry
:func:`emscatter.brdf.build_tables`.
"""

from __future__ import annotations

import argparse

from .args import (
    Integer,
    Number,
    add_command,
    add_roughness_args,
    fmt,
    parse_eps,
    reject_unless,
    roughness_from_args,
)
from .heightmap_args import add_height_map_args, height_map_roughness
from .paths import OutputPath, check_format

FORMATS = {".npz": "npz", ".binary": "merl", ".bsdf": "rgl", ".pbsdf": "pbsdf"}
#: Default wavelengths [nm]: every format, and ``.pbsdf`` (the five ``measured_polarized`` reads).
DEFAULT_WAVELENGTHS_NM = "450,550,650"
PBSDF_WAVELENGTHS_NM = "450,500,550,600,650"


def _material(text: str):
    """A permittivity (``2.25``, ``4+0.3j``, ``pec``) or a material name (``Au``,
    ``itu:concrete``), checked when the command runs."""
    try:
        return parse_eps(text)
    except argparse.ArgumentTypeError:
        name = text.strip()
        if not name or not (name[0].isalpha()):
            raise
        return name


def _wavelengths_nm(text: str):
    import numpy as np

    try:
        if ":" in text:
            a, b, n = text.split(":")
            vals = np.linspace(float(a), float(b), int(n))
        else:
            vals = np.array([float(v) for v in text.split(",")])
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"wavelengths must be 'a,b,c' or 'start:stop:count' in nm, got {text!r}"
        ) from None
    if vals.size == 0 or not np.all(np.isfinite(vals)) or np.any(vals <= 0):
        raise argparse.ArgumentTypeError(f"wavelengths must be positive [nm], got {text!r}")
    if np.any(vals < 10) or np.any(vals > 1e9):
        raise argparse.ArgumentTypeError(
            f"wavelengths {text!r} nm are outside 10 nm – 1 m; the unit here is nm "
            "(e.g. 450,550,650)"
        )
    if np.any(np.diff(vals) <= 0):
        raise argparse.ArgumentTypeError(f"wavelengths must increase, got {text!r}")
    return vals


def _method_choices() -> list[str]:
    from ..solvers import available

    return ["auto", *available()]


def check_inputs(a) -> tuple[str, object, object]:
    """``(format, roughness, wavelengths [m])`` once every input is checked (nothing computed
    yet): ValueError naming the option, the value and what is allowed."""
    import numpy as np

    from ..brdf.build import material_eps

    fmt_name = check_format(a.output, a.format, FORMATS, "output")
    default_wavelengths = a.wavelengths_nm is None
    if a.wavelengths_nm is None:
        a.wavelengths_nm = _wavelengths_nm(
            PBSDF_WAVELENGTHS_NM if fmt_name == "pbsdf" else DEFAULT_WAVELENGTHS_NM
        )
    if fmt_name == "pbsdf":
        _check_pbsdf(a)
    reject_unless(a, a.fit is not None, ("--fit-json",), "only with --fit (beckmann or ggx)")
    reject_unless(a, fmt_name == "rgl", ("--rgl-channels",), "to RGL .bsdf output only")
    reject_unless(
        a,
        a.tol is None,
        ("--n-theta", "--n-phi"),
        "to a fixed grid only; --tol refines the grid by itself (drop one of them)",
    )
    rough = height_map_roughness(a) or roughness_from_args(a)
    if rough.dimension != 2:
        what = f"--height-map {a.height_map} is" if a.height_map else "--profile describes"
        raise ValueError(f"{what} a 1-D profile; a BRDF table needs a 2-D surface")
    wl = np.asarray(a.wavelengths_nm, float) * 1e-9
    for lam in wl:
        try:
            material_eps(a.material, float(lam))
        except (ValueError, TypeError) as exc:
            raise ValueError(f"--material {a.material!s} at {fmt(lam * 1e9)} nm: {exc}") from None
    if default_wavelengths and fmt_name != "pbsdf" and not a.transmission:
        _warn_colour(a.material, wl)
    if a.transmission:
        _check_transmission(a, fmt_name, rough, wl)
    return fmt_name, rough, wl


def transmission_paths(output) -> tuple:
    """``(OUT_btdf.npz, OUT_inner.npz)`` beside ``OUT.npz``."""
    from pathlib import Path

    out = Path(output)
    return out.with_name(f"{out.stem}_btdf.npz"), out.with_name(f"{out.stem}_inner.npz")


def _check_transmission(a, fmt_name, rough, wl) -> None:
    from ..brdf.build import material_eps
    from ..solvers.kirchhoff.transmission.go import check_transmission_eps

    if fmt_name != "npz":
        raise ValueError(
            f"--transmission writes .npz tables (OUT_btdf.npz beside OUT.npz), got {fmt_name} "
            f"output {str(a.output)!r}"
        )
    if a.anisotropic or not rough.is_isotropic:
        raise ValueError("--transmission needs an isotropic surface (BTDF tables are θi, θt, Δφ)")
    if a.tol is not None:
        raise ValueError("--transmission takes a fixed grid (--n-theta/--n-phi), not --tol")
    if a.polarized and a.method == "iem":
        raise ValueError(
            "--transmission --method iem has no --polarized BTDF (the IEM "
            "transmission is a power-level model); use --method go, po or spm"
        )
    for lam in wl:
        try:
            check_transmission_eps(material_eps(a.material, float(lam)))
        except ValueError as exc:
            raise ValueError(
                f"--transmission needs a lossless dielectric: --material {a.material!s} at "
                f"{fmt(lam * 1e9)} nm: {exc}"
            ) from None


def _run_transmission(a, rough, wl, resolution, table_kw):
    """The BRDF, the BTDF and the inside BRDF of a rough dielectric, the reflection capped
    at ``1 − T`` of the BTDF (:func:`~emscatter.brdf.btdf_table.cap_energy`)."""
    from ..brdf import build_table
    from ..brdf.btdf_table import build_btdf_table, cap_energy
    from ..brdf.build import material_eps

    n_theta = 90 if resolution is None else resolution[0]
    tm = a.method if a.method in ("po", "spm", "iem") else "go"  # the same method's BTDF, else GO
    bt = build_btdf_table(
        rough, a.material, wl, n_theta=n_theta, polarized=a.polarized,
        dtype=table_kw["dtype"], method=tm,
        **({"out_of_range": a.out_of_range} if tm != "go" and a.out_of_range != "nan" else {}),
    )  # fmt: skip
    kw = dict(table_kw, energy="off")
    table = build_table(rough, a.material, wl, **kw)
    mat = a.material

    def inside(lam):
        return 1.0 / complex(material_eps(mat, float(lam))).real

    inner = build_table(rough, inside, wl, **dict(table_kw))
    if a.energy == "rescale":
        table, bt = cap_energy(table, bt)
    return table, bt, inner


def _warn_colour(material, wl) -> None:
    """Warn when the default wavelengths shift the material's colour beyond
    :data:`~emscatter.brdf.colour.COLOUR_TOL`, naming the error and the count that meets it
    (:func:`~emscatter.brdf.colour.wavelengths_for`); a grey material gets no warning."""
    import warnings

    from ..brdf.colour import COLOUR_TOL, colour_error, wavelengths_for

    try:
        err = colour_error(material, wl)
        if err <= COLOUR_TOL:
            return
        n = wavelengths_for(material, COLOUR_TOL).size
    except (ValueError, TypeError):  # a material without visible-range data: no colour advice
        return
    warnings.warn(
        f"the default wavelengths ({DEFAULT_WAVELENGTHS_NM} nm) shift this material's rendered "
        f"colour by {100 * err:.2g} % (linear sRGB of its normal-incidence reflectance, worst "
        f"channel); --wavelengths-nm 360:830:{n} keeps it within {100 * COLOUR_TOL:g} %",
        stacklevel=2,
    )


def _check_pbsdf(a) -> None:
    """The options a ``.pbsdf`` (Mueller) output allows, before anything is computed."""
    import numpy as np

    from ..brdf.mueller import _REFUSED, SUPPORTED

    if a.method not in SUPPORTED:
        why = _REFUSED.get(a.method, "no phase between the polarization pairs' amplitudes")
        why = why if a.method != "auto" else "auto may pick a method without a Mueller matrix"
        raise ValueError(
            f"--method {a.method} gives no Mueller table for a .pbsdf output ({why}); allowed "
            f"with --format pbsdf: --method {' or '.join(SUPPORTED)}"
        )
    wl = np.asarray(a.wavelengths_nm, float)
    if wl.size != 5 or np.any(wl != np.round(wl)) or wl[-1] > 65535:
        raise ValueError(
            f"--wavelengths-nm {','.join(fmt(float(v)) for v in wl)}: a .pbsdf holds exactly 5 "
            "rising whole-nanometre wavelengths (measured_polarized reads five, as uint16); "
            f"allowed: 5 whole numbers, e.g. {PBSDF_WAVELENGTHS_NM} (the default)"
        )
    for opts, why in (
        (("--anisotropic",), "to npz/merl/rgl output only; a .pbsdf stores isotropic tables"),
        (("--tol",), "to npz/merl/rgl output only; a .pbsdf table uses a fixed grid "
         "(--n-theta/--n-phi)"),
        (("--float32",), "to npz/merl/rgl output only; a .pbsdf is float32 always"),
    ):  # fmt: skip
        reject_unless(a, False, opts, why)


def register(subparsers) -> None:
    p = add_command(
        subparsers,
        "brdf",
        help="build a BRDF table (surface + material) and export it (npz, MERL, RGL .bsdf, "
        "polarized .pbsdf)",
    )
    p.add_argument(
        "output",
        type=OutputPath(suffixes=tuple(FORMATS)),
        help="output file: .npz (table + metadata), .binary (MERL), .bsdf (RGL) or .pbsdf "
        "(Mueller table for measured_polarized; --method go or spm)",
    )
    add_roughness_args(p, sigma=0.15e-6, length=1.0e-6)
    add_height_map_args(p)
    p.add_argument(
        "--material",
        type=_material,
        default="Au",
        help="material name (Au, Ag, Cu, Al, Cr, ..., itu:concrete) or a permittivity "
        "(exp(-iωt), Im ≥ 0) or 'pec'",
    )
    p.add_argument(
        "--wavelengths-nm",
        type=_wavelengths_nm,
        default=None,
        help=f"wavelengths [nm]: 'a,b,c' or 'start:stop:count' (default {DEFAULT_WAVELENGTHS_NM}; "
        f".pbsdf: exactly five, default {PBSDF_WAVELENGTHS_NM})",
    )
    p.add_argument(
        "--method",
        type=str.lower,
        default="auto",
        choices=_method_choices(),
        help="solver, or auto (the best valid one per wavelength)",
    )
    p.add_argument(
        "--n-theta",
        type=Integer(low=2, high=2000),
        default=None,
        help="θ nodes (default: from the lobe width, 90 unless the lobe is narrower than ~10°)",
    )
    p.add_argument(
        "--n-phi",
        type=Integer(low=4, high=4000),
        default=None,
        help="Δφ (or φ) nodes (default: 2 × the θ nodes, at least 180)",
    )
    p.add_argument(
        "--tol",
        type=Number(low=0, high=1),
        default=None,
        help="target interpolation error: refine the grid adaptively instead of --n-theta/--n-phi",
    )
    p.add_argument("--polarized", action="store_true", help="also store f_r per polarization pair")
    p.add_argument(
        "--transmission",
        action="store_true",
        help="a rough dielectric (real ε > 0, ≠ 1): also write its BTDF (GO; PO, SPM or IEM "
        "with --method po / spm / iem) as OUT_btdf.npz and "
        "the inside reflection (1/ε) as OUT_inner.npz (.npz output, isotropic; the reflection "
        "capped at 1 − T of that BTDF); render them with emscatter render OUT.npz --btdf …",
    )
    p.add_argument(
        "--float32",
        action="store_true",
        help="store the table in float32 (half the memory; every exporter and the plugin take it)",
    )
    p.add_argument(
        "--anisotropic",
        action="store_true",
        help="(θi, φi, θo, φo) table even for an isotropic surface",
    )
    p.add_argument(
        "--energy",
        default="rescale",
        choices=["rescale", "off"],
        help="reciprocal energy remedy where the albedo exceeds 1 ('off': diagnostics only)",
    )
    p.add_argument(
        "--out-of-range",
        default="warn",
        choices=["warn", "raise", "ignore"],
        help="what to do outside the method's validity",
    )
    p.add_argument(
        "--format",
        choices=sorted(set(FORMATS.values())),
        help="the format, which must match the extension (npz: .npz, merl: .binary, rgl: .bsdf, "
        "pbsdf: .pbsdf)",
    )
    p.add_argument(
        "--rgl-channels",
        default="spectral",
        choices=["spectral", "rgb"],
        help="RGL .bsdf only: spectral or rgb tables",
    )
    p.add_argument(
        "--fit",
        choices=["beckmann", "ggx"],
        help="also fit a microfacet model and print its Mitsuba dict (JSON)",
    )
    p.add_argument("--fit-json", type=OutputPath(suffixes=(".json",)), help="write the fit here")
    p.add_argument(
        "--quiet",
        action="store_true",
        help="no progress bar (the bar is drawn only when stderr is a terminal anyway); many "
        "tables on a dask cluster: emscatter farm brdf --scheduler local|tcp://HOST:PORT",
    )
    p.set_defaults(func=run)


def run(a) -> int:
    from ..brdf import build_table

    fmt_name, rough, wl = check_inputs(a)
    resolution = None
    if a.n_theta is not None or a.n_phi is not None:
        n_theta = 90 if a.n_theta is None else a.n_theta
        resolution = (n_theta, max(180, 2 * n_theta) if a.n_phi is None else a.n_phi)
    if fmt_name == "pbsdf":
        return _run_pbsdf(a, rough, wl, resolution)
    table_kw = dict(
        method=a.method,
        resolution=resolution,
        tol=a.tol,
        anisotropic=True if a.anisotropic else None,
        polarized=a.polarized,
        energy=a.energy,
        out_of_range=a.out_of_range,
        dtype="float32" if a.float32 else "float64",
        progress=False if a.quiet else None,
    )
    try:
        if a.transmission:
            table, bt, inner = _run_transmission(a, rough, wl, resolution, table_kw)
        else:
            table = build_table(rough, a.material, wl, **table_kw)
    except MemoryError as exc:  # the estimate, before any work: a user error, not a crash
        raise ValueError(exc.cli() if hasattr(exc, "cli") else str(exc)) from None
    if a.transmission:
        from ..brdf.export_npz import write_btdf_npz, write_npz

        bt_path, in_path = transmission_paths(a.output)
        print(f"wrote {write_btdf_npz(bt, bt_path)} (btdf): {bt.describe()}")
        print(f"wrote {write_npz(inner, in_path)} (npz, inside 1/ε): {inner.describe()}")
    path = export(table, a.output, fmt_name, rgl_channels=a.rgl_channels)
    energy = table.metadata.get("energy", {})
    print(f"wrote {path} ({fmt_name}): {table.describe()}")
    if energy.get("remedy_applied"):
        worst = max(energy["max_albedo_before"])
        limit = "1 − T (the transmitted fraction)" if energy.get("transmission_counted") else "1"
        print(f"energy remedy applied: albedo up to {fmt(worst)} capped at ≤ {limit} (metadata)")
    if a.fit:
        _fit(table, a.fit, a.fit_json)
    return 0


def _run_pbsdf(a, rough, wl, resolution) -> int:
    """``.pbsdf`` output: a Mueller table (:func:`~emscatter.brdf.mueller.build_mueller_table`)
    written by :func:`~emscatter.brdf.export_pbsdf.write_pbsdf` at its own five wavelengths."""
    from ..brdf.export_pbsdf import write_pbsdf
    from ..brdf.mueller import build_mueller_table

    mt = build_mueller_table(
        rough, a.material, wl, method=a.method, resolution=resolution, energy=a.energy,
        out_of_range=a.out_of_range,
    )  # fmt: skip
    path = write_pbsdf(mt, a.output)
    print(f"wrote {path} (pbsdf, Mueller {a.method}): {mt.table.describe()}")
    energy = mt.table.metadata.get("energy", {})
    if energy.get("remedy_applied"):
        worst = max(energy["max_albedo_before"])
        print(f"energy remedy applied: albedo up to {fmt(worst)} brought to ≤ 1 (see metadata)")
    if a.fit:
        _fit(mt.table, a.fit, a.fit_json)
    return 0


def export(table, path, fmt_name: str, *, rgl_channels: str = "spectral"):
    """Write ``table`` in ``fmt_name`` (``npz``, ``merl``, ``rgl``); returns the path."""
    if fmt_name == "npz":
        from ..brdf.export_npz import write_npz

        return write_npz(table, path)
    if fmt_name == "merl":
        from ..brdf.export_merl import write_merl

        return write_merl(table, path)
    if fmt_name == "rgl":
        try:
            from ..brdf.export_rgl import write_rgl
        except ImportError:
            raise ValueError(
                "the RGL .bsdf exporter (emscatter.brdf.export_rgl) is not installed in this "
                "build; write .npz or .binary instead"
            ) from None
        return write_rgl(path, table, channels=rgl_channels)
    raise ValueError(f"format must be one of {sorted(set(FORMATS.values()))}, got {fmt_name!r}")


def _fit(table, distribution: str, json_path) -> None:
    import json

    from emscatter.brdf.analytic.fit import fit_microfacet

    from ..io import write_json

    fit = fit_microfacet(table, distribution=distribution)
    out = {"mitsuba": fit.to_mitsuba(), "errors": fit.errors, "alpha": fit.alpha}
    print(json.dumps(out["mitsuba"]))
    e = fit.errors
    print(
        f"fit error: rms {fmt(e['rms'])} of the peak, median {fmt(100 * e['median_rel'])} %, "
        f"p90 {fmt(100 * e['p90_rel'])} %"
    )
    if json_path is not None:
        write_json(json_path, out)
