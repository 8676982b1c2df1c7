"""A part without half-turn symmetry is picked and carried turning the last wrist joint least.

Pick may take it with the gripper half a turn round (``/<obj>/grasp_half_turn``) and Place reads
that, so the part still lands at its target's yaw; the carry takes the way round that, with the park
for the look after it, turns the wrist least (``toward_home_q``).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from behaviour_helpers import command_at, read, set_up, write
from py_trees.common import Status

from bt_arrange.behaviours import Pick, Place, keys
from bt_arrange.behaviours.moves import grasp_of, half_turn_free, toward_home_q
from bt_arrange.geometry import PlanarPose, Pose, fold_yaw
from bt_arrange.motion import DEFAULT_HOME_Q, ArmKinematics
from bt_arrange.objects import CUBE, ObjectType
from bt_arrange.settings import ManipulationSettings
from bt_arrange.shapes import Prism
from bt_arrange.testing import fake_arm, fake_gripper, make_context, tick_until_done

SETTINGS = ManipulationSettings()
FRAGMENT = ObjectType(
    "fragment",
    shape=Prism.from_outline([[0, 0], [0.045, 0.004], [0.06, 0.03], [0.035, 0.028], [0.03, 0.05], [0.005, 0.04]], 0.02),
)
GRASP = grasp_of(SETTINGS, FRAGMENT)
HOME_WRIST_YAW_RAD = ArmKinematics().wrist_yaw_rad(DEFAULT_HOME_Q)
WRIST = 5


def _pick_and_place(clock, part_yaw_rad: float, target_yaw_rad: float) -> tuple[bool, Pose, Pose, np.ndarray]:
    """Pick the fragment at ``part_yaw_rad`` from home and place it at ``target_yaw_rad``.

    Returns whether the pick took the half turn, the TCP at the grasp and at the release, and the
    joints above the target (the carry's end).
    """
    width_m = GRASP.width_m
    context = make_context(clock=clock, gripper_width_m=width_m, object_width_m=width_m)
    write(
        {
            "/p/pose": Pose.from_rotation([0.42, 0.12, 0.01], _yaw_matrix(part_yaw_rad)),
            "/p/target": PlanarPose(0.5, -0.1, target_yaw_rad),
        }
    )
    pick = tick_until_done(set_up(Pick("pick p", "p", FRAGMENT), context), context)
    assert pick.status == Status.SUCCESS, pick.feedback
    half_turn = bool(read(keys.key("p", keys.GRASP_HALF_TURN)))
    arm, gripper = fake_arm(context), fake_gripper(context)
    grasp = arm.tcp_pose_at(command_at(arm.commands, gripper.commands[1].time_s).positions_rad)
    place = tick_until_done(set_up(Place("place p", "p", FRAGMENT), context), context)
    assert place.status == Status.SUCCESS, place.feedback
    release_time_s = gripper.commands[-1].time_s
    release = arm.tcp_pose_at(command_at(arm.commands, release_time_s).positions_rad)
    lowered = [c for c in arm.commands if c.time_s < release_time_s][-1].positions_rad
    return half_turn, grasp, release, np.asarray(lowered)


def _yaw_matrix(yaw_rad: float) -> np.ndarray:
    c, s = math.cos(yaw_rad), math.sin(yaw_rad)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _part_yaw_for_grasp_turn(turn_rad: float) -> float:
    """The part yaw whose grasp turns the gripper by ``turn_rad`` from home's."""
    return HOME_WRIST_YAW_RAD + turn_rad - GRASP.yaw_offset_rad


def test_a_part_turned_most_of_a_turn_is_taken_half_a_turn_round_and_still_lands_at_its_targets_yaw(clock) -> None:
    part_yaw = _part_yaw_for_grasp_turn(1.3)
    target_yaw = part_yaw + 2.5
    half_turn, grasp, release, lowered = _pick_and_place(clock, part_yaw, target_yaw)
    assert half_turn, "a grasp 1.3 rad round and a carry 2.5 rad on would park the wrist back 3.8 rad"
    # The pads are on the other sides of the same grasp: the gripper half a turn from the part's grasp yaw.
    assert fold_yaw(grasp.yaw_rad - (part_yaw + GRASP.yaw_offset_rad), 2 * math.pi) == pytest.approx(
        math.pi, abs=1e-4
    ) or fold_yaw(grasp.yaw_rad - (part_yaw + GRASP.yaw_offset_rad), 2 * math.pi) == pytest.approx(-math.pi, abs=1e-4)
    # Place knows it: the part is released at its target's own yaw, the gripper half a turn round.
    turned = fold_yaw(release.yaw_rad - (target_yaw + GRASP.yaw_offset_rad), 2 * math.pi)
    assert abs(turned) == pytest.approx(math.pi, abs=1e-4)
    # The grasp's centre is the same point of the part either way round: the TCP stands over it.
    c, s = math.cos(target_yaw), math.sin(target_yaw)
    cx, cy = GRASP.centre_m
    np.testing.assert_allclose(release.position_m[:2], [0.5 + c * cx - s * cy, -0.1 + s * cx + c * cy], atol=1e-5)
    # And the wrist ends the carry within half a turn of home's, where the look parks it.
    assert abs(lowered[WRIST] - DEFAULT_HOME_Q[WRIST]) < math.pi


def test_a_part_the_wrist_reaches_as_it_is_keeps_the_nearest_grasp(clock) -> None:
    part_yaw = _part_yaw_for_grasp_turn(0.4)
    half_turn, grasp, release, _ = _pick_and_place(clock, part_yaw, part_yaw - 0.5)
    assert not half_turn
    assert fold_yaw(grasp.yaw_rad - (part_yaw + GRASP.yaw_offset_rad), 2 * math.pi) == pytest.approx(0.0, abs=1e-4)
    assert fold_yaw(release.yaw_rad - (part_yaw - 0.5 + GRASP.yaw_offset_rad), 2 * math.pi) == pytest.approx(
        0.0, abs=1e-4
    )


def test_without_a_target_on_the_blackboard_the_pick_keeps_the_nearest_grasp(clock) -> None:
    context = make_context(clock=clock, gripper_width_m=GRASP.width_m, object_width_m=GRASP.width_m)
    write({"/p/pose": Pose.from_rotation([0.42, 0.12, 0.01], _yaw_matrix(_part_yaw_for_grasp_turn(1.3)))})
    pick = tick_until_done(set_up(Pick("pick p", "p", FRAGMENT), context), context)
    assert pick.status == Status.SUCCESS, pick.feedback
    assert read(keys.key("p", keys.GRASP_HALF_TURN)) is False


def test_a_cuboid_has_the_half_turn_for_free_and_never_records_one(clock) -> None:
    assert half_turn_free(CUBE) and not half_turn_free(FRAGMENT)
    context = make_context(clock=clock, gripper_width_m=0.05, object_width_m=0.05)
    write(
        {
            "/red/pose": Pose.from_rotation([0.42, 0.12, 0.025], _yaw_matrix(1.2)),
            "/red/target": PlanarPose(0.5, -0.1, 2.9),
        }
    )
    pick = tick_until_done(set_up(Pick("pick red", "red"), context), context)
    assert pick.status == Status.SUCCESS, pick.feedback
    assert read(keys.key("red", keys.GRASP_HALF_TURN)) is False


def test_toward_home_takes_the_wrists_way_round_that_reaches_and_leaves_for_home_soonest(clock) -> None:
    context = make_context(clock=clock)
    home = np.asarray(context.home_q, dtype=float)
    start = home.copy()
    start[WRIST] += 0.5
    target = home.copy()
    target[WRIST] += 3.5  # the same TCP pose as home's wrist turned -2.78 rad
    chosen = toward_home_q(context, start, target)
    # 3.28 rad on and 2.78 back, not 3.0 on and 3.5 back.
    assert chosen[WRIST] == pytest.approx(home[WRIST] + 3.5 - 2.0 * math.pi)
    np.testing.assert_allclose(chosen[:WRIST], target[:WRIST])
    near = home.copy()
    near[WRIST] += 0.5
    np.testing.assert_allclose(toward_home_q(context, start, near), near)
    # A way round outside the joint's limits is never taken.
    low = home.copy()
    low[WRIST] = -2.0 * math.pi + 0.3
    assert toward_home_q(context, low, low)[WRIST] >= -2.0 * math.pi
