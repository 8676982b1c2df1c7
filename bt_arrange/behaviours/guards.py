"""GraspGuard: runs its child only while the held part stays between the fingers."""

from __future__ import annotations

from collections.abc import Iterator

import py_trees
from py_trees.common import Status

from bt_arrange.behaviours.base import FAILURE, RUNNING, debug_logging, end_tick
from bt_arrange.behaviours.context import Context
from bt_arrange.behaviours.moves import min_held_width_m
from bt_arrange.errors import BtArrangeError
from bt_arrange.objects import CUBE, ObjectType
from bt_arrange.ports import Port


class GraspGuard(py_trees.decorators.EternalGuard):
    """Runs its child (e.g. Place) only while the part stays between the fingers.

    Checked before every tick: when the fingers close past the part's width (it slipped out),
    the child is interrupted at once, the pads open (what is left between them is let go here, not
    carried to the next pick) and the guard fails, so a retry above can detect and pick the part
    again instead of placing air.

    "Past the part's width" is judged against the grip the guard finds at its first tick, not the
    part's width alone: pads sink into a part (a prism's corner into a compliant pad, up to 3 mm
    in the real-cell model), so a part held firmly can stand under the nominal width less the
    tolerance; the fingers closing ``grasp_width_tolerance_m`` past that grip (or past the nominal
    width less it, whichever is lower) is what a part leaving looks like.
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
        #: The fingers' width at this run's first tick (m): the grip the pick left; None between runs.
        self.grip_width_m: float | None = None
        # ``held_width_m`` for the settings, part and grip it was worked out for: the guard checks it
        # every tick of its run, and it changes only with them (the grasp is the shape's preferred one).
        self._held_bound: tuple[object, object, float | None, float] | None = None

    def setup(self, **kwargs: object) -> None:
        """Receive the context; without one the guard could never fire, so that is an error."""
        context = kwargs.get("context")
        if not isinstance(context, Context):
            raise BtArrangeError(f"guard {self.name!r} needs setup(context=Context(...)), got {type(context).__name__}")
        self.context = context
        super().setup(**kwargs)

    def held_width_m(self) -> float:
        """Fingers closed narrower than this (m) hold nothing: the grip found at the first tick, or the nominal's.

        A grip at least the nominal least width (``min_held_width_m``) lowers the bound to that grip
        less ``grasp_width_tolerance_m``, never raises it; a narrower first grip leaves the nominal bound.
        """
        assert self.context is not None
        low_m = min_held_width_m(self.context.settings, self.object_type)
        if self.grip_width_m is None or self.grip_width_m < low_m:
            return low_m
        return min(low_m, self.grip_width_m - self.context.settings.grasp_width_tolerance_m)

    def _held_width_now_m(self) -> float:
        """``held_width_m``, worked out anew only when the settings, the part or the grip changed since last tick."""
        assert self.context is not None
        settings, bound = self.context.settings, self._held_bound
        if (
            bound is None
            or bound[0] is not settings
            or bound[1] is not self.object_type
            or bound[2] != self.grip_width_m
        ):
            bound = self._held_bound = (settings, self.object_type, self.grip_width_m, self.held_width_m())
        return bound[3]

    def _holding(self) -> bool:
        if self.context is None:
            return True
        gripper = self.context.robot.gripper
        width_m = gripper.width()
        if self.grip_width_m is None:
            self.grip_width_m = width_m
        low_m = self._held_width_now_m()
        if width_m > low_m:
            return True
        self.feedback_message = (
            f"the part left the gripper: fingers at {width_m * 1000:.1f} mm, "
            f"under the {low_m * 1000:.1f} mm of a held part"
        )
        gripper.open(gripper.max_width_m)
        return False

    def tick(self) -> Iterator[py_trees.behaviour.Behaviour]:
        """py_trees' ``EternalGuard.tick`` and ``Decorator.tick``, step for step.

        The guard is ticked every control period while its child runs: its debug messages are
        formatted only when py_trees logs at DEBUG, and the status is checked by its type
        (``end_tick``) instead of against ``list(Status)`` built at every tick.
        """
        if debug_logging():
            self.logger.debug(f"{self.__class__.__name__}.tick()")
        held = self.condition()
        if isinstance(held, Status):
            held = held != FAILURE
        elif not isinstance(held, bool):
            raise RuntimeError(f"conditional check must return 'bool' or 'common.Status' [{type(held)}]")
        if not held:
            self.stop(FAILURE)
            yield self
            return
        if debug_logging():
            self.logger.debug(f"{self.__class__.__name__}.tick()")
        if self.status != RUNNING:
            self.initialise()
        yield from self.decorated.tick()
        new_status = self.update()
        end_tick(self, new_status)
        yield self

    def terminate(self, new_status: Status) -> None:
        """Forget the grip: the next run judges its own."""
        self.grip_width_m = None
        self._held_bound = None
        super().terminate(new_status)

    def update(self) -> Status:
        """Reflect the child, with its feedback."""
        self.feedback_message = f"holding; {self.decorated.feedback_message}"
        return self.decorated.status
