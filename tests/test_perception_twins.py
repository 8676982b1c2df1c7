"""Two cubes of one colour closer than a pixel (a pyramid's raised twin bumped towards its neighbour).

The corner pipeline cannot measure such a face: the two faces are one blob ("ambiguous"), or the
side facing the twin cannot be measured below a pixel ("partial"). Looked for around where it is
expected (Inspect's region of interest), the face is registered on its free edges instead, as a
prism's is (``bt_arrange.perception.outline_merged``); looked for anywhere, it stays ambiguous.
"""

from __future__ import annotations

import math

import pytest

from bt_arrange.behaviours.looking import EXPECTED_MARGIN_M, identical_roi_half_m
from bt_arrange.objects import CUBE
from bt_arrange.perception import DetectionStatus, PartDetector, WorldRegion
from bt_arrange.perception.synthetic import SyntheticCube, render_frame
from bt_arrange.robot import CameraFrame

#: The pyramid's green layer: twins 52 mm apart along y, the second bumped towards the first.
FIRST_XY_M = (0.5, -0.026)
TARGET_XY_M = (0.5, 0.026)


def twins(gap_mm: float, blur_px: float = 1.0):
    """The frame, and where the bumped twin lies: 2 mm off its target, ``gap_mm`` from the first."""
    y_m = FIRST_XY_M[1] + 0.05 + gap_mm / 1000
    bumped = (TARGET_XY_M[0] - 0.0015, y_m)
    cubes = [SyntheticCube("green", *FIRST_XY_M), SyntheticCube("green", *bumped)]
    return render_frame(cubes, blur_sigma_px=blur_px), bumped


def window_at_target(detector: PartDetector, frame: CameraFrame) -> CameraFrame:
    """The full-resolution window Inspect renders around the target (the frame's pixels there)."""
    half_m = 0.5 * math.hypot(0.05, 0.05) + EXPECTED_MARGIN_M
    window = detector.window_around(frame.intrinsics, frame.camera_pose_world, *TARGET_XY_M, half_m)
    assert window is not None
    rgb = frame.rgb[window.y_px : window.y_px + window.height_px, window.x_px : window.x_px + window.width_px]
    return CameraFrame(rgb.copy(), None, frame.intrinsics.windowed(window), frame.camera_pose_world, 0.0)


@pytest.mark.parametrize("gap_mm", [0.0, 0.3])
def test_a_cube_beside_its_twin_is_measured_on_its_free_edges_where_it_is_expected(gap_mm) -> None:
    frame, (x_m, y_m) = twins(gap_mm)
    detector = PartDetector()
    # As Inspect looks among identical parts: a window around the target, the face's centre near it.
    window = window_at_target(detector, frame)
    detection = detector.detect(window, "green", roi=WorldRegion.around(*TARGET_XY_M, identical_roi_half_m(CUBE)))
    assert detection.found, detection.reason
    pose = detection.pose_world
    assert 1000 * math.hypot(pose.x_m - x_m, pose.y_m - y_m) < 0.1
    assert abs(math.degrees(pose.yaw_rad)) < 0.2
    # Anywhere (no expected place) the blob is two faces' or one face's edge is not measurable: not found.
    anywhere = detector.detect(frame, "green")
    assert anywhere.status in (DetectionStatus.AMBIGUOUS, DetectionStatus.PARTIAL), anywhere.reason
