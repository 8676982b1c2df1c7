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

import operator
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import py_trees

from bt_arrange.behaviours import (
    Detect,
    EstimateGraspFromDepth,
    GraspGuard,
    Inspect,
    MoveHome,
    Pick,
    Place,
    Push,
    Recheck,
    keys,
)
from bt_arrange.behaviours.push import PUSH_STRATEGIES
from bt_arrange.checks import finite_number, positive_number, whole_number
from bt_arrange.decorators import RepeatUntilWithin
from bt_arrange.errors import PlanError, UnreachableError
from bt_arrange.geometry import PlanarPose
from bt_arrange.layout import DIRECTIONS, Pads, Part, Release, Step, free_push_directions, plan_layout, restage_releases
from bt_arrange.motion import ArmKinematics, gripper_down_pose
from bt_arrange.objects import CUBE, ObjectType, PartOnTable, kind_of
from bt_arrange.perception import DEFAULT_COLOUR_TABLE, ColourTable
from bt_arrange.perception.depth_grasp import DepthGraspEstimator
from bt_arrange.ports import COLOURS, DOUBLE, OFF_DOUBLE, Port, targets_type
from bt_arrange.settings import ManipulationSettings

CORRECT_MODES = ("each", "after_all")
#: The yaw error (degrees) the correction loop leaves by default.
DEFAULT_YAW_THRESHOLD_DEG = 1.0


@dataclass(frozen=True)
class Target(PartOnTable):
    """Where one part should end up: ``colour`` (of its top face), ``x_m``, ``y_m`` and ``yaw_rad`` on the table.

    ``name`` is the object's blackboard namespace (``/<name>/pose``); it defaults to the colour.
    ``object_type`` is its size (default the paper's cube, ``bt_arrange.objects.CUBE``). Several
    targets may share a type and a colour (identical parts): each needs its own name.
    """

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

    Malformed entries, unknown colours, two targets for one object, one colour on two types, a
    target out of the arm's reach, and a plan no order and approach can build (``plan_steps``:
    targets that overlap or lie closer than 2 mm, a part the pads find no room beside, each part's
    footprint its type's size) are each a clear error. Targets of one type and colour are
    identical parts (each with its own name).
    """
    if isinstance(targets, (str, bytes)) or not isinstance(targets, Iterable):
        raise PlanError(f"targets must be a list of Target(colour, x_m, y_m, yaw_rad), got {targets!r}")
    plan = list(targets)
    if not plan:
        raise PlanError("no targets: an arrangement needs at least one Target(colour, x_m, y_m, yaw_rad)")
    known = list(colours) if colours is not None else list(DEFAULT_COLOUR_TABLE.names)
    settings = settings or ManipulationSettings()
    names: dict[str, int] = {}
    type_of_colour: dict[str, tuple[ObjectType, int]] = {}
    for index, target in enumerate(plan, start=1):
        if not isinstance(target, Target):
            raise PlanError(f"target {index} is {target!r}, not a Target(colour, x_m, y_m, yaw_rad)")
        for field_name in ("x_m", "y_m", "yaw_rad"):
            finite_number(field_name, getattr(target, field_name), where=f"target {index} ({target.colour}): ")
        if not isinstance(target.object_type, ObjectType):
            raise PlanError(f"target {index} ({target.obj}): object_type {target.object_type!r} is not an ObjectType")
        if target.colour not in known:
            raise PlanError(f"target {index}: unknown colour {target.colour!r}; known colours: {', '.join(known)}")
        if target.obj in names:
            first_index = names[target.obj]
            hint = (
                f" (identical parts need a name each, e.g. name='{target.colour} 1' and name='{target.colour} 2')"
                if target.name is None
                else ""
            )
            raise PlanError(f"targets {first_index} and {index} are both named {target.obj!r}{hint}")
        names[target.obj] = index
        seen = type_of_colour.get(target.colour)
        if seen is not None and seen[0] != target.object_type:
            raise PlanError(
                f"targets {seen[1]} and {index} are both {target.colour} but of types {seen[0].name!r} and "
                f"{target.object_type.name!r}: the camera tells parts apart by colour, so one colour is one type"
            )
        type_of_colour.setdefault(target.colour, (target.object_type, index))
    checked = [target for target in plan if isinstance(target, Target)]
    kinematics = kinematics or ArmKinematics()
    for target in checked:
        grasp_m = settings.grasp_height_m + (target.object_type.grasp_height_m - CUBE.grasp_height_m)
        approach_m = target.object_type.approach_height_m(settings.approach_height_m)
        for height_m in (grasp_m, approach_m):
            try:
                kinematics.check_reachable(gripper_down_pose(target.x_m, target.y_m, height_m, target.yaw_rad))
            except UnreachableError as error:
                raise PlanError(
                    f"target {target.obj} at ({target.x_m:.3f}, {target.y_m:.3f}) m is out of reach: {error}"
                ) from error
    plan_steps(checked, settings)
    return checked


def kinds(targets: Iterable[Target]) -> dict[str, tuple[PlanarPose, ...]]:
    """For each target's object, the targets of every part of its kind (type and colour), its own among them.

    Only kinds of several parts (identical parts) are listed; an object alone in its kind is left out.
    """
    plan = list(targets)
    by_kind: dict[tuple[ObjectType, str], list[Target]] = {}
    for target in plan:
        by_kind.setdefault(kind_of(target), []).append(target)
    return {
        target.obj: tuple(t.planar for t in by_kind[kind_of(target)])
        for target in plan
        if len(by_kind[kind_of(target)]) > 1
    }


def footprint_m(target: Target, settings: ManipulationSettings | None = None) -> tuple[float, float]:
    """The part's size on the table (x, y in its own frame, metres): its type's top face.

    The cube's is the settings' edge (``cube_edge_m``, 50 mm unless a test changes it).
    """
    kind = getattr(target, "object_type", CUBE)
    if kind == CUBE:
        edge = (settings or ManipulationSettings()).cube_edge_m
        return edge, edge
    return float(kind.top_size_m[0]), float(kind.top_size_m[1])


def parts_of(targets: Iterable[Target], settings: ManipulationSettings | None = None) -> list[Part]:
    """The plan's targets as footprints for ``bt_arrange.layout``, each held only across a side the stroke spans."""
    return [
        Part(t.obj, t.x_m, t.y_m, t.yaw_rad, *footprint_m(t, settings), grasp_axes=_grasp_axes(t.object_type))
        for t in targets
    ]


def _grasp_axes(kind: ObjectType) -> tuple[str, ...]:
    """The axes of the part's frame the pads may close across: its grasp axis, and the other too on a square top."""
    return ("x", "y") if kind.square_top else (kind.grasp_axis,)


def plan_steps(
    targets: Sequence[Target], settings: ManipulationSettings | None = None, order: Sequence[str] | None = None
) -> list[Step]:
    """The layout's steps (``bt_arrange.layout.plan_layout``): the placing order and each part's approach."""
    settings = settings or ManipulationSettings()
    return plan_layout(parts_of(targets, settings), Pads.from_settings(settings), order)


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
        return Detect(f"detect {target.obj}", target.obj, target.colour, target.object_type)

    return locate


def by_depth(
    seed: int = 0, *, estimator: DepthGraspEstimator | None = None, near_xy_m: tuple[float, float] | None = None
) -> Locate:
    """Estimate the grasp from the depth image alone: ``EstimateGraspFromDepth`` (Table 1, row 4).

    ``seed`` seeds the depth noise (each attempt draws afresh), ``near_xy_m`` is the optional
    colour-blind hint; see :class:`~bt_arrange.behaviours.EstimateGraspFromDepth`.
    """

    def locate(target: Target) -> py_trees.behaviour.Behaviour:
        if target.object_type != CUBE:
            raise PlanError(
                f"target {target.obj}: the depth-only grasp estimator knows the paper's 5 cm cube only, "
                f"not a {target.object_type.name} ({target.object_type.size_text})"
            )
        return EstimateGraspFromDepth(
            f"estimate {target.obj} grasp from depth",
            target.obj,
            target.colour,
            estimator=estimator,
            near_xy_m=near_xy_m,
            seed=seed,
        )

    return locate


def transfer(
    target: Target,
    max_regrasps: int = 3,
    *,
    locate: Locate | None = None,
    kind_targets: Sequence[PlanarPose] = (),
    release: Release | None = None,
) -> py_trees.behaviour.Behaviour:
    """Locate, pick and place one object; a part lost on the way is located and picked again.

    ``locate`` builds the behaviour that finds the object (default ``by_camera()``: Detect).
    ``kind_targets`` (identical parts: the targets of the kind) let a Detect choose a part that
    is not at one of them. ``release`` says where the pads go among neighbours
    (``bt_arrange.layout``; default: anywhere).
    """
    obj = target.obj
    kind = target.object_type

    def find() -> py_trees.behaviour.Behaviour:
        finder = (locate or by_camera())(target)
        if kind_targets and isinstance(finder, Detect):
            finder.among(kind_targets)
        return finder

    look_again: list[py_trees.behaviour.Behaviour] = []
    if release is not None:
        # Among neighbours the part's offset in the pads (unknown while held: a pick 2 cm off
        # places it 2 cm off) would carry into a neighbour: set it down where it was picked, look
        # at it again, and pick it centred.
        look_again = [
            GraspGuard(
                f"while setting {obj} down",
                Place(f"set {obj} down to look again", obj, kind, where="pick"),
            ),
            find(),
            Pick(f"pick {obj} centred", obj, kind),
        ]
    carry = py_trees.composites.Sequence(
        name=f"transfer {obj}",
        memory=True,
        children=[
            find(),
            Pick(f"pick {obj}", obj, kind),
            *look_again,
            GraspGuard(f"while holding {obj}", Place(f"place {obj}", obj, kind, release=release)),
        ],
    )
    whole_number("max_regrasps", max_regrasps)
    # py_trees' Retry counts every attempt: the first one plus max_regrasps more.
    return py_trees.decorators.Retry(name=f"pick and place {obj}", child=carry, num_failures=max_regrasps + 1)


def inspect(
    target: Target, name: str, *, after_placing: bool = False, kind_targets: Sequence[PlanarPose] = ()
) -> Inspect:
    """The Inspect of one object (its type, colour and, for identical parts, the targets of its kind)."""
    return Inspect(
        name, target.obj, target.colour, after_placing, object_type=target.object_type, kind_targets=kind_targets
    )


def check_strategy(strategy: object) -> str:
    """The push strategy's name, or a ``PlanError`` listing the strategies."""
    if strategy not in PUSH_STRATEGIES:
        raise PlanError(f"strategy={strategy!r}: choose one of {', '.join(PUSH_STRATEGIES)}")
    return str(strategy)


def correction(
    target: Target,
    threshold_mm: float = 1.0,
    max_pushes: int = 10,
    strategy: str = "paper",
    *,
    yaw_threshold_deg: float | None = DEFAULT_YAW_THRESHOLD_DEG,
    kind_targets: Sequence[PlanarPose] = (),
    towards: tuple[str, ...] | None = None,
    restage: dict[str, Release] | None = None,
    push_opening_m: float | None = None,
    count: bool = True,
    label: str = "",
) -> py_trees.behaviour.Behaviour:
    """Push and inspect one object until it lies within ``threshold_mm`` (and ``yaw_threshold_deg``) of its target.

    ``towards``: the directions (target frame) it may be pushed, the sides a neighbour blocks left
    out (default all four). ``restage``: per blocked direction, a release on the other side; when
    a correction needs a blocked side, Push fails and the part is picked up and released there,
    from where a push is free. ``count``: the loop's pushes are the object's ``corrections``.
    ``strategy`` is the push's (``Push``): ``"paper"``, the paper's alternating push, ``"learned"``
    or ``"diagonal"``.
    ``yaw_threshold_deg=None`` corrects the position only.
    """
    check_threshold(threshold_mm)
    check_strategy(strategy)
    if yaw_threshold_deg is not None:
        positive_number("yaw_threshold_deg", yaw_threshold_deg, "deg")
    obj = target.obj
    push: py_trees.behaviour.Behaviour = Push(
        f"push {obj}{label}",
        obj,
        strategy,
        target.object_type,
        yaw_threshold_deg,
        towards=towards,
        opening_m=push_opening_m,
    )
    if restage:
        push = py_trees.composites.Selector(
            name=f"push {obj} from a free side{label}",
            memory=True,
            children=[push, *(_restage(target, d, release, label) for d, release in restage.items())],
        )
    push_and_look = py_trees.composites.Sequence(
        name=f"push and inspect {obj}{label}",
        memory=True,
        children=[push, inspect(target, f"inspect {obj}{label}", kind_targets=kind_targets)],
    )
    return RepeatUntilWithin(
        name=f"correct {obj} to {threshold_mm:g} mm{label}",
        child=push_and_look,
        offset_key=keys.key(obj, keys.OFFSET_MM),
        threshold_mm=threshold_mm,
        max_attempts=max_pushes,
        corrections_key=keys.key(obj, keys.CORRECTIONS) if count else None,
        obj=obj,
        yaw_key=keys.key(obj, keys.YAW_ERROR_DEG),
        yaw_threshold_deg=yaw_threshold_deg,
    )


def _restage(target: Target, towards: str, release: Release, label: str) -> py_trees.behaviour.Behaviour:
    """When Push needed ``towards`` from a blocked side: pick the part up, release it past the target on that side."""
    obj = target.obj
    dx, dy = release.offset_m
    return py_trees.composites.Sequence(
        name=f"release {obj} again {dx * 1000:+.0f}, {dy * 1000:+.0f} mm to push it {towards}{label}",
        memory=True,
        children=[
            py_trees.behaviours.CheckBlackboardVariableValue(
                name=f"{obj} needs a push {towards}{label}",
                check=py_trees.common.ComparisonExpression(keys.key(obj, keys.BLOCKED_TOWARDS), towards, operator.eq),
            ),
            Pick(f"pick {obj} again{label}", obj, target.object_type, grasp=release),
            GraspGuard(
                f"while holding {obj} again{label}",
                Place(f"place {obj} again{label}", obj, target.object_type, release=release),
            ),
        ],
    )


def arrange_one(
    target: Target,
    threshold_mm: float = 1.0,
    max_pushes: int = 10,
    max_regrasps: int = 3,
    *,
    locate: Locate | None = None,
    step: Step | None = None,
    neighbours: Sequence[tuple[Target, tuple[str, ...], dict[str, Release]]] = (),
    strategy: str = "paper",
    yaw_threshold_deg: float | None = DEFAULT_YAW_THRESHOLD_DEG,
    kind_targets: Sequence[PlanarPose] = (),
    kind_of_neighbour: Mapping[str, Sequence[PlanarPose]] | None = None,
) -> py_trees.behaviour.Behaviour:
    """Algorithm 1 for one object: locate (detect), pick, place, inspect, push until within the thresholds.

    ``step`` (from ``plan_steps``) places it among neighbours: its release, the sides it may be
    pushed from and how to release it again. ``neighbours`` are the parts placed before it nearby,
    each with the directions it may be pushed and its restaging once this one is down: each is
    looked at again afterwards (``Recheck``) and corrected when it moved beyond the threshold.
    ``kind_targets`` (identical parts) are the targets of its kind; ``kind_of_neighbour`` gives
    a neighbour's.
    """
    obj = target.obj
    dense = step is not None and _is_dense(step)
    release = step.release if dense and step is not None else None
    towards = step.push_towards if dense and step is not None else None
    restage = step.restage if dense and step is not None else None
    children: list[py_trees.behaviour.Behaviour] = [
        set_target(target),
        transfer(target, max_regrasps, locate=locate, kind_targets=kind_targets, release=release),
        inspect(target, f"inspect {obj} after placing", after_placing=True, kind_targets=kind_targets),
        correction(
            target,
            threshold_mm,
            max_pushes,
            strategy,
            yaw_threshold_deg=yaw_threshold_deg,
            kind_targets=kind_targets,
            towards=towards,
            restage=restage,
            push_opening_m=_opening(step, dense),
        ),
    ]
    for neighbour, sides, again in neighbours:
        label = f" after {obj}"
        neighbour_kind = (kind_of_neighbour or {}).get(neighbour.obj, ())
        children.append(
            py_trees.composites.Sequence(
                name=f"look again at {neighbour.obj}{label}",
                memory=True,
                children=[
                    Recheck(
                        f"look at {neighbour.obj}{label}",
                        neighbour.obj,
                        neighbour.colour,
                        after=obj,
                        object_type=neighbour.object_type,
                        kind_targets=neighbour_kind,
                    ),
                    correction(
                        neighbour,
                        threshold_mm,
                        max_pushes,
                        strategy,
                        yaw_threshold_deg=yaw_threshold_deg,
                        kind_targets=neighbour_kind,
                        towards=sides,
                        restage=again,
                        push_opening_m=_DENSE_PADS.push_opening_m(parts_of([neighbour])[0], "x"),
                        count=False,
                        label=label,
                    ),
                ],
            )
        )
    return py_trees.composites.Sequence(name=f"arrange {obj}", memory=True, children=children)


_DENSE_PADS = Pads.from_settings(ManipulationSettings())


def _opening(step: Step | None, dense: bool) -> float | None:
    """The push opening among neighbours (along x; Push keeps it within the pushed face's own width), None when free."""
    return _DENSE_PADS.push_opening_m(step.part, "x") if dense and step is not None else None


def _dense_release(step: Step) -> Release | None:
    return step.release if _is_dense(step) else None


def _is_dense(step: Step) -> bool:
    """A step among neighbours: released away from its target, near placed parts, or with a blocked side."""
    return step.release.staged or bool(step.neighbours) or set(step.push_towards) != set(DIRECTIONS)


#: The port type of a plan: ``colour,x_m,y_m,yaw_rad[,name[,type=x_m*y_m*z_m]]`` per target, read into ``Target``s.
TARGETS = targets_type(Target)


class Arrangement(py_trees.composites.Sequence):
    """The root of an arrangement tree; remembers its plan so a runner can report per object.

    ``place_all`` is the subtree that places every object before any is corrected (the paper's
    Fig. 5, ``correct="after_all"``), None otherwise: a recorder saves its "after placing" picture then.
    """

    #: The node's description in the XML ``TreeNodesModel``.
    node_description = "a sequence with memory that knows its plan (the report and the scene come from it)"

    @classmethod
    def provided_ports(cls) -> tuple[Port, ...]:
        """The plan, its thresholds and its colours (BehaviorTree.CPP's ``providedPorts``)."""
        return (
            Port("targets", TARGETS, description="colour,x_m,y_m,yaw_rad[,name] per object, separated by ;"),
            Port("threshold_mm", DOUBLE, description="the accuracy threshold the report checks [mm]"),
            Port("yaw_threshold_deg", OFF_DOUBLE, None, "the yaw threshold the report checks [deg] (0: position only)"),
            Port("colours", COLOURS, DEFAULT_COLOUR_TABLE, "the plan's own colours: name:rgb:r,g,b;... (empty: none)"),
        )

    @classmethod
    def from_ports(
        cls, name: str, values: Mapping[str, Any], children: Sequence[py_trees.behaviour.Behaviour]
    ) -> Arrangement:
        """The node of an XML tree: its plan is checked (``validate_targets``) against its colours first."""
        colours: ColourTable = values["colours"]
        return cls(
            name,
            children,
            validate_targets(values["targets"], colours=colours.names),
            values["threshold_mm"],
            yaw_threshold_deg=values["yaw_threshold_deg"],
            colours=colours,
        )

    def __init__(
        self,
        name: str,
        children: Sequence[py_trees.behaviour.Behaviour],
        targets: list[Target],
        threshold_mm: float,
        *,
        place_all: py_trees.behaviour.Behaviour | None = None,
        yaw_threshold_deg: float | None = None,
        colours: ColourTable | None = None,
    ) -> None:
        super().__init__(name=name, memory=True, children=list(children))
        self.targets = targets
        self.threshold_mm = threshold_mm
        self.place_all = place_all
        #: The yaw error (degrees) the correction loop leaves; None: position only.
        self.yaw_threshold_deg = yaw_threshold_deg
        #: The colour table the plan's colours come from: the cell paints with it, the camera reads it.
        self.colours = colours if colours is not None else DEFAULT_COLOUR_TABLE


def arrangement(
    targets: Iterable[Target],
    threshold_mm: float = 1.0,
    max_pushes: int = 10,
    correct: str = "each",
    *,
    max_regrasps: int = 3,
    keep_going: bool = True,
    locate: Locate | None = None,
    order: Sequence[str] | None = None,
    strategy: str = "paper",
    yaw_threshold_deg: float | None = DEFAULT_YAW_THRESHOLD_DEG,
    colours: ColourTable | Mapping[str, object] | None = None,
) -> Arrangement:
    """An arrangement of several objects, checked before anything moves.

    ``correct="each"`` corrects every object right after placing it (Algorithm 1);
    ``"after_all"`` places all of them first and corrects them afterwards (the paper's Fig. 5).
    With ``keep_going`` (the default) an object that cannot be finished does not stop the others:
    its subtree's failure is kept in the log and in the report, and the next object is handled.
    ``locate`` says how each object is found before it is picked (default ``by_camera()``).
    ``order`` (object names) is the placing order; by default the layout chooses one
    (``bt_arrange.layout.plan_layout``: the plan's own order where it can be built). Among
    neighbours each part is released where the pads fit, pushed only from free sides, and the
    parts near it are looked at again once it is down.
    ``strategy`` chooses the pushes: ``"paper"`` (alternating x and y, Table 1's), ``"learned"``
    (``Push``: the larger axis first, each push's landing error learned) or ``"diagonal"`` (learned,
    and the same push corrects the other axis too).
    ``yaw_threshold_deg`` (default 1) is the yaw error each object must end under, too (None:
    position only). ``colours`` is the colour table of the plan (default the cell's four; a
    user's colours join it with ``DEFAULT_COLOUR_TABLE.with_colour(ColourRange.around_rgb(...))``).
    """
    check_strategy(strategy)
    if correct not in CORRECT_MODES:
        raise PlanError(f"correct={correct!r}: choose one of {', '.join(CORRECT_MODES)}")
    check_threshold(threshold_mm)
    whole_number("max_pushes", max_pushes)
    if yaw_threshold_deg is not None:
        positive_number("yaw_threshold_deg", yaw_threshold_deg, "deg")
    if colours is not None and not isinstance(colours, ColourTable):
        raise PlanError(f"colours must be a ColourTable (bt_arrange.perception), got {type(colours).__name__}")
    table = colours if isinstance(colours, ColourTable) else DEFAULT_COLOUR_TABLE
    plan = validate_targets(targets, colours=table.names)
    siblings = kinds(plan)
    steps = plan_steps(plan, order=order)
    steps_by_obj = {st.part.name: st for st in steps}
    by_obj = {t.obj: t for t in plan}
    ordered = [by_obj[st.part.name] for st in steps]
    pads = Pads.from_settings(ManipulationSettings())

    def carry_on(subtree: py_trees.behaviour.Behaviour, obj: str) -> py_trees.behaviour.Behaviour:
        if not keep_going:
            return subtree
        return py_trees.decorators.FailureIsSuccess(name=f"then the next ({obj})", child=subtree)

    if correct == "each":
        children = []
        for index, step in enumerate(steps):
            placed = [(st.part.name, st.part.footprint) for st in steps[: index + 1]]
            neighbours = [
                (
                    by_obj[name],
                    free_push_directions(steps_by_obj[name].part, placed, pads),
                    restage_releases(steps_by_obj[name].part, placed, pads),
                )
                for name in step.neighbours
            ]
            target = by_obj[step.part.name]
            subtree = arrange_one(
                target,
                threshold_mm,
                max_pushes,
                max_regrasps,
                locate=locate,
                strategy=strategy,
                step=step,
                neighbours=neighbours,
                yaw_threshold_deg=yaw_threshold_deg,
                kind_targets=siblings.get(target.obj, ()),
                kind_of_neighbour=siblings,
            )
            children.append(carry_on(subtree, target.obj))
    else:
        everything = [(st.part.name, st.part.footprint) for st in steps]
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
                            transfer(
                                t,
                                max_regrasps,
                                locate=locate,
                                kind_targets=siblings.get(t.obj, ()),
                                release=_dense_release(steps_by_obj[t.obj]),
                            ),
                            inspect(
                                t,
                                f"inspect {t.obj} after placing",
                                after_placing=True,
                                kind_targets=siblings.get(t.obj, ()),
                            ),
                        ],
                    ),
                    t.obj,
                )
                for t in ordered
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
                            inspect(t, f"inspect {t.obj} before correcting", kind_targets=siblings.get(t.obj, ())),
                            correction(
                                t,
                                threshold_mm,
                                max_pushes,
                                strategy,
                                yaw_threshold_deg=yaw_threshold_deg,
                                kind_targets=siblings.get(t.obj, ()),
                                towards=free_push_directions(steps_by_obj[t.obj].part, everything, pads),
                                restage=restage_releases(steps_by_obj[t.obj].part, everything, pads),
                            ),
                        ],
                    ),
                    t.obj,
                )
                for t in ordered
            ],
        )
        children = [place_all, correct_all]
    return Arrangement(
        name="arrangement",
        children=[*children, MoveHome("park the arm")],
        targets=plan,
        threshold_mm=float(threshold_mm),
        place_all=children[0] if correct == "after_all" else None,
        yaw_threshold_deg=None if yaw_threshold_deg is None else float(yaw_threshold_deg),
        colours=table,
    )
