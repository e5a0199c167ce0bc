"""Progress bars (issue 22): one policy (:mod:`emscatter.progress`) on every long call and
command — off when stderr is not a terminal (here: pytest captures it) or with ``--quiet``, on
when forced, and the results bit-identical with and without a bar."""

import io
import math
import types

import numpy as np
import pytest

from emscatter import montecarlo
from emscatter import progress as pg
from emscatter.api import emissivity
from emscatter.cli import main
from emscatter.radio import sweep as radio_sweep
from emscatter.radio import tables as radio_tables
from emscatter.solvers import mom3d
from emscatter.spectra import GaussianCorrelation

K = 2 * math.pi  # λ = 1 m


def _bar_in(err: str, desc: str) -> bool:
    """A tqdm bar of ``desc`` was drawn (its "n/total" counter and the bar's pipe)."""
    return desc in err and "|" in err


class _Tty(io.StringIO):
    """A stderr that says it is a terminal (to test the auto default and --quiet)."""

    def isatty(self):
        return True


@pytest.fixture
def tty(monkeypatch):
    """stderr, as :mod:`emscatter.progress` sees it, is a 'terminal' and auto bars show at
    once (no 2 s delay). (pytest re-installs its own sys.stderr after fixtures run.)"""
    stream = _Tty()
    monkeypatch.setattr(pg, "sys", types.SimpleNamespace(stderr=stream))
    monkeypatch.setattr(pg, "AUTO_SECONDS", 0.0)
    monkeypatch.delenv("EMSCATTER_PROGRESS", raising=False)
    return stream


# ---------------------------------------------------------------------------- the policy
def test_policy_auto_forced_off_and_bad_values(monkeypatch, tty):
    assert pg.wanted(True) and not pg.wanted(False)
    assert pg.wanted(None)  # a terminal
    assert not pg.wanted(None, estimate_s=-1.0)  # estimated short: no bar
    with pg.silenced():
        assert not pg.wanted(None) and pg.wanted(True)  # --quiet: auto off, True still draws
    assert pg.wanted(None)
    monkeypatch.setenv("EMSCATTER_PROGRESS", "0")
    assert not pg.wanted(None) and pg.wanted(True)
    monkeypatch.setenv("EMSCATTER_PROGRESS", "loud")
    with pytest.raises(ValueError, match="EMSCATTER_PROGRESS must be one of .*'loud'"):
        pg.wanted(None)
    monkeypatch.delenv("EMSCATTER_PROGRESS")
    with pytest.raises(ValueError, match="progress must be True, False or None .*'yes'"):
        pg.wanted("yes")
    with pytest.raises(ValueError, match="progress must be"):
        montecarlo.run(lambda r: r.uniform(), 4, seed=0, progress=1)


def test_nested_task_draws_no_bar_of_its_own(capsys):
    with pg.task("outer", 2, True) as outer:
        with pg.task("inner", 5) as inner:
            pg.advance(5)  # dropped: the outer bar counts its own units
        outer.update(2)
    err = capsys.readouterr().err
    assert _bar_in(err, "outer") and "inner" not in err
    assert inner is pg._NULL


def test_auto_bar_waits_for_long_work(monkeypatch):
    """Auto mode on a terminal: nothing for work shorter than AUTO_SECONDS (tqdm's delay)."""
    stream = _Tty()
    monkeypatch.setattr(pg, "sys", types.SimpleNamespace(stderr=stream))
    with pg.task("short", 3) as b:
        b.update(3)
    assert stream.getvalue() == ""


# ---------------------------------------------------------------------------- the calls
def _draw(rng):
    return {"a": rng.normal(size=3), "b": rng.uniform()}


def test_montecarlo_bar(capsys, tty):
    quiet = montecarlo.run(_draw, 40, seed=5, progress=False, chunk=4)
    assert tty.getvalue() == ""
    auto = montecarlo.run(_draw, 40, seed=5, chunk=4)  # a terminal: auto draws
    assert _bar_in(tty.getvalue(), "realizations")
    for k in ("a", "b"):
        assert np.array_equal(quiet.mean[k], auto.mean[k])
        assert np.array_equal(quiet.std_error[k], auto.std_error[k])


def test_montecarlo_off_a_terminal_and_forced(capsys):
    off = montecarlo.run(_draw, 20, seed=1)
    assert capsys.readouterr().err == ""  # captured stderr is not a terminal
    on = montecarlo.run(_draw, 20, seed=1, progress=True)
    assert _bar_in(capsys.readouterr().err, "realizations")
    assert np.array_equal(off.mean["a"], on.mean["a"])


def test_radio_sweep_bar(capsys):
    rough = GaussianCorrelation(2e-3, 2e-2)
    f = np.array([2e9, 10e9, 28e9])
    off = radio_sweep.sweep(rough, frequencies=f)
    assert capsys.readouterr().err == ""
    on = radio_sweep.sweep(rough, frequencies=f, progress=True)
    assert _bar_in(capsys.readouterr().err, "frequency sweep")
    for key in ("emscatter_h_db", "emscatter_v_db", "ament_db", "boithias_db", "k_sigma"):
        assert np.array_equal(off[key], on[key])


def test_radio_tables_bar(capsys):
    rough = GaussianCorrelation(1e-3, 1e-2)
    opts = radio_tables.TableOptions(n_cos=33, n_cos_spm=5, n_theta=8, n_alpha=7, n_s=12)
    radio_tables.clear_cache()
    off = radio_tables.build_tables(rough, 5 + 0.3j, 3e9, options=opts, label="wall")
    assert capsys.readouterr().err == ""
    radio_tables.clear_cache()  # a real build again, not the reused one
    on = radio_tables.build_tables(rough, 5 + 0.3j, 3e9, options=opts, label="wall", progress=True)
    assert _bar_in(capsys.readouterr().err, "radio tables wall 3 GHz")
    assert on is not off
    for name in ("lobe", "incoherent", "coherent", "coherent_power"):
        assert np.array_equal(getattr(off, name), getattr(on, name))
    radio_tables.clear_cache()


def test_emissivity_bar(capsys, monkeypatch):
    monkeypatch.setenv("EMSCATTER_CACHE", "0")  # compute both times
    rough = GaussianCorrelation(0.02, 0.1)
    ti = np.radians([10.0, 40.0, 60.0])
    kw = dict(wavelength=1.0, theta_i=ti, method="spm", tol=1e-3)
    off = emissivity(rough, 3 + 0.1j, **kw)
    assert capsys.readouterr().err == ""
    on = emissivity(rough, 3 + 0.1j, progress=True, **kw)
    err = capsys.readouterr().err
    assert _bar_in(err, "emissivity") and "σ⁰" in err
    for name in ("emissivity", "coherent", "incoherent", "error"):
        assert np.array_equal(getattr(off, name), getattr(on, name))
    with pytest.raises(ValueError, match="progress must be True, False or None"):
        emissivity(rough, 3 + 0.1j, progress="on", **kw)


def test_mom3d_bar(capsys):
    flat = GaussianCorrelation(1e-9, 3 / K)
    ts = np.radians([0.0, 30.0])
    kw = dict(realizations=2, length=3.0, seed=2)
    off = mom3d.bistatic(flat, "pec", K, 0.2, ts, math.pi, **kw)
    cap = capsys.readouterr()
    assert cap.err == "" and cap.out == ""  # no more prints on stdout either
    on = mom3d.bistatic(flat, "pec", K, 0.2, ts, math.pi, progress=True, **kw)
    assert _bar_in(capsys.readouterr().err, "mom3d realizations")
    assert np.array_equal(off.sigma0, on.sigma0)
    assert np.array_equal(off.coherent, on.coherent)


# ---------------------------------------------------------------------------- the commands
CURVES = ["curves", "--quantity", "emissivity", "--sigma", "0.02", "--length", "0.1",
          "--wavelength", "1", "--eps", "3+0.1j", "--method", "spm", "--theta-i-deg", "10,40",
          "--tol", "1e-3"]  # fmt: skip


def test_curves_quiet(tty, monkeypatch, capsys):
    monkeypatch.setenv("EMSCATTER_CACHE", "0")
    assert main(CURVES) == 0
    assert _bar_in(tty.getvalue(), "emissivity")  # a terminal: the bar
    tty.seek(0)
    tty.truncate()
    assert main([*CURVES, "--quiet"]) == 0
    assert tty.getvalue() == ""
    assert "method: spm" in capsys.readouterr().err  # the command's own line stays


def test_validate_and_bench_take_quiet(monkeypatch, capfd):
    from emscatter.cli import build_parser

    a = build_parser().parse_args(["validate", "--quiet"])
    assert a.quiet is True
    seen = {}

    def call(cmd, env=None):  # the benchmark runner's process: record what it is given
        seen["cmd"], seen["env"] = cmd, env
        return 0

    monkeypatch.setattr("subprocess.call", call)
    assert main(["bench", "--quiet", "--list"]) == 0
    assert seen["env"]["EMSCATTER_PROGRESS"] == "0"
    assert main(["bench", "--list"]) == 0
    assert seen["env"] is None
