"""Pick: grasp a part at its measured pose, check the grip, square a pinched part, lift."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from bt_arrange.behaviours import keys
from bt_arrange.behaviours import stages as stage
from bt_arrange.behaviours.base import GripperStage, InstantStage, MoveStage, OnlyIf, Stage, StagedBehaviour
from bt_arrange.behaviours.common_ports import OBJ, OBJECT_TYPE_PORT, Z_PORT, entries
from bt_arrange.behaviours.context import Context
from bt_arrange.behaviours.moves import (
    axis_yaw_offset_rad,
    centred_grasp,
    close_stage,
    free_grasp_pose,
    grasp_width_m,
    half_turn_free,
    heights_m,
    line_nearly_done,
    line_to,
    max_grip_width_m,
    min_held_width_m,
    open_stage,
    pick_opening_m,
    slow_close_from_m,
    to_pose,
    toward_home_q,
    wrist_yaw_rad,
)
from bt_arrange.errors import BtArrangeError
from bt_arrange.geometry import FloatArray, PlanarPose, Pose, fold_yaw
from bt_arrange.motion import GRIPPER_SYMMETRY_RAD, Motion, gripper_down_pose, nearest_symmetric_yaw
from bt_arrange.motion.bounds import joint_move_bound_s
from bt_arrange.numbers import fixed
from bt_arrange.objects import CUBE, ObjectType
from bt_arrange.plan.layout import Release
from bt_arrange.ports import BOOL, RELEASE, Port
from bt_arrange.settings import ManipulationSettings

#: Pick's success feedback holds this when it squared a part it had pinched across its corners.
SQUARED_FEEDBACK = "squared from a"
#: A part without half-turn symmetry is taken with the gripper half a turn round when that makes the
#: joint moves to it, to its target and home for the look after at least this much shorter (s, by
#: their lower bounds): the last wrist joint otherwise turns up to a whole turn there and back.
HALF_TURN_GAIN_S = 0.05


class Pick(StagedBehaviour):
    """Grasp the object at its measured pose (``/<obj>/pose``) and lift it.

    Approach above it with the pads square to its faces, descend, close with a force limit,
    check from the finger width that the pads hold the part across two faces, lift. A bad grasp
    (nothing between the pads, or a part turned so the pads meet its corners) lets go before
    lifting and fails with the width, so a retry can look and pick again.

    A grip wider than ``max_grip_width_m`` (the pads pinch two vertical edges of a 5 cm cube turned
    about 27 degrees or more: its corners stick on the pads, and no closing force turns it) is
    squared by contact first, as a real gripper's fingertips align the part
    (``settings.squaring``): "shift" opens, moves ``squaring_shift_m`` along the pads so the
    corner on one pad falls beyond its edge, closes (the pad's edge turns the face), opens, comes
    back to the measured centre and closes again; "sweep" opens and sweeps ``squaring_sweep_m``
    along the closing axis (towards the robot) so one pad pushes the part's leading corner as a
    flat fence, then closes there. Either turns the part about a corner, so it ends off centre
    along the pads: that offset shows up after placing. "turn" opens, turns the wrist by
    ``squaring_turn_deg`` about the TCP's vertical axis at grasp height and closes: a 5 cm cube pinched
    at 27 to 45 degrees is then 4.5 to 22.5 degrees from the pads, and the centred close squares
    it about its centre, as any cube turned less than about 27 degrees; a grip still that wide
    (the part was turned the other way) opens, turns to minus that from the measured yaw and
    closes again. The decision reads only the finger width; the lift keeps the turned yaw (the
    part is square in the pads there, and Place turns it to the target's yaw modulo its
    symmetry). Only a grip still that wide lets go and fails.
    Among neighbours (``grasp``) there is no room for it: a turned grip lets go at once.

    ``grasp`` (a :class:`~bt_arrange.plan.layout.Release`), for a part among neighbours: the pads
    close across that axis of the target's frame, opened only to ``grasp.opening_m``, so they
    come down in the free room beside two faces and nowhere else.
    """

    #: The node's description in the XML ``TreeNodesModel``.
    node_description = "grasp at /<obj>/pose"

    @classmethod
    def provided_ports(cls) -> tuple[Port, ...]:
        """The object, its type and the grasp among neighbours (BehaviorTree.CPP's ``providedPorts``)."""
        grasp = Port(
            "grasp",
            RELEASE,
            None,
            "among neighbours: axis;opening_m[;offset_x_m;offset_y_m[;centre_x_m;centre_y_m]], pads across that "
            "axis of the target's frame (empty: the free grasp)",
            optional=True,
        )
        nearest_grasp = Port(
            "nearest_grasp",
            BOOL,
            False,
            "the wrist's nearest grasp always (false: a part without half-turn symmetry may be taken with the "
            "gripper half a turn round when the wrist then turns less to it, to its target and home)",
            optional=True,
        )
        return (
            OBJ,
            OBJECT_TYPE_PORT,
            grasp,
            Z_PORT,
            nearest_grasp,
            *entries((keys.POSE, keys.TARGET), (keys.GRASP_HALF_TURN,)),
        )

    def __init__(
        self,
        name: str,
        obj: str,
        object_type: ObjectType | None = None,
        grasp: Release | None = None,
        z_m: float = 0.0,
        nearest_grasp: bool = False,
    ) -> None:
        super().__init__(name)
        self.obj = obj
        #: True keeps a free grasp to the wrist's nearest, never the half turn (``_half_turn_shorter``).
        self.nearest_grasp = bool(nearest_grasp)
        #: Layers: the height of the part's bottom face where it is picked (0: the table).
        self.z_m = float(z_m)
        #: The part's type: the pads take its shape's preferred grasp (``Shape.grasps``).
        self.object_type = object_type or CUBE
        self.grasp = grasp
        self.reads(keys.key(obj, keys.POSE), written_by=f"Detect of {obj}")
        if grasp is not None:
            self.reads(keys.key(obj, keys.TARGET), written_by=keys.TARGET_SETTER)
        else:
            self.reads(keys.key(obj, keys.TARGET))  # optional: where the part goes, to choose the half turn
        self.writes(keys.key(obj, keys.GRASP_HALF_TURN))
        self.grip_width_m: float | None = None
        self.bad_grasp: str | None = None
        #: The first close's width when the pads pinched a turned part and Pick squared it (m), else None.
        self.squared_from_width_m: float | None = None
        self._sweep_m = np.zeros(2)
        #: How far the wrist turned from the measured yaw to square a pinched part (rad): the lift keeps it.
        self.wrist_turn_rad = 0.0

    def stages(self, context: Context) -> list[Stage]:
        """Open, approach, descend, close, check, lift."""
        pose: Pose = self.read(keys.key(self.obj, keys.POSE), f"Detect of {self.obj}")
        s = context.settings
        kind = self.object_type
        grasp_m, approach_m, _ = heights_m(s, kind, self.z_m)
        x, y = pose.x_m, pose.y_m
        opening_m = s.open_width_m
        if self.grasp is None and not centred_grasp(s, kind):
            # Held off its centre (an irregular part): open only clear of its grasped side.
            opening_m = pick_opening_m(s, kind)
        if self.grasp is None:
            half_turn = self._half_turn_shorter(context, pose, approach_m)
            x, y, yaw = free_grasp_pose(s, kind, x, y, pose.yaw_rad, wrist_yaw_rad(context), half_turn)
        else:
            target: PlanarPose = self.read(keys.key(self.obj, keys.TARGET), "the tree's target setter")
            # The turn of the part's measured yaw (modulo its symmetry) whose closing axis is the chosen one.
            offset_rad = axis_yaw_offset_rad(self.grasp.axis)
            across = target.yaw_rad + offset_rad
            grasp_yaw = nearest_symmetric_yaw(pose.yaw_rad + offset_rad, across, kind.shape.symmetry_rad)
            yaw = nearest_symmetric_yaw(grasp_yaw, wrist_yaw_rad(context), GRIPPER_SYMMETRY_RAD)
            # The wrist's nearest half turn may hold a part without half-turn symmetry the other way round.
            half_turn = not half_turn_free(kind) and abs(fold_yaw(yaw - grasp_yaw, 2.0 * math.pi)) > math.pi / 2
            opening_m = self.grasp.opening_m
        self.write(keys.key(self.obj, keys.GRASP_HALF_TURN), half_turn)
        self.squared_from_width_m = None
        self._sweep_m = np.zeros(2)
        self.wrist_turn_rad = 0.0
        squaring: list[Stage] = []
        if self.grasp is None and s.squaring != "off":
            squaring = self._squaring_stages(s, x, y, grasp_m, yaw, opening_m)

        def lift_plan(context: Context, q: FloatArray) -> Motion:
            # Straight up from where the close ended (after a squaring sweep, that far along; after a
            # squaring turn, at the turned yaw: the part is square in the pads there).
            return line_to(x + self._sweep_m[0], y + self._sweep_m[1], approach_m, yaw + self.wrist_turn_rad)(
                context, q
            )

        return [
            GripperStage(stage.OPEN_GRIPPER, lambda c: c.robot.gripper.open(opening_m), wait=False),
            MoveStage(stage.MOVE_ABOVE_PART, to_pose(x, y, approach_m, yaw, free=True)),
            GripperStage(stage.WAIT_FOR_OPEN_FINGERS, lambda c: None, start_periods=0),
            MoveStage(stage.DESCEND_TO_PART, line_to(x, y, grasp_m, yaw, free=True)),
            # An irregular part is held off its centre: pads meeting its outline fast turn it, so they
            # meet it at the squaring speed (crossing the free stroke before at full speed); a cuboid's
            # centred grasp closes at the fingers' full speed.
            close_stage(
                stage.CLOSE_ON_PART,
                s.grip_force_n,
                squaring=not centred_grasp(s, kind),
                slow_from_m=(lambda c: slow_close_from_m(c.settings, kind)) if self.grasp is None else None,
            ),
            InstantStage(stage.CHECK_GRASP, self._check_grasp),
            *self._reclose_stages(s, opening_m),
            *squaring,
            # A bad grasp lets go before lifting, so the retry finds the part where it lies.
            OnlyIf(GripperStage(stage.LET_GO_OF_BAD_GRASP, lambda c: c.robot.gripper.open(opening_m)), self._bad),
            MoveStage(stage.LIFT_PART, lift_plan, hand_on=line_nearly_done(s.hand_on_remaining_m)),
            InstantStage(stage.CONFIRM_GRASP, lambda c: self.bad_grasp),
        ]

    def _half_turn_shorter(self, context: Context, pose: Pose, approach_m: float) -> bool:
        """Take a part without half-turn symmetry with the gripper half a turn round, when that is shorter.

        Costed, each way round, by the lower bounds of the joint moves above the part, above its
        target (``/<obj>/target``, when the tree has written it) and home for the look after
        (``toward_home_q``); the half turn must save ``HALF_TURN_GAIN_S``. A cuboid, or a pick with
        no target yet, keeps the wrist's nearest grasp.
        """
        target_key = keys.key(self.obj, keys.TARGET)
        kind = self.object_type
        if self.nearest_grasp or half_turn_free(kind) or not self.blackboard.exists(target_key):
            return False
        target: PlanarPose = self.blackboard.get(target_key)
        s = context.settings
        kinematics = context.planner.kinematics
        limits = s.free_joint_limits
        start_q = context.robot.arm.joint_positions()
        wrist_rad = wrist_yaw_rad(context)
        seconds: dict[bool, float] = {}
        for half_turn in (False, True):
            x, y, yaw = free_grasp_pose(s, kind, pose.x_m, pose.y_m, pose.yaw_rad, wrist_rad, half_turn)
            tx, ty, target_yaw = free_grasp_pose(s, kind, target.x_m, target.y_m, target.yaw_rad, yaw, half_turn)
            try:
                above_q = kinematics.inverse(gripper_down_pose(x, y, approach_m, yaw), start_q)
                place_q = kinematics.inverse(gripper_down_pose(tx, ty, approach_m, target_yaw), above_q)
            except BtArrangeError:
                continue  # that way round is out of reach: the other (or the stage's own error) decides
            place_q = toward_home_q(context, above_q, place_q)
            seconds[half_turn] = (
                joint_move_bound_s(start_q, above_q, limits)
                + joint_move_bound_s(above_q, place_q, limits)
                + joint_move_bound_s(place_q, context.home_q, limits)
            )
        return True in seconds and seconds[True] < seconds.get(False, math.inf) - HALF_TURN_GAIN_S

    def _reclose_stages(self, s: ManipulationSettings, opening_m: float) -> list[Stage]:
        """After a fast close that left the part a little turned in the pads: open just clear of it, close slowly.

        The first close runs at the fingers' full speed (``finger_speed_m_s``); pads that meet a turned
        part that fast leave it turned more often than a slow close, which turns it square as the
        pads meet it. A grip wider than the grasped side by ``square_grip_tolerance_m`` (a cube more
        than about a degree off square), but not pinched across its corners (squaring's case), opens
        to just outside the part's widest (its sweep diameter and the release clearance) and closes
        again at ``squaring_finger_speed_m_s``. A square grip costs nothing.
        """
        reopen_m = min(opening_m, 2.0 * self.object_type.shape.sweep_radius_m + 2.0 * s.release_clearance_per_side_m)
        steps: list[Stage] = [
            GripperStage(
                stage.OPEN_TO_CLOSE_SLOWLY,
                lambda c: c.robot.gripper.open(reopen_m, speed_m_s=c.settings.finger_speed_m_s),
            ),
            close_stage(stage.CLOSE_SLOWLY_ON_PART, s.grip_force_n, squaring=True),
            InstantStage(stage.CHECK_GRASP_AFTER_CLOSING_SLOWLY, self._check_grasp),
        ]
        return [OnlyIf(step, self._a_little_turned) for step in steps]

    def _a_little_turned(self, context: Context) -> bool:
        """The fast close left the grip wider than a square hold, but not pinched across the corners."""
        width = self.grip_width_m
        s = context.settings
        if width is None or self._turned(context):
            return False
        return width > grasp_width_m(s, self.object_type) + s.square_grip_tolerance_m

    def _squaring_stages(
        self, s: ManipulationSettings, x: float, y: float, grasp_m: float, yaw: float, opening_m: float
    ) -> list[Stage]:
        """Stages that square a part pinched across its corners, each run only after such a grip."""
        if s.squaring == "turn":
            return self._turn_stages(s, x, y, grasp_m, yaw, opening_m)
        closing = np.array([math.cos(yaw), math.sin(yaw)])
        towards_base = -math.copysign(1.0, float(closing @ np.array([x, y])))

        def line(name: str, offset: FloatArray, pushing: bool = False) -> MoveStage:
            def plan(context: Context, q: FloatArray) -> Motion:
                self._sweep_m = offset
                return line_to(x + offset[0], y + offset[1], grasp_m, yaw, pushing=pushing)(context, q)

            return MoveStage(name, plan)

        if s.squaring == "sweep":
            steps: list[Stage] = [
                open_stage(stage.OPEN_TO_SQUARE, opening_m),
                line(stage.SWEEP_TO_SQUARE, closing * towards_base * s.squaring_sweep_m, pushing=True),
                close_stage(stage.CLOSE_ON_SQUARED_PART, s.grip_force_n, squaring=True),
            ]
        else:  # "shift"
            along_pads = np.array([-math.sin(yaw), math.cos(yaw)]) * s.squaring_shift_m
            steps = [
                open_stage(stage.OPEN_TO_SQUARE, opening_m),
                line(stage.SHIFT_ALONG_PADS, along_pads),
                close_stage(stage.CLOSE_TO_SQUARE, s.grip_force_n, squaring=True),
                open_stage(stage.OPEN_SQUARED_PART, opening_m),
                line(stage.RECENTRE_ON_PART, np.zeros(2)),
                close_stage(stage.CLOSE_ON_SQUARED_PART, s.grip_force_n, squaring=True),
            ]
        steps.append(InstantStage(stage.CHECK_SQUARED_GRASP, self._check_squared_grasp))
        return [OnlyIf(step, self._turned) for step in steps]

    def _turn_stages(
        self, s: ManipulationSettings, x: float, y: float, grasp_m: float, yaw: float, opening_m: float
    ) -> list[Stage]:
        """Squaring by a wrist turn: ``+squaring_turn_deg`` after a pinched grip, ``-`` only if still pinched.

        The width alone tells which way the part was turned: turned the other way, ``+`` leaves it
        pinched (further from square), and ``-`` from the measured yaw brings it within reach.
        """
        turn_rad = math.radians(s.squaring_turn_deg)

        def turn(name: str, turn_rad: float) -> MoveStage:
            def plan(context: Context, q: FloatArray) -> Motion:
                self.wrist_turn_rad = turn_rad
                # At grasp height, about the TCP's vertical axis (the last wrist joint alone): the open
                # pads (85 mm apart) clear a centred cube's corners (35.4 mm from its centre).
                return to_pose(x, y, grasp_m, yaw + turn_rad)(context, q)

            return MoveStage(name, plan)

        one_way: list[Stage] = [
            open_stage(stage.OPEN_TO_SQUARE, opening_m),
            turn(stage.TURN_WRIST_TO_SQUARE, turn_rad),
            close_stage(stage.CLOSE_ON_TURNED_PART, s.grip_force_n, squaring=True),
            InstantStage(stage.CHECK_TURNED_GRASP, self._check_squared_grasp),
        ]
        other_way: list[Stage] = [
            open_stage(stage.OPEN_TO_TURN_BACK, opening_m),
            turn(stage.TURN_WRIST_OTHER_WAY, -turn_rad),
            close_stage(stage.CLOSE_ON_SQUARED_PART, s.grip_force_n, squaring=True),
            InstantStage(stage.CHECK_SQUARED_GRASP, self._check_squared_grasp),
        ]
        guarded: list[Stage] = [OnlyIf(step, self._turned) for step in one_way]
        return guarded + [OnlyIf(step, self._still_turned) for step in other_way]

    def _still_turned(self, context: Context) -> bool:
        """A squaring close left the grip as wide as a pinch (the first wrist turn went the wrong way)."""
        return self.squared_from_width_m is not None and self._turned(context)

    def _turned(self, context: Context) -> bool:
        """The first close pinched a turned part across its corners (wider than a square grip)."""
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
        """Record whether the pads hold the part across two faces; never fails by itself."""
        s = context.settings
        self.grip_width_m = width = max(0.0, context.robot.gripper.width())
        kind = self.object_type
        low, high = min_held_width_m(s, kind), max_grip_width_m(s, kind)
        side_mm = grasp_width_m(s, kind) * 1000
        what = f"{side_mm:.0f} mm cube" if kind.shape.is_cube else f"{kind.name} ({side_mm:.0f} mm across)"
        self.bad_grasp = None
        if width < low:
            self.bad_grasp = (
                f"no part between the pads: the fingers closed to {width * 1000:.1f} mm, "
                f"a {what} holds them at least {low * 1000:.1f} mm apart"
            )
        elif width > high:
            self.bad_grasp = (
                f"the pads hold the part across its corners: {width * 1000:.1f} mm apart, more than the "
                f"{high * 1000:.1f} mm of a {what} held nearly square (it is turned)"
            )
        return None

    @property
    def facts(self) -> dict[str, Any]:
        """The grip: its width (mm), whether it was squared from a pinch, and why it was bad (None: good)."""
        return {
            "grip_width_mm": None if self.grip_width_m is None else round(self.grip_width_m * 1000, 3),
            "squared": self.squared_from_width_m is not None,
            "bad_grasp": self.bad_grasp,
        }

    def success_message(self) -> str:
        """Feedback with the grip width."""
        assert self.grip_width_m is not None
        message = f"holding {self.obj}, fingers {self.grip_width_m * 1000:.1f} mm apart"
        if self.squared_from_width_m is not None:
            turned = (
                f", the wrist turned {fixed(math.degrees(self.wrist_turn_rad), 1, sign=True)} deg"
                if self.wrist_turn_rad
                else ""
            )
            message += (
                f" ({SQUARED_FEEDBACK} {self.squared_from_width_m * 1000:.1f} mm grip across its corners{turned})"
            )
        return message
