"""Safety a lab needs before a first run, the same on every backend: a speed fraction, a workspace box, safety stops.

- ``MotionSafety.speed_fraction`` slows every motion the planner makes (``bt_arrange.motion.MotionPlanner``):
  velocity limits times ``f``, accelerations times ``f**2``, jerks times ``f**3``, so each motion is the
  same path played ``1/f`` times slower. A real cell starts at ``REAL_CELL_SPEED_FRACTION`` (0.5);
  ``bt-arrange run --speed-fraction F`` raises it.
- ``MotionSafety.workspace`` (a ``WorkspaceBox`` given by the backend's cell) is checked for every
  planned motion before it starts: the TCP's path, sampled, must stay inside the box. A motion that
  leaves it raises ``WorkspaceStop`` naming the motion and the box; nothing of it was sent.
- ``SafetyStop`` ends the whole tree: the runner (``bt_arrange.runner.Runner``) catches it, stops every
  behaviour, and the run ends with a FAILURE and the stop's one-line reason (the command line prints it
  and exits 1). A world raises it from ``step()`` when the robot stopped (a protective or emergency
  stop, a program that stopped, a connection lost: ``arm_stopped``, nothing is sent afterwards); the
  planner raises ``WorkspaceStop`` (the arm is brought to rest by the framework's brake first).

``SafetyStop`` is deliberately *not* a ``BtArrangeError``: behaviours turn those into a FAILURE of
their own and the tree moves on to its next part; a safety stop must reach the runner untouched.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from bt_arrange.errors import OutOfRangeError
from bt_arrange.geometry import FloatArray

if TYPE_CHECKING:
    from bt_arrange.motion.kinematics import ArmKinematics
    from bt_arrange.motion.limits import CartesianLimits, JointLimits
    from bt_arrange.motion.trajectory import Motion

#: The speed fraction a real cell starts at: every motion at half the speed the simulator runs it.
REAL_CELL_SPEED_FRACTION = 0.5
#: A joint motion's TCP path is checked against the workspace box at least this often (s of motion).
WORKSPACE_SAMPLE_PERIOD_S = 0.02


class SafetyStop(Exception):  # noqa: N818 - a stop, not an error of the user's: named for what happens
    """The run must end now: the tree ends with a FAILURE and ``reason``, and nothing moves afterwards.

    ``arm_stopped``: the robot itself stopped (its controller's protective or emergency stop, its
    program, its connection): no command may be sent any more. False when the framework refused a
    motion (``WorkspaceStop``): the arm is still under control and is brought to rest before the run ends.
    """

    def __init__(self, reason: str, *, arm_stopped: bool = True) -> None:
        super().__init__(reason)
        self.reason = reason
        self.arm_stopped = arm_stopped


class WorkspaceStop(SafetyStop):
    """A planned motion would take the TCP out of the workspace box: refused before any of it was sent."""

    def __init__(self, reason: str) -> None:
        super().__init__(reason, arm_stopped=False)


@dataclass(frozen=True)
class WorkspaceBox:
    """An axis-aligned box in the world (the robot's base) frame that the TCP must stay inside, metres."""

    x_m: tuple[float, float]
    y_m: tuple[float, float]
    z_m: tuple[float, float]

    def __post_init__(self) -> None:
        for axis, (low, high) in (("x", self.x_m), ("y", self.y_m), ("z", self.z_m)):
            if not (math.isfinite(low) and math.isfinite(high) and low < high):
                raise OutOfRangeError(f"workspace box {axis} from {low:g} to {high:g} m is not a range")

    def contains(self, point_m: Sequence[float] | FloatArray) -> bool:
        """True when ``point_m`` (x, y, z) lies inside the box (its faces included)."""
        x, y, z = (float(v) for v in point_m)
        return bool(
            self.x_m[0] <= x <= self.x_m[1] and self.y_m[0] <= y <= self.y_m[1] and self.z_m[0] <= z <= self.z_m[1]
        )

    def describe(self) -> str:
        """``x 0.100..0.900, y -0.550..0.550, z 0.005..0.650 m``."""
        return (
            f"x {self.x_m[0]:.3f}..{self.x_m[1]:.3f}, y {self.y_m[0]:.3f}..{self.y_m[1]:.3f}, "
            f"z {self.z_m[0]:.3f}..{self.z_m[1]:.3f} m"
        )

    def check_motion(self, motion: Motion, kinematics: ArmKinematics, what: str) -> None:
        """Raise ``WorkspaceStop`` naming ``what`` and the box when the motion's TCP path leaves the box.

        A line is straight in the world and the box convex: its two ends decide. A joint motion's TCP
        path curves: it is sampled every ``WORKSPACE_SAMPLE_PERIOD_S`` of the motion, both ends included.
        """
        for point in tcp_path_samples(motion, kinematics):
            if not self.contains(point):
                x, y, z = (float(v) for v in point)
                raise WorkspaceStop(
                    f"{what} would take the TCP to ({x:.3f}, {y:.3f}, {z:.3f}) m, outside the workspace box "
                    f"({self.describe()}): refused before it started"
                )


def tcp_path_samples(motion: Motion, kinematics: ArmKinematics) -> list[FloatArray]:
    """TCP positions along a planned motion: a line's two ends, a joint motion's every 20 ms of it."""
    from bt_arrange.motion.trajectory import JointMotion, LinearMotion

    if isinstance(motion, LinearMotion):
        return [motion.start_pose.position_m, motion.end_pose.position_m]
    if not isinstance(motion, JointMotion):
        raise TypeError(f"no path to sample of a {type(motion).__name__}")
    duration_s = motion.duration_s
    times = np.linspace(0.0, duration_s, max(1, math.ceil(duration_s / WORKSPACE_SAMPLE_PERIOD_S)) + 1)
    return [kinematics.forward(np.array(motion.trajectory.at_time(float(t))[0])).position_m for t in times]


@dataclass(frozen=True)
class MotionSafety:
    """What the motion planner applies to every motion: a speed fraction and, where the cell gives one, a box."""

    speed_fraction: float = 1.0
    workspace: WorkspaceBox | None = None

    def __post_init__(self) -> None:
        check_speed_fraction(self.speed_fraction)

    def joint_limits(self, limits: JointLimits) -> JointLimits:
        """``limits`` slowed to the speed fraction: velocity ``f``, acceleration ``f**2``, jerk ``f**3``."""
        f = self.speed_fraction
        if f == 1.0:
            return limits
        return replace(
            limits,
            velocity_rad_s=tuple(v * f for v in _six(limits.velocity_rad_s)),
            acceleration_rad_s2=tuple(a * f**2 for a in _six(limits.acceleration_rad_s2)),
            jerk_rad_s3=tuple(j * f**3 for j in _six(limits.jerk_rad_s3)),
        )

    def cartesian_limits(self, limits: CartesianLimits) -> CartesianLimits:
        """``limits`` slowed to the speed fraction (``CartesianLimits.time_scaled``)."""
        return limits if self.speed_fraction == 1.0 else limits.time_scaled(self.speed_fraction)

    def describe(self) -> str:
        """``speed fraction 0.5, workspace box x ...`` for a run's first line."""
        box = f"workspace box {self.workspace.describe()}" if self.workspace is not None else "no workspace box"
        return f"speed fraction {self.speed_fraction:g}, {box}"


def check_speed_fraction(value: float) -> float:
    """``value`` when it is a fraction of the full speed (0 < f <= 1); an ``OutOfRangeError`` otherwise."""
    if not (math.isfinite(value) and 0.0 < value <= 1.0):
        raise OutOfRangeError(f"speed fraction {value:g} must lie in (0, 1]: 1 is the full speed the motions plan for")
    return float(value)


def _six(values: float | tuple[float, ...]) -> tuple[float, ...]:
    return tuple(float(v) for v in np.broadcast_to(np.asarray(values, dtype=float), (6,)))
