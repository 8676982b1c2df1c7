"""The behaviours alone, on fake devices and a hand-filled blackboard: what they write, how they fail.

Every run is driven the way the runner drives a tree (``fakes.tick_until_done``: tick, brake step,
one control period of world time) and checked tick by tick: a feedback message on every tick, and
at most one arm setpoint per tick (a behaviour never blocks).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import py_trees
import pytest
from fakes import (
    ArmCommand,
    Run,
    Tick,
    brake_until_idle,
    cube,
    fake_arm,
    fake_camera,
    fake_clock,
    fake_gripper,
    make_context,
    tick_until_done,
)
from py_trees.common import Access, Status

from bt_arrange.behaviours import (
    Context,
    Detect,
    GraspGuard,
    Inspect,
    MoveHome,
    Pick,
    Place,
    Push,
    Stage,
    StagedBehaviour,
    keys,
    offset_in_target_frame_mm,
    stages,
)
from bt_arrange.behaviours.push import Blocked
from bt_arrange.errors import BtArrangeError, MotionError, OutOfRangeError, UnreachableError
from bt_arrange.geometry import PlanarPose, Pose, fold_yaw
from bt_arrange.motion import ArmKinematics, LinearMotion, gripper_down_pose
from bt_arrange.objects import BAR, CUBE, ObjectType
from bt_arrange.robot import PixelWindow
from bt_arrange.settings import ManipulationSettings

SETTINGS = ManipulationSettings()
#: Narrowest opening that still counts as holding a cube: 47 mm.
HELD_MIN_WIDTH_M = SETTINGS.cube_edge_m - SETTINGS.grasp_width_tolerance_m
#: Somewhere away from home, reachable, arm bent the usual way.
AWAY_Q = [0.3, -1.8, 1.6, -1.4, -1.57, 0.3]
#: Out of the UR5's 0.92 m reach.
FAR_X_M = 1.2


# -- helpers -------------------------------------------------------------------------------------


def write(values: dict[str, object]) -> None:
    """Fill the blackboard by hand, as the behaviours before this one would have."""
    client = py_trees.blackboard.Client(name="test")
    for key, value in values.items():
        client.register_key(key, access=Access.WRITE)
        client.set(key, value, overwrite=True)


def read(key: str) -> object:
    return py_trees.blackboard.Blackboard.get(key)


def exists(key: str) -> bool:
    return py_trees.blackboard.Blackboard.exists(key)


def set_up(behaviour: py_trees.behaviour.Behaviour, context: Context) -> py_trees.behaviour.Behaviour:
    for node in behaviour.iterate():
        node.setup(context=context)
    return behaviour


def assert_never_blocks(run: Run) -> None:
    """Every tick explains itself and sends at most one setpoint."""
    for index, tick in enumerate(run.ticks):
        assert tick.feedback, f"tick {index} ({tick.status}) left the feedback message empty"
        assert tick.arm_commands <= 1, f"tick {index} ({tick.feedback}) sent {tick.arm_commands} arm commands"


def after(feedback: str, ticks: int = 1) -> Callable[[Tick], bool]:
    """A ``tick_until_done(until=...)`` predicate: the n-th tick that ends with this feedback."""
    seen = [0]

    def predicate(tick: Tick) -> bool:
        seen[0] += tick.feedback == feedback
        return seen[0] >= ticks

    return predicate


def command_at(commands: list[ArmCommand], time_s: float) -> ArmCommand:
    """The setpoint the arm was following at ``time_s``."""
    sent = [c for c in commands if c.time_s <= time_s]
    assert sent, f"no arm command before t = {time_s} s"
    return sent[-1]


def speeds(commands: list[ArmCommand]) -> list[float]:
    return [float(np.linalg.norm(c.velocities_rad_s)) for c in commands]


def assert_comes_to_rest(braking: list[ArmCommand]) -> None:
    """Jerk-limited: the speed may still rise while the acceleration turns round, then only falls to zero."""
    assert braking, "the brake sent no setpoint"
    profile = speeds(braking)
    peak = int(np.argmax(profile))
    assert np.all(np.diff(profile[: peak + 1]) >= -1e-9), profile
    assert np.all(np.diff(profile[peak:]) <= 1e-9), profile
    assert profile[-1] == pytest.approx(0.0, abs=1e-9)


def cube_pose(x_m: float, y_m: float, yaw_rad: float = 0.0) -> Pose:
    return Pose.from_planar(x_m, y_m, yaw_rad, SETTINGS.cube_edge_m / 2)


def test_blackboard_keys_are_one_namespace_per_object() -> None:
    assert keys.key("red", keys.POSE) == "/red/pose"
    assert [keys.key("a", field) for field in (keys.TARGET, keys.OFFSET_MM, keys.OFFSET_XY_MM)] == [
        "/a/target",
        "/a/offset_mm",
        "/a/offset_xy_mm",
    ]
    assert [keys.key("a", field) for field in (keys.PLACED_OFFSET_MM, keys.CORRECTIONS, keys.PUSH_AXIS)] == [
        "/a/placed_offset_mm",
        "/a/corrections",
        "/a/push_axis",
    ]


# -- set-up --------------------------------------------------------------------------------------

BEHAVIOURS: dict[str, Callable[[], StagedBehaviour]] = {
    "Detect": lambda: Detect("detect red", "red"),
    "Inspect": lambda: Inspect("inspect red", "red"),
    "Pick": lambda: Pick("pick red", "red"),
    "Place": lambda: Place("place red", "red"),
    "Push": lambda: Push("push red", "red"),
    "MoveHome": lambda: MoveHome("park"),
}


@pytest.mark.parametrize("make", BEHAVIOURS.values(), ids=BEHAVIOURS.keys())
def test_setup_without_a_context_raises_a_clear_error(make: Callable[[], StagedBehaviour]) -> None:
    behaviour = make()
    with pytest.raises(BtArrangeError, match=r"needs setup\(context=Context\(\.\.\.\)\), got NoneType"):
        behaviour.setup()
    assert behaviour.context is None


def test_setup_with_something_else_than_a_context_names_what_it_got() -> None:
    with pytest.raises(BtArrangeError, match=r"'pick red' needs setup\(context=Context\(\.\.\.\)\), got dict"):
        Pick("pick red", "red").setup(context={"arm": None})


def test_ticking_a_behaviour_that_was_not_set_up_raises_a_clear_error() -> None:
    with pytest.raises(BtArrangeError, match=r"'park' was not set up: call tree.setup\(context=\.\.\.\) first"):
        MoveHome("park").tick_once()


# -- MoveHome ------------------------------------------------------------------------------------


def test_move_home_when_parked_succeeds_at_once_without_moving(context: Context) -> None:
    run = tick_until_done(set_up(MoveHome("park"), context), context)
    assert [t.status for t in run.ticks] == [Status.SUCCESS]
    assert run.feedback == "at home, out of the camera's view"
    assert fake_arm(context).commands == []


def test_move_home_brings_the_arm_home_one_setpoint_per_tick(clock) -> None:
    context = make_context(clock, q=AWAY_Q)
    run = tick_until_done(set_up(MoveHome("park"), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    assert run.feedback == "at home, out of the camera's view"
    assert {t.feedback for t in run.running} == {stages.MOVE_HOME}
    assert_never_blocks(run)
    arm = fake_arm(context)
    assert len(arm.commands) > 50, "a joint motion of a second or more, one setpoint per control period"
    np.testing.assert_allclose(arm.joint_positions(), context.home_q, atol=1e-9)
    # Then the arm settles: the last ticks wait settle_s without sending anything.
    settle_ticks = [t for t in run.running if t.time_s > arm.commands[-1].time_s]
    assert len(settle_ticks) == pytest.approx(SETTINGS.settle_s / arm.control_period_s, abs=1)
    assert all(t.arm_commands == 0 for t in settle_ticks)


# -- Detect --------------------------------------------------------------------------------------


def test_detect_writes_the_measured_pose_under_the_object_name(clock) -> None:
    context = make_context(clock, cubes=[cube("red", 0.55, -0.12, math.radians(20.0)), cube("blue", 0.4, 0.15)])
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
    context = make_context(clock, q=AWAY_Q, cubes=[cube("green", 0.5, 0.0)])
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
        ([cube("blue", 0.5, 0.0)], "not_found", "no red blob"),
        ([cube("red", 0.245, 0.0)], "partial", "cut by the image border"),
        ([cube("red", 0.45, -0.1), cube("red", 0.55, 0.1)], "ambiguous", "two red cubes"),
    ],
    ids=["not_found", "partial", "ambiguous"],
)
def test_detect_of_a_cube_the_camera_cannot_see_fails_saying_why(clock, cubes, status: str, why: str) -> None:
    context = make_context(clock, cubes=cubes)
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
    context = make_context(clock, cubes=[cube("red", 0.502, -0.001, 0.2)])
    write({"/red/target": PlanarPose(0.5, 0.0, target_yaw_rad)})
    run = tick_until_done(set_up(Inspect("inspect red", "red"), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    dx_mm, dy_mm = read("/red/offset_xy_mm")
    assert (dx_mm, dy_mm) == pytest.approx(expected_xy_mm, abs=0.3)
    assert read("/red/offset_mm") == pytest.approx(math.hypot(dx_mm, dy_mm))
    assert read("/red/offset_mm") == pytest.approx(math.sqrt(5.0), abs=0.3)
    assert isinstance(read("/red/pose"), Pose)
    assert run.feedback.endswith(f"; {read('/red/offset_mm'):.2f} mm from the target")
    assert not exists("/red/placed_offset_mm"), "only an inspection after placing records it"


def test_inspect_after_placing_also_records_the_placed_offset(clock) -> None:
    context = make_context(clock, cubes=[cube("yellow", 0.45, 0.1)])
    write({"/yellow/target": PlanarPose(0.45, 0.103, 0.0)})
    inspect = Inspect("inspect yellow after placing", "yellow", after_placing=True)
    run = tick_until_done(set_up(inspect, context), context)
    assert run.status == Status.SUCCESS, run.feedback
    assert read("/yellow/placed_offset_mm") == read("/yellow/offset_mm")
    assert read("/yellow/placed_offset_mm") == pytest.approx(3.0, abs=0.3)


def test_inspect_of_a_cube_it_cannot_see_fails_and_leaves_the_offsets_alone(clock) -> None:
    context = make_context(clock, cubes=[])
    write({"/red/target": PlanarPose(0.5, 0.0), "/red/offset_mm": 4.0})
    run = tick_until_done(set_up(Inspect("inspect red", "red", after_placing=True), context), context)
    assert run.status == Status.FAILURE
    assert run.feedback.startswith("red not_found: ")
    assert read("/red/offset_mm") == 4.0
    assert not exists("/red/placed_offset_mm")


def test_inspect_looks_through_a_window_around_the_target_only(clock) -> None:
    context = make_context(clock, cubes=[cube("red", 0.507, 0.004, 0.3), cube("blue", 0.4, 0.15)])
    write({"/red/target": PlanarPose(0.5, 0.0)})
    run = tick_until_done(set_up(Inspect("inspect red", "red"), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    camera = fake_camera(context)
    (window,) = camera.windows
    assert window is not None and window.binning == 1
    assert window.width_px * window.height_px < 0.1 * camera.intrinsics.width_px * camera.intrinsics.height_px
    assert read("/red/offset_mm") == pytest.approx(math.hypot(7.0, 4.0), abs=0.3)


def test_inspect_searches_the_whole_view_for_a_cube_far_from_its_target(clock) -> None:
    context = make_context(clock, cubes=[cube("red", 0.62, -0.2, 0.3)])
    write({"/red/target": PlanarPose(0.5, 0.0)})
    run = tick_until_done(set_up(Inspect("inspect red", "red"), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    target_window, search, measure = fake_camera(context).windows
    assert target_window is not None and search is not None and measure is not None
    assert search.binning > 1 and measure.binning == 1 and measure != target_window
    pose = read("/red/pose")
    assert 1000 * math.hypot(pose.x_m - 0.62, pose.y_m + 0.2) < 0.5


def test_a_detection_in_a_window_is_the_full_frames(clock) -> None:
    context = make_context(clock, cubes=[cube("green", 0.47, 0.06, 0.4)])
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


# -- Pick ----------------------------------------------------------------------------------------


def test_pick_grasps_at_the_measured_pose_and_lifts(clock) -> None:
    context = make_context(clock, q=AWAY_Q, gripper_width_m=0.0, object_width_m=SETTINGS.cube_edge_m)
    yaw = math.radians(17.0)
    write({"/red/pose": cube_pose(0.5, 0.1, yaw)})
    run = tick_until_done(set_up(Pick("pick red", "red"), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    assert run.feedback == "holding red, fingers 50.0 mm apart"
    assert_never_blocks(run)
    seen = list(dict.fromkeys(t.feedback for t in run.running))
    assert seen == [
        stages.MOVE_ABOVE_CUBE,
        stages.WAIT_FOR_OPEN_FINGERS,
        stages.DESCEND_TO_CUBE,
        stages.CLOSE_ON_CUBE,
        stages.LIFT_CUBE,
    ]
    arm, gripper = fake_arm(context), fake_gripper(context)
    assert [(c.kind, c.value) for c in gripper.commands] == [
        ("open", SETTINGS.open_width_m),
        ("close", SETTINGS.grip_force_n),
    ]
    grasp = arm.tcp_pose_at(command_at(arm.commands, gripper.commands[1].time_s).positions_rad)
    np.testing.assert_allclose(grasp.position_m, [0.5, 0.1, SETTINGS.grasp_height_m], atol=1e-6)
    assert fold_yaw(grasp.yaw_rad - yaw) == pytest.approx(0.0, abs=1e-4), "pads square to the cube's faces"
    np.testing.assert_allclose(arm.tcp_pose().position_m, [0.5, 0.1, SETTINGS.approach_height_m], atol=1e-6)


def test_pick_that_closes_on_nothing_fails_naming_the_width(clock) -> None:
    context = make_context(clock, object_width_m=None)
    write({"/red/pose": cube_pose(0.45, -0.05)})
    run = tick_until_done(set_up(Pick("pick red", "red"), context), context)
    assert run.status == Status.FAILURE
    assert run.feedback == (
        "no cube between the pads: the fingers closed to 0.0 mm, a 50 mm cube holds them at least 47.0 mm apart"
    )
    feedback = [t.feedback for t in run.ticks]
    assert feedback.index(stages.LET_GO_OF_BAD_GRASP) < feedback.index(stages.LIFT_CUBE), "lets go before lifting"
    assert fake_arm(context).tcp_pose().z_m == pytest.approx(SETTINGS.approach_height_m, abs=1e-6), "lifted clear"
    assert fake_gripper(context).width() == pytest.approx(SETTINGS.open_width_m, abs=1e-3)


def test_pick_that_still_holds_a_turned_cube_by_its_corners_after_squaring_lets_go_and_fails(clock) -> None:
    # A cube turned ~30 degrees under the pads is gripped across two vertical edges, 68 mm apart,
    # and (in this fake) the squaring closes leave it so.
    context = make_context(clock, object_width_m=0.068)
    write({"/red/pose": cube_pose(0.45, -0.05)})
    run = tick_until_done(set_up(Pick("pick red", "red"), context), context)
    assert run.status == Status.FAILURE
    assert run.feedback == (
        "the pads hold the cube across its corners: 68.0 mm apart, more than the 60.0 mm of a 50 mm cube "
        "held nearly square (it is turned) after squaring a 68.0 mm grip"
    )
    feedback = [t.feedback for t in run.ticks]
    assert feedback.index(stages.CLOSE_ON_SQUARED_CUBE) < feedback.index(stages.LET_GO_OF_BAD_GRASP)
    assert feedback.index(stages.LET_GO_OF_BAD_GRASP) < feedback.index(stages.LIFT_CUBE), "lets go before lifting"
    assert fake_gripper(context).width() == pytest.approx(SETTINGS.open_width_m, abs=1e-3)


def _squared_by_the_second_close(context: Context, squared_width_m: float) -> None:
    """The fake cube is pinched across its corners by the first close and square from the next one on."""
    gripper = fake_gripper(context)
    close = gripper.close

    def close_then_square(force_n: float) -> None:
        close(force_n)
        gripper.object_width_m = squared_width_m

    gripper.close = close_then_square  # type: ignore[method-assign]


def test_pick_squares_a_cube_pinched_across_its_corners_and_holds_it(clock) -> None:
    shift = ManipulationSettings(squaring="shift")
    context = make_context(clock, q=AWAY_Q, gripper_width_m=0.0, object_width_m=0.068, settings=shift)
    _squared_by_the_second_close(context, 0.0505)
    write({"/red/pose": cube_pose(0.5, 0.1, 0.0)})
    run = tick_until_done(set_up(Pick("pick red", "red"), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    assert run.feedback == "holding red, fingers 50.5 mm apart (squared from a 68.0 mm grip across its corners)"
    assert_never_blocks(run)
    seen = list(dict.fromkeys(t.feedback for t in run.running))
    assert seen == [
        stages.MOVE_ABOVE_CUBE,
        stages.WAIT_FOR_OPEN_FINGERS,
        stages.DESCEND_TO_CUBE,
        stages.CLOSE_ON_CUBE,
        stages.OPEN_TO_SQUARE,
        stages.SHIFT_ALONG_PADS,
        stages.CLOSE_TO_SQUARE,
        stages.OPEN_SQUARED_CUBE,
        stages.RECENTRE_ON_CUBE,
        stages.CLOSE_ON_SQUARED_CUBE,
        stages.LIFT_CUBE,
    ]
    arm, gripper = fake_arm(context), fake_gripper(context)
    assert [c.kind for c in gripper.commands] == ["open", "close", "open", "close", "open", "close"]
    first, squaring, final = (
        arm.tcp_pose_at(command_at(arm.commands, c.time_s).positions_rad) for c in gripper.commands if c.kind == "close"
    )
    # The squaring close stands half a pad's width along the pads (across the closing axis), the last at the centre.
    closing = np.array([math.cos(first.yaw_rad), math.sin(first.yaw_rad)])
    shift = squaring.position_m[:2] - first.position_m[:2]
    assert float(np.linalg.norm(shift)) == pytest.approx(SETTINGS.squaring_shift_m, abs=1e-5)
    assert float(shift @ closing) == pytest.approx(0.0, abs=1e-5)
    np.testing.assert_allclose(final.position_m, [0.5, 0.1, SETTINGS.grasp_height_m], atol=1e-6)
    np.testing.assert_allclose(arm.tcp_pose().position_m, [0.5, 0.1, SETTINGS.approach_height_m], atol=1e-6)


def test_pick_squaring_by_a_sweep_pushes_along_the_closing_axis_towards_the_base(clock) -> None:
    context = make_context(clock, object_width_m=0.069, settings=ManipulationSettings(squaring="sweep"))
    _squared_by_the_second_close(context, 0.051)
    write({"/red/pose": cube_pose(0.5, 0.1, 0.0)})
    run = tick_until_done(set_up(Pick("pick red", "red"), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    seen = list(dict.fromkeys(t.feedback for t in run.running))
    assert seen[seen.index(stages.CLOSE_ON_CUBE) + 1 :] == [
        stages.OPEN_TO_SQUARE,
        stages.SWEEP_TO_SQUARE,
        stages.CLOSE_ON_SQUARED_CUBE,
        stages.LIFT_CUBE,
    ]
    arm, gripper = fake_arm(context), fake_gripper(context)
    first, final = (
        arm.tcp_pose_at(command_at(arm.commands, c.time_s).positions_rad) for c in gripper.commands if c.kind == "close"
    )
    sweep = final.position_m[:2] - first.position_m[:2]
    closing = np.array([math.cos(first.yaw_rad), math.sin(first.yaw_rad)])
    assert abs(float(sweep @ closing)) == pytest.approx(SETTINGS.squaring_sweep_m, abs=1e-5), "along the closing axis"
    assert float(sweep @ first.position_m[:2]) < 0.0, "towards the robot's base"
    # The lift goes straight up from where the sweep ended.
    np.testing.assert_allclose(arm.tcp_pose().position_m[:2], final.position_m[:2], atol=1e-6)


def test_pick_with_squaring_off_lets_a_cube_pinched_across_its_corners_go_at_once(clock) -> None:
    context = make_context(clock, object_width_m=0.068, settings=ManipulationSettings(squaring="off"))
    write({"/red/pose": cube_pose(0.45, -0.05)})
    run = tick_until_done(set_up(Pick("pick red", "red"), context), context)
    assert run.status == Status.FAILURE
    assert run.feedback.startswith("the pads hold the cube across its corners: 68.0 mm apart")
    assert [c.kind for c in fake_gripper(context).commands] == ["open", "close", "open"]


def test_an_unknown_squaring_is_a_one_line_error() -> None:
    with pytest.raises(OutOfRangeError, match="squaring 'twist': choose one of shift, sweep, turn, off"):
        ManipulationSettings(squaring="twist")


def _closes_stop_at(context: Context, widths_m: list[float]) -> None:
    """The fake's n-th close stops at ``widths_m[n]`` (the last one from there on)."""
    gripper = fake_gripper(context)
    close = gripper.close
    count = [0]

    def close_at_next_width(force_n: float) -> None:
        gripper.object_width_m = widths_m[min(count[0], len(widths_m) - 1)]
        count[0] += 1
        close(force_n)

    gripper.close = close_at_next_width  # type: ignore[method-assign]


def _close_poses(context: Context) -> list[Pose]:
    """The TCP pose at each close command."""
    arm, gripper = fake_arm(context), fake_gripper(context)
    return [
        arm.tcp_pose_at(command_at(arm.commands, c.time_s).positions_rad) for c in gripper.commands if c.kind == "close"
    ]


def _yaw_step_deg(a: Pose, b: Pose) -> float:
    return math.degrees(math.remainder(b.yaw_rad - a.yaw_rad, 2 * math.pi))


TURN = ManipulationSettings(squaring="turn")


def test_pick_squaring_by_a_turn_turns_the_wrist_once_when_that_squares_the_cube(clock) -> None:
    context = make_context(clock, q=AWAY_Q, gripper_width_m=0.0, settings=TURN)
    _closes_stop_at(context, [0.068, 0.0505])
    write({"/red/pose": cube_pose(0.5, 0.1, 0.0)})
    run = tick_until_done(set_up(Pick("pick red", "red"), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    assert run.feedback == (
        "holding red, fingers 50.5 mm apart "
        "(squared from a 68.0 mm grip across its corners, the wrist turned +22.5 deg)"
    )
    assert_never_blocks(run)
    seen = list(dict.fromkeys(t.feedback for t in run.running))
    assert seen[seen.index(stages.CLOSE_ON_CUBE) + 1 :] == [
        stages.OPEN_TO_SQUARE,
        stages.TURN_WRIST_TO_SQUARE,
        stages.CLOSE_ON_TURNED_CUBE,
        stages.LIFT_CUBE,
    ], "the other way is not tried when the first turn squared it"
    assert [c.kind for c in fake_gripper(context).commands] == ["open", "close", "open", "close"]
    first, turned = _close_poses(context)
    # The second close stands where the first did, the wrist turned by the setting about the TCP.
    np.testing.assert_allclose(turned.position_m, first.position_m, atol=1e-6)
    assert _yaw_step_deg(first, turned) == pytest.approx(TURN.squaring_turn_deg, abs=1e-3)
    # The lift goes straight up, keeping the turned yaw.
    lifted = fake_arm(context).tcp_pose()
    np.testing.assert_allclose(lifted.position_m, [0.5, 0.1, SETTINGS.approach_height_m], atol=1e-6)
    assert _yaw_step_deg(first, lifted) == pytest.approx(TURN.squaring_turn_deg, abs=1e-3)


def test_pick_squaring_by_a_turn_turns_the_other_way_only_when_the_first_turn_left_it_pinched(clock) -> None:
    context = make_context(clock, settings=TURN)
    # Turned the other way: +22.5 deg leaves the corners on the pads, -22.5 from the first yaw squares it.
    _closes_stop_at(context, [0.068, 0.070, 0.051])
    write({"/red/pose": cube_pose(0.5, 0.1, 0.0)})
    run = tick_until_done(set_up(Pick("pick red", "red"), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    assert run.feedback.endswith("(squared from a 68.0 mm grip across its corners, the wrist turned -22.5 deg)")
    assert_never_blocks(run)
    seen = list(dict.fromkeys(t.feedback for t in run.running))
    assert seen[seen.index(stages.CLOSE_ON_CUBE) + 1 :] == [
        stages.OPEN_TO_SQUARE,
        stages.TURN_WRIST_TO_SQUARE,
        stages.CLOSE_ON_TURNED_CUBE,
        stages.OPEN_TO_TURN_BACK,
        stages.TURN_WRIST_OTHER_WAY,
        stages.CLOSE_ON_SQUARED_CUBE,
        stages.LIFT_CUBE,
    ]
    first, plus, minus = _close_poses(context)
    assert _yaw_step_deg(first, plus) == pytest.approx(TURN.squaring_turn_deg, abs=1e-3)
    assert _yaw_step_deg(first, minus) == pytest.approx(-TURN.squaring_turn_deg, abs=1e-3)
    np.testing.assert_allclose(minus.position_m, first.position_m, atol=1e-6)
    lifted = fake_arm(context).tcp_pose()
    np.testing.assert_allclose(lifted.position_m, [0.5, 0.1, SETTINGS.approach_height_m], atol=1e-6)
    assert _yaw_step_deg(first, lifted) == pytest.approx(-TURN.squaring_turn_deg, abs=1e-3), "lifts at the final yaw"


def test_pick_squaring_by_a_turn_that_leaves_it_pinched_both_ways_lets_go_and_fails(clock) -> None:
    context = make_context(clock, object_width_m=0.068, settings=TURN)
    write({"/red/pose": cube_pose(0.45, -0.05)})
    run = tick_until_done(set_up(Pick("pick red", "red"), context), context)
    assert run.status == Status.FAILURE
    assert run.feedback == (
        "the pads hold the cube across its corners: 68.0 mm apart, more than the 60.0 mm of a 50 mm cube "
        "held nearly square (it is turned) after squaring a 68.0 mm grip"
    )
    assert [c.kind for c in fake_gripper(context).commands] == [
        "open",
        "close",
        "open",
        "close",
        "open",
        "close",
        "open",
    ]
    feedback = [t.feedback for t in run.ticks]
    assert feedback.index(stages.TURN_WRIST_OTHER_WAY) < feedback.index(stages.LET_GO_OF_BAD_GRASP)
    assert feedback.index(stages.LET_GO_OF_BAD_GRASP) < feedback.index(stages.LIFT_CUBE), "lets go before lifting"
    assert fake_gripper(context).width() == pytest.approx(SETTINGS.open_width_m, abs=1e-3)


def test_pick_squaring_by_a_turn_leaves_a_square_grasp_alone(clock) -> None:
    context = make_context(clock, object_width_m=SETTINGS.cube_edge_m, settings=TURN)
    write({"/red/pose": cube_pose(0.45, -0.05, 0.3)})
    run = tick_until_done(set_up(Pick("pick red", "red"), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    assert run.feedback == "holding red, fingers 50.0 mm apart"
    assert [c.kind for c in fake_gripper(context).commands] == ["open", "close"]


@pytest.mark.parametrize("turn_deg", [0.0, -10.0, 45.0, 60.0])
def test_a_squaring_turn_outside_0_to_45_degrees_is_a_one_line_error(turn_deg: float) -> None:
    with pytest.raises(OutOfRangeError, match=f"squaring turn {turn_deg:g} deg must lie between 0 and 45 deg"):
        ManipulationSettings(squaring_turn_deg=turn_deg)


@pytest.mark.parametrize("make", [Pick, Place], ids=["Pick", "Place"])
def test_a_target_out_of_reach_fails_before_any_arm_command(context: Context, make) -> None:
    write({"/red/pose": cube_pose(FAR_X_M, 0.0), "/red/target": PlanarPose(FAR_X_M, 0.0)})
    with pytest.raises(UnreachableError) as unreachable:
        ArmKinematics().check_reachable(gripper_down_pose(FAR_X_M, 0.0, SETTINGS.approach_height_m))
    run = tick_until_done(set_up(make(f"{make.__name__} red", "red"), context), context)
    assert [t.status for t in run.ticks] == [Status.FAILURE], "fails on its first tick"
    first_move = stages.MOVE_ABOVE_CUBE if make is Pick else stages.CARRY_ABOVE_TARGET
    assert run.feedback.startswith(f"{first_move}: ")
    assert str(unreachable.value).split(" is out of reach")[1] in run.feedback
    assert fake_arm(context).commands == []


def test_fingers_that_never_stop_fail_after_the_gripper_timeout(clock) -> None:
    context = make_context(clock, stuck_gripper=True)
    write({"/red/pose": cube_pose(0.5, 0.0)})
    run = tick_until_done(set_up(Pick("pick red", "red"), context), context)
    assert run.status == Status.FAILURE
    assert run.feedback.startswith(f"{stages.WAIT_FOR_OPEN_FINGERS}: fingers still moving after 2.0 s (limit 2.0 s)")
    waiting = [t for t in run.ticks if t.feedback == stages.WAIT_FOR_OPEN_FINGERS]
    waited_s = run.ticks[-1].time_s - waiting[0].time_s
    assert SETTINGS.gripper_timeout_s < waited_s <= SETTINGS.gripper_timeout_s + 2 * fake_arm(context).control_period_s
    assert all(t.arm_commands == 0 for t in waiting)


def test_pick_without_a_pose_on_the_blackboard_fails_naming_the_key(context: Context) -> None:
    run = tick_until_done(set_up(Pick("pick red", "red"), context), context)
    assert run.status == Status.FAILURE
    assert "/red/pose" in run.feedback


# -- Place ---------------------------------------------------------------------------------------


def test_place_lowers_the_cube_onto_its_target_and_releases_it(clock) -> None:
    context = make_context(clock, gripper_width_m=SETTINGS.cube_edge_m, object_width_m=SETTINGS.cube_edge_m)
    target = PlanarPose(0.45, -0.1, math.radians(30.0))
    write({"/red/target": target})
    run = tick_until_done(set_up(Place("place red", "red"), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    assert run.feedback == "red released at its target"
    assert_never_blocks(run)
    assert list(dict.fromkeys(t.feedback for t in run.running)) == [
        stages.CARRY_ABOVE_TARGET,
        stages.LOWER_CUBE,
        stages.RELEASE_CUBE,
        stages.RETREAT,
    ]
    arm, gripper = fake_arm(context), fake_gripper(context)
    assert [(c.kind, c.value) for c in gripper.commands] == [("open", SETTINGS.open_width_m)]
    release = arm.tcp_pose_at(command_at(arm.commands, gripper.commands[0].time_s).positions_rad)
    expected_z_m = SETTINGS.grasp_height_m + SETTINGS.release_clearance_m
    np.testing.assert_allclose(release.position_m, [0.45, -0.1, expected_z_m], atol=1e-6)
    assert fold_yaw(release.yaw_rad - target.yaw_rad) == pytest.approx(0.0, abs=1e-4)
    np.testing.assert_allclose(arm.tcp_pose().position_m, [0.45, -0.1, SETTINGS.approach_height_m], atol=1e-6)


# -- Push ----------------------------------------------------------------------------------------


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
    context = make_context(clock)
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
    assert from_centre @ towards == pytest.approx(-(s.push_reach_m + s.push_clearance_m), abs=1e-6)
    assert from_centre @ across == pytest.approx(0.0, abs=1e-6)
    assert behind.z_m == pytest.approx(s.approach_height_m, abs=1e-6)
    # Fingers side by side along the pushed face: the closing axis lies across the push.
    assert fold_yaw(behind.yaw_rad - math.atan2(across[1], across[0]), math.pi) == pytest.approx(0.0, abs=1e-4)
    gripper = fake_gripper(context)
    # The cube (yaw 0.1 rad) is turned from the push: its leading corner on the middle of a pad.
    turn_rad = abs(fold_yaw(math.atan2(towards[1], towards[0]) - 0.1, math.pi / 2))
    corner_m = s.cube_edge_m * (math.cos(turn_rad) - math.sin(turn_rad))
    assert [(c.kind, c.value) for c in gripper.commands] == [
        ("open", pytest.approx(max(0.0, corner_m - s.pad_thickness_m)))
    ]

    before = len(arm.commands)
    rest = tick_until_done(push, context)
    assert rest.status == Status.SUCCESS, rest.feedback
    assert_never_blocks(rest)
    tcp = np.array([arm.tcp_pose_at(c.positions_rad).position_m for c in arm.commands[before:]])
    along = (tcp[:, :2] - centre) @ towards
    deepest = int(np.argmax(along))
    assert along[deepest] == pytest.approx(-s.push_reach_m + distance_mm / 1000, abs=1e-6)
    assert tcp[deepest, 2] == pytest.approx(s.push_height_m, abs=1e-6)
    np.testing.assert_allclose((tcp[:, :2] - centre) @ across, 0.0, atol=1e-6)
    assert along[-1] == pytest.approx(along[deepest] - s.push_clearance_m, abs=1e-6), "backed off"
    assert tcp[-1, 2] == pytest.approx(s.approach_height_m, abs=1e-6), "lifted"
    axis = "x" if "x" in rest.feedback else "y"
    assert rest.feedback == f"pushed {math.copysign(distance_mm, sum(offset_xy_mm)):+.2f} mm along {axis}"


def leading_corner_across_mm(pose: Pose, kind: ObjectType, towards: np.ndarray, line_xy: np.ndarray) -> float:
    """How far (mm) beside the pushing TCP's line the footprint's corner furthest along ``towards`` lies."""
    corners = kind.footprint_m(pose.x_m, pose.y_m, pose.yaw_rad)
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
    inner_mm, outer_mm = opening * 500, opening * 500 + SETTINGS.pad_thickness_m * 1000
    assert inner_mm - 1e-6 <= corner_mm <= outer_mm + 1e-6, (
        f"the leading corner {corner_mm:.1f} mm beside the push's line misses the pads "
        f"({inner_mm:.1f} to {outer_mm:.1f} mm)"
    )


# -- interruption --------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("make", "during"),
    [
        (lambda: MoveHome("park"), stages.MOVE_HOME),
        (lambda: Pick("pick red", "red"), stages.DESCEND_TO_CUBE),
    ],
    ids=["joint motion", "straight line"],
)
def test_an_interrupted_motion_is_handed_to_the_brake_which_brings_the_arm_to_rest(clock, make, during) -> None:
    context = make_context(clock, q=AWAY_Q)
    write({"/red/pose": cube_pose(0.5, 0.1)})
    behaviour = set_up(make(), context)
    run = tick_until_done(behaviour, context, until=after(during, 30))
    assert run.status == Status.RUNNING
    arm = fake_arm(context)
    assert speeds(arm.commands[-1:])[0] > 0.1, "interrupted at speed"

    behaviour.stop(Status.INVALID)
    assert behaviour.status == Status.INVALID
    assert behaviour.feedback_message == stages.INTERRUPTED
    assert context.brake.active
    braking = brake_until_idle(context)
    assert_comes_to_rest(braking)
    assert len(braking) < 150, "a stop, not the rest of the motion"
    assert not context.brake.active


def test_a_behaviour_started_while_the_arm_brakes_waits_for_it(clock) -> None:
    context = make_context(clock, q=AWAY_Q)
    first = set_up(MoveHome("park"), context)
    tick_until_done(first, context, until=after(stages.MOVE_HOME, 40))
    first.stop(Status.INVALID)
    arm = fake_arm(context)

    second = set_up(MoveHome("park again"), context)
    run = tick_until_done(second, context)
    assert run.status == Status.SUCCESS, run.feedback
    waiting = [t for t in run.ticks if t.feedback == stages.WAITING_FOR_BRAKE]
    assert len(waiting) > 10
    assert run.ticks[: len(waiting)] == waiting, "it waits first, then moves"
    assert all(t.arm_commands == 0 for t in waiting), "only the brake commands the arm meanwhile"
    assert_never_blocks(run)
    own = [c for c in arm.commands if c.time_s > waiting[-1].time_s]
    rest_q = command_at(arm.commands, waiting[-1].time_s).positions_rad
    assert np.max(np.abs(own[0].positions_rad - rest_q)) < 1e-3, "its motion starts where the brake left the arm"
    np.testing.assert_allclose(arm.joint_positions(), context.home_q, atol=1e-9)


def test_each_tick_sends_at_most_one_arm_command_even_without_settling(clock) -> None:
    context = make_context(
        clock, gripper_width_m=0.05, object_width_m=0.05, settings=ManipulationSettings(settle_s=0.0)
    )
    write({"/red/target": PlanarPose(0.45, -0.1, 0.2)})
    run = tick_until_done(set_up(Place("place red", "red"), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    assert max(t.arm_commands for t in run.ticks) == 1


# -- GraspGuard ----------------------------------------------------------------------------------


def guarded_place(context: Context) -> tuple[GraspGuard, Place]:
    """A cube held between closed fingers, a Place under the guard."""
    fake_gripper(context).close(SETTINGS.grip_force_n)
    fake_clock(context).advance(2.0)  # 85 mm closed at 50 mm/s: at rest
    write({"/red/target": PlanarPose(0.45, -0.1, 0.0)})
    place = Place("place red", "red")
    guard = GraspGuard("while holding red", place)
    set_up(guard, context)
    return guard, place


def test_grasp_guard_runs_the_child_while_the_cube_is_held(clock) -> None:
    context = make_context(clock, object_width_m=SETTINGS.cube_edge_m)
    guard, place = guarded_place(context)
    run = tick_until_done(guard, context)
    assert run.status == Status.SUCCESS, run.feedback
    assert place.status == Status.SUCCESS
    assert run.ticks[0].feedback == f"holding; {stages.CARRY_ABOVE_TARGET}"
    assert all(t.feedback.startswith("holding; ") for t in run.ticks)
    assert_never_blocks(run)


def test_grasp_guard_fails_within_a_tick_when_the_cube_slips_out(clock) -> None:
    context = make_context(clock, object_width_m=SETTINGS.cube_edge_m)
    guard, place = guarded_place(context)
    run = tick_until_done(guard, context, until=after(f"holding; {stages.CARRY_ABOVE_TARGET}", 50))
    assert guard.status == Status.RUNNING and place.status == Status.RUNNING
    assert run.feedback == f"holding; {stages.CARRY_ABOVE_TARGET}"

    gripper = fake_gripper(context)
    gripper.slip()
    for _ in range(100):
        width_m = gripper.width()
        guard.tick_once()
        context.brake.step()
        clock.advance(fake_arm(context).control_period_s)
        if width_m >= HELD_MIN_WIDTH_M:
            assert guard.status == Status.RUNNING, f"still held at {width_m * 1000:.1f} mm"
        else:
            assert guard.status == Status.FAILURE, f"the first tick at {width_m * 1000:.1f} mm fails"
            break
    assert guard.status == Status.FAILURE
    assert place.status == Status.INVALID, "the child is interrupted"
    assert place.feedback_message == stages.INTERRUPTED
    assert guard.feedback_message.startswith("the cube left the gripper: fingers at ")
    assert guard.feedback_message.endswith("mm, under the 47.0 mm of a held cube")
    assert context.brake.active, "the carry motion goes to the brake"
    assert_comes_to_rest(brake_until_idle(context))


def test_grasp_guard_fails_at_once_when_nothing_is_held(clock) -> None:
    context = make_context(clock, object_width_m=None)
    guard, place = guarded_place(context)
    guard.tick_once()
    assert guard.status == Status.FAILURE
    assert guard.feedback_message == "the cube left the gripper: fingers at 0.0 mm, under the 47.0 mm of a held cube"
    assert place.status == Status.INVALID, "the child never ran"
    assert fake_arm(context).commands == []


def test_an_error_raised_mid_motion_is_a_failure_with_the_reason_and_the_motion_goes_to_the_brake(clock) -> None:
    context = make_context(clock, q=AWAY_Q)
    behaviour = set_up(MoveHome("park"), context)
    run = tick_until_done(behaviour, context, until=after(stages.MOVE_HOME, 30))
    assert run.status == Status.RUNNING
    assert speeds(fake_arm(context).commands[-1:])[0] > 0.1, "at speed when the error comes"
    motion = behaviour._stages[behaviour._index].motion
    step = motion.step

    def fails_once():
        motion.step = step  # the brake steps the same motion afterwards
        raise MotionError("joint motion failed at t = 0.300 s: ruckig Error")

    motion.step = fails_once
    behaviour.tick_once()
    assert behaviour.status == Status.FAILURE
    assert behaviour.feedback_message == f"{stages.MOVE_HOME}: joint motion failed at t = 0.300 s: ruckig Error"
    assert context.brake.active, "the motion was handed to the brake"
    assert_comes_to_rest(brake_until_idle(context))


def test_a_stage_without_poll_cannot_be_made() -> None:
    class Forgetful(Stage):
        pass

    with pytest.raises(TypeError, match="abstract"):
        Forgetful("forgot to poll")  # type: ignore[abstract]


def test_the_base_class_owns_the_client_and_the_declared_keys() -> None:
    push = Push("push red", "red")
    assert isinstance(push.blackboard, py_trees.blackboard.Client)
    assert set(push.blackboard.read) >= {"/red/pose", "/red/target", "/red/offset_xy_mm", "/red/push_axis"}
    assert set(push.blackboard.write) == {"/red/push_axis", "/red/blocked_towards"}
    inspect = Inspect("inspect red", "red", after_placing=True)
    assert set(inspect.blackboard.write) == {
        "/red/pose",
        "/red/offset_mm",
        "/red/offset_xy_mm",
        "/red/placed_offset_mm",
        "/red/yaw_error_deg",
        "/red/placed_yaw_error_deg",
    }


# -- pushes only from free sides (neighbours as the layout names them) ---------------------


@pytest.mark.parametrize(
    ("offset_xy_mm", "towards", "expected"),
    [
        ((3.0, 0.0), ("+x", "-x", "+y", "-y"), "x"),
        ((3.0, 2.0), ("-x", "+y", "-y"), "y"),  # +x blocked (a neighbour on the -x side): the other axis
        ((3.0, 0.1), ("-x", "+y", "-y"), ("+x", 3.0)),  # only +x would do: blocked
        ((-3.0, 0.0), ("-x", "+y", "-y"), "x"),
        ((0.1, -2.0), ("+y",), ("-y", -2.0)),
    ],
    ids=["all free", "other axis", "blocked", "free direction", "blocked y"],
)
def test_push_chooses_a_free_side_or_says_which_side_is_blocked(offset_xy_mm, towards, expected) -> None:
    choice = Push.choose_side("x", offset_xy_mm, 0.2, towards)
    if isinstance(expected, tuple):
        assert isinstance(choice, Blocked) and (choice.towards, choice.offset_mm) == expected
    else:
        assert choice == expected


def test_a_push_a_neighbour_blocks_fails_saying_so_and_writes_the_direction(context: Context) -> None:
    write({"/red/pose": cube_pose(0.5, 0.0), "/red/target": PlanarPose(0.0, 0.0, 0.0), "/red/offset_xy_mm": (1.5, 0.0)})
    push = set_up(Push("push red", "red", towards=("-x", "+y", "-y")), context)
    run = tick_until_done(push, context)
    assert run.status == Status.FAILURE
    assert "red needs a push of 1.50 mm towards +x, from its -x side, where a neighbour leaves the pads no room" in (
        run.feedback
    )
    assert "release it again on the side it can be pushed from" in run.feedback
    assert read("/red/blocked_towards") == "+x"
    assert fake_arm(context).commands == [], "never pushes through the neighbour"


def test_a_push_among_neighbours_opens_only_to_keep_the_fingers_within_the_face(context: Context) -> None:
    write({"/red/pose": cube_pose(0.5, 0.0), "/red/target": PlanarPose(0.0, 0.0, 0.0), "/red/offset_xy_mm": (0.0, 2.0)})
    push = set_up(Push("push red", "red", towards=("+y", "-y"), opening_m=0.024), context)
    run = tick_until_done(push, context)
    assert run.status == Status.SUCCESS, run.feedback
    assert run.feedback == "pushed +2.00 mm along y"
    assert [(c.kind, c.value) for c in fake_gripper(context).commands] == [("open", 0.024)]


# -- the learned push strategy (ours; the paper's stays the default) ----------------------------


def test_learned_push_goes_along_the_larger_offset_first() -> None:
    assert Push.plan_learned((0.5, -3.0), (0.0, 0.0), None, 0.2) == ((0.0, 0.0), "y", -3.0)
    assert Push.plan_learned((2.0, 1.0), (0.0, 0.0), None, 0.2) == ((0.0, 0.0), "x", 2.0)


def test_learned_push_learns_where_the_last_push_landed_and_aims_short_by_it() -> None:
    # The last push along x aimed at the target (aim 0) and the cube stopped 0.6 mm past it
    # (offset -0.6 mm): pushes along x land 0.6 mm beyond their aim.
    bias, axis, distance = Push.plan_learned((-0.6, 0.1), (0.0, 0.0), ("x", 0.0), 0.2)
    assert bias == pytest.approx((0.6, 0.0))
    assert axis == "x"
    assert distance == pytest.approx(-1.2), "aim 0.6 mm short of the target, from 0.6 mm past it"
    # Aimed 0.6 mm short and landed on the target: the bias stays 0.6 mm.
    bias, _, _ = Push.plan_learned((0.0, 0.1), bias, ("x", -0.6), 0.2)
    assert bias == pytest.approx((0.6, 0.0))


def test_learned_push_that_fell_short_of_the_cube_reaches_further_next_time() -> None:
    # Aimed at the target, but the cube did not move from 0.3 mm short: push further.
    bias, axis, distance = Push.plan_learned((0.3, 0.0), (0.0, 0.0), ("x", 0.0), 0.2)
    assert bias == pytest.approx((-0.3, 0.0))
    assert (axis, distance) == ("x", pytest.approx(0.6))


def test_learned_push_keeps_its_bias_on_the_blackboard_between_pushes(context: Context) -> None:
    write({"/red/pose": cube_pose(0.5, 0.0), "/red/target": PlanarPose(0.0, 0.0, 0.0), "/red/offset_xy_mm": (3.0, 1.0)})
    run = tick_until_done(set_up(Push("push red", "red", strategy="learned"), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    assert run.feedback == "pushed +3.00 mm along x"
    assert read("/red/last_push") == ("x", -0.0)
    # The camera then sees the cube 0.4 mm past the target along x, 1 mm short along y.
    write({"/red/offset_xy_mm": (-0.4, 1.0)})
    run = tick_until_done(set_up(Push("push red", "red", strategy="learned"), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    assert read("/red/push_bias_mm") == pytest.approx((0.4, 0.0))
    assert run.feedback == "pushed +1.00 mm along y"


def test_an_unknown_push_strategy_is_a_clear_error() -> None:
    with pytest.raises(BtArrangeError, match="push strategy 'magic': choose one of paper, learned"):
        Push("push red", "red", strategy="magic")


def test_a_diagonal_push_moves_the_cube_across_its_axis_by_the_other_offset_within_the_friction_limit() -> None:
    assert Push.across_push_mm((3.0, 1.0), "x", 3.0, 0.2) == pytest.approx(1.0)
    assert Push.across_push_mm((-0.5, 2.0), "y", 2.0, 0.2) == pytest.approx(-0.5)
    # At most 0.6 mm across per mm along: the rest is left to a later push.
    assert Push.across_push_mm((1.0, -2.0), "x", 1.0, 0.2) == pytest.approx(-0.6)
    # Nothing across below the shortest push, nor when there is no push.
    assert Push.across_push_mm((3.0, 0.1), "x", 3.0, 0.2) == 0.0
    assert Push.across_push_mm((0.1, 3.0), "x", 0.1, 0.2) == 0.0


def test_a_diagonal_push_goes_sideways_while_the_pads_touch_and_says_so(clock) -> None:
    context = make_context(clock)
    centre = np.array([0.5, 0.05])
    write({"/red/pose": cube_pose(*centre), "/red/target": PlanarPose(0.0, 0.0, 0.0), "/red/offset_xy_mm": (3.0, 1.0)})
    push = set_up(Push("push red", "red", strategy="diagonal"), context)
    arm, s = fake_arm(context), SETTINGS
    run = tick_until_done(push, context)
    assert run.status == Status.SUCCESS, run.feedback
    assert run.feedback == "pushed +3.00 mm along x, +1.00 mm along y"
    assert read("/red/last_push") == ("x", -0.0), "the push along x is learned as the learned strategy's"
    tcp = np.array([arm.tcp_pose_at(c.positions_rad).position_m for c in arm.commands]) - [*centre, 0.0]
    low = tcp[np.abs(tcp[:, 2] - s.push_height_m) < 1e-6]
    deepest = low[int(np.argmax(low[:, 0]))]
    assert deepest[0] == pytest.approx(-s.push_reach_m + 0.003, abs=1e-6)
    assert deepest[1] == pytest.approx(0.001, abs=1e-6), "1 mm along y by the end of the push"
    # Where the pads meet the face (reach from the centre), the line has not gone sideways yet.
    meet = low[int(np.argmin(np.abs(low[:, 0] + s.push_reach_m)))]
    assert meet[1] == pytest.approx(0.0, abs=5e-5)
    assert low[0][1] == pytest.approx(-0.001 * s.push_clearance_m / 0.003, abs=1e-6), "started that far the other way"


def test_a_diagonal_push_does_not_go_sideways_towards_a_blocked_side(clock) -> None:
    context = make_context(clock)
    write(
        {"/red/pose": cube_pose(0.5, 0.05), "/red/target": PlanarPose(0.0, 0.0, 0.0), "/red/offset_xy_mm": (3.0, 1.0)}
    )
    # +y is blocked by a neighbour: the push along +x stays straight.
    push = set_up(Push("push red", "red", strategy="diagonal", towards=("+x", "-x", "-y")), context)
    run = tick_until_done(push, context)
    assert run.status == Status.SUCCESS, run.feedback
    assert run.feedback == "pushed +3.00 mm along x"
    assert push.across_m == 0.0


# -- a squaring push among neighbours (issues 10 and 14 together) ----------------------------


def test_a_squaring_push_among_neighbours_goes_from_a_free_side(context: Context) -> None:
    # Within reach (0.1 mm along x) but turned 3 degrees: the line contact squares it. A neighbour
    # on the -x side blocks a push towards +x, so the squaring push goes towards -x.
    write(
        {
            "/red/pose": cube_pose(0.5, 0.0),
            "/red/target": PlanarPose(0.5, 0.0, 0.0),
            "/red/offset_xy_mm": (0.1, 0.0),
            "/red/yaw_error_deg": 3.0,
        }
    )
    push = set_up(Push("push red", "red", yaw_threshold_deg=1.0, towards=("-x", "+y", "-y")), context)
    run = tick_until_done(push, context)
    assert run.status == Status.SUCCESS, run.feedback
    assert run.feedback == "squared the part with a push of -0.10 mm along x"
    assert fake_arm(context).commands, "the squaring push is made"


def test_a_squaring_push_with_both_sides_of_its_axis_blocked_is_not_made(context: Context) -> None:
    write(
        {
            "/red/pose": cube_pose(0.5, 0.0),
            "/red/target": PlanarPose(0.5, 0.0, 0.0),
            "/red/offset_xy_mm": (0.1, 0.0),
            "/red/yaw_error_deg": 3.0,
        }
    )
    push = set_up(Push("push red", "red", yaw_threshold_deg=1.0, towards=("+y", "-y")), context)
    run = tick_until_done(push, context)
    assert run.status == Status.SUCCESS, run.feedback
    assert fake_arm(context).commands == [], "never pushes from a side a neighbour blocks"


def test_detect_among_identical_parts_2_mm_apart_picks_the_free_one_not_the_pair_between_targets(clock) -> None:
    # Two placed green cubes 2 mm apart merge into one blob in a binned view, its centre between
    # their targets (at neither): the search among identical parts reads the full frame instead.
    placed = [PlanarPose(0.452, 0.0, 0.0), PlanarPose(0.504, 0.0, 0.0)]
    free = PlanarPose(0.40, -0.20, 0.0)
    context = make_context(clock, cubes=[cube("green", p.x_m, p.y_m) for p in (*placed, free)])
    write({"/green 3/target": PlanarPose(0.556, 0.0, 0.0)})
    kind_targets = [*placed, PlanarPose(0.556, 0.0, 0.0)]
    detect = Detect("detect green 3", "green 3", colour="green", kind_targets=kind_targets)
    run = tick_until_done(set_up(detect, context), context)
    assert run.status == Status.SUCCESS, run.feedback
    pose = read("/green 3/pose")
    assert 1000 * math.hypot(pose.x_m - free.x_m, pose.y_m - free.y_m) < 0.5


# -- a bar: grasp, push and squaring from the type's size (issue 14) ---------------------------


def bar_pose(x_m: float, y_m: float, yaw_rad: float = 0.0) -> Pose:
    return Pose.from_planar(x_m, y_m, yaw_rad, BAR.height_m / 2)


def test_pick_of_a_bar_closes_across_its_40_mm_side_at_the_types_grasp_height(clock) -> None:
    assert BAR.size_m == (0.08, 0.04, 0.04)
    context = make_context(clock, q=AWAY_Q, gripper_width_m=0.0, object_width_m=0.04)
    yaw = math.radians(17.0)
    write({"/bar/pose": bar_pose(0.5, 0.1, yaw)})
    run = tick_until_done(set_up(Pick("pick bar", "bar", object_type=BAR), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    assert run.feedback == "holding bar, fingers 40.0 mm apart"
    assert_never_blocks(run)
    arm, gripper = fake_arm(context), fake_gripper(context)
    assert [(c.kind, c.value) for c in gripper.commands] == [
        ("open", SETTINGS.open_width_m),
        ("close", SETTINGS.grip_force_n),
    ]
    grasp = arm.tcp_pose_at(command_at(arm.commands, gripper.commands[1].time_s).positions_rad)
    # Mid-pad at the bar's centre of mass where the pads allow: 22.75 mm, the pads 4 mm off the table.
    assert BAR.grasp_height_m == pytest.approx(0.02275)
    np.testing.assert_allclose(grasp.position_m, [0.5, 0.1, BAR.grasp_height_m], atol=1e-6)
    # The closing axis (the gripper's yaw) lies along the bar's y axis, across its 40 mm side.
    assert fold_yaw(grasp.yaw_rad - (yaw + math.pi / 2), math.pi) == pytest.approx(0.0, abs=1e-4)


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
    assert opening_m == pytest.approx(0.04 - s.pad_thickness_m)
    assert reach_m == pytest.approx(0.04 + s.pad_width_m / 2)
    assert push.face_geometry(s, math.pi / 2, 0.0) == pytest.approx(
        (0.08 - s.pad_thickness_m, 0.02 + s.pad_width_m / 2)
    )
    run, tcp = pushed_path(context, push)
    assert run.status == Status.SUCCESS, run.feedback
    assert run.feedback == "pushed +3.00 mm along x"
    assert [(c.kind, c.value) for c in fake_gripper(context).commands] == [("open", pytest.approx(opening_m))]
    deepest = int(np.argmax(tcp[:, 0]))
    assert tcp[deepest, 0] == pytest.approx(-reach_m + 0.003, abs=1e-6)
    assert tcp[deepest, 2] == pytest.approx(BAR.grasp_height_m, abs=1e-6), "pads 4 mm above the table"
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


def test_detect_among_identical_parts_chooses_a_free_one_nearest_its_own_target(clock) -> None:
    # Four green cubes: two at targets of their kind (one of them right beside the own target),
    # two free. Detect takes the free one nearer the own target, never a placed one.
    placed = [PlanarPose(0.45, 0.10, 0.0), PlanarPose(0.45, 0.0, 0.0)]
    own = PlanarPose(0.45, -0.09, 0.0)
    near_free, far_free = PlanarPose(0.62, -0.15, 0.0), PlanarPose(0.65, 0.20, 0.0)
    context = make_context(clock, cubes=[cube("green", p.x_m, p.y_m) for p in (*placed, far_free, near_free)])
    write({"/green 3/target": own})
    detect = Detect("detect green 3", "green 3", colour="green", kind_targets=[*placed, own])
    run = tick_until_done(set_up(detect, context), context)
    assert run.status == Status.SUCCESS, run.feedback
    pose = read("/green 3/pose")
    assert isinstance(pose, Pose)
    assert 1000 * math.hypot(pose.x_m - near_free.x_m, pose.y_m - near_free.y_m) < 0.5


def test_detect_when_every_identical_part_is_at_a_target_fails_saying_so(clock) -> None:
    placed = [PlanarPose(0.45, 0.10, 0.0), PlanarPose(0.45, 0.0, 0.0)]
    context = make_context(clock, cubes=[cube("green", p.x_m, p.y_m) for p in placed])
    write({"/green 2/target": placed[1]})
    detect = Detect("detect green 2", "green 2", colour="green", kind_targets=placed)
    run = tick_until_done(set_up(detect, context), context)
    assert run.status == Status.FAILURE
    assert "lie at targets of their kind" in run.feedback
