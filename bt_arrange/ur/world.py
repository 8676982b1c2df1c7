"""A real UR5 cell as a ``bt_arrange.world.World``, and its dry-run shadow.

``UrWorld`` is the robot itself: its arm (``rtde.UrArm``), its gripper (``robotiq.RobotiqGripper``), its
camera (``camera``) and the controller's clock. ``step()`` ends one control period (``waitPeriod``),
starts the next (``initPeriod``), reads the robot once, and checks it: an emergency stop, a protective
stop, a program that stopped, a connection lost or a gripper fault raises ``SafetyStop`` with a one-line
reason, which ends the tree (``bt_arrange.runner``) with nothing sent afterwards. It has no ground truth
(``truth`` is None: the report is camera only) and places nothing: real parts lie where they lie.

``DryRunWorld`` ticks the same tree against a kinematic shadow of the arm and the gripper that starts
from the robot's measured joints, with the real camera for looks and a clock of its own; it opens only
the receive interface, so no motion command can reach the robot.
"""

from __future__ import annotations

import contextlib
from collections.abc import Sequence
from typing import Any

import numpy as np

from bt_arrange.geometry import FloatArray
from bt_arrange.motion import ARM_JOINT_NAMES
from bt_arrange.motion.safety import SafetyStop
from bt_arrange.perception import ColourTable
from bt_arrange.ranges import (
    checked_grip_force_n,
    checked_gripper_speed_m_s,
    checked_gripper_width_m,
    checked_joint_setpoint,
)
from bt_arrange.robot import GRIPPER_MAX_WIDTH_M, CameraFrame, Robot
from bt_arrange.ur.rtde import (
    CONTROL_PERIOD_S,
    ControllerClock,
    RobotLinkError,
    UrArm,
    UrJointState,
    explained,
    fault_reason,
    stop_servo,
)

#: The gripper's fault code is read every this many periods (a third round trip per period is not needed).
GRIPPER_FAULT_PERIODS = 25


class UrWorld:
    """The real cell: ur_rtde's two interfaces, the Robotiq socket and a camera, behind the ``World`` protocol."""

    truth = None
    #: No measured camera error to add to the threshold until the cell's camera is characterised.
    camera_margin_mm = None

    def __init__(self, host: str, receive: Any, control: Any, gripper: Any, camera: Any) -> None:
        self.host = host
        self._receive = receive
        self._control = control
        self.arm = UrArm(host, receive, control)
        self.gripper = gripper
        self.camera = camera
        self._clock = ControllerClock(receive)
        self._robot = Robot(self.arm, gripper, camera, self._clock)
        self._periods = 0
        self._stopped = ""
        self._period_start = control.initPeriod()
        try:
            self._check()
        except SafetyStop as stop:
            # Before the tree starts this is a setup error (one line, exit 2), not a stop of a run.
            self.close()
            raise RobotLinkError(f"the robot at {host} cannot be commanded: {stop.reason}") from None

    @property
    def robot(self) -> Robot:
        """The arm, gripper, camera and the controller's clock."""
        return self._robot

    @property
    def clock(self) -> ControllerClock:
        """The controller's timestamp."""
        return self._clock

    def place(self, starts: Sequence[Any], colours: ColourTable) -> None:
        """Nothing to place: the real parts lie where they lie (the tree's Detect finds them)."""

    def settle(self, seconds: float) -> None:
        """Nothing to wait for: real parts already rest (the robot was read and checked when the world opened)."""

    def step(self) -> None:
        """End this control period, start the next, read the robot and check that it may still be commanded."""
        if self._stopped:
            raise SafetyStop(self._stopped)
        try:
            self._control.waitPeriod(self._period_start)
            self._period_start = self._control.initPeriod()
        except RuntimeError as error:
            self._stop(f"lost the control connection to the robot at {self.host} ({error})")
        self._periods += 1
        self._check()

    def _check(self) -> None:
        reason = fault_reason(self.host, self._receive, self._control)
        if reason:
            self._stop(reason)
        try:
            self._clock.refresh()
            self.arm.refresh()
            self.gripper.refresh()
            if self._periods % GRIPPER_FAULT_PERIODS == 0:
                code = self.gripper.fault()
                if code:
                    self._stop(f"the gripper reports fault FLT {code}")
        except RuntimeError as error:
            self._stop(f"lost the connection to the robot at {self.host} ({error})")
        except SafetyStop:
            raise
        except Exception as error:  # the gripper's socket (GripperLinkError) and anything below it
            self._stop(f"{error}")

    def _stop(self, reason: str) -> None:
        """Latch the stop, stop the servo where the link allows, and end the tree.

        The gripper's socket (its values read ``?``) or the control script may tell of a stop before
        the receive interface's next package does: a few periods more are given to it, so the line
        names the cause (an emergency or a protective stop), not its echo.
        """
        reason = explained(reason, self._receive)
        self._stopped = reason
        self.arm.halt(reason)
        raise SafetyStop(reason)

    def capture_image(self) -> CameraFrame:
        """A frame of the top camera (the recorded images)."""
        return self.camera.capture()

    def close(self) -> None:
        """Stop the arm (servoStop) and the control script, and let go of every link; safe after any fault."""
        if self._control is None:
            return
        # Only a running program is told to stop (ur_rtde complains on stderr to a stopped one).
        with contextlib.suppress(RuntimeError):
            if self._control.isConnected() and self._control.isProgramRunning():
                stop_servo(self._control)
                self._control.stopScript()
        for disconnect in (self._control.disconnect, self._receive.disconnect):
            with contextlib.suppress(RuntimeError):
                disconnect()
        # The interfaces go now, while nothing else talks to the controller: left to the garbage
        # collector, ur_rtde's objects were destroyed in the middle of the next run's connection, and
        # that crashed the process (one run in about ten, several runs in one process).
        self._control = self._receive = None
        self.arm.release()
        self._clock.release()
        with contextlib.suppress(Exception):
            self.gripper.close_link()
        with contextlib.suppress(Exception):
            getattr(self.camera, "close", lambda: None)()


class ShadowArm(UrJointState):
    """A kinematic arm for a dry run: it is where it was last commanded, starting at the robot's measured joints."""

    def __init__(self, start_q: FloatArray) -> None:
        super().__init__(start_q, np.zeros(len(ARM_JOINT_NAMES)))

    def command(self, positions_rad: FloatArray, velocities_rad_s: FloatArray | None = None) -> None:
        """Be at the setpoint (range-checked as the real arm's are); nothing is sent anywhere."""
        checked_joint_setpoint(positions_rad, velocities_rad_s)
        self._q = np.asarray(positions_rad, dtype=float).copy()
        zero = np.zeros(len(ARM_JOINT_NAMES))
        self._qd = zero if velocities_rad_s is None else np.asarray(velocities_rad_s, dtype=float).copy()


class ShadowGripper:
    """A kinematic gripper for a dry run: the fingers travel at the commanded speed; a close stops at ``held_width_m``.

    There is no part between the shadow's pads: a dry run assumes each grasp takes, at the width of the
    plan's part (``held_width_m``), so the tree goes on to plan the carry and the place.
    """

    def __init__(self, start_width_m: float, held_width_m: float, default_speed_m_s: float = 0.15) -> None:
        self._width_m = start_width_m
        self._target_m = start_width_m
        self._speed_m_s = default_speed_m_s
        self._default_speed_m_s = default_speed_m_s
        self.held_width_m = held_width_m

    @property
    def max_width_m(self) -> float:
        """The 2F-85's stroke."""
        return GRIPPER_MAX_WIDTH_M

    def open(self, width_m: float, speed_m_s: float | None = None) -> None:
        """Start opening to ``width_m``."""
        self._target_m = checked_gripper_width_m(width_m)
        self._speed_m_s = checked_gripper_speed_m_s(speed_m_s or self._default_speed_m_s)

    def close(self, force_n: float, speed_m_s: float | None = None) -> None:
        """Start closing onto the assumed part."""
        checked_grip_force_n(force_n)
        self._target_m = min(self.held_width_m, self._width_m)
        self._speed_m_s = checked_gripper_speed_m_s(speed_m_s or self._default_speed_m_s)

    def width(self) -> float:
        """The shadow's opening."""
        return self._width_m

    def is_moving(self) -> bool:
        """True until the fingers reach their target."""
        return abs(self._width_m - self._target_m) > 1e-9

    def step(self, period_s: float) -> None:
        """Travel one period's worth towards the target."""
        travel = self._speed_m_s * period_s
        delta = self._target_m - self._width_m
        self._width_m = self._target_m if abs(delta) <= travel else self._width_m + np.sign(delta) * travel


class ShadowClock:
    """A dry run's world time: it starts at the controller's and advances one period per step, never waiting."""

    def __init__(self, start_s: float) -> None:
        self._now_s = start_s

    def now(self) -> float:
        """Seconds."""
        return self._now_s

    def advance(self, seconds: float) -> None:
        """Let ``seconds`` pass."""
        self._now_s += seconds


class DryRunWorld:
    """The tree ticked against a shadow of the robot: only the receive interface and the camera are opened."""

    truth = None
    camera_margin_mm = None

    def __init__(self, host: str, receive: Any, camera: Any, start_width_m: float, held_width_m: float) -> None:
        self.host = host
        self._receive = receive
        #: The joints the robot stood at when the dry run began (every motion is planned from them).
        self.start_q = np.array(receive.getActualQ(), dtype=float)
        self.arm = ShadowArm(self.start_q)
        self.gripper = ShadowGripper(start_width_m, held_width_m)
        self.camera = camera
        self._clock = ShadowClock(float(receive.getTimestamp()))
        self._robot = Robot(self.arm, self.gripper, camera, self._clock)

    @property
    def robot(self) -> Robot:
        """The shadow arm and gripper, the real camera, the shadow clock."""
        return self._robot

    @property
    def clock(self) -> ShadowClock:
        """The shadow clock."""
        return self._clock

    def place(self, starts: Sequence[Any], colours: ColourTable) -> None:
        """Nothing to place."""

    def settle(self, seconds: float) -> None:
        """Nothing settles in a shadow."""

    def step(self) -> None:
        """One period of the shadow (no waiting)."""
        self._clock.advance(CONTROL_PERIOD_S)
        self.gripper.step(CONTROL_PERIOD_S)

    def capture_image(self) -> CameraFrame:
        """A frame of the real camera."""
        return self.camera.capture()

    def close(self) -> None:
        """Let go of the receive interface and the camera."""
        if self._receive is None:
            return
        with contextlib.suppress(RuntimeError):
            self._receive.disconnect()
        self._receive = None
        with contextlib.suppress(Exception):
            getattr(self.camera, "close", lambda: None)()
