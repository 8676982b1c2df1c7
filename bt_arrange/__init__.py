"""bt-arrange: behaviour trees for precise robotic arrangement (pick, place, inspect, push)."""

from bt_arrange.errors import (
    BtArrangeError,
    MotionError,
    OutOfRangeError,
    PerceptionError,
    PlanError,
    TreeFileError,
    UnreachableError,
)
from bt_arrange.geometry import PlanarPose, Pose
from bt_arrange.robot import Arm, Camera, CameraFrame, CameraIntrinsics, Clock, Gripper, Robot

__version__ = "0.1.0"

__all__ = [
    "Arm",
    "BtArrangeError",
    "Camera",
    "CameraFrame",
    "CameraIntrinsics",
    "Clock",
    "Gripper",
    "MotionError",
    "OutOfRangeError",
    "PerceptionError",
    "PlanError",
    "PlanarPose",
    "Pose",
    "Robot",
    "TreeFileError",
    "UnreachableError",
]
