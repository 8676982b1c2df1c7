"""Motions a behaviour advances one control period at a time: joint-space moves and straight TCP lines.

A ``Motion`` is planned completely in its constructor, so every error (a target out of reach or
outside the joint limits, bad limits) raises there, before a single setpoint goes to the arm.
Afterwards each ``step()`` hands out the setpoint for the next control period, ``done`` says when
the last one was handed out, and ``stop()`` turns the rest of the motion into a jerk-limited stop
(ruckig's velocity interface with a zero target velocity), after which ``done`` means at rest.

Time inside a motion is counted in control periods, never read from a clock: the motion plays the
same at any simulation speed.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod

import numpy as np
from numpy.typing import ArrayLike
from ruckig import (
    ControlInterface,
    DurationDiscretization,
    InputParameter,
    OutputParameter,
    Result,
    Ruckig,
    RuckigError,
    Synchronization,
    Trajectory,
)

from bt_arrange.errors import MotionError, PlanError, UnreachableError
from bt_arrange.geometry import FloatArray, Pose
from bt_arrange.motion.kinematics import ArmKinematics, joint_vector, rotation_angle_rad
from bt_arrange.motion.limits import CartesianLimits, JointLimits
from bt_arrange.motion.setpoints import JointSetpoint, check_control_period
from bt_arrange.motion.urdf import ARM_JOINT_NAMES

#: A line's target orientation may differ this much from the start's (the line keeps the start's).
DEFAULT_LINE_ORIENTATION_TOLERANCE_RAD = 0.02
#: A line that would need to run more than this many times slower than its Cartesian limits to
#: respect the joint limits passes too close to a singularity, and is refused.
MAX_LINE_SLOWDOWN = 10.0
# Replanning a line aims this much below the joint limits, because finite differences of a
# stretched trajectory are not exactly the stretched finite differences.
_SLOWDOWN_MARGIN = 1.02
_LINE_REPLANS = 4
# Lines shorter than this are treated as "already there".
_MIN_LINE_LENGTH_M = 1e-9
#: Longest stretch of a line between two IK solutions (m), before any refinement.
LINE_KNOT_SPACING_M = 0.04
#: Largest TCP distance from the line (m) that interpolating the joints between IK knots may add,
#: checked at each interval's midpoint: the IK's own position tolerance.
LINE_DEVIATION_TOLERANCE_M = 1e-6
#: Largest turn away from the line's orientation (rad) that the interpolation may add.
LINE_ORIENTATION_DEVIATION_TOLERANCE_RAD = 2e-6
# Knots closer than this are not split again (the joints curve so sharply there, near a
# singularity, that interpolation cannot follow; the slowdown check refuses such a line anyway).
_MIN_KNOT_SPACING_M = 1e-4

_RUCKIG_OK = (Result.Working, Result.Finished)


def _per_joint_list(values: float | tuple[float, ...]) -> list[float]:
    """A ``JointLimits`` field (six values after validation) as the list ruckig wants."""
    return [float(v) for v in np.broadcast_to(np.asarray(values, dtype=float), (len(ARM_JOINT_NAMES),))]


class Motion(ABC):
    """One planned motion, advanced by ``step()`` once per control period.

    Typical use in a behaviour: plan it in ``initialise()``, and in ``update()``::

        setpoint = motion.step()
        arm.command(setpoint.positions_rad, setpoint.velocities_rad_s)
        return Status.SUCCESS if motion.done else Status.RUNNING

    and call ``motion.stop()`` (then keep stepping until ``done``) to halt it early.
    """

    def __init__(self, control_period_s: float) -> None:
        self._control_period_s = check_control_period(control_period_s)
        self._done = False
        self._stopping = False
        self._steps = 0
        self._last: JointSetpoint | None = None
        #: True once the motion was handed on to the next one before its end, without stopping
        #: (``ArmBrake.carry_on``): its waypoint was passed at speed.
        self.handed_on = False

    @property
    def control_period_s(self) -> float:
        """Seconds between two setpoints."""
        return self._control_period_s

    @property
    @abstractmethod
    def duration_s(self) -> float:
        """Planned duration in seconds, from the start state to the target (after a stop: when at rest)."""

    @property
    @abstractmethod
    def target_positions_rad(self) -> FloatArray:
        """Joint vector at the end of the plan (unless stopped)."""

    @property
    def done(self) -> bool:
        """True once the last setpoint was handed out: at the target, or at rest after ``stop()``."""
        return self._done

    @property
    def stopping(self) -> bool:
        """True once ``stop()`` was called."""
        return self._stopping

    @property
    def elapsed_s(self) -> float:
        """Time of the last setpoint handed out, since the motion started."""
        return self._steps * self._control_period_s

    def step(self) -> JointSetpoint:
        """Setpoint for the next control period; once ``done``, the final setpoint at zero velocity."""
        if self._done:
            assert self._last is not None
            return JointSetpoint(self._last.positions_rad.copy(), np.zeros(len(ARM_JOINT_NAMES)))
        setpoint, finished = self._advance()
        self._steps += 1
        self._last = setpoint
        self._done = finished
        return setpoint

    def state(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Positions, velocities and accelerations of the last setpoint handed out (the start state before any).

        What the next motion starts from when this one is handed on at speed.
        """
        return self._state()

    @abstractmethod
    def _state(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """The last setpoint's positions, velocities and accelerations."""

    def stop(self) -> None:
        """Bring the motion to rest as fast as the limits allow (jerk-limited); idempotent.

        Keep calling ``step()``: the setpoints decelerate, and ``done`` turns true at rest.
        """
        if self._done or self._stopping:
            return
        self._stopping = True
        self._begin_stop()

    @abstractmethod
    def _advance(self) -> tuple[JointSetpoint, bool]:
        """Compute the next setpoint and whether it is the last."""

    @abstractmethod
    def _begin_stop(self) -> None:
        """Switch the trajectory generator to a stop from the current state."""


class JointMotion(Motion):
    """A jerk-limited joint-space motion from a start state to a target joint vector (ruckig, 6 DoF).

    The joints are phase-synchronised: for a start at rest the path is a straight line in joint
    space and every joint arrives at the same time. The duration is a whole number of control
    periods, so the last setpoint is exactly the target, at rest.

    Raises ``UnreachableError`` when the target (or, for a moving start, the path) leaves the joint
    position limits, and ``MotionError`` when ruckig rejects the input.
    """

    def __init__(
        self,
        start_positions_rad: ArrayLike,
        target_positions_rad: ArrayLike,
        limits: JointLimits,
        control_period_s: float,
        start_velocities_rad_s: ArrayLike | None = None,
        start_accelerations_rad_s2: ArrayLike | None = None,
    ) -> None:
        """Plan the motion; ``start_*`` is the measured state (velocities and accelerations default to rest)."""
        super().__init__(control_period_s)
        start = joint_vector(start_positions_rad)
        target = joint_vector(target_positions_rad)
        limits.check_positions(target, "joint target")
        self._limits = limits
        self._target = target
        dofs = len(ARM_JOINT_NAMES)
        zeros = np.zeros(dofs)
        velocity = zeros if start_velocities_rad_s is None else joint_vector(start_velocities_rad_s)
        acceleration = zeros if start_accelerations_rad_s2 is None else joint_vector(start_accelerations_rad_s2)

        self._otg = Ruckig(dofs, self._control_period_s)
        self._input = InputParameter(dofs)
        self._output = OutputParameter(dofs)
        inp = self._input
        inp.current_position = start.tolist()
        inp.current_velocity = velocity.tolist()
        inp.current_acceleration = acceleration.tolist()
        inp.target_position = target.tolist()
        inp.target_velocity = zeros.tolist()
        inp.target_acceleration = zeros.tolist()
        inp.max_velocity = _per_joint_list(limits.velocity_rad_s)
        inp.max_acceleration = _per_joint_list(limits.acceleration_rad_s2)
        inp.max_jerk = _per_joint_list(limits.jerk_rad_s3)
        inp.synchronization = Synchronization.Phase
        inp.duration_discretization = DurationDiscretization.Discrete

        trajectory = Trajectory(dofs)
        try:
            result = self._otg.calculate(inp, trajectory)
        except RuckigError as error:
            raise MotionError(f"joint motion to {np.round(target, 4)} rad rejected by ruckig: {error}") from error
        if result not in _RUCKIG_OK:
            raise MotionError(f"joint motion to {np.round(target, 4)} rad could not be planned: ruckig {result}")
        self._duration_s = float(trajectory.duration)
        #: The planned trajectory (ruckig's), e.g. to check where it goes before it starts (``motion.safety``).
        self.trajectory = trajectory
        # A start that already moves can overshoot on its way to the target: check the whole path.
        for name, bound, lower, upper in zip(
            ARM_JOINT_NAMES, trajectory.position_extrema, limits.lower_rad, limits.upper_rad, strict=True
        ):
            if bound.min < lower - 1e-9 or bound.max > upper + 1e-9:
                raise UnreachableError(
                    f"joint motion: {name} would pass through [{bound.min:.4f}, {bound.max:.4f}] rad, outside the "
                    f"joint limits [{lower:.4f}, {upper:.4f}] rad"
                )

    @property
    def duration_s(self) -> float:
        """Planned duration in seconds (a whole number of control periods)."""
        return self._duration_s

    @property
    def target_positions_rad(self) -> FloatArray:
        """The target joint vector."""
        return self._target.copy()

    def _state(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """The ruckig input's current state: after ``pass_to_input`` that is the last setpoint."""
        inp = self._input
        return (
            np.array(inp.current_position, dtype=float),
            np.array(inp.current_velocity, dtype=float),
            np.array(inp.current_acceleration, dtype=float),
        )

    def _advance(self) -> tuple[JointSetpoint, bool]:
        """One ruckig update: the classic ``update()`` then ``pass_to_input()`` control cycle."""
        try:
            result = self._otg.update(self._input, self._output)
        except RuckigError as error:
            raise MotionError(f"joint motion failed at t = {self.elapsed_s:.3f} s: {error}") from error
        if result not in _RUCKIG_OK:
            raise MotionError(f"joint motion failed at t = {self.elapsed_s:.3f} s: ruckig {result}")
        self._output.pass_to_input(self._input)
        setpoint = JointSetpoint(np.array(self._output.new_position), np.array(self._output.new_velocity))
        return setpoint, result == Result.Finished

    def _begin_stop(self) -> None:
        """Velocity interface, zero target velocity and acceleration: ruckig brakes under the same limits."""
        zeros = [0.0] * len(ARM_JOINT_NAMES)
        self._input.control_interface = ControlInterface.Velocity
        self._input.target_velocity = zeros
        self._input.target_acceleration = zeros


class LinearMotion(Motion):
    """A straight TCP line from the TCP pose at ``start_positions_rad`` to ``target.position_m``.

    Orientation: the line keeps the start orientation from the first setpoint to the last. The
    target's orientation only has to agree with it within ``orientation_tolerance_rad`` (a
    ``PlanError`` otherwise): a line never turns the gripper, so a target that asks for a turn is
    a mistake, while the start (a measured joint state) always differs a little from the intent.

    Path: IK is solved at knots along the line (at most ``LINE_KNOT_SPACING_M`` apart, each
    warm-started from the previous one on its branch), and the joints between two knots follow the
    cubic Hermite curve through both knots' joints and joint rates (``dq/ds``, from the Jacobian).
    Where the TCP of that curve, at an interval's midpoint, strays more than
    ``LINE_DEVIATION_TOLERANCE_M`` from the line or ``LINE_ORIENTATION_DEVIATION_TOLERANCE_RAD``
    from the orientation, the midpoint becomes a knot too, until every interval is within both.
    An unreachable line raises ``UnreachableError`` before any motion starts. The path depends on
    the line alone, so a slowed-down replan reuses it.

    Timing: ruckig plans the path length ``s`` (1 DoF, from rest to rest) under ``cartesian_limits``,
    sampled every control period and mapped through the path to joints.
    The joint velocities, accelerations and jerks of those samples (finite differences) must stay
    within ``joint_limits``; if they do not (near a singularity, or a fast wrist turn), the whole
    line is slowed down in time (velocity, acceleration and jerk limits scaled by ``f``, ``f**2``,
    ``f**3``) and replanned. A line that would need more than ``MAX_LINE_SLOWDOWN`` raises
    ``MotionError``. ``time_scale`` reports the factor used (1.0: the Cartesian limits applied).

    Stop: ``stop()`` brakes ``s`` with ruckig's velocity interface under the same (scaled) limits,
    so the TCP decelerates along the line and comes to rest on it, never past the target.
    """

    def __init__(
        self,
        kinematics: ArmKinematics,
        start_positions_rad: ArrayLike,
        target: Pose,
        cartesian_limits: CartesianLimits,
        joint_limits: JointLimits,
        control_period_s: float,
        orientation_tolerance_rad: float = DEFAULT_LINE_ORIENTATION_TOLERANCE_RAD,
    ) -> None:
        """Plan the line; everything that can fail fails here."""
        super().__init__(control_period_s)
        self._kinematics = kinematics
        start = joint_vector(start_positions_rad)
        start_pose = kinematics.forward(start)
        turn_rad = rotation_angle_rad(start_pose.rotation, target.rotation)
        if turn_rad > orientation_tolerance_rad:
            raise PlanError(
                f"line target orientation differs from the start's by {turn_rad:.4f} rad, tolerance "
                f"{orientation_tolerance_rad:.4f} rad: a line keeps the orientation (turn with a joint motion first)"
            )
        self._rotation = start_pose.rotation
        self._start_m = start_pose.position_m
        end_pose = Pose.from_rotation(target.position_m, self._rotation)
        kinematics.check_reachable(end_pose)
        offset_m = end_pose.position_m - self._start_m
        self._length_m = float(np.linalg.norm(offset_m))
        self._direction = offset_m / self._length_m if self._length_m > _MIN_LINE_LENGTH_M else np.zeros(3)
        self._joint_limits = joint_limits
        self.start_pose = start_pose
        self.end_pose = end_pose

        self._knots_m, self._knot_q, self._knot_dq_ds = self._solve_path(start)
        limits = cartesian_limits
        scale = 1.0
        for _ in range(_LINE_REPLANS):
            self._plan(limits)
            ratio = self._joint_limit_ratio()
            if ratio <= 1.0:
                break
            scale /= ratio * _SLOWDOWN_MARGIN
            if 1.0 / scale > MAX_LINE_SLOWDOWN:
                raise MotionError(
                    f"line from {start_pose!r} to {end_pose!r} would have to run {1.0 / scale:.1f} times slower than "
                    f"its Cartesian limits to respect the joint limits, more than the {MAX_LINE_SLOWDOWN:g}x slowdown "
                    "allowed: it passes too close to a singularity"
                )
            limits = cartesian_limits.time_scaled(scale)
        else:
            raise MotionError(f"line to {end_pose!r} still exceeds the joint limits after {_LINE_REPLANS} replans")
        self._cartesian_limits = limits
        self._time_scale = scale
        self._index = 0
        self._stop_otg: Ruckig | None = None
        self._stop_input: InputParameter | None = None
        self._stop_output: OutputParameter | None = None

    # ----------------------------------------------------------------------------------------------
    # Planning

    def _solve_path(self, start: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Knots along the line: path lengths (m), joints (rad) and joint rates ``dq/ds`` (rad/m).

        Uniform knots first, each IK warm-started from the previous knot's first-order prediction;
        then every interval whose Hermite midpoint strays from the line (position or orientation)
        beyond the deviation tolerances is split at its midpoint, which is solved from that
        midpoint's interpolated joints, until none does.
        """
        if self._length_m <= _MIN_LINE_LENGTH_M:
            return np.zeros(1), start[None, :].copy(), np.zeros((1, len(ARM_JOINT_NAMES)))
        count = max(1, math.ceil(self._length_m / LINE_KNOT_SPACING_M - 1e-9))
        knots = [float(v) for v in np.linspace(0.0, self._length_m, count + 1)]
        knots[-1] = self._length_m
        knot_q = [start]
        knot_dq_ds = [self._joints_per_metre_at(start, 0.0)]
        for k in range(1, len(knots)):
            seed = knot_q[-1] + knot_dq_ds[-1] * (knots[k] - knots[k - 1])
            q = self._solve_at(knots[k], seed)
            knot_q.append(q)
            knot_dq_ds.append(self._joints_per_metre_at(q, knots[k]))
        i = 0
        while i < len(knots) - 1:
            span_m = knots[i + 1] - knots[i]
            mid_m = 0.5 * (knots[i] + knots[i + 1])
            # The Hermite curve at the interval's midpoint.
            guess = 0.5 * (knot_q[i] + knot_q[i + 1]) + 0.125 * span_m * (knot_dq_ds[i] - knot_dq_ds[i + 1])
            if span_m < 2 * _MIN_KNOT_SPACING_M or self._deviation_ok(guess, mid_m):
                i += 1
                continue
            q = self._solve_at(mid_m, guess)
            knots.insert(i + 1, mid_m)
            knot_q.insert(i + 1, q)
            knot_dq_ds.insert(i + 1, self._joints_per_metre_at(q, mid_m))
        return np.array(knots), np.array(knot_q), np.array(knot_dq_ds)

    def _joints_per_metre_at(self, q: FloatArray, s_m: float) -> FloatArray:
        """``dq/ds``: the joint rates that move the TCP along the line at 1 m/s without turning it."""
        twist = np.concatenate([self._direction, np.zeros(3)])
        try:
            return np.linalg.solve(self._kinematics.jacobian(q), twist)
        except np.linalg.LinAlgError as error:
            raise MotionError(f"line passes through a singularity at s = {s_m:.4f} m") from error

    def _deviation_ok(self, q: FloatArray, s_m: float) -> bool:
        """True when the TCP at ``q`` lies within the deviation tolerances of the line's pose at ``s_m``."""
        pose = self._kinematics.forward(q)
        position_error_m = float(np.linalg.norm(pose.position_m - (self._start_m + s_m * self._direction)))
        return (
            position_error_m <= LINE_DEVIATION_TOLERANCE_M
            and rotation_angle_rad(pose.rotation, self._rotation) <= LINE_ORIENTATION_DEVIATION_TOLERANCE_RAD
        )

    def _path_at(self, s_m: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Joints (rad) and ``dq/ds`` (rad/m) at path lengths ``s_m``: the cubic Hermite curve between knots."""
        s = np.atleast_1d(np.asarray(s_m, dtype=float))
        knots = self._knots_m
        if len(knots) == 1:
            return np.repeat(self._knot_q, len(s), axis=0), np.repeat(self._knot_dq_ds, len(s), axis=0)
        i = np.clip(np.searchsorted(knots, s, side="right") - 1, 0, len(knots) - 2)
        h = (knots[i + 1] - knots[i])[:, None]
        t = np.clip((s[:, None] - knots[i][:, None]) / h, 0.0, 1.0)
        q0, q1 = self._knot_q[i], self._knot_q[i + 1]
        m0, m1 = self._knot_dq_ds[i] * h, self._knot_dq_ds[i + 1] * h
        t2, t3 = t * t, t * t * t
        positions = (2 * t3 - 3 * t2 + 1) * q0 + (t3 - 2 * t2 + t) * m0 + (3 * t2 - 2 * t3) * q1 + (t3 - t2) * m1
        rates = ((6 * t2 - 6 * t) * q0 + (3 * t2 - 4 * t + 1) * m0 + (6 * t - 6 * t2) * q1 + (3 * t2 - 2 * t) * m1) / h
        return positions, rates

    def _plan(self, limits: CartesianLimits) -> None:
        """Sample ``s(t)`` every control period and map the samples through the path to joints."""
        dt = self._control_period_s
        if self._length_m <= _MIN_LINE_LENGTH_M:
            s, s_dot, s_ddot = np.zeros(1), np.zeros(1), np.zeros(1)
        else:
            otg = Ruckig(1, dt)
            inp = InputParameter(1)
            inp.current_position = [0.0]
            inp.current_velocity = [0.0]
            inp.current_acceleration = [0.0]
            inp.target_position = [self._length_m]
            inp.target_velocity = [0.0]
            inp.target_acceleration = [0.0]
            inp.max_velocity = [limits.velocity_m_s]
            inp.max_acceleration = [limits.acceleration_m_s2]
            inp.max_jerk = [limits.jerk_m_s3]
            inp.duration_discretization = DurationDiscretization.Discrete
            trajectory = Trajectory(1)
            try:
                result = otg.calculate(inp, trajectory)
            except RuckigError as error:
                raise MotionError(f"line of {self._length_m:.4f} m rejected by ruckig: {error}") from error
            if result not in _RUCKIG_OK:
                raise MotionError(f"line of {self._length_m:.4f} m could not be planned: ruckig {result}")
            count = int(round(trajectory.duration / dt))
            samples = np.array([[v[0] for v in trajectory.at_time(k * dt)] for k in range(count + 1)])
            s, s_dot, s_ddot = samples[:, 0], samples[:, 1], samples[:, 2]
            s[-1] = self._length_m  # exactly on the target, not a rounding away from it
        positions, joints_per_metre = self._path_at(s)
        # Exactly the measured start and the last knot's IK solution, not a rounding away from them.
        positions[0], positions[-1] = self._knot_q[0], self._knot_q[-1]
        self._s, self._s_dot, self._s_ddot = s, s_dot, s_ddot
        self._positions = positions
        self._joints_per_metre = joints_per_metre

    def _solve_at(self, s_m: float, seed: FloatArray) -> FloatArray:
        """IK of the line's pose at path length ``s_m``, on the seed's branch."""
        pose = Pose.from_rotation(self._start_m + s_m * self._direction, self._rotation)
        try:
            return self._kinematics.inverse(pose, seed, retry=False)
        except UnreachableError as error:
            raise UnreachableError(
                f"line from {self.start_pose!r} to {self.end_pose!r} breaks off at {s_m:.4f} m of "
                f"{self._length_m:.4f} m: {error}"
            ) from error

    def _joint_limit_ratio(self) -> float:
        """How far the sampled joints exceed their limits: 1.0 means exactly at a limit.

        Velocity ratios count once, acceleration ratios as a square root and jerk ratios as a cube
        root, so that the result is the time-stretch factor that brings all three within limits.
        """
        limits = self._joint_limits
        dt = self._control_period_s
        ratio = 0.0
        derivative = self._positions
        for order, limit in enumerate((limits.velocity_rad_s, limits.acceleration_rad_s2, limits.jerk_rad_s3), start=1):
            derivative = np.diff(derivative, axis=0) / dt
            if len(derivative) == 0:
                break
            worst = float(np.max(np.abs(derivative) / np.asarray(limit, dtype=float)))
            ratio = max(ratio, worst ** (1.0 / order))
        return ratio

    # ----------------------------------------------------------------------------------------------
    # Properties

    @property
    def duration_s(self) -> float:
        """Planned duration in seconds (after any slowdown)."""
        return (len(self._s) - 1) * self._control_period_s

    @property
    def target_positions_rad(self) -> FloatArray:
        """Joint vector at the end of the line."""
        return self._positions[-1].copy()

    @property
    def length_m(self) -> float:
        """Length of the line in metres."""
        return self._length_m

    @property
    def time_scale(self) -> float:
        """1.0 when the Cartesian limits applied as given; below 1 when the joint limits slowed the line."""
        return self._time_scale

    @property
    def cartesian_limits(self) -> CartesianLimits:
        """The path limits the plan used (the given ones, time-scaled by ``time_scale``)."""
        return self._cartesian_limits

    @property
    def planned_positions_rad(self) -> FloatArray:
        """All planned setpoints, one row per control period, starting with the start state."""
        return self._positions.copy()

    @property
    def knots_m(self) -> FloatArray:
        """Path lengths (m) where IK was solved; the joints between them are interpolated."""
        return self._knots_m.copy()

    @property
    def remaining_m(self) -> float:
        """Path length still ahead of the last setpoint (m); the whole line before the first step."""
        return self._length_m - float(self._s[self._index]) if self._stop_otg is None else 0.0

    def _state(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """The last planned sample: joints, ``dq/ds * ds/dt``, and the samples' second difference."""
        if self._stop_otg is not None:
            raise MotionError("a stopping line has no planned state to hand on")
        k, dt = self._index, self._control_period_s
        positions = self._positions
        velocity = self._joints_per_metre[k] * self._s_dot[k]
        if 0 < k < len(positions) - 1:
            acceleration = (positions[k + 1] - 2.0 * positions[k] + positions[k - 1]) / dt**2
        else:
            acceleration = np.zeros(len(ARM_JOINT_NAMES))
        return positions[k].copy(), velocity, acceleration

    def path_positions_rad(self, s_m: ArrayLike) -> FloatArray:
        """Joints (one row per value) at path lengths ``s_m`` in metres from the start, on the planned path."""
        return self._path_at(np.clip(np.asarray(s_m, dtype=float), 0.0, self._length_m))[0]

    # ----------------------------------------------------------------------------------------------
    # Stepping and stopping

    def _advance(self) -> tuple[JointSetpoint, bool]:
        """Next planned sample, or, while stopping, the next braking sample from ruckig."""
        last = len(self._s) - 1
        if self._stop_otg is None:
            self._index = min(self._index + 1, last)
            k = self._index
            velocity = self._joints_per_metre[k] * self._s_dot[k]
            return JointSetpoint(self._positions[k].copy(), velocity), k == last
        assert self._stop_input is not None and self._stop_output is not None
        try:
            result = self._stop_otg.update(self._stop_input, self._stop_output)
        except RuckigError as error:
            raise MotionError(f"stopping the line failed: {error}") from error
        if result not in _RUCKIG_OK:
            raise MotionError(f"stopping the line failed: ruckig {result}")
        self._stop_output.pass_to_input(self._stop_input)
        s_m = min(max(self._stop_output.new_position[0], 0.0), self._length_m)
        s_dot = self._stop_output.new_velocity[0]
        positions, joints_per_metre = self._interpolate(s_m)
        return JointSetpoint(positions, joints_per_metre * s_dot), result == Result.Finished

    def _interpolate(self, s_m: float) -> tuple[FloatArray, FloatArray]:
        """Joints and ``dq/ds`` at path length ``s_m``, on the path (within its deviation tolerances)."""
        positions, joints_per_metre = self._path_at(s_m)
        return positions[0], joints_per_metre[0]

    def _begin_stop(self) -> None:
        """Brake ``s`` from its current state with ruckig's velocity interface, zero target velocity."""
        k = self._index
        limits = self._cartesian_limits
        self._stop_otg = Ruckig(1, self._control_period_s)
        self._stop_input = inp = InputParameter(1)
        self._stop_output = OutputParameter(1)
        inp.current_position = [float(self._s[k])]
        inp.current_velocity = [float(self._s_dot[k])]
        inp.current_acceleration = [float(self._s_ddot[k])]
        inp.control_interface = ControlInterface.Velocity
        inp.target_velocity = [0.0]
        inp.target_acceleration = [0.0]
        inp.max_velocity = [limits.velocity_m_s]
        inp.max_acceleration = [limits.acceleration_m_s2]
        inp.max_jerk = [limits.jerk_m_s3]
