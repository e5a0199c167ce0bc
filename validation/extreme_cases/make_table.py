"""The extreme cases of issue 11 and what each returns now: one command, one table.

    PYTHONPATH=src python validation/extreme_cases/make_table.py     # ≈ 2 min on 2 cores

Writes ``extreme_cases.csv`` and ``extreme_cases.md`` beside this file: per case the call,
the method used, the values (σ⁰ or emissivity, min/max over the angles), whether the result is
flagged (validity per angle, energy balance), the warning or error message a user sees, and the
wall time. Every case must answer: an exception is a clear error (its message is the row).
"""

from __future__ import annotations

import csv
import math
import os
import platform
import sys
import time
import warnings
from pathlib import Path

import numpy as np

import emscatter as em

HERE = Path(__file__).parent
K = 2 * math.pi  # λ = 1 m
GRAZING = np.radians([85.0, 88.0, 89.0])


def rough(ks, kl, kind="gaussian", **kw):
    return em.roughness(kind, sigma=ks / K, length=kl / K, **kw)


def emissivity(r, eps, th, method="auto", **kw):
    return lambda: em.emissivity(r, eps, wavelength=1.0, theta_i=th, method=method, **kw)


def backscatter(r, eps, th, method="auto", **kw):
    return lambda: em.backscatter(r, eps, wavelength=1.0, theta_i=th, method=method, **kw)


def _cases():
    th_corner = np.radians([0.0, 45.0, 89.99])
    yield (
        "issue: GO σ=0.6 ℓ=4 λ=1 ε=17+2i, e at 85/88/89°",
        emissivity(em.GaussianCorrelation(0.6, 4.0), 17 + 2j, GRAZING, "go"),
    )
    yield (
        "issue: same, method=auto",
        emissivity(em.GaussianCorrelation(0.6, 4.0), 17 + 2j, GRAZING),
    )
    yield (
        "issue: SPM PEC kσ=0.2 kℓ=1, e at 85/88/89°",
        emissivity(rough(0.2, 1.0), "pec", GRAZING, "spm"),
    )
    yield (
        "issue: PO kσ=1 kℓ=10 ε=17+2i, e at 85/88/89°",
        emissivity(rough(1.0, 10.0), 17 + 2j, GRAZING, "po"),
    )
    yield (
        "issue: PO emissivity at kσ=1e3 (kℓ=1e4), 0/45/89.99°",
        emissivity(rough(1e3, 1e4), 17 + 2j, th_corner, "po"),
    )
    yield (
        "GO→PO fallback: σ=0.3 ℓ=6, e at 20/60/80°",
        emissivity(em.GaussianCorrelation(0.3, 6.0), 17 + 2j, np.radians([20.0, 60.0, 80.0])),
    )
    yield (
        "issue: frequency=5.4 (GHz meant)",
        lambda: em.backscatter(rough(0.1, 5.0), 5.0, frequency=5.4, theta_i=0.3),
    )
    yield (
        "issue: eps=True",
        lambda: em.backscatter(rough(0.1, 5.0), True, wavelength=1, theta_i=0.3),
    )
    yield (
        "issue: coherent_pol('x')",
        lambda: em.bistatic(
            rough(0.1, 5.0), 5.0, wavelength=1, theta_i=0.3, theta_s=0.3, phi_s=0.0
        ).coherent_pol("x"),
    )
    yield (
        "theta_i = 100° in radians",
        lambda: em.backscatter(rough(0.1, 5), 5.0, wavelength=1, theta_i=math.radians(100)),
    )
    # validity gaps found by the energy check: the method says valid, the API flags (notes)
    yield (
        "gap: PO exponential kσ=25 kℓ=9608 ε=−451.6, e at 64.8°",
        emissivity(
            rough(25.0113, 9608.1946, "exponential"),
            -451.60608908293074,
            np.radians([64.7938]),
            "po",
        ),
    )
    yield (
        "quadrature: SPM kσ=0.1 kℓ=1 ε=−1e4 at 57.3°, tol=1e-3 (estimate 1.3e-4 < actual 1.6e-4)",
        emissivity(rough(0.1, 1.0), -1e4 + 0j, np.array([1.0]), "spm", tol=1e-3),
    )
    for ks in (1e-6, 1e3):
        for kl in (1e-3, 1e6):
            for eps in ("pec", 1e9j, -20 + 1j):
                yield (
                    f"corner: kσ={ks:g} kℓ={kl:g} ε={eps}, e at 0/45/89.99°",
                    emissivity(rough(ks, kl), eps, th_corner),
                )
                yield (
                    f"corner: kσ={ks:g} kℓ={kl:g} ε={eps}, σ⁰ backscatter",
                    backscatter(rough(ks, kl), eps, th_corner),
                )
    for kind, extra in (
        ("exponential", {}),
        ("power-law", {"hurst": 0.01}),
        ("power-law", {"hurst": 0.99}),
    ):
        for ks, kl in ((1e-3, 1e3), (10.0, 100.0)):
            yield (
                f"{kind} {extra or ''} kσ={ks:g} kℓ={kl:g} ε=17+2i, e at 0/45/89.99°",
                emissivity(rough(ks, kl, kind, **extra), 17 + 2j, th_corner),
            )


def _values(res) -> tuple[str, str, str]:
    if isinstance(res, em.Scattering):
        s = res.sigma0[[0, 1], [0, 1]]
        flags = res.info["validity"]
        return f"σ⁰ hh,vv ∈ [{np.nanmin(s):.3g}, {np.nanmax(s):.3g}]", res.method, _flag(flags)
    if hasattr(res, "emissivity"):
        e = res.emissivity
        return (
            f"e ∈ [{np.nanmin(e):.4g}, {np.nanmax(e):.4g}]",
            res.method,
            _flag(res.info["validity"], res.energy_ok),
        )
    return f"{np.asarray(res).round(6).tolist()}", "", ""


def _flag(report, energy_ok=None) -> str:
    parts = []
    if not report.get("roughness_valid", report.get("valid", True)):
        parts.append("roughness invalid")
    angle = np.asarray(report.get("angle_valid", True))
    if not angle.all():
        parts.append(f"{int((~angle).sum())} angle(s) invalid")
    if energy_ok is not None and not np.all(energy_ok):
        parts.append(f"energy broken at {int((~np.asarray(energy_ok)).sum())}")
    return "; ".join(parts) or "valid"


def run() -> list[dict]:
    rows = []
    for label, call in _cases():
        t0 = time.perf_counter()
        with warnings.catch_warnings(record=True) as rec:
            warnings.simplefilter("always")
            try:
                values, method, flags = _values(call())
                outcome = "answer"
            except Exception as exc:  # the row records the message a user sees
                values, method, flags = "", "", ""
                outcome = f"{type(exc).__name__}: {' '.join(str(exc).split())}"
        dt = time.perf_counter() - t0
        said = " | ".join(dict.fromkeys(" ".join(str(w.message).split()) for w in rec))
        rows.append(
            {
                "case": label,
                "method": method,
                "values": values,
                "flags": flags,
                "outcome": outcome,
                "warnings": said,
                "seconds": f"{dt:.2f}",
            }
        )
        print(f"{dt:6.2f} s  {label}: {values} {flags} {outcome[:60]}", flush=True)
    return rows


def _cell(text: str, limit: int = 220) -> str:
    text = text.replace("|", "\\|")
    return text if len(text) <= limit else text[: limit - 1] + "…"


def main() -> None:
    rows = run()
    fields = list(rows[0])
    with open(HERE / "extreme_cases.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fields)
        w.writeheader()
        w.writerows(rows)
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    lines = [
        "# Extreme cases: what each returns",
        "",
        f"Made by `PYTHONPATH=src python validation/extreme_cases/make_table.py` — emscatter "
        f"{em.__version__}, Python {platform.python_version()}, numpy {np.__version__}, "
        f"{os.cpu_count()} CPUs, load average {load:.1f} at the start (times are wall clock on a "
        "shared machine).",
        "",
        "| case | method | values | flags | outcome | warning shown | s |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append("| " + " | ".join(_cell(r[f]) for f in fields) + " |")
    (HERE / "extreme_cases.md").write_text("\n".join(lines) + "\n")
    print(f"wrote {HERE / 'extreme_cases.csv'} and extreme_cases.md", file=sys.stderr)


if __name__ == "__main__":
    main()
