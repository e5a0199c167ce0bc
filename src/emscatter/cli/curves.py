"""``emscatter curves``: bistatic, backscatter or emissivity curves over an angle axis.

Every option is honoured or rejected: a single angle, a list or a range gives exactly those
angles (bistatic with several incidence angles computes them all); an option that does not
apply to the quantity is an error. ``--json``/``--csv`` carry every input and a schema line, and
``--from FILE`` recomputes a figure from such a file. ``--height-map FILE`` (with
``--detrend``, ``--unit``, ``--segments``, ``--tail``; :mod:`.heightmap_args`) takes the surface
from a measured height map instead of ``--kind/--sigma/--length`` (recorded: the file and the
choices, with the measured σ and ℓ).
"""

from __future__ import annotations

import json
import math
import shlex
import sys
from pathlib import Path

import numpy as np

from .args import (
    Angles,
    Number,
    OutputPath,
    add_command,
    add_frequency_args,
    add_roughness_args,
    fmt,
    frequency_kwargs,
    given_options,
    parse_eps,
    reject_unless,
    roughness_from_args,
)
from .heightmap_args import (
    add_height_map_args,
    height_map_argv,
    height_map_inputs,
    height_map_roughness,
)
from .paths import check_distinct

FIGURE_SUFFIXES = (".png", ".pdf", ".svg")
SCHEMA = "emscatter.curves/1"
QUANTITIES = ("bistatic", "backscatter", "emissivity")
DEFAULT_THETA_I = {"bistatic": "45", "backscatter": "0:80:81", "emissivity": "0:85:35"}
DEFAULT_THETA_S = "0:89.9:180"
OUTPUTS = ("--png", "--csv", "--json")


def _method_choices() -> list[str]:
    from ..solvers import available

    return ["auto", *available()]


def register(subparsers) -> None:
    c = add_command(
        subparsers,
        "curves",
        help="bistatic, backscatter or emissivity curves",
        description="Bistatic, backscatter or emissivity curves over an angle axis. Angles "
        "in degrees: 'a', 'a,b,c' or 'start:stop:count'.",
    )
    c.add_argument("--quantity", default="bistatic", choices=QUANTITIES, help="what to compute")
    add_roughness_args(c)
    add_height_map_args(c)
    c.add_argument(
        "--eps",
        type=parse_eps,
        default=17 + 2j,
        help="relative permittivity, exp(-iωt) so Im ≥ 0 (17+2j or 17+2i), 'pec', or a material "
        "(a Mitsuba metal such as Au, an ITU-R P.2040 name such as concrete)",
    )
    add_frequency_args(c)
    c.add_argument(
        "--theta-i-deg",
        type=Angles(high=90),
        default=None,
        metavar="DEG",
        help="incidence angle(s) [deg] (default: 45 for bistatic, 0:80:81 for backscatter, "
        "0:85:35 for emissivity)",
    )
    c.add_argument(
        "--theta-s-deg",
        type=Angles(high=90),
        default=None,
        metavar="DEG",
        help=f"scattering angles [deg], bistatic only (default: {DEFAULT_THETA_S})",
    )
    c.add_argument(
        "--phi-s-deg",
        type=Number(low=-360, high=360, low_open=False, high_open=False),
        default=None,
        metavar="DEG",
        help="scattering azimuth [deg], bistatic only; 0 = forward plane (default: 0)",
    )
    c.add_argument(
        "--method",
        type=str.lower,
        default="auto",
        choices=_method_choices(),
        help="solver, or auto (the best valid one for the regime)",
    )
    c.add_argument(
        "--out-of-range",
        default="warn",
        choices=["warn", "raise", "nan", "ignore"],
        help="outside the method's validity (or where energy is not conserved): warn, stop, "
        "blank those angles, or only record",
    )
    c.add_argument(
        "--tol",
        type=Number(low=0, high=1),
        default=None,
        help="emissivity only: absolute quadrature tolerance (default: 0.0001)",
    )
    c.add_argument("--png", type=OutputPath(suffixes=FIGURE_SUFFIXES), help="figure file")
    c.add_argument(
        "--csv", type=OutputPath(suffixes=(".csv",)), help="CSV file (with a metadata header)"
    )
    c.add_argument(
        "--json", type=OutputPath(suffixes=(".json",)), help="JSON file (inputs, result, columns)"
    )
    c.add_argument(
        "--from",
        dest="from_file",
        metavar="FILE",
        help="recompute from a JSON or CSV written by 'emscatter curves' (only --png, --csv, "
        "--json may be given with it)",
    )
    c.add_argument(
        "--quiet",
        action="store_true",
        help="no progress bar (drawn on stderr only when it is a terminal and the work runs past "
        "2 s anyway)",
    )
    c.set_defaults(func=run, _parser=c)


# ----------------------------------------------------------------------------- inputs
def _check_consistent(a) -> None:
    q = a.quantity
    reject_unless(
        a, q == "bistatic", ("--theta-s-deg", "--phi-s-deg"), "to --quantity bistatic only"
    )
    reject_unless(a, q == "emissivity", ("--tol",), "to --quantity emissivity only")
    check_distinct({"--png": a.png, "--csv": a.csv, "--json": a.json})


def _inputs(a, rough) -> dict:
    """Every input of the computation, normalized (numbers, lists, degrees)."""
    from ..constants import SPEED_OF_LIGHT

    fk = frequency_kwargs(a)
    if "frequency" in fk:
        f = fk["frequency"]
        lam = SPEED_OF_LIGHT / f
    else:
        lam = fk["wavelength"]
        f = SPEED_OF_LIGHT / lam
    if isinstance(a.eps, str):  # "pec" or a material name
        eps = a.eps if a.eps == "pec" else {"material": str(a.eps)}
    else:
        eps = {"re": a.eps.real, "im": a.eps.imag}
    inputs = {
        "quantity": a.quantity,
        "roughness": {
            "kind": a.kind,
            "sigma_m": a.sigma,
            "length_m": a.length,
            "length_y_m": a.length_y,
            "hurst": a.hurst if a.kind == "power-law" else None,
            "dimension": rough.dimension,
            "description": rough.describe(),
        },
        "eps": eps,
        "frequency_hz": f,
        "wavelength_m": lam,
        "given": "frequency" if "frequency" in fk else "wavelength",
        "theta_i_deg": a.theta_i_deg,
        "method": a.method,
        "out_of_range": a.out_of_range,
    }
    if a.height_map is not None:
        inputs["roughness"] = height_map_inputs(a, rough)
    if a.quantity == "bistatic":
        inputs.update(theta_s_deg=a.theta_s_deg, phi_s_deg=a.phi_s_deg)
    if a.quantity == "emissivity":
        inputs["tol"] = a.tol
    return inputs


def _angles_text(values) -> str:
    return ",".join(repr(float(v)) for v in values)


def _argv_from_inputs(inputs: dict) -> list[str]:
    """The ``curves`` options that reproduce ``inputs`` (inverse of :func:`_inputs`)."""
    r = inputs["roughness"]
    eps = inputs["eps"]
    argv = ["--quantity", inputs["quantity"]]
    if "height_map" in r:  # a measured surface: the file and the choices, not σ and ℓ
        argv += height_map_argv(r)
    else:
        argv += ["--kind", r["kind"], "--sigma", repr(r["sigma_m"])]
        argv += ["--length", repr(r["length_m"])]
        if r.get("length_y_m") is not None:
            argv += ["--length-y", repr(r["length_y_m"])]
        if r.get("hurst") is not None:
            argv += ["--hurst", repr(r["hurst"])]
        if r.get("dimension") == 1:
            argv.append("--profile")
    if eps == "pec" or "material" in eps:
        argv += ["--eps", "pec" if eps == "pec" else eps["material"]]
    else:
        re, im = float(eps["re"]), float(eps["im"])
        argv += ["--eps", f"{re!r}{'+' if im >= 0 else '-'}{abs(im)!r}j"]
    if inputs["given"] == "frequency":
        argv += ["--frequency", repr(inputs["frequency_hz"])]
    else:
        argv += ["--wavelength", repr(inputs["wavelength_m"])]
    argv += ["--theta-i-deg", _angles_text(inputs["theta_i_deg"])]
    if inputs["quantity"] == "bistatic":
        argv += ["--theta-s-deg", _angles_text(inputs["theta_s_deg"])]
        argv += ["--phi-s-deg", repr(inputs["phi_s_deg"])]
    if inputs["quantity"] == "emissivity":
        argv += ["--tol", repr(inputs["tol"])]
    argv += ["--method", inputs["method"], "--out-of-range", inputs["out_of_range"]]
    return argv


def _load_inputs(path: str) -> dict:
    """The ``inputs`` block of a JSON or CSV written by this command."""
    from ..io import read_csv

    p = Path(path)
    if not p.is_file():
        raise ValueError(
            f"--from {path!r}: no such file; give a JSON or CSV from 'emscatter curves'"
        )
    try:
        meta = json.loads(p.read_text()) if p.suffix.lower() == ".json" else read_csv(p)[2]
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ValueError(f"--from {path!r}: not a JSON file ({exc})") from None
    if not isinstance(meta, dict) or meta.get("schema") != SCHEMA or "inputs" not in meta:
        found = meta.get("schema") if isinstance(meta, dict) else None
        raise ValueError(
            f"--from {path!r}: not written by 'emscatter curves' (schema {found!r}, "
            f"expected {SCHEMA!r})"
        )
    return meta["inputs"]


def _reparse(a):
    """``a`` with its inputs replaced by those of ``--from FILE`` (outputs kept)."""
    extra = sorted(given_options(a) - {"--from", "--quiet", *OUTPUTS})
    if extra:
        raise ValueError(
            f"--from takes every input from the file; only {', '.join(OUTPUTS)} may be given "
            f"with it, got {', '.join(extra)}"
        )
    argv = _argv_from_inputs(_load_inputs(a.from_file))
    b = a._parser.parse_args(argv)
    for opt in ("png", "csv", "json", "quiet"):
        setattr(b, opt, getattr(a, opt))
    b._argv = argv
    return b


# ----------------------------------------------------------------------------- compute
def _valid(report: dict, shape) -> np.ndarray:
    """Per element: the method is valid for the roughness and at that incidence angle."""
    rough_ok = bool(report.get("roughness_valid", report.get("valid", False)))
    angle_ok = np.broadcast_to(np.asarray(report.get("angle_valid", True), dtype=bool), shape)
    return angle_ok & rough_ok


def _compute(a, rough):
    """``(columns, figure, result summary)`` for the quantity asked."""
    from .. import api
    from ..plots import curves_figure, emissivity_figure

    common = dict(method=a.method, out_of_range=a.out_of_range, **frequency_kwargs(a))
    th_i = np.asarray(a.theta_i_deg, dtype=float)
    eps_label = str(a.eps) if isinstance(a.eps, str) else fmt(a.eps)
    title_tail = f"{rough.describe()}, ε = {eps_label}"
    if a.quantity == "emissivity":
        res = api.emissivity(rough, a.eps, theta_i=np.radians(th_i), tol=a.tol, **common)
        report = res.info["validity"]
        valid = _valid(report, th_i.shape)
        cols = {
            "theta_i_deg": th_i,
            "e_h": res.h,
            "e_v": res.v,
            "r_coh_h": res.coherent[0],
            "r_coh_v": res.coherent[1],
            "r_incoh_h": res.incoherent[0],
            "r_incoh_v": res.incoherent[1],
            "error_h": res.error[0],
            "error_v": res.error[1],
            "energy_ok": res.energy_ok.astype(int),
            "valid": valid.astype(int),
            "method": np.asarray(res.info["methods"], dtype=object),
        }
        fig = emissivity_figure(
            th_i,
            {res.method: (res.h, res.v)},
            title=f"emissivity ({res.method}), {title_tail}",
            flagged=~valid,
        )
        return cols, fig, res.method, report
    pols = ("hh", "hv", "vh", "vv")
    if a.quantity == "backscatter":
        res = api.backscatter(rough, a.eps, theta_i=np.radians(th_i), **common)
        x, xlabel = th_i, "incidence angle θi [deg] (backscatter)"
        cols = {"theta_i_deg": th_i}
        curves = {p: res.pol(p) for p in pols}
    else:
        th_s = np.asarray(a.theta_s_deg, dtype=float)
        ti, ts = np.meshgrid(th_i, th_s, indexing="ij")
        res = api.bistatic(
            rough,
            a.eps,
            theta_i=np.radians(ti),
            theta_s=np.radians(ts),
            phi_s=math.radians(a.phi_s_deg),
            **common,
        )
        x = th_s
        xlabel = f"scattering angle θs [deg] (φs = {a.phi_s_deg:g}°)"
        cols = {"theta_i_deg": ti.ravel(), "theta_s_deg": ts.ravel()}
        if th_i.size == 1:
            xlabel += f", θi = {th_i[0]:g}°"
            curves = {p: res.pol(p)[0] for p in pols}
        else:
            curves = {
                f"{p} θi={t:g}°": res.pol(p)[j] for j, t in enumerate(th_i) for p in ("hh", "vv")
            }
    report = res.info["validity"]
    cols.update({f"sigma0_{p}": res.pol(p).ravel() for p in pols})
    cols["valid"] = _valid(report, res.shape).ravel().astype(int)
    fig = curves_figure(
        x,
        curves,
        xlabel=xlabel,
        ylabel="σ⁰ [dB]",
        title=f"{a.quantity} ({res.method}), {title_tail}",
    )
    return cols, fig, res.method, report


def _check_material(a) -> None:
    """A material name for ``--eps`` must be defined at the frequency: checked before the
    solver runs, naming the option."""
    if not isinstance(a.eps, str) or a.eps == "pec":
        return
    from ..materials import eps_at

    try:
        eps_at(str(a.eps), **frequency_kwargs(a))
    except (ValueError, TypeError) as exc:
        raise ValueError(f"--eps {a.eps}: {exc}") from None


def _summary(report: dict) -> dict:
    out = {"valid": bool(report.get("valid", False)), "reasons": list(report.get("reasons", []))}
    if report.get("angle_reasons"):
        out["angle_reasons"] = list(report["angle_reasons"])
    return out


def run(a) -> int:
    from .._version import __version__
    from ..io import jsonable, save_figure, write_csv, write_json

    if a.from_file:
        a = _reparse(a)
    _check_consistent(a)
    if a.theta_i_deg is None:
        a.theta_i_deg = Angles(high=90)(DEFAULT_THETA_I[a.quantity])
    if a.quantity == "bistatic":
        a.theta_s_deg = a.theta_s_deg if a.theta_s_deg is not None else Angles()(DEFAULT_THETA_S)
        a.phi_s_deg = 0.0 if a.phi_s_deg is None else a.phi_s_deg
    a.tol = 1e-4 if a.tol is None else a.tol
    _check_material(a)
    rough = height_map_roughness(a) or roughness_from_args(a)
    from ..progress import silenced

    with silenced(a.quiet):
        cols, fig, method, report = _compute(a, rough)
    inputs = _inputs(a, rough)
    meta = {
        "schema": SCHEMA,
        "emscatter_version": __version__,
        "command": "emscatter curves " + shlex.join(_argv_from_inputs(inputs)),
        "inputs": inputs,
        "result": {"method": method, **_summary(report)},
    }
    header = list(cols)
    if a.csv:
        write_csv(a.csv, header, [cols[h] for h in header], schema=SCHEMA, metadata=meta)
    if a.json:
        write_json(a.json, jsonable({**meta, "columns": cols}))
    if a.png:
        save_figure(fig, a.png)
    else:
        import matplotlib.pyplot as plt

        plt.close(fig)
    _print_table(cols)
    print(f"method: {method}", file=sys.stderr)
    return 0


def _print_table(cols: dict, width: int = 12) -> None:
    header = list(cols)
    print("  ".join(f"{h:>{width}}" for h in header))
    for vals in zip(*[np.ravel(cols[h]) for h in header], strict=True):
        cells = [
            f"{v:>{width}.5g}" if isinstance(v, float | np.floating) else f"{v!s:>{width}}"
            for v in vals
        ]
        print("  ".join(cells))
