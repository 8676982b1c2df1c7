"""What Pick, Place, Push and the guard share.

Stage planners (a joint move, a TCP line), the fingers' stages, the held part's widths and heights.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from py_trees.common import Status

from bt_arrange.behaviours.base import GripperStage
from bt_arrange.behaviours.context import Context
from bt_arrange.geometry import FloatArray, Pose
from bt_arrange.motion import GRIPPER_SYMMETRY_RAD, LinearMotion, Motion, gripper_down_pose, nearest_symmetric_yaw
from bt_arrange.motion.bounds import joint_move_bound_s
from bt_arrange.objects import CUBE, ObjectType
from bt_arrange.settings import ManipulationSettings
from bt_arrange.shapes import Grasp, preferred_grasp


class JointMovePlan:
    """A stage planner for a joint-space move; it may start from a moving arm (``moving_start``).

    ``target(context)`` gives the goal: a TCP pose (solved by IK from the start) or a joint vector.
    ``free``: the pads hold nothing, so the move runs at the settings' free-space limits
    (``free_joint_limits``, the UR5's joint speeds); ``carrying``: the carry of a held part
    (``carry_joint_limits``); otherwise at the planner's limits.
    """

    #: ``MoveStage`` may call it with a handed-on motion's velocities and accelerations.
    moving_start = True

    def __init__(
        self,
        target: Callable[[Context], Pose | FloatArray],
        free: bool = False,
        carrying: bool = False,
        via_home: bool = False,
    ) -> None:
        """Move to ``target(context)`` (read when the move starts).

        ``via_home``: the move is followed by one home (a look): its last wrist joint takes whichever
        way round, a whole turn either side, that makes the two moves the shortest (``toward_home_q``).
        """
        self._target = target
        self._free = free
        self._carrying = carrying
        self._via_home = via_home

    def __call__(
        self,
        context: Context,
        q: FloatArray,
        velocities_rad_s: FloatArray | None = None,
        accelerations_rad_s2: FloatArray | None = None,
    ) -> Motion:
        """The move from ``q`` (at rest, or moving at the given rates: a motion handed on)."""
        s = context.settings
        limits = s.free_joint_limits if self._free else s.carry_joint_limits if self._carrying else None
        target = self._target(context)
        if isinstance(target, Pose) and self._via_home:
            target = toward_home_q(context, q, context.planner.kinematics.inverse(target, q))
        if isinstance(target, Pose):
            return context.planner.move_to_pose(
                q,
                target,
                start_velocities_rad_s=velocities_rad_s,
                start_accelerations_rad_s2=accelerations_rad_s2,
                joint_limits=limits,
            )
        return context.planner.move_joints(
            q, target, velocities_rad_s, start_accelerations_rad_s2=accelerations_rad_s2, joint_limits=limits
        )


def to_pose(
    x_m: float,
    y_m: float,
    z_m: float,
    yaw_rad: float,
    free: bool = False,
    carrying: bool = False,
    via_home: bool = False,
) -> JointMovePlan:
    """A stage planner: a joint-space move to a gripper-down pose (fast, path free; ``JointMovePlan``)."""
    pose = gripper_down_pose(x_m, y_m, z_m, yaw_rad)
    return JointMovePlan(lambda context: pose, free=free, carrying=carrying, via_home=via_home)


def toward_home_q(context: Context, start_q: FloatArray, target_q: FloatArray) -> FloatArray:
    """``target_q``, or it with the last wrist joint a whole turn either way: the one soonest reached and left home.

    The TCP's pose is the same for all three. Costed by the moves' lower bounds at the free-space
    limits (``bt_arrange.motion.bounds``), from ``start_q`` and then to ``context.home_q``; a turn
    outside the joint's limits is not taken, and ``target_q`` wins a tie.
    """
    limits = context.settings.free_joint_limits
    wrist = len(target_q) - 1
    best, best_s = target_q, math.inf
    for turns in (0, -1, 1):
        q = np.array(target_q, dtype=float)
        q[wrist] += 2.0 * math.pi * turns
        if not limits.lower_rad[wrist] <= q[wrist] <= limits.upper_rad[wrist]:
            continue
        seconds = joint_move_bound_s(start_q, q, limits) + joint_move_bound_s(q, context.home_q, limits)
        if seconds < best_s - 1e-9:
            best, best_s = q, seconds
    return best


def half_turn_free(object_type: ObjectType) -> bool:
    """True when the part looks the same turned half a turn (a cuboid): the gripper's own half turn is then free."""
    return object_type.shape.symmetry_rad <= GRIPPER_SYMMETRY_RAD + 1e-9


def line_nearly_done(remaining_m: float | None = None) -> Callable[[Context, Motion], bool]:
    """A ``MoveStage`` hand-on: a line passes its last ``remaining_m`` at speed into the next (joint) move.

    ``None``: the settings' ``hand_on_remaining_m``, read when the line runs.
    """

    def hand_on(context: Context, motion: Motion) -> bool:
        distance_m = context.settings.hand_on_remaining_m if remaining_m is None else remaining_m
        return isinstance(motion, LinearMotion) and motion.remaining_m <= distance_m

    return hand_on


def line_to(  # noqa: ANN201 - a planning function
    x_m: float, y_m: float, z_m: float, yaw_rad: float, pushing: bool = False, free: bool = False, gentle: bool = False
):
    """A stage planner: a straight TCP line to a gripper-down pose (approach, descend, lift, push).

    ``pushing``: at the settings' push limits, slower than the planner's, so the part does not slide on;
    ``gentle`` with it: at ``raised_push_limits``, for a part standing on others.
    ``free``: the pads hold nothing and touch nothing on the way (down to a part, up from a released
    one): at the settings' free-space line and joint limits.
    """

    def plan(context: Context, q: FloatArray) -> Motion:
        s = context.settings
        if pushing:
            limits = s.raised_push_limits if gentle else s.push_limits
            return context.planner.move_line(q, gripper_down_pose(x_m, y_m, z_m, yaw_rad), cartesian_limits=limits)
        if free:
            return context.planner.move_line(
                q,
                gripper_down_pose(x_m, y_m, z_m, yaw_rad),
                cartesian_limits=s.free_line_limits,
                joint_limits=s.free_joint_limits,
            )
        return context.planner.move_line(q, gripper_down_pose(x_m, y_m, z_m, yaw_rad))

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
    settings: ManipulationSettings,
    object_type: ObjectType,
    x_m: float,
    y_m: float,
    yaw_rad: float,
    wrist_rad: float,
    half_turn: bool = False,
) -> tuple[float, float, float]:
    """The TCP's (x, y, gripper yaw) for the part's grasp with the part at ``(x, y, yaw)``, turning the wrist least.

    The grasp's yaw is taken modulo the shape's symmetry. A grasp centred on the part (a cuboid's)
    stands the TCP at the part's origin; an off-centre one (an irregular part's) at its centre,
    turned with the part. ``half_turn``: the gripper turned half a turn on the same grasp (the pads
    swap sides; the same for a cuboid). Pick chooses it (``/<obj>/grasp_half_turn``) and Place
    reads it, so the part's turn in the pads is the same at the pick and at the place.
    """
    grasp = grasp_of(settings, object_type)
    turn_rad = math.pi if half_turn else 0.0
    yaw = nearest_symmetric_yaw(yaw_rad + grasp.yaw_offset_rad + turn_rad, wrist_rad, object_type.shape.symmetry_rad)
    if grasp.centre_m == (0.0, 0.0):
        return x_m, y_m, yaw
    # The turn of the part, within its symmetry, this grasp is taken at.
    part_yaw = yaw - grasp.yaw_offset_rad - turn_rad
    c, s = math.cos(part_yaw), math.sin(part_yaw)
    cx, cy = grasp.centre_m
    return x_m + c * cx - s * cy, y_m + s * cx + c * cy, yaw


def centred_grasp(settings: ManipulationSettings, object_type: ObjectType) -> bool:
    """True when the pads hold the part through its centre (a cuboid's): its inertia puts no torque on the grip."""
    return grasp_of(settings, object_type).centre_m == (0.0, 0.0)


def min_held_width_m(settings: ManipulationSettings, object_type: ObjectType) -> float:
    """Fingers closed narrower than this hold nothing: the side grasped, less the tolerance."""
    return grasp_width_m(settings, object_type) - settings.grasp_width_tolerance_m


def grasp_width_m(settings: ManipulationSettings, object_type: ObjectType) -> float:
    """The width of the side the pads close on (m)."""
    return grasp_of(settings, object_type).width_m


def max_grip_width_m(settings: ManipulationSettings, object_type: ObjectType) -> float:
    """A grip wider than this holds the part turned (the settings' margin over the grasped side)."""
    return grasp_width_m(settings, object_type) + settings.turned_grip_margin_m


def heights_m(settings: ManipulationSettings, object_type: ObjectType, z_m: float = 0.0) -> tuple[float, float, float]:
    """(grasp, approach, push) TCP heights for a part (``ManipulationSettings.tcp_heights_m``).

    ``z_m``: the part's bottom face above the table (a raised part, ``bt_arrange.plan.stacking.heights_at_m``).
    """
    from bt_arrange.plan.stacking import heights_at_m

    return heights_at_m(settings, object_type.shape, z_m)


def open_stage(name: str, opening_m: float) -> GripperStage:
    """Open the fingers to ``opening_m`` and wait for them."""
    return GripperStage(name, lambda c: c.robot.gripper.open(opening_m))


def close_stage(
    name: str, force_n: float, squaring: bool = False, slow_from_m: Callable[[Context], float] | None = None
) -> GripperStage:
    """Close the fingers with ``force_n`` and wait for them to stop.

    At the settings' ``finger_speed_m_s``; a close that squares a part pinched across its corners
    (``squaring``) at ``squaring_finger_speed_m_s``, slower: the pads turn the part as they meet it.
    ``slow_from_m`` (with ``squaring``): the opening (m) above which the fingers still run at full
    speed; they slow to the squaring speed once it is reached, before the pads meet the part.
    """
    if slow_from_m is not None and squaring:
        return TwoSpeedClose(name, force_n, slow_from_m)

    def close(context: Context) -> None:
        s = context.settings
        context.robot.gripper.close(force_n, speed_m_s=s.squaring_finger_speed_m_s if squaring else s.finger_speed_m_s)

    return GripperStage(name, close)


class TwoSpeedClose(GripperStage):
    """A close at the fingers' full speed down to an opening, then at the squaring speed until they stop.

    The pads cross the free stroke fast and meet the part slowly: the gentle close of a part held
    off its centre (``Pick``), at a fraction of its time. Fingers that stop before they reach the
    opening (a part met early) end the stage as any close does.
    """

    def __init__(self, name: str, force_n: float, slow_from_m: Callable[[Context], float]) -> None:
        super().__init__(name, self._close_fast)
        self._force_n = force_n
        self._slow_from_m = slow_from_m
        self._slow_below_m = 0.0
        self._slowed = False

    def _close_fast(self, context: Context) -> None:
        s, gripper = context.settings, context.robot.gripper
        self._slow_below_m = self._slow_from_m(context)
        self._slowed = gripper.width() <= self._slow_below_m
        gripper.close(self._force_n, speed_m_s=s.squaring_finger_speed_m_s if self._slowed else s.finger_speed_m_s)

    def poll(self, context: Context) -> Status:
        """Slow down once the opening is reached; SUCCESS once the fingers stand still."""
        gripper = context.robot.gripper
        if self._commanded and not self._slowed and gripper.width() <= self._slow_below_m:
            gripper.close(self._force_n, speed_m_s=context.settings.squaring_finger_speed_m_s)
            self._slowed = True
        return super().poll(context)


def slow_close_from_m(settings: ManipulationSettings, object_type: ObjectType) -> float:
    """The opening (m) a close that meets the part slowly slows at: the grasped side and the clearance each side."""
    return grasp_width_m(settings, object_type) + 2.0 * settings.slow_close_clearance_per_side_m


def pick_opening_m(settings: ManipulationSettings, object_type: ObjectType) -> float:
    """How far a pick of a part held off its centre opens: its grasped side and the pick clearance each side."""
    held_m = grasp_width_m(settings, object_type)
    return min(settings.open_width_m, held_m + 2.0 * settings.off_centre_pick_clearance_per_side_m)


def release_opening_m(settings: ManipulationSettings, object_type: ObjectType) -> float:
    """How far a release opens the pads: the held side plus the release clearance each side, within the stroke."""
    held_m = grasp_width_m(settings, object_type)
    return min(settings.open_width_m, held_m + 2.0 * settings.release_clearance_per_side_m)


def release_clearance_m(settings: ManipulationSettings, z_m: float) -> float:
    """How far above its support (m) a part is let go: ``release_clearance_m``, on parts ``raised_release_clearance_m``.

    The larger of the two on parts, so an injected release height (``release_height``) still counts.
    """
    if z_m <= 0.0:
        return settings.release_clearance_m
    return max(settings.release_clearance_m, settings.raised_release_clearance_m)
