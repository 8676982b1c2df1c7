"""The tree of an arrangement: the paper's Algorithm 1, rendered from a compiled plan.

One part (``render_part`` of a ``PartStep``)::

    Sequence "arrange red"
    ├── SetBlackboardVariable "red target"        /red/target
    ├── Retry "pick and place red"                 (a lost grasp starts over)
    │   └── Sequence "transfer red"
    │       ├── Detect "detect red"               camera -> /red/pose (``locate``: how the part is found)
    │       ├── Pick "pick red"
    │       └── GraspGuard "while holding red"    fails within a tick when the part slips out
    │           └── Place "place red"
    ├── Inspect "inspect red after placing"        -> /red/offset_mm, /red/placed_offset_mm
    └── RepeatUntilWithin "correct red"            while /red/offset_mm >= threshold
        └── Sequence "push and inspect red"
            ├── Push "push red"                    along x, then y, then x ...
            └── Inspect "inspect red"

``render_targets(plan)`` chains these per part (``CorrectMode.EACH``) or places every part before
correcting them all (``AFTER_ALL``, the paper's Fig. 5); ``Arrangement`` is the root that carries
the plan (``Arrangement.plan``), so a run reports per part. The public builder ``arrangement()``
(``bt_arrange.trees.builder``) compiles a plan (``bt_arrange.plan.compiled.compile_plan``) and
renders it, puzzles included.

``locate`` says how a part is found before it is picked: ``by_camera()`` (the default, the top
camera's colour detection, ``Detect``) or ``by_depth(seed)`` (the depth-only grasp estimator of
Table 1's row 4, ``EstimateGraspFromDepth``); any ``Callable[[Target], Behaviour]`` that writes
``/<obj>/pose`` will do.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from typing import Any

import py_trees

from bt_arrange.behaviours import MoveHome, Place, Recheck, keys
from bt_arrange.checks import whole_number
from bt_arrange.deprecation import warn_once
from bt_arrange.geometry import PlanarPose
from bt_arrange.objects import ObjectStart
from bt_arrange.perception import DEFAULT_COLOUR_TABLE, ColourTable
from bt_arrange.plan.choices import CorrectMode
from bt_arrange.plan.compiled import (
    ArrangementPlan,
    NeighbourCheck,
    PartStep,
    check_grasp_among_neighbours,
    is_among_neighbours,
    over_the_plan,
)
from bt_arrange.plan.layout import Pads, Release, Step
from bt_arrange.plan.targets import DEFAULT_YAW_THRESHOLD_DEG, Target, check_threshold, parts_of
from bt_arrange.plan.tolerance import Tolerance
from bt_arrange.plan.validate import validate_targets
from bt_arrange.ports import COLOURS, DOUBLE, INT, OFF_DOUBLE, Port, starts_type, targets_type
from bt_arrange.settings import ManipulationSettings
from bt_arrange.trees import layers
from bt_arrange.trees.steps import (
    Locate,
    check_strategy,
    correction,
    inspect,
    regrasp_while_turned,
    set_target,
    transfer,
    turned_limit_deg,
)


def render_part(part: PartStep, plan: ArrangementPlan, locate: Locate | None = None) -> py_trees.behaviour.Behaviour:
    """Algorithm 1 for one part of a compiled plan: locate, pick, place, inspect, push until within its tolerance.

    Among neighbours it is released where its step says, pushed only from its free sides, and the
    parts near it (``part.neighbours``) are looked at again once it is down (``Recheck``) and
    corrected when they moved beyond the threshold.
    """
    target = part.target
    obj = target.obj
    tolerance = plan.tolerance
    children: list[py_trees.behaviour.Behaviour] = [
        set_target(target),
        transfer(part, plan, locate=locate),
        inspect(target, f"inspect {obj} after placing", after_placing=True, kind_targets=part.kind_targets),
        # Layers: a raised part must stand on its support; far off, it is placed again, not pushed.
        *layers.standing(target),
        *layers.regrasp_while_far(target, part.release, part.kind_targets),
        # An irregular part turned in the pads by more than pushes correct is picked up again (a box's
        # grasp squares it, so its tree is the paper's). Among neighbours there is no room for a free pick.
        *(
            []
            if part.among_neighbours or target.object_type.shape.rectangular
            else [
                regrasp_while_turned(
                    target, yaw_limit_deg=turned_limit_deg(tolerance.yaw_threshold_deg, part.rechecked)
                )
            ]
        ),
        correction(part, plan),
    ]
    if part.neighbours and plan.keep_going:
        # The neighbours are looked at again whatever became of this part: a part placed and then
        # failed (not found again, pushes that stalled) may have moved them, and a neighbour's last
        # look from before that would report it where it no longer lies. (A plan that stops at the
        # first failure, ``keep_going=False``, stops here as it always did.)
        own = py_trees.composites.Sequence(name=f"place and correct {obj}", memory=True, children=children)
        children = [
            py_trees.decorators.FailureIsSuccess(name=f"then look again at {obj}'s neighbours", child=own),
            # A neighbour it cannot measure (merged with this part's face) leaves the others to be looked at.
            *(
                py_trees.decorators.FailureIsSuccess(name=f"then the next look after {obj}", child=look)
                for look in (_look_again(neighbour, obj, plan) for neighbour in part.neighbours)
            ),
        ]
    subtree = py_trees.composites.Sequence(name=f"arrange {obj}", memory=True, children=children)
    #: The part this subtree arranges: the XML writer writes it as a SubTree of the part's ports.
    subtree.part = target  # type: ignore[attr-defined]
    return subtree


def _look_again(neighbour: NeighbourCheck, after: str, plan: ArrangementPlan) -> py_trees.behaviour.Behaviour:
    """Look at a neighbour again once ``after`` is down and correct it if it moved; nothing if it was never placed."""
    label = f" after {after}"
    obj = neighbour.target.obj
    look_again = py_trees.composites.Sequence(
        name=f"look again at {obj}{label}",
        memory=True,
        children=[
            Recheck(
                f"look at {obj}{label}",
                obj,
                neighbour.target.colour,
                after=after,
                object_type=neighbour.target.object_type,
                kind_targets=neighbour.kind_targets,
                z_m=neighbour.target.z_m,
            ),
            correction(neighbour, plan, count=False, label=label),
        ],
    )
    # A neighbour whose transfer failed (the tree going on past it) lies where it started: nothing
    # to look at again, and a push from there towards its target would be the wrong one.
    return py_trees.composites.Selector(
        name=f"look again at {obj}{label} if it was placed",
        memory=True,
        children=[
            py_trees.decorators.Inverter(
                name=f"{obj} was never placed{label}",
                child=py_trees.behaviours.CheckBlackboardVariableExists(
                    name=f"{obj} was placed{label}",
                    variable_name=keys.key(obj, keys.PLACED_OFFSET_MM),
                ),
            ),
            look_again,
        ],
    )


def render_targets(plan: ArrangementPlan, locate: Locate | None = None) -> list[py_trees.behaviour.Behaviour]:
    """The subtrees of a compiled plan's parts, in placing order (without the park at the end).

    ``CorrectMode.EACH``: one ``arrange <obj>`` per part; ``AFTER_ALL``: ``place all`` then ``correct all``.
    With ``plan.keep_going`` a part that cannot be finished does not stop the others.
    """

    def carry_on(subtree: py_trees.behaviour.Behaviour, obj: str) -> py_trees.behaviour.Behaviour:
        if not plan.keep_going:
            return subtree
        return py_trees.decorators.FailureIsSuccess(name=f"then the next ({obj})", child=subtree)

    if plan.correct is CorrectMode.EACH:
        return [carry_on(render_part(part, plan, locate), part.target.obj) for part in plan.steps]
    place_all = py_trees.composites.Sequence(
        name="place all",
        memory=True,
        children=[
            carry_on(
                py_trees.composites.Sequence(
                    name=f"place {part.target.obj} first",
                    memory=True,
                    children=[
                        set_target(part.target),
                        transfer(part, plan, locate=locate),
                        inspect(
                            part.target,
                            f"inspect {part.target.obj} after placing",
                            after_placing=True,
                            kind_targets=part.kind_targets,
                        ),
                    ],
                ),
                part.target.obj,
            )
            for part in plan.steps
        ],
    )
    correct_all = py_trees.composites.Sequence(
        name="correct all",
        memory=True,
        children=[
            carry_on(
                py_trees.composites.Sequence(
                    name=f"correct {part.target.obj} after all",
                    memory=True,
                    children=[
                        # A part whose transfer failed was never placed: nothing to correct.
                        py_trees.behaviours.CheckBlackboardVariableExists(
                            name=f"{part.target.obj} was placed",
                            variable_name=keys.key(part.target.obj, keys.PLACED_OFFSET_MM),
                        ),
                        inspect(
                            part.target, f"inspect {part.target.obj} before correcting", kind_targets=part.kind_targets
                        ),
                        correction(part, plan),
                    ],
                ),
                part.target.obj,
            )
            for part in plan.steps
        ],
    )
    return [place_all, correct_all]


def render(plan: ArrangementPlan, locate: Locate | None = None) -> Arrangement:
    """The tree of a compiled plan: its parts' subtrees, then the arm moved out of the camera's view."""
    children = render_targets(plan, locate)
    return Arrangement(
        name="arrangement",
        children=[*children, MoveHome("park the arm")],
        plan=plan,
        place_all=children[0] if plan.correct is CorrectMode.AFTER_ALL else None,
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
    settings: ManipulationSettings | None = None,
    rechecked: bool = False,
) -> py_trees.behaviour.Behaviour:
    """Deprecated: ``render_part(step, plan)`` of a compiled plan. Algorithm 1 for one object, from a layout ``step``.

    ``step`` (from ``plan_steps``) places it among neighbours: its release, the sides it may be
    pushed from and how to release it again. ``neighbours`` are the parts placed before it nearby,
    each with the directions it may be pushed and its restaging once this one is down.
    ``kind_targets`` (identical parts) are the targets of its kind; ``kind_of_neighbour`` gives a
    neighbour's. ``rechecked``: a later part's step looks at this one again, so its correction counts
    the camera's error twice.
    """
    warn_once("arrange_one(target, threshold_mm, max_pushes, ...)", "render_part(step, plan) of a compiled plan")
    settings = settings or ManipulationSettings()
    pads = Pads.from_settings(settings)
    dense = step is not None and is_among_neighbours(step)
    if step is not None:
        check_grasp_among_neighbours(target, step, dense)
    check_threshold(threshold_mm, settings)
    part = PartStep(
        target=target,
        layout=step,
        among_neighbours=dense,
        release=step.release if dense and step is not None else None,
        push_towards=step.push_towards if dense and step is not None else None,
        restage=step.restage if dense and step is not None else None,
        push_opening_m=pads.neighbour_push_opening_m(step.part, "x") if dense and step is not None else None,
        kind_targets=tuple(kind_targets),
        rechecked=rechecked,
        nearest_grasp=dense or rechecked,
        neighbours=tuple(
            NeighbourCheck(
                neighbour,
                sides,
                again,
                tuple((kind_of_neighbour or {}).get(neighbour.obj, ())),
                pads.neighbour_push_opening_m(parts_of([neighbour], settings)[0], "x"),
            )
            for neighbour, sides, again in neighbours
        ),
    )
    plan = ArrangementPlan(
        targets=(target,),
        tolerance=Tolerance(threshold_mm, yaw_threshold_deg),
        settings=settings,
        strategy=check_strategy(strategy),
        max_pushes=max_pushes,
        max_regrasps=max_regrasps,
    )
    return render_part(part, plan, locate)


#: The port type of a plan: ``colour,x_m,y_m,yaw_rad[,name[,object type[,z_m]]]`` per target, read into ``Target``s.
TARGETS = targets_type(Target)
#: The port type of a plan's starts, written as targets are, read into ``ObjectStart``s (empty: None).
STARTS = starts_type(ObjectStart)


class Arrangement(py_trees.composites.Sequence):
    """The root of an arrangement tree: it carries its plan (``plan``), so a run reports per part.

    Built by ``render`` from a compiled plan, or by hand from ``targets`` and ``threshold_mm`` (a
    plan of targets alone, ``ArrangementPlan.of``). ``place_all`` is the subtree that places every
    part before any is corrected (the paper's Fig. 5), None otherwise: a recorder saves its "after
    placing" picture then. ``scene_seed`` and ``starts`` are a plan file's scene, for the simulator.
    """

    #: The node's description in the XML ``TreeNodesModel``.
    node_description = "a sequence with memory that knows its plan (the report and the scene come from it)"

    @classmethod
    def provided_ports(cls) -> tuple[Port, ...]:
        """The plan, its thresholds, its colours and its scene (BehaviorTree.CPP's ``providedPorts``)."""
        return (
            Port(
                "targets",
                TARGETS,
                description="colour,x_m,y_m,yaw_rad[,name[,object type[,z_m]]] per object, separated by ;",
            ),
            Port("threshold_mm", DOUBLE, description="the accuracy threshold the report checks [mm]"),
            Port("yaw_threshold_deg", OFF_DOUBLE, None, "the yaw threshold the report checks [deg] (0: position only)"),
            Port("colours", COLOURS, DEFAULT_COLOUR_TABLE, "the plan's own colours: name:rgb:r,g,b;... (empty: none)"),
            # A plan's [scene]: the simulator's business, carried so that the exported tree runs as its plan.
            Port("scene_seed", INT, 0, "the seed the parts are scattered from when no --seed is given", optional=True),
            Port("starts", STARTS, None, "where the parts start, written as targets (empty: scattered)", optional=True),
        )

    @classmethod
    def from_ports(
        cls, name: str, values: Mapping[str, Any], children: Sequence[py_trees.behaviour.Behaviour]
    ) -> Arrangement:
        """The node of an XML tree: its plan is checked (``validate_targets``) against its colours first."""
        colours: ColourTable = values["colours"]
        puzzles = _puzzles_in(children)
        # A tree of puzzles alone has no targets until its solves (its pieces join them then).
        targets = values["targets"]
        plan = validate_targets(targets, colours=colours.names) if targets or not puzzles else []
        settings = ManipulationSettings().for_threshold(float(values["threshold_mm"]))
        among_neighbours = any(
            isinstance(node, Place) and node.release is not None for child in children for node in child.iterate()
        )
        return cls(
            name,
            children,
            plan,
            values["threshold_mm"],
            # The settings the plan's own tree was built with, so the exported tree moves as it did.
            settings=over_the_plan(plan, settings, among_neighbours),
            yaw_threshold_deg=values["yaw_threshold_deg"],
            colours=colours,
            scene_seed=whole_number("scene_seed", values["scene_seed"]),
            starts=values["starts"],
            puzzles=puzzles,
        )

    def __init__(
        self,
        name: str,
        children: Sequence[py_trees.behaviour.Behaviour],
        targets: Sequence[Target] = (),
        threshold_mm: float | None = None,
        *,
        plan: ArrangementPlan | None = None,
        place_all: py_trees.behaviour.Behaviour | None = None,
        yaw_threshold_deg: float | None = None,
        colours: ColourTable | None = None,
        settings: ManipulationSettings | None = None,
        scene_seed: int = 0,
        starts: list[ObjectStart] | None = None,
        puzzles: Sequence[Any] | None = None,
    ) -> None:
        super().__init__(name=name, memory=True, children=list(children))
        if plan is None:
            if threshold_mm is None:
                raise TypeError("Arrangement needs a plan= or targets and a threshold_mm")
            plan = ArrangementPlan.of(
                targets,
                Tolerance(threshold_mm, yaw_threshold_deg),
                settings=settings,
                colours=colours,
                puzzles=_puzzles_in(children) if puzzles is None else puzzles,
            )
        #: The plan the tree carries out: targets, tolerance, settings, colours, puzzles.
        self.plan = plan
        self.place_all = place_all
        #: A plan's scene, for the simulator: the seed its parts are scattered from, or where they start (None: so).
        self.scene_seed = scene_seed
        self.starts = starts

    @property
    def targets(self) -> list[Target]:
        """The plan's targets (a puzzle's pieces among them once solved)."""
        return list(self.plan.targets)

    @property
    def threshold_mm(self) -> float:
        """The plan's threshold [mm]."""
        return self.plan.tolerance.threshold_mm

    @property
    def yaw_threshold_deg(self) -> float | None:
        """The yaw error (degrees) the correction loop leaves; None: position only."""
        return self.plan.tolerance.yaw_threshold_deg

    @property
    def colours(self) -> ColourTable:
        """The colour table the plan's colours come from: the cell paints with it, the camera reads it."""
        return self.plan.colours

    @property
    def settings(self) -> ManipulationSettings:
        """The handling settings the plan was checked and built with: the run's context uses them too."""
        return self.plan.settings

    @property
    def puzzles(self) -> list[Any]:
        """The plan's puzzles (``PuzzleSpec``): their pieces join ``targets`` once solved."""
        return list(self.plan.puzzles)

    @property
    def source(self) -> Any:
        """Where the plan was written (a plan file's ``PlanSource``), so the run's checks name its entries; or None."""
        return self.plan.source

    @source.setter
    def source(self, value: Any) -> None:
        self.plan = dataclasses.replace(self.plan, source=value)


def plan_of(root: py_trees.behaviour.Behaviour) -> ArrangementPlan | None:
    """The plan a tree carries out: its root's when it carries one (an ``Arrangement``), else None."""
    plan = getattr(root, "plan", None)
    return plan if isinstance(plan, ArrangementPlan) else None


def _puzzles_in(children: Sequence[py_trees.behaviour.Behaviour]) -> list[Any]:
    """The puzzles (``PuzzleSpec``s) of the ``SurveyPieces`` among ``children``'s nodes."""
    from bt_arrange.behaviours.puzzle import SurveyPieces

    return [node.spec for child in children for node in child.iterate() if isinstance(node, SurveyPieces)]


__all__ = [
    "STARTS",
    "TARGETS",
    "Arrangement",
    "arrange_one",
    "plan_of",
    "render",
    "render_part",
    "render_targets",
]
