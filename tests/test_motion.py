"""Motions: ruckig joint motions and straight TCP lines, stepped the way a behaviour steps them."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_arrange import MotionError, OutOfRangeError, PlanError, Pose, UnreachableError
from bt_arrange.motion import (
    DEFAULT_HOME_Q,
    ArmKinematics,
    CartesianLimits,
    JointLimits,
    JointMotion,
    LinearMotion,
    Motion,
    MotionPlanner,
    gripper_down_pose,
    rotation_angle_rad,
    trajectory,
)

DT_S = 0.008  # the UR CB3's 125 Hz, as in the simulated cell
# Finite differences of exact samples stay within the limits (a k-th difference is an average of the
# k-th derivative); this only absorbs floating-point round-off.
ROUND_OFF = 1e-6


@pytest.fixture(scope="module")
def kinematics() -> ArmKinematics:
    return ArmKinematics()


#: The limits the figures of these tests were worked out for (slower than the defaults, so that
#: a motion of a radian or two reaches its limits well before it ends).
TEST_JOINT_LIMITS = JointLimits(velocity_rad_s=1.0, acceleration_rad_s2=2.0, jerk_rad_s3=10.0)
TEST_CARTESIAN_LIMITS = CartesianLimits(velocity_m_s=0.15, acceleration_m_s2=0.5, jerk_m_s3=3.5)


@pytest.fixture(scope="module")
def planner(kinematics: ArmKinematics) -> MotionPlanner:
    return MotionPlanner(kinematics, TEST_JOINT_LIMITS, TEST_CARTESIAN_LIMITS, DT_S)


def run(motion: Motion, start_q: np.ndarray, stop_after_steps: int | None = None, max_steps: int = 5000) -> np.ndarray:
    """Step a motion to the end (optionally calling stop() after some steps); rows: start, then setpoints."""
    return run_with_velocities(motion, start_q, stop_after_steps, max_steps)[0]


def run_with_velocities(
    motion: Motion, start_q: np.ndarray, stop_after_steps: int | None = None, max_steps: int = 5000
) -> tuple[np.ndarray, np.ndarray]:
    """Like run(), and also the setpoints' velocities (the start at rest)."""
    positions = [np.asarray(start_q, dtype=float)]
    velocities = [np.zeros(6)]
    for count in range(max_steps):
        if stop_after_steps is not None and count == stop_after_steps:
            motion.stop()
        setpoint = motion.step()
        positions.append(setpoint.positions_rad)
        velocities.append(setpoint.velocities_rad_s)
        if motion.done:
            return np.array(positions), np.array(velocities)
    raise AssertionError(f"motion not done after {max_steps} steps")


def derivatives(samples: np.ndarray, dt_s: float = DT_S) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Velocity, acceleration and jerk by finite differences."""
    velocity = np.diff(samples, axis=0) / dt_s
    acceleration = np.diff(velocity, axis=0) / dt_s
    return velocity, acceleration, np.diff(acceleration, axis=0) / dt_s


def assert_within_joint_limits(positions: np.ndarray, limits: JointLimits) -> None:
    velocity, acceleration, jerk = derivatives(positions)
    for values, limit in (
        (velocity, limits.velocity_rad_s),
        (acceleration, limits.acceleration_rad_s2),
        (jerk, limits.jerk_rad_s3),
    ):
        assert np.all(np.abs(values) <= np.asarray(limit) * (1 + ROUND_OFF) + ROUND_OFF)


def line_deviation_m(kinematics: ArmKinematics, positions: np.ndarray, start_m: np.ndarray, end_m: np.ndarray) -> float:
    """Largest distance of the setpoints' TCP from the segment start-end."""
    axis = end_m - start_m
    length = float(np.linalg.norm(axis))
    worst = 0.0
    for q in positions:
        offset = kinematics.forward(q).position_m - start_m
        along = float(np.clip(offset @ axis / length, 0.0, length))
        worst = max(worst, float(np.linalg.norm(offset - along * axis / length)))
    return worst


# --------------------------------------------------------------------------------------------------
# Limits


def test_limit_defaults_and_per_joint_values() -> None:
    limits = JointLimits()
    assert limits.velocity_rad_s == (2.0,) * 6
    assert limits.acceleration_rad_s2 == (8.0,) * 6
    assert limits.jerk_rad_s3 == (100.0,) * 6
    per_joint = JointLimits(velocity_rad_s=[0.5, 0.6, 0.7, 0.8, 0.9, 1.0])
    assert per_joint.velocity_rad_s == (0.5, 0.6, 0.7, 0.8, 0.9, 1.0)
    cartesian = CartesianLimits()
    assert (cartesian.velocity_m_s, cartesian.acceleration_m_s2, cartesian.jerk_m_s3) == (0.6, 3.0, 30.0)
    slower = cartesian.time_scaled(0.5)
    assert (slower.velocity_m_s, slower.acceleration_m_s2, slower.jerk_m_s3) == pytest.approx((0.3, 0.75, 3.75))


@pytest.mark.parametrize(
    ("build", "message"),
    [
        (
            lambda: JointLimits(velocity_rad_s=4.0),
            r"shoulder_pan_joint velocity limit 4 rad/s is above the hardware limit 3\.15 rad/s",
        ),
        (lambda: JointLimits(velocity_rad_s=0.0), r"velocity limit 0 rad/s must be positive"),
        (lambda: JointLimits(acceleration_rad_s2=-1.0), r"acceleration limit -1 rad/s\^2 must be positive"),
        (
            lambda: JointLimits(acceleration_rad_s2=114.6),
            r"acceleration limit 114\.6 rad/s\^2 is above the hardware limit 40",
        ),
        (lambda: JointLimits(jerk_rad_s3=573.0), r"jerk limit 573 rad/s\^3 is above the hardware limit 500"),
        (lambda: JointLimits(velocity_rad_s=(1.0, 1.0)), r"velocity_rad_s has 2 entries, the arm has 6 joints"),
        (lambda: CartesianLimits(velocity_m_s=150.0), r"TCP velocity limit 150 m/s is above the hardware limit 1 m/s"),
        (lambda: CartesianLimits(acceleration_m_s2=0.0), r"TCP acceleration limit 0 m/s\^2 must be positive"),
        (lambda: CartesianLimits(jerk_m_s3=math.nan), r"TCP jerk limit nan m/s\^3 must be positive"),
    ],
)
def test_bad_limits_raise_out_of_range(build: object, message: str) -> None:
    with pytest.raises(OutOfRangeError, match=message):
        build()  # type: ignore[operator]


def test_bad_control_period(kinematics: ArmKinematics) -> None:
    with pytest.raises(OutOfRangeError, match=r"control period 0 s must lie in \(0, 0\.1\] s"):
        MotionPlanner(kinematics, JointLimits(), CartesianLimits(), 0.0)
    with pytest.raises(OutOfRangeError, match=r"control period 0\.5 s"):
        JointMotion(DEFAULT_HOME_Q, DEFAULT_HOME_Q, JointLimits(), 0.5)


# --------------------------------------------------------------------------------------------------
# Joint motions


def test_joint_motion_respects_limits_and_ends_at_the_target(planner: MotionPlanner) -> None:
    target = np.array([0.6, -1.2, 1.0, -1.9, -1.2, 1.5])
    motion = planner.move_joints(DEFAULT_HOME_Q, target)
    assert not motion.done
    positions = run(motion, DEFAULT_HOME_Q)
    assert len(positions) - 1 == round(motion.duration_s / DT_S)  # one setpoint per control period
    assert motion.elapsed_s == pytest.approx(motion.duration_s)
    assert np.allclose(positions[-1], target, atol=1e-12)
    assert_within_joint_limits(positions, planner.joint_limits)
    velocity, acceleration, jerk = derivatives(positions)
    # The limits are reached, not just respected: the motion is time-optimal for its slowest joint.
    assert np.abs(velocity).max() == pytest.approx(1.0, rel=1e-3)
    assert np.abs(acceleration).max() == pytest.approx(2.0, rel=0.05)
    # Phase synchronisation: from rest, a straight line in joint space.
    direction = (target - DEFAULT_HOME_Q) / np.linalg.norm(target - DEFAULT_HOME_Q)
    for q in positions:
        offset = q - DEFAULT_HOME_Q
        assert np.linalg.norm(offset - (offset @ direction) * direction) < 1e-9
    final = motion.step()  # after done: hold the target, at rest
    assert np.allclose(final.positions_rad, target) and not final.velocities_rad_s.any()


def test_joint_motion_reports_velocities_consistent_with_positions(planner: MotionPlanner) -> None:
    motion = planner.move_joints(DEFAULT_HOME_Q, DEFAULT_HOME_Q + 0.3)
    previous = DEFAULT_HOME_Q
    while not motion.done:
        setpoint = motion.step()
        average = (setpoint.positions_rad - previous) / DT_S
        # Velocity changes by at most a_max * dt within one period.
        assert np.all(np.abs(setpoint.velocities_rad_s - average) <= 2.0 * DT_S + 1e-9)
        previous = setpoint.positions_rad


def test_joint_motion_per_joint_limits(kinematics: ArmKinematics) -> None:
    limits = JointLimits(velocity_rad_s=(0.2, 0.4, 0.6, 0.8, 1.0, 1.2), acceleration_rad_s2=(1.0, 1, 1, 3, 3, 3))
    start = DEFAULT_HOME_Q
    target = start + np.array([1.0, -0.5, 0.5, 1.0, 1.0, 2.0])
    positions = run(JointMotion(start, target, limits, DT_S), start)
    assert_within_joint_limits(positions, limits)
    assert np.allclose(positions[-1], target)


def test_joint_motion_stop_midway_comes_to_rest_within_limits(planner: MotionPlanner) -> None:
    target = DEFAULT_HOME_Q + np.array([1.5, 0.4, -0.5, 0.3, 0.2, -1.0])
    motion = planner.move_joints(DEFAULT_HOME_Q, target)
    planned_steps = round(motion.duration_s / DT_S)
    positions, velocities = run_with_velocities(motion, DEFAULT_HOME_Q, stop_after_steps=planned_steps // 3)
    assert motion.stopping and motion.done
    assert motion.elapsed_s < motion.duration_s
    assert_within_joint_limits(positions, planner.joint_limits)
    assert np.abs(velocities[-1]).max() < 1e-9  # at rest
    assert np.abs(velocities[planned_steps // 3]).max() == pytest.approx(1.0)  # stopped at full speed
    assert not np.allclose(positions[-1], target, atol=0.1)  # stopped well short of the target
    # Stopping from full speed 1 rad/s takes at least 1 / 2 rad/s^2 = 0.5 s, and about that.
    stop_s = (len(positions) - 1 - planned_steps // 3) * DT_S
    assert 0.5 <= stop_s < 0.8
    held = motion.step()
    assert np.allclose(held.positions_rad, positions[-1]) and not held.velocities_rad_s.any()


def test_stop_before_the_first_step_holds_the_start(planner: MotionPlanner) -> None:
    motion = planner.move_joints(DEFAULT_HOME_Q, DEFAULT_HOME_Q + 0.5)
    motion.stop()
    motion.stop()  # idempotent
    setpoint = motion.step()
    assert motion.done
    assert np.allclose(setpoint.positions_rad, DEFAULT_HOME_Q)


def test_joint_target_outside_the_limits_is_refused(planner: MotionPlanner) -> None:
    target = DEFAULT_HOME_Q.copy()
    target[2] = 3.5
    with pytest.raises(
        UnreachableError, match=r"elbow_joint = 3\.5000 rad is outside the joint limits \[-3\.1416, 3\.1416\] rad"
    ):
        planner.move_joints(DEFAULT_HOME_Q, target)


def test_move_to_pose_ends_at_the_pose(planner: MotionPlanner, kinematics: ArmKinematics) -> None:
    target = gripper_down_pose(0.55, -0.2, 0.12, 0.8)
    positions = run(planner.move_to_pose(DEFAULT_HOME_Q, target), DEFAULT_HOME_Q)
    reached = kinematics.forward(positions[-1])
    assert np.linalg.norm(reached.position_m - target.position_m) < 1e-6
    assert rotation_angle_rad(reached.rotation, target.rotation) < 1e-5
    assert_within_joint_limits(positions, planner.joint_limits)


def test_move_to_pose_refuses_an_unreachable_pose(planner: MotionPlanner) -> None:
    with pytest.raises(UnreachableError, match=r"out of reach"):
        planner.move_to_pose(DEFAULT_HOME_Q, gripper_down_pose(0.95, 0.3, 0.1))


def test_zero_length_joint_motion(planner: MotionPlanner) -> None:
    motion = planner.move_joints(DEFAULT_HOME_Q, DEFAULT_HOME_Q)
    assert motion.duration_s == 0.0
    assert np.allclose(motion.step().positions_rad, DEFAULT_HOME_Q)
    assert motion.done


# --------------------------------------------------------------------------------------------------
# Straight lines


@pytest.fixture(scope="module")
def above_cube_q(kinematics: ArmKinematics) -> np.ndarray:
    return kinematics.inverse(gripper_down_pose(0.5, 0.1, 0.15, 0.3), DEFAULT_HOME_Q)


@pytest.mark.parametrize(
    "end_m",
    [
        (0.5, 0.1, 0.025),  # descend to a grasp
        (0.62, 0.1, 0.15),  # push along x
        (0.4, -0.25, 0.06),  # a long diagonal
    ],
)
def test_line_stays_on_the_segment_and_keeps_the_orientation(
    planner: MotionPlanner, kinematics: ArmKinematics, above_cube_q: np.ndarray, end_m: tuple[float, float, float]
) -> None:
    start = kinematics.forward(above_cube_q)
    end = np.array(end_m)
    motion = planner.move_line(above_cube_q, Pose.from_rotation(end, start.rotation))
    positions = run(motion, above_cube_q)
    assert line_deviation_m(kinematics, positions, start.position_m, end) < 1e-4
    tcp = np.array([kinematics.forward(q).position_m for q in positions])
    for q in positions:
        assert rotation_angle_rad(kinematics.forward(q).rotation, start.rotation) < 1e-5
    assert np.linalg.norm(tcp[-1] - end) < 1e-6
    # Along the path: within the (possibly time-scaled) Cartesian limits...
    limits = motion.cartesian_limits
    speed, acceleration, _ = derivatives(tcp)
    assert np.linalg.norm(speed, axis=1).max() <= limits.velocity_m_s * (1 + ROUND_OFF)
    assert np.linalg.norm(acceleration, axis=1).max() <= limits.acceleration_m_s2 * (1 + 1e-3)
    # ...and every joint within the joint limits.
    assert_within_joint_limits(positions, planner.joint_limits)


def test_line_velocities_are_the_derivative_of_the_positions(
    planner: MotionPlanner, kinematics: ArmKinematics, above_cube_q: np.ndarray
) -> None:
    start = kinematics.forward(above_cube_q)
    motion = planner.move_line(above_cube_q, Pose.from_rotation(start.position_m - [0, 0, 0.1], start.rotation))
    previous = above_cube_q
    while not motion.done:
        setpoint = motion.step()
        average = (setpoint.positions_rad - previous) / DT_S
        assert np.all(np.abs(setpoint.velocities_rad_s - average) <= 2.0 * DT_S + 1e-6)
        previous = setpoint.positions_rad


def test_line_is_slowed_down_to_respect_slow_joints(kinematics: ArmKinematics, above_cube_q: np.ndarray) -> None:
    slow_joints = JointLimits(velocity_rad_s=0.1, acceleration_rad_s2=0.5, jerk_rad_s3=5.0)
    planner = MotionPlanner(kinematics, slow_joints, TEST_CARTESIAN_LIMITS, DT_S)
    start = kinematics.forward(above_cube_q)
    motion = planner.move_line(above_cube_q, Pose.from_rotation(start.position_m + [0.1, 0.0, -0.05], start.rotation))
    assert motion.time_scale < 0.7
    assert motion.cartesian_limits.velocity_m_s == pytest.approx(0.15 * motion.time_scale)
    positions = run(motion, above_cube_q)
    assert_within_joint_limits(positions, slow_joints)
    assert line_deviation_m(kinematics, positions, start.position_m, start.position_m + [0.1, 0.0, -0.05]) < 1e-4


def test_line_stop_comes_to_rest_on_the_line(
    planner: MotionPlanner, kinematics: ArmKinematics, above_cube_q: np.ndarray
) -> None:
    start = kinematics.forward(above_cube_q)
    end = start.position_m + np.array([0.15, 0.0, -0.1])
    motion = planner.move_line(above_cube_q, Pose.from_rotation(end, start.rotation))
    planned_steps = round(motion.duration_s / DT_S)
    positions, velocities = run_with_velocities(motion, above_cube_q, stop_after_steps=planned_steps // 2)
    assert motion.stopping and motion.done
    assert np.abs(velocities[-1]).max() < 1e-9  # at rest
    assert line_deviation_m(kinematics, positions, start.position_m, end) < 1e-4
    tcp = np.array([kinematics.forward(q).position_m for q in positions])
    travelled = np.linalg.norm(tcp[-1] - start.position_m)
    assert 0.2 * motion.length_m < travelled < 0.95 * motion.length_m  # stopped short of the target
    speed, acceleration, _ = derivatives(tcp)
    assert np.linalg.norm(speed, axis=1).max() <= motion.cartesian_limits.velocity_m_s * (1 + 1e-3)
    assert np.linalg.norm(acceleration, axis=1).max() <= motion.cartesian_limits.acceleration_m_s2 * (1 + 1e-2)
    for q in positions:
        assert rotation_angle_rad(kinematics.forward(q).rotation, start.rotation) < 1e-5


def line_pose_errors(kinematics: ArmKinematics, motion: LinearMotion, q: np.ndarray, s_m: float) -> tuple[float, float]:
    """Distance (m) and turn (rad) of the TCP at ``q`` from the line's pose at path length ``s_m``."""
    start, end = motion.start_pose, motion.end_pose
    direction = (end.position_m - start.position_m) / motion.length_m
    tcp = kinematics.forward(q)
    return (
        float(np.linalg.norm(tcp.position_m - (start.position_m + s_m * direction))),
        rotation_angle_rad(tcp.rotation, start.rotation),
    )


@pytest.mark.parametrize(
    "end_m",
    [
        (0.5, 0.1, 0.025),  # descend to a grasp
        (0.62, 0.1, 0.15),  # push along x
        (0.4, -0.25, 0.06),  # a long diagonal
    ],
)
def test_line_joints_between_ik_knots_stay_within_the_deviation_bound(
    planner: MotionPlanner, kinematics: ArmKinematics, above_cube_q: np.ndarray, end_m: tuple[float, float, float]
) -> None:
    start = kinematics.forward(above_cube_q)
    motion = planner.move_line(above_cube_q, Pose.from_rotation(np.array(end_m), start.rotation))
    # IK at knots only: far fewer solves than setpoints.
    assert len(motion.knots_m) < len(motion.planned_positions_rad) / 4
    assert motion.knots_m[0] == 0.0 and motion.knots_m[-1] == motion.length_m
    # Densely along the path, not only at the knots' midpoints the planner checked: the TCP of
    # the interpolated joints is where the line's pose is, within the bound (the Hermite error
    # peaks at the midpoints, so the bound holds everywhere up to round-off).
    for s_m in np.linspace(0.0, motion.length_m, 301):
        position_m, turn_rad = line_pose_errors(kinematics, motion, motion.path_positions_rad([s_m])[0], s_m)
        assert position_m <= trajectory.LINE_DEVIATION_TOLERANCE_M * 1.05
        assert turn_rad <= trajectory.LINE_ORIENTATION_DEVIATION_TOLERANCE_RAD * 1.05
    # ...and at the knots themselves the joints are the IK's exact solutions.
    for s_m, q in zip(motion.knots_m, motion.path_positions_rad(motion.knots_m), strict=True):
        position_m, turn_rad = line_pose_errors(kinematics, motion, q, s_m)
        assert position_m < 1e-6 and turn_rad < 1e-5


def test_line_knots_are_refined_where_interpolation_strays(
    kinematics: ArmKinematics, above_cube_q: np.ndarray, monkeypatch: pytest.MonkeyPatch
) -> None:
    # One knot at each end only: interpolating a 25 cm diagonal between them strays millimetres
    # from the line, so the planner splits the intervals until the bound holds again.
    monkeypatch.setattr(trajectory, "LINE_KNOT_SPACING_M", 1.0)
    planner = MotionPlanner(kinematics, TEST_JOINT_LIMITS, TEST_CARTESIAN_LIMITS, DT_S)
    start = kinematics.forward(above_cube_q)
    end = Pose.from_rotation([0.4, -0.25, 0.06], start.rotation)
    motion = planner.move_line(above_cube_q, end)
    assert len(motion.knots_m) > 2
    for s_m in np.linspace(0.0, motion.length_m, 201):
        position_m, turn_rad = line_pose_errors(kinematics, motion, motion.path_positions_rad([s_m])[0], s_m)
        assert position_m <= trajectory.LINE_DEVIATION_TOLERANCE_M * 1.05
        assert turn_rad <= trajectory.LINE_ORIENTATION_DEVIATION_TOLERANCE_RAD * 1.05


def test_line_below_the_table_is_refused_before_any_setpoint(
    planner: MotionPlanner, kinematics: ArmKinematics, above_cube_q: np.ndarray
) -> None:
    start = kinematics.forward(above_cube_q)
    with pytest.raises(UnreachableError, match=r"below the table: TCP z 0\.00500 m < minimum 0\.02175 m"):
        planner.move_line(above_cube_q, Pose.from_rotation([0.5, 0.1, 0.005], start.rotation))


def test_line_out_of_reach_is_refused(
    planner: MotionPlanner, kinematics: ArmKinematics, above_cube_q: np.ndarray
) -> None:
    start = kinematics.forward(above_cube_q)
    with pytest.raises(UnreachableError, match=r"out of reach: .* m from the shoulder, the reach is 0\.918 m"):
        planner.move_line(above_cube_q, Pose.from_rotation([1.0, 0.1, 0.15], start.rotation))


def test_line_through_the_base_axis_breaks_off_in_planning(planner: MotionPlanner, kinematics: ArmKinematics) -> None:
    # Both ends are reachable, but the straight line between them passes over the base, where the
    # wrist centre cannot go.
    start_q = kinematics.inverse(gripper_down_pose(0.3, 0.25, 0.2, 0.0), DEFAULT_HOME_Q)
    start = kinematics.forward(start_q)
    with pytest.raises(UnreachableError, match=r"breaks off at 0\.\d{4} m of 0\.\d{4} m: .*"):
        planner.move_line(start_q, Pose.from_rotation([-0.3, -0.25, 0.2], start.rotation))


def test_line_that_turns_the_gripper_is_a_plan_error(planner: MotionPlanner, above_cube_q: np.ndarray) -> None:
    with pytest.raises(PlanError, match=r"differs from the start's by 0\.\d{4} rad, tolerance 0\.0200 rad"):
        planner.move_line(above_cube_q, gripper_down_pose(0.5, 0.1, 0.05, 0.3 + 0.2))


def test_line_within_the_orientation_tolerance_keeps_the_start_orientation(
    planner: MotionPlanner, kinematics: ArmKinematics, above_cube_q: np.ndarray
) -> None:
    start = kinematics.forward(above_cube_q)
    motion = planner.move_line(above_cube_q, gripper_down_pose(0.5, 0.1, 0.05, 0.3 + 0.01))
    end = kinematics.forward(motion.target_positions_rad)
    assert rotation_angle_rad(end.rotation, start.rotation) < 1e-5
    assert np.linalg.norm(end.position_m - [0.5, 0.1, 0.05]) < 1e-6


def test_zero_length_line(planner: MotionPlanner, kinematics: ArmKinematics, above_cube_q: np.ndarray) -> None:
    motion = planner.move_line(above_cube_q, kinematics.forward(above_cube_q))
    assert motion.duration_s == 0.0
    assert np.allclose(motion.step().positions_rad, above_cube_q)
    assert motion.done


def test_line_needing_a_huge_slowdown_is_a_motion_error(kinematics: ArmKinematics, above_cube_q: np.ndarray) -> None:
    crawling_joints = JointLimits(velocity_rad_s=0.005)
    planner = MotionPlanner(kinematics, crawling_joints, TEST_CARTESIAN_LIMITS, DT_S)
    start = kinematics.forward(above_cube_q)
    with pytest.raises(MotionError, match=r"more than the 10x slowdown allowed"):
        LinearMotion(
            kinematics,
            above_cube_q,
            Pose.from_rotation(start.position_m + [0.0, 0.0, -0.1], start.rotation),
            planner.cartesian_limits,
            crawling_joints,
            DT_S,
        )


def test_line_towards_full_stretch_slows_down_within_joint_limits(
    planner: MotionPlanner, kinematics: ArmKinematics
) -> None:
    # Near the stretched-arm singularity the elbow has to move fast for little TCP motion.
    start_q = kinematics.inverse(gripper_down_pose(0.6, 0.1, 0.1, 0.0), DEFAULT_HOME_Q)
    start = kinematics.forward(start_q)
    end = np.array([0.88, 0.1, 0.1])
    motion = planner.move_line(start_q, Pose.from_rotation(end, start.rotation))
    assert motion.time_scale < 0.5
    positions = run(motion, start_q)
    assert_within_joint_limits(positions, planner.joint_limits)
    assert line_deviation_m(kinematics, positions, start.position_m, end) < 1e-4
