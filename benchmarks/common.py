"""Shared benchmark plumbing: machine/version record, timing (median of repeats), the stamp
every figure carries (machine, versions, load, median of N, the command), JSON output.

Not part of the package: benchmarks import it as ``from common import ...`` (run_all.py puts
this folder on ``sys.path``; each script also runs on its own from the repository root).
"""

from __future__ import annotations

import importlib.metadata as md
import json
import os
import platform
import shlex
import statistics
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results"
ROOT = HERE.parent
if str(ROOT / "src") not in sys.path:  # the source tree first, as the house rules run it
    sys.path.insert(0, str(ROOT / "src"))


def cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def versions(*extra: str) -> dict:
    out = {"python": platform.python_version()}
    for name in ("emscatter", "numpy", "scipy", "numba", *extra):
        try:
            out[name] = md.version(name)
        except md.PackageNotFoundError:
            out[name] = None
    try:  # the source tree's version (the installed metadata may be older)
        import emscatter

        out["emscatter"] = emscatter.__version__
    except ImportError:
        pass
    return out


def machine(*extra: str) -> dict:
    return {
        "cpu": cpu_model(),
        "cores": os.cpu_count(),
        "platform": platform.platform(),
        "load_average": list(os.getloadavg()),
        "versions": versions(*extra),
        "date": time.strftime("%Y-%m-%d %H:%M:%S %z"),
    }


def command() -> str:
    """The command that reproduces the current script's results."""
    rel = Path(sys.argv[0]).resolve()
    try:
        rel = rel.relative_to(ROOT)
    except ValueError:
        pass
    return " ".join(["python", str(rel), *map(shlex.quote, sys.argv[1:])])


def timeit(fn, repeat: int = 5, warmup: int = 1) -> dict:
    """Median and min wall/CPU time of ``repeat`` calls after ``warmup`` calls [s]."""
    for _ in range(warmup):
        fn()
    wall, cpu = [], []
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        fn()
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    return {
        "median_s": statistics.median(wall),
        "min_s": min(wall),
        "cpu_median_s": statistics.median(cpu),
        "repeat": repeat,
    }


def stamp(fig, info: dict, cmd: str, repeat: int | None = None) -> None:
    """Footer on a figure: machine, versions, load average, repeats, the command."""
    v = info["versions"]
    vs = ", ".join(f"{k} {v[k]}" for k in ("emscatter", "numpy", "scipy", "numba") if v.get(k))
    extra = [
        f"{k} {val}"
        for k, val in v.items()
        if k not in ("python", "emscatter", "numpy", "scipy", "numba") and val
    ]
    load = ", ".join(f"{x:.1f}" for x in info["load_average"])
    rep = f"median of {repeat} runs · " if repeat else ""
    lines = [
        f"{info['cpu']} · {info['cores']} cores · Python {v['python']} · {vs}"
        + (" · " + ", ".join(extra) if extra else ""),
        f"{rep}load average {load} · {info['date']}",
        f"$ {cmd}",
    ]
    fig.text(
        0.01, 0.005, "\n".join(lines), fontsize=6.5, family="monospace", va="bottom", color="0.3"
    )
    fig.subplots_adjust(bottom=max(fig.subplotpars.bottom, 0.2))


def write(name: str, data: dict) -> Path:
    RESULTS.mkdir(parents=True, exist_ok=True)
    path = RESULTS / f"{name}.json"
    tmp = path.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(data, indent=2, default=_jsonable) + "\n")
    os.replace(tmp, path)
    return path


def _jsonable(o):
    import numpy as np

    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, complex):
        return str(o)
    return str(o)


def save(fig, name: str) -> Path:
    from emscatter.io import save_figure

    return save_figure(fig, RESULTS / f"{name}.png")
