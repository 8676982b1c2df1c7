"""The devices' range checks: the framework's (``bt_arrange.ranges``), shared by every backend, re-exported here."""

from bt_arrange.ranges import (
    ARM_JOINT_COUNT,
    checked_grip_force_n,
    checked_gripper_speed_m_s,
    checked_gripper_width_m,
    checked_joint_setpoint,
    checked_joint_setpoint_lists,
    checked_render_offset,
)

__all__ = [
    "ARM_JOINT_COUNT",
    "checked_grip_force_n",
    "checked_gripper_speed_m_s",
    "checked_gripper_width_m",
    "checked_joint_setpoint",
    "checked_joint_setpoint_lists",
    "checked_render_offset",
]
