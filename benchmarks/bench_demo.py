"""The demo with a cold and a warm result cache (``make demo`` twice).

    python benchmarks/bench_demo.py [--quick]      → benchmarks/results/demo.json, demo.png

Runs ``emscatter demo --out <tmp>`` twice in fresh processes with one new, empty cache folder
(``EMSCATTER_CACHE_DIR``): the first fills it, the second reads it. Checks that both runs wrote
byte-identical files, and records both wall times and their ratio (target ≥ 5×).
"""

from __future__ import annotations

import argparse
import filecmp
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import ROOT, command, machine, save, stamp, write  # noqa: E402


def _run(out: Path, cache_dir: Path, quick: bool) -> float:
    env = {**os.environ, "EMSCATTER_CACHE_DIR": str(cache_dir), "EMSCATTER_CACHE": "1"}
    env["PYTHONPATH"] = str(ROOT / "src") + os.pathsep + env.get("PYTHONPATH", "")
    cmd = [sys.executable, "-m", "emscatter", "demo", "--out", str(out)] + (["--quick"] * quick)
    t0 = time.perf_counter()
    subprocess.run(cmd, env=env, check=True, capture_output=True)
    return time.perf_counter() - t0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    a = ap.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="emscatter-bench-demo-") as tmp:
        tmp = Path(tmp)
        cold = _run(tmp / "cold", tmp / "cache", a.quick)
        warm = _run(tmp / "warm", tmp / "cache", a.quick)
        files = sorted(str(p.relative_to(tmp / "cold")) for p in (tmp / "cold").rglob("*.*"))
        warm_files = sorted(str(p.relative_to(tmp / "warm")) for p in (tmp / "warm").rglob("*.*"))
        only_in_one = sorted(set(files) ^ set(warm_files))
        diff = [
            f
            for f in files
            if f in warm_files and not filecmp.cmp(tmp / "cold" / f, tmp / "warm" / f, False)
        ]
        cache_mb = sum(p.stat().st_size for p in (tmp / "cache").rglob("*.npz")) / 2**20
    data = {
        "benchmark": "demo, cold vs warm result cache",
        "command": command(),
        "machine": machine(),
        "quick": a.quick,
        "cold_s": cold,
        "warm_s": warm,
        "speedup": cold / warm,
        "files": files,
        "files_differing": diff,
        "only_in_one": only_in_one,
        "cache_mib": cache_mb,
    }
    print(
        f"demo{' --quick' * a.quick}: cold {cold:.1f} s, warm {warm:.1f} s → ×{cold / warm:.1f}"
        f"; {len(files)} files, {len(diff)} differ; cache {cache_mb:.1f} MiB"
    )
    write("demo", data)
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5.5, 3.4))
    ax.barh(["warm cache", "cold cache"], [warm, cold], color=["C2", "C0"])
    for y, v in enumerate([warm, cold]):
        ax.annotate(f"{v:.1f} s", (v, y), xytext=(3, 0), textcoords="offset points", va="center")
    ax.set_xlabel("wall time of `emscatter demo` [s]")
    ax.set_title(
        f"demo{' --quick' * a.quick} with the result cache: ×{cold / warm:.1f}", fontsize=9
    )
    stamp(fig, data["machine"], data["command"], 1)
    save(fig, "demo")
    return data


if __name__ == "__main__":
    main()
