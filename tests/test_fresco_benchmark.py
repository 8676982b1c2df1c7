"""benchmarks/fresco.py's cell options: parsed and handed to the run as ``bt-arrange run`` does (no simulation)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from benchmark_modules import load_benchmark


@pytest.fixture(scope="module")
def fresco():  # noqa: ANN201
    return load_benchmark("fresco.py", "fresco_benchmark")


def test_the_cell_and_its_calibration_are_parsed(fresco, tmp_path: Path) -> None:
    camera = tmp_path / "camera.toml"
    camera.write_text("")
    args = fresco.parse_args(["--pieces", "5", "--cell", "real", "--calibration", str(camera), "--seeds", "0", "4"])
    assert (args.cell, args.calibration, args.seeds, args.pieces) == ("real", camera, [0, 4], 5)
    assert fresco.parse_args([]).cell == "ideal" and fresco.parse_args([]).calibration is None


@pytest.mark.parametrize(
    ("argv", "said"),
    [
        (["--cell", "real"], "--cell real needs --calibration FILE"),
        (["--calibration", "no/such/camera.toml"], "no/such/camera.toml: no such file"),
    ],
)
def test_a_real_cell_without_its_calibration_is_one_line(fresco, capsys, argv: list[str], said: str) -> None:
    with pytest.raises(SystemExit) as stop:
        fresco.parse_args(argv)
    assert stop.value.code == 2
    error = capsys.readouterr().err.strip().splitlines()[-1]
    assert said in error and "Traceback" not in error


def test_the_run_gets_the_cell_its_seed_and_the_calibration(fresco, monkeypatch, tmp_path: Path) -> None:
    """As ``bt-arrange run --cell real --calibration FILE``: the cell, the run's seed for its errors, the file."""
    opened: list[dict[str, Any]] = []

    class Opened(Exception):
        pass

    simulator = type(fresco.backends.load(fresco.backends.DEFAULT_BACKEND))

    class Backend(simulator):  # the simulator's scatter, a run that stops where it would start
        def open_run(self, root: object, starts: object, **options: Any) -> None:
            opened.append(options)
            raise Opened

    monkeypatch.setattr(fresco.backends, "load", lambda name: Backend())
    camera = tmp_path / "camera.toml"
    with pytest.raises(Opened):
        fresco.run_once(3, 3, 2.0, None, 100, cell="real", calibration=camera)
    with pytest.raises(Opened):
        fresco.run_once(3, 3, 2.0, None, 100)
    assert opened == [{"cell": "real", "run_seed": 3, "calibration": camera}, {}]


def test_a_seed_whose_fracture_cannot_be_built_is_its_own_line_and_the_seeds_go_on(fresco, monkeypatch, capsys) -> None:
    def run_once(seed: int, *args: Any, **options: Any) -> dict:
        if seed == 8:
            return {"seed": 8, "pieces": 5, "gap_mm": 2.0, "plan_error": "no order and approach builds this plan"}
        return {
            "seed": seed,
            "pieces": 5,
            "within": 5,
            "within_by_camera": 4,
            "within_run_threshold": 5,
            "min_gap_truth_mm": 1.2,
            "max_moved_by_later_truth_mm": 0.01,
        }

    monkeypatch.setattr(fresco, "run_once", run_once)
    assert fresco.main(["--pieces", "5", "--seeds", "7", "8", "9"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert [line.split(",")[0] for line in lines[:3]] == ['{"seed": 7', '{"seed": 8', '{"seed": 9']
    assert '"plan_error": "no order and approach builds this plan"' in lines[1]
    assert lines[-1].startswith("gap 2 mm: 10 of 10 pieces within 1 mm and 1 deg by ground truth (8 confirmed")
    assert lines[-1].endswith("; no plan built at seed 8")


def test_a_plan_error_building_the_fracture_is_returned_not_raised(fresco, monkeypatch) -> None:
    def unbuildable(path: Path) -> None:
        raise fresco.PlanError("no order and approach builds this plan (in any order): tile 2 has no room")

    monkeypatch.setattr(fresco.treefile, "load", unbuildable)
    result = fresco.run_once(8, 5, 2.0, None, 100)
    assert result == {
        "seed": 8,
        "pieces": 5,
        "gap_mm": 2.0,
        "plan_error": "no order and approach builds this plan (in any order): tile 2 has no room",
    }
