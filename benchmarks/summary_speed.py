"""SUMMARY rows for the public-API speed targets (issue 22) and `auto`'s cost (issue 20).

Called by :mod:`summary`. Benchmarks that write under a name of the caller's choosing
(``bench_api.py --out NAME``) are read from their newest run (the ``machine.date`` stamped in each
file); every row names the file it came from, so a reader can see which run it quotes.
"""

from __future__ import annotations

import json
from pathlib import Path

RESULTS = Path(__file__).resolve().parent / "results"


def _met(ok) -> str:
    return "**yes**" if ok else "no"


def _machine(d: dict) -> dict:
    return d.get("machine") or d.get("machine_info") or {}


def _newest(pattern: str, part: str) -> tuple[str, dict] | tuple[None, None]:
    """The newest ``results/<pattern>`` file holding ``part`` (by its machine date)."""
    best = (None, None, "")
    for p in RESULTS.glob(pattern):
        try:
            d = json.loads(p.read_text())
        except (json.JSONDecodeError, OSError):
            continue
        if not isinstance(d, dict) or part not in d:
            continue
        date = str(_machine(d).get("date", ""))
        if date >= best[2]:
            best = (p.stem, d, date)
    return best[0], best[1]


def _load(name: str) -> dict | None:
    p = RESULTS / f"{name}.json"
    try:
        return json.loads(p.read_text())
    except (json.JSONDecodeError, OSError):
        return None


def _load_note(d: dict) -> str:
    la = _machine(d).get("load_average")
    return f" (load {la[0]:.1f})" if la else ""


def _api_rows() -> list[tuple]:
    name, d = _newest("api_speed*.json", "speed")
    if not d:
        return []
    out, cmd, speed = [], d.get("command", "python benchmarks/bench_api.py"), d["speed"]
    for key, c in speed.items():
        method = key.split("_")[0]
        api, kernel = c.get("api_numba", {}).get("per_s"), c.get("kernel", {}).get("per_s")
        if api is None:
            continue
        out.append(
            (
                f"{method.upper()} through `emscatter.bistatic`, {key.split('_')[-1]} geometries",
                "≥ 2.5e7 σ⁰/s",
                f"{api:.3g}/s (kernel alone {kernel:.3g}/s; API/solver "
                f"×{c.get('api_over_solver_numba', float('nan')):.2f}){_load_note(d)}",
                _met(api >= 2.5e7),
                cmd,
                name,
            )
        )
        ratio = c.get("api_numba_over_numpy")
        if method == "go" and ratio is not None:
            out.append(
                (
                    "GO through the API: compiled / numpy",
                    "≥ 8×",
                    f"×{ratio:.2f}",
                    _met(ratio >= 8),
                    cmd,
                    name,
                )
            )
        ct = c.get("api_numba_over_cook_torrance")
        if ct is not None:
            out.append(
                (
                    "GO through the API / a plain numpy Cook–Torrance",
                    "≥ 4×",
                    f"×{ct:.2f}",
                    _met(ct >= 4),
                    cmd,
                    name,
                )
            )
    return out


def _cold_rows() -> list[tuple]:
    name, d = _newest("api_cold*.json", "cold")
    if not d:
        return []
    cold = d["cold"]
    limit = cold.get("limit_s", 2.0)
    after = {k.split("/", 1)[1]: v for k, v in cold.items() if k.startswith("after_setup/")}
    if not after:
        return []
    slow = {k: v["first_call_s"] for k, v in after.items() if v["first_call_s"] > limit}
    worst = max(after.items(), key=lambda kv: kv[1]["first_call_s"])
    measured = (
        f"{len(after) - len(slow)} of {len(after)} under {limit:g} s; slowest {worst[0]} "
        f"{worst[1]['first_call_s']:.2f} s"
        + (f"; over: {', '.join(f'{k} {v:.2f} s' for k, v in slow.items())}" if slow else "")
        + _load_note(d)
    )
    return [
        (
            "first call per method in a fresh process after `make setup`",
            f"each < {limit:g} s",
            measured,
            _met(not slow),
            d.get("command", "python benchmarks/bench_api.py --parts cold"),
            name,
        )
    ]


def _iem_smrt_rows() -> list[tuple]:
    d = _load("iem_smrt")
    if not d:
        return []
    w = d.get("worst_median_ratio_over_rows", {})
    out = []
    for key, label in (
        ("smrt_converged/emscatter_default", "default configuration"),
        ("smrt_converged/emscatter_fung92", "1992 configuration"),
    ):
        if key in w:
            out.append(
                (
                    f"IEM backscatter through the API vs SMRT `iem_fung92` ({label}), worst of "
                    "1–1000 angles × kσ 0.1–2.5",
                    "SMRT/emscatter ≥ 1.2",
                    f"×{w[key]:.2f}{_load_note(d)}",
                    _met(w[key] >= 1.2),
                    d.get("command", "benchmarks/bench_iem_smrt.py"),
                    "iem_smrt",
                )
            )
    return out


def _farm_rows() -> list[tuple]:
    out = []
    # full-size tables first (the newest 90×180 run), then the small
    for name in ("brdf_farm_s7", "brdf_farm"):
        out += _farm_file_rows(name)
    return out


def _farm_file_rows(name: str) -> list[tuple]:
    d = _load(name)
    if not d:
        return []
    out = []
    for method, r in d.get("rows", {}).items():
        if "farm_speedup" not in r:
            continue
        out.append(
            (
                f"BRDF farm, {d.get('workers', 2)}-worker LocalCluster: {r.get('what', method)}",
                "≥ 1.7× serial, identical",
                f"×{r['farm_speedup']:.2f} ({r.get('per_table_serial_ms', float('nan')):.3g} "
                f"ms/table serial), identical {r.get('identical')}{_load_note(d)}",
                _met(r["farm_speedup"] >= 1.7 and r.get("identical")),
                d.get("command", "python benchmarks/bench_brdf_farm.py"),
                name,
            )
        )
        for key, how in (
            ("farm_out_dir_speedup", "compressed .npz"),
            ("farm_out_dir_stored_speedup", "stored .npz, `compress=False`"),
        ):
            if key in r:
                out.append(
                    (
                        f"BRDF farm with `out_dir` (the workers write {how}; serial writes "
                        f"the same files): {method.upper()} tables of {name}",
                        "≥ 1.7× serial, identical",
                        f"×{r[key]:.2f}{_load_note(d)}",
                        _met(r[key] >= 1.7 and r.get("identical")),
                        d.get("command", "python benchmarks/bench_brdf_farm.py"),
                        name,
                    )
                )
    return out


def _emissivity_rows() -> list[tuple]:
    name, d = _newest("emissivity*.json", "pyi2em")
    if not d:
        return []
    eq = d["pyi2em"].get("equal_accuracy")
    if not eq:
        return []
    return [
        (
            "IEM emissivity per θi vs pyi2em at equal accuracy",
            f"≤ {eq.get('target_ratio', 10):g}×",
            f"×{eq['ratio']:.1f} ({eq['emscatter_ms_per_theta']:.3g} ms vs "
            f"{eq['pyi2em_ms_per_theta']:.3g} ms; max error {eq['emscatter_max_abs_error']:.2g})"
            + _load_note(d),
            _met(eq["ratio"] <= eq.get("target_ratio", 10)),
            d.get("command", "python benchmarks/bench_emissivity.py"),
            name,
        )
    ]


def _auto_rows() -> list[tuple]:
    d = _load("auto")
    if not d or "mean_ms" not in d:
        return []
    m = d["mean_ms"]
    ratio = m["after_hv_s"] / m["before_s"]
    return [
        (
            f"`auto` backscatter with hv, {len(d.get('rows', []))} cases: new case (hv computed) "
            "/ the hard pick without hv",
            "≤ 1.5×",
            f"×{ratio:.2f} ({m['before_s']:.3g} → {m['after_hv_s']:.3g} ms per case; repeated "
            f"call {m['after_s']:.3g} ms){_load_note(d)}",
            _met(ratio <= 1.5),
            d.get("command", "python benchmarks/bench_auto.py"),
            "auto",
        )
    ]


def rows() -> list[tuple]:
    """(what, target, measured, met, command, file) rows, in the order of issue 22's list."""
    return (
        _api_rows()
        + _cold_rows()
        + _iem_smrt_rows()
        + _farm_rows()
        + _emissivity_rows()
        + _auto_rows()
    )
