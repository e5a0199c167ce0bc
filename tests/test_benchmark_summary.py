"""The generated benchmark summary: every row names an existing result file and a command, and
the issue-22 speed rows come from the newest run of each benchmark."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[1] / "benchmarks"


@pytest.fixture(scope="module")
def summary_modules():
    sys.path.insert(0, str(BENCH))
    try:
        import summary
        import summary_speed

        yield summary, summary_speed
    finally:
        sys.path.remove(str(BENCH))


def test_every_row_names_a_result_file_and_a_command(summary_modules):
    summary, _ = summary_modules
    rows = summary.rows()
    assert rows
    for what, _target, _measured, met, cmd, file in rows:
        assert (BENCH / "results" / f"{file}.json").exists(), (what, file)
        assert cmd and "benchmarks/" in cmd, (what, cmd)
        assert met in ("**yes**", "no", ""), (what, met)


def test_speed_rows_read_the_newest_run(summary_modules, tmp_path, monkeypatch):
    _, speed = summary_modules
    old = {"machine": {"date": "2026-01-01 00:00:00 +0000"}, "speed": {}}
    new = {
        "machine": {"date": "2026-06-01 00:00:00 +0000", "load_average": [0.5, 0, 0]},
        "command": "python benchmarks/bench_api.py --out api_speed_b",
        "speed": {
            "go_1000000": {
                "api_numba": {"per_s": 3e7},
                "kernel": {"per_s": 1e8},
                "api_over_solver_numba": 1.1,
                "api_numba_over_numpy": 7.9,
                "api_numba_over_cook_torrance": 4.2,
            }
        },
    }
    (tmp_path / "api_speed_a.json").write_text(json.dumps(new))
    (tmp_path / "api_speed_b.json").write_text(json.dumps(old))
    monkeypatch.setattr(speed, "RESULTS", tmp_path)
    rows = speed._api_rows()
    assert {r[5] for r in rows} == {"api_speed_a"}
    met = {r[0]: r[3] for r in rows}
    assert met["GO through the API: compiled / numpy"] == "no"  # 7.9 < 8
    assert met["GO through the API / a plain numpy Cook–Torrance"] == "**yes**"
