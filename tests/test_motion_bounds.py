"""Lower bounds on motion times (``bt_arrange.motion.bounds``): never above a motion that meets the same limits."""

from __future__ import annotations

import numpy as np
import pytest

from bt_arrange.motion import (
    DEFAULT_HOME_Q,
    ArmKinematics,
    CartesianLimits,
    JointLimits,
    JointMotion,
    LinearMotion,
    gripper_down_pose,
)
from bt_arrange.motion.bounds import finger_bound_s, joint_move_bound_s, line_bound_s, rest_to_rest_s
from bt_arrange.motion.limits import HARDWARE_JOINT_VELOCITY_RAD_S

DT_S = 0.008


def test_rest_to_rest_of_a_long_move_is_cruise_plus_the_ramps() -> None:
    # 10 rad at 1 rad/s, 1 rad/s^2, 10 rad/s^3: 10 s cruising plus the 1.1 s that the ramps cost.
    assert rest_to_rest_s([0.0], [10.0], 1.0, 1.0, 10.0) == pytest.approx(11.1, abs=1e-6)
    assert rest_to_rest_s([0.3] * 6, [0.3] * 6, 1.0, 1.0, 1.0) == 0.0


@pytest.mark.parametrize("seed", range(5))
def test_a_joint_move_at_hardware_speed_takes_its_bound_and_a_slower_one_longer(seed: int) -> None:
    rng = np.random.default_rng(seed)
    start = DEFAULT_HOME_Q + rng.uniform(-1.0, 1.0, 6)
    target = DEFAULT_HOME_Q + rng.uniform(-1.0, 1.0, 6)
    fast = JointLimits(velocity_rad_s=HARDWARE_JOINT_VELOCITY_RAD_S, acceleration_rad_s2=16.0, jerk_rad_s3=200.0)
    bound = joint_move_bound_s(start, target, fast)
    assert JointMotion(start, target, fast, DT_S).duration_s == pytest.approx(bound, abs=DT_S)
    slower = JointLimits(velocity_rad_s=2.0, acceleration_rad_s2=16.0, jerk_rad_s3=200.0)
    assert JointMotion(start, target, slower, DT_S).duration_s >= bound - 1e-9
    # The bound takes the hardware's speed whatever the motion's own velocity limit.
    assert joint_move_bound_s(start, target, slower) == pytest.approx(bound)


def test_a_line_is_never_faster_than_its_bound() -> None:
    kinematics = ArmKinematics()
    start = kinematics.inverse(gripper_down_pose(0.5, 0.1, 0.025, 0.3), DEFAULT_HOME_Q)
    free = JointLimits(velocity_rad_s=HARDWARE_JOINT_VELOCITY_RAD_S, acceleration_rad_s2=16.0, jerk_rad_s3=200.0)
    for limits in (CartesianLimits(), CartesianLimits(1.0, 4.0, 40.0)):
        line = LinearMotion(kinematics, start, gripper_down_pose(0.5, 0.1, 0.1, 0.3), limits, free, DT_S)
        bound = line_bound_s(start, line.target_positions_rad, line.length_m, free, CartesianLimits(1.0, 4.0, 40.0))
        assert line.duration_s >= bound - DT_S
    assert bound == pytest.approx(line.duration_s, abs=DT_S), "at the fastest line limits the path bound is met"


def test_fingers_bound_is_their_travel_at_top_speed() -> None:
    assert finger_bound_s(-0.035, 0.15) == pytest.approx(0.035 / 0.15)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"finger_speed_m_s": 0.3}, "finger speed 300 mm/s is outside the gripper's 20 to 150 mm/s"),
        ({"squaring_finger_speed_m_s": 0.01}, "squaring finger speed 10 mm/s is outside"),
        ({"settled_speed_rad_s": 0.0}, "settled speed 0 rad/s must be positive"),
        ({"settle_s": -0.1}, "settle time -0.1 s must not be negative"),
        ({"hand_on_remaining_m": -0.01}, "hand-on distance -10 mm must not be negative"),
        ({"release_clearance_per_side_m": -0.002}, "release clearance per side -2 mm must not be negative"),
    ],
)
def test_cycle_time_settings_out_of_range_are_one_line_errors(change: dict, message: str) -> None:
    from bt_arrange.errors import OutOfRangeError
    from bt_arrange.settings import ManipulationSettings

    with pytest.raises(OutOfRangeError, match=message):
        ManipulationSettings(**change)
