"""MoveHome: parks the arm out of the camera's view."""

from __future__ import annotations

import numpy as np
import pytest
from behaviour_helpers import AWAY_Q, SETTINGS, assert_never_blocks, set_up
from py_trees.common import Status

from bt_arrange.behaviours import Context, MoveHome, stages
from bt_arrange.testing import fake_arm, make_context, tick_until_done

# -- MoveHome ------------------------------------------------------------------------------------


def test_move_home_when_parked_succeeds_at_once_without_moving(context: Context) -> None:
    run = tick_until_done(set_up(MoveHome("park"), context), context)
    assert [t.status for t in run.ticks] == [Status.SUCCESS]
    assert run.feedback == "at home, out of the camera's view"
    assert fake_arm(context).commands == []


def test_move_home_brings_the_arm_home_one_setpoint_per_tick(clock) -> None:
    context = make_context(clock=clock, q=AWAY_Q)
    run = tick_until_done(set_up(MoveHome("park"), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    assert run.feedback == "at home, out of the camera's view"
    assert {t.feedback for t in run.running} == {stages.MOVE_HOME}
    assert_never_blocks(run)
    arm = fake_arm(context)
    assert len(arm.commands) > 50, "a joint motion of a second or more, one setpoint per control period"
    np.testing.assert_allclose(arm.joint_positions(), context.home_q, atol=1e-9)
    # Then the arm settles: the fake arm is still at once (its last setpoint is at rest), so the
    # stage ends on the next tick, without sending anything more.
    settle_ticks = [t for t in run.ticks if t.time_s > arm.commands[-1].time_s]
    assert len(settle_ticks) == 1
    assert all(t.arm_commands == 0 for t in settle_ticks)


def test_move_home_waits_while_the_arm_still_moves_but_no_longer_than_settle_s(clock) -> None:
    context = make_context(clock=clock, q=AWAY_Q)
    arm = fake_arm(context)
    real_velocities = arm.joint_velocities
    arm.joint_velocities = lambda: real_velocities() + 0.01  # type: ignore[method-assign] - a joint that creeps on
    run = tick_until_done(set_up(MoveHome("park"), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    settle_ticks = [t for t in run.ticks if t.time_s > arm.commands[-1].time_s]
    assert len(settle_ticks) == pytest.approx(SETTINGS.settle_s / arm.control_period_s, abs=1)
    assert all(t.arm_commands == 0 for t in settle_ticks)
