"""The regrasp of a turned irregular part: its place in the tree, and its logic on a hand-filled blackboard.

The Pick, Place and Inspect under the decorator are the real ones in the structure tests; the logic
tests swap that sequence for a scripted one that writes the yaw error an Inspect would, so only the
tree's decisions are under test (when the part is picked up again, how often, and when it gives up).
"""

from __future__ import annotations

import math
from collections.abc import Iterable

import py_trees
import pytest
from py_trees.common import Access, Status

from bt_arrange.behaviours import GraspGuard, Inspect, Pick, Place, keys
from bt_arrange.decorators import RepeatUntilWithin
from bt_arrange.objects import ObjectType
from bt_arrange.shapes import Prism
from bt_arrange.trees import Target
from bt_arrange.trees.steps import (
    CAMERA_YAW_MARGIN_DEG,
    MAX_TURNED_REGRASPS,
    REGRASP_ANY_YAW_DEG,
    REGRASP_YAW_DEG,
    regrasp_while_turned,
    turned_limit_deg,
)

FRAGMENT_OUTLINE_M = [[0, 0], [0.045, 0.004], [0.060, 0.030], [0.035, 0.028], [0.030, 0.050], [0.005, 0.040]]
FRAGMENT = ObjectType("fragment", shape=Prism.from_outline(FRAGMENT_OUTLINE_M, 0.02))
ORANGE = Target("orange", 0.50, -0.14, math.radians(-120), object_type=FRAGMENT)
RED_CUBE = Target("red", 0.45, 0.10)
OFFSET = keys.key("orange", keys.OFFSET_MM)
YAW = keys.key("orange", keys.YAW_ERROR_DEG)


@pytest.fixture(autouse=True)
def clean_blackboard() -> Iterable[None]:
    py_trees.blackboard.Blackboard.clear()
    yield
    py_trees.blackboard.Blackboard.clear()


def write(offset_mm: float, yaw_error_deg: float) -> None:
    client = py_trees.blackboard.Client(name="inspect after placing")
    client.register_key(OFFSET, access=Access.WRITE)
    client.register_key(YAW, access=Access.WRITE)
    client.set(OFFSET, offset_mm, overwrite=True)
    client.set(YAW, yaw_error_deg, overwrite=True)


class PickPlaceInspect(py_trees.behaviour.Behaviour):
    """Stands for Pick, Place and Inspect again: RUNNING for a tick (the arm moves), then writes the next yaw error."""

    def __init__(self, yaw_errors_deg: Iterable[float]) -> None:
        super().__init__(name="pick and place orange again")
        self.yaw_errors_deg = list(yaw_errors_deg)
        self.runs = 0
        self._ticks = 0

    def initialise(self) -> None:
        self._ticks = 0

    def update(self) -> Status:
        self._ticks += 1
        if self._ticks < 2:
            return Status.RUNNING
        self.runs += 1
        write(0.4, self.yaw_errors_deg.pop(0))
        return Status.SUCCESS


def scripted(yaw_errors_deg: Iterable[float]) -> tuple[RepeatUntilWithin, PickPlaceInspect]:
    """The decorator as built, its pick-and-place-again sequence swapped for a script."""
    node = regrasp_while_turned(ORANGE)
    assert isinstance(node, RepeatUntilWithin)
    script = PickPlaceInspect(yaw_errors_deg)
    node.children = [script]
    node.decorated = script
    script.parent = node
    return node, script


def run(node: py_trees.behaviour.Behaviour, max_ticks: int = 50) -> int:
    ticks = 0
    node.tick_once()
    ticks += 1
    while node.status == Status.RUNNING and ticks < max_ticks:
        node.tick_once()
        ticks += 1
    return ticks


def test_the_regrasp_picks_the_part_again_at_its_camera_pose_places_it_and_looks_again() -> None:
    node = regrasp_while_turned(ORANGE)
    assert isinstance(node, RepeatUntilWithin)
    assert node.yaw_threshold_deg == REGRASP_YAW_DEG and node.max_attempts == MAX_TURNED_REGRASPS
    assert math.isinf(node.threshold_mm), "only the yaw decides a regrasp: pushes close an offset"
    pick, guard, look = node.decorated.children
    assert isinstance(pick, Pick) and pick.grasp is None and pick.object_type == FRAGMENT
    assert isinstance(guard, GraspGuard) and isinstance(guard.decorated, Place)
    assert isinstance(look, Inspect) and look.after_placing


def test_an_irregular_part_s_tree_regrasps_between_the_inspect_after_placing_and_the_pushes() -> None:
    names = [child.name for child in one_part(ORANGE).children]
    assert names.index("inspect orange after placing") + 1 == names.index(
        f"regrasp orange while turned {1.0 - CAMERA_YAW_MARGIN_DEG:g} deg or more"
    )
    assert names[-1].startswith("correct orange")


@pytest.mark.parametrize(
    ("yaw_threshold_deg", "rechecked", "limit_deg"),
    [
        # The example's 1 deg: turned past it less the camera's yaw margin (0.92 deg) is placed again.
        (1.0, False, 1.0 - CAMERA_YAW_MARGIN_DEG),
        (3.0, False, 3.0 - CAMERA_YAW_MARGIN_DEG),
        (0.25, False, REGRASP_YAW_DEG),  # finer: presses square it, placed again from 1.5 deg
        (0.99, False, REGRASP_YAW_DEG),
        (None, False, REGRASP_ANY_YAW_DEG),  # position only
        (1.0, True, REGRASP_ANY_YAW_DEG),  # a later neighbour's recheck reads it again: as before
    ],
)
def test_how_far_turned_a_free_part_is_placed_again(
    yaw_threshold_deg: float | None, rechecked: bool, limit_deg: float
) -> None:
    assert turned_limit_deg(yaw_threshold_deg, rechecked) == pytest.approx(limit_deg)


def test_a_plan_s_yaw_threshold_sets_the_regrasp_of_its_tree() -> None:
    names = [child.name for child in one_part(ORANGE, yaw_threshold_deg=3.0).children]
    assert "regrasp orange while turned 2.92 deg or more" in names
    names = [child.name for child in one_part(ORANGE, yaw_threshold_deg=None).children]
    assert f"regrasp orange while turned {REGRASP_ANY_YAW_DEG:g} deg or more" in names


def test_a_cuboid_s_tree_has_no_regrasp() -> None:
    # The fallback of a correction that stalls places any free part again: not a regrasp while turned.
    assert not [node for node in one_part(RED_CUBE).iterate() if "regrasp" in node.name or "while turned" in node.name]


def test_a_part_placed_nearly_square_is_not_picked_again_and_nothing_waits_a_tick() -> None:
    write(0.8, REGRASP_YAW_DEG - 0.5)
    node, script = scripted([])
    node.tick_once()
    assert node.status == Status.SUCCESS and script.runs == 0


def test_a_part_within_a_coarse_yaw_threshold_by_less_than_the_camera_s_yaw_margin_is_placed_again() -> None:
    # 0.95 deg measured, under the 1 deg threshold but within the camera's error of it: placed again.
    node = regrasp_while_turned(ORANGE, yaw_limit_deg=turned_limit_deg(1.0))
    write(0.4, 0.95)
    script = PickPlaceInspect([0.1])
    node.children, node.decorated, script.parent = [script], script, node
    run(node)
    assert node.status == Status.SUCCESS and script.runs == 1


def test_a_part_turned_60_deg_is_picked_and_placed_again_until_it_lies_square() -> None:
    write(3.0, 60.0)
    node, script = scripted([-0.6])
    run(node)
    assert node.status == Status.SUCCESS and script.runs == 1
    assert node.feedback_message == "offset 0.40 mm, yaw error -0.60 deg after 1 correction(s)"


def test_the_sign_of_the_turn_does_not_matter() -> None:
    write(3.0, -25.0)
    node, script = scripted([30.0, 0.2])
    run(node)
    assert node.status == Status.SUCCESS and script.runs == 2


def test_a_part_still_turned_after_the_last_regrasp_fails_saying_its_yaw() -> None:
    write(3.0, 60.0)
    node, script = scripted([55.0, 58.0, 0.0])
    run(node)
    assert node.status == Status.FAILURE and script.runs == MAX_TURNED_REGRASPS
    assert "yaw error +58.0" in node.feedback_message


def test_no_inspect_before_the_regrasp_is_a_failure_not_a_blind_pick() -> None:
    node, script = scripted([0.0])
    node.tick_once()
    assert node.status == Status.FAILURE and script.runs == 0


def one_part(target, threshold_mm=1.0, yaw_threshold_deg=1.0):  # noqa: ANN001, ANN201
    """Algorithm 1 for one part placed free, as a compiled plan renders it."""
    from bt_arrange.plan import ArrangementPlan, PartStep, Tolerance
    from bt_arrange.trees import render_part

    return render_part(PartStep.free(target), ArrangementPlan.of([target], Tolerance(threshold_mm, yaw_threshold_deg)))
