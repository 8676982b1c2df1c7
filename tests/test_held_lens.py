"""The held look through a calibrated lens: the distortion taken out before the outline goes onto its plane."""

from __future__ import annotations

import dataclasses
import math

import cv2
import numpy as np
import pytest

from bt_arrange.geometry import PlanarPose
from bt_arrange.objects import ObjectType
from bt_arrange.paper_cell import camera_pose_world
from bt_arrange.perception.colours import DEFAULT_COLOUR_TABLE
from bt_arrange.perception.held import measure_held
from bt_arrange.perception.outline_fit import OutlineModel, pixels_on_plane
from bt_arrange.perception.pose import distorted, undistorted
from bt_arrange.robot import CameraFrame, CameraIntrinsics, PixelWindow
from bt_arrange.shapes import Prism

PIECE = ObjectType(
    "piece", shape=Prism.from_outline([[0, 0], [0.06, 0], [0.065, 0.03], [0.03, 0.055], [-0.005, 0.035]], 0.02)
)
PLANE_Z_M = 0.12
#: The calibrated real-cell model's lens (bt-arrange calibrate --cell real): k1, k2, p1, p2, k3.
LENS = (-0.12052, 0.06097, 0.00099, -0.00053, 0.0)
T_W_C = camera_pose_world((0.5, 0.0, 0.7), 3.0)
#: A window 0.3 m off the camera's axis, where the held look stands (about 700 px from the image centre).
WINDOW = PixelWindow(1500, 300, 400, 400)


def _intrinsics(distortion: tuple[float, ...]) -> CameraIntrinsics:
    full = dataclasses.replace(CameraIntrinsics.from_fov(1920, 1080, 70.0), distortion=distortion)
    return full.windowed(WINDOW)


def _frame(part: PlanarPose, distortion: tuple[float, ...]) -> CameraFrame:
    """The part's top face (red) at ``PLANE_Z_M`` over the grey table, seen through ``distortion``."""
    intrinsics = _intrinsics(distortion)
    v, u = np.mgrid[0 : WINDOW.height_px, 0 : WINDOW.width_px]
    raw = np.column_stack([u.ravel(), v.ravel()]).astype(float)
    # Each raw pixel sees the ray of its pinhole pixel: the lens bends it there.
    on_face = pixels_on_plane(intrinsics, T_W_C, undistorted(intrinsics, raw), PLANE_Z_M)
    outline = OutlineModel.of(PIECE).posed(part.x_m, part.y_m, part.yaw_rad).astype(np.float32)
    inside = np.array([cv2.pointPolygonTest(outline, (float(x), float(y)), False) >= 0 for x, y in on_face])
    camera_z = float(T_W_C.position_m[2])
    rgb = np.full((len(raw), 3), 110, np.uint8)
    depth = np.full(len(raw), camera_z, np.float32)
    rgb[inside] = (204, 20, 20)
    depth[inside] = camera_z - PLANE_Z_M
    shape = (WINDOW.height_px, WINDOW.width_px)
    return CameraFrame(rgb.reshape(*shape, 3), depth.reshape(shape), intrinsics, T_W_C, 0.0)


def _piece_in_view() -> PlanarPose:
    centre = pixels_on_plane(_intrinsics(()), T_W_C, np.array([[200.0, 200.0]]), PLANE_Z_M)[0]
    return PlanarPose(float(centre[0]), float(centre[1]), 0.4)


def test_distorted_undoes_undistorted_and_a_plain_pinhole_is_left_alone() -> None:
    intrinsics = _intrinsics(LENS)
    raw = np.array([[10.0, 20.0], [200.0, 200.0], [390.0, 380.0]])
    pinhole = undistorted(intrinsics, raw)
    assert np.abs(pinhole - raw).max() > 5.0, "700 px off the centre the lens moves a pixel several pixels"
    assert distorted(intrinsics, pinhole) == pytest.approx(raw, abs=0.01)
    plain = _intrinsics((0.0, 0.0, 0.0, 0.0, 0.0))
    assert undistorted(plain, raw) is raw and distorted(plain, raw) is raw


def test_a_held_part_seen_through_the_lens_is_measured_where_it_is() -> None:
    truth = _piece_in_view()
    measured = measure_held(_frame(truth, LENS), DEFAULT_COLOUR_TABLE["red"], OutlineModel.of(PIECE), PLANE_Z_M, truth)
    assert measured.trusted, measured.reason
    assert measured.pose is not None
    # Without the distortion taken out, 5 mm or more off towards the camera's axis (the real-cell model's looks).
    assert math.hypot(measured.pose.x_m - truth.x_m, measured.pose.y_m - truth.y_m) < 0.0006
    assert abs(math.degrees(measured.pose.yaw_rad - truth.yaw_rad)) < 0.3
