"""Motion for the UR5 + 2F-85: placo inverse kinematics and ruckig jerk-limited trajectories.

``ArmKinematics`` maps joint vectors to TCP poses and back; ``MotionPlanner`` turns a start joint
vector and a target into a ``Motion`` (``JointMotion`` or ``LinearMotion``) that a behaviour
advances one control period per tick with ``step()`` and can halt with ``stop()``.
See docs/motion.md.
"""

from bt_arrange.motion.kinematics import (
    CUBE_SYMMETRY_RAD,
    DEFAULT_HOME_Q,
    DEFAULT_TABLE_CLEARANCE_M,
    GRIPPER_SYMMETRY_RAD,
    ORIENTATION_TOLERANCE_RAD,
    PAD_HALF_HEIGHT_M,
    POSITION_TOLERANCE_M,
    ArmKinematics,
    gripper_down_pose,
    gripper_down_rotation,
    nearest_symmetric_yaw,
    rotation_angle_rad,
)
from bt_arrange.motion.limits import CartesianLimits, JointLimits
from bt_arrange.motion.planner import MotionPlanner
from bt_arrange.motion.trajectory import JointMotion, JointSetpoint, LinearMotion, Motion
from bt_arrange.motion.urdf import ARM_JOINT_NAMES, TCP_FRAME, default_urdf_path

__all__ = [
    "ARM_JOINT_NAMES",
    "CUBE_SYMMETRY_RAD",
    "DEFAULT_HOME_Q",
    "DEFAULT_TABLE_CLEARANCE_M",
    "GRIPPER_SYMMETRY_RAD",
    "ORIENTATION_TOLERANCE_RAD",
    "PAD_HALF_HEIGHT_M",
    "POSITION_TOLERANCE_M",
    "TCP_FRAME",
    "ArmKinematics",
    "CartesianLimits",
    "JointLimits",
    "JointMotion",
    "JointSetpoint",
    "LinearMotion",
    "Motion",
    "MotionPlanner",
    "default_urdf_path",
    "gripper_down_pose",
    "gripper_down_rotation",
    "nearest_symmetric_yaw",
    "rotation_angle_rad",
]
