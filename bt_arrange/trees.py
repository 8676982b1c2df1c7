"""Builders of arrangement trees: the paper's Algorithm 1 as py_trees subtrees.

One object (``arrange_one``)::

    Sequence "arrange red"
    ├── SetBlackboardVariable "red target"        /red/target
    ├── Retry "pick and place red"                 (a lost grasp starts over)
    │   └── Sequence "transfer red"
    │       ├── Detect "detect red"               camera -> /red/pose (``locate``: how the object is found)
    │       ├── Pick "pick red"
    │       └── GraspGuard "while holding red"    fails within a tick when the cube slips out
    │           └── Place "place red"
    ├── Inspect "inspect red after placing"        -> /red/offset_mm, /red/placed_offset_mm
    └── RepeatUntilWithin "correct red"            while /red/offset_mm >= threshold
        └── Sequence "push and inspect red"
            ├── Push "push red"                    along x, then y, then x ...
            └── Inspect "inspect red"

``arrangement(targets)`` checks the plan before anything moves, then chains these per object
(``correct="each"``) or places every object before correcting them all (``"after_all"``, the
paper's Fig. 5), and ends by moving the arm out of the camera's view.

``locate`` says how an object is found before it is picked: ``by_camera()`` (the default, the
top camera's colour detection, ``Detect``) or ``by_depth(seed)`` (the depth-only grasp
estimator of Table 1's row 4, ``EstimateGraspFromDepth``); any ``Callable[[Target], Behaviour]``
that writes ``/<obj>/pose`` will do.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass

import py_trees

from bt_arrange.behaviours import Detect, EstimateGraspFromDepth, GraspGuard, Inspect, MoveHome, Pick, Place, Push, keys
from bt_arrange.behaviours.handling import PUSH_STRATEGIES
from bt_arrange.checks import finite_number, positive_number, whole_number
from bt_arrange.decorators import RepeatUntilWithin
from bt_arrange.errors import PlanError, UnreachableError
from bt_arrange.geometry import PlanarPose
from bt_arrange.motion import ArmKinematics, gripper_down_pose
from bt_arrange.perception import DEFAULT_COLOUR_TABLE
from bt_arrange.perception.depth_grasp import DepthGraspEstimator
from bt_arrange.settings import ManipulationSettings

#: Cube centres closer than this leave the pads no room beside a face: a push starts with the
#: pads 10 mm behind the face and 22 mm deep, so they reach 57 mm from the cube's centre, where a
#: neighbour's face must not be (57 mm + half an edge, rounded up).
MIN_TARGET_SPACING_M = 0.09
CORRECT_MODES = ("each", "after_all")


@dataclass(frozen=True)
class Target:
    """Where one cube should end up: ``colour``, ``x_m``, ``y_m`` and ``yaw_rad`` on the table.

    ``name`` is the object's blackboard namespace (``/<name>/pose``); it defaults to the colour.
    """

    colour: str
    x_m: float
    y_m: float
    yaw_rad: float = 0.0
    name: str | None = None

    @property
    def obj(self) -> str:
        """The object's name: its blackboard namespace."""
        return self.name or self.colour

    @property
    def planar(self) -> PlanarPose:
        """The target as a planar pose."""
        return PlanarPose(self.x_m, self.y_m, self.yaw_rad)


def validate_targets(
    targets: Iterable[object],
    *,
    colours: Iterable[str] | None = None,
    kinematics: ArmKinematics | None = None,
    settings: ManipulationSettings | None = None,
) -> list[Target]:
    """Check a plan before anything moves; a ``PlanError`` names the first problem.

    Malformed entries, unknown colours, two targets for one object, a target out of the arm's
    reach and two targets closer than ``MIN_TARGET_SPACING_M`` are each a clear error.
    """
    if isinstance(targets, (str, bytes)) or not isinstance(targets, Iterable):
        raise PlanError(f"targets must be a list of Target(colour, x_m, y_m, yaw_rad), got {targets!r}")
    plan = list(targets)
    if not plan:
        raise PlanError("no targets: an arrangement needs at least one Target(colour, x_m, y_m, yaw_rad)")
    known = list(colours) if colours is not None else list(DEFAULT_COLOUR_TABLE.names)
    settings = settings or ManipulationSettings()
    seen: dict[str, int] = {}
    for index, target in enumerate(plan, start=1):
        if not isinstance(target, Target):
            raise PlanError(f"target {index} is {target!r}, not a Target(colour, x_m, y_m, yaw_rad)")
        for field in ("x_m", "y_m", "yaw_rad"):
            finite_number(field, getattr(target, field), where=f"target {index} ({target.colour}): ")
        if target.colour not in known:
            raise PlanError(f"target {index}: unknown colour {target.colour!r}; known colours: {', '.join(known)}")
        for taken, what in ((target.obj, "named"), (target.colour, "coloured")):
            if taken in seen:
                raise PlanError(
                    f"targets {seen[taken]} and {index} are both {what} {taken!r}: "
                    "the camera tells cubes apart by colour, so each colour is one object"
                )
        seen[target.obj] = seen[target.colour] = index
    checked = [target for target in plan if isinstance(target, Target)]
    kinematics = kinematics or ArmKinematics()
    for target in checked:
        for height_m in (settings.grasp_height_m, settings.approach_height_m):
            try:
                kinematics.check_reachable(gripper_down_pose(target.x_m, target.y_m, height_m, target.yaw_rad))
            except UnreachableError as error:
                raise PlanError(
                    f"target {target.obj} at ({target.x_m:.3f}, {target.y_m:.3f}) m is out of reach: {error}"
                ) from error
    for i, first in enumerate(checked):
        for second in checked[i + 1 :]:
            distance_m = math.hypot(first.x_m - second.x_m, first.y_m - second.y_m)
            if distance_m < MIN_TARGET_SPACING_M:
                raise PlanError(
                    f"targets {first.obj} and {second.obj} are {distance_m * 1000:.0f} mm apart: the pads need "
                    f"at least {MIN_TARGET_SPACING_M * 1000:.0f} mm between cube centres to grasp and push"
                )
    return checked


def check_threshold(threshold_mm: object, settings: ManipulationSettings | None = None) -> float:
    """The threshold in millimetres, or a ``PlanError``: it must be a number a push can correct.

    The floor is ``settings.min_threshold_mm`` (0.28 mm with the default ``min_push_m`` of 0.2 mm):
    below it a correction loop could "push" without moving the arm.
    """
    value_mm = positive_number("threshold_mm", threshold_mm, "mm")
    settings = settings or ManipulationSettings()
    floor_mm = settings.min_threshold_mm
    if value_mm < floor_mm:
        raise PlanError(
            f"threshold {threshold_mm:g} mm is below {floor_mm:.2f} mm, the smallest offset a push can correct "
            f"(pushes shorter than min_push_m = {settings.min_push_m * 1000:.1f} mm along an axis are not made)"
        )
    return value_mm


def set_target(target: Target) -> py_trees.behaviour.Behaviour:
    """Write the object's target to ``/<obj>/target``."""
    return py_trees.behaviours.SetBlackboardVariable(
        name=f"{target.obj} target",
        variable_name=keys.key(target.obj, keys.TARGET),
        variable_value=target.planar,
        overwrite=True,
    )


#: How an object is found before it is picked: a behaviour that writes ``/<obj>/pose``.
Locate = Callable[["Target"], py_trees.behaviour.Behaviour]


def by_camera() -> Locate:
    """Find the object with the top camera's colour detection: ``Detect "detect <obj>"`` (the default)."""

    def locate(target: Target) -> py_trees.behaviour.Behaviour:
        return Detect(f"detect {target.obj}", target.obj, target.colour)

    return locate


def by_depth(
    seed: int = 0, *, estimator: DepthGraspEstimator | None = None, near_xy_m: tuple[float, float] | None = None
) -> Locate:
    """Estimate the grasp from the depth image alone: ``EstimateGraspFromDepth`` (Table 1, row 4).

    ``seed`` seeds the depth noise (each attempt draws afresh), ``near_xy_m`` is the optional
    colour-blind hint; see :class:`~bt_arrange.behaviours.EstimateGraspFromDepth`.
    """

    def locate(target: Target) -> py_trees.behaviour.Behaviour:
        return EstimateGraspFromDepth(
            f"estimate {target.obj} grasp from depth",
            target.obj,
            target.colour,
            estimator=estimator,
            near_xy_m=near_xy_m,
            seed=seed,
        )

    return locate


def transfer(target: Target, max_regrasps: int = 3, *, locate: Locate | None = None) -> py_trees.behaviour.Behaviour:
    """Locate, pick and place one object; a cube lost on the way is located and picked again.

    ``locate`` builds the behaviour that finds the object (default ``by_camera()``: Detect).
    """
    obj = target.obj
    carry = py_trees.composites.Sequence(
        name=f"transfer {obj}",
        memory=True,
        children=[
            (locate or by_camera())(target),
            Pick(f"pick {obj}", obj),
            GraspGuard(f"while holding {obj}", Place(f"place {obj}", obj)),
        ],
    )
    whole_number("max_regrasps", max_regrasps)
    # py_trees' Retry counts every attempt: the first one plus max_regrasps more.
    return py_trees.decorators.Retry(name=f"pick and place {obj}", child=carry, num_failures=max_regrasps + 1)


def check_strategy(strategy: object) -> str:
    """The push strategy's name, or a ``PlanError`` listing the strategies."""
    if strategy not in PUSH_STRATEGIES:
        raise PlanError(f"strategy={strategy!r}: choose one of {', '.join(PUSH_STRATEGIES)}")
    return str(strategy)


def correction(
    target: Target, threshold_mm: float = 1.0, max_pushes: int = 10, strategy: str = "paper"
) -> py_trees.behaviour.Behaviour:
    """Push and inspect one object until it lies within ``threshold_mm`` of its target.

    ``strategy`` is the push's (``Push``): ``"paper"``, the paper's alternating push, ``"learned"`` or ``"diagonal"``.
    """
    check_threshold(threshold_mm)
    check_strategy(strategy)
    obj, colour = target.obj, target.colour
    push_and_look = py_trees.composites.Sequence(
        name=f"push and inspect {obj}",
        memory=True,
        children=[Push(f"push {obj}", obj, strategy), Inspect(f"inspect {obj}", obj, colour)],
    )
    return RepeatUntilWithin(
        name=f"correct {obj} to {threshold_mm:g} mm",
        child=push_and_look,
        offset_key=keys.key(obj, keys.OFFSET_MM),
        threshold_mm=threshold_mm,
        max_attempts=max_pushes,
        corrections_key=keys.key(obj, keys.CORRECTIONS),
        obj=obj,
    )


def arrange_one(
    target: Target,
    threshold_mm: float = 1.0,
    max_pushes: int = 10,
    max_regrasps: int = 3,
    *,
    locate: Locate | None = None,
    strategy: str = "paper",
) -> py_trees.behaviour.Behaviour:
    """Algorithm 1 for one object: locate (detect), pick, place, inspect, push until within the threshold."""
    obj = target.obj
    return py_trees.composites.Sequence(
        name=f"arrange {obj}",
        memory=True,
        children=[
            set_target(target),
            transfer(target, max_regrasps, locate=locate),
            Inspect(f"inspect {obj} after placing", obj, target.colour, after_placing=True),
            correction(target, threshold_mm, max_pushes, strategy),
        ],
    )


class Arrangement(py_trees.composites.Sequence):
    """The root of an arrangement tree; remembers its plan so a runner can report per object.

    ``place_all`` is the subtree that places every object before any is corrected (the paper's
    Fig. 5, ``correct="after_all"``), None otherwise: a recorder saves its "after placing" picture then.
    """

    def __init__(
        self,
        name: str,
        children: Sequence[py_trees.behaviour.Behaviour],
        targets: list[Target],
        threshold_mm: float,
        *,
        place_all: py_trees.behaviour.Behaviour | None = None,
    ) -> None:
        super().__init__(name=name, memory=True, children=list(children))
        self.targets = targets
        self.threshold_mm = threshold_mm
        self.place_all = place_all


def arrangement(
    targets: Iterable[Target],
    threshold_mm: float = 1.0,
    max_pushes: int = 10,
    correct: str = "each",
    *,
    max_regrasps: int = 3,
    keep_going: bool = True,
    locate: Locate | None = None,
    strategy: str = "paper",
) -> Arrangement:
    """An arrangement of several objects, checked before anything moves.

    ``correct="each"`` corrects every object right after placing it (Algorithm 1);
    ``"after_all"`` places all of them first and corrects them afterwards (the paper's Fig. 5).
    With ``keep_going`` (the default) an object that cannot be finished does not stop the others:
    its subtree's failure is kept in the log and in the report, and the next object is handled.
    ``locate`` says how each object is found before it is picked (default ``by_camera()``).
    ``strategy`` chooses the pushes: ``"paper"`` (alternating x and y, Table 1's), ``"learned"``
    (``Push``: the larger axis first, each push's landing error learned) or ``"diagonal"`` (learned,
    and the same push corrects the other axis too).
    """
    check_strategy(strategy)
    if correct not in CORRECT_MODES:
        raise PlanError(f"correct={correct!r}: choose one of {', '.join(CORRECT_MODES)}")
    check_threshold(threshold_mm)
    whole_number("max_pushes", max_pushes)
    plan = validate_targets(targets)

    def carry_on(subtree: py_trees.behaviour.Behaviour, obj: str) -> py_trees.behaviour.Behaviour:
        if not keep_going:
            return subtree
        return py_trees.decorators.FailureIsSuccess(name=f"then the next ({obj})", child=subtree)

    if correct == "each":
        children = [
            carry_on(arrange_one(t, threshold_mm, max_pushes, max_regrasps, locate=locate, strategy=strategy), t.obj)
            for t in plan
        ]
    else:
        place_all = py_trees.composites.Sequence(
            name="place all",
            memory=True,
            children=[
                carry_on(
                    py_trees.composites.Sequence(
                        name=f"place {t.obj} first",
                        memory=True,
                        children=[
                            set_target(t),
                            transfer(t, max_regrasps, locate=locate),
                            Inspect(f"inspect {t.obj} after placing", t.obj, t.colour, after_placing=True),
                        ],
                    ),
                    t.obj,
                )
                for t in plan
            ],
        )
        correct_all = py_trees.composites.Sequence(
            name="correct all",
            memory=True,
            children=[
                carry_on(
                    py_trees.composites.Sequence(
                        name=f"correct {t.obj} after all",
                        memory=True,
                        children=[
                            # An object whose transfer failed was never placed: nothing to correct.
                            py_trees.behaviours.CheckBlackboardVariableExists(
                                name=f"{t.obj} was placed", variable_name=keys.key(t.obj, keys.PLACED_OFFSET_MM)
                            ),
                            Inspect(f"inspect {t.obj} before correcting", t.obj, t.colour),
                            correction(t, threshold_mm, max_pushes, strategy),
                        ],
                    ),
                    t.obj,
                )
                for t in plan
            ],
        )
        children = [place_all, correct_all]
    return Arrangement(
        name="arrangement",
        children=[*children, MoveHome("park the arm")],
        targets=plan,
        threshold_mm=float(threshold_mm),
        place_all=children[0] if correct == "after_all" else None,
    )
