"""The pybullet work cell on its own: worlds, devices, camera geometry, bad input."""

import cv2
import numpy as np
import pybullet
import pytest

from bt_arrange.errors import BtArrangeError, OutOfRangeError
from bt_arrange.objects import CUBE
from bt_arrange.robot import Arm, Camera, Clock, Gripper
from bt_arrange_sim.config import CameraConfig, CellConfig
from bt_arrange_sim.noise import CameraNoiseConfig
from bt_arrange_sim.pybullet.cell import WorkCell

CUBE_EDGE_M = CUBE.size_m[0]


@pytest.fixture
def cell():
    with WorkCell() as world:
        yield world


def test_devices_implement_the_robot_interfaces(cell):
    robot = cell.robot
    assert isinstance(robot.arm, Arm)
    assert isinstance(robot.gripper, Gripper)
    assert isinstance(robot.camera, Camera)
    assert isinstance(robot.clock, Clock)


def test_clock_advances_only_when_stepped(cell):
    start = cell.clock.now()
    assert cell.clock.now() == start
    cell.step(5)
    assert cell.clock.now() == pytest.approx(start + 5 * cell.config.physics.control_period_s)


def test_two_worlds_in_one_process_are_independent():
    with WorkCell() as first, WorkCell() as second:
        first.add_cube("red", 0.5, 0.0)
        second.add_cube("red", 0.4, 0.1)
        first.settle(0.2)
        second.settle(0.2)
        assert first.part_pose_truth("red").x_m == pytest.approx(0.5, abs=1e-4)
        assert second.part_pose_truth("red").x_m == pytest.approx(0.4, abs=1e-4)
        assert first.client._client != second.client._client


def test_a_cube_rests_where_it_was_put(cell):
    cell.add_cube("green", 0.45, -0.12, 0.4)
    cell.settle(1.0)
    x, y, yaw = cell.part_planar_truth("green")
    assert (x, y) == pytest.approx((0.45, -0.12), abs=2e-5)
    assert yaw == pytest.approx(0.4, abs=1e-3)
    assert cell.part_pose_truth("green").z_m == pytest.approx(CUBE_EDGE_M / 2, abs=1e-3)


def test_no_constraint_touches_a_cube(cell):
    cell.add_cube("red", 0.5, 0.0)
    client = cell.client
    constraints = [client.getConstraintInfo(client.getConstraintUniqueId(i)) for i in range(client.getNumConstraints())]
    # The only constraint in the world is the gear that mirrors the two fingers.
    assert len(constraints) == 1
    parent_body, _, child_body, _, joint_type = constraints[0][:5]
    assert parent_body == child_body == cell.robot_id
    assert joint_type == pybullet.JOINT_GEAR


def test_gripper_opens_and_closes_symmetrically(cell):
    cell.gripper.open(0.030)
    cell.settle(1.5)  # 55 mm at the default 50 mm/s
    left, right = (s[0] for s in cell.client.getJointStates(cell.robot_id, cell.finger_joint_indices))
    assert cell.gripper.width() == pytest.approx(0.030, abs=2e-4)
    assert left == pytest.approx(right, abs=1e-4)
    assert not cell.gripper.is_moving()


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda g: g.open(0.090), "90.0 mm is outside 0 to 85 mm"),
        (lambda g: g.open(-0.001), "-1.0 mm is outside 0 to 85 mm"),
        (lambda g: g.close(300.0), "300.0 N is outside 20 to 235 N"),
        (lambda g: g.close(40.0, speed_m_s=1.0), "1000 mm/s is outside 20 to 150 mm/s"),
    ],
)
def test_gripper_rejects_values_outside_the_2f85_range(cell, call, message):
    with pytest.raises(OutOfRangeError, match=message) as error:
        call(cell.gripper)
    assert isinstance(error.value, BtArrangeError)


def test_unknown_cube_colour_names_the_known_ones(cell):
    with pytest.raises(ValueError, match="unknown cube colour 'purple'; known: blue, green, red, yellow"):
        cell.add_cube("purple", 0.5, 0.0)


def _red_blob_centroid(rgb):
    hsv = cv2.cvtColor(rgb, cv2.COLOR_RGB2HSV)
    mask = ((hsv[..., 1] > 150) & ((hsv[..., 0] < 10) | (hsv[..., 0] > 170))).astype(np.uint8)
    moments = cv2.moments(mask, binaryImage=True)
    return np.array([moments["m10"] / moments["m00"], moments["m01"] / moments["m00"]]), moments["m00"]


@pytest.mark.parametrize("x_m, y_m", [(0.5, 0.0), (0.36, 0.27), (0.64, -0.31)])
def test_camera_projects_where_its_intrinsics_say(x_m, y_m):
    """The top face's centre lands on the pixel the calibrated intrinsics and pose predict."""
    config = CellConfig(camera=CameraConfig(width_px=960, height_px=540))
    with WorkCell(config) as world:
        world.add_cube("red", x_m, y_m, 0.3)  # turned, so the binary raster carries sub-pixel position
        frame = world.camera.capture()
        assert frame.rgb.shape == (540, 960, 3)
        centre_camera = frame.camera_pose_world.inverse().transform_point([x_m, y_m, CUBE_EDGE_M])
        projected = frame.intrinsics.matrix @ centre_camera
        centroid, area = _red_blob_centroid(frame.rgb)
        assert np.linalg.norm(centroid - projected[:2] / projected[2]) < 0.2
        expected_side_px = frame.intrinsics.fx_px * CUBE_EDGE_M / centre_camera[2]
        assert area == pytest.approx(expected_side_px**2, rel=0.05)


def test_depth_is_metric(cell):
    cell.add_cube("blue", 0.5, 0.0)
    frame = cell.camera.capture(with_depth=True)
    assert frame.depth_m is not None
    centre = frame.depth_m[frame.depth_m.shape[0] // 2, frame.depth_m.shape[1] // 2]
    corner = frame.depth_m[5, 5]
    assert centre == pytest.approx(0.70 - CUBE_EDGE_M, abs=2e-3)
    assert corner == pytest.approx(0.70, abs=2e-3)


def test_camera_noise_is_seeded_and_off_by_default():
    config = CellConfig(camera=CameraConfig(width_px=320, height_px=180))
    with WorkCell(config) as clean:
        clean_image = clean.camera.capture().rgb
        assert np.array_equal(clean_image, clean.camera.capture().rgb)
    noisy_config = CellConfig(camera=config.camera, camera_noise=CameraNoiseConfig.realistic(seed=3))
    images = []
    for _ in range(2):
        with WorkCell(noisy_config) as noisy:
            images.append(noisy.camera.capture().rgb)
    assert np.array_equal(images[0], images[1])
    assert not np.array_equal(images[0], clean_image)
