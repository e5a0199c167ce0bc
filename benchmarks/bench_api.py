"""What users call, timed: ``emscatter.bistatic`` against the solver and the kernel, and the
first call of every method in a fresh process (empty caches, and after ``make setup``).

    python benchmarks/bench_api.py [--sizes 10000 1000000] [--repeat 7] [--parts speed cold]
                                   [--methods spm go po iem auto] [--kinds ...] [--states ...]
                                   [--out api]
    → benchmarks/results/api.json

speed — SPM1, GO and PO on random full-polarization geometries (θi, θs uniform in [0°, 89.9°],
φs uniform; one dielectric ε = 17 + 2i), at each size: the compiled kernel alone (SPM1, GO;
PO has no single kernel), the solver's ``bistatic`` and the public ``emscatter.bistatic``
(``out_of_range="ignore"``: every validity check runs and is recorded), each with
``EMSCATTER_KERNELS=numba`` and ``=numpy``. The contenders are alternated in one process
(round after round, one call each), result cache off (``EMSCATTER_CACHE=0``); medians of
``--repeat`` rounds after one warm-up round (compilation excluded: that is ``cold``).
Throughput = geometries per second (one geometry = all four σ⁰_pq). Each timing also records
the process CPU time (``cpu_median_s``, all threads): on a shared machine the ratio of CPU times
(``api_over_solver_numba_cpu``) shows the work the API adds, whatever the wall clock waited.
GO rows add the kernel writing into a fresh output array each call (``kernel_fresh_out``: the
floor of a call that returns new arrays — the page faults of 32 MB at 1e6) and a plain numpy
Cook–Torrance (:func:`cook_torrance`, one polarization), the peer
the compiled path is compared with. ``api_numba_plain_checks`` is the compiled API with its
input checks done by numpy (``check_angle``: min, max, then a copy) instead of the fused
check-and-copy pass of :mod:`emscatter.kernels.checks` — the before/after of that change in one
process (``api_plain_checks_over_api_numba``).

cold — per method, a fresh Python process times ``import emscatter`` and then its first call:
``backscatter`` at 91 angles (the default kernel selection) and ``bistatic`` at 1e5 geometries
(compiled path) and ``emissivity`` at 9 θi (0–80°, default tolerance; IEM with its hv term and,
as ``emissivity_copol``, without), twice: with an empty numba cache folder
(``EMSCATTER_NUMBA_CACHE_DIR`` new) and after ``python -m emscatter.warm`` filled that folder
(what ``make setup`` runs). ``auto`` is the newcomer's call: ``backscatter(rough,
"medium_dry_ground", frequency=5.4e9, ...)`` and ``emissivity(rough, 17 + 2i, ...)``. Each row
has the import time, the first and second call (result cache off) and ``under_limit``: import +
first call < 2 s (issue 22's target after setup), and ``compiled``: the kernels the call
compiled into the cache folder (new ``.nbc`` files: a new kernel or a new signature of one;
after setup: none expected — a kernel listed there is missing from :mod:`emscatter.warm`, or
is called with other argument types than its warm-up, e.g. a read-only array). ``--kinds`` /
``--states`` select rows.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import numpy as np  # noqa: E402
from common import ROOT, command, machine, write  # noqa: E402

EPS = 17 + 2j
LAM = 0.1  # wavelength [m]
K = 2 * math.pi / LAM


def _roughness(method):
    from emscatter.spectra import GaussianCorrelation

    return {
        "spm": GaussianCorrelation(0.1 / K, 2.0 / K),  # kσ = 0.1, kℓ = 2
        "go": GaussianCorrelation(0.3, 1.5),  # kσ ≈ 19, rms slope ≈ 0.28
        "po": GaussianCorrelation(0.4 / K, 6.0 / K),  # kσ = 0.4, kℓ = 6
        "iem": GaussianCorrelation(0.5 / K, 4.0 / K),
        "auto": GaussianCorrelation(0.01, 0.1),
    }[method]


def cook_torrance(ti, ts, ps, eps, m2):
    """A plain numpy Cook–Torrance σ⁰ of one polarization (h) [-], the peer a renderer writes:
    ``σ⁰ = 4π cosθi cosθs f_r = π D G F`` with ``f_r = D G F/(4 cosθi cosθs)`` — Beckmann
    ``D = exp(−tan²θh/m²)/(π m² cos⁴θh)``, separable Smith ``G = G1(θi) G1(θs)`` in Walter et
    al.'s rational form (2007, EGSR, eq. 27), the exact Fresnel ``|R_h|²`` at the half-vector
    (Cook & Torrance 1982, ACM TOG 1, 7). ``m2`` = total mean-square slope; φi = 0."""
    si, ci, ss, cs = np.sin(ti), np.cos(ti), np.sin(ts), np.cos(ts)
    hx, hy, hz = ss * np.cos(ps) - si, ss * np.sin(ps), cs + ci  # wi = (−sinθi, 0, cosθi)
    hn = np.sqrt(hx * hx + hy * hy + hz * hz)
    ch = hz / hn
    c2 = ch * ch
    d = np.exp(-(1.0 - c2) / (c2 * m2)) / (math.pi * m2 * c2 * c2)

    def g1(c, s):
        a = c / (math.sqrt(m2) * np.maximum(s, 1e-12))  # cotθ/α, α² = m²
        return np.where(a < 1.6, (3.535 * a + 2.181 * a * a) / (1 + 2.276 * a + 2.577 * a * a), 1.0)

    cl = (ci * hz - si * hx) / hn  # cos of the local incidence angle, wi·h
    w = np.sqrt(eps - 1.0 + cl * cl)
    f = np.abs((cl - w) / (cl + w)) ** 2
    return math.pi * d * g1(ci, si) * g1(cs, ss) * f


def _contenders(method, n):
    """``{name: callable}`` for one method and size (module docstring)."""
    import emscatter as em
    from emscatter import solvers

    rng = np.random.default_rng(0)
    ti = rng.uniform(0, math.radians(89.9), n)
    ts = rng.uniform(0, math.radians(89.9), n)
    ps = rng.uniform(-math.pi, math.pi, n)
    rough, mod = _roughness(method), solvers.get(method)
    out = np.empty((2, 2, n))

    def api():
        em.bistatic(rough, EPS, wavelength=LAM, theta_i=ti, theta_s=ts, phi_s=ps,
                    method=method, out_of_range="ignore")  # fmt: skip

    def solver():
        mod.bistatic(rough, EPS, K, ti, ts, ps, coherent=False)

    runs = {}
    if method == "spm":
        from emscatter.kernels import SPM_GAUSSIAN
        from emscatter.solvers.spm.kernel import spm1_sigma0

        def kernel():
            spm1_sigma0(ti, ts, ps, EPS, k=K, sigma=rough.sigma, length=rough.length,
                        spectrum=SPM_GAUSSIAN, out=out)  # fmt: skip

        runs["kernel"] = ("numba", kernel)
    if method == "go":
        from emscatter.solvers.kirchhoff.go_kernel import go_sigma0

        s2 = rough.mean_square_slope()[0]

        def kernel():
            # the shadowing the solver and the API run by default (check_shadowing(True)):
            # the kernel figure is the same work as the rows beside it
            go_sigma0(ti, ts, ps, EPS, slope_variance=s2, shadowing="direction-correlated",
                      out=out)  # fmt: skip

        runs["kernel"] = ("numba", kernel)

        def kernel_fresh():  # the floor of a call that returns new arrays: a fresh output
            go_sigma0(ti, ts, ps, EPS, slope_variance=s2, shadowing="direction-correlated",
                      out=np.empty((2, 2, n)))  # fmt: skip

        runs["kernel_fresh_out"] = ("numba", kernel_fresh)

        def plain():
            cook_torrance(ti, ts, ps, EPS, 2 * s2)

        runs["cook_torrance_numpy"] = ("numpy", plain)
    for backend in ("numba", "numpy"):
        runs[f"solver_{backend}"] = (backend, solver)
        runs[f"api_{backend}"] = (backend, api)
    from emscatter import api as api_mod

    fused = api_mod._checked_copy

    def api_plain_checks():  # the API before the fused check + copy (the numpy checks)
        api_mod._checked_copy = lambda *a, **k: None
        try:
            api()
        finally:
            api_mod._checked_copy = fused

    runs["api_numba_plain_checks"] = ("numba", api_plain_checks)
    return runs


def speed(sizes, repeat, methods=("spm", "go", "po")) -> dict:
    os.environ["EMSCATTER_CACHE"] = "0"
    results = {}
    for method in methods:
        for n in sizes:
            runs = _contenders(method, n)
            times = {name: [] for name in runs}
            cpu = {name: [] for name in runs}  # process CPU time (all threads): the work done
            rounds = repeat if n < 10**6 or method != "po" else max(3, repeat // 2)
            for r in range(rounds + 1):  # round 0: warm-up (compile / load), not counted
                for name, (backend, fn) in runs.items():
                    os.environ["EMSCATTER_KERNELS"] = backend
                    t0, c0 = time.perf_counter(), time.process_time()
                    fn()
                    if r:
                        times[name].append(time.perf_counter() - t0)
                        cpu[name].append(time.process_time() - c0)
            os.environ["EMSCATTER_KERNELS"] = "auto"
            row = {}
            for name, ts_ in times.items():
                med = statistics.median(ts_)
                row[name] = {"median_s": med, "min_s": min(ts_), "per_s": n / med,
                             "cpu_median_s": statistics.median(cpu[name])}  # fmt: skip
            row["api_over_solver_numba"] = (
                row["api_numba"]["median_s"] / row["solver_numba"]["median_s"]
            )
            row["api_over_solver_numba_cpu"] = (
                row["api_numba"]["cpu_median_s"] / row["solver_numba"]["cpu_median_s"]
            )
            if "kernel" in row:  # what the API keeps of the kernel's rate
                row["api_over_kernel"] = row["api_numba"]["median_s"] / row["kernel"]["median_s"]
            row["api_numba_over_numpy"] = (
                row["api_numpy"]["median_s"] / row["api_numba"]["median_s"]
            )
            row["api_plain_checks_over_api_numba"] = (
                row["api_numba_plain_checks"]["median_s"] / row["api_numba"]["median_s"]
            )
            if "cook_torrance_numpy" in row:
                row["api_numba_over_cook_torrance"] = (
                    row["cook_torrance_numpy"]["median_s"] / row["api_numba"]["median_s"]
                )
            row["rounds"] = rounds
            results[f"{method}_{n}"] = row
            print(f"{method:4s} n={n:>8d}  " + "  ".join(
                f"{name} {v['per_s']:.3g}/s" for name, v in row.items() if isinstance(v, dict)
            ) + f"  API/solver ×{row['api_over_solver_numba']:.2f}"
                f" (CPU time ×{row['api_over_solver_numba_cpu']:.2f})"
                f"  API numba/numpy ×{row['api_numba_over_numpy']:.1f}", flush=True)  # fmt: skip
    return results


_CHILD = r"""
import json, math, sys, time, warnings
import numpy as np
t0 = time.perf_counter()
import emscatter as em
t1 = time.perf_counter()
sys.path.insert(0, {bench!r})
from bench_api import _roughness, EPS, LAM
method, kind = {method!r}, {kind!r}
rough = _roughness(method)
warnings.simplefilter("ignore")
if kind.startswith("emissivity"):  # 9 θi, the default tolerance; "_copol": IEM without hv
    th = np.radians(np.linspace(0.0, 80.0, 9))
    kw = dict(crosspol=False) if kind == "emissivity_copol" else {{}}
    if method != "auto":
        kw["out_of_range"] = "ignore"
    call = lambda: em.emissivity(rough, EPS, wavelength=LAM, theta_i=th, method=method, **kw)
elif kind == "backscatter":
    th = np.radians(np.linspace(0.0, 60.0, 91))
    if method == "auto":
        call = lambda: em.backscatter(rough, "medium_dry_ground", frequency=5.4e9, theta_i=th)
    else:
        call = lambda: em.backscatter(rough, EPS, wavelength=LAM, theta_i=th, method=method,
                                      out_of_range="ignore")
else:
    n = 100_000
    rng = np.random.default_rng(0)
    ti, ts = rng.uniform(0, 1.5, n), rng.uniform(0, 1.5, n)
    ps = rng.uniform(-math.pi, math.pi, n)
    kw = dict(crosspol=False) if method == "iem" else {{}}
    if method == "iem":
        ti, ts, ps = ti[:2000], ts[:2000], ps[:2000]
    call = lambda: em.bistatic(rough, EPS, wavelength=LAM, theta_i=ti, theta_s=ts, phi_s=ps,
                               method=method, out_of_range="ignore", **kw)
call()
t2 = time.perf_counter()
call()
t3 = time.perf_counter()
print(json.dumps({{"import_s": t1 - t0, "first_call_s": t2 - t1, "second_call_s": t3 - t2,
                  "first_minus_second_s": (t2 - t1) - (t3 - t2)}}))
"""


def _child(method, kind, cache) -> dict:
    env = {**os.environ, "EMSCATTER_NUMBA_CACHE_DIR": str(cache), "EMSCATTER_CACHE": "0"}
    env.pop("NUMBA_CACHE_DIR", None)
    env.pop("EMSCATTER_KERNELS", None)
    env["PYTHONPATH"] = str(ROOT / "src")
    code = _CHILD.format(bench=str(Path(__file__).resolve().parent), method=method, kind=kind)
    before = compiled_entries(cache)
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         check=True)  # fmt: skip
    row = json.loads(out.stdout.strip().splitlines()[-1])
    # the kernels this first call compiled (after setup: none expected; names, not counts)
    row["compiled"] = sorted({name.split("-")[0] for name in compiled_entries(cache) - before})
    return row


def compiled_entries(cache) -> set:
    """The compiled signatures in a numba cache folder: one ``.nbc`` file per kernel and
    signature (its ``.nbi`` index lists them). A new signature of a kernel already cached
    (e.g. a read-only or non-contiguous array argument) adds an ``.nbc`` file, not an index."""
    cache = Path(cache)
    return {str(p.relative_to(cache)) for p in cache.rglob("*.nbc")} if cache.is_dir() else set()


COLD_KINDS = ("backscatter", "bistatic", "emissivity")


def cold(methods=("spm", "go", "po", "iem", "auto"), kinds=COLD_KINDS,
         states=("empty_cache", "after_setup")) -> dict:  # fmt: skip
    """The first call per method and kind in fresh processes (module docstring); ``states``:
    ``after_setup`` alone skips the empty-cache rows (minutes of compilation)."""
    cases = [(m, kind) for m in ("spm", "go", "po", "iem") for kind in kinds]
    if "emissivity" in kinds:
        cases.append(("iem", "emissivity_copol"))
    cases += [("auto", kind) for kind in ("backscatter", "emissivity") if kind in kinds]
    cases = [c for c in cases if c[0] in methods]
    results = {"limit_s": 2.0}
    with tempfile.TemporaryDirectory(prefix="emscatter-bench-numba-") as tmp:
        for state in states:
            if state == "after_setup":  # what `make setup` runs, into the same folder
                env = {**os.environ, "EMSCATTER_NUMBA_CACHE_DIR": tmp,
                       "PYTHONPATH": str(ROOT / "src")}  # fmt: skip
                t0 = time.perf_counter()
                subprocess.run([sys.executable, "-m", "emscatter.warm", "--quiet"], env=env,
                               check=True)  # fmt: skip
                results["warm_s"] = time.perf_counter() - t0
                print(f"python -m emscatter.warm: {results['warm_s']:.1f} s", flush=True)
            for method, kind in cases:
                cache = (
                    Path(tmp) if state == "after_setup" else Path(tmp) / f"empty-{method}-{kind}"
                )
                row = _child(method, kind, cache)
                results[f"{state}/{method}/{kind}"] = row
                row["under_limit"] = row["import_s"] + row["first_call_s"] < results["limit_s"]
                print(f"{state:12s} {method:5s} {kind:16s} import {row['import_s']:.2f} s, "
                      f"first call {row['first_call_s']:.2f} s, "
                      f"second {row['second_call_s']:.3f} s, compiled {len(row['compiled'])} "
                      "kernel(s)", flush=True)  # fmt: skip
    return results


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[10_000, 1_000_000])
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--parts", nargs="+", default=["speed", "cold"], choices=["speed", "cold"])
    ap.add_argument("--methods", nargs="+", default=["spm", "go", "po", "iem", "auto"],
                    choices=["spm", "go", "po", "iem", "auto"],
                    help="methods timed (speed: spm, go, po; cold: all five)")  # fmt: skip
    ap.add_argument("--kinds", nargs="+", default=list(COLD_KINDS), choices=COLD_KINDS,
                    help="cold: the calls timed (emissivity adds IEM without hv)")  # fmt: skip
    states = ["empty_cache", "after_setup"]
    ap.add_argument(
        "--states", nargs="+", default=states, choices=states, help="cold: cache states"
    )
    ap.add_argument("--out", default="api", help="results file name (results/NAME.json)")
    args = ap.parse_args()
    data = {"machine": machine(), "command": command()}
    if "speed" in args.parts:
        data["speed"] = speed(
            args.sizes, args.repeat, tuple(m for m in args.methods if m in ("spm", "go", "po"))
        )
    if "cold" in args.parts:
        data["cold"] = cold(tuple(args.methods), tuple(args.kinds), tuple(args.states))
    data["machine"]["load_average_end"] = list(os.getloadavg())
    print(write(args.out, data))


if __name__ == "__main__":
    main()
