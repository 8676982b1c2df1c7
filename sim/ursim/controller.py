"""The controller: the work cell stepped at the CB3's 125 Hz in real time, its program, safety and state.

One thread (``run``) owns the pybullet cell: every pybullet call, rendering included, happens on
it (pybullet is not thread-safe). Each control period (8 ms of world time, paced to 8 ms of wall
time) it runs what other threads handed it (``call``), one iteration of the uploaded program, one
step of the motion generator (a setpoint for the arm's position motors), the gripper, the armed
faults, and one ``WorkCell.step``; then it publishes a ``Snapshot`` of the state that the RTDE and
the gripper's threads read. When a render makes it fall behind, it catches up without sleeping.

The safety state is a real controller's: a protective stop or an emergency stop halts the arm at
once and stops the program (``runtime_state`` leaves 2, the output registers keep what they
held), and the RTDE fields say so (``safety_status_bits``, ``safety_mode``, ``robot_mode``).
"""

from __future__ import annotations

import collections
import queue
import sys
import threading
import time
from collections.abc import Callable
from concurrent.futures import Future
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from bt_arrange_sim.ursim.kinematics import UrKinematics
from bt_arrange_sim.ursim.motion import STEADY_RAD_S, MotionGenerator
from bt_arrange_sim.ursim.program import ControlProgram
from bt_arrange_sim.ursim.registers import RegisterBank
from bt_arrange_sim.ursim.robotiq import RobotiqGripper

# RTDE ``robot_mode`` values (and the dashboard's names of them).
ROBOT_MODE_POWER_OFF = 3
ROBOT_MODE_IDLE = 5
ROBOT_MODE_RUNNING = 7
ROBOT_MODE_NAMES = {3: "POWER_OFF", 4: "POWER_ON", 5: "IDLE", 7: "RUNNING"}
# RTDE ``safety_mode`` values.
SAFETY_MODE_NORMAL = 1
SAFETY_MODE_PROTECTIVE_STOP = 3
SAFETY_MODE_ROBOT_EMERGENCY_STOP = 7
SAFETY_MODE_NAMES = {1: "NORMAL", 3: "PROTECTIVE_STOP", 7: "ROBOT_EMERGENCY_STOP"}
# ``safety_status_bits``: normal mode, protective stopped, robot e-stopped, e-stopped, stopped due to safety.
SAFETY_BIT_NORMAL = 1 << 0
SAFETY_BIT_PROTECTIVE = 1 << 2
SAFETY_BIT_ROBOT_EMERGENCY = 1 << 6
SAFETY_BIT_EMERGENCY = 1 << 7
SAFETY_BIT_STOPPED_BY_SAFETY = 1 << 10
# ``robot_status_bits``: power on, program running.
ROBOT_BIT_POWER_ON = 1 << 0
ROBOT_BIT_PROGRAM_RUNNING = 1 << 1
# ``runtime_state``.
RUNTIME_STOPPED = 1
RUNTIME_PLAYING = 2
# ``joint_mode`` of every joint: running, idle (powered, brakes on), power off.
JOINT_MODE_RUNNING = 253
JOINT_MODE_IDLE = 255
JOINT_MODE_POWER_OFF = 239
#: A protective stop may be unlocked this long after it happened (s), as Polyscope enforces.
PROTECTIVE_STOP_UNLOCK_DELAY_S = 5.0
#: The longest the clock catches up after falling behind (s of wall time); beyond it the backlog is dropped.
MAX_CATCH_UP_S = 1.0
#: How many control periods of joint positions are kept (``get_actual_joint_positions_history``).
HISTORY_PERIODS = 1000


@dataclass
class Snapshot:
    """The controller's state after one control period: what every RTDE client and the gripper socket read."""

    time_s: float = 0.0
    actual_q: list[float] = field(default_factory=lambda: [0.0] * 6)
    actual_qd: list[float] = field(default_factory=lambda: [0.0] * 6)
    target_q: list[float] = field(default_factory=lambda: [0.0] * 6)
    target_qd: list[float] = field(default_factory=lambda: [0.0] * 6)
    target_qdd: list[float] = field(default_factory=lambda: [0.0] * 6)
    actual_tcp_pose: list[float] = field(default_factory=lambda: [0.0] * 6)
    actual_tcp_speed: list[float] = field(default_factory=lambda: [0.0] * 6)
    target_tcp_pose: list[float] = field(default_factory=lambda: [0.0] * 6)
    elbow_position: list[float] = field(default_factory=lambda: [0.0] * 3)
    robot_mode: int = ROBOT_MODE_RUNNING
    safety_mode: int = SAFETY_MODE_NORMAL
    safety_status_bits: int = SAFETY_BIT_NORMAL
    robot_status_bits: int = ROBOT_BIT_POWER_ON
    runtime_state: int = RUNTIME_STOPPED
    joint_mode: list[int] = field(default_factory=lambda: [JOINT_MODE_RUNNING] * 6)
    speed_scaling: float = 1.0
    tcp_offset: list[float] = field(default_factory=lambda: [0.0] * 6)
    payload_kg: float = 0.0
    payload_cog_m: list[float] = field(default_factory=lambda: [0.0] * 3)
    input_int: list[int] = field(default_factory=lambda: [0] * 48)
    input_double: list[float] = field(default_factory=lambda: [0.0] * 48)
    input_bits: int = 0
    output_int: list[int] = field(default_factory=lambda: [0] * 48)
    output_double: list[float] = field(default_factory=lambda: [0.0] * 48)
    output_bits: int = 0
    period_index: int = 0


class Controller:
    """The UR5's controller on one ``WorkCell``; ``run()`` is the physics thread's loop."""

    def __init__(self, cell: Any, realtime_factor: float = 1.0) -> None:
        self.cell = cell
        self.period_s: float = cell.config.physics.control_period_s
        self.realtime_factor = realtime_factor
        self.kinematics = UrKinematics()
        self.registers = RegisterBank()
        self.actual_q = np.asarray(cell.arm.joint_positions(), dtype=float)
        self.actual_qd = np.zeros(6)
        self.motion = MotionGenerator(self.period_s, self.actual_q)
        self.gripper = RobotiqGripper(cell.gripper, self.period_s)
        self.tcp_offset: list[float] = [0.0] * 6
        self.payload_kg = 0.0
        self.payload_cog_m: list[float] = [0.0] * 3
        self.program: ControlProgram | None = None
        self.robot_mode = ROBOT_MODE_RUNNING
        self.safety_mode = SAFETY_MODE_NORMAL
        self.protective_stop_time_s: float | None = None
        self.protective_stop_on_contact = False
        self._watchdog: tuple[float, int, int, float] | None = None  # (min Hz, register, last count, last time)
        self._history: collections.deque[np.ndarray] = collections.deque(maxlen=HISTORY_PERIODS)
        self._requests: queue.Queue[tuple[Callable[[], Any], Future]] = queue.Queue()
        self._stop = threading.Event()
        self._snapshot_ready = threading.Condition()
        self.snapshot = Snapshot()
        self._period_index = 0
        self._previous_tcp: list[float] | None = None
        self._wall_start_s: float | None = None
        self._world_start_s = 0.0
        self._wall_last_s: float | None = None
        self._publish()

    # -- other threads' access ------------------------------------------------------------------

    def call(self, function: Callable[[], Any], timeout_s: float = 30.0) -> Any:
        """Run ``function`` on the physics thread (between two periods) and return its result."""
        future: Future = Future()
        self._requests.put((function, future))
        return future.result(timeout=timeout_s)

    def submit(self, function: Callable[[], Any]) -> None:
        """Run ``function`` on the physics thread, without waiting for it."""
        self._requests.put((function, Future()))

    def wait_for_period(self, after_index: int, timeout_s: float = 1.0) -> Snapshot:
        """The first snapshot of a period after ``after_index`` (blocks until the physics publishes it)."""
        with self._snapshot_ready:
            self._snapshot_ready.wait_for(lambda: self.snapshot.period_index > after_index, timeout=timeout_s)
            return self.snapshot

    def stop(self) -> None:
        """End ``run`` after the current period."""
        self._stop.set()

    @property
    def stopped(self) -> bool:
        """True once ``stop`` was called."""
        return self._stop.is_set()

    def realtime_ratio(self) -> float:
        """World time over wall time since the loop started (1.0: real time)."""
        if self._wall_start_s is None or self._wall_last_s is None:
            return 0.0
        # The wall time includes the period under way: the first one is stepped at once, at wall time 0.
        wall_s = self._wall_last_s - self._wall_start_s + self.period_s / self.realtime_factor
        return (self.cell.sim_time_s - self._world_start_s) / wall_s

    # -- the physics thread ----------------------------------------------------------------------

    def run(self) -> None:
        """Step the cell one control period per ``period_s / realtime_factor`` of wall time until ``stop``."""
        wall_period_s = self.period_s / self.realtime_factor
        self._wall_start_s = time.monotonic()
        self._world_start_s = self.cell.sim_time_s
        next_s = self._wall_start_s
        while not self._stop.is_set():
            self._serve_requests()
            self._period()
            self._wall_last_s = time.monotonic()
            next_s += wall_period_s
            behind_s = self._wall_last_s - next_s
            if behind_s > MAX_CATCH_UP_S:
                next_s = self._wall_last_s  # a long stall (a debugger, a swapped machine): resume from now
            elif behind_s < 0:
                self._stop.wait(-behind_s)
        self._serve_requests()

    def _serve_requests(self) -> None:
        while True:
            try:
                function, future = self._requests.get_nowait()
            except queue.Empty:
                return
            if not future.set_running_or_notify_cancel():
                continue
            try:
                future.set_result(function())
            except BaseException as error:  # noqa: BLE001 - the caller gets the error; the loop goes on
                future.set_exception(error)

    def _period(self) -> None:
        """One control period: program, faults, motion, gripper, physics, snapshot."""
        if self.program is not None and self.program.running:
            self._check_watchdog()
            self.program.tick()
        if self.protective_stop_on_contact and self.motion.moving and self._fingers_touch_a_part():
            self.protective_stop_on_contact = False
            self.protective_stop("a finger touched a part while the arm moved (armed by the faults port)")
        try:
            setpoint = self.motion.step(self.actual_q)
            self.cell.arm.command(setpoint.positions_rad, setpoint.velocities_rad_s)
        except Exception as error:  # noqa: BLE001 - a motion that fails stops the program, never the controller
            self.program_error(f"motion: {type(error).__name__}: {error}")
            self.motion.halt(self.actual_q)
            self.cell.arm.command(self.motion.setpoint.positions_rad, self.motion.setpoint.velocities_rad_s)
        self.gripper.tick()
        self.cell.step()
        previous_q = self.actual_q
        self.actual_q = np.asarray(self.cell.arm.joint_positions(), dtype=float)
        # The encoders' rate over the period: pybullet's own joint velocity is the last physics step's,
        # which under position motors fed once a period swings around the mean (half of it at 0.2 rad/s).
        self.actual_qd = (self.actual_q - previous_q) / self.period_s
        self._history.append(self.actual_q.copy())
        self._publish()

    def _publish(self) -> None:
        kinematics = self.kinematics
        setpoint = self.motion.setpoint
        tcp = kinematics.tcp_pose(self.actual_q, self.tcp_offset)
        speed = [0.0] * 6
        if self._previous_tcp is not None:
            speed[:3] = [(a - b) / self.period_s for a, b in zip(tcp[:3], self._previous_tcp[:3], strict=True)]
        self._previous_tcp = tcp
        input_int, input_double, input_bits, output_int, output_double, output_bits = self.registers.copy()
        program_running = self.program is not None and self.program.running
        powered = self.robot_mode != ROBOT_MODE_POWER_OFF
        joint_mode = (
            JOINT_MODE_RUNNING
            if self.robot_mode == ROBOT_MODE_RUNNING
            else (JOINT_MODE_IDLE if powered else JOINT_MODE_POWER_OFF)
        )
        snapshot = Snapshot(
            time_s=self.cell.sim_time_s,
            actual_q=self.actual_q.tolist(),
            actual_qd=self.actual_qd.tolist(),
            target_q=setpoint.positions_rad.tolist(),
            target_qd=setpoint.velocities_rad_s.tolist(),
            target_qdd=((setpoint.velocities_rad_s - self.motion.previous_velocities) / self.period_s).tolist(),
            actual_tcp_pose=tcp,
            actual_tcp_speed=speed,
            target_tcp_pose=kinematics.tcp_pose(setpoint.positions_rad, self.tcp_offset),
            elbow_position=kinematics.elbow_position_m(self.actual_q),
            robot_mode=self.robot_mode,
            safety_mode=self.safety_mode,
            safety_status_bits=self.safety_status_bits(),
            robot_status_bits=(ROBOT_BIT_POWER_ON if powered else 0)
            | (ROBOT_BIT_PROGRAM_RUNNING if program_running else 0),
            runtime_state=RUNTIME_PLAYING if program_running else RUNTIME_STOPPED,
            joint_mode=[joint_mode] * 6,
            speed_scaling=1.0 if self.safety_mode == SAFETY_MODE_NORMAL and powered else 0.0,
            tcp_offset=list(self.tcp_offset),
            payload_kg=self.payload_kg,
            payload_cog_m=list(self.payload_cog_m),
            input_int=input_int,
            input_double=input_double,
            input_bits=input_bits,
            output_int=output_int,
            output_double=output_double,
            output_bits=output_bits,
            period_index=self._period_index,
        )
        with self._snapshot_ready:
            self.snapshot = snapshot
            self._period_index += 1
            self._snapshot_ready.notify_all()

    # -- program ---------------------------------------------------------------------------------

    def start_program(self, register_offset: int) -> bool:
        """Start the uploaded ``rtde_control`` program; False (and why on stderr) when the robot cannot run it."""
        if self.safety_mode != SAFETY_MODE_NORMAL or self.robot_mode != ROBOT_MODE_RUNNING:
            mode = SAFETY_MODE_NAMES.get(self.safety_mode, str(self.safety_mode))
            robot = ROBOT_MODE_NAMES.get(self.robot_mode, str(self.robot_mode))
            print(f"ursim: program not started: safety mode {mode}, robot mode {robot}", file=sys.stderr)
            return False
        if self.program is not None and self.program.running:
            self.stop_program("a new program was uploaded")
        self._watchdog = None
        self.program = ControlProgram(self, register_offset)
        print(f"ursim: rtde_control program started (register offset {register_offset})", file=sys.stderr)
        return True

    def stop_program(self, reason: str) -> None:
        """The program ends: its motion brakes, the arm holds, ``runtime_state`` is stopped."""
        if self.program is None or not self.program.running:
            return
        self.program.end()
        self._watchdog = None
        if self.motion.moving:
            from bt_arrange_sim.ursim.motion import Stop

            self.motion.start(Stop(10.0, self.period_s))
        print(f"ursim: program stopped: {reason}", file=sys.stderr)

    def program_error(self, message: str) -> None:
        """A runtime error in the program (no IK solution...): it stops, as a script error stops a real one."""
        self.stop_program(f"runtime error: {message}")

    def set_watchdog(self, min_frequency_hz: float, register_offset: int) -> None:
        """The program's ``rtde_set_watchdog`` on the command register, action ``stop``."""
        if min_frequency_hz <= 0:
            self._watchdog = None
            return
        register = register_offset
        self._watchdog = (min_frequency_hz, register, self.registers.int_write_count(register), self.cell.sim_time_s)

    def _check_watchdog(self) -> None:
        if self._watchdog is None:
            return
        frequency, register, last_count, last_time = self._watchdog
        count = self.registers.int_write_count(register)
        now = self.cell.sim_time_s
        if count != last_count:
            self._watchdog = (frequency, register, count, now)
        elif now - last_time > 1.0 / frequency:
            self.stop_program(f"RTDE watchdog: input_int_register_{register} not written for {now - last_time:.3f} s")

    # -- safety ------------------------------------------------------------------------------------

    def safety_status_bits(self) -> int:
        """``safety_status_bits`` of the current safety mode."""
        if self.safety_mode == SAFETY_MODE_PROTECTIVE_STOP:
            return SAFETY_BIT_PROTECTIVE | SAFETY_BIT_STOPPED_BY_SAFETY
        if self.safety_mode == SAFETY_MODE_ROBOT_EMERGENCY_STOP:
            return SAFETY_BIT_ROBOT_EMERGENCY | SAFETY_BIT_EMERGENCY | SAFETY_BIT_STOPPED_BY_SAFETY
        return SAFETY_BIT_NORMAL

    def protective_stop(self, reason: str) -> None:
        """Halt the arm at once and stop the program; ``unlock protective stop`` (after 5 s) or ``clear`` ends it."""
        if self.safety_mode == SAFETY_MODE_ROBOT_EMERGENCY_STOP:
            return
        self.motion.halt(self.actual_q)
        self.safety_mode = SAFETY_MODE_PROTECTIVE_STOP
        self.protective_stop_time_s = self.cell.sim_time_s
        print(f"ursim: protective stop: {reason}", file=sys.stderr)
        self.stop_program("protective stop")

    def emergency_stop(self) -> None:
        """Halt the arm at once, cut the power (arm and gripper), stop the program."""
        self.motion.halt(self.actual_q)
        self.safety_mode = SAFETY_MODE_ROBOT_EMERGENCY_STOP
        self.robot_mode = ROBOT_MODE_POWER_OFF
        self.gripper.emergency_stop(True)
        print("ursim: emergency stop", file=sys.stderr)
        self.stop_program("emergency stop")

    def unlock_protective_stop(self) -> str:
        """The dashboard's ``unlock protective stop``: its reply."""
        if self.safety_mode != SAFETY_MODE_PROTECTIVE_STOP:
            return "Protective stop releasing"
        assert self.protective_stop_time_s is not None
        if self.cell.sim_time_s - self.protective_stop_time_s < PROTECTIVE_STOP_UNLOCK_DELAY_S:
            return (
                "Cannot unlock protective stop until 5s after occurrence. "
                "Always inspect cause of protective stop before unlocking"
            )
        self.safety_mode = SAFETY_MODE_NORMAL
        return "Protective stop releasing"

    def clear_faults(self) -> None:
        """The faults port's ``clear``: stops released, the arm powered and running (the program stays stopped)."""
        self.protective_stop_on_contact = False
        self.safety_mode = SAFETY_MODE_NORMAL
        self.robot_mode = ROBOT_MODE_RUNNING
        self.gripper.emergency_stop(False)
        self.motion.halt(self.actual_q)

    def _fingers_touch_a_part(self) -> bool:
        cell = self.cell
        client = cell.client
        for body in cell.parts.values():
            for finger in cell.finger_joint_indices:
                if client.getContactPoints(cell.robot_id, body, linkIndexA=finger):
                    return True
        return False

    # -- state for the program -------------------------------------------------------------------

    def is_steady(self) -> bool:
        """True when no motion runs and every joint is at rest."""
        return not self.motion.moving and bool(np.all(np.abs(self.snapshot.actual_qd) < STEADY_RAD_S))

    def joint_positions_back(self, periods: int) -> list[float]:
        """The joint positions ``periods`` control periods ago (the newest when fewer are kept)."""
        if not self._history:
            return self.actual_q.tolist()
        index = max(0, len(self._history) - 1 - max(0, periods))
        return self._history[index].tolist()

    def joint_torques_n_m(self) -> list[float]:
        """The torques the arm's motors apply now (pybullet's applied motor torques)."""
        states = self.cell.client.getJointStates(self.cell.robot_id, list(self.cell.arm_joint_indices))
        return [float(s[3]) for s in states]

    def set_power(self, on: bool) -> None:
        """The dashboard's ``power on``/``power off``: idle (brakes on) or off; the program stops when off."""
        if self.safety_mode == SAFETY_MODE_ROBOT_EMERGENCY_STOP:
            return
        if on:
            if self.robot_mode == ROBOT_MODE_POWER_OFF:
                self.robot_mode = ROBOT_MODE_IDLE
        else:
            self.motion.halt(self.actual_q)
            self.robot_mode = ROBOT_MODE_POWER_OFF
            self.stop_program("power off")

    def release_brakes(self) -> None:
        """The dashboard's ``brake release``: a powered arm runs."""
        if self.robot_mode == ROBOT_MODE_IDLE and self.safety_mode != SAFETY_MODE_ROBOT_EMERGENCY_STOP:
            self.robot_mode = ROBOT_MODE_RUNNING

    def part_truth(self) -> dict[str, list[float]]:
        """Every part's true pose: name to ``[x_m, y_m, z_m, yaw_rad]`` (evaluation only)."""
        truth = {}
        for name in self.cell.parts:
            pose = self.cell.part_pose_truth(name)
            truth[name] = [float(pose.x_m), float(pose.y_m), float(pose.z_m), float(pose.yaw_rad)]
        return truth
