"""SimulatedRun, the session on a pybullet cell, checks everything before it builds the cell.

A ``FakeCell`` (fake devices, synthetic camera) stands in for the pybullet cell, so these run in
milliseconds and can tell whether a world was ever built. What every session does, whatever its
world, is tested in ``tests/test_session.py``.
"""

from __future__ import annotations

from pathlib import Path

import py_trees
import pytest

from bt_arrange import session
from bt_arrange.errors import PlanError
from bt_arrange.session import Session, SessionReport, World
from bt_arrange.testing import FakeClock, make_context, part
from bt_arrange.trees import Target, arrangement
from bt_arrange_sim.pybullet import runs
from bt_arrange_sim.scenes import PartStart

RED = Target("red", 0.50, 0.0)
RED_START = PartStart("red", 0.40, -0.20, 0.0)


class FakeCell:
    """What SimulatedRun uses of a WorkCell, over the fake devices of the testing kit (bt_arrange.testing)."""

    built: list[FakeCell] = []

    def __init__(self, config: object = None, gui: bool = False) -> None:
        self.clock = FakeClock()
        self.context = make_context(clock=self.clock)
        self.robot = self.context.robot
        self.camera = self.robot.camera
        self.starts: dict[str, PartStart] = {}
        self.parts = self.starts  # the names of the parts, as the cell's body ids by name
        FakeCell.built.append(self)

    def add_parts(self, starts) -> None:
        for start in starts:
            self.starts[start.name or start.colour] = start
        self.camera.parts = [part(s.colour, s.x_m, s.y_m, s.yaw_rad) for s in self.starts.values()]

    def settle(self, seconds: float) -> None:
        self.clock.advance(seconds)

    def step(self) -> None:
        self.clock.advance(0.008)

    #: What ``parts_at_rest`` answers (the fake's parts never move unless a test says so).
    resting = True

    def parts_at_rest(self) -> bool:
        return self.resting

    def part_planar_truth(self, name: str) -> tuple[float, float, float]:
        start = self.starts[name]
        return start.x_m, start.y_m, start.yaw_rad

    def close(self) -> None:
        pass


@pytest.fixture
def fake_cell(monkeypatch: pytest.MonkeyPatch) -> type[FakeCell]:
    FakeCell.built = []
    monkeypatch.setattr(runs, "WorkCell", FakeCell)
    return FakeCell


def test_the_run_counts_world_time_from_the_start_of_the_tree(fake_cell) -> None:  # item 9: live view vs report
    run = runs.SimulatedRun(arrangement([RED]), [RED_START])
    # The scene settles only as long as its parts move: these rest at once.
    assert run.cell.clock.now() == pytest.approx(runs.RESTING_PERIODS * 0.008)
    assert run.elapsed_s() == pytest.approx(0.0)


def test_the_scene_settles_while_a_part_moves_at_most_the_settle_time(
    fake_cell, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(FakeCell, "resting", False)
    run = runs.SimulatedRun(arrangement([RED]), [RED_START])
    assert run.cell.clock.now() == pytest.approx(round(runs.SETTLE_S / 0.008) * 0.008)


def test_a_simulated_run_is_a_session_on_the_cell_as_a_world(fake_cell) -> None:
    with runs.SimulatedRun(arrangement([RED]), [RED_START], time_limit_s=0.02) as run:
        assert isinstance(run, Session) and isinstance(run.world, runs.SimWorld) and isinstance(run.world, World)
        assert run.cell is fake_cell.built[0] and run.world.truth is run.world
        assert run.world.part_names() == ["red"] and run.part_of(RED) == "red"
        report = run.run()
    (red,) = report.objects
    assert report.ground_truth and red.final_offset_truth_mm == pytest.approx(223.607, abs=1e-3)
    assert runs.SimulationReport is SessionReport and runs.REASON_TYPES is session.REASON_TYPES


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"starts": []}, r"^target red: no part 'red' in the scene \(the scene has none\)$"),
        ({"starts": [PartStart("red", 0.30, 0.45, 0.0)]}, r"^part red starts at x 300 mm, y 450 mm, outside"),
        ({"time_limit_s": 0}, r"^time limit 0 s must be a positive number of seconds$"),
        ({"time_limit_s": -1.0}, r"^time limit -1\.0 s must be a positive number of seconds$"),
        ({"root": "tree"}, r"^the root must be a py_trees behaviour, got str$"),
    ],
)
def test_a_bad_run_is_refused_before_a_world_is_built(fake_cell, kwargs, message) -> None:
    arguments = {"root": arrangement([RED]), "starts": [RED_START], **kwargs}
    with pytest.raises(PlanError, match=message):
        runs.SimulatedRun(arguments.pop("root"), arguments.pop("starts"), **arguments)
    assert fake_cell.built == []


def test_a_custom_root_still_has_its_scene_checked(fake_cell) -> None:
    with pytest.raises(PlanError, match="unknown colour 'purple'"):
        runs.SimulatedRun(py_trees.behaviours.Success("done"), [PartStart("purple", 0.5, 0.0, 0.0)])
    assert fake_cell.built == []


def test_the_window_without_a_display_is_refused_first(fake_cell, monkeypatch) -> None:  # item 5
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    with pytest.raises(PlanError, match=r"^the pybullet window \(--gui\) needs a display, and DISPLAY is not set"):
        runs.SimulatedRun(arrangement([RED]), [RED_START], gui=True)
    assert fake_cell.built == []


def test_an_object_whose_name_has_a_space_keeps_its_reason(fake_cell) -> None:
    target = Target("red", 0.50, 0.0, name="red cube")
    start = PartStart("red", 0.40, -0.20, 0.0, name="red cube")
    with runs.SimulatedRun(arrangement([target], max_regrasps=0), [start]) as run:
        report = run.run()
    (red,) = report.objects
    assert red.name == "red cube" and red.status == "failed"
    # The fake gripper closes on nothing: Pick's reason, found by the node's type and object.
    assert red.reason.startswith("no part between the pads"), red.reason


def test_the_injectors_find_a_node_by_type_and_object_not_by_name() -> None:
    from bt_arrange import treefile
    from bt_arrange.behaviours import Place
    from bt_arrange_sim.injection import _NodeFinder

    root = treefile.build_root(treefile.load(Path(__file__).resolve().parents[1] / "trees" / "row_of_three.py"))
    named = [node for node in root.iterate() if node.name == "place red"]
    assert len(named) == 2 and {type(node) for node in named} == {Place, py_trees.composites.Sequence}
    found = _NodeFinder(Place, "red")(root)
    assert isinstance(found, Place) and found.obj == "red"
