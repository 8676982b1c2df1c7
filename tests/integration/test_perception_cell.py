"""Perception on frames rendered by the pybullet cell, checked against its ground truth."""

import math

import numpy as np
import pytest

from bt_arrange.geometry import fold_yaw
from bt_arrange.motion import gripper_down_pose
from bt_arrange.perception import DetectionStatus, PartDetector
from bt_arrange.robot import PixelWindow
from bt_arrange_sim.config import CellConfig
from bt_arrange_sim.noise import CameraNoiseConfig
from bt_arrange_sim.pybullet.cell import WorkCell
from bt_arrange_sim.pybullet.scripted import ScriptedPickPlace

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
        detections = PartDetector().detect_all(cell.camera.capture())
        for colour, *_ in SCENE:
            detection = detections[colour]
            assert detection.found, detection.reason
            true_x, true_y, true_yaw = cell.part_planar_truth(colour)
            assert math.hypot(detection.planar.x_m - true_x, detection.planar.y_m - true_y) < 0.2e-3
            assert abs(fold_yaw(detection.planar.yaw_rad - true_yaw)) < math.radians(0.3)


def test_a_cube_under_the_gripper_is_not_reported_as_found():
    with WorkCell() as cell:
        cell.add_cube("red", 0.5, 0.0, 0.2)
        cell.settle(0.1)
        script = ScriptedPickPlace(cell)
        # Hover over the cube, low enough for the gripper body to hide part of its face.
        script.move_to(gripper_down_pose(0.515, 0.0, 0.09, 0.2))
        detection = PartDetector().detect(cell.camera.capture(), "red")
        assert detection.status in (DetectionStatus.PARTIAL, DetectionStatus.NOT_FOUND)
        assert detection.reason


def test_a_cube_off_the_edge_of_the_image_is_partial():
    with WorkCell() as cell:
        cell.add_cube("blue", 0.5, 0.46, 0.0)  # the image spans about y -0.45..0.45 m at the top faces
        cell.settle(0.1)
        detection = PartDetector().detect(cell.camera.capture(), "blue")
        assert detection.status is DetectionStatus.PARTIAL
        assert "border" in detection.reason


# -- windows: render only what a detection needs ------------------------------------------------


@pytest.mark.parametrize("noise", [False, True], ids=["clean", "noisy"])
def test_a_window_has_the_full_frames_pixels_and_gives_its_detection(noise):
    # With noise, each frame draws its own noise: the pixels differ, the detections must not (much).
    config = CellConfig(camera_noise=CameraNoiseConfig.realistic(seed=2) if noise else CameraNoiseConfig())
    with WorkCell(config) as cell:
        for colour, x, y, yaw in SCENE:
            cell.add_cube(colour, x, y, yaw)
        cell.settle(0.1)
        camera, detector = cell.camera, PartDetector()
        full = camera.capture(with_depth=True)
        for colour, x, y, _ in SCENE:
            window = detector.window_around(camera.intrinsics, camera.pose_world, x, y, 0.05)
            assert window is not None
            part = camera.capture(with_depth=True, window=window)
            assert part.rgb.shape == (window.height_px, window.width_px, 3)
            assert part.intrinsics.cx_px == pytest.approx(camera.intrinsics.cx_px - window.x_px)
            assert part.intrinsics.cy_px == pytest.approx(camera.intrinsics.cy_px - window.y_px)
            rows = slice(window.y_px, window.y_px + window.height_px)
            columns = slice(window.x_px, window.x_px + window.width_px)
            if not noise:
                np.testing.assert_array_equal(part.rgb, full.rgb[rows, columns])
            np.testing.assert_allclose(part.depth_m, full.depth_m[rows, columns], atol=1e-5)
            in_full, in_window = detector.detect(full, colour), detector.detect(part, colour)
            assert in_full.found and in_window.found, in_window.reason
            shift_mm = 1000 * math.dist(
                (in_full.planar.x_m, in_full.planar.y_m), (in_window.planar.x_m, in_window.planar.y_m)
            )
            assert shift_mm < (0.01 if not noise else 0.1)
            if not noise:
                assert abs(fold_yaw(in_full.planar.yaw_rad - in_window.planar.yaw_rad)) < math.radians(0.01)


def test_a_binned_full_view_locates_every_cube_within_two_millimetres():
    with WorkCell() as cell:
        for colour, x, y, yaw in SCENE:
            cell.add_cube(colour, x, y, yaw)
        cell.settle(0.1)
        camera, detector = cell.camera, PartDetector()
        binning = detector.search_binning(camera.intrinsics, camera.pose_world)
        assert binning == 8
        search = camera.capture(window=PixelWindow.full(camera.intrinsics, binning))
        assert search.rgb.shape == (135, 240, 3)
        for colour, *_ in SCENE:
            (located,) = detector.locate(search, colour)
            true_x, true_y, _ = cell.part_planar_truth(colour)
            assert 1000 * math.dist(located, (true_x, true_y)) < 2.0
