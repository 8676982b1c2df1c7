"""``run --inject`` and ``run --cell real``: refused in one line before anything moves, passed on to the backend.

No simulator runs here: a spy stands in for the work cell, and the sim backend's ``open_run`` is
replaced where the test only needs to see what reaches it. ``tests/integration/test_injection.py``
runs four cubes with the translation error injected.
"""

from __future__ import annotations

import contextlib
import io
import shlex
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import py_trees
import pytest

import bt_arrange_sim.pybullet.cell
import bt_arrange_sim.pybullet.runs
from bt_arrange import backends, cli, cli_run
from bt_arrange.errors import PlanError
from bt_arrange.report import ObjectOutcome, SessionReport
from bt_arrange.trees import Target, arrangement
from bt_arrange_sim.engine import CellBackend
from bt_arrange_sim.experiment.rows import ROW_INJECTORS
from bt_arrange_sim.injection.named import ERRORS, Injected, _specs, check_named, part_seed, parts_of
from bt_arrange_sim.injection.registry import make_injector

TREES = Path(__file__).resolve().parents[1] / "trees"
FOUR = str(TREES / "four_cubes.py")
KNOWN = "translation, orientation, perception, surface, slip, sticking, release, tilt, all"


class Simulated(BaseException):
    """Raised by the spies: the command got as far as building a world."""


@pytest.fixture(autouse=True)
def no_world(monkeypatch: pytest.MonkeyPatch) -> None:
    def spy(*_: object, **__: object) -> None:
        raise Simulated

    monkeypatch.setattr(bt_arrange_sim.pybullet.runs, "WorkCell", spy)
    monkeypatch.setattr(bt_arrange_sim.pybullet.cell, "WorkCell", spy)


def call(argv: list[str]) -> tuple[int | str, str, str]:
    """Run the CLI in-process: the exit code, or "simulated" when a spy was reached."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code: int | str = cli.main(argv)
        except SystemExit as exit_:
            code = exit_.code if isinstance(exit_.code, int) else 2
        except Simulated:
            code = "simulated"
    return code, out.getvalue(), err.getvalue()


def one_line(code: int | str, err: str) -> str:
    assert code == 2, (code, err)
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("bt-arrange: error: "), err
    return lines[0]


@pytest.mark.parametrize("tree", [FOUR, str(TREES / "four_cubes.toml"), str(TREES / "four_cubes.xml"), "four_cubes"])
def test_an_unknown_error_is_one_line_naming_the_known_ones(tree: str) -> None:
    code, out, err = call(["run", tree, "--inject", "nonsense"])
    assert one_line(code, err) == f"bt-arrange: error: --inject nonsense: unknown error; the errors are {KNOWN}"
    assert out == ""


@pytest.mark.parametrize(
    ("value", "says"),
    [
        ("translation,tranlsation", "--inject tranlsation: unknown error (did you mean 'translation'?)"),
        (",", "--inject is empty; the errors are"),
        ("system", "--inject system: unknown error"),  # a row, but one that injects nothing
        ("pick_translation", "--inject pick_translation: unknown error"),  # an injector's name, not an error's
    ],
)
def test_a_bad_inject_list_is_refused_in_one_line(value: str, says: str) -> None:
    code, _, err = call(["run", FOUR, "--inject", value])
    assert says in one_line(code, err)


def test_the_known_errors_are_the_experiment_rows_that_inject_into_the_run_s_parts() -> None:
    assert ", ".join(ERRORS) == KNOWN
    assert all(ROW_INJECTORS[error] for error in ERRORS)
    assert CellBackend().injectable_errors == ERRORS
    # The help names the same ones.
    code, out, _ = call(["run", "--help"])
    help_text = " ".join(out.split())
    assert code == 0
    assert "translation, orientation, perception, surface, slip, sticking, release, tilt, or all" in help_text


def test_the_errors_reach_the_backend_with_the_run_s_seed(monkeypatch: pytest.MonkeyPatch) -> None:
    seen: dict[str, Any] = {}

    def open_run(self: object, root: object, starts: object, **options: Any) -> None:
        seen.update(options)
        raise Simulated

    monkeypatch.setattr(CellBackend, "open_run", open_run)
    assert call(["run", FOUR, "--inject", "translation, tilt,translation", "--seed", "1"])[0] == "simulated"
    assert (seen["inject"], seen["inject_seed"]) == (["translation", "tilt"], 1)
    seen.clear()
    assert call(["run", FOUR])[0] == "simulated"
    assert "inject" not in seen


def test_the_sim_backend_refuses_an_unknown_error_before_building_the_world() -> None:
    root = arrangement([Target("red", 0.5, 0.0)])
    backend = CellBackend()
    with pytest.raises(Exception, match="--inject bogus: unknown error"):
        backend.open_run(root, backend.scatter(["red"], 0), inject=["bogus"])


def test_a_backend_that_cannot_inject_refuses_in_one_line(monkeypatch: pytest.MonkeyPatch) -> None:
    class Robot:
        name = "robot"
        experiment = None

        def open_run(self, *args: object, **options: object) -> None:
            raise Simulated

        def scatter(self, colours, seed, avoid=(), object_types=None, names=None):  # noqa: ANN001, ANN201
            return CellBackend().scatter(colours, seed, avoid, object_types, names)

        def check(self):  # noqa: ANN201
            yield "ok"

        def prepare_out(self, path: Path) -> Path:
            return path

    monkeypatch.setattr(backends, "_registered", {"robot": Robot})
    code, _, err = call(["run", FOUR, "--backend", "robot", "--inject", "translation"])
    assert one_line(code, err) == (
        "bt-arrange: error: backend 'robot' cannot inject errors (--inject): it has no simulated world to put them in"
    )
    assert call(["run", FOUR, "--backend", "robot"])[0] == "simulated"


def test_a_real_cell_without_a_calibration_is_refused_with_the_command_that_calibrates() -> None:
    code, out, err = call(["run", FOUR, "--cell", "real"])
    line = one_line(code, err)
    assert line == (
        "bt-arrange: error: --cell real needs a calibrated camera (its nominal one puts parts centimetres off): "
        "bt-arrange calibrate --cell real --out camera.toml, then add --calibration camera.toml"
    )
    assert out == ""
    # The command it gives is one the command line takes.
    args = cli.build_parser().parse_args(shlex.split(cli_run.CALIBRATE_COMMAND)[1:])
    assert (args.cell, str(args.out)) == ("real", "camera.toml")


def test_all_is_every_error_in_the_row_s_order_each_named_by_its_own_row() -> None:
    assert _specs(["all"]) == [
        ("perception", "perception_offset"),
        ("translation", "pick_translation"),
        ("orientation", "pick_rotation"),
        ("surface", "surface_shift"),
        ("slip", "transport_slip"),
        ("sticking", "release_stick"),
        ("release", "release_height"),
        ("tilt", "release_tilt"),
    ]
    assert [spec for _, spec in _specs(["all"])] == list(ROW_INJECTORS["all"])
    assert _specs(["tilt", "translation"]) == [("translation", "pick_translation"), ("tilt", "release_tilt")]
    assert _specs(["tilt", "all"]) == _specs(["all"])


def test_the_parts_are_those_the_tree_picks_in_tick_order_then_the_plan_s_other_targets() -> None:
    targets = [Target("green", 0.45, -0.05), Target("red", 0.45, 0.05)]
    root = arrangement(targets)
    run = SimpleNamespace(root=root, plan=None, cell=SimpleNamespace(parts={"red": 1, "green": 2, "blue": 3}))
    assert parts_of(run) == ["green", "red"]
    run.plan = SimpleNamespace(targets=[*targets, Target("blue", 0.55, 0.05), Target("pink", 0.55, -0.05)])
    assert parts_of(run) == ["green", "red", "blue"]  # pink is no part of the cell
    run.root, run.plan = py_trees.behaviours.Success("a puzzle's survey"), None
    assert parts_of(run) == []
    with pytest.raises(PlanError, match="^--inject: this tree names no part it picks"):
        check_named(run.root)


def test_each_part_draws_from_its_own_seed() -> None:
    seeds = {part_seed(1, part) for part in ("red", "green", "blue", "yellow")}
    assert len(seeds) == 4 and part_seed(1, "red") == part_seed(1, "red") != part_seed(2, "red")


def test_the_report_lists_what_was_injected_into_which_part_at_the_experiment_s_magnitudes() -> None:
    injector = make_injector("pick_translation")
    injector.obj, injector.fired, injector.details = "red", True, {"dx_mm": 3.0}
    record = Injected("translation", "red", injector).record()
    assert record == {
        "error": "translation",
        "part": "red",
        "injector": "pick_translation",
        "max_m": 0.025,
        "fired": True,
        "dx_mm": 3.0,
    }
    outcome = ObjectOutcome("red", (0.45, 0.05, 0.0), 3.0, 0.2, 0.2, 3.0, 1, "within")
    report = SessionReport([outcome], "SUCCESS", 1.0, 10.0, 1.0, False)
    assert "injected" not in report.to_dict()
    report.injected = [record]
    assert report.to_dict()["injected"] == [record]
    assert cli_run._injected_line([record, {**record, "part": "blue", "fired": False}]) == (
        "injected: translation into red, blue (not reached) (the experiment's magnitudes; what each did: --json)"
    )


def test_a_tree_that_names_no_part_it_picks_is_refused_before_the_world_is_built() -> None:
    code, _, err = call(["run", "puzzle", "--inject", "translation"])
    assert "--inject: this tree names no part it picks (a puzzle's pieces are named by its solve)" in one_line(
        code, err
    )
