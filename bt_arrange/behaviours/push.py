"""Push: one corrective push of a placed part towards its target, by one of three strategies."""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from bt_arrange.behaviours import keys
from bt_arrange.behaviours import stages as stage
from bt_arrange.behaviours.base import GripperStage, InstantStage, MoveStage, Stage, StagedBehaviour
from bt_arrange.behaviours.common_ports import OBJ, OBJECT_TYPE_PORT, Z_PORT, entries
from bt_arrange.behaviours.context import Context
from bt_arrange.behaviours.moves import heights_m, line_nearly_done, line_to, to_pose, wrist_yaw_rad
from bt_arrange.behaviours.square_pushes import (  # noqa: F401 - re-exported: Push's figures and verdicts
    APPROACH_RESERVE_MM,
    CONE_MAX_OFFSET_MM,
    DIAGONAL_ACROSS_RATIO,
    LONG_PUSH_MAX_ACROSS_MM,
    LONG_PUSH_MM,
    SLANT_RUN_IN_MM,
    SLANT_STEP_ACROSS_MM,
    SLANT_STEP_RESERVE_MM,
    SQUARING_PRESS_MM,
    STOP_SHORT_FACTOR,
    Blocked,
    SquareMove,
    choose_square_push,
    cone_push,
    plan_square_push,
)
from bt_arrange.errors import BtArrangeError
from bt_arrange.geometry import FloatArray, PlanarPose, Pose, fold_yaw, rotation_z
from bt_arrange.motion import GRIPPER_SYMMETRY_RAD, nearest_symmetric_yaw
from bt_arrange.numbers import fixed
from bt_arrange.objects import CUBE, ObjectType
from bt_arrange.plan.choices import PushStrategy
from bt_arrange.plan.layout import DIRECTIONS
from bt_arrange.ports import BLOCKERS, DIRECTIONS_TYPE, OFF_DOUBLE, STRING, Port
from bt_arrange.settings import ManipulationSettings
from bt_arrange.shapes import ROBOTIQ_2F85, SquarePush

#: Correction strategies: the paper's alternating push, and ours (``Push``'s docstring).
PUSH_STRATEGIES = tuple(strategy.value for strategy in PushStrategy)


class Push(StagedBehaviour):
    """One corrective push along the target's x or y axis, alternating between pushes.

    Reads the measured pose and the offset (``/<obj>/offset_xy_mm``, target minus pose in the
    target's frame); pushes along ``/<obj>/push_axis`` (x first) by that axis' offset, unless it is
    below ``min_push_m`` and the other one is not. The fingers stand side by side along the face,
    opened to the part's width minus a pad's thickness so both pads meet it (a line contact that
    also squares the part up); the pads start on the side away from the target, push, back off.

    ``strategy="paper"`` (the default, and what Table 1 uses) is the paper's: alternate x and y,
    push by the axis' offset. ``strategy="learned"`` is ours: push the axis with the larger offset,
    and learn from each push's response where pushes along that axis land beyond their aim (the arm's
    local calibration error as the camera sees it, which an absolute push never corrects by itself):
    after a push along an axis aimed at ``aim``, the part's measured position minus ``aim`` is added to
    that axis' bias, and the next push along it aims the bias short of the target.

    ``towards`` (directions of the target's frame, ``"+x"``, ``"-y"`` ...; default all four) are
    the directions it may push: a side a neighbour blocks is never pushed from. When the offset
    can only be corrected from a blocked side, Push fails saying so and writes the direction it
    needed to ``/<obj>/blocked_towards``: the tree releases the part again on the side it can be
    pushed from.

    An irregular part (a ``Prism``) is pushed squarely onto one of its edges instead
    (``Prism.named_pushes``: along the edge's inward normal at the target's yaw, through the
    centroid, both pads on the edge), the one that closes the most of the offset
    (``choose_square_push``); that contact also turns it back to the target's yaw. Its
    ``towards`` are those pushes' names (``"@-54.0"``). When no square push closes the offset and
    none is blocked, the axis push above is made.

    ``strategy="diagonal"`` is "learned" whose push also corrects the other axis: the pads move
    across the push by that axis' offset (at most ``DIAGONAL_ACROSS_RATIO`` of the push's length)
    while they press on the face, and the part follows them by friction, so one push can correct x
    and y together. The sideways part is a relative motion of the pads, so the arm's absolute
    error does not enter it and it is not learned. It moves sideways only towards a free side
    (``towards``): a neighbour across the push is never shoved.
    """

    #: The node's description in the XML ``TreeNodesModel``.
    node_description = "one push"

    @classmethod
    def provided_ports(cls) -> tuple[Port, ...]:
        """The object, its type, yaw squaring, free directions, opening, strategy (``providedPorts``)."""
        return (
            OBJ,
            OBJECT_TYPE_PORT,
            Port("yaw_threshold_deg", OFF_DOUBLE, None, "square the part at this yaw error [deg] (0: never)"),
            Port(
                "towards",
                DIRECTIONS_TYPE,
                tuple(DIRECTIONS),
                "the directions it may be pushed, +x,-y ... of the target's frame (default all four)",
                optional=True,
            ),
            Port(
                "opening_m",
                OFF_DOUBLE,
                None,
                "the finger opening for pushing among neighbours [m] (0: default)",
                optional=True,
            ),
            Port("strategy", STRING, "paper", "how pushes are chosen: paper, learned or diagonal", optional=True),
            Z_PORT,
            Port(
                "blockers",
                BLOCKERS,
                {},
                "per push a neighbour blocks, that neighbour, for the reason it fails with: +y=red;@61.5=tile 2",
                optional=True,
            ),
            Port(
                "threshold_mm",
                OFF_DOUBLE,
                None,
                "the correction's threshold [mm]: among neighbours a push stops short of the place only where "
                "that leaves the part well outside it (0: never)",
                optional=True,
            ),
            *entries(
                (keys.POSE, keys.OFFSET_XY_MM, keys.TARGET, keys.YAW_ERROR_DEG),
                (keys.BLOCKED_TOWARDS, keys.BLOCKED_BY),
                (keys.PUSH_AXIS, keys.PUSH_BIAS_MM, keys.LAST_PUSH),
            ),
        )

    def __init__(
        self,
        name: str,
        obj: str,
        strategy: PushStrategy | str = PushStrategy.PAPER,
        object_type: ObjectType | None = None,
        yaw_threshold_deg: float | None = None,
        *,
        towards: tuple[str, ...] | None = None,
        opening_m: float | None = None,
        z_m: float = 0.0,
        threshold_mm: float | None = None,
        blockers: Mapping[str, str] | None = None,
    ) -> None:
        super().__init__(name)
        #: Per push a neighbour blocks (a direction or a square push's name), that neighbour: the
        #: reason Push fails with names it (the plan's ``PartStep.blocked_by``).
        self.blockers: dict[str, str] = dict(blockers or {})
        #: The correction's threshold (mm; None: unknown): a square push among neighbours stops short
        #: of the place (``plan_square_push``) only by what leaves the part ``STOP_SHORT_FACTOR`` of it away.
        self.threshold_mm = threshold_mm
        #: Layers: the height of the part's bottom face (0: the table); the pads push at its own height.
        self.z_m = float(z_m)
        if strategy not in PUSH_STRATEGIES:
            raise BtArrangeError(f"push strategy {strategy!r}: choose one of {', '.join(PUSH_STRATEGIES)}")
        self.strategy = PushStrategy(strategy)
        self.obj = obj
        self.object_type = object_type or CUBE
        #: With a yaw error (``/<obj>/yaw_error_deg``) at or above this, a push is made even when the
        #: offset along its axis is below ``min_push_m``: the pads' line contact squares the part.
        self.yaw_threshold_deg = yaw_threshold_deg
        #: The opening among neighbours (``Pads.push_opening_m``: the fingers within the face's
        #: width); default the paper's width minus a pad's thickness.
        self.opening_m = opening_m
        shape = self.object_type.shape
        #: An irregular part's square pushes by name (``Shape.named_pushes``); empty for a box, which is
        #: pushed along its target frame's axes (the paper's Algorithm 1).
        self.square_pushes: dict[str, SquarePush] = {} if shape.rectangular else shape.named_pushes(ROBOTIQ_2F85)
        known = tuple(self.square_pushes) if self.square_pushes else tuple(DIRECTIONS)
        if towards is not None and any(d not in known for d in towards):
            raise BtArrangeError(f"push {name!r}: directions {towards} must be among {', '.join(known)}")
        self.towards = known if towards is None else tuple(towards)
        self.reads(keys.key(obj, keys.POSE), keys.key(obj, keys.OFFSET_XY_MM), written_by=f"Inspect of {obj}")
        self.reads(keys.key(obj, keys.TARGET), written_by=keys.TARGET_SETTER)
        if yaw_threshold_deg is not None:
            self.reads(keys.key(obj, keys.YAW_ERROR_DEG))
        # Push reads the axis it alternates from and writes the next one.
        self.reads(keys.key(obj, keys.PUSH_AXIS))
        self.writes(keys.key(obj, keys.PUSH_AXIS), keys.key(obj, keys.BLOCKED_TOWARDS), keys.key(obj, keys.BLOCKED_BY))
        if strategy in ("learned", "diagonal"):
            for field in (keys.PUSH_BIAS_MM, keys.LAST_PUSH):
                self.reads(keys.key(obj, field))
                self.writes(keys.key(obj, field))
        self.pushed: tuple[str, float] | None = None
        #: Strategy "diagonal": the last push's sideways part (m, signed along the other axis).
        self.across_m = 0.0
        self.squaring = False

    def stages(self, context: Context) -> list[Stage]:
        """Choose the axis, then open, go behind the part, lower, push, back off, lift."""
        pose: Pose = self.read(keys.key(self.obj, keys.POSE), f"Inspect of {self.obj}")
        target: PlanarPose = self.read(keys.key(self.obj, keys.TARGET), "the tree's target setter")
        offset_xy_mm = self.read(keys.key(self.obj, keys.OFFSET_XY_MM), f"Inspect of {self.obj}")
        # Fresh for every push: the loop above tells a push that was blocked (and a restaging) from a free one.
        self.write(keys.key(self.obj, keys.BLOCKED_TOWARDS), keys.NOT_BLOCKED)
        self.write(keys.key(self.obj, keys.BLOCKED_BY), keys.NOT_BLOCKED)
        if self.square_pushes:
            planned = self._square_push_stages(context, pose, target, offset_xy_mm)
            if planned is not None:
                return planned
            # No square push closes the offset (an L's few edges leave directions out), and nothing
            # stands beside the part: the target frame's x and y pushes will do.
            return self._axis_push_stages(context, pose, target, offset_xy_mm, tuple(DIRECTIONS))
        return self._axis_push_stages(context, pose, target, offset_xy_mm, self.towards)

    def _axis_push_stages(
        self,
        context: Context,
        pose: Pose,
        target: PlanarPose,
        offset_xy_mm: tuple[float, float],
        towards: tuple[str, ...],
    ) -> list[Stage]:
        """A push along the target frame's x or y axis (a cuboid's), by the strategy, towards a free side."""
        s = context.settings
        axis_key = keys.key(self.obj, keys.PUSH_AXIS)
        preferred = self.blackboard.get(axis_key) if self.blackboard.exists(axis_key) else "x"
        self.across_m = 0.0
        if self.strategy in ("learned", "diagonal"):
            axis, distance_m = self._learned_push(offset_xy_mm, s.min_push_m * 1000)
            needed = ("+" if distance_m >= 0 else "-") + axis
            choice: str | Blocked = axis
            if abs(distance_m) >= s.min_push_m and needed not in towards:
                choice = Blocked(needed, distance_m * 1000)
            if self.strategy == "diagonal" and not isinstance(choice, Blocked):
                across_mm = self.across_push_mm(offset_xy_mm, axis, distance_m * 1000, s.min_push_m * 1000)
                # Sideways only towards a free side: a neighbour there is never shoved.
                across_towards = ("+" if across_mm >= 0 else "-") + ("y" if axis == "x" else "x")
                self.across_m = across_mm / 1000 if across_towards in towards else 0.0
        else:
            choice = self.choose_side(preferred, offset_xy_mm, s.min_push_m * 1000, towards)
            if not isinstance(choice, Blocked):
                distance_m = (offset_xy_mm[0] if choice == "x" else offset_xy_mm[1]) / 1000
        if isinstance(choice, Blocked):
            return self._blocked(choice)
        axis = choice
        self.write(axis_key, "y" if axis == "x" else "x")
        distance_m = self._short_of_a_blocked_side(axis, distance_m, towards)
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
            free = [d for d in (sign, -sign) if ("+" if d > 0 else "-") + axis in towards]
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
        yaw = nearest_symmetric_yaw(heading + math.pi / 2, wrist_yaw_rad(context), GRIPPER_SYMMETRY_RAD)
        opening_m, reach_m = self.face_geometry(s, heading, pose.yaw_rad)
        _, approach_m, push_m = heights_m(s, self.object_type, self.z_m)
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
        return self._motion(
            opening_m, begin, end, back, (approach_m, push_m), yaw, stage.push(distance_m, axis), gentle=self.z_m > 0.0
        )

    @staticmethod
    def _motion(
        opening_m: float,
        begin: FloatArray,
        end: FloatArray,
        back: FloatArray,
        heights: tuple[float, float],
        yaw: float,
        push_stage: str,
        gentle: bool = False,
        via: FloatArray | None = None,
        lift_away: bool = False,
    ) -> list[Stage]:
        """The push's stages: open, go behind the part, lower, push, back off, lift (every push's).

        ``via``: the pads go there first, straight and at the push's speed, and push from there (a
        push that also moves the part across). ``lift_away``: back off and lift in one slanted line
        (a square push on the table; the paper's pushes of cuboids keep its back-off, then lift).
        """
        approach_m, push_m = heights
        run_in: list[Stage] = []
        if via is not None:
            run_in = [MoveStage(stage.APPROACH_EDGE, line_to(via[0], via[1], push_m, yaw, pushing=True, gentle=gentle))]
        return [
            GripperStage(stage.SET_PUSH_OPENING, lambda c: c.robot.gripper.open(opening_m), wait=False),
            # Only the push itself touches the part: the moves before and after it run at the free-space limits.
            MoveStage(stage.MOVE_BEHIND_PART, to_pose(begin[0], begin[1], approach_m, yaw, free=True)),
            GripperStage(stage.WAIT_FOR_FINGERS, lambda c: None, start_periods=0),
            MoveStage(stage.LOWER_FINGERS, line_to(begin[0], begin[1], push_m, yaw, free=True)),
            *run_in,
            MoveStage(push_stage, line_to(end[0], end[1], push_m, yaw, pushing=True, gentle=gentle)),
            *([] if lift_away else [MoveStage(stage.BACK_OFF, line_to(back[0], back[1], push_m, yaw, free=True))]),
            MoveStage(
                stage.LIFT_FINGERS,
                line_to(back[0], back[1], approach_m, yaw, free=True),
                hand_on=line_nearly_done(),
            ),
        ]

    def _square_push_stages(
        self, context: Context, pose: Pose, target: PlanarPose, offset_xy_mm: tuple[float, float]
    ) -> list[Stage] | None:
        """An irregular part's push: squarely onto one edge, the one whose push best closes the offset.

        None when no square push closes an offset of a push or more and the part is free (no
        opening among neighbours given): an axis push is made instead. Among neighbours with every
        square push free, the larger of two that take the offset between them (``cone_push``).
        """
        s = context.settings
        self.across_m = 0.0
        shape = self.object_type.shape
        # The part's turn from its target's yaw, which a square push takes away.
        yaw_error_rad = fold_yaw(pose.yaw_rad - target.yaw_rad, shape.symmetry_rad)
        min_push_mm, turned = s.min_push_m * 1000, self._turned()
        args = (offset_xy_mm, self.square_pushes, self.towards, min_push_mm, turned, self.threshold_mm, yaw_error_rad)
        among_neighbours = self.opening_m is not None or not set(self.towards) >= set(self.square_pushes)
        choice = self.plan_square_push(*args, among_neighbours)
        if choice is None and math.hypot(*offset_xy_mm) >= s.min_push_m * 1000:
            every_push_free = set(self.towards) >= set(self.square_pushes)
            if every_push_free and self.opening_m is None:
                return None
            # Among neighbours (an opening given) the axis push is never made: its pads were not checked
            # against them (a fresco piece 0.59 mm off across its pushes was pushed along y with the pads
            # closed, and a neighbour moved 14 mm). Two square pushes take the offset between them.
            cone = cone_push(offset_xy_mm, self.square_pushes, self.towards, min_push_mm) if every_push_free else None
            if cone is not None:
                choice = SquareMove(*cone)
            else:
                best = max(self.square_pushes, key=lambda n: self._along(offset_xy_mm, n))
                choice = Blocked(best, math.hypot(*offset_xy_mm), across_every_push=every_push_free)
        if isinstance(choice, Blocked):
            return self._blocked(choice)
        if choice is None:
            self.pushed = ("x", 0.0)
            self.squaring = False
            return []
        name, distance_mm = choice.name, choice.distance_mm
        distance_m = distance_mm / 1000
        self.pushed = (name, distance_m)
        self.squaring = distance_m < s.min_push_m
        self.across_m = choice.across_mm / 1000
        heading = target.yaw_rad + self.square_pushes[name].heading_rad
        direction = np.array([math.cos(heading), math.sin(heading)])
        yaw = nearest_symmetric_yaw(heading + math.pi / 2, wrist_yaw_rad(context), GRIPPER_SYMMETRY_RAD)
        # The push's own opening (``Prism.named_pushes``): both pads on the edge, the fingers within
        # its ends, so among neighbours too (the layout checked this opening).
        opening_m = self.square_pushes[name].opening_m
        half_span_m = opening_m / 2 + s.gripper.pad_thickness_m
        reach_m = shape.back_within_m(heading, pose.yaw_rad, half_span_m) + s.gripper.pad_width_m / 2
        # A long push squares the part: it ends with the edge flat on the pads, where the squared edge
        # belongs, not its leading corner (pieces turned 0.5 to 1.3 deg stopped 0.14 to 0.64 mm short).
        squared_yaw_rad = pose.yaw_rad - (yaw_error_rad if distance_mm > LONG_PUSH_MM else 0.0)
        end_reach_m = shape.back_within_m(heading, squared_yaw_rad, half_span_m) + s.gripper.pad_width_m / 2
        _, approach_m, push_m = heights_m(s, self.object_type, self.z_m)
        centre = np.array([pose.x_m, pose.y_m])
        begin = centre - direction * (reach_m + s.push_clearance_m)
        end = centre - direction * end_reach_m + direction * distance_m
        via = None
        if self.across_m:
            # Straight up to the edge, then slanted: the pads carry the part across by friction while
            # they press it along, and come into contact where a straight push would. A long push (a
            # staged part's way home) slants from its start, in one line that meets the edge there
            # too: stopping at the edge cost 0.15 s a piece on the fresco.
            across = np.array([-direction[1], direction[0]]) * self.across_m
            long_push = distance_mm > LONG_PUSH_MM
            run_in_m = s.push_clearance_m if long_push else min(SLANT_RUN_IN_MM / 1000, s.push_clearance_m / 2)
            lead = across * (run_in_m / distance_m)
            begin = begin - lead
            via = None if long_push else centre - direction * (reach_m + run_in_m) - lead
            end = end + across
        back = end - direction * s.push_clearance_m
        return self._motion(
            opening_m,
            begin,
            end,
            back,
            (approach_m, push_m),
            yaw,
            stage.push(distance_m, name),
            gentle=self.z_m > 0.0,
            via=via,
            # Above the pads' swept line, clear of neighbours: 0.21 s a push less on the example fresco.
            lift_away=self.z_m == 0.0,
        )

    def _along(self, offset_xy_mm: tuple[float, float], name: str) -> float:
        heading = self.square_pushes[name].heading_rad
        return float(offset_xy_mm[0] * math.cos(heading) + offset_xy_mm[1] * math.sin(heading))

    #: ``bt_arrange.behaviours.square_pushes.plan_square_push``: the square push among neighbours.
    plan_square_push = staticmethod(plan_square_push)
    #: ``bt_arrange.behaviours.square_pushes.choose_square_push``: the square push that closes most.
    choose_square_push = staticmethod(choose_square_push)

    def face_geometry(self, s: ManipulationSettings, heading_rad: float, object_yaw_rad: float) -> tuple[float, float]:
        """(opening, reach) for the face pushed along ``heading_rad``.

        Both pads meet the face near its edges (the face's width less a pad's thickness, at most
        the open width); the TCP stops half the part's depth along the push plus half a pad from
        its centre when the pads touch: the shape's face, the gripper's pads.

        A part turned by ``phi`` from square to the push (``object_yaw_rad``, measured) leads with
        a corner ``width / 2 cos phi - depth / 2 sin phi`` beside the push's line: the pads close
        so that corner meets the middle of a pad (the opening ``width cos phi - depth sin phi``
        less a pad's thickness; the paper's when square). Left in the gap between the pads, the
        corner wedges there: each pad stops on one of the two faces beside it, which neither
        squares the part nor pushes it home (a cube turned 9.4 deg, with the paper's opening,
        stopped 4.2 mm short, turned 12.8 deg, and later pushes to the same line did not move it).
        """
        shape = self.object_type.shape
        face = shape.pushed_face(heading_rad, object_yaw_rad)
        gripper = s.gripper
        opening_m = min(gripper.free_push_opening_m(face.width_m), s.open_width_m)
        reach_m = face.depth_m / 2 + gripper.pad_width_m / 2
        opening_m = max(0.0, min(opening_m, face.leading_width_m - gripper.pad_thickness_m))
        if not shape.rectangular:
            # An irregular part: the pads stop where they first meet it, which need not be its
            # back-most point (a corner beside the pads is never touched by them).
            half_span_m = opening_m / 2 + gripper.pad_thickness_m
            reach_m = shape.back_within_m(heading_rad, object_yaw_rad, half_span_m) + gripper.pad_width_m / 2
        return opening_m, reach_m

    def _short_of_a_blocked_side(self, axis: str, distance_m: float, towards: tuple[str, ...]) -> float:
        """Among neighbours, a long push whose overshoot only a blocked push could undo stops short (m, signed).

        A box released past its place for a blocked push comes home by a long push; pushed all the
        way, it landed past its place by 0.4 mm in the real-cell model (a 4 mm push), where only the
        blocked push reaches, and was released again. Stopped ``APPROACH_RESERVE_MM`` short, it lies on
        the free side, and a short push closes the rest.
        """
        if self.opening_m is None or self.square_pushes or abs(distance_m) * 1000 < LONG_PUSH_MM:
            return distance_m
        overshoot_towards = ("-" if distance_m > 0 else "+") + axis
        if overshoot_towards in towards:
            return distance_m
        reserve_mm = math.copysign(APPROACH_RESERVE_MM, distance_m)
        last_key = keys.key(self.obj, keys.LAST_PUSH)
        if self.strategy in ("learned", "diagonal") and self.blackboard.exists(last_key):
            # The learned strategy's aim moves back by the reserve: stopping short is no landing error to learn.
            last_axis, aim_mm = self.blackboard.get(last_key)
            if aim_mm is not None:
                self.write(last_key, (last_axis, aim_mm - reserve_mm))
        return distance_m - reserve_mm / 1000

    def _blocked(self, blocked: Blocked) -> list[Stage]:
        """No push: name the blocked side and the neighbour (``/<obj>/blocked_towards``, ``blocked_by``)."""
        self.pushed = None
        neighbour = None if blocked.across_every_push else self.blockers.get(blocked.towards)
        self.write(keys.key(self.obj, keys.BLOCKED_TOWARDS), blocked.towards)
        by = keys.NOT_BLOCKED if blocked.across_every_push else neighbour or "a neighbour"
        self.write(keys.key(self.obj, keys.BLOCKED_BY), by)
        if self.strategy in ("learned", "diagonal"):
            # No push was made: the next one must not learn a landing from it (a release past the place
            # in between read as a push landing 4 mm beyond its aim, and sent the part 5 mm the wrong way).
            self.write(keys.key(self.obj, keys.LAST_PUSH), ("x", None))
        return [InstantStage(stage.CHOOSE_PUSH_SIDE, lambda c: blocked.reason(self.obj, neighbour))]

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
        # Where this push aims the part, relative to the target along its axis: the bias short of it.
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

        The part's position relative to the target is minus the offset. After a push along ``axis``
        aimed at ``aim`` (relative to the target), the push landed ``position - aim`` beyond its aim:
        that is the axis' new bias (a push that fell short of the part underestimates it, and the
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
        """Strategy "diagonal": how far (mm, signed) the push along ``axis`` also moves the part across it.

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
        if axis in self.square_pushes:
            edge = self.square_pushes[axis].edge + 1
            if self.squaring:
                return f"squared the part on its edge {edge} with a push of {fixed(distance_m * 1000, sign=True)} mm"
            across = f", {fixed(self.across_m * 1000, sign=True)} mm across" if self.across_m else ""
            onto = f"squarely onto its edge {edge} ({axis[1:]} deg)"
            return f"pushed {fixed(distance_m * 1000, sign=True)} mm {onto}{across}"
        if self.squaring:
            return f"squared the part with a push of {fixed(distance_m * 1000, sign=True)} mm along {axis}"
        if abs(distance_m) < (self.context.settings.min_push_m if self.context else 0.0):
            return f"nothing to push: {abs(distance_m) * 1000:.2f} mm along {axis}"
        if self.across_m:
            other = "y" if axis == "x" else "x"
            return (
                f"pushed {fixed(distance_m * 1000, sign=True)} mm along {axis}, "
                f"{fixed(self.across_m * 1000, sign=True)} mm along {other}"
            )
        return f"pushed {fixed(distance_m * 1000, sign=True)} mm along {axis}"
