"""What the behaviour tests share: blackboard by hand, set-up, the never-blocks check, arm-command helpers.

Every run is driven the way the runner drives a tree (``bt_arrange.testing.tick_until_done``: tick, brake step,
one control period of world time) and checked tick by tick: a feedback message on every tick, and
at most one arm setpoint per tick (a behaviour never blocks). The fixtures (``clock``, ``context``,
the clean blackboard) are in ``tests/conftest.py``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import py_trees
import pytest
from py_trees.common import Access

from bt_arrange.behaviours import Context
from bt_arrange.geometry import Pose
from bt_arrange.objects import BAR, CUBE
from bt_arrange.settings import ManipulationSettings
from bt_arrange.testing import ArmCommand, Run, Tick

SETTINGS = ManipulationSettings()
#: The paper's cube: its edge, the TCP height that grasps and pushes it, and the TCP's distance
#: from its centre when the pads touch a face (half an edge and half a pad).
CUBE_EDGE_M = CUBE.size_m[0]
CUBE_GRASP_HEIGHT_M = SETTINGS.tcp_heights_m(CUBE.shape)[0]
CUBE_PUSH_REACH_M = CUBE_EDGE_M / 2 + SETTINGS.gripper.pad_width_m / 2
#: Narrowest opening that still counts as holding a cube: 47 mm.
HELD_MIN_WIDTH_M = CUBE_EDGE_M - SETTINGS.grasp_width_tolerance_m
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
    return Pose.from_planar(x_m, y_m, yaw_rad, CUBE_EDGE_M / 2)


def bar_pose(x_m: float, y_m: float, yaw_rad: float = 0.0) -> Pose:
    return Pose.from_planar(x_m, y_m, yaw_rad, BAR.shape.height_m / 2)
