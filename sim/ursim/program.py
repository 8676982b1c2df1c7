"""``rtde_control.script``'s register protocol, run natively: the program ``ur_rtde`` uploads, without URScript.

The uploaded program is a loop that reads a command from ``input_int_register_0`` (plus the
register offset: 0, or 24 with ``FLAG_UPPER_RANGE_REGISTERS``), its arguments from the input
double registers, and answers on ``output_int_register_0``: 1 ready, 2 done with the command. This
class is that loop, one iteration per control period (the script's ``sync()``):

- real-time commands (``servoj``, ``speedj``, the history and step-time queries...) are processed
  and answered ready at once, every period, without a handshake;
- any other command is processed once (the client keeps it in the register until it sees 2), and
  a blocking one (``movej``, ``movel``, ``stopj``...) answers 2 only when its motion has ended;
- 0 (the client's clear) answers ready; 255 ends the program.

``async`` moves (``input_int_register_1`` = 1) answer 2 at once and report their progress in
``output_int_register_2`` as the script's ``write_async_progress_register`` does.
"""

from __future__ import annotations

import sys
from typing import Any

import numpy as np

from bt_arrange_sim.ursim.kinematics import matrix_to_pose, pose_to_matrix
from bt_arrange_sim.ursim.motion import (
    JointPath,
    JointTrajectory,
    MoveError,
    Servo,
    Speed,
    Stop,
    line_samples,
)

READY = 1
DONE = 2

# The script's command numbers (rtde_control.script, RTDE::RobotCommand::Type).
NO_CMD = 0
MOVEJ = 1
MOVEJ_IK = 2
MOVEL = 3
MOVEL_FK = 4
SPEEDJ = 9
SPEEDL = 10
SERVOJ = 11
SPEED_STOP = 15
SERVO_STOP = 16
SET_PAYLOAD = 17
SERVOL = 24
GET_STEPTIME = 26
GET_ACTUAL_JOINT_POSITIONS_HISTORY = 27
GET_TARGET_WAYPOINT = 28
SET_TCP = 29
GET_INVERSE_KINEMATICS_ARGS = 30
PROTECTIVE_STOP = 31
STOPL = 33
STOPJ = 34
SET_WATCHDOG = 35
IS_POSE_WITHIN_SAFETY_LIMITS = 36
IS_JOINTS_WITHIN_SAFETY_LIMITS = 37
GET_JOINT_TORQUES = 38
POSE_TRANS = 39
GET_TCP_OFFSET = 40
GET_FORWARD_KINEMATICS_DEFAULT = 43
GET_FORWARD_KINEMATICS_ARGS = 44
GET_INVERSE_KINEMATICS_DEFAULT = 46
IS_STEADY = 47
GET_ACTUAL_TOOL_FLANGE_POSE = 58
GET_INVERSE_KINEMATICS_HAS_SOLUTION_DEFAULT = 60
GET_INVERSE_KINEMATICS_HAS_SOLUTION_ARGS = 61
STOP_SCRIPT = 255

#: Processed every period and answered ready at once (the script's main loop lists them).
REALTIME_COMMANDS = frozenset({SERVOL, SERVOJ, SPEEDJ, SPEEDL, 6, 25, GET_STEPTIME, 27, GET_JOINT_TORQUES, 58})
#: Commands the script has that this controller does not emulate: answered done, and said once on stderr.
NOT_EMULATED = {
    6: "force_mode",
    7: "force_mode_stop",
    8: "zero_ftsensor",
    10: "speedl",
    12: "servoc",
    18: "teach_mode",
    19: "end_teach_mode",
    20: "force_mode_set_damping",
    21: "force_mode_set_gain_scaling",
    25: "tool_contact",
    41: "jog_start",
    42: "jog_stop",
    45: "move_path",
    51: "move_until_contact",
    52: "freedrive_mode",
    53: "end_freedrive_mode",
    54: "get_freedrive_status",
    56: "ft_rtde_input_enable",
    57: "enable_external_ft_sensor",
    59: "set_gravity",
    62: "start_contact_detection",
    63: "stop_contact_detection",
    64: "read_contact_detection",
}


class ControlProgram:
    """One run of the uploaded ``rtde_control`` program (``register_offset`` 0 or 24).

    ``controller`` is the ``controller.Controller`` that runs it (not imported: it imports this module).
    """

    def __init__(self, controller: Any, register_offset: int) -> None:
        self.controller = controller
        self.offset = register_offset
        self.running = True
        self._executing = False
        #: The blocking command's motion has not ended yet: the loop waits (the script sits in ``movej``).
        self._blocked = False
        self._async_write_count = 0
        self._async_operation_id = 0
        self._warned: set[int] = set()
        self._servo: Servo | None = None
        self._speed: Speed | None = None
        #: The command register as the client last wrote it before this program started: a command
        #: left there by a program that died (a runtime error) is not this program's to run, and a
        #: loaded machine may start the program before the client's clear arrives.
        self._command_writes_at_start: int | None = controller.registers.int_write_count(register_offset)
        self._write_async_progress(-1)
        self._signal(READY)

    # -- registers --------------------------------------------------------------------------

    def _int(self, index: int) -> int:
        return self.controller.registers.read_int(index + self.offset)

    def _double(self, index: int) -> float:
        return self.controller.registers.read_double(index + self.offset)

    def _doubles(self, first: int, count: int = 6) -> list[float]:
        return self.controller.registers.read_doubles(first + self.offset, count)

    def _signal(self, value: int) -> None:
        self.controller.registers.write_int(0 + self.offset, value)

    def _write_int(self, index: int, value: int) -> None:
        self.controller.registers.write_int(index + self.offset, value)

    def _write_doubles(self, values: list[float]) -> None:
        self.controller.registers.write_doubles(0 + self.offset, values)

    def _write_async_progress(self, value: int) -> None:
        """The script's ``write_async_progress_register``: op id, write count, running bit and progress."""
        self._async_write_count = (self._async_write_count + 1) % 128
        if value == 0:
            self._async_operation_id = (self._async_operation_id + 1) % 128
        register = self._async_write_count * 65536 + self._async_operation_id * 16777216
        if value >= 0:
            register += min(value, 32767) + 32768
        self._write_int(2, register)

    # -- the loop ---------------------------------------------------------------------------

    def tick(self) -> None:
        """One iteration of the script's main loop (one control period)."""
        if not self.running or self._blocked:
            return
        command = self._int(0)
        if self._command_writes_at_start is not None:
            if self.controller.registers.int_write_count(self.offset) == self._command_writes_at_start:
                command = NO_CMD  # nothing written since the program started
            else:
                self._command_writes_at_start = None
        if command in REALTIME_COMMANDS:
            self._process(command)
            if self.running:  # a runtime error answers nothing: the client sees the program stopped
                self._signal(READY)
        elif command == NO_CMD:
            self._executing = False
            self._signal(READY)
        elif not self._executing:
            self._executing = True
            self._process(command)
            if command == STOP_SCRIPT:
                self.controller.stop_program("the client's stopScript")
            elif self.running and not self._blocked:
                self._signal(DONE)

    def _block_until_done(self) -> None:
        """The command's motion runs; its end answers done."""
        self._blocked = True

    def _motion_done(self) -> None:
        if self._blocked and self.running:
            self._blocked = False
            self._signal(DONE)

    def _async_done(self) -> None:
        if self.running:
            self._write_async_progress(-1)

    def _move(self, motion: object, asynchronous: bool) -> None:
        """Start a move: blocking, or async with its progress in ``output_int_register_2``."""
        generator = self.controller.motion
        self._servo = self._speed = None
        if asynchronous:
            generator.start(motion, self._async_done)  # type: ignore[arg-type]
            self._write_async_progress(0)  # after the replaced move's "finished"
        else:
            generator.start(motion, self._motion_done)  # type: ignore[arg-type]
            self._block_until_done()

    def _stop_motion(self, deceleration_rad_s2: float, asynchronous: bool = False) -> None:
        """Brake the arm to rest (stopj, stopl, servo_stop, speed_stop)."""
        self._move(Stop(deceleration_rad_s2, self.controller.period_s), asynchronous)

    def _process(self, command: int) -> None:  # noqa: C901 - one branch per command, as the script has
        controller = self.controller
        kinematics = controller.kinematics
        period_s = controller.period_s
        try:
            if command in (MOVEJ, MOVEJ_IK):
                values = self._doubles(0, 8)
                if command == MOVEJ_IK:
                    target = kinematics.inverse(values[:6], controller.tcp_offset, controller.actual_q)
                else:
                    target = np.array(values[:6])
                if not kinematics.within_limits(target):
                    raise MoveError(f"movej: target {np.round(target, 4).tolist()} is outside the joint limits")
                start = controller.motion.setpoint
                self._move(JointTrajectory(start, target, values[6], values[7], period_s), self._int(1) == 1)
            elif command in (MOVEL, MOVEL_FK):
                values = self._doubles(0, 8)
                pose = values[:6]
                if command == MOVEL_FK:
                    pose = kinematics.tcp_pose(np.array(values[:6]), controller.tcp_offset)
                samples = line_samples(
                    kinematics,
                    controller.motion.setpoint.positions_rad,
                    pose,
                    controller.tcp_offset,
                    values[6],
                    values[7],
                    period_s,
                )
                self._move(JointPath(samples, period_s), self._int(1) == 1)
            elif command in (SERVOJ, SERVOL):
                values = self._doubles(0, 6)
                target = (
                    np.array(values)
                    if command == SERVOJ
                    else kinematics.inverse(values, controller.tcp_offset, controller.actual_q)
                )
                if not kinematics.within_limits(target):
                    raise MoveError(f"servoj: target {np.round(target, 4).tolist()} is outside the joint limits")
                if self._servo is None or controller.motion.motion is not self._servo:
                    self._servo = Servo(controller.motion.setpoint.positions_rad, period_s)
                    self._speed = None
                    controller.motion.start(self._servo)
                self._servo.update(target)
            elif command == SPEEDJ:
                values = self._doubles(0, 8)
                if not np.all(np.isfinite(values)):
                    raise MoveError(f"speedj: {values} are not finite numbers")
                if self._speed is None or controller.motion.motion is not self._speed:
                    self._speed = Speed(np.array(values[:6]), values[6], period_s)
                    self._servo = None
                    controller.motion.start(self._speed)
                else:
                    self._speed.update(np.array(values[:6]), values[6])
            elif command in (SERVO_STOP, SPEED_STOP):
                # The script's stopl/stopj takes m/s^2 or rad/s^2: braked here as joints, at that figure.
                self._stop_motion(self._double(0))
            elif command in (STOPJ, STOPL):
                self._stop_motion(self._double(0), self._int(1) == 1)
            elif command == SET_TCP:
                controller.tcp_offset = self._doubles(0, 6)
            elif command == SET_PAYLOAD:
                mass, *cog = self._doubles(0, 4)
                controller.payload_kg = mass
                if any(cog):
                    controller.payload_cog_m = cog
            elif command == PROTECTIVE_STOP:
                controller.protective_stop("the program's protective_stop()")
            elif command == SET_WATCHDOG:
                controller.set_watchdog(self._double(0), self.offset)
            elif command == GET_STEPTIME:
                self._write_doubles([period_s])
            elif command == GET_ACTUAL_JOINT_POSITIONS_HISTORY:
                self._write_doubles(controller.joint_positions_back(self._int(1)))
            elif command == GET_JOINT_TORQUES:
                self._write_doubles(controller.joint_torques_n_m())
            elif command == GET_TARGET_WAYPOINT:
                self._write_doubles(
                    kinematics.tcp_pose(controller.motion.setpoint.positions_rad, controller.tcp_offset)
                )
            elif command == GET_TCP_OFFSET:
                self._write_doubles(list(controller.tcp_offset))
            elif command == GET_FORWARD_KINEMATICS_DEFAULT:
                self._write_doubles(kinematics.tcp_pose(controller.actual_q, controller.tcp_offset))
            elif command == GET_FORWARD_KINEMATICS_ARGS:
                values = self._doubles(0, 12)
                self._write_doubles(kinematics.tcp_pose(np.array(values[:6]), values[6:12]))
            elif command == GET_ACTUAL_TOOL_FLANGE_POSE:
                self._write_doubles(matrix_to_pose(kinematics.flange_matrix(controller.actual_q)))
            elif command in (GET_INVERSE_KINEMATICS_DEFAULT, GET_INVERSE_KINEMATICS_ARGS):
                values = self._doubles(0, 14)
                seed = controller.actual_q if command == GET_INVERSE_KINEMATICS_DEFAULT else np.array(values[6:12])
                self._write_doubles(kinematics.inverse(values[:6], controller.tcp_offset, seed).tolist())
            elif command in (GET_INVERSE_KINEMATICS_HAS_SOLUTION_DEFAULT, GET_INVERSE_KINEMATICS_HAS_SOLUTION_ARGS):
                values = self._doubles(0, 14)
                seed = controller.actual_q if command == GET_INVERSE_KINEMATICS_HAS_SOLUTION_DEFAULT else values[6:12]
                try:
                    kinematics.inverse(values[:6], controller.tcp_offset, np.array(seed))
                    self._write_int(1, 1)
                except Exception:  # noqa: BLE001 - no solution is the answer 0
                    self._write_int(1, 0)
            elif command == POSE_TRANS:
                values = self._doubles(0, 12)
                self._write_doubles(matrix_to_pose(pose_to_matrix(values[:6]) @ pose_to_matrix(values[6:12])))
            elif command == IS_JOINTS_WITHIN_SAFETY_LIMITS:
                self._write_int(1, int(kinematics.within_limits(np.array(self._doubles(0, 6)))))
            elif command == IS_POSE_WITHIN_SAFETY_LIMITS:
                self._write_int(1, 1)
            elif command == IS_STEADY:
                self._write_int(1, int(controller.is_steady()))
            elif command in NOT_EMULATED and command not in self._warned:
                self._warned.add(command)
                print(f"ursim: {NOT_EMULATED[command]} (command {command}) is not emulated: ignored", file=sys.stderr)
        except MoveError as error:
            controller.program_error(str(error))
        except Exception as error:  # noqa: BLE001 - a failed IK etc. ends the program, as a script error does
            controller.program_error(f"command {command}: {type(error).__name__}: {error}")

    def end(self) -> None:
        """The program stops (its end, a stop, a fault): nothing more is processed."""
        self.running = False
        self._blocked = False
