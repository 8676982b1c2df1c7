"""One behaviour at a time on a world that is already open: the session's small sibling.

A ``Session`` owns a whole arrangement run (the plan check, the world built and settled, the
report). Some callers want less: a yardstick of the cell (``bt_arrange_sim.pybullet.scripted``)
or a benchmark runs the arrangement's own behaviours (``Pick``, ``Place``, ``Push``) one by one on
a world it set up itself, with hand-filled blackboard keys. ``BehaviourRun`` is that, built from
bt_arrange's pieces, so a backend supplies only the world (the rule of docs/architecture.md:
the session belongs to ``bt_arrange``, a backend never builds a ``Runner``).

Unlike ``Session.run``, it leaves the blackboard alone (the caller wrote the keys the behaviour
reads) and neither places nor settles parts.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import py_trees
from py_trees.common import Status

from bt_arrange.behaviours import Context
from bt_arrange.checks import positive_number
from bt_arrange.motion import CartesianLimits, JointLimits
from bt_arrange.runner import Runner
from bt_arrange.settings import ManipulationSettings

if TYPE_CHECKING:
    from bt_arrange.session import World


@dataclass(frozen=True)
class BehaviourResult:
    """How one behaviour ended: its status, the world time it took (s), its last feedback, a stop at the limit."""

    status: Status
    sim_seconds: float
    feedback: str
    timed_out: bool


class BehaviourRun:
    """Behaviours ticked one at a time, each as a one-node tree on ``world``'s clock, stepping ``world``.

    ``context`` (the world's robot, the bundled kinematics with ``joint_limits`` and
    ``cartesian_limits``, ``settings``) is shared by every behaviour run, as a tree's nodes share it.
    ``time_limit_s`` is the world time each behaviour may take.
    """

    def __init__(
        self,
        world: World,
        *,
        settings: ManipulationSettings | None = None,
        joint_limits: JointLimits | None = None,
        cartesian_limits: CartesianLimits | None = None,
        time_limit_s: float = 60.0,
    ) -> None:
        positive_number("time limit", time_limit_s, "s", style="unit")
        self.world = world
        self.context = Context.create(
            world.robot, joint_limits=joint_limits, cartesian_limits=cartesian_limits, settings=settings
        )
        self.time_limit_s = time_limit_s

    def run(self, behaviour: py_trees.behaviour.Behaviour) -> BehaviourResult:
        """Tick ``behaviour`` until it succeeds or fails, or its world time runs out (then INVALID)."""
        result = Runner(behaviour, self.context, self.world.step, time_limit_s=self.time_limit_s).run()
        return BehaviourResult(result.status, result.sim_seconds, result.feedback, result.timed_out)
