"""Builders of arrangement trees: the paper's Algorithm 1 as py_trees subtrees.

One object (``arrange_one``)::

    Sequence "arrange red"
    ├── SetBlackboardVariable "red target"        /red/target
    ├── Retry "pick and place red"                 (a lost grasp starts over)
    │   └── Sequence "transfer red"
    │       ├── Detect "detect red"               camera -> /red/pose (``locate``: how the object is found)
    │       ├── Pick "pick red"
    │       └── GraspGuard "while holding red"    fails within a tick when the part slips out
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

from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import py_trees

from bt_arrange.behaviours import (
    MoveHome,
    Place,
    Recheck,
    keys,
)
from bt_arrange.checks import positive_number, whole_number
from bt_arrange.errors import PlanError
from bt_arrange.geometry import PlanarPose
from bt_arrange.layout import Pads, Release, Step, free_push_directions, restage_releases
from bt_arrange.objects import ObjectStart
from bt_arrange.perception import DEFAULT_COLOUR_TABLE, ColourTable
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
from bt_arrange.trees.targets import (
    CORRECT_MODES,
    DEFAULT_YAW_THRESHOLD_DEG,
    Target,
    check_threshold,
    kinds,
    parts_of,
    plan_steps,
    validate_targets,
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
    """Algorithm 1 for one object: locate (detect), pick, place, inspect, push until within the thresholds.

    ``step`` (from ``plan_steps``) places it among neighbours: its release, the sides it may be
    pushed from and how to release it again. ``neighbours`` are the parts placed before it nearby,
    each with the directions it may be pushed and its restaging once this one is down: each is
    looked at again afterwards (``Recheck``) and corrected when it moved beyond the threshold.
    ``kind_targets`` (identical parts) are the targets of its kind; ``kind_of_neighbour`` gives
    a neighbour's. ``settings`` are the run's (the pads' figures among neighbours). ``rechecked``:
    a later part's step looks at this one again (it is that part's neighbour): its own correction
    counts the camera's error twice (``RepeatUntilWithin.margins``), so that the second reading,
    beside the new neighbour, still finds it within.
    """
    settings = settings or ManipulationSettings()
    pads = Pads.from_settings(settings)
    obj = target.obj
    dense = step is not None and _is_dense(step)
    if dense and step is not None and not target.object_type.shape.rectangular and not step.part.by_outline:
        raise PlanError(
            f"target {target.obj}: a {target.object_type.shape.describe()} among neighbours (released off its "
            "target, or with a side blocked) needs a grasp across its own x or y axis, where the layout puts the "
            "pads: write its outline turned so that two facing edges run along x or y"
        )
    release = step.release if dense and step is not None else None
    towards = step.push_towards if dense and step is not None else None
    restage = step.restage if dense and step is not None else None
    children: list[py_trees.behaviour.Behaviour] = [
        set_target(target),
        transfer(
            target, max_regrasps, locate=locate, kind_targets=kind_targets, release=release, nearest=dense or rechecked
        ),
        inspect(target, f"inspect {obj} after placing", after_placing=True, kind_targets=kind_targets),
        # Layers (issue 33): a raised part must stand on its support; far off, it is placed again, not pushed.
        *layers.standing(target),
        *layers.regrasp_while_far(target, release, kind_targets),
        # An irregular part turned in the pads by more than pushes correct is picked up again (a box's
        # grasp squares it, so its tree is the paper's). Among neighbours there is no room for a free pick.
        *(
            []
            if dense or target.object_type.shape.rectangular
            else [regrasp_while_turned(target, yaw_limit_deg=turned_limit_deg(yaw_threshold_deg, rechecked))]
        ),
        correction(
            target,
            threshold_mm,
            max_pushes,
            strategy,
            yaw_threshold_deg=yaw_threshold_deg,
            kind_targets=kind_targets,
            towards=towards,
            restage=restage,
            push_opening_m=_opening(step, dense, pads),
            settings=settings,
            margins=2 if rechecked else 1,
        ),
    ]
    for neighbour, sides, again in neighbours:
        label = f" after {obj}"
        neighbour_kind = (kind_of_neighbour or {}).get(neighbour.obj, ())
        look_again = py_trees.composites.Sequence(
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
                    z_m=neighbour.z_m,
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
                    push_opening_m=pads.neighbour_push_opening_m(parts_of([neighbour], settings)[0], "x"),
                    count=False,
                    label=label,
                    settings=settings,
                ),
            ],
        )
        # A neighbour whose transfer failed (the tree going on past it) lies where it started: nothing
        # to look at again, and a push from there towards its target would be the wrong one.
        children.append(
            py_trees.composites.Selector(
                name=f"look again at {neighbour.obj}{label} if it was placed",
                memory=True,
                children=[
                    py_trees.decorators.Inverter(
                        name=f"{neighbour.obj} was never placed{label}",
                        child=py_trees.behaviours.CheckBlackboardVariableExists(
                            name=f"{neighbour.obj} was placed{label}",
                            variable_name=keys.key(neighbour.obj, keys.PLACED_OFFSET_MM),
                        ),
                    ),
                    look_again,
                ],
            )
        )
    return py_trees.composites.Sequence(name=f"arrange {obj}", memory=True, children=children)


def _sides_in_layer(
    part: Target, steps: Sequence[Step], by_obj: Mapping[str, Target], pads: Pads
) -> tuple[tuple[str, ...], dict[str, Release]]:
    """A lower part's free push directions and restaging among the parts of its own layer placed so far."""
    own = next(st for st in steps if st.part.name == part.obj)
    placed = [(st.part.name, st.part.footprint) for st in steps if layers.same_layer(by_obj[st.part.name], part)]
    return free_push_directions(own.part, placed, pads), restage_releases(own.part, placed, pads)


def _opening(step: Step | None, dense: bool, pads: Pads) -> float | None:
    """The push opening among neighbours (along x; Push keeps it within the pushed face's own width), None when free."""
    return pads.neighbour_push_opening_m(step.part, "x") if dense and step is not None else None


def _dense_release(step: Step) -> Release | None:
    return step.release if _is_dense(step) else None


def _is_dense(step: Step) -> bool:
    """A step among neighbours: released away from its target, near placed parts, or with a blocked side."""
    return step.release.staged or bool(step.neighbours) or set(step.push_towards) != set(step.part.push_directions)


#: The port type of a plan: ``colour,x_m,y_m,yaw_rad[,name[,object type[,z_m]]]`` per target, read into ``Target``s.
TARGETS = targets_type(Target)
#: The port type of a plan's starts, written as targets are, read into ``ObjectStart``s (empty: None).
STARTS = starts_type(ObjectStart)


class Arrangement(py_trees.composites.Sequence):
    """The root of an arrangement tree; remembers its plan so a runner can report per object.

    ``place_all`` is the subtree that places every object before any is corrected (the paper's
    Fig. 5, ``correct="after_all"``), None otherwise: a recorder saves its "after placing" picture then.
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
        from bt_arrange.behaviours.puzzle import SurveyPieces

        # A tree of puzzles alone has no targets until its solves (its pieces join them then).
        puzzles = any(isinstance(n, SurveyPieces) for child in children for n in child.iterate())
        targets = values["targets"]
        plan = validate_targets(targets, colours=colours.names) if targets or not puzzles else []
        return cls(
            name,
            children,
            plan,
            values["threshold_mm"],
            # The settings the plan's own tree was built with, so the exported tree moves as it did.
            settings=over_the_plan(plan, ManipulationSettings().for_threshold(float(values["threshold_mm"])), children),
            yaw_threshold_deg=values["yaw_threshold_deg"],
            colours=colours,
            scene_seed=whole_number("scene_seed", values["scene_seed"]),
            starts=values["starts"],
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
        settings: ManipulationSettings | None = None,
        scene_seed: int = 0,
        starts: list[ObjectStart] | None = None,
    ) -> None:
        super().__init__(name=name, memory=True, children=list(children))
        self.targets = targets
        self.threshold_mm = threshold_mm
        self.place_all = place_all
        #: The yaw error (degrees) the correction loop leaves; None: position only.
        self.yaw_threshold_deg = yaw_threshold_deg
        #: The colour table the plan's colours come from: the cell paints with it, the camera reads it.
        self.colours = colours if colours is not None else DEFAULT_COLOUR_TABLE
        #: The handling settings the plan was checked and built with: the run's context uses them too.
        self.settings = settings if settings is not None else ManipulationSettings()
        #: Where the plan was written (a plan file's ``PlanSource``), so the run's checks name its entries; or None.
        self.source: Any = None
        #: A plan's scene, for the simulator: the seed its parts are scattered from, or where they start (None: so).
        self.scene_seed = scene_seed
        self.starts = starts

    @property
    def puzzles(self) -> list[Any]:
        """The tree's puzzles (``PuzzleSpec``, one per ``SurveyPieces``): their pieces join ``targets`` once solved."""
        from bt_arrange.behaviours.puzzle import SurveyPieces

        return [node.spec for node in self.iterate() if isinstance(node, SurveyPieces)]


def over_the_plan(
    plan: Sequence[Target], settings: ManipulationSettings, children: Sequence[py_trees.behaviour.Behaviour]
) -> ManipulationSettings:
    """The settings with the moves above the table at the plan's heights, for the tree of ``children``.

    Over a finished tower in layers (``layers.stack_settings``); down to ``approach_clearance_m``
    over the tallest part of a plan of flat parts each placed free (issue 36,
    ``ManipulationSettings.for_tallest_part``). Among neighbours (a release the layout stages)
    they keep ``approach_height_m``: in the tight-gap fresco benchmark (0.5 mm gaps, 0.25 mm,
    seeds 0 to 14) the lower approach ended 81 of 90 pieces within by truth, 85 before (docs/motion.md).
    """
    if not plan:
        return settings
    settings = layers.stack_settings(plan, settings)
    among_neighbours = any(
        isinstance(node, Place) and node.release is not None for child in children for node in child.iterate()
    )
    if among_neighbours:
        return settings
    return settings.for_tallest_part(max(layers.top_m(t) for t in plan))


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
    settings: ManipulationSettings | None = None,
    puzzles: Sequence[Any] = (),
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
    ``settings`` (default ``ManipulationSettings()``) are the handling settings the plan is checked
    and built with; the tree keeps them (``Arrangement.settings``) and a run hands them to the context.
    ``puzzles`` (``bt_arrange.puzzle.PuzzleSpec``s) are slabs reassembled after the targets, each from
    the camera alone (``bt_arrange.trees.puzzle``); with puzzles, ``targets`` may be empty.
    """
    if puzzles:
        return _with_puzzles(
            list(targets),
            list(puzzles),
            dict(
                threshold_mm=threshold_mm,
                max_pushes=max_pushes,
                max_regrasps=max_regrasps,
                keep_going=keep_going,
                strategy=strategy,
                yaw_threshold_deg=yaw_threshold_deg,
                colours=colours,
                settings=settings,
            ),
            correct=correct,
            locate=locate,
            order=order,
        )
    settings = settings or ManipulationSettings()
    check_strategy(strategy)
    if correct not in CORRECT_MODES:
        raise PlanError(f"correct={correct!r}: choose one of {', '.join(CORRECT_MODES)}")
    check_threshold(threshold_mm, settings)
    # A threshold finer than 0.28 mm needs pushes shorter than 0.2 mm along an axis.
    settings = settings.for_threshold(float(threshold_mm))
    whole_number("max_pushes", max_pushes)
    if yaw_threshold_deg is not None:
        positive_number("yaw_threshold_deg", yaw_threshold_deg, "deg")
    if colours is not None and not isinstance(colours, ColourTable):
        raise PlanError(f"colours must be a ColourTable (bt_arrange.perception), got {type(colours).__name__}")
    table = colours if isinstance(colours, ColourTable) else DEFAULT_COLOUR_TABLE
    plan = validate_targets(targets, colours=table.names, settings=settings)
    # Layers (issue 33): corrected part by part, every move above the table over the finished tower.
    layers.check_correct_mode(plan, correct)
    settings = layers.stack_settings(plan, settings)
    siblings = kinds(plan)
    steps = plan_steps(plan, settings, order=order)
    steps_by_obj = {st.part.name: st for st in steps}
    by_obj = {t.obj: t for t in plan}
    ordered = [by_obj[st.part.name] for st in steps]
    pads = Pads.from_settings(settings)

    def carry_on(subtree: py_trees.behaviour.Behaviour, obj: str) -> py_trees.behaviour.Behaviour:
        if not keep_going:
            return subtree
        return py_trees.decorators.FailureIsSuccess(name=f"then the next ({obj})", child=subtree)

    if correct == "each":
        children = []
        # The parts a later step looks at again: its neighbours, and in layers the parts below it.
        rechecked = {name for st in steps for name in st.neighbours} | {
            part.obj
            for index, st in enumerate(steps)
            for part in layers.watched_below(by_obj[st.part.name], ordered[:index], settings)
        }
        for index, step in enumerate(steps):
            target = by_obj[step.part.name]
            # Layers (issue 33): the pads meet only the parts of a part's own layer on the table.
            placed = [
                (st.part.name, st.part.footprint)
                for st in steps[: index + 1]
                if layers.same_layer(by_obj[st.part.name], target)
            ]
            below = layers.watched_below(target, [by_obj[st.part.name] for st in steps[:index]], settings)
            neighbours = [
                (
                    by_obj[name],
                    free_push_directions(steps_by_obj[name].part, placed, pads),
                    restage_releases(steps_by_obj[name].part, placed, pads),
                )
                for name in step.neighbours
            ] + [(part, *_sides_in_layer(part, steps[:index], by_obj, pads)) for part in below]
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
                settings=settings,
                rechecked=target.obj in rechecked,
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
                                settings=settings,
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
        settings=over_the_plan(plan, settings, children),
    )


def _with_puzzles(targets: list[Target], puzzles: list[Any], options: dict[str, Any], **plan_only: Any) -> Arrangement:
    """The targets' arrangement (if any), then each puzzle's subtree; the root knows the puzzles."""
    from bt_arrange.trees.puzzle import OPTIONS as PUZZLE_OPTIONS
    from bt_arrange.trees.puzzle import arrange_puzzle

    if plan_only["correct"] != "each":
        raise PlanError(f"correct={plan_only['correct']!r}: a plan with a [puzzle] is corrected part by part (each)")
    # Without targets, a stand-in's arrangement checks the options; its steps are dropped.
    root = arrangement(targets or [Target("red", 0.5, 0.0)], **options, **plan_only)
    steps = list(root.children[:-1])
    for child in steps:
        root.remove_child(child)
    if not targets:
        steps, root.targets = [], []
    keep_going = options["keep_going"]
    for spec in puzzles:
        subtree = arrange_puzzle(spec, {k: v for k, v in options.items() if k in PUZZLE_OPTIONS})
        steps.append(
            py_trees.decorators.FailureIsSuccess(name=f"then the next ({spec.name})", child=subtree)
            if keep_going
            else subtree
        )
    park = root.children[-1]
    root.remove_child(park)
    for child in [*steps, park]:
        root.add_child(child)
    return root
