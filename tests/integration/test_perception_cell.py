"""Perception on frames rendered by the pybullet cell, checked against its ground truth."""

import math

import pytest

from bt_arrange.geometry import fold_yaw
from bt_arrange.motion import gripper_down_pose
from bt_arrange.perception import CubeDetector, DetectionStatus
from bt_arrange_sim import CameraNoiseConfig, CellConfig, WorkCell
from bt_arrange_sim.scripted import ScriptedPickPlace

SCENE = [
    ("red", 0.40, 0.20, 0.3),
    ("green", 0.62, -0.25, -1.1),
    ("blue", 0.55, 0.05, 0.0),
    ("yellow", 0.33, -0.1, 0.78),
]


@pytest.mark.parametrize("noise", [False, True], ids=["clean", "noisy"])
def test_every_cube_is_found_within_a_fifth_of_a_millimetre(noise):
    config = CellConfig(camera_noise=CameraNoiseConfig.realistic(seed=1) if noise else CameraNoiseConfig())
    with WorkCell(config) as cell:
        for colour, x, y, yaw in SCENE:
            cell.add_cube(colour, x, y, yaw)
        cell.settle(0.1)
        detections = CubeDetector().detect_all(cell.camera.capture())
        for colour, *_ in SCENE:
            detection = detections[colour]
            assert detection.found, detection.reason
            true_x, true_y, true_yaw = cell.cube_planar_truth(colour)
            assert math.hypot(detection.planar.x_m - true_x, detection.planar.y_m - true_y) < 0.2e-3
            assert abs(fold_yaw(detection.planar.yaw_rad - true_yaw)) < math.radians(0.3)


def test_a_cube_under_the_gripper_is_not_reported_as_found():
    with WorkCell() as cell:
        cell.add_cube("red", 0.5, 0.0, 0.2)
        cell.settle(0.1)
        script = ScriptedPickPlace(cell)
        # Hover over the cube, low enough for the gripper body to hide part of its face.
        script.move_to(gripper_down_pose(0.515, 0.0, 0.09, 0.2))
        detection = CubeDetector().detect(cell.camera.capture(), "red")
        assert detection.status in (DetectionStatus.PARTIAL, DetectionStatus.NOT_FOUND)
        assert detection.reason


def test_a_cube_off_the_edge_of_the_image_is_partial():
    with WorkCell() as cell:
        cell.add_cube("blue", 0.5, 0.46, 0.0)  # the image spans about y -0.45..0.45 m at the top faces
        cell.settle(0.1)
        detection = CubeDetector().detect(cell.camera.capture(), "blue")
        assert detection.status is DetectionStatus.PARTIAL
        assert "border" in detection.reason
