"""Cold start (issue 22: the first call of every method in a fresh process under 2 s after
``make setup``): what a first call imports, that ``python -m emscatter.warm`` compiles the
kernels an emissivity call needs, and that a slow first chunk (compilation) in the SPM
validity's hemispherical integral is not taken for the integral's cost."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pytest

import emscatter as em
from emscatter.spectra import GaussianCorrelation

SRC = Path(__file__).resolve().parents[1] / "src"
LAM = 0.1
K = 2 * math.pi / LAM

_CHILD = r"""
import json, math, sys, warnings
import numpy as np
import emscatter as em
from emscatter.spectra import GaussianCorrelation
warnings.simplefilter("ignore")
k = 2 * math.pi / 0.1
th = np.radians([10.0, 40.0])
out = {}
em.backscatter(GaussianCorrelation(0.1 / k, 2.0 / k), 17 + 2j, wavelength=0.1, theta_i=th,
               method="spm")
out["spm"] = sorted(m for m in ("scipy.integrate", "scipy.optimize", "emscatter.surfaces")
                    if m in sys.modules)
em.backscatter(GaussianCorrelation(0.5 / k, 4.0 / k), 17 + 2j, wavelength=0.1, theta_i=th,
               method="iem")
out["iem"] = sorted(m for m in ("scipy.optimize", "emscatter.surfaces") if m in sys.modules)
print(json.dumps(out))
"""


def test_first_calls_do_not_import_what_they_do_not_use():
    """SPM's closed-form slope variance needs no scipy.integrate, and the IEM's validity no
    surfaces package (scipy.optimize, FFT generation: 0.2–0.8 s of a first call)."""
    env = {**os.environ, "PYTHONPATH": str(SRC), "EMSCATTER_CACHE": "0",
           "EMSCATTER_KERNELS": "numpy"}  # fmt: skip
    run = subprocess.run([sys.executable, "-c", _CHILD], env=env, capture_output=True,
                         text=True, timeout=300)  # fmt: skip
    assert run.returncode == 0, run.stderr
    mods = json.loads(run.stdout.strip().splitlines()[-1])
    assert mods == {"spm": [], "iem": []}


def test_warm_up_compiles_the_spm_coherent_kernel(monkeypatch):
    """The SPM warm-up includes emissivity calls, which read the second-order coherent part:
    its kernel (:mod:`emscatter.solvers.spm.kernel_coherent`) is compiled (or loaded from the
    cache) by them, not by the user's first emissivity call."""
    pytest.importorskip("numba")
    from emscatter import warm

    monkeypatch.setenv("EMSCATTER_KERNELS", "numba")
    monkeypatch.setenv("EMSCATTER_CACHE", "0")
    calls = warm._calls()["spm"]
    names = [c.__code__.co_names for c in calls]
    emis = [c for c, n in zip(calls, names, strict=True) if "emissivity" in n]
    assert len(emis) == 2
    from emscatter.solvers.spm import kernel_coherent

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for c in emis:
            res = c()
            assert np.all(np.isfinite(res.emissivity))
    assert kernel_coherent._amplitudes.signatures  # compiled or loaded for the call's types


def test_slow_first_chunk_in_the_spm_validity_integral_is_not_refused(monkeypatch):
    """A first σ⁰ chunk that takes 60 % of the time budget (a cold numba cache compiles the
    kernel there) does not make the scattered-fraction integral of the SPM validity (24 θi,
    tol 1e-2, inside the emissivity call's budget) raise TimeBudgetError: the estimate is
    made from the measured chunks after it."""
    from emscatter.solvers.spm import first_order

    real = first_order.sigma0_broadcast
    state = {"first": True}

    def slow_first(*args, **kwargs):
        if state["first"]:
            state["first"] = False
            time.sleep(1.2)  # what compiling the σ⁰ kernel costs on an idle machine, ~×0.3
        return real(*args, **kwargs)

    monkeypatch.setattr(first_order, "sigma0_broadcast", slow_first)
    monkeypatch.setenv("EMSCATTER_CACHE", "0")
    monkeypatch.setenv("EMSCATTER_TIME_BUDGET_S", "2.0")
    rough = GaussianCorrelation(0.1 / K * 1.000123, 2.0 / K)  # not in the r₁ grid's memo
    res = em.emissivity(rough, 17 + 2j, wavelength=LAM, theta_i=np.radians([10.0, 50.0]),
                        method="spm", tol=1e-2)  # fmt: skip
    assert not state["first"]  # the slow chunk ran
    assert np.all((res.emissivity > 0) & (res.emissivity < 1))
    assert res.info["validity"]["valid"]


def test_frozen_erfcx_coefficients_are_the_fit():
    """:mod:`emscatter.kernels._vmath`'s erfcx Chebyshev coefficients are frozen (no scipy
    import, no fit at import); they are the fit to scipy's erfcx (bits may differ with the
    LAPACK build: ≤ 1e-12 of the leading coefficient), and meet its error bound."""
    from scipy import special

    from emscatter.kernels import _vmath as vm

    coef, err = vm._erfcx_fit()
    np.testing.assert_allclose(vm.ERFCX_COEF, coef, rtol=0, atol=1e-12 * abs(coef[0]))
    assert vm.ERFCX_COEF.size == vm.ERFCX_DEGREE + 1 and err <= 4e-15
    x = np.linspace(0.0, vm.ERFCX_HI, 20_001)
    t = (x - vm._ERFCX_K) / (x + vm._ERFCX_K)
    u = 2.0 * (t + 1.0) / (vm._ERFCX_T1 + 1.0) - 1.0
    approx = np.polynomial.chebyshev.chebval(u, vm.ERFCX_COEF) / (1.0 + 2.0 * x)
    assert np.max(np.abs(approx / special.erfcx(x) - 1.0)) <= 4e-15


def test_loading_the_kernels_imports_no_scipy_special():
    pytest.importorskip("numba")
    code = (
        "import sys; import emscatter.kernels._vmath, emscatter.solvers.spm.kernel; "
        "print('scipy.special' in sys.modules)"
    )
    env = {**os.environ, "PYTHONPATH": str(SRC)}
    run = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         timeout=300)  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip().splitlines()[-1] == "False"


def test_warm_up_compiles_the_go_validity_pass(monkeypatch):
    """The compiled GO per-angle validity pass runs only above 4096 angles
    (``method_resolution._DISTINCT_MAX``): the GO warm-up has such a call."""
    pytest.importorskip("numba")
    from emscatter import method_resolution, warm
    from emscatter.solvers.kirchhoff import go_validity

    monkeypatch.setenv("EMSCATTER_KERNELS", "numba")
    monkeypatch.setenv("EMSCATTER_CACHE", "0")
    big = warm._calls()["go"][-1]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = big()
    assert res.sigma0.shape[-1] > max(method_resolution._DISTINCT_MAX, go_validity.MIN_ANGLES)
    assert go_validity._angle_pass.signatures


_AUTO_EMISSIVITY = r"""
import math, warnings
import numpy as np
import emscatter as em
from emscatter.spectra import GaussianCorrelation
warnings.simplefilter("ignore")
# benchmarks/bench_api.py's cold "auto" emissivity row: kσ ≈ 0.63, kℓ ≈ 6.3 at λ = 0.1 m
res = em.emissivity(GaussianCorrelation(0.01, 0.1), 17 + 2j, wavelength=0.1,
                    theta_i=np.radians(np.linspace(0.0, 80.0, 9)), method="auto")
assert np.all(np.isfinite(res.emissivity)), res.emissivity
print(res.method)
"""


def _nbc(folder: Path) -> set:
    """Compiled signatures in a numba cache folder (one ``.nbc`` file per kernel and
    signature; a new signature of a cached kernel adds a file, not an index)."""
    return {str(p.relative_to(folder)) for p in folder.rglob("*.nbc")}


@pytest.mark.slow
def test_auto_emissivity_compiles_nothing_after_warm(tmp_path):
    """Issue 22 (first call under 2 s after ``make setup``): after ``python -m emscatter.warm``
    (the methods the call uses: IEM, PO and the ``auto`` entry) into an empty numba cache, a
    fresh process's ``auto`` emissivity — whose energy fallback evaluates the IEM's coherent
    part at the specular geometry, with full-length read-only views that used to select
    another signature of ``amplitudes_kernel`` (11 s compile) — adds no compiled signature."""
    pytest.importorskip("numba")
    cache = tmp_path / "numba"
    env = {**os.environ, "PYTHONPATH": str(SRC), "EMSCATTER_NUMBA_CACHE_DIR": str(cache),
           "EMSCATTER_CACHE": "0"}  # fmt: skip
    for name in ("NUMBA_CACHE_DIR", "EMSCATTER_KERNELS"):
        env.pop(name, None)
    warm = subprocess.run([sys.executable, "-m", "emscatter.warm", "po", "iem", "auto"], env=env,
                          capture_output=True, text=True, timeout=1200)  # fmt: skip
    assert warm.returncode == 0, warm.stderr
    assert "failed" not in warm.stdout, warm.stdout
    before = _nbc(cache)
    assert before  # the warm-up did compile into the folder
    run = subprocess.run([sys.executable, "-c", _AUTO_EMISSIVITY], env=env, capture_output=True,
                         text=True, timeout=1200)  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert sorted(_nbc(cache) - before) == []


def test_iem_kernel_arguments_are_writeable_whatever_the_input():
    """numba compiles once per argument type, and a read-only array is another type: the IEM's
    argument normalizer gives a C-contiguous writeable array (same values, dtype asked) for a
    read-only full-length view, a strided view, a number and a writeable array (no copy)."""
    from emscatter.solvers.iem.compiled import flat_n

    x = np.linspace(0.1, 1.2, 7)
    ro = np.broadcast_to(x, (7,))  # what np.broadcast_to gives for an (n,) array: read-only
    assert not ro.flags.writeable and ro.flags.c_contiguous
    cases = ((ro, float), (x[::-1], float), (0.3, float), (ro, complex), (17 + 2j, complex))
    for v, dtype in cases:
        a = flat_n(v, 7, dtype)
        assert a.flags.writeable and a.flags.c_contiguous and a.shape == (7,) and a.dtype == dtype
        np.testing.assert_array_equal(a, np.broadcast_to(np.asarray(v, dtype), (7,)))
    assert flat_n(x, 7) is x
