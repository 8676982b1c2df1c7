"""Pick squaring a cube pinched across its corners: by a shift, a sweep, a turn of the wrist, or off."""

from __future__ import annotations

import math

import numpy as np
import pytest
from behaviour_helpers import (
    AWAY_Q,
    CUBE_EDGE_M,
    CUBE_GRASP_HEIGHT_M,
    SETTINGS,
    assert_never_blocks,
    command_at,
    cube_pose,
    set_up,
    write,
)
from py_trees.common import Status

from bt_arrange.behaviours import Context, Pick, stages
from bt_arrange.errors import OutOfRangeError
from bt_arrange.geometry import Pose
from bt_arrange.settings import ManipulationSettings
from bt_arrange.testing import fake_arm, fake_gripper, make_context, tick_until_done


def _squared_by_the_second_close(context: Context, squared_width_m: float) -> None:
    """The fake cube is pinched across its corners by the first close and square from the next one on."""
    gripper = fake_gripper(context)
    close = gripper.close

    def close_then_square(force_n: float, speed_m_s: float | None = None) -> None:
        close(force_n)
        gripper.object_width_m = squared_width_m

    gripper.close = close_then_square  # type: ignore[method-assign]


def test_pick_squares_a_cube_pinched_across_its_corners_and_holds_it(clock) -> None:
    shift = ManipulationSettings(squaring="shift")
    context = make_context(clock=clock, q=AWAY_Q, gripper_width_m=0.0, object_width_m=0.068, settings=shift)
    _squared_by_the_second_close(context, 0.0505)
    write({"/red/pose": cube_pose(0.5, 0.1, 0.0)})
    run = tick_until_done(set_up(Pick("pick red", "red"), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    assert run.feedback == "holding red, fingers 50.5 mm apart (squared from a 68.0 mm grip across its corners)"
    assert_never_blocks(run)
    seen = list(dict.fromkeys(t.feedback for t in run.running))
    assert seen == [
        stages.MOVE_ABOVE_PART,
        stages.WAIT_FOR_OPEN_FINGERS,
        stages.DESCEND_TO_PART,
        stages.CLOSE_ON_PART,
        stages.OPEN_TO_SQUARE,
        stages.SHIFT_ALONG_PADS,
        stages.CLOSE_TO_SQUARE,
        stages.OPEN_SQUARED_PART,
        stages.RECENTRE_ON_PART,
        stages.CLOSE_ON_SQUARED_PART,
        stages.LIFT_PART,
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
    np.testing.assert_allclose(final.position_m, [0.5, 0.1, CUBE_GRASP_HEIGHT_M], atol=1e-6)
    np.testing.assert_allclose(arm.tcp_pose().position_m, [0.5, 0.1, SETTINGS.approach_height_m], atol=1e-6)


def test_pick_squaring_by_a_sweep_pushes_along_the_closing_axis_towards_the_base(clock) -> None:
    context = make_context(clock=clock, object_width_m=0.069, settings=ManipulationSettings(squaring="sweep"))
    _squared_by_the_second_close(context, 0.051)
    write({"/red/pose": cube_pose(0.5, 0.1, 0.0)})
    run = tick_until_done(set_up(Pick("pick red", "red"), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    seen = list(dict.fromkeys(t.feedback for t in run.running))
    assert seen[seen.index(stages.CLOSE_ON_PART) + 1 :] == [
        stages.OPEN_TO_SQUARE,
        stages.SWEEP_TO_SQUARE,
        stages.CLOSE_ON_SQUARED_PART,
        stages.LIFT_PART,
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
    context = make_context(clock=clock, object_width_m=0.068, settings=ManipulationSettings(squaring="off"))
    write({"/red/pose": cube_pose(0.45, -0.05)})
    run = tick_until_done(set_up(Pick("pick red", "red"), context), context)
    assert run.status == Status.FAILURE
    assert run.feedback.startswith("the pads hold the part across its corners: 68.0 mm apart")
    assert [c.kind for c in fake_gripper(context).commands] == ["open", "close", "open"]


def test_an_unknown_squaring_is_a_one_line_error() -> None:
    with pytest.raises(OutOfRangeError, match="squaring 'twist': choose one of shift, sweep, turn, off"):
        ManipulationSettings(squaring="twist")


def _closes_stop_at(context: Context, widths_m: list[float]) -> None:
    """The fake's n-th close stops at ``widths_m[n]`` (the last one from there on)."""
    gripper = fake_gripper(context)
    close = gripper.close
    count = [0]

    def close_at_next_width(force_n: float, speed_m_s: float | None = None) -> None:
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
    context = make_context(clock=clock, q=AWAY_Q, gripper_width_m=0.0, settings=TURN)
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
    assert seen[seen.index(stages.CLOSE_ON_PART) + 1 :] == [
        stages.OPEN_TO_SQUARE,
        stages.TURN_WRIST_TO_SQUARE,
        stages.CLOSE_ON_TURNED_PART,
        stages.LIFT_PART,
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
    context = make_context(clock=clock, settings=TURN)
    # Turned the other way: +22.5 deg leaves the corners on the pads, -22.5 from the first yaw squares it.
    _closes_stop_at(context, [0.068, 0.070, 0.051])
    write({"/red/pose": cube_pose(0.5, 0.1, 0.0)})
    run = tick_until_done(set_up(Pick("pick red", "red"), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    assert run.feedback.endswith("(squared from a 68.0 mm grip across its corners, the wrist turned -22.5 deg)")
    assert_never_blocks(run)
    seen = list(dict.fromkeys(t.feedback for t in run.running))
    assert seen[seen.index(stages.CLOSE_ON_PART) + 1 :] == [
        stages.OPEN_TO_SQUARE,
        stages.TURN_WRIST_TO_SQUARE,
        stages.CLOSE_ON_TURNED_PART,
        stages.OPEN_TO_TURN_BACK,
        stages.TURN_WRIST_OTHER_WAY,
        stages.CLOSE_ON_SQUARED_PART,
        stages.LIFT_PART,
    ]
    first, plus, minus = _close_poses(context)
    assert _yaw_step_deg(first, plus) == pytest.approx(TURN.squaring_turn_deg, abs=1e-3)
    assert _yaw_step_deg(first, minus) == pytest.approx(-TURN.squaring_turn_deg, abs=1e-3)
    np.testing.assert_allclose(minus.position_m, first.position_m, atol=1e-6)
    lifted = fake_arm(context).tcp_pose()
    np.testing.assert_allclose(lifted.position_m, [0.5, 0.1, SETTINGS.approach_height_m], atol=1e-6)
    assert _yaw_step_deg(first, lifted) == pytest.approx(-TURN.squaring_turn_deg, abs=1e-3), "lifts at the final yaw"


def test_pick_squaring_by_a_turn_that_leaves_it_pinched_both_ways_lets_go_and_fails(clock) -> None:
    context = make_context(clock=clock, object_width_m=0.068, settings=TURN)
    write({"/red/pose": cube_pose(0.45, -0.05)})
    run = tick_until_done(set_up(Pick("pick red", "red"), context), context)
    assert run.status == Status.FAILURE
    assert run.feedback == (
        "the pads hold the part across its corners: 68.0 mm apart, more than the 60.0 mm of a 50 mm cube "
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
    assert feedback.index(stages.LET_GO_OF_BAD_GRASP) < feedback.index(stages.LIFT_PART), "lets go before lifting"
    assert fake_gripper(context).width() == pytest.approx(SETTINGS.open_width_m, abs=1e-3)


def test_pick_squaring_by_a_turn_leaves_a_square_grasp_alone(clock) -> None:
    context = make_context(clock=clock, object_width_m=CUBE_EDGE_M, settings=TURN)
    write({"/red/pose": cube_pose(0.45, -0.05, 0.3)})
    run = tick_until_done(set_up(Pick("pick red", "red"), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    assert run.feedback == "holding red, fingers 50.0 mm apart"
    assert [c.kind for c in fake_gripper(context).commands] == ["open", "close"]


@pytest.mark.parametrize("turn_deg", [0.0, -10.0, 45.0, 60.0])
def test_a_squaring_turn_outside_0_to_45_degrees_is_a_one_line_error(turn_deg: float) -> None:
    with pytest.raises(OutOfRangeError, match=f"squaring turn {turn_deg:g} deg must lie between 0 and 45 deg"):
        ManipulationSettings(squaring_turn_deg=turn_deg)
