"""bt-arrange: behaviour trees for precise robotic arrangement (pick, place, inspect, push)."""

from typing import TYPE_CHECKING, Any

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

if TYPE_CHECKING:
    from bt_arrange.xmltree.registry import register_node

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
    "register_node",
]


def __getattr__(name: str) -> Any:
    """``register_node``, imported when first asked for (the XML registry imports the behaviours and trees)."""
    if name == "register_node":
        from bt_arrange.xmltree.registry import register_node

        return register_node
    raise AttributeError(f"module 'bt_arrange' has no attribute {name!r}")
