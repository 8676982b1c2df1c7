"""A plan compiled: targets, a tolerance and settings turned into one frozen step per part.

``compile_plan`` checks a plan before anything moves and decides everything a tree needs to carry
it out: the placing order, and for each part its release, the sides it may be pushed from, how it
is released again for a blocked side, the pads' opening among neighbours, the parts looked at again
once it is down, the targets of its kind (identical parts) and the settings of the run. The tree
builders (``bt_arrange.trees``) render a tree from an ``ArrangementPlan``; the session reads its
targets and tolerance from it. Nothing here builds a behaviour::

    plan = compile_plan(targets, Tolerance(1.0, yaw_threshold_deg=1.0))
    for step in plan.steps:
        print(step.target.obj, step.release, step.push_towards)
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from bt_arrange.checks import whole_number
from bt_arrange.errors import PlanError
from bt_arrange.geometry import PlanarPose
from bt_arrange.perception import DEFAULT_COLOUR_TABLE, ColourTable
from bt_arrange.plan import stacking
from bt_arrange.plan.choices import CorrectMode, PushStrategy
from bt_arrange.plan.footprints import Footprint
from bt_arrange.plan.layout import Pads, Part, Release, Step, free_push_directions, push_blockers, restage_releases
from bt_arrange.plan.move_aside import MoveAside, move_aside
from bt_arrange.plan.targets import DEFAULT_YAW_THRESHOLD_DEG, Target, check_threshold, kinds, parts_of
from bt_arrange.plan.tolerance import Tolerance
from bt_arrange.plan.validate import plan_steps, validate_targets
from bt_arrange.settings import ManipulationSettings


@dataclass(frozen=True)
class NeighbourCheck:
    """A part placed before another, near it: looked at again once that one is down, and corrected if it moved.

    ``push_towards`` and ``restage`` are its free push directions and restaging among the parts placed
    by then; ``push_opening_m`` the pads' opening for a push among them.
    """

    target: Target
    push_towards: tuple[str, ...]
    restage: Mapping[str, Release]
    kind_targets: tuple[PlanarPose, ...]
    push_opening_m: float
    #: Per push a neighbour blocks, that neighbour (the reason a blocked correction ends names it).
    blocked_by: Mapping[str, str] = field(default_factory=dict)
    #: Neighbours moved aside for a blocked push, and put back (``Aside``).
    move_aside: tuple[Aside, ...] = ()


@dataclass(frozen=True)
class Aside:
    """A neighbour moved aside so that a blocked push of a part is free, then put back and corrected.

    ``move`` is the layout's plan (``bt_arrange.plan.move_aside.MoveAside``: the part's blocked push,
    the neighbour's push aside, how far, its push back); ``neighbour`` the neighbour's correction
    once back, among the parts placed by then (it moves nothing aside itself: one level).
    """

    move: MoveAside
    neighbour: NeighbourCheck


@dataclass(frozen=True)
class PartStep:
    """Everything one part's subtree needs: how it is released, pushed and looked at again.

    ``layout`` is the layout's step (``bt_arrange.plan.layout.Step``; None for a part placed free
    outside a compiled plan, ``PartStep.free``). ``release`` is where the
    pads let go among neighbours (None: anywhere at the target); ``push_towards`` the directions it
    may be pushed (None: any); ``restage`` per blocked direction a release on the other side;
    ``push_opening_m`` the pads' opening for a push among neighbours (None: free). ``rechecked``: a
    later part's step looks at it again, so its correction counts the camera's error twice
    (``margins``). ``neighbours``: the parts looked at again once it is down. ``nearest_grasp``: the
    wrist takes its nearest grasp and turn (a part neighbours are placed beside).
    """

    target: Target
    layout: Step | None
    among_neighbours: bool
    release: Release | None
    push_towards: tuple[str, ...] | None
    restage: Mapping[str, Release] | None
    push_opening_m: float | None
    kind_targets: tuple[PlanarPose, ...] = ()
    rechecked: bool = False
    neighbours: tuple[NeighbourCheck, ...] = ()
    nearest_grasp: bool = False
    #: Per push a neighbour blocks (not in ``push_towards``), that neighbour.
    blocked_by: Mapping[str, str] = field(default_factory=dict)
    #: Neighbours moved aside for a blocked push of this part, and put back (``Aside``).
    move_aside: tuple[Aside, ...] = ()

    @classmethod
    def free(cls, target: Target, kind_targets: Iterable[PlanarPose] = ()) -> PartStep:
        """The step of a part placed free, at its target, pushed from any side: a hand-composed tree's."""
        return cls(target, None, False, None, None, None, None, tuple(kind_targets))

    @property
    def margins(self) -> int:
        """How many times the camera's error is added to this part's offset: twice when it is looked at again."""
        return 2 if self.rechecked else 1


@dataclass(frozen=True)
class ArrangementPlan:
    """A checked plan, ready to render: its targets, tolerance, choices and one ``PartStep`` per part in placing order.

    ``settings`` are the run's (the moves above the table at the plan's heights: the context uses
    them); ``targets`` are in the plan's order, ``steps`` in the placing order. A plan of a hand-built
    tree has targets and a tolerance and no steps (``ArrangementPlan.of``). ``puzzles`` are slabs
    solved from the camera, whose pieces join ``targets`` once solved (``joined``). ``source`` is
    where a plan file wrote its entries (``bt_arrange.plan.check.PlanSource``), or None.
    """

    targets: tuple[Target, ...]
    tolerance: Tolerance
    settings: ManipulationSettings = field(default_factory=ManipulationSettings)
    steps: tuple[PartStep, ...] = ()
    correct: CorrectMode = CorrectMode.EACH
    strategy: PushStrategy = PushStrategy.PAPER
    max_pushes: int = 10
    max_regrasps: int = 3
    keep_going: bool = True
    colours: ColourTable = field(default_factory=lambda: DEFAULT_COLOUR_TABLE)
    puzzles: tuple[Any, ...] = ()
    source: Any = None

    @classmethod
    def of(
        cls,
        targets: Iterable[Target],
        tolerance: Tolerance,
        *,
        settings: ManipulationSettings | None = None,
        colours: ColourTable | None = None,
        puzzles: Iterable[Any] = (),
    ) -> ArrangementPlan:
        """The plan of a tree composed by hand: its targets and tolerance, no steps compiled."""
        return cls(
            tuple(targets),
            tolerance,
            settings if settings is not None else ManipulationSettings(),
            colours=colours if colours is not None else DEFAULT_COLOUR_TABLE,
            puzzles=tuple(puzzles),
        )

    @property
    def threshold_mm(self) -> float:
        """The tolerance's threshold [mm]."""
        return self.tolerance.threshold_mm

    @property
    def yaw_threshold_deg(self) -> float | None:
        """The tolerance's yaw threshold [deg], or None: position only."""
        return self.tolerance.yaw_threshold_deg

    def target(self, obj: str) -> Target | None:
        """The target of object ``obj``, or None."""
        return next((t for t in self.targets if t.obj == obj), None)

    def joined(self, targets: Iterable[Target]) -> ArrangementPlan:
        """The plan with ``targets`` (a puzzle's solved pieces) added, those it already names left out."""
        known = {t.obj for t in self.targets}
        new = tuple(t for t in targets if t.obj not in known)
        return dataclasses.replace(self, targets=self.targets + new) if new else self


def over_the_plan(
    targets: Sequence[Target], settings: ManipulationSettings, among_neighbours: bool
) -> ManipulationSettings:
    """The run's settings: the moves above the table at the plan's heights.

    Over a finished tower in layers (``stacking.stack_settings``); down to ``approach_clearance_m``
    over the tallest part of a plan of flat parts each placed free
    (``ManipulationSettings.for_tallest_part``). Among neighbours (a release the layout stages, or
    any part ``among_neighbours``) they keep ``approach_height_m``: in the tight-gap fresco benchmark
    (0.5 mm gaps, 0.25 mm, seeds 0 to 14) the lower approach ended 81 of 90 pieces within by truth,
    85 before (docs/motion.md).
    """
    if not targets:
        return settings
    settings = stacking.stack_settings(targets, settings)
    if among_neighbours:
        return settings
    return settings.for_tallest_part(max(stacking.top_m(t) for t in targets))


def is_among_neighbours(step: Step) -> bool:
    """A step among neighbours: released away from its target, near placed parts, or with a blocked side."""
    return step.release.staged or bool(step.neighbours) or set(step.push_towards) != set(step.part.push_directions)


def compile_plan(
    targets: Iterable[Target],
    tolerance: Tolerance | None = None,
    *,
    settings: ManipulationSettings | None = None,
    correct: CorrectMode | str = CorrectMode.EACH,
    strategy: PushStrategy | str = PushStrategy.PAPER,
    order: Sequence[str] | None = None,
    max_pushes: int = 10,
    max_regrasps: int = 3,
    keep_going: bool = True,
    colours: ColourTable | Mapping[str, object] | None = None,
) -> ArrangementPlan:
    """Check ``targets`` before anything moves and decide every part's step; a ``PlanError`` names the first problem.

    ``tolerance`` defaults to 1 mm and 1 deg. ``order`` (object names) is the placing order; by
    default the layout chooses one (the plan's own order where it can be built). ``correct`` and
    ``strategy`` are parsed from their names. ``settings`` (default ``ManipulationSettings()``) are
    lowered to the threshold (``for_threshold``) and raised over a tower; the plan keeps the run's.
    """
    tolerance = tolerance if tolerance is not None else Tolerance(1.0, DEFAULT_YAW_THRESHOLD_DEG)
    settings = settings or ManipulationSettings()
    strategy = PushStrategy.parse(strategy, "strategy")
    correct = CorrectMode.parse(correct, "correct")
    check_threshold(tolerance.threshold_mm, settings)
    # A threshold finer than 0.28 mm needs pushes shorter than 0.2 mm along an axis.
    settings = settings.for_threshold(tolerance.threshold_mm)
    whole_number("max_pushes", max_pushes)
    whole_number("max_regrasps", max_regrasps)
    if colours is not None and not isinstance(colours, ColourTable):
        raise PlanError(f"colours must be a ColourTable (bt_arrange.perception), got {type(colours).__name__}")
    table = colours if isinstance(colours, ColourTable) else DEFAULT_COLOUR_TABLE
    plan = validate_targets(targets, colours=table.names, settings=settings)
    # Layers: corrected part by part, every move above the table over the finished tower.
    stacking.check_correct_mode(plan, correct)
    settings = stacking.stack_settings(plan, settings)
    layout = plan_steps(plan, settings, order=order)
    steps = (
        _steps_each(plan, layout, settings)
        if correct is CorrectMode.EACH
        else _steps_after_all(plan, layout, Pads.from_settings(settings))
    )
    return ArrangementPlan(
        targets=tuple(plan),
        tolerance=tolerance,
        settings=over_the_plan(plan, settings, any(_releases_among_neighbours(step) for step in steps)),
        steps=steps,
        correct=correct,
        strategy=strategy,
        max_pushes=max_pushes,
        max_regrasps=max_regrasps,
        keep_going=keep_going,
        colours=table,
    )


def _steps_each(plan: list[Target], layout: list[Step], settings: ManipulationSettings) -> tuple[PartStep, ...]:
    """Each part corrected right after it is placed: its neighbours, and in layers the parts below, looked at again."""
    pads = Pads.from_settings(settings)
    siblings = kinds(plan)
    layout_by_obj = {st.part.name: st for st in layout}
    by_obj = {t.obj: t for t in plan}
    ordered = [by_obj[st.part.name] for st in layout]
    # The parts a later step looks at again: its neighbours, and in layers the parts below it.
    rechecked = {name for st in layout for name in st.neighbours} | {
        part.obj
        for index, st in enumerate(layout)
        for part in stacking.watched_below(by_obj[st.part.name], ordered[:index], settings)
    }
    steps = []
    for index, step in enumerate(layout):
        target = by_obj[step.part.name]
        # Layers: the pads meet only the parts of a part's own layer on the table.
        placed = [
            (st.part.name, st.part.footprint)
            for st in layout[: index + 1]
            if stacking.same_layer(by_obj[st.part.name], target)
        ]
        below = stacking.watched_below(target, [by_obj[st.part.name] for st in layout[:index]], settings)
        placed_parts = [layout_by_obj[name].part for name, _ in placed]

        def check(
            name: str,
            aside: bool = True,
            placed: list[tuple[str, Footprint]] = placed,
            placed_parts: list[Part] = placed_parts,
        ) -> NeighbourCheck:
            """The correction of ``name`` among the parts placed: free pushes, restaging, neighbours moved aside."""
            part = layout_by_obj[name].part
            return NeighbourCheck(
                by_obj[name],
                free_push_directions(part, placed, pads),
                restage_releases(part, placed, pads),
                siblings.get(name, ()),
                pads.neighbour_push_opening_m(parts_of([by_obj[name]], settings)[0], "x"),
                push_blockers(part, placed, pads),
                tuple(
                    Aside(m, check(m.neighbour, False, placed, placed_parts))
                    for m in _moves(part, placed_parts, pads, aside)
                ),
            )

        neighbours = [check(name) for name in step.neighbours]
        for part in below:
            own = layout_by_obj[part.obj]
            in_layer = [
                (st.part.name, st.part.footprint)
                for st in layout[:index]
                if stacking.same_layer(by_obj[st.part.name], part)
            ]
            neighbours.append(
                NeighbourCheck(
                    part,
                    free_push_directions(own.part, in_layer, pads),
                    restage_releases(own.part, in_layer, pads),
                    siblings.get(part.obj, ()),
                    pads.neighbour_push_opening_m(parts_of([part], settings)[0], "x"),
                    push_blockers(own.part, in_layer, pads),
                )
            )
        dense = is_among_neighbours(step)
        check_grasp_among_neighbours(target, step, dense)
        steps.append(
            PartStep(
                target=target,
                layout=step,
                among_neighbours=dense,
                release=step.release if dense else None,
                push_towards=step.push_towards if dense else None,
                restage=step.restage if dense else None,
                push_opening_m=pads.neighbour_push_opening_m(step.part, "x") if dense else None,
                kind_targets=siblings.get(target.obj, ()),
                rechecked=target.obj in rechecked,
                neighbours=tuple(neighbours),
                nearest_grasp=dense or target.obj in rechecked,
                blocked_by=push_blockers(step.part, placed, pads) if dense else {},
                move_aside=check(target.obj).move_aside if dense else (),
            )
        )
    return tuple(steps)


def _moves(part: Part, placed: Sequence[Part], pads: Pads, aside: bool) -> tuple[MoveAside, ...]:
    """The neighbours moved aside for ``part``'s blocked pushes (``move_aside``), when ``aside``.

    Only for a part pushed squarely onto its edges (a box is released again on the other side
    instead, ``restage_releases``), and one level deep: the neighbour's own correction once it is
    back moves nothing aside.
    """
    return move_aside(part, placed, pads) if aside and part.by_outline else ()


def _steps_after_all(plan: list[Target], layout: list[Step], pads: Pads) -> tuple[PartStep, ...]:
    """Every part placed before any is corrected: each pushed from the sides the whole arrangement leaves free."""
    siblings = kinds(plan)
    by_obj = {t.obj: t for t in plan}
    everything = [(st.part.name, st.part.footprint) for st in layout]
    steps = []
    for step in layout:
        dense = is_among_neighbours(step)
        steps.append(
            PartStep(
                target=by_obj[step.part.name],
                layout=step,
                among_neighbours=dense,
                release=step.release if dense else None,
                push_towards=free_push_directions(step.part, everything, pads),
                restage=restage_releases(step.part, everything, pads),
                push_opening_m=None,
                kind_targets=siblings.get(step.part.name, ()),
                blocked_by=push_blockers(step.part, everything, pads),
            )
        )
    return tuple(steps)


def check_grasp_among_neighbours(target: Target, step: Step, among_neighbours: bool) -> None:
    """An irregular part among neighbours needs a grasp across its own x or y axis, where the layout puts the pads."""
    if among_neighbours and not target.object_type.shape.rectangular and not step.part.by_outline:
        raise PlanError(
            f"target {target.obj}: a {target.object_type.shape.describe()} among neighbours (released off its "
            "target, or with a side blocked) needs a grasp across its own x or y axis, where the layout puts the "
            "pads: write its outline turned so that two facing edges run along x or y"
        )


def _releases_among_neighbours(step: PartStep) -> bool:
    """True when the part's subtree lets a part go where the layout says: a staged release or a restaging."""
    return step.release is not None or bool(step.restage) or any(n.restage for n in step.neighbours)
