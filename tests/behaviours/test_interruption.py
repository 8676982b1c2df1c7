"""Interrupted motions and errors mid-motion go to the brake; one arm command per tick at most."""

from __future__ import annotations

import numpy as np
import pytest
from behaviour_helpers import (
    AWAY_Q,
    after,
    assert_comes_to_rest,
    assert_never_blocks,
    command_at,
    cube_pose,
    set_up,
    speeds,
    write,
)
from py_trees.common import Status

from bt_arrange.behaviours import MoveHome, Pick, Place, stages
from bt_arrange.errors import MotionError
from bt_arrange.geometry import PlanarPose
from bt_arrange.settings import ManipulationSettings
from bt_arrange.testing import brake_until_idle, fake_arm, make_context, tick_until_done

# -- interruption --------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("make", "during"),
    [
        (lambda: MoveHome("park"), stages.MOVE_HOME),
        (lambda: Pick("pick red", "red"), stages.DESCEND_TO_PART),
    ],
    ids=["joint motion", "straight line"],
)
def test_an_interrupted_motion_is_handed_to_the_brake_which_brings_the_arm_to_rest(clock, make, during) -> None:
    context = make_context(clock=clock, q=AWAY_Q)
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
    context = make_context(clock=clock, q=AWAY_Q)
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
        clock=clock, gripper_width_m=0.05, object_width_m=0.05, settings=ManipulationSettings(settle_s=0.0)
    )
    write({"/red/target": PlanarPose(0.45, -0.1, 0.2)})
    run = tick_until_done(set_up(Place("place red", "red"), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    assert max(t.arm_commands for t in run.ticks) == 1


def test_an_error_raised_mid_motion_is_a_failure_with_the_reason_and_the_motion_goes_to_the_brake(clock) -> None:
    context = make_context(clock=clock, q=AWAY_Q)
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
