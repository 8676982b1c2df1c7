"""A camera seen through its calibration: the ``Camera`` a run's behaviours use with ``--calibration``.

``CalibratedCamera`` wraps the world's camera and reports the calibration's intrinsics (with the
lens distortion) and camera-to-base pose instead of the camera's own nominal ones, on the camera
and on every frame it takes (a window's intrinsics are the calibration's, windowed). The detector
then undistorts the corner points (``PartDetector`` reads ``intrinsics.distortion``) and maps them
to the table through the calibrated pose. The image itself is untouched.
"""

from __future__ import annotations

import dataclasses

from bt_arrange.calibration.file import CameraCalibration, check_image_size
from bt_arrange.geometry import Pose
from bt_arrange.robot import Camera, CameraFrame, CameraIntrinsics, PixelWindow


class CalibratedCamera:
    """``camera`` with ``calibration``'s intrinsics, distortion and pose.

    A ``PlanError`` when the calibration was made for another image size.
    """

    def __init__(self, camera: Camera, calibration: CameraCalibration) -> None:
        check_image_size(calibration, camera.intrinsics.width_px, camera.intrinsics.height_px)
        self.camera = camera
        self.calibration = calibration

    @property
    def intrinsics(self) -> CameraIntrinsics:
        """The calibrated intrinsics of the full image (with the distortion)."""
        return self.calibration.intrinsics

    @property
    def pose_world(self) -> Pose:
        """The calibrated camera-to-base pose ``T_W_C`` (the base frame is the world frame)."""
        return self.calibration.camera_to_base

    def capture(self, with_depth: bool = False, window: PixelWindow | None = None) -> CameraFrame:
        """The camera's frame, reported with the calibrated intrinsics (windowed) and pose."""
        frame = self.camera.capture(with_depth=with_depth, window=window)
        intrinsics = self.intrinsics if window is None else self.intrinsics.windowed(window)
        return dataclasses.replace(frame, intrinsics=intrinsics, camera_pose_world=self.pose_world)
