"""What every behaviour of a tree shares: the robot, the planner, the detector, the settings.

A tree is set up with ``tree.setup(context=context)``: py_trees hands the keyword to every
behaviour's ``setup()``. Building a tree needs no context, so a tree can be drawn without a robot.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from bt_arrange.geometry import FloatArray
from bt_arrange.motion import DEFAULT_HOME_Q, ArmKinematics, CartesianLimits, JointLimits, Motion, MotionPlanner
from bt_arrange.motion.safety import MotionSafety
from bt_arrange.perception import PartDetector
from bt_arrange.robot import Arm, Robot
from bt_arrange.settings import ManipulationSettings


class ArmBrake:
    """Drives the motions no behaviour drives any more, one setpoint per control period.

    Two kinds:

    - an interrupted motion (``take``): a behaviour that is interrupted mid-motion
      (``terminate(INVALID)``) is not ticked again, so it hands its motion here, which finishes its
      jerk-limited stop. Behaviours wait for the brake to be idle (``active``) before they start a
      motion of their own.
    - a motion handed on at speed (``carry_on``): a stage that needs no stop at its waypoint ends
      while its motion still runs; the motion keeps going until the next motion stage takes it over
      from its state (``take_over``: position, velocity, acceleration), or, if the next stage needs
      the arm at rest, until it is braked (``brake_carried``). Unclaimed, it runs to its end.

    The runner calls ``step()`` once per control period, after the tick. A motion handed over
    during a tick already had its setpoint for this period: the brake leaves it until the next.
    """

    def __init__(self, arm: Arm) -> None:
        self._arm = arm
        self._motion: Motion | None = None
        self._carried: Motion | None = None
        self._commanded_this_period = False

    @property
    def active(self) -> bool:
        """True while a stopping motion still moves the arm."""
        return self._motion is not None

    @property
    def busy(self) -> bool:
        """True while the brake drives the arm: braking, or carrying a handed-on motion."""
        return self._motion is not None or self._carried is not None

    @property
    def carrying(self) -> bool:
        """True while a motion handed on at speed runs, waiting for the next motion to take it over."""
        return self._carried is not None

    def take(self, motion: Motion) -> None:
        """Start the jerk-limited stop of ``motion`` and drive it from now on."""
        if motion.done:
            return
        motion.stop()
        self._motion = motion

    def carry_on(self, motion: Motion) -> None:
        """Keep ``motion`` running past its stage (its setpoint for this period already sent)."""
        if motion.done:
            return
        motion.handed_on = True
        self._carried = motion
        self._commanded_this_period = True

    def take_over(self) -> tuple[FloatArray, FloatArray, FloatArray, bool]:
        """The carried motion's state for the next motion to start from, and whether it was commanded this period.

        The brake stops driving it. Only while ``carrying``.
        """
        assert self._carried is not None
        q, velocity, acceleration = self._carried.state()
        commanded = self._commanded_this_period
        self._carried = None
        self._commanded_this_period = False
        return q, velocity, acceleration, commanded

    def brake_carried(self) -> None:
        """The next stage needs the arm at rest: stop the carried motion (jerk-limited) instead."""
        if self._carried is not None:
            motion, self._carried = self._carried, None
            motion.handed_on = False
            self.take(motion)

    def step(self) -> None:
        """Hand the arm the next setpoint of the stopping or carried motion (nothing when idle)."""
        motion = self._motion or self._carried
        if motion is None:
            return
        if self._commanded_this_period:
            self._commanded_this_period = False
            return
        setpoint = motion.step()
        self._arm.command(setpoint.positions_rad, setpoint.velocities_rad_s)
        if motion.done:
            self._motion = None
            self._carried = None


@dataclass
class Context:
    """The robot and the tools the behaviours use to act on it."""

    robot: Robot
    planner: MotionPlanner
    detector: PartDetector = field(default_factory=PartDetector)
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
        detector: PartDetector | None = None,
        settings: ManipulationSettings | None = None,
        safety: MotionSafety | None = None,
    ) -> Context:
        """A context with the bundled UR5 kinematics and default limits at the arm's control period.

        ``safety`` (a speed fraction, a workspace box: ``bt_arrange.motion.safety``) applies to every motion.
        """
        planner = MotionPlanner(
            ArmKinematics(),
            joint_limits or JointLimits(),
            cartesian_limits or CartesianLimits(),
            robot.arm.control_period_s,
            safety=safety,
        )
        return cls(
            robot=robot,
            planner=planner,
            detector=detector or PartDetector(),
            settings=settings or ManipulationSettings(),
        )
