"""Behaviours that handle a cube: Pick, Place and Push, and the guard that watches a grasp."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import py_trees
from py_trees.common import Status

from bt_arrange.behaviours import keys
from bt_arrange.behaviours import stages as stage
from bt_arrange.behaviours.base import GripperStage, InstantStage, MoveStage, OnlyIf, Stage, StagedBehaviour
from bt_arrange.behaviours.context import Context
from bt_arrange.errors import BtArrangeError
from bt_arrange.geometry import FloatArray, PlanarPose, Pose, fold_yaw, rotation_z
from bt_arrange.layout import DIRECTIONS, Release
from bt_arrange.motion import GRIPPER_SYMMETRY_RAD, Motion, gripper_down_pose, nearest_symmetric_yaw
from bt_arrange.objects import CUBE, ObjectType
from bt_arrange.settings import ManipulationSettings


def _to_pose(x_m: float, y_m: float, z_m: float, yaw_rad: float):  # noqa: ANN202 - a planning function
    """A stage planner: a joint-space move to a gripper-down pose (fast, path free)."""

    def plan(context: Context, q: FloatArray) -> Motion:
        return context.planner.move_to_pose(q, gripper_down_pose(x_m, y_m, z_m, yaw_rad))

    return plan


def _line_to(x_m: float, y_m: float, z_m: float, yaw_rad: float, pushing: bool = False):  # noqa: ANN202
    """A stage planner: a straight TCP line to a gripper-down pose (approach, descend, lift, push).

    ``pushing``: at the settings' push limits, slower than the planner's, so the cube does not slide on.
    """

    def plan(context: Context, q: FloatArray) -> Motion:
        limits = context.settings.push_limits if pushing else None
        return context.planner.move_line(q, gripper_down_pose(x_m, y_m, z_m, yaw_rad), cartesian_limits=limits)

    return plan


def _axis_yaw_offset_rad(axis: str) -> float:
    """Gripper yaw minus the target's yaw for pads that close across the target frame's ``axis``."""
    return math.pi / 2 if axis == "y" else 0.0


def _wrist_yaw(context: Context) -> float:
    return context.planner.kinematics.wrist_yaw_rad(context.robot.arm.joint_positions())


def holding(context: Context, object_type: ObjectType | None = None) -> bool:
    """True when the closed fingers still stand the held part's width apart (default: a cube's)."""
    return context.robot.gripper.width() > min_held_width_m(context.settings, object_type or CUBE)


def min_held_width_m(settings: ManipulationSettings, object_type: ObjectType) -> float:
    """Fingers closed narrower than this hold nothing: the side grasped, less the tolerance."""
    return _grasp_width_m(settings, object_type) - settings.grasp_width_tolerance_m


def _grasp_width_m(settings: ManipulationSettings, object_type: ObjectType) -> float:
    return settings.cube_edge_m if object_type == CUBE else object_type.grasp_width_m


def max_grip_width_m(settings: ManipulationSettings, object_type: ObjectType) -> float:
    """A grip wider than this holds the part turned (the cube's margin over its edge, for any side)."""
    return _grasp_width_m(settings, object_type) + (settings.max_grip_width_m - settings.cube_edge_m)


def heights_m(settings: ManipulationSettings, object_type: ObjectType) -> tuple[float, float, float]:
    """(grasp, approach, push) TCP heights for a part: the settings' for the cube, moved by the part's height.

    The grasp holds the part through its centre of mass where the pads allow
    (``ObjectType.grasp_height_m``); moves above the table rise with a taller part.
    """
    shift_m = object_type.grasp_height_m - CUBE.grasp_height_m
    return (
        settings.grasp_height_m + shift_m,
        object_type.approach_height_m(settings.approach_height_m),
        settings.push_height_m + shift_m,
    )


#: Pick's success feedback holds this when it squared a cube it had pinched across its corners.
SQUARED_FEEDBACK = "squared from a"


class Pick(StagedBehaviour):
    """Grasp the object at its measured pose (``/<obj>/pose``) and lift it.

    Approach above it with the pads square to its faces, descend, close with a force limit,
    check from the finger width that the pads hold the cube across two faces, lift. A bad grasp
    (nothing between the pads, or a cube turned so the pads meet its corners) lets go before
    lifting and fails with the width, so a retry can look and pick again.

    A grip wider than ``max_grip_width_m`` (the pads pinch two vertical edges of a cube turned
    about 27 degrees or more: its corners stick on the pads, and no closing force turns it) is
    squared by contact first, as a real gripper's fingertips align the part
    (``settings.squaring``): "shift" opens, moves ``squaring_shift_m`` along the pads so the
    corner on one pad falls beyond its edge, closes (the pad's edge turns the face), opens, comes
    back to the measured centre and closes again; "sweep" opens and sweeps ``squaring_sweep_m``
    along the closing axis (towards the robot) so one pad pushes the cube's leading corner as a
    flat fence, then closes there. Either turns the cube about a corner, so it ends off centre
    along the pads: that offset shows up after placing. "turn" opens, turns the wrist by
    ``squaring_turn_deg`` about the TCP's vertical axis at grasp height and closes: a cube pinched
    at 27 to 45 degrees is then 4.5 to 22.5 degrees from the pads, and the centred close squares
    it about its centre, as any cube turned less than about 27 degrees; a grip still that wide
    (the cube was turned the other way) opens, turns to minus that from the measured yaw and
    closes again. The decision reads only the finger width; the lift keeps the turned yaw (the
    cube is square in the pads there, and Place turns it to the target's yaw modulo its
    symmetry). Only a grip still that wide lets go and fails.
    Among neighbours (``grasp``) there is no room for it: a turned grip lets go at once.

    ``grasp`` (a :class:`~bt_arrange.layout.Release`), for a part among neighbours: the pads
    close across that axis of the target's frame, opened only to ``grasp.opening_m``, so they
    come down in the free room beside two faces and nowhere else.
    """

    def __init__(
        self, name: str, obj: str, object_type: ObjectType | None = None, grasp: Release | None = None
    ) -> None:
        super().__init__(name)
        self.obj = obj
        #: The part's type: the pads close across its narrower side (``ObjectType.grasp_axis``).
        self.object_type = object_type or CUBE
        self.grasp = grasp
        self.reads(keys.key(obj, keys.POSE))
        if grasp is not None:
            self.reads(keys.key(obj, keys.TARGET))
        self.grip_width_m: float | None = None
        self.bad_grasp: str | None = None
        #: The first close's width when the pads pinched a turned cube and Pick squared it (m), else None.
        self.squared_from_width_m: float | None = None
        self._sweep_m = np.zeros(2)
        #: How far the wrist turned from the measured yaw to square a pinched cube (rad): the lift keeps it.
        self.wrist_turn_rad = 0.0

    def stages(self, context: Context) -> list[Stage]:
        """Open, approach, descend, close, check, lift."""
        pose: Pose = self.read(keys.key(self.obj, keys.POSE), f"Detect of {self.obj}")
        s = context.settings
        kind = self.object_type
        grasp_m, approach_m, _ = heights_m(s, kind)
        x, y = pose.x_m, pose.y_m
        opening_m = s.open_width_m
        if self.grasp is None:
            yaw = nearest_symmetric_yaw(
                pose.yaw_rad + kind.grasp_yaw_offset_rad, _wrist_yaw(context), kind.symmetry_rad
            )
        else:
            target: PlanarPose = self.read(keys.key(self.obj, keys.TARGET), "the tree's target setter")
            # The turn of the part's measured yaw (modulo its symmetry) whose closing axis is the chosen one.
            offset_rad = _axis_yaw_offset_rad(self.grasp.axis)
            across = target.yaw_rad + offset_rad
            yaw = nearest_symmetric_yaw(
                nearest_symmetric_yaw(pose.yaw_rad + offset_rad, across, kind.symmetry_rad),
                _wrist_yaw(context),
                GRIPPER_SYMMETRY_RAD,
            )
            opening_m = self.grasp.opening_m
        self.squared_from_width_m = None
        self._sweep_m = np.zeros(2)
        self.wrist_turn_rad = 0.0
        squaring: list[Stage] = []
        if self.grasp is None and s.squaring != "off":
            squaring = self._squaring_stages(s, x, y, grasp_m, yaw, opening_m)

        def lift_plan(context: Context, q: FloatArray) -> Motion:
            # Straight up from where the close ended (after a squaring sweep, that far along; after a
            # squaring turn, at the turned yaw: the cube is square in the pads there).
            return _line_to(x + self._sweep_m[0], y + self._sweep_m[1], approach_m, yaw + self.wrist_turn_rad)(
                context, q
            )

        return [
            GripperStage(stage.OPEN_GRIPPER, lambda c: c.robot.gripper.open(opening_m), wait=False),
            MoveStage(stage.MOVE_ABOVE_CUBE, _to_pose(x, y, approach_m, yaw)),
            GripperStage(stage.WAIT_FOR_OPEN_FINGERS, lambda c: None),
            MoveStage(stage.DESCEND_TO_CUBE, _line_to(x, y, grasp_m, yaw)),
            GripperStage(stage.CLOSE_ON_CUBE, lambda c: c.robot.gripper.close(s.grip_force_n)),
            InstantStage(stage.CHECK_GRASP, self._check_grasp),
            *squaring,
            # A bad grasp lets go before lifting, so the retry finds the cube where it lies.
            OnlyIf(GripperStage(stage.LET_GO_OF_BAD_GRASP, lambda c: c.robot.gripper.open(opening_m)), self._bad),
            MoveStage(stage.LIFT_CUBE, lift_plan),
            InstantStage(stage.CONFIRM_GRASP, lambda c: self.bad_grasp),
        ]

    def _squaring_stages(
        self, s: ManipulationSettings, x: float, y: float, grasp_m: float, yaw: float, opening_m: float
    ) -> list[Stage]:
        """Stages that square a cube pinched across its corners, each run only after such a grip."""
        if s.squaring == "turn":
            return self._turn_stages(s, x, y, grasp_m, yaw, opening_m)
        closing = np.array([math.cos(yaw), math.sin(yaw)])
        towards_base = -math.copysign(1.0, float(closing @ np.array([x, y])))

        def line(name: str, offset: FloatArray, pushing: bool = False) -> MoveStage:
            def plan(context: Context, q: FloatArray) -> Motion:
                self._sweep_m = offset
                return _line_to(x + offset[0], y + offset[1], grasp_m, yaw, pushing=pushing)(context, q)

            return MoveStage(name, plan)

        if s.squaring == "sweep":
            steps: list[Stage] = [
                _open_stage(stage.OPEN_TO_SQUARE, opening_m),
                line(stage.SWEEP_TO_SQUARE, closing * towards_base * s.squaring_sweep_m, pushing=True),
                _close_stage(stage.CLOSE_ON_SQUARED_CUBE, s.grip_force_n),
            ]
        else:  # "shift"
            along_pads = np.array([-math.sin(yaw), math.cos(yaw)]) * s.squaring_shift_m
            steps = [
                _open_stage(stage.OPEN_TO_SQUARE, opening_m),
                line(stage.SHIFT_ALONG_PADS, along_pads),
                _close_stage(stage.CLOSE_TO_SQUARE, s.grip_force_n),
                _open_stage(stage.OPEN_SQUARED_CUBE, opening_m),
                line(stage.RECENTRE_ON_CUBE, np.zeros(2)),
                _close_stage(stage.CLOSE_ON_SQUARED_CUBE, s.grip_force_n),
            ]
        steps.append(InstantStage(stage.CHECK_SQUARED_GRASP, self._check_squared_grasp))
        return [OnlyIf(step, self._turned) for step in steps]

    def _turn_stages(
        self, s: ManipulationSettings, x: float, y: float, grasp_m: float, yaw: float, opening_m: float
    ) -> list[Stage]:
        """Squaring by a wrist turn: ``+squaring_turn_deg`` after a pinched grip, ``-`` only if still pinched.

        The width alone tells which way the cube was turned: turned the other way, ``+`` leaves it
        pinched (further from square), and ``-`` from the measured yaw brings it within reach.
        """
        turn_rad = math.radians(s.squaring_turn_deg)

        def turn(name: str, turn_rad: float) -> MoveStage:
            def plan(context: Context, q: FloatArray) -> Motion:
                self.wrist_turn_rad = turn_rad
                # At grasp height, about the TCP's vertical axis (the last wrist joint alone): the open
                # pads (85 mm apart) clear a centred cube's corners (35.4 mm from its centre).
                return _to_pose(x, y, grasp_m, yaw + turn_rad)(context, q)

            return MoveStage(name, plan)

        one_way: list[Stage] = [
            _open_stage(stage.OPEN_TO_SQUARE, opening_m),
            turn(stage.TURN_WRIST_TO_SQUARE, turn_rad),
            _close_stage(stage.CLOSE_ON_TURNED_CUBE, s.grip_force_n),
            InstantStage(stage.CHECK_TURNED_GRASP, self._check_squared_grasp),
        ]
        other_way: list[Stage] = [
            _open_stage(stage.OPEN_TO_TURN_BACK, opening_m),
            turn(stage.TURN_WRIST_OTHER_WAY, -turn_rad),
            _close_stage(stage.CLOSE_ON_SQUARED_CUBE, s.grip_force_n),
            InstantStage(stage.CHECK_SQUARED_GRASP, self._check_squared_grasp),
        ]
        guarded: list[Stage] = [OnlyIf(step, self._turned) for step in one_way]
        return guarded + [OnlyIf(step, self._still_turned) for step in other_way]

    def _still_turned(self, context: Context) -> bool:
        """A squaring close left the grip as wide as a pinch (the first wrist turn went the wrong way)."""
        return self.squared_from_width_m is not None and self._turned(context)

    def _turned(self, context: Context) -> bool:
        """The first close pinched a turned cube across its corners (wider than a square grip)."""
        high_m = max_grip_width_m(context.settings, self.object_type)
        return self.grip_width_m is not None and self.grip_width_m > high_m

    def _check_squared_grasp(self, context: Context) -> str | None:
        """After a squaring close: record the first close's width (once), then check the new grip."""
        if self.squared_from_width_m is None:
            self.squared_from_width_m = self.grip_width_m
        result = self._check_grasp(context)
        if self.bad_grasp is not None:
            assert self.squared_from_width_m is not None
            self.bad_grasp += f" after squaring a {self.squared_from_width_m * 1000:.1f} mm grip"
        return result

    def _bad(self, context: Context) -> bool:
        return self.bad_grasp is not None

    def _check_grasp(self, context: Context) -> str | None:
        """Record whether the pads hold the cube across two faces; never fails by itself."""
        s = context.settings
        self.grip_width_m = width = max(0.0, context.robot.gripper.width())
        kind = self.object_type
        low, high = min_held_width_m(s, kind), max_grip_width_m(s, kind)
        side_mm = _grasp_width_m(s, kind) * 1000
        what = f"{side_mm:.0f} mm cube" if kind.square_top else f"{kind.name} ({side_mm:.0f} mm across)"
        self.bad_grasp = None
        if width < low:
            self.bad_grasp = (
                f"no cube between the pads: the fingers closed to {width * 1000:.1f} mm, "
                f"a {what} holds them at least {low * 1000:.1f} mm apart"
            )
        elif width > high:
            self.bad_grasp = (
                f"the pads hold the cube across its corners: {width * 1000:.1f} mm apart, more than the "
                f"{high * 1000:.1f} mm of a {what} held nearly square (it is turned)"
            )
        return None

    def success_message(self) -> str:
        """Feedback with the grip width."""
        assert self.grip_width_m is not None
        message = f"holding {self.obj}, fingers {self.grip_width_m * 1000:.1f} mm apart"
        if self.squared_from_width_m is not None:
            turned = f", the wrist turned {math.degrees(self.wrist_turn_rad):+.1f} deg" if self.wrist_turn_rad else ""
            message += (
                f" ({SQUARED_FEEDBACK} {self.squared_from_width_m * 1000:.1f} mm grip across its corners{turned})"
            )
        return message


def _open_stage(name: str, opening_m: float) -> GripperStage:
    """Open the fingers to ``opening_m`` and wait for them."""
    return GripperStage(name, lambda c: c.robot.gripper.open(opening_m))


def _close_stage(name: str, force_n: float) -> GripperStage:
    """Close the fingers with ``force_n`` and wait for them to stop."""
    return GripperStage(name, lambda c: c.robot.gripper.close(force_n))


class Place(StagedBehaviour):
    """Carry the held object above its target (``/<obj>/target``), lower it to rest, open, retreat.

    ``release`` (a :class:`~bt_arrange.layout.Release`), for a part among neighbours: the pads
    stand across that axis of the target's frame and open only to ``release.opening_m``, and a
    staged release lets go ``release.offset_m`` (target frame) away from the target, where the
    pads fit, for pushes to bring it home.

    ``where="pick"`` sets the part down where it was picked (``/<obj>/pose``) instead: a part
    about to go among neighbours is set down and looked at once more, so the next grasp is
    centred on it and its offset in the pads (unknown while held) does not carry into a neighbour.
    """

    def __init__(
        self,
        name: str,
        obj: str,
        object_type: ObjectType | None = None,
        release: Release | None = None,
        where: str = "target",
    ) -> None:
        super().__init__(name)
        if where not in ("target", "pick"):
            raise BtArrangeError(f"place {name!r}: where={where!r}, choose target or pick")
        self.obj = obj
        self.object_type = object_type or CUBE
        self.release = release
        self.where = where
        self.reads(keys.key(obj, keys.TARGET))
        if where == "pick":
            self.reads(keys.key(obj, keys.POSE))

    def stages(self, context: Context) -> list[Stage]:
        """Carry, lower, open, retreat."""
        target: PlanarPose = self.read(keys.key(self.obj, keys.TARGET), "the tree's target setter")
        s = context.settings
        kind = self.object_type
        grasp_m, approach_m, _ = heights_m(s, kind)
        x, y = target.x_m, target.y_m
        opening_m = s.open_width_m
        if self.where == "pick":
            picked: Pose = self.read(keys.key(self.obj, keys.POSE), f"Detect of {self.obj}")
            x, y = picked.x_m, picked.y_m
            yaw = nearest_symmetric_yaw(
                picked.yaw_rad + kind.grasp_yaw_offset_rad, _wrist_yaw(context), kind.symmetry_rad
            )
        elif self.release is None:
            # The grasp squared the part to the pads, so the target yaw modulo the shape's symmetry
            # will do (any quarter turn for a square top, a half turn otherwise).
            yaw = nearest_symmetric_yaw(
                target.yaw_rad + kind.grasp_yaw_offset_rad, _wrist_yaw(context), kind.symmetry_rad
            )
        else:
            offset = rotation_z(target.yaw_rad) @ np.array([*self.release.offset_m, 0.0])
            x, y = x + float(offset[0]), y + float(offset[1])
            across = target.yaw_rad + _axis_yaw_offset_rad(self.release.axis)
            yaw = nearest_symmetric_yaw(across, _wrist_yaw(context), GRIPPER_SYMMETRY_RAD)
            opening_m = self.release.opening_m
        return [
            MoveStage(stage.CARRY_ABOVE_TARGET, _to_pose(x, y, approach_m, yaw)),
            MoveStage(stage.LOWER_CUBE, _line_to(x, y, grasp_m + s.release_clearance_m, yaw)),
            GripperStage(stage.RELEASE_CUBE, lambda c: c.robot.gripper.open(opening_m)),
            MoveStage(stage.RETREAT, _line_to(x, y, approach_m, yaw)),
        ]

    def success_message(self) -> str:
        """Feedback once released."""
        if self.where == "pick":
            return f"{self.obj} set down where it was picked, to be looked at and picked again"
        if self.release is not None and self.release.staged:
            dx, dy = self.release.offset_m
            return f"{self.obj} released {dx * 1000:+.0f}, {dy * 1000:+.0f} mm from its target, to push home"
        return f"{self.obj} released at its target"


#: Correction strategies: the paper's alternating push, and ours (``Push``'s docstring).
PUSH_STRATEGIES = ("paper", "learned", "diagonal")

#: Strategy "diagonal": the most a push may move the cube across its axis, per millimetre along it.
#: The pads drag the cube sideways by friction (pads 1.2 on the cube: slipping only beyond about
#: 50 deg, atan 1.2); 0.6 (31 deg) keeps well inside that and the line contact squares the cube.
DIAGONAL_ACROSS_RATIO = 0.6


class Push(StagedBehaviour):
    """One corrective push along the target's x or y axis, alternating between pushes.

    Reads the measured pose and the offset (``/<obj>/offset_xy_mm``, target minus pose in the
    target's frame); pushes along ``/<obj>/push_axis`` (x first) by that axis' offset, unless it is
    below ``min_push_m`` and the other one is not. The fingers stand side by side along the face,
    opened to the cube's width minus a pad's thickness so both pads meet it (a line contact that
    also squares the cube up); the pads start on the side away from the target, push, back off.

    ``strategy="paper"`` (the default, and what Table 1 uses) is the paper's: alternate x and y,
    push by the axis' offset. ``strategy="learned"`` is ours: push the axis with the larger offset,
    and learn from each push's response where pushes along that axis land beyond their aim (the arm's
    local calibration error as the camera sees it, which an absolute push never corrects by itself):
    after a push along an axis aimed at ``aim``, the cube's measured position minus ``aim`` is added to
    that axis' bias, and the next push along it aims the bias short of the target.

    ``towards`` (directions of the target's frame, ``"+x"``, ``"-y"`` ...; default all four) are
    the directions it may push: a side a neighbour blocks is never pushed from. When the offset
    can only be corrected from a blocked side, Push fails saying so and writes the direction it
    needed to ``/<obj>/blocked_towards``: the tree releases the part again on the side it can be
    pushed from.

    ``strategy="diagonal"`` is "learned" whose push also corrects the other axis: the pads move
    across the push by that axis' offset (at most ``DIAGONAL_ACROSS_RATIO`` of the push's length)
    while they press on the face, and the cube follows them by friction, so one push can correct x
    and y together. The sideways part is a relative motion of the pads, so the arm's absolute
    error does not enter it and it is not learned. It moves sideways only towards a free side
    (``towards``): a neighbour across the push is never shoved.
    """

    def __init__(
        self,
        name: str,
        obj: str,
        strategy: str = "paper",
        object_type: ObjectType | None = None,
        yaw_threshold_deg: float | None = None,
        *,
        towards: tuple[str, ...] | None = None,
        opening_m: float | None = None,
    ) -> None:
        super().__init__(name)
        if strategy not in PUSH_STRATEGIES:
            raise BtArrangeError(f"push strategy {strategy!r}: choose one of {', '.join(PUSH_STRATEGIES)}")
        self.strategy = strategy
        self.obj = obj
        self.object_type = object_type or CUBE
        #: With a yaw error (``/<obj>/yaw_error_deg``) at or above this, a push is made even when the
        #: offset along its axis is below ``min_push_m``: the pads' line contact squares the part.
        self.yaw_threshold_deg = yaw_threshold_deg
        #: The opening among neighbours (``Pads.push_opening_m``: the fingers within the face's
        #: width); default the paper's width minus a pad's thickness.
        self.opening_m = opening_m
        if towards is not None and any(d not in DIRECTIONS for d in towards):
            raise BtArrangeError(f"push {name!r}: directions {towards} must be among {', '.join(DIRECTIONS)}")
        self.towards = tuple(DIRECTIONS) if towards is None else tuple(towards)
        self.reads(keys.key(obj, keys.POSE), keys.key(obj, keys.TARGET), keys.key(obj, keys.OFFSET_XY_MM))
        if yaw_threshold_deg is not None:
            self.reads(keys.key(obj, keys.YAW_ERROR_DEG))
        # Push reads the axis it alternates from and writes the next one.
        self.reads(keys.key(obj, keys.PUSH_AXIS))
        self.writes(keys.key(obj, keys.PUSH_AXIS), keys.key(obj, keys.BLOCKED_TOWARDS))
        if strategy in ("learned", "diagonal"):
            for field in (keys.PUSH_BIAS_MM, keys.LAST_PUSH):
                self.reads(keys.key(obj, field))
                self.writes(keys.key(obj, field))
        self.pushed: tuple[str, float] | None = None
        #: Strategy "diagonal": the last push's sideways part (m, signed along the other axis).
        self.across_m = 0.0
        self.squaring = False

    def stages(self, context: Context) -> list[Stage]:
        """Choose the axis, then open, go behind the cube, lower, push, back off, lift."""
        s = context.settings
        pose: Pose = self.read(keys.key(self.obj, keys.POSE), f"Inspect of {self.obj}")
        target: PlanarPose = self.read(keys.key(self.obj, keys.TARGET), "the tree's target setter")
        offset_xy_mm = self.read(keys.key(self.obj, keys.OFFSET_XY_MM), f"Inspect of {self.obj}")
        axis_key = keys.key(self.obj, keys.PUSH_AXIS)
        preferred = self.blackboard.get(axis_key) if self.blackboard.exists(axis_key) else "x"
        self.across_m = 0.0
        if self.strategy in ("learned", "diagonal"):
            axis, distance_m = self._learned_push(offset_xy_mm, s.min_push_m * 1000)
            needed = ("+" if distance_m >= 0 else "-") + axis
            choice: str | Blocked = axis
            if abs(distance_m) >= s.min_push_m and needed not in self.towards:
                choice = Blocked(needed, distance_m * 1000)
            if self.strategy == "diagonal" and not isinstance(choice, Blocked):
                across_mm = self.across_push_mm(offset_xy_mm, axis, distance_m * 1000, s.min_push_m * 1000)
                # Sideways only towards a free side: a neighbour there is never shoved.
                across_towards = ("+" if across_mm >= 0 else "-") + ("y" if axis == "x" else "x")
                self.across_m = across_mm / 1000 if across_towards in self.towards else 0.0
        else:
            choice = self.choose_side(preferred, offset_xy_mm, s.min_push_m * 1000, self.towards)
            if not isinstance(choice, Blocked):
                distance_m = (offset_xy_mm[0] if choice == "x" else offset_xy_mm[1]) / 1000
        if isinstance(choice, Blocked):
            self.pushed = None
            self.write(keys.key(self.obj, keys.BLOCKED_TOWARDS), choice.towards)
            blocked = choice
            return [InstantStage(stage.CHOOSE_PUSH_SIDE, lambda c: blocked.reason(self.obj))]
        axis = choice
        self.write(axis_key, "y" if axis == "x" else "x")
        self.pushed = (axis, distance_m)
        self.squaring = False
        if abs(distance_m) < s.min_push_m:
            if not self._turned():
                return []
            # Within reach of the target but turned: a push of the line contact alone squares it.
            self.squaring = True
        sign = math.copysign(1.0, distance_m)
        if self.squaring:
            # A squaring push barely moves the part: make it from a free side, whichever sign.
            free = [d for d in (sign, -sign) if ("+" if d > 0 else "-") + axis in self.towards]
            if not free:
                self.squaring = False
                return []
            sign = free[0]
            distance_m = math.copysign(abs(distance_m), sign)
            self.pushed = (axis, distance_m)
        unit = np.array([1.0, 0.0, 0.0]) if axis == "x" else np.array([0.0, 1.0, 0.0])
        direction = (rotation_z(target.yaw_rad) @ unit)[:2] * sign
        heading = math.atan2(direction[1], direction[0])
        # The closing axis lies across the push; the gripper is symmetric under a half turn.
        yaw = nearest_symmetric_yaw(heading + math.pi / 2, _wrist_yaw(context), GRIPPER_SYMMETRY_RAD)
        opening_m, reach_m = self.face_geometry(s, heading, pose.yaw_rad)
        _, approach_m, push_m = heights_m(s, self.object_type)
        centre = np.array([pose.x_m, pose.y_m])
        begin = centre - direction * (reach_m + s.push_clearance_m)
        end = centre - direction * reach_m + direction * abs(distance_m)
        if self.across_m:
            other = np.array([0.0, 1.0, 0.0]) if axis == "x" else np.array([1.0, 0.0, 0.0])
            across = (rotation_z(target.yaw_rad) @ other)[:2] * self.across_m
            # One straight line that meets the face where a straight push would and moves sideways
            # by ``across`` over the part in contact: it starts that far the other way, scaled.
            begin = begin - across * (s.push_clearance_m / abs(distance_m))
            end = end + across
        back = end - direction * s.push_clearance_m
        if self.opening_m is not None:
            # Among neighbours: the fingers stay within the face's width (the layout's opening).
            opening_m = min(opening_m, self.opening_m)
        return [
            GripperStage(stage.SET_PUSH_OPENING, lambda c: c.robot.gripper.open(opening_m), wait=False),
            MoveStage(stage.MOVE_BEHIND_CUBE, _to_pose(begin[0], begin[1], approach_m, yaw)),
            GripperStage(stage.WAIT_FOR_FINGERS, lambda c: None),
            MoveStage(stage.LOWER_FINGERS, _line_to(begin[0], begin[1], push_m, yaw)),
            MoveStage(stage.push(distance_m, axis), _line_to(end[0], end[1], push_m, yaw, pushing=True)),
            MoveStage(stage.BACK_OFF, _line_to(back[0], back[1], push_m, yaw)),
            MoveStage(stage.LIFT_FINGERS, _line_to(back[0], back[1], approach_m, yaw)),
        ]

    def face_geometry(self, s: ManipulationSettings, heading_rad: float, object_yaw_rad: float) -> tuple[float, float]:
        """(opening, reach) for the face pushed along ``heading_rad``.

        Both pads meet the face near its edges (the face's width less a pad's thickness, at most
        the open width); the TCP stops half the part's depth along the push plus half a pad from
        its centre when the pads touch. The settings' figures for the cube.

        A part turned by ``phi`` from square to the push (``object_yaw_rad``, measured) leads with
        a corner ``width / 2 cos phi - depth / 2 sin phi`` beside the push's line: the pads close
        so that corner meets the middle of a pad (the opening ``width cos phi - depth sin phi``
        less a pad's thickness; the paper's when square). Left in the gap between the pads, the
        corner wedges there: each pad stops on one of the two faces beside it, which neither
        squares the part nor pushes it home (a cube turned 9.4 deg, with the paper's opening,
        stopped 4.2 mm short, turned 12.8 deg, and later pushes to the same line did not move it).
        """
        if self.object_type == CUBE:
            width_m = depth_m = s.cube_edge_m
            opening_m, reach_m = s.push_opening_m, s.push_reach_m
        else:
            width_m, depth_m = self.object_type.pushed_face(heading_rad, object_yaw_rad)
            opening_m, reach_m = min(width_m - s.pad_thickness_m, s.open_width_m), depth_m / 2 + s.pad_width_m / 2
        turn_rad = abs(fold_yaw(heading_rad - object_yaw_rad, math.pi / 2))
        corner_m = width_m * math.cos(turn_rad) - depth_m * math.sin(turn_rad)
        return max(0.0, min(opening_m, corner_m - s.pad_thickness_m)), reach_m

    def _turned(self) -> bool:
        """True when the measured yaw error is at or above ``yaw_threshold_deg``."""
        if self.yaw_threshold_deg is None:
            return False
        yaw_key = keys.key(self.obj, keys.YAW_ERROR_DEG)
        if not self.blackboard.exists(yaw_key):
            return False
        return abs(float(self.blackboard.get(yaw_key))) >= self.yaw_threshold_deg

    def _learned_push(self, offset_xy_mm: tuple[float, float], min_push_mm: float) -> tuple[str, float]:
        """Strategy "learned": update the bias from the last push's response, then choose axis and distance."""
        bias_key, last_key = keys.key(self.obj, keys.PUSH_BIAS_MM), keys.key(self.obj, keys.LAST_PUSH)
        known = tuple(self.blackboard.get(bias_key)) if self.blackboard.exists(bias_key) else (0.0, 0.0)
        last = self.blackboard.get(last_key) if self.blackboard.exists(last_key) else None
        bias, axis, distance_mm = self.plan_learned(offset_xy_mm, (known[0], known[1]), last, min_push_mm)
        self.write(bias_key, bias)
        index = 0 if axis == "x" else 1
        # Where this push aims the cube, relative to the target along its axis: the bias short of it.
        aim_mm = -bias[index] if abs(distance_mm) >= min_push_mm else None
        self.write(last_key, (axis, aim_mm))
        return axis, distance_mm / 1000

    @staticmethod
    def plan_learned(
        offset_xy_mm: tuple[float, float],
        bias_mm: tuple[float, float],
        last_push: tuple[str, float | None] | None,
        min_push_mm: float,
    ) -> tuple[tuple[float, float], str, float]:
        """The learned strategy's arithmetic: (new bias, axis, signed push distance in mm).

        The cube's position relative to the target is minus the offset. After a push along ``axis``
        aimed at ``aim`` (relative to the target), the push landed ``position - aim`` beyond its aim:
        that is the axis' new bias (a push that fell short of the cube underestimates it, and the
        next push reaches further). The next push goes along the axis of the larger offset and
        aims at ``-bias``: it pushes ``offset - bias``.
        """
        bias = [float(bias_mm[0]), float(bias_mm[1])]
        if last_push is not None and last_push[1] is not None:
            index = 0 if last_push[0] == "x" else 1
            bias[index] = -offset_xy_mm[index] - last_push[1]
        # The axis whose corrected push is longer; below a push, the other one.
        wanted = [offset_xy_mm[0] - bias[0], offset_xy_mm[1] - bias[1]]
        axis = "x" if abs(wanted[0]) >= abs(wanted[1]) else "y"
        if abs(wanted[0 if axis == "x" else 1]) < min_push_mm:
            axis = "x" if abs(offset_xy_mm[0]) >= abs(offset_xy_mm[1]) else "y"
        return (bias[0], bias[1]), axis, wanted[0 if axis == "x" else 1]

    @staticmethod
    def choose_side(
        preferred: str, offset_xy_mm: tuple[float, float], min_push_mm: float, towards: tuple[str, ...]
    ) -> str | Blocked:
        """The axis to push along (as ``choose_axis``) among the free directions, or what blocks it.

        An axis whose offset needs a push towards a direction not in ``towards`` is skipped; when
        every axis with an offset of a push or more is so, the answer is ``Blocked``.
        """
        along = {"x": offset_xy_mm[0], "y": offset_xy_mm[1]}

        def needs(axis: str) -> str:
            return ("+" if along[axis] >= 0 else "-") + axis

        axis = Push.choose_axis(preferred, offset_xy_mm, min_push_mm)
        other = "y" if axis == "x" else "x"
        if abs(along[axis]) < min_push_mm or needs(axis) in towards:
            return axis
        if abs(along[other]) >= min_push_mm and needs(other) in towards:
            return other
        return Blocked(needs(axis), along[axis])

    @staticmethod
    def across_push_mm(offset_xy_mm: tuple[float, float], axis: str, distance_mm: float, min_push_mm: float) -> float:
        """Strategy "diagonal": how far (mm, signed) the push along ``axis`` also moves the cube across it.

        The other axis' offset, at most ``DIAGONAL_ACROSS_RATIO`` times the push's length (the rest
        is left to a later push); none below the shortest push, or when there is no push.
        """
        if abs(distance_mm) < min_push_mm:
            return 0.0
        wanted = offset_xy_mm[1] if axis == "x" else offset_xy_mm[0]
        if abs(wanted) < min_push_mm:
            return 0.0
        limit = DIAGONAL_ACROSS_RATIO * abs(distance_mm)
        return max(-limit, min(limit, float(wanted)))

    @staticmethod
    def choose_axis(preferred: str, offset_xy_mm: tuple[float, float], min_push_mm: float) -> str:
        """The preferred (alternated) axis, unless its offset is below a push and the other's is not."""
        other = "y" if preferred == "x" else "x"
        along = {"x": abs(offset_xy_mm[0]), "y": abs(offset_xy_mm[1])}
        if along[preferred] < min_push_mm <= along[other]:
            return other
        return preferred

    def success_message(self) -> str:
        """Feedback with the push made."""
        assert self.pushed is not None
        axis, distance_m = self.pushed
        if self.squaring:
            return f"squared the part with a push of {distance_m * 1000:+.2f} mm along {axis}"
        if abs(distance_m) < (self.context.settings.min_push_m if self.context else 0.0):
            return f"nothing to push: {abs(distance_m) * 1000:.2f} mm along {axis}"
        if self.across_m:
            other = "y" if axis == "x" else "x"
            return f"pushed {distance_m * 1000:+.2f} mm along {axis}, {self.across_m * 1000:+.2f} mm along {other}"
        return f"pushed {distance_m * 1000:+.2f} mm along {axis}"


@dataclass(frozen=True)
class Blocked:
    """A correction Push cannot make: the part must move ``towards`` (target frame) by ``offset_mm``."""

    towards: str
    offset_mm: float

    def reason(self, obj: str) -> str:
        """The feedback: which side, and what happens next."""
        side = ("-" if self.towards[0] == "+" else "+") + self.towards[1]
        return (
            f"{obj} needs a push of {abs(self.offset_mm):.2f} mm towards {self.towards}, from its {side} side, "
            "where a neighbour leaves the pads no room: pick it up and release it again "
            "on the side it can be pushed from"
        )


class GraspGuard(py_trees.decorators.EternalGuard):
    """Runs its child (e.g. Place) only while the cube stays between the fingers.

    Checked before every tick: when the fingers close past the cube's width (it slipped out),
    the child is interrupted at once and the guard fails, so a retry above can detect and pick
    the cube again instead of placing air.
    """

    def __init__(self, name: str, child: py_trees.behaviour.Behaviour, obj: str | None = None) -> None:
        super().__init__(name=name, child=child, condition=self._holding)
        #: The object held: ``obj``, else the child's (a Place knows its object).
        self.obj: str | None = obj if obj is not None else getattr(child, "obj", None)
        #: The held part's type: the child's (a Place knows it), else the cube.
        self.object_type: ObjectType = getattr(child, "object_type", None) or CUBE
        self.context: Context | None = None

    def setup(self, **kwargs: object) -> None:
        """Receive the context; without one the guard could never fire, so that is an error."""
        context = kwargs.get("context")
        if not isinstance(context, Context):
            raise BtArrangeError(f"guard {self.name!r} needs setup(context=Context(...)), got {type(context).__name__}")
        self.context = context
        super().setup(**kwargs)

    def _holding(self) -> bool:
        if self.context is None:
            return True
        if holding(self.context, self.object_type):
            return True
        low_m = min_held_width_m(self.context.settings, self.object_type)
        self.feedback_message = (
            f"the cube left the gripper: fingers at {self.context.robot.gripper.width() * 1000:.1f} mm, "
            f"under the {low_m * 1000:.1f} mm of a held cube"
        )
        return False

    def update(self) -> Status:
        """Reflect the child, with its feedback."""
        self.feedback_message = f"holding; {self.decorated.feedback_message}"
        return self.decorated.status
