"""The undistortion path: a lens-distorted frame measured through a calibration's distortion is right again."""

from __future__ import annotations

import math

import cv2
import numpy as np

from bt_arrange.calibration import CalibratedCamera, CameraCalibration
from bt_arrange.perception import PartDetector
from bt_arrange.perception.synthetic import SyntheticCube, render_frame, sim_intrinsics, top_down_camera_pose
from bt_arrange.robot import CameraFrame, CameraIntrinsics, PixelWindow

DISTORTION = (-0.12, 0.06, 8e-4, -5e-4, 0.0)


def _distorted(frame: CameraFrame, distortion: tuple[float, ...]) -> CameraFrame:
    """The pinhole frame as a lens with ``distortion`` would image it (each output pixel's ray sampled)."""
    k = frame.intrinsics
    height, width = frame.rgb.shape[:2]
    u, v = np.meshgrid(np.arange(width, dtype=np.float64), np.arange(height, dtype=np.float64))
    grid = np.stack([u, v], axis=-1).reshape(-1, 1, 2)
    pinhole = cv2.undistortPoints(grid, k.matrix, np.asarray(distortion), P=k.matrix).reshape(height, width, 2)
    rgb = cv2.remap(frame.rgb, pinhole[..., 0].astype(np.float32), pinhole[..., 1].astype(np.float32),
                    cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)  # fmt: skip
    return CameraFrame(np.ascontiguousarray(rgb), None, k, frame.camera_pose_world, 0.0)


class _Camera:
    """A camera that always shows one frame (windows cut from it)."""

    def __init__(self, frame: CameraFrame) -> None:
        self.frame = frame

    @property
    def intrinsics(self) -> CameraIntrinsics:
        return self.frame.intrinsics

    @property
    def pose_world(self):  # noqa: ANN201
        return self.frame.camera_pose_world

    def capture(self, with_depth: bool = False, window: PixelWindow | None = None) -> CameraFrame:
        if window is None:
            return self.frame
        rgb = self.frame.rgb[window.y_px : window.y_px + window.height_px, window.x_px : window.x_px + window.width_px]
        return CameraFrame(np.ascontiguousarray(rgb), None, self.frame.intrinsics.windowed(window),
                           self.frame.camera_pose_world, 0.0)  # fmt: skip


def test_a_calibrations_distortion_undoes_the_lens_and_the_nominal_pinhole_does_not() -> None:
    # Far from the optical axis, where the lens moves the face most (0.35 m off: about 15 px here).
    truth = SyntheticCube("red", 0.36, 0.30, math.radians(17.0))
    pose = top_down_camera_pose()
    pinhole = render_frame([truth], sim_intrinsics(), pose)
    lens = _distorted(pinhole, DISTORTION)
    detector = PartDetector()
    calibration = CameraCalibration(
        intrinsics=CameraIntrinsics(**{**sim_intrinsics().__dict__, "distortion": DISTORTION}),
        camera_to_base=pose,
        reprojection_error_px=0.1,
        views=20,
    )
    camera = CalibratedCamera(_Camera(lens), calibration)
    full = detector.detect(camera.capture(), "red")
    window = detector.window_around(camera.intrinsics, camera.pose_world, truth.x_m, truth.y_m, 0.05)
    assert window is not None
    windowed = detector.detect(camera.capture(window=window), "red")
    nominal = detector.detect(lens, "red")
    for detection in (full, windowed):
        assert detection.found and detection.pose_world is not None, detection.reason

    def error_mm(d) -> float:  # noqa: ANN001
        return math.hypot(d.pose_world.x_m - truth.x_m, d.pose_world.y_m - truth.y_m) * 1000

    assert error_mm(full) < 0.15, error_mm(full)
    assert error_mm(windowed) < 0.15, error_mm(windowed)
    # Without the distortion the lens shrinks the face (4.8 cm: refused) or puts it millimetres off.
    assert not nominal.found or error_mm(nominal) > 2.0, nominal.reason
    assert np.allclose(camera.capture(window=window).intrinsics.distortion, DISTORTION)
