"""The correction subtrees of one part: push and look until within; regrasp, restage, move a neighbour aside.

Split from ``bt_arrange.trees.steps`` (which re-exports every name): ``correction(step, plan)`` is
the paper's inner loop (Algorithm 1, lines 11-15) as a ``RepeatUntilWithin`` over Push and
Inspect, with the fallbacks a part among neighbours or a free part that stalls needs.
"""

from __future__ import annotations

import functools
import operator
from collections.abc import Mapping, Sequence
from typing import Any

import py_trees

from bt_arrange.behaviours import GraspGuard, Inspect, Pick, Place, Push, PushAside, PutBack, keys
from bt_arrange.checks import positive_number
from bt_arrange.decorators import RepeatUntilWithin
from bt_arrange.deprecation import warn_once
from bt_arrange.geometry import PlanarPose
from bt_arrange.numbers import fixed
from bt_arrange.plan.choices import PushStrategy
from bt_arrange.plan.compiled import ArrangementPlan, Aside, NeighbourCheck, PartStep
from bt_arrange.plan.layout import Release
from bt_arrange.plan.targets import DEFAULT_YAW_THRESHOLD_DEG, Target, check_threshold
from bt_arrange.plan.tolerance import Tolerance
from bt_arrange.settings import ManipulationSettings


def inspect(
    target: Target, name: str, *, after_placing: bool = False, kind_targets: Sequence[PlanarPose] = ()
) -> Inspect:
    """The Inspect of one object (its type, colour and, for identical parts, the targets of its kind)."""
    return Inspect(
        name,
        target.obj,
        target.colour,
        after_placing,
        object_type=target.object_type,
        kind_targets=kind_targets,
        z_m=target.z_m,
    )


def check_strategy(strategy: object) -> PushStrategy:
    """The push strategy named ``strategy``, or a ``PlanError`` listing the strategies."""
    return PushStrategy.parse(strategy, "strategy")


#: Corrections in a row that close less than a tenth of the best offset or yaw error so far
#: (``RepeatUntilWithin.stall_after``) before a free part is picked up and placed again. Two: with three,
#: a fragment whose small pushes moved nothing spent its ten pushes at 0.58 mm.
STALL_AFTER_PUSHES = 2


def correction(
    step: PartStep | NeighbourCheck | Target,
    plan: ArrangementPlan | None = None,
    *legacy: Any,
    label: str = "",
    count: bool = True,
    **legacy_keywords: Any,
) -> py_trees.behaviour.Behaviour:
    """Push and inspect one part until it lies within the plan's tolerance of its target.

    ``step`` is a compiled plan's ``PartStep`` (the sides it may be pushed from, its restaging, the
    pads' opening, the camera's margin counted twice when it is looked at again), a
    ``NeighbourCheck`` (a neighbour corrected after another part is down) or a ``Target`` placed
    free. ``plan`` gives the tolerance, the pushes (``max_pushes``, ``strategy``) and the settings
    (default: 1 mm, 1 deg, 10 pushes, the paper's strategy). ``count``: the loop's pushes are the
    part's ``corrections``; ``label`` ends every node's name. The older form
    ``correction(target, threshold_mm, max_pushes, strategy, yaw_threshold_deg=, ...)`` still works,
    with a ``DeprecationWarning`` once.
    """
    if legacy or legacy_keywords or (plan is not None and not isinstance(plan, ArrangementPlan)):
        warn_once(
            "correction(target, threshold_mm, max_pushes, strategy, ...)", "correction(step, plan) of a compiled plan"
        )
        target = step.target if isinstance(step, (PartStep, NeighbourCheck)) else step
        return _correction(
            target, *(() if plan is None else (plan,)), *legacy, label=label, count=count, **legacy_keywords
        )
    plan = plan if plan is not None else ArrangementPlan.of([], Tolerance(1.0, DEFAULT_YAW_THRESHOLD_DEG))
    towards: tuple[str, ...] | None
    restage: dict[str, Release] | None
    opening_m: float | None
    if isinstance(step, NeighbourCheck):
        target, towards, restage, opening_m, kind_targets, margins, blocked_by = (
            step.target,
            step.push_towards,
            dict(step.restage),
            step.push_opening_m,
            step.kind_targets,
            1,
            step.blocked_by,
        )
        asides = step.move_aside
    else:
        part = step if isinstance(step, PartStep) else PartStep.free(step)
        target, towards, restage, opening_m, kind_targets, margins, blocked_by = (
            part.target,
            part.push_towards,
            dict(part.restage) if part.restage is not None else None,
            part.push_opening_m,
            part.kind_targets,
            part.margins,
            part.blocked_by,
        )
        asides = part.move_aside
    return _correction(
        target,
        plan.tolerance.threshold_mm,
        plan.max_pushes,
        plan.strategy,
        yaw_threshold_deg=plan.tolerance.yaw_threshold_deg,
        kind_targets=kind_targets,
        towards=towards,
        restage=restage,
        push_opening_m=opening_m,
        count=count,
        label=label,
        settings=plan.settings,
        margins=margins,
        blocked_by=blocked_by,
        move_aside=tuple(
            _move_aside(target, aside, plan, towards or (), opening_m, label, blocked_by, margins) for aside in asides
        ),
    )


def _correction(
    target: Target,
    threshold_mm: float = 1.0,
    max_pushes: int = 10,
    strategy: PushStrategy | str = PushStrategy.PAPER,
    *,
    yaw_threshold_deg: float | None = DEFAULT_YAW_THRESHOLD_DEG,
    kind_targets: Sequence[PlanarPose] = (),
    towards: tuple[str, ...] | None = None,
    restage: dict[str, Release] | None = None,
    push_opening_m: float | None = None,
    count: bool = True,
    label: str = "",
    settings: ManipulationSettings | None = None,
    margins: int = 1,
    blocked_by: Mapping[str, str] | None = None,
    move_aside: Sequence[py_trees.behaviour.Behaviour] = (),
) -> py_trees.behaviour.Behaviour:
    """Push and inspect one object until it lies within ``threshold_mm`` (and ``yaw_threshold_deg``) of its target.

    ``towards``: the directions (target frame) it may be pushed, the sides a neighbour blocks left
    out (default all four). ``restage``: per blocked direction, a release on the other side; when
    a correction needs a blocked side, Push fails and the part is picked up and released there,
    from where a push is free. ``count``: the loop's pushes are the object's ``corrections``.
    ``strategy`` is the push's (``Push``): ``"paper"``, the paper's alternating push, ``"learned"``
    or ``"diagonal"``.
    ``yaw_threshold_deg=None`` corrects the position only. ``settings`` are the run's (the
    threshold's floor). ``margins``: how many times the camera's error is added to the offset
    (``RepeatUntilWithin.margins``: 2 for a part a later neighbour's recheck reads again).
    ``blocked_by``: per blocked push, the neighbour in the way, which a blocked correction names.
    ``move_aside``: fallbacks after the restaging, each moving a neighbour aside for one blocked push
    (``_move_aside``).
    """
    check_threshold(threshold_mm, settings)
    strategy = check_strategy(strategy)
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
        z_m=target.z_m,
        # Among neighbours a part pushed squarely onto its edges may be stopped short of its place,
        # as far as the threshold allows (``Push.plan_square_push``); a box is pushed as Table 1's.
        threshold_mm=None if towards is None or target.object_type.shape.rectangular else threshold_mm,
        blockers=blocked_by,
    )
    if restage or move_aside:
        push = py_trees.composites.Selector(
            name=f"push {obj} from a free side{label}",
            memory=True,
            children=[
                push,
                *(_restage(target, d, release, label) for d, release in (restage or {}).items()),
                *move_aside,
            ],
        )
    push_and_look = py_trees.composites.Sequence(
        name=f"push and inspect {obj}{label}",
        memory=True,
        children=[push, inspect(target, f"inspect {obj}{label}", kind_targets=kind_targets)],
    )
    # A free part whose pushes stop converging is picked up and placed again, and corrected once more,
    # rather than spending the rest of its pushes. Among neighbours the release and the
    # sides to push from are the layout's: there the loop keeps its pushes.
    free = towards is None and not restage and not move_aside
    # What the loop and the loop after placing again share: the part's offset, corrections and yaw keys.
    correction_loop = functools.partial(
        RepeatUntilWithin,
        offset_key=keys.key(obj, keys.OFFSET_MM),
        threshold_mm=threshold_mm,
        max_attempts=max_pushes,
        corrections_key=keys.key(obj, keys.CORRECTIONS) if count else None,
        obj=obj,
        yaw_key=keys.key(obj, keys.YAW_ERROR_DEG),
        yaw_threshold_deg=yaw_threshold_deg,
        margins=margins,
    )
    loop = correction_loop(
        name=f"correct {obj} to {threshold_mm:g} mm{label}",
        child=push_and_look,
        stall_after=STALL_AFTER_PUSHES if free else 0,
        release_again=bool(restage),
    )
    if not free:
        return loop
    kind = target.object_type
    again = correction_loop(
        name=f"correct {obj} to {threshold_mm:g} mm after placing it again{label}",
        child=py_trees.composites.Sequence(
            name=f"push and inspect {obj} after placing it again{label}",
            memory=True,
            children=[
                Push(
                    f"push {obj} after placing it again{label}", obj, strategy, kind, yaw_threshold_deg, z_m=target.z_m
                ),
                inspect(target, f"inspect {obj} after pushing it again{label}", kind_targets=kind_targets),
            ],
        ),
        accumulate=True,
    )
    place_again = py_trees.composites.Sequence(
        name=f"place {obj} again when its pushes stall{label}",
        memory=True,
        children=[
            reads_text(f"{obj}'s pushes stalled{label}", keys.key(obj, keys.PUSHES_STALLED), keys.STALLED),
            Pick(f"pick {obj} to place it again{label}", obj, kind, z_m=target.z_m),
            GraspGuard(
                f"while holding {obj} to place it again{label}",
                Place(f"place {obj} again{label}", obj, kind, z_m=target.z_m),
            ),
            inspect(target, f"inspect {obj} after placing it again{label}", kind_targets=kind_targets),
            again,
        ],
    )
    return py_trees.composites.Selector(
        name=f"correct {obj}, else place it again{label}", memory=True, children=[loop, place_again]
    )


def reads_text(name: str, key: str, text: str) -> py_trees.behaviour.Behaviour:
    """A condition: SUCCESS while the blackboard's ``key`` holds ``text`` (the only check an XML tree writes)."""
    return py_trees.behaviours.CheckBlackboardVariableValue(
        name=name, check=py_trees.common.ComparisonExpression(key, text, operator.eq)
    )


def _restage(target: Target, towards: str, release: Release, label: str) -> py_trees.behaviour.Behaviour:
    """When Push needed ``towards`` from a blocked side: pick the part up, release it past the target on that side."""
    obj = target.obj
    dx, dy = release.offset_m
    return py_trees.composites.Sequence(
        name=f"release {obj} again {fixed(dx * 1000, 0, sign=True)}, {fixed(dy * 1000, 0, sign=True)} mm "
        f"to push it {towards}{label}",
        memory=True,
        children=[
            reads_text(f"{obj} needs a push {towards}{label}", keys.key(obj, keys.BLOCKED_TOWARDS), towards),
            # The loop allows it while a correction is left to push the part back and doing so brought it closer.
            reads_text(f"{obj} may be released again{label}", keys.key(obj, keys.RELEASE_AGAIN), keys.ALLOWED),
            Pick(f"pick {obj} again{label}", obj, target.object_type, grasp=release, z_m=target.z_m),
            GraspGuard(
                f"while holding {obj} again{label}",
                Place(f"place {obj} again{label}", obj, target.object_type, release=release, z_m=target.z_m),
            ),
        ],
    )


def _move_aside(
    target: Target,
    aside: Aside,
    plan: ArrangementPlan,
    towards: tuple[str, ...],
    opening_m: float | None,
    label: str,
    blocked_by: Mapping[str, str],
    margins: int = 1,
) -> py_trees.behaviour.Behaviour:
    """When Push needed ``aside.move.towards`` and the neighbour in its way is one the layout can move aside.

    ::

        Sequence "move <neighbour> aside to correct <obj>"
        ├── CheckBlackboardVariableValue "<obj> needs a push <towards>"   /<obj>/blocked_towards
        ├── CheckBlackboardVariableValue "<neighbour> is in its way"       /<obj>/blocked_by
        ├── PushAside "push <neighbour> aside"                             the layout's push, how far
        ├── Inspect "inspect <neighbour> aside"
        ├── FailureIsSuccess "then put <neighbour> back"
        │   └── RepeatUntilWithin "correct <obj> to T mm with <neighbour> aside"
        │       └── Push "push <obj> with <neighbour> aside" (<towards> free too), Inspect
        ├── Sequence "put <neighbour> back"
        │   ├── Push "put <neighbour> back"                                from the side it went to
        │   ├── Inspect "inspect <neighbour> put back"
        │   └── the neighbour's correction, as its recheck's (nothing moved aside for it)
        └── RepeatUntilWithin "<obj> within with <neighbour> back"         its last look: no push

    The neighbour is put back whatever became of the part; the branch succeeds only when the part's
    last look found it within (``margins`` as its own loop's), so a correction that failed with the
    neighbour aside fails here rather than moving the neighbour again.
    """
    obj, move = target.obj, aside.move
    back = aside.neighbour
    neighbour = back.target
    other = neighbour.obj
    tolerance = plan.tolerance
    threshold_mm, yaw_threshold_deg = tolerance.threshold_mm, tolerance.yaw_threshold_deg

    # The push with the neighbour aside still names the others in its way.
    blocked_with_aside = {d: n for d, n in blocked_by.items() if d != move.towards}

    def loop(name: str, child: py_trees.behaviour.Behaviour, max_attempts: int) -> RepeatUntilWithin:
        return RepeatUntilWithin(
            name=name,
            child=child,
            offset_key=keys.key(obj, keys.OFFSET_MM),
            threshold_mm=threshold_mm,
            max_attempts=max_attempts,
            obj=obj,
            yaw_key=keys.key(obj, keys.YAW_ERROR_DEG),
            yaw_threshold_deg=yaw_threshold_deg,
            # As the part's own loop counts the camera's error: within for one is within for the other.
            margins=margins,
        )

    with_aside = loop(
        f"correct {obj} to {threshold_mm:g} mm with {other} aside{label}",
        py_trees.composites.Sequence(
            name=f"push and inspect {obj} with {other} aside{label}",
            memory=True,
            children=[
                Push(
                    f"push {obj} with {other} aside{label}",
                    obj,
                    plan.strategy,
                    target.object_type,
                    yaw_threshold_deg,
                    towards=(*towards, move.towards),
                    opening_m=opening_m,
                    z_m=target.z_m,
                    threshold_mm=threshold_mm,
                    blockers=blocked_with_aside,
                ),
                inspect(target, f"inspect {obj} with {other} aside{label}"),
            ],
        ),
        plan.max_pushes,
    )
    put_back = py_trees.composites.Sequence(
        name=f"put {other} back{label}",
        memory=True,
        children=[
            PutBack(f"put {other} back{label}", other, move.back, neighbour.object_type, z_m=neighbour.z_m),
            inspect(neighbour, f"inspect {other} put back{label}", kind_targets=back.kind_targets),
            correction(back, plan, count=False, label=f" put back for {obj}{label}"),
        ],
    )
    return py_trees.composites.Sequence(
        name=f"move {other} aside to correct {obj}{label}",
        memory=True,
        children=[
            reads_text(f"{obj} needs a push {move.towards}{label}", keys.key(obj, keys.BLOCKED_TOWARDS), move.towards),
            reads_text(f"{other} is in its way{label}", keys.key(obj, keys.BLOCKED_BY), other),
            PushAside(
                f"push {other} aside{label}",
                other,
                move.aside,
                move.distance_m,
                neighbour.object_type,
                for_obj=obj,
                z_m=neighbour.z_m,
            ),
            inspect(neighbour, f"inspect {other} aside{label}", kind_targets=back.kind_targets),
            py_trees.decorators.FailureIsSuccess(name=f"then put {other} back{label}", child=with_aside),
            put_back,
            loop(f"{obj} within with {other} back{label}", py_trees.behaviours.Success(name=f"{obj} looked at"), 0),
        ],
    )
