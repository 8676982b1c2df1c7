"""Ticking a behaviour on the fake clock, the way the runner ticks a tree: tick, brake step, one control period."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import py_trees
from py_trees.common import Status

from bt_arrange.behaviours import Context
from bt_arrange.testing.devices import ArmCommand
from bt_arrange.testing.scene import fake_arm, fake_clock


@dataclass(frozen=True)
class Tick:
    """What one tick did: the world time, the status and feedback after it, and how many arm commands it sent."""

    time_s: float
    status: Status
    feedback: str
    arm_commands: int


@dataclass
class Run:
    """The ticks of one run of a behaviour."""

    ticks: list[Tick] = field(default_factory=list)

    @property
    def status(self) -> Status:
        """The status after the last tick."""
        return self.ticks[-1].status if self.ticks else Status.INVALID

    @property
    def feedback(self) -> str:
        """The feedback after the last tick."""
        return self.ticks[-1].feedback if self.ticks else ""

    @property
    def running(self) -> list[Tick]:
        """The ticks that ended RUNNING."""
        return [t for t in self.ticks if t.status == Status.RUNNING]


def tick_until_done(
    behaviour: py_trees.behaviour.Behaviour,
    context: Context,
    max_ticks: int = 5000,
    *,
    until: Callable[[Tick], bool] | None = None,
    setup: bool = True,
) -> Run:
    """Tick ``behaviour`` like the runner does (tick, brake step, one control period) until it is not RUNNING.

    The result's ``status`` and ``feedback`` are those after the last tick; ``ticks`` holds every
    tick. Before the first tick every node of ``behaviour`` that has not received ``context`` yet is
    set up with it (``setup=False``: as it is). ``until`` stops earlier, after the first tick it
    accepts (to interrupt a behaviour mid-run). A behaviour that ends hands a motion still at speed
    to the brake, which runs it to its end here, as in a tree. Raises ``AssertionError`` if the
    behaviour still runs after ``max_ticks`` (5000 ticks: 40 s of world time).
    """
    if setup:
        for node in behaviour.iterate():
            if getattr(node, "context", None) is not context:
                node.setup(context=context)
    arm, clock = fake_arm(context), fake_clock(context)
    run = Run()
    for _ in range(max_ticks):
        before = len(arm.commands)
        behaviour.tick_once()
        tick = Tick(clock.now(), behaviour.status, behaviour.feedback_message, len(arm.commands) - before)
        run.ticks.append(tick)
        context.brake.step()
        clock.advance(arm.control_period_s)
        if until is not None and until(tick):
            return run
        if behaviour.status != Status.RUNNING:
            # As the runner does: a motion the behaviour handed on at speed runs to its end.
            while context.brake.busy:
                context.brake.step()
                clock.advance(arm.control_period_s)
            return run
    raise AssertionError(f"{behaviour.name} still RUNNING after {max_ticks} ticks: {behaviour.feedback_message}")


def brake_until_idle(context: Context, max_steps: int = 2000) -> list[ArmCommand]:
    """Step the brake (one control period each) until the arm is at rest; the brake's commands."""
    arm, clock = fake_arm(context), fake_clock(context)
    before = len(arm.commands)
    for _ in range(max_steps):
        if not context.brake.active:
            return arm.commands[before:]
        context.brake.step()
        clock.advance(arm.control_period_s)
    raise AssertionError(f"the brake still moves the arm after {max_steps} steps")
