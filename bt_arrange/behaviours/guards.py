"""GraspGuard: runs its child only while the held part stays between the fingers."""

from __future__ import annotations

import py_trees
from py_trees.common import Status

from bt_arrange.behaviours.context import Context
from bt_arrange.behaviours.moves import (
    holding,
    min_held_width_m,
)
from bt_arrange.errors import BtArrangeError
from bt_arrange.objects import CUBE, ObjectType
from bt_arrange.ports import Port


class GraspGuard(py_trees.decorators.EternalGuard):
    """Runs its child (e.g. Place) only while the part stays between the fingers.

    Checked before every tick: when the fingers close past the part's width (it slipped out),
    the child is interrupted at once and the guard fails, so a retry above can detect and pick
    the part again instead of placing air.
    """

    #: The node's description in the XML ``TreeNodesModel``.
    node_description = "fails within a tick when the held part slips out"

    @classmethod
    def provided_ports(cls) -> tuple[Port, ...]:
        """None: the object held is its child's (BehaviorTree.CPP's ``providedPorts``)."""
        return ()

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
            f"the part left the gripper: fingers at {self.context.robot.gripper.width() * 1000:.1f} mm, "
            f"under the {low_m * 1000:.1f} mm of a held part"
        )
        return False

    def update(self) -> Status:
        """Reflect the child, with its feedback."""
        self.feedback_message = f"holding; {self.decorated.feedback_message}"
        return self.decorated.status
