"""``emscatter.radio.farm.farm_tables``: radio tables of materials × frequencies serially, on a
process pool and on a dask LocalCluster — bit-identical, in order, equal to the single
builder's; every (material, frequency) checked before any work; worker warnings named."""

from __future__ import annotations

import concurrent.futures as cf
import dataclasses
import warnings

import numpy as np
import pytest

import emscatter as em
from emscatter import radio
from emscatter.parallel import limited_threads
from emscatter.radio.farm import farm_tables
from emscatter.radio.tables import EnergyWarning, clear_cache

SMALL = radio.TableOptions(n_cos=17, n_cos_spm=5, n_theta=8, n_alpha=9, n_s=16)
ROUGH = em.GaussianCorrelation(sigma=0.2e-3, length=5e-3)


def _walls():
    return {
        "concrete": radio.MaterialSpec(surface=ROUGH, medium="concrete", options=SMALL),
        "glass": radio.MaterialSpec(
            surface=em.GaussianCorrelation(sigma=0.5e-3, length=8e-3),
            medium=6.3 + 0.1j,
            method="po",
            options=SMALL,
        ),  # fmt: skip
        "flat": radio.MaterialSpec(surface=None, medium="wood", options=SMALL),
    }


FREQS = [28e9, 60e9]  # every surface inside its method's validity at both


def _same(a, b):
    """Every field equal bit for bit, except the build's wall-clock seconds."""
    for f in dataclasses.fields(a):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if f.name == "seconds":
            continue
        if isinstance(x, np.ndarray) or isinstance(y, np.ndarray):
            assert x is not None and y is not None, f.name
            assert x.dtype == y.dtype and x.tobytes() == y.tobytes(), f.name
        else:
            assert x == y, f.name


def test_serial_farm_equals_the_single_builder_in_order():
    clear_cache()
    tables = farm_tables(_walls(), FREQS, progress=False)
    assert list(tables) == [(m, f) for m in ("concrete", "glass", "flat") for f in FREQS]
    for (label, f), t in tables.items():
        clear_cache()  # a fresh build, not the reused object
        # at the farm's threads=1 (a threaded BLAS sum may differ in the last bit)
        with limited_threads(1, wheel_blas=True):
            ref = _walls()[label].tables(f, label=label)
        assert ref is not t
        _same(t, ref)
        assert t.label == label and t.frequency == f


def test_process_pool_and_dask_local_cluster_bit_identical_to_serial():
    clear_cache()
    serial = farm_tables(_walls(), FREQS, progress=False)
    with cf.ProcessPoolExecutor(2) as pool:
        pooled = farm_tables(_walls(), FREQS, client=pool, progress=False)
    pytest.importorskip("dask.distributed")
    dask = farm_tables(_walls(), FREQS, client="local", n_workers=2, progress=False)
    for key, t in serial.items():
        _same(t, pooled[key])
        _same(t, dask[key])
    assert not serial["concrete", 28e9].flat and serial["flat", 60e9].flat


def test_worker_warnings_come_back_once_named_with_the_table():
    # physical optics without shadowing puts more than 1 − r_coh into its lobe near grazing:
    # an EnergyWarning once the scaling starts below energy_warn_below_deg (test_radio_tables)
    opts = dataclasses.replace(SMALL, energy_warn_below_deg=89.5)
    rough = em.GaussianCorrelation(sigma=1e-3, length=10e-3)
    walls = {"wall": radio.MaterialSpec(surface=rough, medium=5.24 + 0.6j, method="po",
                                        options=opts)}  # fmt: skip
    with cf.ProcessPoolExecutor(1) as pool, warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        farm_tables(walls, [140e9], client=pool, progress=False)
    texts = [str(w.message) for w in caught if issubclass(w.category, EnergyWarning)]
    assert len(texts) == 1 and texts[0].startswith("radio tables 'wall' at 140 GHz: ")
    assert "scaled down" in texts[0]


class _Recording(cf.ThreadPoolExecutor):
    """A real executor that counts what it is given (a bad job must stop before any)."""

    submitted = 0

    def submit(self, *a, **k):
        type(self).submitted += 1
        return super().submit(*a, **k)


@pytest.mark.parametrize(
    "materials, freqs, message",
    [
        (
            {"w": radio.MaterialSpec(surface=ROUGH, medium="concrete")},
            [3.5e9, 500e9],
            "materials['w'] at 500 GHz: ",
        ),  # fmt: skip  (ITU-R P.2040 concrete: 1-100 GHz)
        (
            {"w": radio.MaterialSpec(surface=ROUGH, medium="unobtainium")},
            FREQS,
            "materials['w']: ",
        ),  # fmt: skip
        (
            {"w": radio.MaterialSpec(surface=ROUGH, medium="concrete", method="nope")},
            FREQS,
            "materials['w']: method must be one of",
        ),  # fmt: skip
        (
            {"w": radio.MaterialSpec(surface=ROUGH, medium="concrete", out_of_range="nan")},
            FREQS,
            "materials['w']: out_of_range must be one of",
        ),  # fmt: skip
        (
            {
                "w": radio.MaterialSpec(
                    surface=em.GaussianCorrelation(sigma=1e-3, length=1e-2, dimension=1),
                    medium="concrete",
                )
            },
            FREQS,
            "materials['w']: ",
        ),  # fmt: skip
        ({"w": "concrete"}, FREQS, "materials['w'] must be an emscatter.radio.MaterialSpec"),
        ({}, FREQS, "materials is empty"),
        ({"w": radio.MaterialSpec(medium="concrete")}, [28e9, -1.0], "got -1.0"),
        ({"w": radio.MaterialSpec(medium="concrete")}, [28e9, 28e9], "frequencies repeat"),
    ],
)
def test_bad_job_named_before_any_work(materials, freqs, message):
    _Recording.submitted = 0
    with _Recording(1) as pool, pytest.raises(ValueError) as err:
        farm_tables(materials, freqs, client=pool, progress=False)
    assert message in str(err.value)
    assert _Recording.submitted == 0


@pytest.mark.parametrize(
    "kw, message",
    [
        ({"client": "mpi://x"}, "client must be None (serial), 'local'"),
        ({"threads": 0}, "threads must be a positive integer"),
        ({"n_workers": 0}, "n_workers must be a positive integer"),
        ({"progress": "yes"}, "progress must be True, False or None"),
    ],
)
def test_bad_arguments(kw, message):
    with pytest.raises(ValueError) as err:
        farm_tables(_walls(), FREQS[:1], **kw)
    assert message in str(err.value)


def test_bar_counts_the_tables(capsys):
    clear_cache()
    farm_tables(_walls(), FREQS[:1], progress=True)
    err = capsys.readouterr().err
    assert "radio tables" in err and "/3" in err
