"""Push: the axis, the start behind the part, the slower limits, the turned part's corner, a bar."""

from __future__ import annotations

import math

import numpy as np
import pytest
from behaviour_helpers import (
    CUBE_EDGE_M,
    CUBE_GRASP_HEIGHT_M,
    CUBE_PUSH_REACH_M,
    SETTINGS,
    after,
    assert_never_blocks,
    bar_pose,
    cube_pose,
    read,
    set_up,
    write,
)
from py_trees.common import Status

from bt_arrange.behaviours import Context, Push, stages
from bt_arrange.geometry import PlanarPose, Pose, fold_yaw
from bt_arrange.motion import LinearMotion
from bt_arrange.objects import BAR, CUBE, ObjectType
from bt_arrange.shapes import ROBOTIQ_2F85, footprint_m, preferred_grasp
from bt_arrange.testing import Run, fake_arm, fake_gripper, make_context, tick_until_done

# -- Push ----------------------------------------------------------------------------------------

BAR_GRASP_HEIGHT_M = preferred_grasp(BAR.shape, ROBOTIQ_2F85).height_m


@pytest.mark.parametrize(
    ("preferred", "offset_xy_mm", "axis"),
    [
        ("x", (3.0, 2.0), "x"),
        ("y", (3.0, 2.0), "y"),
        ("x", (0.1, 2.0), "y"),
        ("y", (-2.0, -0.1), "x"),
        ("x", (0.1, 0.1), "x"),
        ("y", (0.1, 0.1), "y"),
        ("x", (0.2, 0.0), "x"),
    ],
    ids=["x kept", "y kept", "x too short", "y too short", "both too short", "both too short y", "x at min"],
)
def test_push_chooses_the_alternated_axis_unless_its_offset_is_below_min_push(preferred, offset_xy_mm, axis) -> None:
    assert Push.choose_axis(preferred, offset_xy_mm, min_push_mm=0.2) == axis


def push_setup(context: Context, pose: Pose, target_yaw_rad: float, offset_xy_mm: tuple[float, float]) -> Push:
    write({"/red/pose": pose, "/red/target": PlanarPose(0.0, 0.0, target_yaw_rad), "/red/offset_xy_mm": offset_xy_mm})
    return set_up(Push("push red", "red"), context)


def test_push_alternates_axes_through_the_blackboard(context: Context) -> None:
    pushed = []
    for _ in range(3):
        push = push_setup(context, cube_pose(0.5, 0.0), 0.0, (3.0, -2.0))
        run = tick_until_done(push, context)
        assert run.status == Status.SUCCESS, run.feedback
        pushed.append((run.feedback, read("/red/push_axis")))
    assert pushed == [
        ("pushed +3.00 mm along x", "y"),
        ("pushed -2.00 mm along y", "x"),
        ("pushed +3.00 mm along x", "y"),
    ]


def test_push_falls_back_to_the_other_axis_when_the_preferred_offset_is_below_min_push(context: Context) -> None:
    write({"/red/push_axis": "x"})
    run = tick_until_done(push_setup(context, cube_pose(0.5, 0.0), 0.0, (0.1, -2.5)), context)
    assert run.status == Status.SUCCESS, run.feedback
    assert run.feedback == "pushed -2.50 mm along y"
    assert read("/red/push_axis") == "x", "the next push goes along the other axis again"


def test_the_push_itself_runs_at_the_slower_push_limits(context: Context) -> None:
    push = push_setup(context, cube_pose(0.5, 0.0), 0.0, (6.0, 0.0))
    run = tick_until_done(push, context)
    assert run.status == Status.SUCCESS, run.feedback
    lines = {
        stage.name: stage.motion for stage in push._stages if isinstance(getattr(stage, "motion", None), LinearMotion)
    }
    pushing = lines["push 6.00 mm along x"]
    assert pushing.cartesian_limits.velocity_m_s <= SETTINGS.push_limits.velocity_m_s
    assert SETTINGS.push_limits.velocity_m_s < context.planner.cartesian_limits.velocity_m_s
    assert lines["lower the fingers"].cartesian_limits.velocity_m_s > SETTINGS.push_limits.velocity_m_s


def test_push_with_nothing_to_push_succeeds_without_moving(context: Context) -> None:
    run = tick_until_done(push_setup(context, cube_pose(0.5, 0.0), 0.0, (0.1, 0.15)), context)
    assert [t.status for t in run.ticks] == [Status.SUCCESS]
    assert run.feedback == "nothing to push: 0.10 mm along x"
    assert fake_arm(context).commands == []
    assert fake_gripper(context).commands == []


@pytest.mark.parametrize(
    ("target_yaw_rad", "offset_xy_mm", "direction", "distance_mm"),
    [
        (0.0, (3.0, 0.5), (1.0, 0.0), 3.0),
        (0.0, (0.05, -2.0), (0.0, -1.0), 2.0),
        (math.pi / 2, (2.5, 0.0), (0.0, 1.0), 2.5),
        (math.pi / 4, (-1.5, 0.0), (-math.sqrt(0.5), -math.sqrt(0.5)), 1.5),
    ],
    ids=["+x", "-y by fallback", "x of a turned target", "-x of a diagonal target"],
)
def test_push_starts_behind_the_cube_and_pushes_it_towards_the_target(
    clock, target_yaw_rad, offset_xy_mm, direction, distance_mm
) -> None:
    context = make_context(clock=clock)
    centre = np.array([0.5, 0.05])
    push = push_setup(context, cube_pose(*centre, 0.1), target_yaw_rad, offset_xy_mm)
    arm, s = fake_arm(context), SETTINGS
    towards = np.array(direction)
    across = np.array([-towards[1], towards[0]])

    run = tick_until_done(push, context, until=after(stages.WAIT_FOR_FINGERS))
    assert run.status == Status.RUNNING, run.feedback
    assert_never_blocks(run)
    behind = arm.tcp_pose()
    # The first waypoint: above the cube's far side from the target, clear of its face.
    from_centre = behind.position_m[:2] - centre
    assert from_centre @ towards == pytest.approx(-(CUBE_PUSH_REACH_M + s.push_clearance_m), abs=1e-6)
    assert from_centre @ across == pytest.approx(0.0, abs=1e-6)
    assert behind.z_m == pytest.approx(s.approach_height_m, abs=1e-6)
    # Fingers side by side along the pushed face: the closing axis lies across the push.
    assert fold_yaw(behind.yaw_rad - math.atan2(across[1], across[0]), math.pi) == pytest.approx(0.0, abs=1e-4)
    gripper = fake_gripper(context)
    # The cube (yaw 0.1 rad) is turned from the push: its leading corner on the middle of a pad.
    turn_rad = abs(fold_yaw(math.atan2(towards[1], towards[0]) - 0.1, math.pi / 2))
    corner_m = CUBE_EDGE_M * (math.cos(turn_rad) - math.sin(turn_rad))
    assert [(c.kind, c.value) for c in gripper.commands] == [
        ("open", pytest.approx(max(0.0, corner_m - s.gripper.pad_thickness_m)))
    ]

    before = len(arm.commands)
    rest = tick_until_done(push, context)
    assert rest.status == Status.SUCCESS, rest.feedback
    assert_never_blocks(rest)
    tcp = np.array([arm.tcp_pose_at(c.positions_rad).position_m for c in arm.commands[before:]])
    along = (tcp[:, :2] - centre) @ towards
    deepest = int(np.argmax(along))
    assert along[deepest] == pytest.approx(-CUBE_PUSH_REACH_M + distance_mm / 1000, abs=1e-6)
    assert tcp[deepest, 2] == pytest.approx(CUBE_GRASP_HEIGHT_M, abs=1e-6)
    np.testing.assert_allclose((tcp[:, :2] - centre) @ across, 0.0, atol=1e-6)
    assert along[-1] == pytest.approx(along[deepest] - s.push_clearance_m, abs=1e-6), "backed off"
    assert tcp[-1, 2] == pytest.approx(s.approach_height_m, abs=1e-6), "lifted"
    axis = "x" if "x" in rest.feedback else "y"
    assert rest.feedback == f"pushed {math.copysign(distance_mm, sum(offset_xy_mm)):+.2f} mm along {axis}"


def leading_corner_across_mm(pose: Pose, kind: ObjectType, towards: np.ndarray, line_xy: np.ndarray) -> float:
    """How far (mm) beside the pushing TCP's line the footprint's corner furthest along ``towards`` lies."""
    corners = footprint_m(kind.shape, pose.x_m, pose.y_m, pose.yaw_rad)
    leading = corners[int(np.argmax(corners @ towards))]
    across = np.array([-towards[1], towards[0]])
    return abs(float((leading - line_xy) @ across)) * 1000


@pytest.mark.parametrize("turn_deg", [0.0, 4.0, 9.42, 12.85, 20.0, 30.0, -12.85])
@pytest.mark.parametrize(
    ("kind", "axis"), [(CUBE, "x"), (CUBE, "y"), (BAR, "x"), (BAR, "y")], ids=["cube x", "cube y", "bar x", "bar y"]
)
def test_the_leading_corner_of_a_turned_part_meets_a_pad_not_the_gap_between_them(
    context: Context, kind: ObjectType, axis: str, turn_deg: float
) -> None:
    # Table 1's translation trial 62: placed 9.4 deg turned, the cube's leading corner lay between
    # the pads opened to the face's width (42 mm apart); each pad stopped on one of the faces
    # beside the corner, 4.2 mm short of home and turned 12.8 deg, and later pushes did not move it.
    offset_xy_mm = (-4.2, 0.0) if axis == "x" else (0.0, -3.2)
    towards = np.array([-1.0, 0.0]) if axis == "x" else np.array([0.0, -1.0])
    pose = Pose.from_planar(0.5, 0.05, math.radians(turn_deg), kind.size_m[2] / 2)
    write({"/red/pose": pose, "/red/target": PlanarPose(0.5, 0.05, 0.0), "/red/offset_xy_mm": offset_xy_mm})
    push = set_up(Push("push red", "red", object_type=kind), context)
    run = tick_until_done(push, context)
    assert run.status == Status.SUCCESS, run.feedback
    (opening,) = [c.value for c in fake_gripper(context).commands if c.kind == "open"]
    arm = fake_arm(context)
    tcp = np.array([arm.tcp_pose_at(c.positions_rad).position_m for c in arm.commands])
    low = tcp[tcp[:, 2] < SETTINGS.approach_height_m - 0.001, :2]  # lowered beside the part
    line_xy = low[int(np.argmax(low @ towards))]
    corner_mm = leading_corner_across_mm(pose, kind, towards, line_xy)
    inner_mm, outer_mm = opening * 500, opening * 500 + SETTINGS.gripper.pad_thickness_m * 1000
    assert inner_mm - 1e-6 <= corner_mm <= outer_mm + 1e-6, (
        f"the leading corner {corner_mm:.1f} mm beside the push's line misses the pads "
        f"({inner_mm:.1f} to {outer_mm:.1f} mm)"
    )


# -- a bar: grasp, push and squaring from the type's size ---------------------------


def push_bar_setup(context: Context, offset_xy_mm: tuple[float, float], yaw_error_deg: float | None = None) -> Push:
    values: dict[str, object] = {
        "/bar/pose": bar_pose(0.5, 0.05),
        "/bar/target": PlanarPose(0.5, 0.05, 0.0),
        "/bar/offset_xy_mm": offset_xy_mm,
    }
    if yaw_error_deg is not None:
        values["/bar/yaw_error_deg"] = yaw_error_deg
    write(values)
    push = Push("push bar", "bar", object_type=BAR, yaw_threshold_deg=None if yaw_error_deg is None else 1.0)
    return set_up(push, context)


def pushed_path(context: Context, push: Push) -> tuple[Run, np.ndarray]:
    """Run a push of the bar at (0.5, 0.05) along +x; its TCP positions relative to the bar."""
    run = tick_until_done(push, context)
    arm = fake_arm(context)
    tcp = np.array([arm.tcp_pose_at(c.positions_rad).position_m for c in arm.commands])
    return run, tcp - np.array([0.5, 0.05, 0.0])


def test_push_of_a_bar_along_its_long_axis_uses_the_end_faces_opening_and_reach(context: Context) -> None:
    push = push_bar_setup(context, (3.0, 0.0))
    s = SETTINGS
    # Along x the pads meet an end face: 40 mm wide, the bar 80 mm deep along the push.
    opening_m, reach_m = push.face_geometry(s, 0.0, 0.0)
    assert opening_m == pytest.approx(0.04 - s.gripper.pad_thickness_m)
    assert reach_m == pytest.approx(0.04 + s.gripper.pad_width_m / 2)
    assert push.face_geometry(s, math.pi / 2, 0.0) == pytest.approx(
        (0.08 - s.gripper.pad_thickness_m, 0.02 + s.gripper.pad_width_m / 2)
    )
    run, tcp = pushed_path(context, push)
    assert run.status == Status.SUCCESS, run.feedback
    assert run.feedback == "pushed +3.00 mm along x"
    assert [(c.kind, c.value) for c in fake_gripper(context).commands] == [("open", pytest.approx(opening_m))]
    deepest = int(np.argmax(tcp[:, 0]))
    assert tcp[deepest, 0] == pytest.approx(-reach_m + 0.003, abs=1e-6)
    assert tcp[deepest, 2] == pytest.approx(BAR_GRASP_HEIGHT_M, abs=1e-6), "pads 4 mm above the table"
    low = tcp[:, 2] < SETTINGS.approach_height_m - 0.001
    np.testing.assert_allclose(tcp[low, 1], 0.0, atol=1e-6)  # lowered and pushed on the long axis


def test_a_bar_within_reach_but_turned_past_the_yaw_threshold_gets_a_squaring_push(context: Context) -> None:
    push = push_bar_setup(context, (0.1, 0.0), yaw_error_deg=1.5)
    run, tcp = pushed_path(context, push)
    assert run.status == Status.SUCCESS, run.feedback
    assert run.feedback == "squared the part with a push of +0.10 mm along x"
    _, reach_m = push.face_geometry(SETTINGS, 0.0, 0.0)
    assert tcp[:, 0].max() == pytest.approx(-reach_m + 0.0001, abs=1e-6), "the pads reach the end face"


def test_a_bar_within_reach_and_square_is_not_pushed(context: Context) -> None:
    push = push_bar_setup(context, (0.1, 0.0), yaw_error_deg=0.5)
    run = tick_until_done(push, context)
    assert run.status == Status.SUCCESS, run.feedback
    assert run.feedback == "nothing to push: 0.10 mm along x"
    assert fake_arm(context).commands == []
