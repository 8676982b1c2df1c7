"""The paper's work cell, stated once: where its top camera is mounted, and the box the TCP works in.

The simulated cell (``bt_arrange_sim.config.CameraConfig``) is built from these figures, and a real
cell (``bt_arrange.ur``) starts from them as its nominal camera until ``bt-arrange calibrate`` measures
the real one. The world frame is the robot's base frame, the table top at z = 0.
"""

from __future__ import annotations

import math

import numpy as np

from bt_arrange.geometry import Pose, rotation_z
from bt_arrange.motion.safety import WorkspaceBox

#: The top camera (an Intel RealSense L515's RGB stream): image size and horizontal field of view.
CAMERA_WIDTH_PX = 1920
CAMERA_HEIGHT_PX = 1080
CAMERA_HORIZONTAL_FOV_DEG = 70.0
#: Its optical centre 70 cm above the table, over the middle of the parts' area (m, base frame).
CAMERA_POSITION_M = (0.5, 0.0, 0.70)
#: Its turn about the optical axis (deg): no mount is square to the table, and a few degrees give a
#: part's edges a staircase of pixels to measure below a pixel (``CameraConfig.roll_deg``).
CAMERA_ROLL_DEG = 3.0

#: The TCP stays over the table in front of the robot, above the table top and below the camera's mount.
WORKSPACE = WorkspaceBox(x_m=(0.10, 0.90), y_m=(-0.55, 0.55), z_m=(0.005, 0.65))


def camera_pose_world(
    position_m: tuple[float, float, float] = CAMERA_POSITION_M, roll_deg: float = CAMERA_ROLL_DEG
) -> Pose:
    """``T_W_C`` of a camera looking straight down (OpenCV optical frame: x right about world -y, y down about -x)."""
    square = np.array([[0.0, -1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
    return Pose.from_rotation(position_m, square @ rotation_z(math.radians(roll_deg)))
