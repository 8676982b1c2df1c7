"""Motions handed on at speed: a lift into the carry, a retreat into the way home (``MoveStage(hand_on=)``).

The handed-on motion keeps going through the brake (``ArmBrake.carry_on``) until the next joint move
takes it over from its state; the setpoint stream stays one setpoint per control period, continuous,
and within the joint limits of the motions on either side, sampled.
"""

from __future__ import annotations

import math

import numpy as np
import py_trees
import pytest
from behaviour_helpers import AWAY_Q, CUBE_EDGE_M, SETTINGS, cube_pose, set_up, write
from py_trees.common import Status

from bt_arrange.behaviours import MoveHome, Pick, Place
from bt_arrange.behaviours.context import ArmBrake
from bt_arrange.geometry import PlanarPose
from bt_arrange.motion import JointLimits, JointMotion
from bt_arrange.motion.trajectory import LinearMotion
from bt_arrange.testing import ArmCommand, fake_arm, fake_gripper, make_context, tick_until_done

#: Finite differences of setpoints taken over from one motion by the next: a line's acceleration is
#: handed on as its samples' second difference, so the first jerk sample may exceed a limit by the
#: round-off of that estimate, not more.
JERK_SLACK = 1.05


def _differences(commands: list[ArmCommand], period_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    q = np.array([c.positions_rad for c in commands])
    velocity = np.diff(q, axis=0) / period_s
    acceleration = np.diff(velocity, axis=0) / period_s
    jerk = np.diff(acceleration, axis=0) / period_s
    return velocity, acceleration, jerk


def _assert_within(commands: list[ArmCommand], period_s: float, limits: JointLimits) -> None:
    velocity, acceleration, jerk = _differences(commands, period_s)
    assert np.all(np.abs(velocity) <= np.array(limits.velocity_rad_s) * (1 + 1e-6))
    assert np.all(np.abs(acceleration) <= np.array(limits.acceleration_rad_s2) * (1 + 1e-3))
    assert np.all(np.abs(jerk) <= np.array(limits.jerk_rad_s3) * JERK_SLACK)


def _stops(commands: list[ArmCommand]) -> int:
    """How many setpoints bring the arm to rest (the last of each motion that stops)."""
    return sum(1 for c in commands if c.velocities_rad_s is not None and np.max(np.abs(c.velocities_rad_s)) < 1e-9)


def _one_setpoint_per_period(commands: list[ArmCommand], period_s: float) -> None:
    times = np.array([c.time_s for c in commands])
    assert np.allclose(np.diff(times), period_s), "every control period gets exactly one setpoint, none skipped"


def test_a_lift_is_handed_on_at_speed_to_the_carry_within_the_joint_limits(clock) -> None:
    context = make_context(clock=clock, q=AWAY_Q, gripper_width_m=0.0, object_width_m=CUBE_EDGE_M)
    write({"/red/pose": cube_pose(0.5, 0.1, math.radians(10.0)), "/red/target": PlanarPose(0.45, -0.15, 0.3)})
    pick, place = Pick("pick red", "red"), Place("place red", "red")
    sequence = py_trees.composites.Sequence("pick and place", memory=True, children=[pick, place])
    run = tick_until_done(set_up(sequence, context), context)
    assert run.status == Status.SUCCESS, run.feedback
    arm = fake_arm(context)
    period_s = arm.control_period_s

    closed_s, released_s = (c.time_s for c in fake_gripper(context).commands[1:3])
    window = [c for c in arm.commands if closed_s <= c.time_s <= released_s]
    _one_setpoint_per_period(window, period_s)
    # At rest above the target (the lowering is a line from rest) and at the release, not at the top
    # of the lift: passed at speed into the carry.
    assert _stops(window) == 2
    # The lift and the lowering within the planner's joint limits, the carry within the carry's: the
    # faster of the two bounds the whole stream, the hand-on included.
    _assert_within(window, period_s, SETTINGS.carry_joint_limits)


def test_a_retreat_is_handed_on_to_the_way_home_and_an_unclaimed_motion_runs_to_its_end(clock) -> None:
    context = make_context(clock=clock, gripper_width_m=CUBE_EDGE_M, object_width_m=CUBE_EDGE_M)
    write({"/red/target": PlanarPose(0.45, -0.1, 0.0)})
    place, home = Place("place red", "red"), MoveHome("park")
    sequence = py_trees.composites.Sequence("place and park", memory=True, children=[place, home])
    run = tick_until_done(set_up(sequence, context), context)
    assert run.status == Status.SUCCESS, run.feedback
    arm = fake_arm(context)
    period_s = arm.control_period_s
    released_s = fake_gripper(context).commands[0].time_s
    window = [c for c in arm.commands if c.time_s >= released_s]
    _one_setpoint_per_period(window, period_s)
    assert _stops(window) == 1, "at rest at home, not at the top of the retreat"
    _assert_within(window, period_s, SETTINGS.free_joint_limits)
    np.testing.assert_allclose(arm.joint_positions(), context.home_q, atol=1e-9)

    # Place alone: its handed-on retreat, claimed by nothing, runs to the top of the line and stops there.
    context = make_context(clock=clock, gripper_width_m=CUBE_EDGE_M, object_width_m=CUBE_EDGE_M)
    write({"/red/target": PlanarPose(0.45, -0.1, 0.0)})
    run = tick_until_done(set_up(Place("place red", "red"), context), context)
    assert run.status == Status.SUCCESS
    assert not context.brake.busy
    top = fake_arm(context).tcp_pose()
    np.testing.assert_allclose(top.position_m, [0.45, -0.1, SETTINGS.approach_height_m], atol=1e-6)


class _Arm:
    """The arm the brake commands: it records setpoints."""

    def __init__(self) -> None:
        self.commands: list[np.ndarray] = []

    def command(self, positions_rad: np.ndarray, velocities_rad_s: np.ndarray | None = None) -> None:
        self.commands.append(np.asarray(positions_rad))


def _motion() -> JointMotion:
    return JointMotion(np.zeros(6), np.full(6, 0.5), JointLimits(), 0.008)


def test_the_brake_carries_a_handed_on_motion_to_its_end_skipping_the_period_already_commanded() -> None:
    arm = _Arm()
    brake = ArmBrake(arm)  # type: ignore[arg-type]
    motion = _motion()
    motion.step()
    brake.carry_on(motion)
    assert brake.carrying and brake.busy and not brake.active and motion.handed_on
    brake.step()
    assert arm.commands == [], "the handing stage already sent this period's setpoint"
    steps = 0
    while brake.busy:
        brake.step()
        steps += 1
    assert motion.done and steps == round(motion.duration_s / 0.008) - 1
    np.testing.assert_allclose(arm.commands[-1], np.full(6, 0.5))


def test_taking_over_hands_the_last_setpoint_state_and_braking_stops_instead() -> None:
    brake = ArmBrake(_Arm())  # type: ignore[arg-type]
    motion = _motion()
    for _ in range(20):
        setpoint = motion.step()
    brake.carry_on(motion)
    q, velocity, acceleration, commanded = brake.take_over()
    np.testing.assert_allclose(q, setpoint.positions_rad)
    np.testing.assert_allclose(velocity, setpoint.velocities_rad_s)
    assert np.any(acceleration != 0.0) and commanded
    assert not brake.busy

    other = _motion()
    other.step()
    brake.carry_on(other)
    brake.brake_carried()
    assert brake.active and not brake.carrying and other.stopping and not other.handed_on


@pytest.mark.parametrize("remaining_m", [0.0, 0.02])
def test_a_line_hands_on_its_state_as_planned(remaining_m: float) -> None:
    from bt_arrange.motion import ArmKinematics, CartesianLimits, gripper_down_pose

    kinematics = ArmKinematics()
    start = kinematics.inverse(gripper_down_pose(0.5, 0.0, 0.03, 0.0), np.array(AWAY_Q))
    line = LinearMotion(
        kinematics, start, gripper_down_pose(0.5, 0.0, 0.1, 0.0), CartesianLimits(), JointLimits(), 0.008
    )
    previous = None
    while line.remaining_m > remaining_m:
        previous = line.state()
        line.step()
    q, velocity, _ = line.state()
    assert previous is not None
    np.testing.assert_allclose(velocity, (q - previous[0]) / 0.008, atol=0.05)
    assert kinematics.forward(q).z_m == pytest.approx(0.1 - line.remaining_m, abs=1e-6)
