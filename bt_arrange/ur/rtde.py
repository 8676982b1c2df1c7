"""The UR5 through ur_rtde: the controller's connection, its safety state, and the arm as a ``bt_arrange.robot.Arm``.

``RTDEReceiveInterface`` reads the measured joints, the controller's timestamp and its safety state;
``RTDEControlInterface`` uploads ur_rtde's control script and servos the arm. The ``Arm`` protocol is
one joint setpoint per control period: ``UrArm.command(q, qd)`` is ``servoJ(q, 0, 0, period,
lookahead, gain)``, and the world's ``step()`` ends the period with ``waitPeriod`` and starts the next
with ``initPeriod`` (ur_rtde's own pacing of a servo loop).

``servoJ``'s lookahead and gain: the setpoints are already jerk-limited (ruckig), so the controller's
own smoothing is not needed: the shortest lookahead (0.03 s) and the highest gain (2000) make the arm
follow each setpoint within the period, as the simulator's position motors do.
"""

from __future__ import annotations

import contextlib
import time
from typing import Any

import numpy as np

from bt_arrange.errors import BackendError
from bt_arrange.geometry import FloatArray, Pose
from bt_arrange.motion import ARM_JOINT_NAMES
from bt_arrange.motion.safety import SafetyStop
from bt_arrange.ranges import checked_joint_setpoint

#: The control period (s): the CB3's RTDE rate, 125 Hz (an e-Series runs its servo loop at it too).
CONTROL_PERIOD_S = 0.008
RTDE_FREQUENCY_HZ = 1.0 / CONTROL_PERIOD_S
#: servoJ's lookahead (s, ur_rtde allows 0.03 to 0.2) and gain (100 to 2000): the stiffest tracking.
SERVO_LOOKAHEAD_S = 0.03
SERVO_GAIN = 2000.0
#: A program found stopped is looked at this many periods more for the stop that halted it.
STOP_REPORT_PERIODS = 3
#: Deceleration of a stop (rad/s^2): servoStop's (ur_rtde's default is 10).
STOP_DECELERATION_RAD_S2 = 4.0


class RobotLinkError(BackendError):
    """The robot's controller cannot be reached (a wrong address, no RTDE, the control script refused)."""


def connect_receive(host: str) -> Any:
    """``RTDEReceiveInterface(host)``: read-only (a dry run opens only this); a one-line error when unreachable."""
    try:
        import rtde_receive
    except ImportError as error:
        raise RobotLinkError("the ur backend needs ur-rtde: pip install 'bt-arrange[ur]'") from error
    try:
        return rtde_receive.RTDEReceiveInterface(host, RTDE_FREQUENCY_HZ)
    except RuntimeError as error:
        raise RobotLinkError(f"cannot reach the robot's controller at {host} (RTDE, port 30004): {error}") from error


def connect_control(host: str) -> Any:
    """``RTDEControlInterface(host)``: uploads ur_rtde's control script; a one-line error when that fails."""
    import rtde_control

    try:
        return rtde_control.RTDEControlInterface(host, RTDE_FREQUENCY_HZ)
    except RuntimeError as error:
        raise RobotLinkError(
            f"cannot take control of the robot at {host} (dashboard 29999, RTDE 30004, script 30003): {error}"
        ) from error


def fault_reason(host: str, receive: Any, control: Any | None) -> str:
    """Why the robot can no longer be commanded ("" when it can): the stops a lab's run must end on.

    In the order a person would want to hear them: an emergency stop, a protective stop, a connection
    lost, a program that stopped (which the other three also cause).
    """
    try:
        if not receive.isConnected():
            return f"lost the RTDE connection to the robot at {host}"
        stop = _safety_stop(receive)
        if stop:
            return stop
        if control is not None:
            if not control.isConnected():
                return f"lost the control connection to the robot at {host}"
            if not control.isProgramRunning():
                # A stop halts the program too, and the two interfaces receive their packages on their
                # own threads: the control's may tell first (``explained`` waits for the cause).
                return "the robot's control program stopped (it no longer runs ur_rtde's control script)"
    except RuntimeError as error:
        return f"lost the connection to the robot at {host} ({error})"
    return ""


def explained(reason: str, receive: Any) -> str:
    """``reason``, or the emergency or protective stop behind it if the receive interface reports one soon.

    A person needs to hear the cause: a stop halts the program and makes the gripper read ``?`` too,
    and those may be seen a period or two before the receive interface's package says why.
    """
    for attempt in range(STOP_REPORT_PERIODS + 1):
        try:
            stop = _safety_stop(receive) if receive is not None and receive.isConnected() else ""
        except RuntimeError:
            return reason
        if stop:
            return stop
        if attempt < STOP_REPORT_PERIODS:
            time.sleep(CONTROL_PERIOD_S)
    return reason


def _safety_stop(receive: Any) -> str:
    """An emergency or a protective stop, as the receive interface reports it ("" for neither)."""
    if receive.isEmergencyStopped():
        return "the robot is in an emergency stop"
    if receive.isProtectiveStopped():
        return "the robot is in a protective stop (a collision or a safety limit)"
    return ""


class ControllerClock:
    """World time of a real cell: the controller's RTDE timestamp (s), read once per control period."""

    def __init__(self, receive: Any) -> None:
        self._receive = receive
        self._now_s = float(receive.getTimestamp())

    def now(self) -> float:
        """The controller's time at the last period's start (s since it booted)."""
        return self._now_s

    def refresh(self) -> None:
        """Read the controller's timestamp (the world calls it once per period)."""
        self._now_s = float(self._receive.getTimestamp())

    def release(self) -> None:
        """Drop the receive interface (the world closes it); the clock keeps its last reading."""
        self._receive = None


class UrJointState:
    """What every UR5 ``Arm`` of this backend shares: its joints, its period, and the joint state it holds.

    The state is ``_q`` (rad) and ``_qd`` (rad/s), measured or a dry run's setpoint; its TCP comes from
    the framework's kinematics.
    """

    def __init__(self, q_rad: FloatArray, qd_rad_s: FloatArray) -> None:
        self._q = np.asarray(q_rad, dtype=float).copy()
        self._qd = np.asarray(qd_rad_s, dtype=float).copy()
        self._kinematics: Any = None

    @property
    def joint_names(self) -> tuple[str, ...]:
        """The UR5's joints, base to wrist 3."""
        return ARM_JOINT_NAMES

    @property
    def control_period_s(self) -> float:
        """One RTDE period (a dry run's shadow plans as the real arm would)."""
        return CONTROL_PERIOD_S

    def joint_positions(self) -> FloatArray:
        """The joint positions held (rad): measured at the period's start, or a shadow's last setpoint."""
        return self._q.copy()

    def joint_velocities(self) -> FloatArray:
        """The joint speeds held (rad/s)."""
        return self._qd.copy()

    def tcp_pose(self) -> Pose:
        """The TCP (between the fingertips) of the joints held, by the framework's kinematics."""
        if self._kinematics is None:
            from bt_arrange.motion import ArmKinematics

            self._kinematics = ArmKinematics()
        return self._kinematics.forward(self._q)


class UrArm(UrJointState):
    """The UR5 servoed through ``RTDEControlInterface.servoJ``, measured through ``RTDEReceiveInterface``.

    Readings are cached per control period (``refresh``): a tick sees one consistent state. Once the
    world has found a fault (``halt``), every command raises the ``SafetyStop`` again: nothing moves.
    """

    def __init__(self, host: str, receive: Any, control: Any) -> None:
        self._host = host
        self._receive = receive
        self._control = control
        super().__init__(np.zeros(len(ARM_JOINT_NAMES)), np.zeros(len(ARM_JOINT_NAMES)))
        self._halted: str = ""
        self.refresh()

    def refresh(self) -> None:
        """Read the measured joints and their speeds (once per period)."""
        self._q = np.array(self._receive.getActualQ(), dtype=float)
        self._qd = np.array(self._receive.getActualQd(), dtype=float)

    def command(self, positions_rad: FloatArray, velocities_rad_s: FloatArray | None = None) -> None:
        """Servo to ``positions_rad`` within this period (``servoJ``); the velocities are the plan's, not sent."""
        checked_joint_setpoint(positions_rad, velocities_rad_s)
        if self._halted:
            raise SafetyStop(self._halted)
        q = [float(v) for v in positions_rad]
        try:
            accepted = self._control.servoJ(q, 0.0, 0.0, CONTROL_PERIOD_S, SERVO_LOOKAHEAD_S, SERVO_GAIN)
        except RuntimeError as error:
            raise SafetyStop(f"lost the control connection to the robot at {self._host} ({error})") from error
        if accepted is False:
            reason = fault_reason(self._host, self._receive, self._control)
            raise SafetyStop(reason or f"the robot at {self._host} refused servoJ")

    def release(self) -> None:
        """Drop the interfaces (the world closes them): every later command raises the ``SafetyStop``."""
        self._halted = self._halted or "the robot's interfaces were closed"
        self._control = self._receive = None

    def halt(self, reason: str) -> None:
        """No command goes to the robot from now on; a servo in progress is stopped where the link allows."""
        self._halted = reason
        stop_servo(self._control)


def stop_servo(control: Any) -> None:
    """``servoStop``: the arm decelerates to rest; a link already gone is left alone.

    (The arm is only ever moved by servoing, so servoStop is the stop; ``stopJ`` would stop a ``moveJ``.)
    """
    if control is None:
        return
    with contextlib.suppress(RuntimeError):
        control.servoStop(STOP_DECELERATION_RAD_S2)
