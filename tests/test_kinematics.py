"""Kinematics of the bundled UR5 + 2F-85 URDF: forward against the UR5 DH parameters, inverse round trips."""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np
import pytest

from bt_arrange import OutOfRangeError, Pose, UnreachableError
from bt_arrange.geometry import rotation_z
from bt_arrange.motion import (
    ARM_JOINT_NAMES,
    CUBE_SYMMETRY_RAD,
    DEFAULT_HOME_Q,
    GRIPPER_SYMMETRY_RAD,
    PAD_HALF_HEIGHT_M,
    ArmKinematics,
    JointLimits,
    default_urdf_path,
    gripper_down_pose,
    gripper_down_rotation,
    nearest_symmetric_yaw,
    rotation_angle_rad,
)

# UR5 (CB3) standard DH parameters.
DH_D = (0.089159, 0.0, 0.0, 0.10915, 0.09465, 0.0823)
DH_A = (0.0, -0.425, -0.39225, 0.0, 0.0, 0.0)
DH_ALPHA = (math.pi / 2, 0.0, 0.0, math.pi / 2, -math.pi / 2, 0.0)
# ur_description's base_link is the DH base frame turned by pi about z.
T_BASELINK_DHBASE = np.diag([-1.0, -1.0, 1.0, 1.0])


def dh_flange(q: np.ndarray) -> np.ndarray:
    """Pose of DH frame 6 (the tool flange) in the DH base frame."""
    t = np.eye(4)
    for theta, d, a, alpha in zip(q, DH_D, DH_A, DH_ALPHA, strict=True):
        ct, st, ca, sa = math.cos(theta), math.sin(theta), math.cos(alpha), math.sin(alpha)
        t = t @ np.array(
            [[ct, -st * ca, st * sa, a * ct], [st, ct * ca, -ct * sa, a * st], [0.0, sa, ca, d], [0.0, 0.0, 0.0, 1.0]]
        )
    return t


@pytest.fixture(scope="module")
def kinematics() -> ArmKinematics:
    return ArmKinematics()


def random_down_pose(rng: np.random.Generator) -> Pose:
    """A gripper-down pose over the table region the cell uses, any yaw."""
    return gripper_down_pose(
        rng.uniform(0.25, 0.70), rng.uniform(-0.4, 0.4), rng.uniform(0.025, 0.30), rng.uniform(-math.pi, math.pi)
    )


# --------------------------------------------------------------------------------------------------
# Forward kinematics


def test_urdf_tool0_is_dh_flange_with_base_turned_half_turn(kinematics: ArmKinematics) -> None:
    rng = np.random.default_rng(1)
    for _ in range(200):
        q = rng.uniform(-math.pi, math.pi, 6)
        expected = T_BASELINK_DHBASE @ dh_flange(q)
        tool0 = kinematics.forward(q, frame="tool0")
        assert np.linalg.norm(tool0.position_m - expected[:3, 3]) < 1e-6
        assert rotation_angle_rad(tool0.rotation, expected[:3, :3]) < 1e-6


def test_dh_without_the_half_turn_does_not_match(kinematics: ArmKinematics) -> None:
    # The half turn is needed: without it every position lands mirrored through the base axis.
    q = np.array([0.3, -1.2, 1.0, -1.4, -1.5, 0.2])
    assert np.linalg.norm(kinematics.forward(q, frame="tool0").position_m - dh_flange(q)[:3, 3]) > 0.1


def test_pybullet_forward_kinematics_matches_dh() -> None:
    pybullet = pytest.importorskip("pybullet")
    from pybullet_utils.bullet_client import BulletClient

    client = BulletClient(connection_mode=pybullet.DIRECT)
    try:
        robot = client.loadURDF(str(default_urdf_path()), useFixedBase=True)
        joints = {}
        links = {}
        for index in range(client.getNumJoints(robot)):
            info = client.getJointInfo(robot, index)
            joints[info[1].decode()] = index
            links[info[12].decode()] = index
        rng = np.random.default_rng(2)
        for _ in range(50):
            q = rng.uniform(-math.pi, math.pi, 6)
            for name, value in zip(ARM_JOINT_NAMES, q, strict=True):
                client.resetJointState(robot, joints[name], float(value))
            state = client.getLinkState(robot, links["tool0"], computeForwardKinematics=True)
            expected = T_BASELINK_DHBASE @ dh_flange(q)
            position = np.array(state[4])
            rotation = np.array(client.getMatrixFromQuaternion(state[5])).reshape(3, 3)
            assert np.linalg.norm(position - expected[:3, 3]) < 1e-6
            assert rotation_angle_rad(rotation, expected[:3, :3]) < 1e-6
    finally:
        client.disconnect()


def test_tcp_is_between_the_pads_at_mid_pad_height(kinematics: ArmKinematics) -> None:
    q = np.array([0.1, -1.7, 1.5, -1.3, -1.6, 0.4])
    tool0 = kinematics.forward(q, frame="tool0")
    tcp = kinematics.forward(q)
    assert rotation_angle_rad(tool0.rotation, tcp.rotation) < 1e-12
    assert np.allclose(tool0.inverse().transform_point(tcp.position_m), [0.0, 0.0, 0.13625], atol=1e-12)
    # Pads: 37.5 mm tall, centred 46.25 mm above the finger joints, which sit 90 mm below tool0.
    pad_bottom_in_tool0_m = 0.09 + 0.04625 + 0.0375 / 2
    assert math.isclose(pad_bottom_in_tool0_m - 0.13625, PAD_HALF_HEIGHT_M, abs_tol=1e-12)


def test_base_pose_world_moves_every_frame(kinematics: ArmKinematics) -> None:
    base = Pose.from_rotation([0.1, -0.2, 0.05], rotation_z(0.3))
    moved = ArmKinematics(base_pose_world=base)
    q = np.array([0.2, -1.9, 1.6, -1.2, -1.57, 0.3])
    expected = base @ kinematics.forward(q)
    got = moved.forward(q)
    assert np.linalg.norm(got.position_m - expected.position_m) < 1e-12
    assert rotation_angle_rad(got.rotation, expected.rotation) < 1e-12
    # And inverse works in the world frame too.
    target = gripper_down_pose(0.5, 0.0, 0.12, 0.4)
    solution = moved.inverse(target, q)
    assert np.linalg.norm(moved.forward(solution).position_m - target.position_m) < 1e-6


def test_home_points_down_above_the_table_with_the_elbow_up(kinematics: ArmKinematics) -> None:
    home = kinematics.forward(DEFAULT_HOME_Q)
    assert np.allclose(home.position_m, [0.25, 0.0, 0.40], atol=1e-6)
    assert np.allclose(home.rotation[:, 2], [0.0, 0.0, -1.0], atol=1e-9)
    JointLimits().check_positions(DEFAULT_HOME_Q, "home")
    elbow = kinematics.forward(DEFAULT_HOME_Q, frame="forearm_link").position_m
    shoulder = kinematics.forward(DEFAULT_HOME_Q, frame="upper_arm_link").position_m
    assert elbow[2] > shoulder[2] + 0.3  # elbow up
    assert elbow[0] < 0.0  # and behind the base, away from the camera at x = 0.5 m


# --------------------------------------------------------------------------------------------------
# Orientation helpers


def test_gripper_down_rotation_points_down_with_the_given_yaw() -> None:
    for yaw in (-3.0, -1.0, 0.0, 0.5, 2.0):
        rotation = gripper_down_rotation(yaw)
        assert np.allclose(rotation.T @ rotation, np.eye(3), atol=1e-12)
        assert math.isclose(np.linalg.det(rotation), 1.0, abs_tol=1e-12)
        assert np.allclose(rotation[:, 2], [0.0, 0.0, -1.0])
        assert np.allclose(rotation[:, 0], [math.cos(yaw), math.sin(yaw), 0.0])
        assert math.isclose(gripper_down_pose(0.4, 0.0, 0.1, yaw).yaw_rad, yaw, abs_tol=1e-12)


def test_nearest_symmetric_yaw() -> None:
    deg = math.radians
    # A cube at 80 deg can be grasped at -10 deg: nearest to a wrist at 0 deg.
    assert math.isclose(nearest_symmetric_yaw(deg(80), 0.0, CUBE_SYMMETRY_RAD), deg(-10))
    # With only the gripper's half-turn symmetry, 80 deg stays 80 deg near 0...
    assert math.isclose(nearest_symmetric_yaw(deg(80), 0.0, GRIPPER_SYMMETRY_RAD), deg(80))
    # ...and 170 deg becomes -10 deg.
    assert math.isclose(nearest_symmetric_yaw(deg(170), 0.0, GRIPPER_SYMMETRY_RAD), deg(-10))
    # The result is unwrapped near the reference, so the wrist turns the least.
    assert math.isclose(nearest_symmetric_yaw(deg(-175), deg(350), CUBE_SYMMETRY_RAD), deg(365))
    rng = np.random.default_rng(3)
    for _ in range(100):
        yaw, reference = rng.uniform(-10, 10, 2)
        result = nearest_symmetric_yaw(yaw, reference)
        assert abs(result - reference) <= CUBE_SYMMETRY_RAD / 2 + 1e-12
        k = (result - yaw) / CUBE_SYMMETRY_RAD
        assert abs(k - round(k)) < 1e-9


# --------------------------------------------------------------------------------------------------
# Inverse kinematics


def test_inverse_round_trips_over_the_workspace(kinematics: ArmKinematics) -> None:
    rng = np.random.default_rng(4)
    limits = JointLimits()
    durations_s = []
    for _ in range(300):
        target = random_down_pose(rng)
        start = time.perf_counter()
        q = kinematics.inverse(target, DEFAULT_HOME_Q)
        durations_s.append(time.perf_counter() - start)
        reached = kinematics.forward(q)
        assert np.linalg.norm(reached.position_m - target.position_m) < 1e-5
        assert rotation_angle_rad(reached.rotation, target.rotation) < 1e-5
        limits.check_positions(q, "IK solution")
    # A few hundred microseconds each; generous bound for a busy two-core machine.
    assert float(np.median(durations_s)) < 0.003


def test_inverse_keeps_the_seed_branch(kinematics: ArmKinematics) -> None:
    rng = np.random.default_rng(5)
    for _ in range(50):
        q = kinematics.inverse(random_down_pose(rng), DEFAULT_HOME_Q)
        assert q[2] > 0.0  # elbow stays up
        assert -math.pi < q[1] < 0.0  # upper arm above the shoulder


def test_inverse_from_its_own_solution_is_a_fixed_point(kinematics: ArmKinematics) -> None:
    q = np.array([0.1, -1.8, 1.7, -1.5, -1.57, 0.9])
    assert np.allclose(kinematics.inverse(kinematics.forward(q), q), q, atol=1e-9)


def test_out_of_reach_names_distance_and_reach(kinematics: ArmKinematics) -> None:
    with pytest.raises(UnreachableError, match=r"out of reach: .*1\.\d{3} m from the shoulder, the reach is 0\.918 m"):
        kinematics.inverse(gripper_down_pose(1.2, 0.0, 0.2), DEFAULT_HOME_Q)


def test_below_the_table_names_z_and_minimum(kinematics: ArmKinematics) -> None:
    minimum = PAD_HALF_HEIGHT_M + kinematics.table_clearance_m
    with pytest.raises(UnreachableError, match=rf"below the table: TCP z 0\.01000 m < minimum {minimum:.5f} m"):
        kinematics.check_reachable(gripper_down_pose(0.5, 0.0, 0.01))
    raised_table = ArmKinematics(table_top_z_m=0.1)
    with pytest.raises(UnreachableError, match=r"TCP z 0\.11000 m < minimum 0\.12175 m"):
        raised_table.inverse(gripper_down_pose(0.5, 0.0, 0.11), DEFAULT_HOME_Q)


def test_too_close_to_the_base_axis(kinematics: ArmKinematics) -> None:
    with pytest.raises(
        UnreachableError, match=r"too close to the base axis: .* 0\.0\d\d m from it, the minimum is 0\.109 m"
    ):
        kinematics.inverse(gripper_down_pose(0.02, 0.0, 0.3), DEFAULT_HOME_Q)


def test_no_solution_within_joint_limits_names_the_residual(tmp_path: Path) -> None:
    # The same arm with wrist_3 limited to +-0.1 rad cannot turn the gripper by 90 degrees.
    urdf = default_urdf_path().read_text()
    start = urdf.index('<joint name="wrist_3_joint"')
    end = urdf.index("</joint>", start)
    wrist = urdf[start:end].replace('lower="-6.283185307179586" upper="6.283185307179586"', 'lower="-0.1" upper="0.1"')
    path = tmp_path / "narrow_wrist.urdf"
    path.write_text(urdf[:start] + wrist + urdf[end:])
    narrow = ArmKinematics(path)
    seed = np.array([0.0, -1.6, 1.6, -1.57, -1.57, 0.0])
    yaw = narrow.forward(seed).yaw_rad
    target = gripper_down_pose(0.45, 0.11, 0.2, yaw + math.pi / 2)
    with pytest.raises(
        UnreachableError, match=r"no inverse kinematics solution within the joint limits: residual .* mm"
    ):
        narrow.inverse(target, seed)


def test_bad_joint_vector_is_rejected(kinematics: ArmKinematics) -> None:
    with pytest.raises(ValueError, match="6 finite values"):
        kinematics.forward([0.0, 1.0])
    with pytest.raises(ValueError, match="6 finite values"):
        kinematics.inverse(gripper_down_pose(0.4, 0.0, 0.2), [0.0, 0.0, math.nan, 0.0, 0.0, 0.0])


def test_joint_limits_match_the_urdf(kinematics: ArmKinematics) -> None:
    limits = JointLimits()
    assert np.allclose(limits.lower_rad, kinematics.lower_rad)
    assert np.allclose(limits.upper_rad, kinematics.upper_rad)
    assert limits.upper_rad[2] == pytest.approx(math.pi)  # the elbow is limited to +-180 deg
    with pytest.raises(
        OutOfRangeError, match=r"elbow_joint velocity limit 3\.5 rad/s is above the hardware limit 3\.15"
    ):
        JointLimits(velocity_rad_s=(1.0, 1.0, 3.5, 1.0, 1.0, 1.0))
