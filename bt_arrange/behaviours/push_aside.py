"""PushAside: push a placed neighbour away, squarely on one of its edges, so that a blocked push of a part is free.

Among neighbours a part is pushed only from its free sides; where the one push that closes its
offset has a neighbour in its pads' way (``/<obj>/blocked_towards``, ``/<obj>/blocked_by``), the
tree moves that neighbour aside, corrects the part, and puts the neighbour back
(``bt_arrange.trees.steps``). The push aside is planned by the layout
(``bt_arrange.plan.move_aside``): which of the neighbour's square pushes, and how far. It is a
``Push`` of the neighbour by that square push and distance, from its camera pose (``/<obj>/pose``
of the Inspect before), the pads on its edge; the part it frees only names it in the feedback.
"""

from __future__ import annotations

import math

from bt_arrange.behaviours import keys
from bt_arrange.behaviours import stages as stage
from bt_arrange.behaviours.base import InstantStage, Stage
from bt_arrange.behaviours.common_ports import OBJ, OBJECT_TYPE_PORT, Z_PORT, entries
from bt_arrange.behaviours.context import Context
from bt_arrange.behaviours.push import Push
from bt_arrange.behaviours.square_pushes import APPROACH_RESERVE_MM, DIAGONAL_ACROSS_RATIO, SquareMove
from bt_arrange.geometry import PlanarPose, Pose
from bt_arrange.objects import ObjectType
from bt_arrange.ports import DOUBLE, STRING, Port


class PushAside(Push):
    """Push ``obj`` (a neighbour) ``distance_m`` by its square push ``aside`` (``"@114.3"``), for ``for_obj``.

    Fails at once, without moving, when its shape has no square push of that name.
    """

    #: The node's description in the XML ``TreeNodesModel``.
    node_description = "push a neighbour aside, so that a blocked push of a part is free"

    @classmethod
    def provided_ports(cls) -> tuple[Port, ...]:
        """The neighbour, its type, its push aside and how far, the part it frees (``providedPorts``)."""
        return (
            OBJ,
            OBJECT_TYPE_PORT,
            Port("aside", STRING, "", "the neighbour's square push that moves it aside (@114.3)"),
            Port("distance_m", DOUBLE, 0.0, "how far it is pushed aside [m]"),
            Port("for_obj", STRING, "", "the part whose blocked push it frees", optional=True),
            Z_PORT,
            *entries((keys.POSE, keys.TARGET), ()),
        )

    def __init__(
        self,
        name: str,
        obj: str,
        aside: str,
        distance_m: float,
        object_type: ObjectType | None = None,
        *,
        for_obj: str = "",
        z_m: float = 0.0,
    ) -> None:
        super().__init__(name, obj, object_type=object_type, z_m=z_m)
        self.aside = aside
        self.distance_m = float(distance_m)
        #: The part whose blocked push this frees (the report counts the neighbour moved for it).
        self.for_obj = for_obj

    def stages(self, context: Context) -> list[Stage]:
        """The square push ``aside`` by ``distance_m``, from the neighbour's camera pose."""
        if self.aside not in self.square_pushes:
            known = ", ".join(self.square_pushes) or "none: a box is pushed along its axes"
            message = f"{self.obj} has no square push {self.aside} to be pushed aside by (its pushes: {known})"
            return [InstantStage(stage.CHOOSE_PUSH_SIDE, lambda c: message)]
        pose: Pose = self.read(keys.key(self.obj, keys.POSE), f"Inspect of {self.obj}")
        target: PlanarPose = self.read(keys.key(self.obj, keys.TARGET), "the tree's target setter")
        planned = self._square_push_stages(context, pose, target, (0.0, 0.0))
        assert planned is not None  # the move is fixed: never the axis push
        return planned

    def plan_square_push(self, *_: object) -> SquareMove:
        """The move is the layout's, not the offset's: ``aside`` by ``distance_m``."""
        return SquareMove(self.aside, self.distance_m * 1000)

    def success_message(self) -> str:
        """Which neighbour, how far, and for which part."""
        edge = self.square_pushes[self.aside].edge + 1
        freed = f", so that {self.for_obj} can be pushed from that side" if self.for_obj else ""
        return f"pushed {self.obj} {self.distance_m * 1000:.1f} mm aside, squarely onto its edge {edge}{freed}"


class PutBack(Push):
    """Push a neighbour moved aside back towards its target by its square push ``back``, across too.

    The push back's heading need not be the way aside's exactly (a piece's edges are not parallel):
    its pads also carry the neighbour across by what lies beside the push (by friction, at most
    ``DIAGONAL_ACROSS_RATIO`` of the push), and it stops ``APPROACH_RESERVE_MM`` short: the
    neighbour's own correction closes the rest from its free sides.
    """

    #: The node's description in the XML ``TreeNodesModel``.
    node_description = "push a neighbour moved aside back towards its target"

    @classmethod
    def provided_ports(cls) -> tuple[Port, ...]:
        """The neighbour, its type, its push back (``providedPorts``)."""
        return (
            OBJ,
            OBJECT_TYPE_PORT,
            Port("back", STRING, "", "the neighbour's square push that brings it back (@-61.3)"),
            Z_PORT,
            *entries((keys.POSE, keys.OFFSET_XY_MM, keys.TARGET), ()),
        )

    def __init__(self, name: str, obj: str, back: str, object_type: ObjectType | None = None, *, z_m: float = 0.0):
        super().__init__(name, obj, object_type=object_type, z_m=z_m)
        self.back = back

    def stages(self, context: Context) -> list[Stage]:
        """The square push ``back`` by the offset along it, less the reserve, and across by what lies beside."""
        if self.back not in self.square_pushes:
            message = f"{self.obj} has no square push {self.back} to be pushed back by"
            return [InstantStage(stage.CHOOSE_PUSH_SIDE, lambda c: message)]
        pose: Pose = self.read(keys.key(self.obj, keys.POSE), f"Inspect of {self.obj}")
        target: PlanarPose = self.read(keys.key(self.obj, keys.TARGET), "the tree's target setter")
        offset = self.read(keys.key(self.obj, keys.OFFSET_XY_MM), f"Inspect of {self.obj}")
        heading = self.square_pushes[self.back].heading_rad
        along = offset[0] * math.cos(heading) + offset[1] * math.sin(heading)
        beside = -offset[0] * math.sin(heading) + offset[1] * math.cos(heading)
        if along - APPROACH_RESERVE_MM < context.settings.min_push_m * 1000:
            message = f"{self.obj} lies {along:.2f} mm from its target along {self.back}: no push back to make"
            return [InstantStage(stage.CHOOSE_PUSH_SIDE, lambda c: message)]
        distance_mm = along - APPROACH_RESERVE_MM
        limit = DIAGONAL_ACROSS_RATIO * distance_mm
        self._move = SquareMove(self.back, distance_mm, max(-limit, min(limit, beside)))
        planned = self._square_push_stages(context, pose, target, (0.0, 0.0))
        assert planned is not None
        return planned

    def plan_square_push(self, *_: object) -> SquareMove:
        """The move planned from the offset in ``stages``."""
        return self._move
