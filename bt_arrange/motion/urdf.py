"""The robot description the motion package reads: where the bundled URDF lives, and its joint limits.

The URDF is parsed with the standard library here (no placo), so that limits can be built and
validated without loading a kinematic model.
"""

from __future__ import annotations

import importlib.resources
import xml.etree.ElementTree as ElementTree
from dataclasses import dataclass
from pathlib import Path

from bt_arrange.errors import MotionError

#: The six arm joints, in URDF order: every joint vector in ``bt_arrange.motion`` uses this order.
ARM_JOINT_NAMES: tuple[str, ...] = (
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "elbow_joint",
    "wrist_1_joint",
    "wrist_2_joint",
    "wrist_3_joint",
)

#: The gripper's prismatic finger joints: inverse kinematics never moves them.
FINGER_JOINT_NAMES: tuple[str, ...] = ("left_finger_joint", "right_finger_joint")

#: The frame a pose target refers to: between the finger pads, at mid-pad height.
TCP_FRAME = "tcp"


def default_urdf_path() -> Path:
    """Path of the bundled UR5 + 2F-85 URDF (``bt_arrange/descriptions/ur5_2f85.urdf``)."""
    resource = importlib.resources.files("bt_arrange.descriptions").joinpath("ur5_2f85.urdf")
    # The package ships as plain files (setuptools package-data), so the resource is a real path
    # that placo, which wants a file name, can open.
    return Path(str(resource))


@dataclass(frozen=True)
class UrdfJointLimits:
    """Position and velocity limits of the arm joints as written in a URDF, in ``ARM_JOINT_NAMES`` order."""

    lower_rad: tuple[float, ...]
    upper_rad: tuple[float, ...]
    velocity_rad_s: tuple[float, ...]


def read_joint_limits(urdf_path: str | Path | None = None) -> UrdfJointLimits:
    """Read the ``<limit lower upper velocity>`` of the six arm joints from a URDF.

    Raises ``MotionError`` when the file lacks an arm joint or a limit, because every motion
    check downstream relies on them.
    """
    path = Path(urdf_path) if urdf_path is not None else default_urdf_path()
    root = ElementTree.parse(path).getroot()
    joints = {joint.get("name"): joint for joint in root.iter("joint")}
    lower, upper, velocity = [], [], []
    for name in ARM_JOINT_NAMES:
        joint = joints.get(name)
        limit = joint.find("limit") if joint is not None else None
        if limit is None:
            raise MotionError(f"URDF {path} has no <limit> for arm joint {name}")
        try:
            lower.append(float(limit.attrib["lower"]))
            upper.append(float(limit.attrib["upper"]))
            velocity.append(float(limit.attrib["velocity"]))
        except (KeyError, ValueError) as error:
            raise MotionError(f"URDF {path}: joint {name} has an incomplete <limit>: {error}") from error
    return UrdfJointLimits(tuple(lower), tuple(upper), tuple(velocity))
