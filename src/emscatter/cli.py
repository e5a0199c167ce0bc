"""The ``emscatter`` command: demo, curves, surface, validate, bench.

Degrees at this edge (``--theta-i-deg``), radians inside; SI units otherwise.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

__all__ = ["main"]


def _parse_eps(text: str):
    t = text.strip().lower().replace(" ", "")
    if t == "pec":
        return "pec"
    try:
        return complex(t.replace("i", "j"))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"--eps must be a complex number like 17+2j (exp(-iωt): Im ≥ 0) or 'pec', got {text!r}"
        ) from None


def _parse_range(text: str) -> np.ndarray:
    """``"a:b:n"`` → linspace(a, b, n); ``"a,b,c"`` → list; ``"a"`` → [a]."""
    try:
        if ":" in text:
            a, b, n = text.split(":")
            return np.linspace(float(a), float(b), int(n))
        return np.array([float(v) for v in text.split(",")])
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"angle list must be 'start:stop:count' or 'a,b,c' in degrees, got {text!r}"
        ) from None


def _add_roughness_args(p: argparse.ArgumentParser, *, sigma=0.03, length=1.0):
    p.add_argument("--kind", default="gaussian", choices=["gaussian", "exponential", "power-law"])
    p.add_argument("--sigma", type=float, default=sigma, help="rms height [m]")
    p.add_argument("--length", type=float, default=length, help="correlation length [m]")
    p.add_argument("--length-y", type=float, default=None, help="correlation length along y [m]")
    p.add_argument("--hurst", type=float, default=0.5, help="Hurst exponent (power-law kind)")
    p.add_argument("--profile", action="store_true", help="1-D profile (2-D scattering problem)")


def _roughness_from_args(a):
    from .spectra import roughness

    params = {"sigma": a.sigma, "length": a.length, "dimension": 1 if a.profile else 2}
    if a.length_y is not None:
        params["length_y"] = a.length_y
    if a.kind == "power-law":
        params["hurst"] = a.hurst
    return roughness(a.kind, **params)


def cmd_curves(a) -> int:
    from . import api
    from .io import save_figure, write_csv, write_json
    from .plots import curves_figure, emissivity_figure

    rough = _roughness_from_args(a)
    freq = dict(frequency=a.frequency) if a.frequency else dict(wavelength=a.wavelength or 1.0)
    common = dict(method=a.method, out_of_range=a.out_of_range, **freq)
    rows: dict[str, np.ndarray] = {}
    if a.quantity == "emissivity":
        th = _parse_range(a.theta_i_deg if ":" in a.theta_i_deg else "0:85:35")
        res = api.emissivity(rough, a.eps, theta_i=np.radians(th), tol=a.tol, **common)
        rows = {
            "theta_i_deg": th,
            "e_h": res.h,
            "e_v": res.v,
            "r_coh_h": res.coherent[0],
            "r_coh_v": res.coherent[1],
            "r_incoh_h": res.incoherent[0],
            "r_incoh_v": res.incoherent[1],
            "error_h": res.error[0],
            "error_v": res.error[1],
        }
        fig = emissivity_figure(
            th, {res.method: (res.h, res.v)}, title=f"emissivity, {rough.describe()}, ε={a.eps}"
        )
        method = res.method
    else:
        if a.quantity == "backscatter":
            th = _parse_range(a.theta_i_deg if ":" in a.theta_i_deg else "0:80:81")
            res = api.backscatter(rough, a.eps, theta_i=np.radians(th), **common)
            xlabel = "incidence angle θi [deg]"
        else:
            th = _parse_range(a.theta_s_deg)
            ti = float(_parse_range(a.theta_i_deg)[0])
            phi = math.radians(a.phi_s_deg)
            res = api.bistatic(
                rough, a.eps, theta_i=math.radians(ti), theta_s=np.radians(th), phi_s=phi, **common
            )
            xlabel = f"scattering angle θs [deg] (θi = {ti:g}°, φs = {a.phi_s_deg:g}°)"
        rows = {"theta_deg": th, **{f"sigma0_{p}": res.pol(p) for p in ("hh", "hv", "vh", "vv")}}
        fig = curves_figure(
            th,
            {p: res.pol(p) for p in ("hh", "hv", "vh", "vv")},
            xlabel=xlabel,
            ylabel="σ⁰ [dB]",
            title=f"{a.quantity} ({res.method}), {rough.describe()}, ε={a.eps}",
        )
        method = res.method
    header = list(rows)
    if a.csv:
        write_csv(a.csv, header, [rows[h] for h in header])
    if a.json:
        write_json(
            a.json,
            {
                "method": method,
                "roughness": rough.describe(),
                "eps": str(a.eps),
                **{h: rows[h] for h in header},
            },
        )
    if a.png:
        save_figure(fig, a.png)
    else:
        import matplotlib.pyplot as plt

        plt.close(fig)
    width = 12
    print("  ".join(f"{h:>{width}}" for h in header))
    for vals in zip(*[np.ravel(rows[h]) for h in header], strict=True):
        print("  ".join(f"{v:>{width}.5g}" for v in vals))
    print(f"method: {method}", file=sys.stderr)
    return 0


def cmd_surface(a) -> int:
    from .demo import surface_report

    stats = surface_report(
        kind=a.kind,
        hurst=a.hurst,
        size=a.size,
        spacing=a.spacing,
        sigma=a.sigma,
        length=a.length,
        seed=a.seed,
        periodic=a.periodic,
        png=a.png,
        json_path=a.json,
        profile=a.profile,
    )
    for k, v in stats.items():
        print(f"{k:>28}: {v:.6g}" if isinstance(v, float) else f"{k:>28}: {v}")
    return 0


def cmd_demo(a) -> int:
    from .demo import run_demo

    written = run_demo(Path(a.out), quick=a.quick)
    print("wrote:")
    for p in written:
        print(f"  {p}")
    return 0


def cmd_validate(a) -> int:
    from .validity_maps import run_validation

    written = run_validation(Path(a.out), full=a.full)
    for p in written:
        print(f"  {p}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    from . import __version__

    p = argparse.ArgumentParser(prog="emscatter", description=__doc__.splitlines()[0])
    p.add_argument("--version", action="version", version=f"emscatter {__version__}")
    sub = p.add_subparsers(dest="command", required=True)

    d = sub.add_parser("demo", help="the main job on built-in defaults (figures + numbers in out/)")
    d.add_argument("--out", default="out")
    d.add_argument("--quick", action="store_true", help="smaller grids (for tests)")
    d.set_defaults(func=cmd_demo)

    c = sub.add_parser("curves", help="bistatic, backscatter or emissivity curves")
    c.add_argument(
        "--quantity", default="bistatic", choices=["bistatic", "backscatter", "emissivity"]
    )
    _add_roughness_args(c)
    c.add_argument(
        "--eps",
        type=_parse_eps,
        default=17 + 2j,
        help="relative permittivity, exp(-iωt) (Im ≥ 0), or 'pec' [default 17+2j]",
    )
    g = c.add_mutually_exclusive_group()
    g.add_argument("--frequency", type=float, help="[Hz]")
    g.add_argument("--wavelength", type=float, help="[m] (default 1.0 when neither is given)")
    c.add_argument("--theta-i-deg", default="45", help="incidence angle(s) [deg]: '45' or 'a:b:n'")
    c.add_argument("--theta-s-deg", default="0:89.9:180", help="scattering angles [deg] 'a:b:n'")
    c.add_argument("--phi-s-deg", type=float, default=0.0, help="scattering azimuth [deg]")
    c.add_argument("--method", default="auto")
    c.add_argument("--out-of-range", default="warn", choices=["warn", "raise", "nan", "ignore"])
    c.add_argument("--tol", type=float, default=1e-4, help="emissivity quadrature tolerance")
    c.add_argument("--png")
    c.add_argument("--csv")
    c.add_argument("--json")
    c.set_defaults(func=cmd_curves)

    s = sub.add_parser("surface", help="generate a surface, draw it and its spectrum, measure it")
    s.add_argument("--kind", default="fbm", choices=["fbm", "gaussian", "exponential", "power-law"])
    s.add_argument("--hurst", type=float, default=0.7)
    s.add_argument("--size", type=int, default=512, help="grid points per side")
    s.add_argument("--spacing", type=float, default=1.0, help="grid spacing [m]")
    s.add_argument(
        "--sigma",
        type=float,
        default=1.0,
        help="rms height [m] (fbm: rms increment at one spacing)",
    )
    s.add_argument("--length", type=float, default=16.0, help="correlation length [m]")
    s.add_argument("--seed", type=int, default=0)
    s.add_argument("--periodic", action="store_true")
    s.add_argument("--profile", action="store_true", help="1-D profile")
    s.add_argument("--png")
    s.add_argument("--json")
    s.set_defaults(func=cmd_surface)

    v = sub.add_parser("validate", help="method-of-moments validity maps (small grid; --full)")
    v.add_argument("--out", default="out/validation")
    v.add_argument("--full", action="store_true")
    v.set_defaults(func=cmd_validate)
    return p


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except (ValueError, TypeError) as exc:
        print(f"emscatter {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
