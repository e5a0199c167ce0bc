"""The NMM3D table reader and the statistics of ``validation/auto/nmm3d_table.py`` (issue 20),
on samples written here: the table itself is not in the repository."""

from __future__ import annotations

import importlib.util
import math
import pathlib
import sys

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).parents[1] / "validation"


def _load(name, path):
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    sys.path.insert(0, str(ROOT))
    try:
        spec.loader.exec_module(mod)
    finally:
        sys.path.remove(str(ROOT))
    return mod


lut = _load("nmm3d_lut", ROOT / "nmm3d_lut.py")
SAMPLE = """\
40   4.00   3.00   1.00    0.021    -27.29    -28.25      -Inf
40   4.00   3.00   1.00    0.042    -20.73    -21.79    -37.00
20   7.00   5.50   2.00    0.084    -12.00    -13.50    -30.00
"""


def test_reader_keeps_the_angle_and_the_missing_hv(tmp_path):
    p = tmp_path / "lut.dat"
    p.write_text(SAMPLE)
    t = lut.read_lut(p)
    assert t.shape == (2, 8)
    assert t[0, 7] == -math.inf and t[1, 7] == -37.0
    assert t[:, 4].tolist() == [0.021, 0.042]
    assert lut.read_lut(p, theta_deg=20.0)[0, 1] == 7.0


def test_reader_names_the_bad_line(tmp_path):
    p = tmp_path / "bad.dat"
    p.write_text(SAMPLE + "40 4.00 3.00 1.00 0.063 -17.96\n")
    with pytest.raises(ValueError, match=r"line 4: 6 columns, expected 8"):
        lut.read_lut(p)
    p.write_text(SAMPLE)
    with pytest.raises(ValueError, match="no row at theta = 60"):
        lut.read_lut(p, theta_deg=60.0)


def test_grid_is_the_tables_162_cases():
    g = lut.grid()
    assert g.shape == (162, 8) and np.isnan(g[:, 5:]).all()
    ks = 2 * np.pi * np.unique(g[:, 4])
    assert ks.min() == pytest.approx(0.132, abs=1e-3) and ks.max() == pytest.approx(1.319, abs=1e-3)


def test_stats_leave_out_zero_hv_and_missing_exact_and_count_them():
    table = _load("nmm3d_table", ROOT / "auto" / "nmm3d_table.py")
    exact = np.array([-20.0, -30.0, -np.inf, -25.0])
    model = np.array([-21.0, -np.inf, -40.0, -22.0])  # hv = 0 on row 1; NMM3D none on row 2
    s = table.stats(model, exact)
    assert s["n"] == 2 and s["zero"] == 1
    assert s["bias"] == pytest.approx(1.0)  # (−1 + 3) / 2
    assert s["rmse"] == pytest.approx(math.sqrt(5.0))
    assert math.isnan(table.stats(np.full(2, np.nan), exact[:2])["rmse"])
