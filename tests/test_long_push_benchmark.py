"""benchmarks/long_push.py: a turned staged piece's long push home, in the headless pybullet cell."""

from __future__ import annotations

import json

import pytest
from benchmark_modules import load_benchmark

from bt_arrange.behaviours import square_pushes


@pytest.fixture
def long_push(monkeypatch: pytest.MonkeyPatch):  # noqa: ANN201
    # The benchmark's --across-limit-mm replaces the rule in its module: put it back after each test.
    monkeypatch.setattr(square_pushes, "long_push_across_limit_mm", square_pushes.long_push_across_limit_mm)
    return load_benchmark("long_push.py", "long_push_benchmark")


@pytest.mark.parametrize(("limit", "landed"), [([], 2), (["--across-limit-mm", "1"], 0)], ids=["now", "held to 1 mm"])
def test_a_piece_turned_2_deg_and_3_mm_beside_its_line_is_pushed_home_square(long_push, capsys, limit, landed) -> None:
    argv = ["--tiles", "1", "--turns-deg", "2", "--across-mm", "3", *limit]
    assert long_push.main(argv) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    runs = [json.loads(line) for line in lines[:-1]]
    assert [run["across_mm"] for run in runs] == [3.0, -3.0]
    assert all(run["status"] == "SUCCESS" and abs(run["final_yaw_deg"]) < 0.5 for run in runs), runs
    assert sum(run["final_mm"] < 0.5 for run in runs) == landed, runs
    assert lines[-1].startswith(f"{landed} of 2 long pushes of 20 mm ended within 0.5 mm and 0.5 deg")
