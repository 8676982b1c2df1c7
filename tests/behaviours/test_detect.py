"""Detect: the measured pose under the object's name, or why the camera cannot give it."""

from __future__ import annotations

import math

import numpy as np
import pytest
from behaviour_helpers import AWAY_Q, assert_never_blocks, exists, read, set_up, write
from py_trees.common import Status

from bt_arrange.behaviours import Context, Detect, stages
from bt_arrange.geometry import PlanarPose, Pose, fold_yaw
from bt_arrange.robot import PixelWindow
from bt_arrange.testing import fake_arm, fake_camera, make_context, part, tick_until_done

# -- Detect --------------------------------------------------------------------------------------


def test_detect_writes_the_measured_pose_under_the_object_name(clock) -> None:
    context = make_context(clock=clock, parts=[part("red", 0.55, -0.12, math.radians(20.0)), part("blue", 0.4, 0.15)])
    run = tick_until_done(set_up(Detect("detect the first", "first", colour="red"), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    pose = read("/first/pose")
    assert isinstance(pose, Pose)
    assert 1000 * math.hypot(pose.x_m - 0.55, pose.y_m + 0.12) < 0.5
    assert math.degrees(fold_yaw(pose.yaw_rad - math.radians(20.0))) == pytest.approx(0.0, abs=0.5)
    assert pose.z_m == pytest.approx(0.025, abs=1e-6)
    assert run.feedback.startswith("red at x=0.55")
    assert not exists("/red/pose")
    assert fake_arm(context).commands == [], "a parked arm does not move to look"


def test_detect_parks_the_arm_before_looking(clock) -> None:
    context = make_context(clock=clock, q=AWAY_Q, parts=[part("green", 0.5, 0.0)])
    run = tick_until_done(set_up(Detect("detect green", "green"), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    assert run.ticks[0].feedback == stages.PARK
    assert_never_blocks(run)
    camera = fake_camera(context)
    assert len(camera.captures) == 2, "a binned full view to find the cube, a window to measure it"
    search, measure = camera.windows
    assert search == PixelWindow.full(camera.intrinsics, search.binning) and search.binning > 1
    assert measure is not None and measure.binning == 1
    assert measure.width_px * measure.height_px < 0.1 * camera.intrinsics.width_px * camera.intrinsics.height_px
    for time_s, q in camera.captures:
        assert q is not None
        np.testing.assert_allclose(q, context.home_q, atol=1e-9)
        assert time_s > fake_arm(context).commands[-1].time_s, "the camera looks once the arm stands still at home"


@pytest.mark.parametrize(
    ("cubes", "status", "why"),
    [
        ([part("blue", 0.5, 0.0)], "not_found", "no red blob"),
        ([part("red", 0.245, 0.0)], "partial", "cut by the image border"),
        ([part("red", 0.45, -0.1), part("red", 0.55, 0.1)], "ambiguous", "two red cubes"),
    ],
    ids=["not_found", "partial", "ambiguous"],
)
def test_detect_of_a_cube_the_camera_cannot_see_fails_saying_why(clock, cubes, status: str, why: str) -> None:
    context = make_context(clock=clock, parts=cubes)
    run = tick_until_done(set_up(Detect("detect red", "red"), context), context)
    assert run.status == Status.FAILURE, why
    assert run.feedback.startswith(f"red {status}: ")
    assert len(run.feedback) > len(f"red {status}: ") + 10, "the detector's reason follows"
    assert not exists("/red/pose")


def test_detect_of_an_unknown_colour_fails_naming_it_before_looking(context: Context) -> None:
    run = tick_until_done(set_up(Detect("detect purple", "purple"), context), context)
    assert run.status == Status.FAILURE
    assert "unknown colour 'purple'" in run.feedback
    assert "red" in run.feedback, "the known colours are listed"
    assert fake_camera(context).captures == []
    assert fake_arm(context).commands == []


def test_detect_among_identical_parts_2_mm_apart_picks_the_free_one_not_the_pair_between_targets(clock) -> None:
    # Two placed green cubes 2 mm apart merge into one blob in a binned view, its centre between
    # their targets (at neither): the search among identical parts reads the full frame instead.
    placed = [PlanarPose(0.452, 0.0, 0.0), PlanarPose(0.504, 0.0, 0.0)]
    free = PlanarPose(0.40, -0.20, 0.0)
    context = make_context(clock=clock, parts=[part("green", p.x_m, p.y_m) for p in (*placed, free)])
    write({"/green 3/target": PlanarPose(0.556, 0.0, 0.0)})
    kind_targets = [*placed, PlanarPose(0.556, 0.0, 0.0)]
    detect = Detect("detect green 3", "green 3", colour="green", kind_targets=kind_targets)
    run = tick_until_done(set_up(detect, context), context)
    assert run.status == Status.SUCCESS, run.feedback
    pose = read("/green 3/pose")
    assert 1000 * math.hypot(pose.x_m - free.x_m, pose.y_m - free.y_m) < 0.5


def test_detect_among_identical_parts_chooses_a_free_one_nearest_its_own_target(clock) -> None:
    # Four green cubes: two at targets of their kind (one of them right beside the own target),
    # two free. Detect takes the free one nearer the own target, never a placed one.
    placed = [PlanarPose(0.45, 0.10, 0.0), PlanarPose(0.45, 0.0, 0.0)]
    own = PlanarPose(0.45, -0.09, 0.0)
    near_free, far_free = PlanarPose(0.62, -0.15, 0.0), PlanarPose(0.65, 0.20, 0.0)
    context = make_context(clock=clock, parts=[part("green", p.x_m, p.y_m) for p in (*placed, far_free, near_free)])
    write({"/green 3/target": own})
    detect = Detect("detect green 3", "green 3", colour="green", kind_targets=[*placed, own])
    run = tick_until_done(set_up(detect, context), context)
    assert run.status == Status.SUCCESS, run.feedback
    pose = read("/green 3/pose")
    assert isinstance(pose, Pose)
    assert 1000 * math.hypot(pose.x_m - near_free.x_m, pose.y_m - near_free.y_m) < 0.5


def test_detect_when_every_identical_part_is_at_a_target_fails_saying_so(clock) -> None:
    placed = [PlanarPose(0.45, 0.10, 0.0), PlanarPose(0.45, 0.0, 0.0)]
    context = make_context(clock=clock, parts=[part("green", p.x_m, p.y_m) for p in placed])
    write({"/green 2/target": placed[1]})
    detect = Detect("detect green 2", "green 2", colour="green", kind_targets=placed)
    run = tick_until_done(set_up(detect, context), context)
    assert run.status == Status.FAILURE
    assert "lie at targets of their kind" in run.feedback
