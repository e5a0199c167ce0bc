"""Build ``results/SUMMARY.md`` from the JSON files in ``results/`` (run_all.py calls it).

python benchmarks/summary.py
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import summary_speed

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results"


def _load(name):
    p = RESULTS / f"{name}.json"
    return json.loads(p.read_text()) if p.exists() else None


def _fmt(x, unit=""):
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "—"
    if isinstance(x, float):
        s = f"{x:.3g}"
    else:
        s = str(x)
    return s + unit


def _met(ok):
    return "**yes**" if ok else "no"


def _machine_line(d):
    m = d["machine"]
    load = ", ".join(f"{v:.1f}" for v in m.get("load_average", []))
    return f"{m.get('cpu', '?')}, {m.get('cores', '?')} cores, load {load}, {m.get('date', '')}"


def rows() -> list[tuple]:
    out = []
    k = _load("kernels")
    if k:
        for case, c in k["cases"].items():
            out.append(
                (
                    f"compiled σ⁰ {case}: speed-up over numpy",
                    "≥ 10×",
                    f"×{c['speedup']:.1f} ({c['numpy_per_s']:.3g}/s → {c['compiled_per_s']:.3g}/s)",
                    _met(c["speedup"] >= 10),
                    k["command"],
                    "kernels",
                )
            )
            out.append(
                (
                    f"compiled σ⁰ {case}: fraction of the roofline",
                    "≥ 1/3 (within 3×)",
                    f"{c['fraction_of_roofline']:.2f} of {c['roofline_per_s']:.3g}/s "
                    f"({c['roofline_bound']}-bound)",
                    _met(c["fraction_of_roofline"] >= 1 / 3),
                    k["command"],
                    "kernels",
                )
            )
        out.append(
            (
                "kernels: first call in a fresh process (compile or load from cache)",
                "—",
                _fmt(k["first_call_s"], " s"),
                "",
                k["command"],
                "kernels",
            )
        )
    p = _load("peers")
    if p:
        for case, c in p["cases"].items():
            target = 3.0 if case.startswith("bistatic") else 1.0
            agree = c.get("max_abs_diff_db", c.get("max_abs_diff_db_copol"))
            out.append(
                (
                    f"{case} [{p['label']}]",
                    f"SMRT/emscatter ≥ {target:g}",
                    f"×{c['speed_ratio_smrt_over_emscatter']:.2f} ({c['emscatter_s'] * 1e3:.3g}"
                    f" ms vs {c['smrt_s'] * 1e3:.3g} ms); max Δ {agree:.2g} dB",
                    _met(c["speed_ratio_smrt_over_emscatter"] >= target),
                    p["command"],
                    "peers",
                )
            )
    iem = _load("iem")
    if iem and "ratio_smrt_fung92_over_iem_copol" in iem:
        cmd = iem.get("command", "PYTHONPATH=src python benchmarks/bench_iem.py")
        for n, ratio in iem["ratio_smrt_fung92_over_iem_copol"].items():
            ours = iem["seconds_median"][f"iem_copol/{n}"]
            theirs = iem["smrt_seconds_median"][f"smrt_iem_fung92/{n}"]
            out.append(
                (
                    f"IEM co-pol backscatter vs SMRT iem_fung92, {n} angle(s)",
                    "SMRT/emscatter ≥ 1",
                    f"×{ratio:.2f} ({ours * 1e3:.3g} ms vs {theirs * 1e3:.3g} ms)",
                    _met(ratio >= 1),
                    cmd,
                    "iem",
                )
            )
    g = _load("generate")
    if g:
        r = g["ratios"]
        for peer in (
            "surfacetopography_fourier_synthesis_4096",
            "tamaas_filter_4096",
            "tamaas_random_phase_4096",
        ):
            key = f"{peer}_over_periodic"
            if key in r:
                out.append(
                    (
                        f"surface 4096²: {peer.replace('_4096', '')} time / emscatter periodic",
                        "≥ 2×",
                        f"×{r[key]:.2f}",
                        _met(r[key] >= 2),
                        g["command"],
                        "generate",
                    )
                )
        if "periodic_over_filter_pass" in r:
            v = r["periodic_over_filter_pass"]
            out.append(
                (
                    "surface 4096²: emscatter periodic / one scipy.fft filter pass",
                    "≤ 1.2×",
                    f"×{v:.2f}",
                    _met(v <= 1.2),
                    g["command"],
                    "generate",
                )
            )
    d = _load("demo")
    if d:
        out.append(
            (
                f"demo{' --quick' if d['quick'] else ''}, warm vs cold cache",
                "≥ 5×",
                f"×{d['speedup']:.1f} ({d['cold_s']:.1f} s → {d['warm_s']:.1f} s), "
                f"{len(d['files_differing'])} of {len(d['files'])} files differ",
                _met(d["speedup"] >= 5 and not d["files_differing"]),
                d["command"],
                "demo",
            )
        )
    s = _load("scaling")
    if s:
        for name, ser in s["series"].items():
            last = ser["rows"][-1]
            out.append(
                (
                    f"cost growth: {name}",
                    "(report)",
                    f"time ∝ n^{ser['time_exponent']:.2f}, memory ∝ n^"
                    f"{ser['memory_exponent']:.2f}; n = {last['size']:g}: "
                    f"{last['seconds']:.3g} s, {last['peak_bytes'] / 2**20:.3g} MiB",
                    "",
                    s["command"],
                    "scaling",
                )
            )
    ra = _load("radio")
    if ra:
        for name, c in ra["configs"].items():
            med = c["median_seconds"]
            out.append(
                (
                    f"Sionna RT {name}: emscatter / built-in material",
                    f"≤ {c['target']}×",
                    f"{c['ratio']:.2f}× ({med['builtin']:.3g} s → {med['emscatter']:.3g} s)",
                    _met(c["meets_target"]),
                    ra["command"],
                    "radio",
                )
            )
    pa = _load("pareto")
    if pa:
        for st in pa["studies"].values():
            pts = "; ".join(
                f"{r['knob']:g}: {r['error']:.2g} in {r['seconds']:.3g} s" for r in st["rows"]
            )
            out.append(
                (f"run time vs error: {st['label']}", "(Pareto)", pts, "", pa["command"], "pareto")
            )
    return out + summary_speed.rows()


def write_summary() -> Path:
    lines = [
        "# Benchmark summary (generated by benchmarks/summary.py — do not edit)",
        "",
        "Each row: the target, what was measured, and the command that reproduces it. "
        "Figures: `results/<file>.png` (each carries machine, versions, load, repeats and "
        "its command).",
        "",
    ]
    lines += ["| what | target | measured | met | file | command |", "|---|---|---|---|---|---|"]
    for what, target, measured, met, cmd, file in rows():
        lines.append(
            f"| {what} | {target} | {measured} | {met} | `results/{file}.json` | `{cmd}` |"
        )
    lines += ["", "Machines the results were measured on:", ""]
    for p in sorted(RESULTS.glob("*.json")):
        try:
            d = json.loads(p.read_text())
        except json.JSONDecodeError:
            continue
        if isinstance(d, dict) and isinstance(d.get("machine"), dict) and "cpu" in d["machine"]:
            lines.append(f"- `{p.name}`: {_machine_line(d)}")
    figs = sorted(RESULTS.glob("*.png"))
    lines += ["", "Figures:", ""] + [f"![{f.stem}]({f.name})" for f in figs]
    path = RESULTS / "SUMMARY.md"
    path.write_text("\n".join(lines) + "\n")
    return path


if __name__ == "__main__":
    print(write_summary())
