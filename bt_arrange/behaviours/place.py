"""Place: carry the held part above its target (or back where it was picked), lower, release, retreat."""

from __future__ import annotations

import math

import numpy as np

from bt_arrange.behaviours import keys
from bt_arrange.behaviours import stages as stage
from bt_arrange.behaviours.base import GripperStage, MoveStage, Stage, StagedBehaviour
from bt_arrange.behaviours.common_ports import OBJ, OBJECT_TYPE_PORT, Z_PORT, entries
from bt_arrange.behaviours.context import Context
from bt_arrange.behaviours.moves import (
    axis_yaw_offset_rad,
    free_grasp_pose,
    half_turn_free,
    heights_m,
    line_nearly_done,
    line_to,
    release_clearance_m,
    release_opening_m,
    to_pose,
    wrist_yaw_rad,
)
from bt_arrange.errors import BtArrangeError
from bt_arrange.geometry import PlanarPose, Pose, rotation_z
from bt_arrange.motion import GRIPPER_SYMMETRY_RAD, nearest_symmetric_yaw
from bt_arrange.numbers import fixed
from bt_arrange.objects import CUBE, ObjectType
from bt_arrange.plan.layout import Release
from bt_arrange.plan.release_room import Settled
from bt_arrange.ports import BOOL, RELEASE, STRING, Port


class Place(StagedBehaviour):
    """Carry the held object above its target (``/<obj>/target``), lower it to rest, open, retreat.

    ``release`` (a :class:`~bt_arrange.plan.layout.Release`), for a part among neighbours: the pads
    stand across that axis of the target's frame and open only to ``release.opening_m``, and a
    staged release lets go ``release.offset_m`` (target frame) away from the target, where the
    pads fit, for pushes to bring it home.

    ``where="pick"`` sets the part down where it was picked (``/<obj>/pose``) instead: a part
    about to go among neighbours is set down and looked at once more, so the next grasp is
    centred on it and its offset in the pads (unknown while held) does not carry into a neighbour.
    """

    #: The node's description in the XML ``TreeNodesModel``.
    node_description = "release at /<obj>/target"

    @classmethod
    def provided_ports(cls) -> tuple[Port, ...]:
        """The object, its type, the release among neighbours and where (BehaviorTree.CPP's ``providedPorts``)."""
        release = Port(
            "release",
            RELEASE,
            None,
            "among neighbours: axis;opening_m[;offset_x_m;offset_y_m[;centre_x_m;centre_y_m]], released that far "
            "from the target (empty: at the target, fully open)",
            optional=True,
        )
        where = Port("where", STRING, "target", "target, or pick: set down where it was picked", optional=True)
        nearest_turn = Port(
            "nearest_turn",
            BOOL,
            False,
            "the wrist's nearest way round for the carry of a part placed free (false, or among neighbours: a "
            "part without half-turn symmetry is carried the way round that, with the park after it, turns the "
            "wrist least)",
            optional=True,
        )
        held = Port(
            "held",
            BOOL,
            False,
            "correct the placing by the part's place in the pads measured in the fingers (LookAtHeld), when measured",
            optional=True,
        )
        return (
            OBJ,
            OBJECT_TYPE_PORT,
            release,
            where,
            Z_PORT,
            nearest_turn,
            held,
            *entries((keys.TARGET, keys.POSE, keys.GRASP_HALF_TURN, keys.HELD_CORRECTION)),
        )

    def __init__(
        self,
        name: str,
        obj: str,
        object_type: ObjectType | None = None,
        release: Release | None = None,
        where: str = "target",
        z_m: float = 0.0,
        nearest_turn: bool = False,
        held: bool = False,
    ) -> None:
        super().__init__(name)
        #: True: the TCP's pose is corrected by ``/<obj>/held_correction`` (LookAtHeld's), when one was measured.
        self.held = bool(held)
        #: True keeps the carry to the wrist's nearest way round (``toward_home_q`` otherwise).
        self.nearest_turn = bool(nearest_turn)
        #: Layers: the height of the support it is released on (0: the table); the lowering
        #: ends with the part's bottom ``release_clearance_m`` above it, the pads clear of the layer below.
        self.z_m = float(z_m)
        if where not in ("target", "pick"):
            raise BtArrangeError(f"place {name!r}: where={where!r}, choose target or pick")
        self.obj = obj
        self.object_type = object_type or CUBE
        self.release = release
        self.where = where
        self.reads(keys.key(obj, keys.TARGET), written_by=keys.TARGET_SETTER)
        if where == "pick":
            self.reads(keys.key(obj, keys.POSE), written_by=f"Detect of {obj}")
        self.reads(keys.key(obj, keys.GRASP_HALF_TURN))  # optional: False (the wrist's nearest grasp) without it
        if self.held:
            self.reads(keys.key(obj, keys.HELD_CORRECTION))  # optional: None or absent, no correction
        #: The correction applied to the last placing's TCP pose (TCP frame), or None.
        self.corrected_by: PlanarPose | None = None
        #: Among neighbours, how the correction's slide along the pads was split to keep them clear, or None.
        self.settled: Settled | None = None

    def stages(self, context: Context) -> list[Stage]:
        """Carry, lower, open, retreat."""
        target: PlanarPose = self.read(keys.key(self.obj, keys.TARGET), "the tree's target setter")
        s = context.settings
        kind = self.object_type
        grasp_m, approach_m, _ = heights_m(s, kind, self.z_m)
        x, y = target.x_m, target.y_m
        opening_m = release_opening_m(s, kind)
        half_turn_key = keys.key(self.obj, keys.GRASP_HALF_TURN)
        half_turn = bool(self.blackboard.get(half_turn_key)) if self.blackboard.exists(half_turn_key) else False
        if self.where == "pick":
            picked: Pose = self.read(keys.key(self.obj, keys.POSE), f"Detect of {self.obj}")
            x, y, yaw = free_grasp_pose(
                s, kind, picked.x_m, picked.y_m, picked.yaw_rad, wrist_yaw_rad(context), half_turn
            )
        elif self.release is None:
            # The grasp squared the part to the pads, so the target yaw modulo the shape's symmetry
            # will do (any quarter turn for a square top, a half turn otherwise); an off-centre grasp
            # brings the TCP to where that grasp's centre lies with the part at its target.
            x, y, yaw = free_grasp_pose(s, kind, x, y, target.yaw_rad, wrist_yaw_rad(context), half_turn)
        else:
            offset = rotation_z(target.yaw_rad) @ np.array([*self.release.offset_m, 0.0])
            x, y = x + float(offset[0]), y + float(offset[1])
            across = target.yaw_rad + axis_yaw_offset_rad(self.release.axis) + (math.pi if half_turn else 0.0)
            # The gripper's half turn is free only when the part looks the same turned so (a cuboid):
            # an irregular part held turned by it would land turned by it.
            symmetry_rad = max(GRIPPER_SYMMETRY_RAD, kind.shape.symmetry_rad)
            yaw = nearest_symmetric_yaw(across, wrist_yaw_rad(context), symmetry_rad)
            opening_m = self.release.opening_m
        self.corrected_by = None
        self.settled = None
        correction_key = keys.key(self.obj, keys.HELD_CORRECTION)
        if self.held and self.where == "target" and self.blackboard.exists(correction_key):
            correction = self.blackboard.get(correction_key)
            if isinstance(correction, PlanarPose):
                # The part sits in the pads where LookAtHeld measured it: the TCP goes where it puts it at its place.
                c, s_ = math.cos(yaw), math.sin(yaw)
                dx, dy = c * correction.x_m - s_ * correction.y_m, s_ * correction.x_m + c * correction.y_m
                dx, dy = self._pads_clear(target.yaw_rad, dx, dy)
                x, y = x + dx, y + dy
                yaw += correction.yaw_rad
                self.corrected_by = correction
        return [
            # At the UR5's joint speeds, whether the grasp holds the part through its centre of mass
            # or off it (an irregular part's): measured, the inertia did not turn a part in the pads.
            # (A prism does turn in them while the wrist turns, up to 1.4 deg on the fresco, at constant
            # speed too; the long push after its staged release takes that out: squaring_shift_mm.)
            # A look follows: a part without half-turn symmetry, placed free or among neighbours, is
            # carried turning the wrist the way round that, with the park after, turns it least (a
            # cuboid's turn is a quarter at most). Set down to be looked at, as the layout planned.
            MoveStage(
                stage.CARRY_ABOVE_TARGET,
                to_pose(x, y, approach_m, yaw, carrying=True, via_home=self._free_transfer(kind)),
            ),
            MoveStage(stage.LOWER_PART, line_to(x, y, grasp_m + release_clearance_m(s, self.z_m), yaw)),
            self._release_stage(opening_m, free=self.release is None, raised=self.z_m > 0.0),
            MoveStage(
                stage.RETREAT,
                line_to(x, y, approach_m, yaw, free=True),
                hand_on=line_nearly_done(s.hand_on_remaining_m),
            ),
        ]

    def _pads_clear(self, target_yaw_rad: float, dx_m: float, dy_m: float) -> tuple[float, float]:
        """The correction's TCP shift on the table, its slide along the pads cut short before they meet a neighbour.

        The pads move with the TCP: a part held some millimetres along them from where the pick meant
        slides them that far along its sides, where the layout did not check them (``release_room``).
        """
        room = self.release.room if self.release is not None else None
        if room is None:
            return dx_m, dy_m
        ux, uy = room.along_pads_world(target_yaw_rad)
        slide_m = dx_m * ux + dy_m * uy
        settled = room.settle(slide_m)
        if not settled.kept_off:
            return dx_m, dy_m
        self.settled = settled
        cut_m = settled.tcp_slide_m - slide_m
        return dx_m + cut_m * ux, dy_m + cut_m * uy

    def _free_transfer(self, kind: ObjectType) -> bool:
        """A part without half-turn symmetry placed at its target, free or staged among neighbours.

        A look follows either way (Inspect after placing), so the carry's last wrist joint takes the
        whole turn either side that makes it and the park the shortest: the example fresco at seed 0,
        45.9 s of world time, was 46.8 s with the nearest turn for its staged pieces (the park back 1.6 s
        longer, the carry 0.7 s shorter). ``nearest_turn`` keeps the nearest turn for a part placed free.
        """
        among_neighbours = self.release is not None
        return not half_turn_free(kind) and (among_neighbours or not self.nearest_turn) and self.where == "target"

    @staticmethod
    def _release_stage(opening_m: float, free: bool, raised: bool = False) -> GripperStage:
        """Open the pads to ``opening_m``; a part that holds them short (wedged) is let go by opening all the way.

        A free part only: among neighbours (``free`` False) the pads open no further than the layout
        allows, and a pad may stop on a neighbour's side rather than on the part; the opening is not checked.
        On others (``raised``) the pads open at ``raised_release_finger_speed_m_s``.
        """
        wanted = {"m": opening_m}

        def speed_m_s(context: Context) -> float:
            s = context.settings
            return s.raised_release_finger_speed_m_s if raised else s.finger_speed_m_s

        def open_fully(context: Context) -> None:
            wanted["m"] = context.settings.open_width_m
            context.robot.gripper.open(wanted["m"], speed_m_s=speed_m_s(context))

        return GripperStage(
            stage.RELEASE_PART,
            lambda c: c.robot.gripper.open(opening_m, speed_m_s=speed_m_s(c)),
            opens_to_m=(lambda c: wanted["m"]) if free else None,
            on_stall=open_fully if free else None,
        )

    def success_message(self) -> str:
        """Feedback once released."""
        if self.where == "pick":
            return f"{self.obj} set down where it was picked, to be looked at and picked again"
        kept = ""
        if self.settled is not None:
            # The pads kept off a neighbour: the part lands that much off along them, to be pushed home.
            kept = (
                f" (the pads slid {fixed(self.settled.tcp_slide_m * 1000, 1)} mm along it, not "
                f"{fixed((self.settled.tcp_slide_m - self.settled.part_off_m) * 1000, 1)}, to keep off "
                f"{' and '.join(self.settled.kept_off)}; it lands {fixed(abs(self.settled.part_off_m) * 1000, 1)} mm "
                "along them from there)"
            )
        if self.release is not None and self.release.staged:
            dx, dy = self.release.offset_m
            return (
                f"{self.obj} released {fixed(dx * 1000, 0, sign=True)}, {fixed(dy * 1000, 0, sign=True)} mm "
                f"from its target, to push home{kept}"
            )
        return f"{self.obj} released at its target{kept}"
