"""Inspect: the offset from the target, in the target's frame, through a window around it."""

from __future__ import annotations

import math

import pytest
from behaviour_helpers import cube_pose, exists, read, set_up, write
from py_trees.common import Status

from bt_arrange.behaviours import Inspect, Recheck, offset_in_target_frame_mm
from bt_arrange.geometry import PlanarPose, Pose
from bt_arrange.objects import ObjectType
from bt_arrange.shapes import Prism
from bt_arrange.testing import fake_camera, make_context, part, tick_until_done

# -- Inspect -------------------------------------------------------------------------------------


def test_offset_in_target_frame_is_target_minus_pose_turned_into_the_target() -> None:
    pose = cube_pose(0.502, -0.001, 0.3)
    assert offset_in_target_frame_mm(PlanarPose(0.5, 0.0, 0.0), pose) == pytest.approx((-2.0, 1.0))
    assert offset_in_target_frame_mm(PlanarPose(0.5, 0.0, math.pi / 2), pose) == pytest.approx((1.0, 2.0))
    assert offset_in_target_frame_mm(PlanarPose(0.5, 0.0, math.pi), pose) == pytest.approx((2.0, -1.0))


@pytest.mark.parametrize(
    ("target_yaw_rad", "expected_xy_mm"),
    [(0.0, (-2.0, 1.0)), (math.pi / 2, (1.0, 2.0))],
    ids=["target yaw 0", "target yaw 90 deg"],
)
def test_inspect_writes_target_minus_pose_in_the_target_frame(clock, target_yaw_rad, expected_xy_mm) -> None:
    context = make_context(clock=clock, parts=[part("red", 0.502, -0.001, 0.2)])
    write({"/red/target": PlanarPose(0.5, 0.0, target_yaw_rad)})
    run = tick_until_done(set_up(Inspect("inspect red", "red"), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    dx_mm, dy_mm = read("/red/offset_xy_mm")
    assert (dx_mm, dy_mm) == pytest.approx(expected_xy_mm, abs=0.3)
    assert read("/red/offset_mm") == pytest.approx(math.hypot(dx_mm, dy_mm))
    assert read("/red/offset_mm") == pytest.approx(math.sqrt(5.0), abs=0.3)
    assert isinstance(read("/red/pose"), Pose)
    assert run.feedback.endswith(f"; {read('/red/offset_mm'):.2f} mm from the target")
    assert read("/red/measured_on") == "whole face"
    assert not exists("/red/placed_offset_mm"), "only an inspection after placing records it"


def test_inspect_after_placing_also_records_the_placed_offset(clock) -> None:
    context = make_context(clock=clock, parts=[part("yellow", 0.45, 0.1)])
    write({"/yellow/target": PlanarPose(0.45, 0.103, 0.0)})
    inspect = Inspect("inspect yellow after placing", "yellow", after_placing=True)
    run = tick_until_done(set_up(inspect, context), context)
    assert run.status == Status.SUCCESS, run.feedback
    assert read("/yellow/placed_offset_mm") == read("/yellow/offset_mm")
    assert read("/yellow/placed_offset_mm") == pytest.approx(3.0, abs=0.3)


def test_inspect_of_a_cube_it_cannot_see_fails_and_leaves_the_offsets_alone(clock) -> None:
    context = make_context(clock=clock, parts=[])
    write({"/red/target": PlanarPose(0.5, 0.0), "/red/offset_mm": 4.0})
    run = tick_until_done(set_up(Inspect("inspect red", "red", after_placing=True), context), context)
    assert run.status == Status.FAILURE
    assert run.feedback.startswith("red not_found: ")
    assert read("/red/offset_mm") == 4.0
    assert not exists("/red/placed_offset_mm")
    assert read("/red/measured_on") == "not measured", "the offset left is stale: it no longer confirms the part"


def test_inspect_looks_through_a_window_around_the_target_only(clock) -> None:
    context = make_context(clock=clock, parts=[part("red", 0.507, 0.004, 0.3), part("blue", 0.4, 0.15)])
    write({"/red/target": PlanarPose(0.5, 0.0)})
    run = tick_until_done(set_up(Inspect("inspect red", "red"), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    camera = fake_camera(context)
    (window,) = camera.windows
    assert window is not None and window.binning == 1
    assert window.width_px * window.height_px < 0.1 * camera.intrinsics.width_px * camera.intrinsics.height_px
    assert read("/red/offset_mm") == pytest.approx(math.hypot(7.0, 4.0), abs=0.3)


def test_inspect_searches_the_whole_view_for_a_cube_far_from_its_target(clock) -> None:
    context = make_context(clock=clock, parts=[part("red", 0.62, -0.2, 0.3)])
    write({"/red/target": PlanarPose(0.5, 0.0)})
    run = tick_until_done(set_up(Inspect("inspect red", "red"), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    target_window, search, measure = fake_camera(context).windows
    assert target_window is not None and search is not None and measure is not None
    assert search.binning > 1 and measure.binning == 1 and measure != target_window
    pose = read("/red/pose")
    assert 1000 * math.hypot(pose.x_m - 0.62, pose.y_m + 0.2) < 0.5


def test_a_detection_in_a_window_is_the_full_frames(clock) -> None:
    context = make_context(clock=clock, parts=[part("green", 0.47, 0.06, 0.4)])
    camera, detector = fake_camera(context), context.detector
    window = detector.window_around(camera.intrinsics, camera.pose_world, 0.47, 0.06, 0.06)
    assert window is not None
    in_full, in_window = (
        detector.detect(camera.capture(), "green"),
        detector.detect(camera.capture(window=window), "green"),
    )
    assert in_full.found and in_window.found
    assert (
        1000 * math.hypot(in_full.planar.x_m - in_window.planar.x_m, in_full.planar.y_m - in_window.planar.y_m) < 0.01
    )


# -- Recheck: a placed part looked at again ------------------------------------------------------

TRIANGLE = ObjectType("triangle", shape=Prism.from_outline([[0, 0], [0.06, 0], [0, 0.06]], 0.02))


@pytest.mark.parametrize("behaviour", [Inspect, Recheck])
def test_away_from_its_target_only_inspect_takes_the_one_blob_of_its_colour_whose_outline_fits(
    clock, behaviour: type[Inspect]
) -> None:
    # A red triangle far from its target and a red cube elsewhere: Inspect tells them apart by outline
    # and finds the triangle; a Recheck (of a part placed there, its face merged with a new neighbour's
    # in a real run) takes no part of its colour farther off than its own size, and fails saying so.
    parts = [part("red", 0.62, -0.2, 0.3, object_type=TRIANGLE), part("red", 0.4, 0.15)]
    context = make_context(clock=clock, parts=parts)
    write({"/red/target": PlanarPose(0.5, 0.0)})
    run = tick_until_done(set_up(behaviour("look at red", "red", object_type=TRIANGLE), context), context)
    if behaviour is Inspect:
        assert run.status == Status.SUCCESS, run.feedback
        pose = read("/red/pose")
        assert 1000 * math.hypot(pose.x_m - 0.62, pose.y_m + 0.2) < 1.0
    else:
        assert run.status == Status.FAILURE
        assert run.feedback == "red not_found: none within 80 mm of (0.500, 0.000) m, 2 red blobs farther off"
        assert not exists("/red/pose")
