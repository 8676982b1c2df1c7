"""The run session of the framework (``bt_arrange.session``) against a kinematic fake world, no simulator.

``tests/fakeworld.py``'s ``FakeWorld`` holds, carries and pushes synthetic cubes that its camera
renders; it has no ground truth unless asked, so the report is camera only. The pybullet twin of
these checks (``SimulatedRun`` on a fake cell) is ``tests/test_runs.py``.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import py_trees
import pytest
from fakeworld import FakeWorld, camera_view

from bt_arrange.behaviours import Inspect
from bt_arrange.errors import PlanError
from bt_arrange.objects import ObjectStart
from bt_arrange.runner import Transition
from bt_arrange.session import SETTLE_S, GroundTruth, Session, World
from bt_arrange.trees import Arrangement, Target, arrangement, set_target, transfer

TESTS = Path(__file__).resolve().parent
ROOT = TESTS.parent
RED = Target("red", 0.50, 0.05)
GREEN = Target("green", 0.50, -0.05)
RED_START = ObjectStart("red", 0.42, -0.22, 0.1)
GREEN_START = ObjectStart("green", 0.58, -0.22, 0.1)


class Opener:
    """``open_world`` for a session: builds a ``FakeWorld`` and remembers it (or that it never was)."""

    def __init__(self, **options: object) -> None:
        self.options = options
        self.worlds: list[FakeWorld] = []

    def __call__(self) -> FakeWorld:
        world = FakeWorld(**self.options)  # type: ignore[arg-type]
        self.worlds.append(world)
        return world

    @property
    def world(self) -> FakeWorld:
        (world,) = self.worlds
        return world


def session(root: py_trees.behaviour.Behaviour, starts: list[ObjectStart], opener: Opener, **options) -> Session:  # noqa: ANN003
    return Session(root, starts, opener, view=camera_view(), **options)


def test_the_fake_world_is_a_world_and_its_truth_a_ground_truth() -> None:
    assert isinstance(FakeWorld(), World)
    assert FakeWorld().truth is None
    assert isinstance(FakeWorld(truth=True).truth, GroundTruth)


def test_an_arrangement_runs_through_the_session_on_a_world_without_truth() -> None:
    opener = Opener(release_errors_m={"red": (0.003, -0.002)})  # red lands off its target: pushes correct it
    with session(arrangement([RED, GREEN]), [RED_START, GREEN_START], opener) as run:
        report = run.run()
    assert opener.world.closed
    assert report.tree_status == "SUCCESS" and report.all_within_threshold
    assert not report.ground_truth and report.to_dict()["ground_truth"] is False
    red, green = report.objects
    assert red.pushes >= 1 and green.pushes == 0
    for outcome, target in ((red, RED), (green, GREEN)):
        assert outcome.status == "within" and outcome.final_offset_mm is not None and outcome.final_offset_mm < 1.0
        # Camera only: no ground truth figure is made up.
        assert outcome.final_offset_truth_mm is None and outcome.placed_offset_truth_mm is None
        assert outcome.final_yaw_error_truth_deg is None and outcome.moved_by_later_truth_mm is None
        # The fake world itself agrees: the cube is within the threshold of its target.
        x, y, _ = opener.world.poses()[target.obj]
        assert math.hypot(x - target.x_m, y - target.y_m) * 1000 < 1.0
    assert red.placed_offset_mm is not None and red.placed_offset_mm > 3.0


def test_a_world_with_truth_fills_the_truth_figures() -> None:
    opener = Opener(truth=True)
    with session(arrangement([RED]), [RED_START], opener) as run:
        report = run.run()
    (red,) = report.objects
    assert report.ground_truth and "ground_truth" not in report.to_dict()
    x, y, _ = opener.world.poses()["red"]
    assert red.final_offset_truth_mm == pytest.approx(math.hypot(x - RED.x_m, y - RED.y_m) * 1000, abs=1e-4)
    assert red.placed_offset_truth_mm is not None and red.final_yaw_error_truth_deg is not None


def test_a_recorded_run_writes_the_log_the_images_the_report_and_the_replay(tmp_path) -> None:
    with session(arrangement([RED]), [RED_START], Opener(), record_dir=tmp_path, title="fake run") as run:
        report = run.run()
    lines = (tmp_path / "transitions.jsonl").read_text().splitlines()
    assert len(lines) == len(report.transitions) and json.loads(lines[0])["time_s"] == pytest.approx(SETTLE_S)
    assert "facts" not in json.loads(lines[0])  # no behaviour states facts yet: the log is as before
    for image in ("before_picking", "after_placing_red", "after_pushing"):
        assert (tmp_path / f"{image}.png").is_file()
    assert json.loads((tmp_path / "report.json").read_text())["ground_truth"] is False
    assert "fake run" in (tmp_path / "replay.html").read_text()


def test_the_hooks_are_called_as_the_tree_runs() -> None:
    calls: dict[str, int] = {"transition": 0, "tick": 0, "runner": 0}
    with session(arrangement([RED]), [RED_START], Opener()) as run:
        run.transition_hooks.append(lambda t: calls.__setitem__("transition", calls["transition"] + 1))
        run.tick_hooks.append(lambda root: calls.__setitem__("tick", calls["tick"] + 1))
        run.runner_hooks.append(lambda runner: calls.__setitem__("runner", calls["runner"] + 1))
        report = run.run()
    assert calls["runner"] == 1 and calls["transition"] == len(report.transitions) and calls["tick"] > 100


def test_an_inspect_named_otherwise_still_records_the_after_placing_figures(tmp_path) -> None:
    inspect = Inspect("look at red once it is down", "red", after_placing=True)
    root = Arrangement("mine", [set_target(RED), transfer(RED), inspect], [RED], 1.0)
    run = session(root, [RED_START], Opener(truth=True), record_dir=tmp_path)
    run._on_transition(
        Transition(1.0, inspect.name, "Inspect", "RUNNING", "SUCCESS", "0.10 mm", str(inspect.id), "red")
    )
    start_mm = math.hypot(RED_START.x_m - RED.x_m, RED_START.y_m - RED.y_m) * 1000
    placed = run.placements.first["red"].offset_truth_mm
    assert placed == pytest.approx(start_mm, abs=1e-3)  # the cube still at its start
    assert (tmp_path / "after_placing_red.png").is_file()


def test_an_inspect_that_does_not_record_placing_is_not_taken_for_one() -> None:
    inspect = Inspect("inspect red after placing", "red")  # the name says so, the flag does not
    root = Arrangement("mine", [set_target(RED), inspect], [RED], 1.0)
    run = session(root, [RED_START], Opener(truth=True))
    run._on_transition(Transition(1.0, inspect.name, "Inspect", "RUNNING", "SUCCESS", "", str(inspect.id), "red"))
    assert run.placements.first == {}


def test_an_object_stopped_by_the_time_limit_says_so() -> None:
    with session(arrangement([RED]), [RED_START], Opener(), time_limit_s=0.02) as run:
        report = run.run()
    (red,) = report.objects
    assert report.timed_out and red.status == "failed"
    assert red.reason == "stopped after 0.02 s of world time"
    assert not report.all_within_threshold


def test_the_session_counts_world_time_from_the_start_of_the_tree() -> None:
    opener = Opener()
    run = session(arrangement([RED]), [RED_START], opener)
    assert opener.world.clock.now() == pytest.approx(SETTLE_S)
    assert run.elapsed_s() == pytest.approx(0.0)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"starts": []}, r"^target red: no part 'red' in the scene \(the scene has none\)$"),
        ({"starts": [ObjectStart("red", 0.30, 0.45, 0.0)]}, r"^part red starts at x 300 mm, y 450 mm, outside"),
        ({"time_limit_s": 0}, r"^time limit 0 s must be a positive number of seconds$"),
        ({"root": "tree"}, r"^the root must be a py_trees behaviour, got str$"),
    ],
)
def test_a_bad_run_is_refused_before_the_world_is_built(kwargs, message) -> None:
    arguments = {"root": arrangement([RED]), "starts": [RED_START], **kwargs}
    opener = Opener()
    with pytest.raises(PlanError, match=message):
        session(arguments.pop("root"), arguments.pop("starts"), opener, **arguments)
    assert opener.worlds == []


def test_a_custom_root_still_has_its_scene_checked_and_recording_into_a_file_is_refused(tmp_path) -> None:
    opener = Opener()
    with pytest.raises(PlanError, match="unknown colour 'purple'"):
        session(py_trees.behaviours.Success("done"), [ObjectStart("purple", 0.5, 0.0, 0.0)], opener)
    a_file = tmp_path / "report.txt"
    a_file.write_text("x")
    with pytest.raises(PlanError, match=r"^cannot record into .*report\.txt: it is a file, not a folder$"):
        session(arrangement([RED]), [RED_START], opener, record_dir=a_file)
    assert opener.worlds == []


#: A whole arrangement through the session on the fake world, in a process of its own.
SESSION_SCRIPT = """
import json, sys
sys.path.insert(0, {tests!r})
from fakeworld import FakeWorld, camera_view
from bt_arrange.objects import ObjectStart
from bt_arrange.session import Session
from bt_arrange.trees import Target, arrangement
targets = [Target("red", 0.50, 0.05), Target("green", 0.50, -0.05)]
starts = [ObjectStart("red", 0.42, -0.22, 0.1), ObjectStart("green", 0.58, -0.22, 0.1)]
with Session(arrangement(targets), starts, FakeWorld, view=camera_view()) as run:
    report = run.run()
simulator = sorted(m for m in sys.modules if m.split(".")[0] in ("pybullet", "bt_arrange_sim"))
print(json.dumps({{"report": report.to_dict(), "simulator": simulator}}))
"""


def test_a_whole_arrangement_through_the_session_imports_no_simulator() -> None:
    result = subprocess.run(
        [sys.executable, "-c", SESSION_SCRIPT.format(tests=str(TESTS))],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=ROOT,
    )
    assert result.returncode == 0, result.stderr
    summary = json.loads(result.stdout.splitlines()[-1])
    assert summary["simulator"] == []
    report = summary["report"]
    assert report["tree_status"] == "SUCCESS" and report["objects_within"] == 2
    assert report["ground_truth"] is False
    assert all(o["final_offset_truth_mm"] is None and o["status"] == "within" for o in report["objects"])


#: The command line with the fake world registered as backend ``fake``, in a process of its own:
#: it prints, last, whether a simulator module was ever imported and what the backend scattered.
CLI_SCRIPT = """
import json, sys
sys.path.insert(0, {tests!r})
from fakeworld import FakeBackend
from bt_arrange import backends, cli
backends.register("fake", FakeBackend)
codes = [cli.main(["run", name, "--backend", "fake"] + extra) for name, extra in {runs!r}]
simulator = sorted(m for m in sys.modules if m.split(".")[0] in ("pybullet", "bt_arrange_sim"))
print(json.dumps({{"codes": codes, "simulator": simulator, "scattered": FakeBackend.scattered}}))
"""


def test_plans_and_xml_trees_run_on_the_chosen_backend_without_a_simulator() -> None:
    runs = [("four_cubes", ["--json"]), (str(ROOT / "trees" / "single_cube.xml"), [])]
    result = subprocess.run(
        [sys.executable, "-c", CLI_SCRIPT.format(tests=str(TESTS), runs=runs)],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=ROOT,
    )
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    summary = json.loads(lines[-1])
    # Both files asked the fake backend for their starts, and no simulator module was imported.
    assert summary["scattered"] == [[["red", "green", "blue", "yellow"], 0], [["red"], 0]]
    # The parser reads the default backend's experiment rows for --help (bt_arrange_sim.experiment,
    # which imports no pybullet); the run itself needs none of the simulator.
    assert "pybullet" not in summary["simulator"] and "bt_arrange_sim.pybullet.runs" not in summary["simulator"]
    assert summary["codes"] == [0, 0]
    plan_report = json.loads(lines[0])
    assert plan_report["ground_truth"] is False and plan_report["objects_within"] == 4
    assert all(o["final_offset_truth_mm"] is None for o in plan_report["objects"])
    table = "\n".join(lines[1:-1])
    assert "camera only: this world has no ground truth" in table
    header = next(line for line in lines if line.startswith("object"))
    assert "truth" not in header and "pushed" in header
    assert "single_cube.xml: 1 of 1 objects within 1 mm" in table


@pytest.mark.parametrize("last_look", ["not measured", "free edges"])
def test_a_part_whose_last_look_cannot_confirm_it_is_unconfirmed_not_within(last_look: str) -> None:
    """Within by an earlier offset, but the last look lost the part or saw only its free edges: unconfirmed."""
    from bt_arrange.trees import plan_of

    arranged = arrangement([RED])
    lost = py_trees.behaviours.SetBlackboardVariable("the last look", "/red/measured_on", last_look, overwrite=True)
    root = py_trees.composites.Sequence("root", memory=True, children=[arranged, lost])
    with session(root, [RED_START], Opener(), plan=plan_of(arranged)) as run:
        report = run.run()
    (red,) = report.objects
    assert red.final_offset_mm is not None and red.final_offset_mm < 1.0
    assert red.status == "unconfirmed" and not report.all_within_threshold
    assert report.within_text().startswith("0 of 1 objects within")
