"""The controller's motion generator: one joint setpoint per control period, as the UR's does at 125 Hz.

Each kind of motion the URScript functions make is one small class with ``step()`` returning the
next setpoint (positions and velocities, rad and rad/s) and whether it is done: ``movej`` a ruckig
trajectory under the command's speed and acceleration, ``movel`` a straight TCP path solved at
every control period before the arm moves, ``servoj`` the client's latest target itself,
``speedj`` a joint velocity reached under an acceleration, ``stopj``/``stopl`` a braking ramp. The
generator hands each setpoint to the cell's arm, whose position motors track it, exactly as the
simulated backend's behaviours feed it (``SimArm.command``).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from ruckig import InputParameter, OutputParameter, Result, Ruckig

from bt_arrange_sim.ursim.kinematics import UrKinematics, matrix_to_pose, pose_to_matrix

#: The jerk of every joint trajectory (rad/s^3): high, so that ``movej``'s profile is nearly the
#: trapezoid (constant acceleration) of a real controller's while staying smooth for the motors.
MOVE_JERK_RAD_S3 = 400.0
#: A blocking ``movej``/``movel`` is done once its trajectory has ended and every joint is this close
#: to the target (rad), or after ``SETTLE_LIMIT_S`` of settling.
SETTLED_RAD = 2e-4
SETTLE_LIMIT_S = 1.0
#: The UR5's joint speed limit (rad/s): the most a servo target's rate is fed forward.
MAX_JOINT_SPEED_RAD_S = 3.15
#: Joints slower than this (rad/s) are at rest (``is_steady``, the end of a stop).
STEADY_RAD_S = 1e-3


class MoveError(Exception):
    """A motion the controller cannot make (no IK solution, a joint limit): the program stops with it."""


class Setpoint:
    """One control period's joint positions and velocities."""

    __slots__ = ("positions_rad", "velocities_rad_s")

    def __init__(self, positions_rad: np.ndarray, velocities_rad_s: np.ndarray) -> None:
        self.positions_rad = positions_rad
        self.velocities_rad_s = velocities_rad_s


class Motion:
    """A motion: ``step()`` gives the next setpoint; ``done`` once it has given its last."""

    done = False

    def step(self, current: Setpoint, measured_q: np.ndarray) -> Setpoint:
        """The setpoint after ``current`` (the last one commanded)."""
        raise NotImplementedError


class Hold(Motion):
    """Stay at one joint vector."""

    done = True

    def __init__(self, positions_rad: np.ndarray) -> None:
        self._setpoint = Setpoint(np.array(positions_rad, dtype=float), np.zeros(6))

    def step(self, current: Setpoint, measured_q: np.ndarray) -> Setpoint:
        """The held joint vector, at rest."""
        return self._setpoint


class JointTrajectory(Motion):
    """``movej``: all joints from the current setpoint to ``target_rad``, arriving together (ruckig)."""

    def __init__(
        self, start: Setpoint, target_rad: np.ndarray, speed_rad_s: float, acceleration_rad_s2: float, period_s: float
    ) -> None:
        self.target_rad = np.array(target_rad, dtype=float)
        self._otg = Ruckig(6, period_s)
        self._input = InputParameter(6)
        self._output = OutputParameter(6)
        inp = self._input
        inp.current_position = start.positions_rad.tolist()
        inp.current_velocity = start.velocities_rad_s.tolist()
        inp.current_acceleration = [0.0] * 6
        inp.target_position = self.target_rad.tolist()
        inp.target_velocity = [0.0] * 6
        inp.target_acceleration = [0.0] * 6
        # A zero speed or acceleration (which the client lets through) would never arrive: a floor.
        inp.max_velocity = [max(speed_rad_s, 1e-3)] * 6
        inp.max_acceleration = [max(acceleration_rad_s2, 1e-3)] * 6
        inp.max_jerk = [MOVE_JERK_RAD_S3] * 6

    def step(self, current: Setpoint, measured_q: np.ndarray) -> Setpoint:
        """Ruckig's next state (the classic update, then pass the output to the input)."""
        if self.done:
            return Setpoint(self.target_rad, np.zeros(6))
        result = self._otg.update(self._input, self._output)
        if result not in (Result.Working, Result.Finished):
            raise MoveError(f"movej: the trajectory generator failed ({result})")
        self._output.pass_to_input(self._input)
        if result == Result.Finished:
            self.done = True
            return Setpoint(self.target_rad, np.zeros(6))
        return Setpoint(np.array(self._output.new_position), np.array(self._output.new_velocity))


class JointPath(Motion):
    """``movel``: joint vectors solved beforehand for every control period of a straight TCP line."""

    def __init__(self, samples_rad: list[np.ndarray], period_s: float) -> None:
        self.target_rad = samples_rad[-1]
        self._samples = samples_rad
        self._period_s = period_s
        self._index = 0

    def step(self, current: Setpoint, measured_q: np.ndarray) -> Setpoint:
        """The next sample, its velocity the difference to the one after it."""
        if self._index >= len(self._samples) - 1:
            self.done = True
            return Setpoint(self.target_rad, np.zeros(6))
        self._index += 1
        here = self._samples[self._index]
        after = self._samples[min(self._index + 1, len(self._samples) - 1)]
        return Setpoint(here, (after - here) / self._period_s)


def line_samples(
    kinematics: UrKinematics,
    start_q: np.ndarray,
    target_pose: list[float],
    tcp_offset: list[float],
    speed_m_s: float,
    acceleration_m_s2: float,
    period_s: float,
) -> list[np.ndarray]:
    """The joint vectors of a straight TCP line to ``target_pose``, one per control period.

    Position moves along the line and orientation turns about one axis (slerp), both by the same
    fraction of the way; the fraction follows a trapezoidal speed profile of ``speed_m_s`` and
    ``acceleration_m_s2`` over the line's length (for a turn in place, over the angle as if it were
    metres, as UR's ``movel`` takes the speed of a pure rotation in rad/s). Each sample is solved
    from the one before. Raises ``MoveError`` when a point has no solution.
    """
    from scipy.spatial.transform import Rotation, Slerp

    start = pose_to_matrix(kinematics.tcp_pose(start_q, tcp_offset))
    end = pose_to_matrix(target_pose)
    length_m = float(np.linalg.norm(end[:3, 3] - start[:3, 3]))
    angle_rad = float(Rotation.from_matrix(start[:3, :3].T @ end[:3, :3]).magnitude())
    distance = length_m if length_m > 1e-6 else angle_rad
    times = trapezoid_fractions(distance, max(speed_m_s, 1e-4), max(acceleration_m_s2, 1e-4), period_s)
    slerp = Slerp([0.0, 1.0], Rotation.from_matrix([start[:3, :3], end[:3, :3]]))
    samples = [np.array(start_q, dtype=float)]
    q = samples[0]
    for fraction in times[1:]:
        matrix = np.eye(4)
        matrix[:3, :3] = slerp(fraction).as_matrix()
        matrix[:3, 3] = start[:3, 3] + fraction * (end[:3, 3] - start[:3, 3])
        try:
            q = kinematics.inverse(matrix_to_pose(matrix), tcp_offset, q)
        except Exception as error:  # noqa: BLE001 - any IK failure stops the program, as on a real controller
            raise MoveError(f"movel: inverse kinematics failed at {fraction:.0%} of the line: {error}") from error
        if np.max(np.abs(q - samples[-1])) > 0.5:
            raise MoveError("movel: the line passes a singularity (a joint would jump)")
        samples.append(q)
    return samples


def trapezoid_fractions(distance: float, speed: float, acceleration: float, period_s: float) -> list[float]:
    """Fractions (0 to 1) of ``distance`` covered at each control period under a trapezoidal speed profile."""
    if distance <= 1e-9:
        return [0.0, 1.0]
    ramp_s = speed / acceleration
    if acceleration * ramp_s**2 >= distance:  # a triangle: the top speed is never reached
        ramp_s = math.sqrt(distance / acceleration)
        speed = acceleration * ramp_s
        cruise_s = 0.0
    else:
        cruise_s = (distance - acceleration * ramp_s**2) / speed
    total_s = 2 * ramp_s + cruise_s
    steps = max(1, math.ceil(total_s / period_s))
    fractions = []
    for i in range(steps + 1):
        t = min(i * period_s, total_s)
        if t < ramp_s:
            s = 0.5 * acceleration * t**2
        elif t < ramp_s + cruise_s:
            s = 0.5 * acceleration * ramp_s**2 + speed * (t - ramp_s)
        else:
            left = total_s - t
            s = distance - 0.5 * acceleration * left**2
        fractions.append(min(1.0, s / distance))
    fractions[-1] = 1.0
    return fractions


class Servo(Motion):
    """``servoj``: track the client's latest joint target, one setpoint per control period.

    The velocity feed-forward is the targets' own rate (their last change over the time it took),
    dropped once the client has sent no new target for ``STALE_PERIODS``: the arm then holds it.
    """

    STALE_PERIODS = 3

    def __init__(self, target_rad: np.ndarray, period_s: float) -> None:
        self._period_s = period_s
        self._target = np.array(target_rad, dtype=float)
        self._rate = np.zeros(6)
        self._periods_since_update = 0

    def update(self, target_rad: np.ndarray) -> None:
        """The client's target (the program reads it every period: only a changed one is news)."""
        target = np.array(target_rad, dtype=float)
        if np.array_equal(target, self._target):
            return
        elapsed_s = max(1, self._periods_since_update) * self._period_s
        # A jump (the first target far from the arm, two targets in one period) is no speed to feed
        # forward: the rate is held to the UR5's joint speed limit.
        self._rate = np.clip((target - self._target) / elapsed_s, -MAX_JOINT_SPEED_RAD_S, MAX_JOINT_SPEED_RAD_S)
        self._target = target
        self._periods_since_update = 0

    def step(self, current: Setpoint, measured_q: np.ndarray) -> Setpoint:
        """The latest target, with its rate while it is fresh."""
        self._periods_since_update += 1
        stale = self._periods_since_update > self.STALE_PERIODS
        return Setpoint(self._target.copy(), np.zeros(6) if stale else self._rate.copy())


class Speed(Motion):
    """``speedj``: reach the joint velocity ``target_rad_s`` under ``acceleration_rad_s2`` and keep it."""

    def __init__(self, target_rad_s: np.ndarray, acceleration_rad_s2: float, period_s: float) -> None:
        self._period_s = period_s
        self.update(target_rad_s, acceleration_rad_s2)

    def update(self, target_rad_s: np.ndarray, acceleration_rad_s2: float) -> None:
        """A new target velocity from the client."""
        self._target = np.array(target_rad_s, dtype=float)
        self._acceleration = max(acceleration_rad_s2, 1e-3)

    def step(self, current: Setpoint, measured_q: np.ndarray) -> Setpoint:
        """One period of acceleration towards the target velocity (all joints scaled together)."""
        velocity = ramp_towards(current.velocities_rad_s, self._target, self._acceleration * self._period_s)
        return Setpoint(current.positions_rad + velocity * self._period_s, velocity)


class Stop(Motion):
    """``stopj``/``stopl``: brake every joint to rest under ``deceleration_rad_s2``."""

    def __init__(self, deceleration_rad_s2: float, period_s: float) -> None:
        self._period_s = period_s
        self._deceleration = max(deceleration_rad_s2, 1e-3)

    def step(self, current: Setpoint, measured_q: np.ndarray) -> Setpoint:
        """One period of braking."""
        velocity = ramp_towards(current.velocities_rad_s, np.zeros(6), self._deceleration * self._period_s)
        if not np.any(velocity):
            self.done = True
        return Setpoint(current.positions_rad + velocity * self._period_s, velocity)


def ramp_towards(velocity: np.ndarray, target: np.ndarray, step: float) -> np.ndarray:
    """``velocity`` moved towards ``target`` by at most ``step`` (the largest joint's change), on a line."""
    change = target - velocity
    largest = float(np.max(np.abs(change)))
    if largest <= step:
        return target.copy()
    return velocity + change * (step / largest)


class MotionGenerator:
    """The arm's one active motion, stepped once per control period; ``hold`` when none runs.

    ``on_done`` of a motion is called once, in the period it ends (a ``movej`` once it has
    settled at its target), for the program's handshake.
    """

    def __init__(self, period_s: float, initial_q: np.ndarray) -> None:
        self.period_s = period_s
        self.setpoint = Setpoint(np.array(initial_q, dtype=float), np.zeros(6))
        self.previous_velocities = np.zeros(6)
        self.motion: Motion = Hold(initial_q)
        self._on_done: Callable[[], None] | None = None
        self._settle_s = 0.0

    def start(self, motion: Motion, on_done: Callable[[], None] | None = None) -> None:
        """Replace the active motion by ``motion`` (which starts from the last setpoint).

        The replaced motion's ``on_done`` is called first: an async move cut short reports itself
        finished, as the script's ``stop_async_move`` does for the thread it kills.
        """
        replaced, self._on_done = self._on_done, None
        if replaced is not None:
            replaced()
        self.motion = motion
        self._on_done = on_done
        self._settle_s = 0.0

    def halt(self, measured_q: np.ndarray) -> None:
        """Stop at once where the arm is (a protective or emergency stop): no ramp, nothing pending."""
        self.setpoint = Setpoint(np.array(measured_q, dtype=float), np.zeros(6))
        self.motion = Hold(measured_q)
        self._on_done = None

    @property
    def moving(self) -> bool:
        """True while a motion other than holding still runs."""
        return not isinstance(self.motion, Hold)

    def step(self, measured_q: np.ndarray) -> Setpoint:
        """The setpoint of the coming control period."""
        motion = self.motion
        self.previous_velocities = self.setpoint.velocities_rad_s
        self.setpoint = motion.step(self.setpoint, measured_q)
        if motion.done and not isinstance(motion, Hold):
            target = getattr(motion, "target_rad", None)
            settled = target is None or float(np.max(np.abs(measured_q - target))) < SETTLED_RAD
            self._settle_s += 0.0 if settled else self.period_s
            if settled or self._settle_s >= SETTLE_LIMIT_S:
                self.motion = Hold(self.setpoint.positions_rad)
                on_done, self._on_done = self._on_done, None
                if on_done is not None:
                    on_done()
        return self.setpoint
