"""Pick: grasp at the measured pose and lift, or let go and say why (squaring: test_pick_squaring.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from behaviour_helpers import (
    AWAY_Q,
    CUBE_EDGE_M,
    CUBE_GRASP_HEIGHT_M,
    FAR_X_M,
    SETTINGS,
    assert_never_blocks,
    bar_pose,
    command_at,
    cube_pose,
    set_up,
    write,
)
from py_trees.common import Status

from bt_arrange.behaviours import Context, Pick, Place, stages
from bt_arrange.errors import UnreachableError
from bt_arrange.geometry import PlanarPose, fold_yaw
from bt_arrange.motion import ArmKinematics, gripper_down_pose
from bt_arrange.objects import BAR
from bt_arrange.shapes import ROBOTIQ_2F85, preferred_grasp
from bt_arrange.testing import fake_arm, fake_gripper, make_context, tick_until_done

# -- Pick ----------------------------------------------------------------------------------------


BAR_GRASP_HEIGHT_M = preferred_grasp(BAR.shape, ROBOTIQ_2F85).height_m


def test_pick_grasps_at_the_measured_pose_and_lifts(clock) -> None:
    context = make_context(clock=clock, q=AWAY_Q, gripper_width_m=0.0, object_width_m=CUBE_EDGE_M)
    yaw = math.radians(17.0)
    write({"/red/pose": cube_pose(0.5, 0.1, yaw)})
    run = tick_until_done(set_up(Pick("pick red", "red"), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    assert run.feedback == "holding red, fingers 50.0 mm apart"
    assert_never_blocks(run)
    seen = list(dict.fromkeys(t.feedback for t in run.running))
    assert seen == [
        stages.MOVE_ABOVE_PART,
        stages.WAIT_FOR_OPEN_FINGERS,
        stages.DESCEND_TO_PART,
        stages.CLOSE_ON_PART,
        stages.LIFT_PART,
    ]
    arm, gripper = fake_arm(context), fake_gripper(context)
    assert [(c.kind, c.value) for c in gripper.commands] == [
        ("open", SETTINGS.open_width_m),
        ("close", SETTINGS.grip_force_n),
    ]
    grasp = arm.tcp_pose_at(command_at(arm.commands, gripper.commands[1].time_s).positions_rad)
    np.testing.assert_allclose(grasp.position_m, [0.5, 0.1, CUBE_GRASP_HEIGHT_M], atol=1e-6)
    assert fold_yaw(grasp.yaw_rad - yaw) == pytest.approx(0.0, abs=1e-4), "pads square to the cube's faces"
    np.testing.assert_allclose(arm.tcp_pose().position_m, [0.5, 0.1, SETTINGS.approach_height_m], atol=1e-6)


def test_pick_that_closes_on_nothing_fails_naming_the_width(clock) -> None:
    context = make_context(clock=clock, object_width_m=None)
    write({"/red/pose": cube_pose(0.45, -0.05)})
    run = tick_until_done(set_up(Pick("pick red", "red"), context), context)
    assert run.status == Status.FAILURE
    assert run.feedback == (
        "no part between the pads: the fingers closed to 0.0 mm, a 50 mm cube holds them at least 47.0 mm apart"
    )
    feedback = [t.feedback for t in run.ticks]
    assert feedback.index(stages.LET_GO_OF_BAD_GRASP) < feedback.index(stages.LIFT_PART), "lets go before lifting"
    assert fake_arm(context).tcp_pose().z_m == pytest.approx(SETTINGS.approach_height_m, abs=1e-6), "lifted clear"
    assert fake_gripper(context).width() == pytest.approx(SETTINGS.open_width_m, abs=1e-3)


def test_pick_that_still_holds_a_turned_cube_by_its_corners_after_squaring_lets_go_and_fails(clock) -> None:
    # A cube turned ~30 degrees under the pads is gripped across two vertical edges, 68 mm apart,
    # and (in this fake) the squaring closes leave it so.
    context = make_context(clock=clock, object_width_m=0.068)
    write({"/red/pose": cube_pose(0.45, -0.05)})
    run = tick_until_done(set_up(Pick("pick red", "red"), context), context)
    assert run.status == Status.FAILURE
    assert run.feedback == (
        "the pads hold the part across its corners: 68.0 mm apart, more than the 60.0 mm of a 50 mm cube "
        "held nearly square (it is turned) after squaring a 68.0 mm grip"
    )
    feedback = [t.feedback for t in run.ticks]
    assert feedback.index(stages.CLOSE_ON_SQUARED_PART) < feedback.index(stages.LET_GO_OF_BAD_GRASP)
    assert feedback.index(stages.LET_GO_OF_BAD_GRASP) < feedback.index(stages.LIFT_PART), "lets go before lifting"
    assert fake_gripper(context).width() == pytest.approx(SETTINGS.open_width_m, abs=1e-3)


@pytest.mark.parametrize("make", [Pick, Place], ids=["Pick", "Place"])
def test_a_target_out_of_reach_fails_before_any_arm_command(context: Context, make) -> None:
    write({"/red/pose": cube_pose(FAR_X_M, 0.0), "/red/target": PlanarPose(FAR_X_M, 0.0)})
    with pytest.raises(UnreachableError) as unreachable:
        ArmKinematics().check_reachable(gripper_down_pose(FAR_X_M, 0.0, SETTINGS.approach_height_m))
    run = tick_until_done(set_up(make(f"{make.__name__} red", "red"), context), context)
    assert [t.status for t in run.ticks] == [Status.FAILURE], "fails on its first tick"
    first_move = stages.MOVE_ABOVE_PART if make is Pick else stages.CARRY_ABOVE_TARGET
    assert run.feedback.startswith(f"{first_move}: ")
    assert str(unreachable.value).split(" is out of reach")[1] in run.feedback
    assert fake_arm(context).commands == []


def test_fingers_that_never_stop_fail_after_the_gripper_timeout(clock) -> None:
    context = make_context(clock=clock, stuck_gripper=True)
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


# -- a bar: grasp, push and squaring from the type's size ---------------------------


def test_pick_of_a_bar_closes_across_its_40_mm_side_at_the_types_grasp_height(clock) -> None:
    assert BAR.size_m == (0.08, 0.04, 0.04)
    context = make_context(clock=clock, q=AWAY_Q, gripper_width_m=0.0, object_width_m=0.04)
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
    assert BAR_GRASP_HEIGHT_M == pytest.approx(0.02275)
    np.testing.assert_allclose(grasp.position_m, [0.5, 0.1, BAR_GRASP_HEIGHT_M], atol=1e-6)
    # The closing axis (the gripper's yaw) lies along the bar's y axis, across its 40 mm side.
    assert fold_yaw(grasp.yaw_rad - (yaw + math.pi / 2), math.pi) == pytest.approx(0.0, abs=1e-4)


# -- the close of a part held off its centre --------------------------------------------


def _recorded_closes(clock, object_type, object_width_m: float) -> list[tuple[float, float | None]]:
    """Pick a part and return each close command's (opening when sent, speed)."""
    from bt_arrange.geometry import Pose

    context = make_context(clock=clock, q=AWAY_Q, gripper_width_m=0.0, object_width_m=object_width_m)
    write({"/red/pose": Pose.from_planar(0.5, 0.1, math.radians(17.0), object_type.shape.height_m / 2)})
    gripper = fake_gripper(context)
    closes: list[tuple[float, float | None]] = []
    close = gripper.close

    def recording_close(force_n: float, speed_m_s: float | None = None) -> None:
        closes.append((gripper.width(), speed_m_s))
        close(force_n, speed_m_s)

    gripper.close = recording_close  # type: ignore[method-assign]
    run = tick_until_done(set_up(Pick("pick red", "red", object_type=object_type), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    return closes


def test_an_off_centre_grasp_crosses_the_stroke_fast_and_meets_the_part_at_the_slow_speed(clock) -> None:
    from bt_arrange.objects import ObjectType
    from bt_arrange.shapes import Prism

    kite = ObjectType("kite", shape=Prism.from_outline([[0, 0], [0.03, -0.02], [0.07, 0], [0.03, 0.02]], 0.02))
    grasp = preferred_grasp(kite.shape, ROBOTIQ_2F85)
    assert grasp.centre_m != (0.0, 0.0), "held off its centre"
    closes = _recorded_closes(clock, kite, grasp.width_m)
    slow_from_m = grasp.width_m + 2 * SETTINGS.slow_close_clearance_per_side_m
    # Opened only the pick clearance clear of the grasped side (not the full stroke), sent from there at
    # the fingers' speed, slowed once the pads stand the clearance off the grasped side (the fake's
    # fingers move 1 mm or so a control period), before they meet it.
    opening_m = grasp.width_m + 2 * SETTINGS.off_centre_pick_clearance_per_side_m
    assert opening_m < SETTINGS.open_width_m
    assert closes[0] == (pytest.approx(opening_m), SETTINGS.finger_speed_m_s)
    assert closes[1][1] == SETTINGS.squaring_finger_speed_m_s
    assert grasp.width_m + 0.004 < closes[1][0] <= slow_from_m
    assert len(closes) == 2


def test_a_cubes_centred_grasp_closes_once_at_the_fingers_speed(clock) -> None:
    from bt_arrange.objects import CUBE

    assert _recorded_closes(clock, CUBE, CUBE_EDGE_M) == [
        (pytest.approx(SETTINGS.open_width_m), SETTINGS.finger_speed_m_s)
    ]


def test_a_part_too_wide_for_the_pick_clearance_opens_to_the_full_stroke() -> None:
    from bt_arrange.behaviours.moves import pick_opening_m
    from bt_arrange.objects import ObjectType
    from bt_arrange.shapes import Prism

    wide = ObjectType("wide", shape=Prism.from_outline([[0, 0], [0.06, 0], [0.05, 0.055], [0, 0.05]], 0.02))
    assert preferred_grasp(wide.shape, ROBOTIQ_2F85).width_m + 2 * SETTINGS.off_centre_pick_clearance_per_side_m > (
        SETTINGS.open_width_m
    )
    assert pick_opening_m(SETTINGS, wide) == SETTINGS.open_width_m
