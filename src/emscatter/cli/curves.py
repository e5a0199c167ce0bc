"""``emscatter curves``: bistatic, backscatter or emissivity curves over an angle axis."""

from __future__ import annotations

import math
import sys

import numpy as np

from .args import (
    Angles,
    Number,
    OutputPath,
    add_command,
    add_frequency_args,
    add_roughness_args,
    frequency_kwargs,
    parse_eps,
    roughness_from_args,
)

FIGURE_SUFFIXES = (".png", ".pdf", ".svg")


def register(subparsers) -> None:
    c = add_command(subparsers, "curves", help="bistatic, backscatter or emissivity curves")
    c.add_argument(
        "--quantity", default="bistatic", choices=["bistatic", "backscatter", "emissivity"]
    )
    add_roughness_args(c)
    c.add_argument(
        "--eps",
        type=parse_eps,
        default=17 + 2j,
        help="relative permittivity, exp(-iωt) (Im ≥ 0), or 'pec'",
    )
    add_frequency_args(c)
    c.add_argument("--theta-i-deg", default="45", help="incidence angle(s) [deg]: '45' or 'a:b:n'")
    c.add_argument("--theta-s-deg", default="0:89.9:180", help="scattering angles [deg] 'a:b:n'")
    c.add_argument(
        "--phi-s-deg",
        type=Number(low=-360, high=360, low_open=False, high_open=False),
        default=0.0,
        help="scattering azimuth [deg]",
    )
    c.add_argument("--method", default="auto", help="solver name or 'auto'")
    c.add_argument(
        "--out-of-range",
        default="warn",
        choices=["warn", "raise", "nan", "ignore"],
        help="what to do outside the method's validity",
    )
    c.add_argument(
        "--tol", type=Number(low=0, high=1), default=1e-4, help="emissivity quadrature tolerance"
    )
    c.add_argument("--png", type=OutputPath(suffixes=FIGURE_SUFFIXES), help="figure file")
    c.add_argument("--csv", type=OutputPath(), help="CSV file")
    c.add_argument("--json", type=OutputPath(), help="JSON file")
    c.set_defaults(func=run)


def run(a) -> int:
    from .. import api
    from ..io import save_figure, write_csv, write_json
    from ..plots import curves_figure, emissivity_figure

    parse = Angles()
    rough = roughness_from_args(a)
    common = dict(method=a.method, out_of_range=a.out_of_range, **frequency_kwargs(a))
    rows: dict[str, np.ndarray] = {}
    if a.quantity == "emissivity":
        th = parse(a.theta_i_deg if ":" in a.theta_i_deg else "0:85:35")
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
            th = parse(a.theta_i_deg if ":" in a.theta_i_deg else "0:80:81")
            res = api.backscatter(rough, a.eps, theta_i=np.radians(th), **common)
            xlabel = "incidence angle θi [deg]"
        else:
            th = parse(a.theta_s_deg)
            ti = float(parse(a.theta_i_deg)[0])
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
