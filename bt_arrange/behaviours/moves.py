"""What Pick, Place, Push and the guard share.

Stage planners (a joint move, a TCP line), the fingers' stages, the held part's widths and heights.
"""

from __future__ import annotations

import math

from bt_arrange.behaviours.base import GripperStage
from bt_arrange.behaviours.context import Context
from bt_arrange.geometry import FloatArray
from bt_arrange.motion import Motion, gripper_down_pose, nearest_symmetric_yaw
from bt_arrange.objects import CUBE, ObjectType
from bt_arrange.settings import ManipulationSettings
from bt_arrange.shapes import Grasp, preferred_grasp


def to_pose(x_m: float, y_m: float, z_m: float, yaw_rad: float):  # noqa: ANN202 - a planning function
    """A stage planner: a joint-space move to a gripper-down pose (fast, path free)."""

    def plan(context: Context, q: FloatArray) -> Motion:
        return context.planner.move_to_pose(q, gripper_down_pose(x_m, y_m, z_m, yaw_rad))

    return plan


def line_to(x_m: float, y_m: float, z_m: float, yaw_rad: float, pushing: bool = False):  # noqa: ANN202
    """A stage planner: a straight TCP line to a gripper-down pose (approach, descend, lift, push).

    ``pushing``: at the settings' push limits, slower than the planner's, so the cube does not slide on.
    """

    def plan(context: Context, q: FloatArray) -> Motion:
        limits = context.settings.push_limits if pushing else None
        return context.planner.move_line(q, gripper_down_pose(x_m, y_m, z_m, yaw_rad), cartesian_limits=limits)

    return plan


def axis_yaw_offset_rad(axis: str) -> float:
    """Gripper yaw minus the target's yaw for pads that close across the target frame's ``axis``."""
    return math.pi / 2 if axis == "y" else 0.0


def wrist_yaw_rad(context: Context) -> float:
    """The yaw of the wrist's last joint now (rad): a new grasp turns it the least."""
    return context.planner.kinematics.wrist_yaw_rad(context.robot.arm.joint_positions())


def holding(context: Context, object_type: ObjectType | None = None) -> bool:
    """True when the closed fingers still stand the held part's width apart (default: a cube's)."""
    return context.robot.gripper.width() > min_held_width_m(context.settings, object_type or CUBE)


def grasp_of(settings: ManipulationSettings, object_type: ObjectType) -> Grasp:
    """The grasp the pads take on a part: its shape's preferred one for the settings' gripper."""
    return preferred_grasp(object_type.shape, settings.gripper)


def free_grasp_pose(
    settings: ManipulationSettings, object_type: ObjectType, x_m: float, y_m: float, yaw_rad: float, wrist_rad: float
) -> tuple[float, float, float]:
    """The TCP's (x, y, gripper yaw) for the part's grasp with the part at ``(x, y, yaw)``, turning the wrist least.

    The grasp's yaw is taken modulo the shape's symmetry. A grasp centred on the part (a cuboid's)
    stands the TCP at the part's origin; an off-centre one (an irregular part's) at its centre,
    turned with the part. The gripper's own half turn is not taken: the part's turn in the pads
    is then the same at the pick and at the place, which each compute it from this alone.
    """
    grasp = grasp_of(settings, object_type)
    yaw = nearest_symmetric_yaw(yaw_rad + grasp.yaw_offset_rad, wrist_rad, object_type.shape.symmetry_rad)
    if grasp.centre_m == (0.0, 0.0):
        return x_m, y_m, yaw
    part_yaw = yaw - grasp.yaw_offset_rad  # the turn of the part, within its symmetry, this grasp is taken at
    c, s = math.cos(part_yaw), math.sin(part_yaw)
    cx, cy = grasp.centre_m
    return x_m + c * cx - s * cy, y_m + s * cx + c * cy, yaw


def min_held_width_m(settings: ManipulationSettings, object_type: ObjectType) -> float:
    """Fingers closed narrower than this hold nothing: the side grasped, less the tolerance."""
    return grasp_width_m(settings, object_type) - settings.grasp_width_tolerance_m


def grasp_width_m(settings: ManipulationSettings, object_type: ObjectType) -> float:
    """The width of the side the pads close on (m)."""
    return grasp_of(settings, object_type).width_m


def max_grip_width_m(settings: ManipulationSettings, object_type: ObjectType) -> float:
    """A grip wider than this holds the part turned (the settings' margin over the grasped side)."""
    return grasp_width_m(settings, object_type) + settings.turned_grip_margin_m


def heights_m(settings: ManipulationSettings, object_type: ObjectType) -> tuple[float, float, float]:
    """(grasp, approach, push) TCP heights for a part (``ManipulationSettings.tcp_heights_m``)."""
    return settings.tcp_heights_m(object_type.shape)


def open_stage(name: str, opening_m: float) -> GripperStage:
    """Open the fingers to ``opening_m`` and wait for them."""
    return GripperStage(name, lambda c: c.robot.gripper.open(opening_m))


def close_stage(name: str, force_n: float) -> GripperStage:
    """Close the fingers with ``force_n`` and wait for them to stop."""
    return GripperStage(name, lambda c: c.robot.gripper.close(force_n))
