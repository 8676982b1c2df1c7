"""The camera's own error as a margin under the threshold: the decorator, the source, the report."""

from __future__ import annotations

import py_trees
import pytest
from py_trees.common import Status
from test_decorators import OFFSET, push_then_inspect, write_offset

from bt_arrange.decorators import RepeatUntilWithin
from bt_arrange.geometry import Pose
from bt_arrange.robot import CameraIntrinsics
from bt_arrange.uncertainty import (
    CAMERA_MARGIN_KEY,
    IDEAL_CELL_CAMERA_MM,
    calibration_margin_mm,
    camera_margin_mm,
)


def loop(offsets_mm: list[float]) -> RepeatUntilWithin:
    child, _ = push_then_inspect(offsets_mm)
    return RepeatUntilWithin("correct red", child, offset_key=OFFSET, threshold_mm=1.0, max_attempts=5)


def run(decorator: RepeatUntilWithin, ticks: int = 20) -> Status:
    for _ in range(ticks):
        decorator.tick_once()
        if decorator.status != Status.RUNNING:
            break
    return decorator.status


def test_an_offset_under_the_threshold_but_not_with_the_margin_is_pushed_again() -> None:
    py_trees.blackboard.Blackboard.set(CAMERA_MARGIN_KEY, 0.04)
    write_offset(0.97)
    decorator = loop([0.5])
    assert run(decorator) == Status.SUCCESS
    assert decorator.attempts == 1
    assert "0.50 mm + camera 0.04 mm < 1.00 mm" in decorator.feedback_message


def test_without_a_margin_the_same_offset_is_within_at_once() -> None:
    write_offset(0.97)
    decorator = loop([0.5])
    assert run(decorator) == Status.SUCCESS
    assert decorator.attempts == 0


def test_the_failure_names_the_margin() -> None:
    py_trees.blackboard.Blackboard.set(CAMERA_MARGIN_KEY, 0.1)
    write_offset(0.95)
    decorator = RepeatUntilWithin("correct red", push_then_inspect([0.95])[0], OFFSET, 1.0, max_attempts=1)
    assert run(decorator) == Status.FAILURE
    assert "0.95 mm + camera 0.10 mm >= 1.00 mm after 1 correction(s)" in decorator.feedback_message


def test_a_part_a_neighbour_will_look_at_again_counts_the_margin_twice() -> None:
    """0.75 mm at a 0.8 mm threshold with a 0.04 mm camera: within once, not with a second reading's error."""
    py_trees.blackboard.Blackboard.set(CAMERA_MARGIN_KEY, 0.04)
    write_offset(0.75)
    once = RepeatUntilWithin("correct red", push_then_inspect([0.3])[0], OFFSET, 0.8, max_attempts=5)
    assert run(once) == Status.SUCCESS and once.attempts == 0
    write_offset(0.75)
    twice = RepeatUntilWithin("correct red", push_then_inspect([0.3])[0], OFFSET, 0.8, max_attempts=5, margins=2)
    assert run(twice) == Status.SUCCESS and twice.attempts == 1
    assert "0.30 mm + camera 0.08 mm < 0.80 mm" in twice.feedback_message


def test_the_parts_later_steps_look_at_again_get_two_margins_in_the_tree() -> None:
    from trees.dense_row import create_root

    loops = {
        node.obj: node.margins
        for node in create_root().iterate()
        if isinstance(node, RepeatUntilWithin) and node.name.startswith("correct") and " after " not in node.name
    }
    # A row of four 2 mm apart: each but the last is the next one's neighbour, looked at again.
    assert loops == {"red": 2, "green": 2, "blue": 2, "yellow": 1}


def test_a_neighbour_never_placed_is_not_looked_at_again() -> None:
    """A part whose transfer failed lies where it started: a later step's recheck passes it by."""
    from bt_arrange.behaviours import keys
    from trees.dense_row import create_root

    guard = next(n for n in create_root().iterate() if n.name == "look again at red after green if it was placed")
    check = guard.children[0].decorated
    assert check.variable_name == keys.key("red", keys.PLACED_OFFSET_MM)
    py_trees.blackboard.Blackboard.unset(keys.key("red", keys.PLACED_OFFSET_MM))
    guard.tick_once()
    assert guard.status == Status.SUCCESS
    assert guard.children[1].status == Status.INVALID  # the recheck and its correction never ran


class Calibration:
    def __init__(self, reprojection_error_px: float, height_m: float, fx_px: float) -> None:
        self.reprojection_error_px = reprojection_error_px
        self.camera_to_base = Pose.from_planar(0.5, 0.0, 0.0, z_m=height_m)
        self.intrinsics = CameraIntrinsics(
            fx_px=fx_px, fy_px=fx_px, cx_px=959.5, cy_px=539.5, width_px=1920, height_px=1080
        )


def test_a_calibrated_camera_s_margin_is_twice_its_rms_at_the_table_s_scale() -> None:
    calibration = Calibration(0.153, 0.70, 1371.0)
    assert calibration_margin_mm(calibration) == pytest.approx(2 * 0.153 * 700 / 1371.0)
    margin, source = camera_margin_mm(calibration, world=None)
    assert margin == pytest.approx(0.156, abs=1e-3)
    assert "0.153 px RMS" in source


def test_the_world_s_figure_without_a_calibration_and_none_without_either() -> None:
    class IdealWorld:
        camera_margin_mm = IDEAL_CELL_CAMERA_MM

    margin, source = camera_margin_mm(None, IdealWorld())
    assert margin == IDEAL_CELL_CAMERA_MM
    assert "perception benchmarks" in source
    margin, source = camera_margin_mm(None, object())
    assert margin == 0.0 and source.startswith("unknown")


# ----------------------------------------------------------------------------------------------
# Pushes that stop converging
# ----------------------------------------------------------------------------------------------


def test_corrections_that_close_nothing_end_the_loop_saying_so() -> None:
    write_offset(2.0)
    child, _ = push_then_inspect([1.2, 1.15, 1.12, 1.1, 0.5])
    decorator = RepeatUntilWithin("correct red", child, OFFSET, 1.0, max_attempts=10, obj="red", stall_after=3)
    assert run(decorator, ticks=40) == Status.FAILURE
    assert decorator.attempts == 4  # 2.0 -> 1.2 closed 40 %, then three that closed under 10 % each
    assert "pushes stopped converging: offset 1.10 mm after 4 correction(s)" in decorator.feedback_message
    assert py_trees.blackboard.Blackboard.get("/red/pushes_stalled") == "stalled"


def test_a_loop_that_keeps_closing_is_not_stalled() -> None:
    write_offset(2.0)
    child, _ = push_then_inspect([1.7, 1.5, 1.3, 1.1, 0.9])
    decorator = RepeatUntilWithin("correct red", child, OFFSET, 1.0, max_attempts=10, obj="red", stall_after=3)
    assert run(decorator, ticks=40) == Status.SUCCESS
    assert decorator.attempts == 5
    assert py_trees.blackboard.Blackboard.get("/red/pushes_stalled") == "no"


def test_a_second_loop_counts_on_from_the_first() -> None:
    corrections = "/red/corrections"
    write_offset(2.0)
    first = RepeatUntilWithin(
        "first", push_then_inspect([1.9, 1.9, 1.9])[0], OFFSET, 1.0, 10, corrections, obj="red", stall_after=2
    )
    assert run(first, ticks=40) == Status.FAILURE
    second = RepeatUntilWithin(
        "second", push_then_inspect([0.5])[0], OFFSET, 1.0, 10, corrections, obj="red", accumulate=True
    )
    assert run(second, ticks=40) == Status.SUCCESS
    assert py_trees.blackboard.Blackboard.get(corrections) == first.attempts + 1
