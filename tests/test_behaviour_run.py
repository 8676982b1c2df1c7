"""BehaviourRun: one behaviour at a time on a world already open, on its clock, the blackboard untouched."""

from __future__ import annotations

import py_trees
import pytest
from py_trees.common import Status

from bt_arrange.behaviour_run import BehaviourRun
from bt_arrange.errors import PlanError
from bt_arrange.testing import make_context


class FakeWorld:
    """The part of a ``World`` a behaviour run uses: the robot, and a step of one control period."""

    def __init__(self) -> None:
        self.robot = make_context().robot
        self.steps = 0

    def step(self) -> None:
        self.steps += 1
        self.robot.clock.advance(self.robot.arm.control_period_s)


def queue(*statuses: Status, eventually: Status | None = None) -> py_trees.behaviours.StatusQueue:
    return py_trees.behaviours.StatusQueue("scripted", queue=list(statuses), eventually=eventually)


def test_a_behaviour_is_ticked_to_its_end_stepping_the_world_between_ticks() -> None:
    world = FakeWorld()
    result = BehaviourRun(world).run(queue(Status.RUNNING, Status.RUNNING, Status.SUCCESS))
    assert result.status == Status.SUCCESS
    assert not result.timed_out
    assert world.steps == 2
    assert result.sim_seconds == pytest.approx(2 * world.robot.arm.control_period_s)


def test_the_blackboard_the_caller_filled_is_left_alone() -> None:
    writer = py_trees.blackboard.Client(name="caller")
    writer.register_key("cube/pose", access=py_trees.common.Access.WRITE)
    writer.set("cube/pose", (0.5, 0.0, 0.0))
    BehaviourRun(FakeWorld()).run(queue(Status.SUCCESS))
    assert writer.get("cube/pose") == (0.5, 0.0, 0.0)


def test_a_behaviour_that_runs_past_the_world_time_limit_is_stopped() -> None:
    world = FakeWorld()
    result = BehaviourRun(world, time_limit_s=0.1).run(queue(eventually=Status.RUNNING))
    assert result.timed_out
    assert result.status == Status.INVALID
    assert result.sim_seconds == pytest.approx(0.1, abs=world.robot.arm.control_period_s)
    assert "0.1 s of world time" in result.feedback


class SetUpWith(py_trees.behaviour.Behaviour):
    """Succeeds at once, keeping the context it was set up with."""

    def setup(self, **kwargs) -> None:  # noqa: ANN003
        self.context = kwargs["context"]

    def update(self) -> Status:
        return Status.SUCCESS


def test_successive_behaviours_share_one_context_on_the_worlds_robot() -> None:
    world = FakeWorld()
    run = BehaviourRun(world)
    first, second = SetUpWith("first"), SetUpWith("second")
    run.run(first)
    run.run(second)
    assert first.context is second.context is run.context
    assert run.context.robot is world.robot


def test_a_time_limit_that_is_not_positive_is_refused_in_one_line() -> None:
    with pytest.raises(PlanError, match="time limit"):
        BehaviourRun(FakeWorld(), time_limit_s=0.0)
