"""What every behaviour of a tree shares: the robot, the planner, the detector, the settings.

A tree is set up with ``tree.setup(context=context)``: py_trees hands the keyword to every
behaviour's ``setup()``. Building a tree needs no context, so a tree can be drawn without a robot.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from bt_arrange.geometry import FloatArray
from bt_arrange.motion import DEFAULT_HOME_Q, ArmKinematics, CartesianLimits, JointLimits, Motion, MotionPlanner
from bt_arrange.perception import CubeDetector
from bt_arrange.robot import Arm, Robot
from bt_arrange.settings import ManipulationSettings


class ArmBrake:
    """Finishes interrupted motions with their jerk-limited stop, one setpoint per control period.

    A behaviour that is interrupted mid-motion (``terminate(INVALID)``) is not ticked again, so it
    hands its motion here; the runner calls ``step()`` once per control period. Behaviours wait
    for the brake to be idle before they start a motion of their own.
    """

    def __init__(self, arm: Arm) -> None:
        self._arm = arm
        self._motion: Motion | None = None

    @property
    def active(self) -> bool:
        """True while a stopping motion still moves the arm."""
        return self._motion is not None

    def take(self, motion: Motion) -> None:
        """Start the jerk-limited stop of ``motion`` and drive it from now on."""
        if motion.done:
            return
        motion.stop()
        self._motion = motion

    def step(self) -> None:
        """Hand the arm the next braking setpoint (nothing when idle)."""
        if self._motion is None:
            return
        setpoint = self._motion.step()
        self._arm.command(setpoint.positions_rad, setpoint.velocities_rad_s)
        if self._motion.done:
            self._motion = None


@dataclass
class Context:
    """The robot and the tools the behaviours use to act on it."""

    robot: Robot
    planner: MotionPlanner
    detector: CubeDetector = field(default_factory=CubeDetector)
    settings: ManipulationSettings = field(default_factory=ManipulationSettings)
    #: Where the arm waits while the camera looks: out of the top camera's view.
    home_q: FloatArray = field(default_factory=lambda: DEFAULT_HOME_Q.copy())
    brake: ArmBrake = field(init=False)

    def __post_init__(self) -> None:
        self.brake = ArmBrake(self.robot.arm)
        self.home_q = np.asarray(self.home_q, dtype=float)

    @classmethod
    def create(
        cls,
        robot: Robot,
        *,
        joint_limits: JointLimits | None = None,
        cartesian_limits: CartesianLimits | None = None,
        detector: CubeDetector | None = None,
        settings: ManipulationSettings | None = None,
    ) -> Context:
        """A context with the bundled UR5 kinematics and default limits at the arm's control period."""
        planner = MotionPlanner(
            ArmKinematics(),
            joint_limits or JointLimits(),
            cartesian_limits or CartesianLimits(),
            robot.arm.control_period_s,
        )
        return cls(
            robot=robot,
            planner=planner,
            detector=detector or CubeDetector(),
            settings=settings or ManipulationSettings(),
        )
