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
