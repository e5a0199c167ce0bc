"""emscatter against SMRT on the same inputs, in one run: time and agreement.

    bash benchmarks/peers/setup.sh                       # once: the peers' environment
    /tmp/emscatter-peers/bin/python benchmarks/bench_peers.py [--label NAME] [--repeat 7]
    → benchmarks/results/peers.json (+ peers_<label>.json), peers.png

Cases (SMRT 1.7; conventions mapped in benchmarks/peers/smrt_map.py):
* backscatter curves, 90 angles 0–89°: emscatter ``backscatter(method="spm")`` and ``"auto"``
  vs SMRT ``iem_fung92`` (SMRT's small-roughness model; at kσ = 0.2 IEM ≈ SPM) on a
  slightly rough surface; emscatter ``backscatter(method="go")`` vs SMRT
  ``geometrical_optics_backscatter`` on a very rough one;
* bistatic GO on a (dphi × θs × θi) grid, 24 × 45 × 6 = 6480 geometries: emscatter
  ``bistatic(method="go", shadowing="correlated")`` vs SMRT ``geometrical_optics``.
Timing: the steady-state call (objects built once), median of ``--repeat``, the two codes
interleaved. Agreement: max |Δ| in dB over points where both are > 1e-6 of the peak.
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
import warnings
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE / "peers"))
import numpy as np  # noqa: E402
from common import command, machine, save, stamp, write  # noqa: E402
from smrt_map import C_SPEED, smrt_mean_square_slope, to_sigma0  # noqa: E402

EPS = 5.0 + 0.5j
FREQ = 5.3e9
THETA = np.radians(np.arange(0.0, 90.0, 1.0))  # 90 angles


def _interleaved(fns: dict, repeat: int) -> dict:
    for f in fns.values():
        f()
    times = {k: [] for k in fns}
    for _ in range(repeat):
        for k, f in fns.items():
            t0 = time.perf_counter()
            f()
            times[k].append(time.perf_counter() - t0)
    return {k: statistics.median(v) for k, v in times.items()}


def _sigma0_only(rough, k, ti, out):
    from emscatter.solvers.spm import compiled as spm_compiled
    from emscatter.solvers.spm import model as spm_solver

    dphi = np.full(ti.size, math.pi)
    if not spm_compiled.spm1_sigma0(rough, EPS, k, ti, ti, dphi, out):
        spm_solver._sigma0_first(rough, EPS, k, ti, ti, dphi, 0.0, out)


def _db_diff(a, b) -> float:
    a, b = np.asarray(a, float), np.asarray(b, float)
    peak = max(np.max(a), np.max(b))
    m = (a > 1e-6 * peak) & (b > 1e-6 * peak)
    return float(np.max(np.abs(10 * np.log10(a[m] / b[m])))) if m.any() else math.nan


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--label", default="current")
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args(argv)
    from smrt.interface.geometrical_optics import GeometricalOptics
    from smrt.interface.geometrical_optics_backscatter import GeometricalOpticsBackscatter
    from smrt.interface.iem_fung92 import IEM_Fung92

    import emscatter as em

    k = 2 * math.pi * FREQ / C_SPEED
    mu = np.cos(THETA)
    cases = {}

    # ---- backscatter, slightly rough (SPM / auto vs IEM)
    small = em.GaussianCorrelation(0.2 / k, 2.0 / k)
    iem = IEM_Fung92(
        roughness_rms=small.sigma,
        corr_length=small.length,
        autocorrelation_function="gaussian",
        warning_handling="none",
    )

    def smrt_iem():
        return to_sigma0(iem.diffuse_reflection_matrix(FREQ, 1.0, EPS, mu, mu, math.pi, 2), mu)

    def ems(method, rough, **kw):
        def f():
            return em.backscatter(
                rough,
                EPS,
                frequency=FREQ,
                theta_i=THETA,
                method=method,
                out_of_range="ignore",
                **kw,
            )

        return f

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t = _interleaved(
            {"smrt_iem": smrt_iem, "spm": ems("spm", small), "auto": ems("auto", small)},
            args.repeat,
        )
        ref = smrt_iem()
        for m in ("spm", "auto"):
            res = ems(m, small)()
            ours = np.stack([res.sigma0[0, 0], res.sigma0[1, 1]])
            cases[f"backscatter_{m}_vs_smrt_iem_fung92"] = {
                "geometries": THETA.size,
                "emscatter_s": t[m],
                "smrt_s": t["smrt_iem"],
                "speed_ratio_smrt_over_emscatter": t["smrt_iem"] / t[m],
                "max_abs_diff_db": _db_diff(ours[:, :60], ref[:, :60]),  # θ < 60°
                "method_used": res.method,
            }

        # where the time of one API call goes (who can make it faster)
        from emscatter.solvers.spm import model as spm_solver

        ti = THETA
        sig = np.empty((2, 2, ti.size))
        solver_only = _interleaved(
            {
                "solver spm.bistatic(coherent=False)": lambda: spm_solver.bistatic(
                    small, EPS, k, ti, ti, ti + math.pi, 0.0, coherent=False
                ),
                "first-order σ⁰ alone (dispatch → kernel or numpy)": lambda: _sigma0_only(
                    small, k, ti, sig
                ),
            },
            args.repeat,
        )
        cases["backscatter_spm_vs_smrt_iem_fung92"]["breakdown_s"] = {
            "api.backscatter(method='spm')": cases["backscatter_spm_vs_smrt_iem_fung92"][
                "emscatter_s"
            ],
            **solver_only,
        }

        # ---- backscatter, very rough (GO vs GO backscatter)
        big = em.GaussianCorrelation(10.0 / k, 60.0 / k)
        mss = smrt_mean_square_slope(big)
        gob = GeometricalOpticsBackscatter(mean_square_slope=mss, shadow_correction=True)
        th_go = THETA[1:]  # SMRT's tan θ at θ = 0 divides by zero
        mu_go = np.cos(th_go)

        def smrt_gob():
            return to_sigma0(
                gob.diffuse_reflection_matrix(FREQ, 1.0, EPS, mu_go, mu_go, math.pi, 2), mu_go
            )

        def ems_go():
            return em.backscatter(
                big, EPS, frequency=FREQ, theta_i=th_go, method="go", out_of_range="ignore"
            )

        t = _interleaved({"smrt": smrt_gob, "go": ems_go}, args.repeat)
        res = ems_go()
        cases["backscatter_go_vs_smrt_geometrical_optics_backscatter"] = {
            "geometries": th_go.size,
            "emscatter_s": t["go"],
            "smrt_s": t["smrt"],
            "speed_ratio_smrt_over_emscatter": t["smrt"] / t["go"],
            "max_abs_diff_db": _db_diff(
                np.stack([res.sigma0[0, 0], res.sigma0[1, 1]])[:, :70], smrt_gob()[:, :70]
            ),
            "note": "SMRT GO-backscatter uses the normal-incidence |R(0)|² (as emscatter GO at "
            "backscatter); compared for θ < 70°",
        }

        # ---- bistatic GO grid
        go = GeometricalOptics(mean_square_slope=mss, shadow_correction=True)
        dphi = np.linspace(0.0, 2 * math.pi, 24, endpoint=False) + 0.01  # avoid exactly π
        mu_s = np.cos(np.radians(np.linspace(1.0, 89.0, 45)))
        mu_i = np.cos(np.radians([10.0, 25.0, 40.0, 55.0, 70.0, 80.0]))
        ti_g = np.arccos(mu_i)[None, None, :]
        ts_g = np.arccos(mu_s)[None, :, None]
        ps_g = dphi[:, None, None]

        def smrt_go():
            return to_sigma0(
                go.diffuse_reflection_matrix(FREQ, 1.0, EPS, mu_s, mu_i, dphi, 2),
                mu_i[None, None, :],
            )

        def ems_bi():
            return em.bistatic(
                big,
                EPS,
                frequency=FREQ,
                theta_i=ti_g,
                theta_s=ts_g,
                phi_s=ps_g,
                method="go",
                shadowing="correlated",
                out_of_range="ignore",
            )

        t = _interleaved({"smrt": smrt_go, "go": ems_bi}, args.repeat)
        keep = np.degrees(np.arccos(mu_s)) <= 84.0  # SMRT clips cosθ at 0.1 (θ > 84.3°)
        a, b = ems_bi().sigma0[:, :, :, keep], smrt_go()[:, :, :, keep]
        cases["bistatic_go_vs_smrt_geometrical_optics"] = {
            "geometries": int(np.prod(a.shape[2:])),
            "emscatter_s": t["go"],
            "smrt_s": t["smrt"],
            "speed_ratio_smrt_over_emscatter": t["smrt"] / t["go"],
            "max_abs_diff_db_copol": max(_db_diff(a[0, 0], b[0, 0]), _db_diff(a[1, 1], b[1, 1])),
            "max_abs_diff_db_crosspol": max(_db_diff(a[0, 1], b[0, 1]), _db_diff(a[1, 0], b[1, 0])),
            "note": "agreement over θs ≤ 84° (SMRT's GO clips cosθ at 0.1)",
        }
    for part, sec in cases["backscatter_spm_vs_smrt_iem_fung92"]["breakdown_s"].items():
        print(f"  SPM backscatter, 90 angles: {part:52s} {sec * 1e6:8.1f} µs")
    for name, c in cases.items():
        print(
            f"{name:56s} emscatter {c['emscatter_s'] * 1e3:8.2f} ms  SMRT {c['smrt_s'] * 1e3:8.2f}"
            f" ms  SMRT/emscatter ×{c['speed_ratio_smrt_over_emscatter']:.2f}  "
            f"Δ {c.get('max_abs_diff_db', c.get('max_abs_diff_db_copol')):.3g} dB"
        )
    info = machine("smrt")
    cmd = command()
    data = {
        "benchmark": "emscatter vs SMRT",
        "label": args.label,
        "command": cmd,
        "machine": info,
        "repeat": args.repeat,
        "eps": EPS,
        "frequency_hz": FREQ,
        "cases": cases,
    }
    write("peers", data)
    write(f"peers_{args.label}", data)
    _plot(data, cmd)
    return data


def _plot(data, cmd):
    import matplotlib.pyplot as plt

    cases = data["cases"]
    names = list(cases)
    fig, ax = plt.subplots(figsize=(8, 4.2))
    y = np.arange(len(names))
    r = [cases[n]["speed_ratio_smrt_over_emscatter"] for n in names]
    ax.barh(y, r, color=["C2" if v >= 1 else "C3" for v in r])
    for yy, v, n in zip(y, r, names, strict=True):
        c = cases[n]
        ax.annotate(
            f"×{v:.2f}  ({c['emscatter_s'] * 1e3:.2f} ms vs {c['smrt_s'] * 1e3:.2f} ms)",
            (v, yy),
            xytext=(4, 0),
            textcoords="offset points",
            va="center",
            fontsize=7,
        )
    ax.axvline(1, color="k", lw=0.8)
    ax.axvline(3, color="0.5", ls=":", lw=0.8)
    ax.set_xscale("log")
    ax.set_yticks(y, [n.replace("_vs_", "\nvs ") for n in names], fontsize=7)
    ax.set_xlabel("SMRT time / emscatter time (> 1: emscatter faster)")
    ax.set_title(f"emscatter vs SMRT, same inputs, one run ({data['label']})", fontsize=9)
    stamp(fig, data["machine"], cmd, data["repeat"])
    save(fig, "peers")


if __name__ == "__main__":
    main()
