"""σ⁰ throughput of the numpy path and the compiled kernels, and their gap to a roofline.

    python benchmarks/bench_kernels.py [--n 1000000] [--repeat 5]
    → benchmarks/results/kernels.json, kernels.png

Throughput: full-polarization σ⁰ evaluations per second (one evaluation = one geometry, all
four σ⁰_pq), random geometries over the hemisphere, median of ``--repeat`` runs after a
warm-up (so compile time is excluded; it is reported separately), numpy and compiled timed
interleaved in the same run, compiled on 1 and on all cores.

Roofline (a simple one, for this machine): the operations of one evaluation are counted in
the kernel's own vectorized LLVM IR (one vector instruction = one operation per lane; both
branches of a case-specialized copy), split in *simple* ops (add, sub, mul, FMA — a
contractible mul whose only use is an add counts once with it —, neg, compare, select, floor,
min/max, conversions, integer ops) and *div/sqrt* (a separate, slower unit); the machine's
peaks are measured here by small numba kernels on all cores: vector instructions per second
(chains of mul and add; an FMA chain issues at the same instruction rate, twice the flops —
recorded too), div+sqrt per second, and copy bandwidth. Roofline time per evaluation =
max(simple / peak_simple, divsqrt / peak_divsqrt, bytes / bandwidth). The fraction of the
roofline compares best-of-repeats with best-of-repeats (on a loaded machine medians of the
short peak kernels and of the longer σ⁰ runs are hit differently by the load); the
throughputs and speed-ups are medians.
"""

from __future__ import annotations

import argparse
import inspect
import math
import re
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import numpy as np  # noqa: E402
from common import command, machine, save, stamp, timeit, write  # noqa: E402

SIMPLE = (
    "fadd",
    "fsub",
    "fmul",
    "fneg",
    "fcmp",
    "select",
    "floor",
    "minnum",
    "maxnum",
    "fptosi",
    "sitofp",
    "add",
    "sub",
    "shl",
    "and",
    "or",
    "xor",
    "bitcast",
    "fabs",
    "icmp",
)
DIVSQRT = ("fdiv", "sqrt")


# ----------------------------------------------------------------------------- peaks
def peaks(threads: int) -> dict:
    """Measured machine peaks on ``threads`` threads: simple ops/s (mul+add chains), FMA
    flops/s, div+sqrt ops/s, copy bandwidth bytes/s."""
    import numba

    from emscatter.kernels._runtime import jit, run_chunked

    def chains(x, out):  # 4 independent chains of 32 × (mul, add) per element
        for i in range(x.size):
            a = x[i]
            b = a + 1.0
            c = a + 2.0
            d = a + 3.0
            for _ in range(32):
                a = a * 0.999 + 0.001
                b = b * 0.999 + 0.001
                c = c * 0.999 + 0.001
                d = d * 0.999 + 0.001
            out[i] = a + b + c + d

    muladd = jit(cache=False, fastmath=False)(chains)  # mul and add: 2 instructions
    fma = jit(cache=False, fastmath={"contract"})(chains)  # one FMA: same rate, 2 flops

    @jit(cache=False, fastmath=False)
    def divsqrt(x, out):
        for i in range(x.size):
            a = x[i] + 1.0
            b = x[i] + 2.0
            for _ in range(8):
                a = math.sqrt(a) / 1.0001
                b = math.sqrt(b) / 1.0001
            out[i] = a + b

    @jit(cache=False, fastmath=False)
    def copy(x, out):
        for i in range(x.size):
            out[i] = x[i]

    n = 1 << 16
    x = np.random.default_rng(0).uniform(1, 2, n)
    o = np.empty_like(x)
    big = np.ones(1 << 25)  # 256 MiB: out of cache
    ob = np.empty_like(big)

    def rate(kernel, arr, out, work_per_elem):
        def run():
            run_chunked(lambda a, b: kernel(arr[a:b], out[a:b]), arr.size, threads)

        t = timeit(run, repeat=5)["min_s"]  # best of 5, as the kernels' roofline fraction
        return arr.size * work_per_elem / t

    res = {
        "threads": threads,
        "simple_ops_per_s": rate(muladd, x, o, 4 * 32 * 2 + 3 + 3),
        "fma_flops_per_s": rate(fma, x, o, 4 * 32 * 2 + 3 + 3),
        "divsqrt_per_s": rate(divsqrt, x, o, 2 * 8 * 2),
        "copy_bytes_per_s": rate(copy, big, ob, 16),
    }
    res["numba"] = numba.__version__
    return res


# ----------------------------------------------------------------------------- op counts
def op_counts(func, replacements: dict, args: tuple) -> dict:
    """Vector ops per evaluation in an LLVM IR copy of ``func`` with branches fixed by
    source ``replacements`` (the case being measured)."""
    from numba import njit

    src = inspect.getsource(func.py_func).split("\n", 1)[1]  # drop the decorator
    for old, new in replacements.items():
        assert old in src, old
        src = src.replace(old, new)
    ns = dict(func.py_func.__globals__)
    exec(compile(src, "<bench>", "exec"), ns)
    from emscatter.kernels._runtime import FASTMATH

    f = njit(nogil=True, fastmath=FASTMATH, error_model="numpy")(ns[func.py_func.__name__])
    f(*args)
    ir = f.inspect_llvm(f.signatures[0])
    lanes = sorted({int(m) for m in re.findall(r"<(\d+) x double>", ir)}, reverse=True)[0]
    line_re = re.compile(
        r"^\s*(%[\w.]+)\s*=\s*(?:tail\s+)?(?:call\s[^@]*@llvm\.(\w+)|(\w+)\s)(.*)$"
    )
    ops, uses = [], {}
    for line in ir.splitlines():
        if f"<{lanes} x " not in line:
            continue
        m = line_re.match(line)
        if not m:
            continue
        name, op, rest = m.group(1), m.group(2) or m.group(3), m.group(4)
        for operand in re.findall(r"%[\w.]+", rest):
            uses[operand] = uses.get(operand, 0) + 1
        ops.append((name, op, rest, "contract" in rest.split("<")[0]))
    # an fmul (contract) whose only use is an fadd/fsub (contract) becomes one FMA instruction
    muls = {n for n, op, _, c in ops if op == "fmul" and c}
    fused = set()
    for _, op, rest, c in ops:
        if op in ("fadd", "fsub") and c:
            for operand in re.findall(r"%[\w.]+", rest):
                if operand in muls and uses.get(operand) == 1:
                    fused.add(operand)
                    break
    counts = {"simple": 0, "divsqrt": 0, "lanes": lanes, "fma": len(fused)}
    for name, op, _, _ in ops:
        if op in DIVSQRT:
            counts["divsqrt"] += 1
        elif op in SIMPLE and name not in fused:
            counts["simple"] += 1
    return counts


def spm_counts(pec: bool) -> dict:
    """Ops of the compiled SPM1 loop for this case (Gaussian spectrum)."""
    from emscatter.solvers.spm import kernel as ks

    x = np.full(64, 0.5)
    outs = [np.empty(64) for _ in range(4)]
    kernel = ks._KERNELS[(pec, ks.GAUSSIAN)]
    return op_counts(kernel, {}, (x, x, x, 17.0, 2.0, 2.0, 1.0, 1.0, *outs))


def go_counts(pec: bool) -> dict:
    """Ops of the compiled GO loop with Smith shadowing (the mode is a runtime select: the
    few ops of the other modes are counted too)."""
    from emscatter.solvers.kirchhoff import go_kernel as kg

    x = np.full(64, 0.5)
    outs = [np.empty(64) for _ in range(4)]
    kernel = kg._KERNELS[(pec, True)]
    return op_counts(kernel, {}, (x, x, x, x, 17.0, 2.0, 0.02, kg.SMITH, *outs))


# ----------------------------------------------------------------------------- throughput
def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=1_000_000)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args(argv)
    import os

    from emscatter.solvers.kirchhoff import go
    from emscatter.solvers.kirchhoff.go_kernel import go_sigma0
    from emscatter.solvers.spm import model as spm
    from emscatter.solvers.spm.kernel import GAUSSIAN, spm1_sigma0
    from emscatter.spectra import GaussianCorrelation

    os.environ["EMSCATTER_KERNELS"] = "numpy"  # the solvers' own path is the reference here
    n, rep = args.n, args.repeat
    rng = np.random.default_rng(0)
    ti = rng.uniform(0, math.radians(89.9), n)
    ts = rng.uniform(0, math.radians(89.9), n)
    dphi = rng.uniform(0, 2 * math.pi, n)
    out = np.empty((2, 2, n))
    k_spm = 2 * math.pi / 0.03
    g_spm = GaussianCorrelation(0.1 / k_spm, 2.0 / k_spm)
    g_go = GaussianCorrelation(0.1, 1.0)
    s2 = g_go.mean_square_slope()[0]
    cores = os.cpu_count() or 1

    t0 = time.perf_counter()  # compile (or load from the numba cache) once, timed
    spm1_sigma0(
        ti[:8],
        ts[:8],
        dphi[:8],
        "pec",
        k=k_spm,
        sigma=g_spm.sigma,
        length=g_spm.length,
        spectrum=GAUSSIAN,
        out=out[:, :, :8],
    )
    go_sigma0(
        ti[:8], ts[:8], dphi[:8], "pec", slope_variance=s2, shadowing="smith", out=out[:, :, :8]
    )
    first_call_s = time.perf_counter() - t0

    cases = {}
    for eps in ("pec", 17 + 2j):
        tag = "pec" if eps == "pec" else "dielectric"

        def np_spm(eps=eps):
            spm._sigma0_first(g_spm, eps, k_spm, ti, ts, dphi, 0.0, out)

        def np_go(eps=eps):
            go.bistatic(g_go, eps, 2 * math.pi, ti, ts, dphi, shadowing=True)

        for name, ref_fn, kern in (
            (
                "spm1",
                np_spm,
                lambda th, eps=eps: spm1_sigma0(
                    ti,
                    ts,
                    dphi,
                    eps,
                    k=k_spm,
                    sigma=g_spm.sigma,
                    length=g_spm.length,
                    spectrum=GAUSSIAN,
                    out=out,
                    threads=th,
                ),
            ),
            (
                "go_smith",
                np_go,
                lambda th, eps=eps: go_sigma0(
                    ti, ts, dphi, eps, slope_variance=s2, shadowing="smith", out=out, threads=th
                ),
            ),
        ):
            r_np = timeit(ref_fn, repeat=max(3, rep // 2))
            r_1 = timeit(lambda k=kern: k(1), repeat=rep)
            r_all = timeit(lambda k=kern: k(cores), repeat=rep)
            cases[f"{name}/{tag}"] = {
                "numpy_per_s": n / r_np["median_s"],
                "compiled_1thread_per_s": n / r_1["median_s"],
                "compiled_per_s": n / r_all["median_s"],
                "speedup": r_np["median_s"] / r_all["median_s"],
                "compiled_best_per_s": n / r_all["min_s"],
                "timings": {"numpy": r_np, "compiled_1thread": r_1, "compiled": r_all},
            }
            c = cases[f"{name}/{tag}"]
            print(
                f"{name:9s} {tag:10s} numpy {c['numpy_per_s']:.3g}/s  compiled "
                f"{c['compiled_1thread_per_s']:.3g}/s (1 thread) {c['compiled_per_s']:.3g}/s "
                f"({cores} threads)  ×{c['speedup']:.1f}",
                flush=True,
            )

    pk = peaks(cores)
    print(
        f"peaks ({cores} threads): simple {pk['simple_ops_per_s']:.3g}/s, FMA flops "
        f"{pk['fma_flops_per_s']:.3g}/s, div/sqrt {pk['divsqrt_per_s']:.3g}/s, copy "
        f"{pk['copy_bytes_per_s'] / 1e9:.3g} GB/s"
    )
    bytes_per_eval = 3 * 8 + 4 * 8  # three angles in, four σ⁰ out
    for key, c in cases.items():
        name, tag = key.split("/")
        cnt = (spm_counts if name == "spm1" else go_counts)(tag == "pec")
        lanes = cnt["lanes"]  # one vector instruction = one operation for each of its lanes
        t_simple = cnt["simple"] / pk["simple_ops_per_s"]
        t_div = cnt["divsqrt"] / pk["divsqrt_per_s"]
        t_mem = bytes_per_eval / pk["copy_bytes_per_s"]
        roof = 1.0 / max(t_simple, t_div, t_mem)
        c.update(
            ops_per_eval={"simple": cnt["simple"], "divsqrt": cnt["divsqrt"]},
            vector_lanes=lanes,
            bytes_per_eval=bytes_per_eval,
            roofline_per_s=roof,
            roofline_bound=["arithmetic", "div/sqrt", "memory"][
                int(np.argmax([t_simple, t_div, t_mem]))
            ],
            fraction_of_roofline=c["compiled_best_per_s"] / roof,
        )
        print(
            f"{key:20s} ops/eval {c['ops_per_eval']}  roofline {roof:.3g}/s "
            f"({c['roofline_bound']})  reached {c['fraction_of_roofline']:.2f}"
        )
    info = machine()
    cmd = command()
    data = {
        "benchmark": "sigma0 throughput, numpy vs compiled, roofline",
        "command": cmd,
        "machine": info,
        "n": n,
        "repeat": rep,
        "first_call_s": first_call_s,
        "peaks": pk,
        "cases": cases,
    }
    write("kernels", data)
    _plot(data, cmd)
    return data


def _plot(data, cmd):
    import matplotlib.pyplot as plt

    cases = data["cases"]
    names = list(cases)
    x = np.arange(len(names))
    fig, ax = plt.subplots(figsize=(8, 4.6))
    w = 0.2
    series = [
        ("numpy", "numpy_per_s"),
        ("compiled, 1 thread", "compiled_1thread_per_s"),
        (f"compiled, {data['machine']['cores']} threads", "compiled_per_s"),
        ("roofline", "roofline_per_s"),
    ]
    for j, (lab, key) in enumerate(series):
        vals = [cases[c][key] for c in names]
        bars = ax.bar(
            x + (j - 1.5) * w,
            vals,
            w,
            label=lab,
            color=["0.6", "C0", "C1", "none"][j],
            edgecolor="k" if j == 3 else None,
            hatch="//" if j == 3 else None,
        )
        if key == "compiled_per_s":
            for b, c in zip(bars, names, strict=True):
                ax.annotate(
                    f"×{cases[c]['speedup']:.0f}\n{cases[c]['fraction_of_roofline']:.0%}",
                    (b.get_x() + b.get_width() / 2, b.get_height()),
                    ha="center",
                    va="bottom",
                    fontsize=7,
                )
    ax.set_yscale("log")
    ax.set_xticks(x, names)
    ax.set_ylabel("full-polarization σ⁰ evaluations per second")
    ax.set_title(
        "σ⁰ throughput: numpy vs compiled kernels (label: speed-up over numpy, "
        "fraction of roofline)",
        fontsize=9,
    )
    ax.legend(fontsize=8)
    ax.grid(True, axis="y", which="both", alpha=0.3)
    stamp(fig, data["machine"], cmd, data["repeat"])
    save(fig, "kernels")


if __name__ == "__main__":
    main()
