"""Compile every numba kernel once, into the disk cache, so that a fresh process starts fast.

    python -m emscatter.warm [--quiet]          (``make setup`` runs it after the install)

Without it the first call of a method in a fresh environment compiles that method's kernels:
~20 s for the integral-equation model (its series, the lockstep backscatter walk and the
cross-pol integral), 1–4 s for SPM, GO and PO (and for the backscatter cross-pol ``auto`` adds,
:mod:`emscatter.solvers.auto_crosspol`: the ``"auto"`` entry). Here each method runs once
through the public API on a few angles with ``EMSCATTER_KERNELS=numba`` (so even these tiny
calls take the compiled path), in the layouts and argument types that select distinct compiled
signatures: a dielectric and ``"pec"``, Gaussian and exponential correlations, flat geometries
and a grid (θi × θs × φs), bistatic and backscatter, 1-D and 2-D where the kernel covers both;
SPM emissivity (it reads the coherent part: the second-order kernel,
:mod:`emscatter.solvers.spm.kernel_coherent`) and a GO call above 4096 angles (the compiled
per-angle validity pass, :mod:`emscatter.solvers.kirchhoff.go_validity`, runs only there);
an ``auto`` emissivity whose energy fallback runs (IEM on a grazing angle). A kernel is
compiled once per argument *type* (dtype, dimensions, layout, read-only or not): the IEM's
geometry and ε arguments go through :func:`emscatter.solvers.iem.compiled.flat_n`
(C-contiguous, writeable), so that the warm-up's signature is the one later calls select.
``python benchmarks/bench_api.py --parts cold`` checks that a fresh process then compiles
nothing and times each method's first call (issue 22: under 2 s).
numba writes what it compiles to the cache folder of :mod:`emscatter.kernels._runtime`
(``EMSCATTER_NUMBA_CACHE_DIR``, default ``~/.cache/emscatter/numba``; ``NUMBA_CACHE_DIR`` when
the user set it); a later process loads it (≈ 0.1–0.5 s per method instead of seconds).

Nothing fails the install: without numba, or when a method's warm-up raises, the reason is
printed and the rest goes on (exit status 0; the kernels then compile on first use, as before).
The result cache is not touched (``EMSCATTER_CACHE=0`` for these calls).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
import warnings

import numpy as np

__all__ = ["CASES", "warm"]

_LAM = 0.1  # wavelength [m] of every warm-up call; k = 2π/λ


def _calls():
    """``{method: [zero-argument callables]}`` — the API calls that compile each method."""
    from emscatter import api as em  # bistatic, backscatter (the facade's own functions)
    from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation

    k = 2 * math.pi / _LAM
    ti = np.radians([10.0, 35.0, 60.0])
    ts = np.radians([20.0, 40.0, 70.0])
    ps = np.radians([0.0, 90.0, 180.0])
    grid = (ti[:, None, None], ts[None, :, None], ps[None, None, :])
    kw = {"wavelength": _LAM, "out_of_range": "ignore"}
    spm_g = GaussianCorrelation(0.1 / k, 2.0 / k)
    spm_e = ExponentialCorrelation(0.1 / k, 2.0 / k)
    go_g = GaussianCorrelation(0.3, 1.5)
    po_g = GaussianCorrelation(0.4 / k, 6.0 / k)
    po_e = ExponentialCorrelation(0.4 / k, 6.0 / k)
    iem_g = GaussianCorrelation(0.5 / k, 4.0 / k)
    iem_e = ExponentialCorrelation(0.5 / k, 4.0 / k)

    def bi(rough, eps, method, angles=(ti, ts, ps), **opt):
        return lambda: em.bistatic(
            rough, eps, theta_i=angles[0], theta_s=angles[1], phi_s=angles[2],
            method=method, **kw, **opt,
        )  # fmt: skip

    def back(rough, eps, method, **opt):
        return lambda: em.backscatter(rough, eps, theta_i=ti, method=method, **kw, **opt)

    def emis(rough, eps, method, theta=ti, **opt):  # reads the coherent part (SPM: kernel_coherent)
        return lambda: em.emissivity(
            rough, eps, theta_i=theta, method=method, tol=1e-2, **kw, **opt
        )

    out = {}
    for method, roughs in (("spm", (spm_g, spm_e)), ("po", (po_g, po_e))):
        out[method] = [
            f(r, e, method)
            for r in roughs
            for e in (17 + 2j, "pec")
            for f in (bi, back, lambda r, e, m: bi(r, e, m, grid))
        ]
    # emissivity: the hemispherical layouts of σ⁰ and (SPM) the second-order coherent kernel
    out["spm"] += [emis(spm_g, 17 + 2j, "spm"), emis(spm_e, "pec", "spm")]
    profile = GaussianCorrelation(0.4 / k, 6.0 / k, dimension=1)
    in_plane = (ti, ts, np.array([0.0, math.pi, 0.0]))  # a 1-D profile scatters in its plane
    out["po"] += [bi(profile, 17 + 2j, "po", in_plane), emis(po_g, 17 + 2j, "po")]
    out["go"] = [
        f(go_g, e, "go", **opt)
        for e in (17 + 2j, "pec")
        for opt in ({}, {"shadowing": "separable"}, {"shadowing": "correlated"})
        for f in (bi, back, lambda r, e, m, **o: bi(r, e, m, grid, **o))
    ]
    # the compiled per-angle validity pass runs above 4096 angles (method_resolution)
    rng = np.random.default_rng(0)
    many = tuple(rng.uniform(lo, hi, 8192) for lo, hi in ((0, 1.5), (0, 1.5), (-3.1, 3.1)))
    out["go"] += [emis(go_g, 17 + 2j, "go"), bi(go_g, 17 + 2j, "go", many)]  # many: last
    out["iem"] = [
        f(r, e, "iem")
        for r in (iem_g, iem_e)
        for e in (17 + 2j, "pec")
        for f in (bi, back, lambda r, e, m: bi(r, e, m, grid))
    ]
    # emissivity: hemispherical chunks of thousands of rows take the kernels' threaded splits
    out["iem"] += [emis(iem_g, 17 + 2j, "iem"), emis(iem_e, 17 + 2j, "iem", crosspol=False)]
    # the backscatter cross-pol auto adds (solvers.auto_crosspol): the resummed term's kernel
    out["auto"] = [back(r, 17 + 2j, "auto") for r in (spm_e, iem_g)]
    # emissivity: PO ranks first for iem_g; at 80° its energy balance fails and the fallback
    # integrates the next ranked method (IEM) on that angle alone, coherent part included
    grazing = np.radians([10.0, 35.0, 80.0])
    out["auto"] += [emis(iem_g, 17 + 2j, "auto", grazing)]
    out["auto"] += [emis(r, 17 + 2j, "auto") for r in (po_g, go_g)]
    return out


#: the methods warmed, in this order (MoM has no compiled kernel)
CASES = ("spm", "go", "po", "iem", "auto")


def warm(methods=CASES, *, echo=print) -> dict:
    """Run each method's warm-up calls; ``{method: seconds}`` (None: failed, reason echoed)."""
    try:
        import numba  # noqa: F401
    except ImportError:
        echo("emscatter.warm: numba is not installed; nothing to compile (numpy paths only)")
        return {}
    saved = {n: os.environ.get(n) for n in ("EMSCATTER_KERNELS", "EMSCATTER_CACHE")}
    os.environ["EMSCATTER_KERNELS"] = "numba"
    os.environ["EMSCATTER_CACHE"] = "0"
    times = {}
    try:
        calls = _calls()
        from emscatter.kernels._runtime import cache_dir

        echo(f"emscatter.warm: compiling the kernels into {cache_dir()}")
        for method in methods:
            t0, failed = time.perf_counter(), []
            for call in calls[method]:
                try:
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore")
                        call()
                except Exception as exc:  # the install goes on; it compiles on first use
                    failed.append(f"{type(exc).__name__}: {exc}")
            times[method] = None if failed else time.perf_counter() - t0
            if failed:
                echo(f"  {method}: {len(failed)} warm-up call(s) failed ({failed[0]})")
            else:
                echo(f"  {method}: {times[method]:.1f} s")
    finally:
        for n, v in saved.items():
            if v is None:
                os.environ.pop(n, None)
            else:
                os.environ[n] = v
    return times


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m emscatter.warm", description=__doc__)
    parser.add_argument("--quiet", action="store_true", help="print nothing")
    parser.add_argument("methods", nargs="*", help=f"any of {', '.join(CASES)} (default: all)")
    args = parser.parse_args(argv)
    bad = sorted(set(args.methods) - set(CASES))
    if bad:
        parser.error(f"methods must be among {', '.join(CASES)}, got {', '.join(bad)}")
    warm(tuple(args.methods) or CASES, echo=(lambda *a: None) if args.quiet else print)
    return 0


if __name__ == "__main__":
    sys.exit(main())
