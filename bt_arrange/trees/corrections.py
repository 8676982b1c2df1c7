"""The correction subtrees of one part: push and look until within; regrasp, restage, move a neighbour aside.

Split from ``bt_arrange.trees.steps`` (which re-exports every name): ``correction(step, plan)`` is
the paper's inner loop (Algorithm 1, lines 11-15) as a ``RepeatUntilWithin`` over Push and
Inspect, with the fallbacks a part among neighbours or a free part that stalls needs.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Mapping, Sequence
from typing import Any

import py_trees

from bt_arrange.behaviours import GraspGuard, Inspect, Pick, Place, Push, PushAside, PutBack, keys
from bt_arrange.checks import positive_number, whole_number
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

#: A part placed turned this far or more from its target's yaw (deg, measured by the camera) is picked
#: up again rather than pushed. A push that moves a part a long way also squares it (a triangle 2.45 deg
#: off, pushed 3.7 mm, ended 0.01 deg off), but near its place a squaring press turns it back 0.16 to
#: 0.33 deg (the runs, seeds 0 and 4: an ell 2.07 deg off took two presses, stalled and was
#: placed again, 0.01 deg off); a push with its look costs 2.4 s of world time, a placing again about 3 s.
#: Over ``irregular_parts`` at seeds 0 to 9, 1.5 deg took 3.87 s a part against 3.97 s at 12 deg.
REGRASP_YAW_DEG = 1.5
#: A part corrected by position alone (no yaw threshold) is picked up again only when turned this far
#: or more (deg): its square pushes meet a turned edge on a corner.
REGRASP_ANY_YAW_DEG = 12.0
#: The most times a turned part is picked up again before its correction is left to fail.
MAX_TURNED_REGRASPS = 2


def turned_limit_deg(yaw_threshold_deg: float | None, rechecked: bool = False) -> float:
    """How far turned (deg) a part placed free is picked up again: ``REGRASP_YAW_DEG``, or a coarser yaw threshold.

    A part within the plan's yaw threshold is never placed again for its yaw. With no yaw threshold
    (position only), and for a part a later neighbour is placed beside (``rechecked``: a fresco's
    first piece), ``REGRASP_ANY_YAW_DEG``: in the real-cell model a fresco's first piece placed again
    at 1.5 deg took ten pushes and a later piece ended 1.5 mm off (seed 2), where it ended within.
    """
    if yaw_threshold_deg is None or rechecked:
        return REGRASP_ANY_YAW_DEG
    return max(REGRASP_YAW_DEG, yaw_threshold_deg)


def regrasp_while_turned(
    target: Target,
    *,
    yaw_limit_deg: float = REGRASP_YAW_DEG,
    max_regrasps: int = MAX_TURNED_REGRASPS,
    kind_targets: Sequence[PlanarPose] = (),
) -> py_trees.behaviour.Behaviour:
    """Pick the part up again at its camera pose and place it again while it lies turned ``yaw_limit_deg`` or more.

    After the inspect after placing (which writes ``/<obj>/pose`` and ``/<obj>/yaw_error_deg``)::

        RepeatUntilWithin "regrasp <obj> while turned 1.5 deg or more"   (yaw only: any offset will do)
        └── Sequence "pick and place <obj> again"
            ├── Pick "pick <obj> again"                  at /<obj>/pose, from the camera
            ├── GraspGuard "while holding <obj> again"
            │   └── Place "place <obj> again"
            └── Inspect "inspect <obj> after placing again"

    A part turned less than the limit passes at once, in the same tick: nothing moves. An irregular
    part held across an edge and a corner can turn in the pads (the close, the carry, the release)
    by a degree or two, at worst tens; a squaring press near its place corrects a few tenths.
    ``max_regrasps`` attempts, then it fails with the yaw. ``turned_limit_deg`` gives a plan's limit.
    """
    positive_number("yaw_limit_deg", yaw_limit_deg, "deg")
    whole_number("max_regrasps", max_regrasps)
    obj = target.obj
    kind = target.object_type
    again = py_trees.composites.Sequence(
        name=f"pick and place {obj} again",
        memory=True,
        children=[
            Pick(f"pick {obj} again", obj, kind, z_m=target.z_m),
            GraspGuard(f"while holding {obj} again", Place(f"place {obj} again", obj, kind, z_m=target.z_m)),
            inspect(target, f"inspect {obj} after placing again", after_placing=True, kind_targets=kind_targets),
        ],
    )
    return RepeatUntilWithin(
        name=f"regrasp {obj} while turned {yaw_limit_deg:g} deg or more",
        child=again,
        offset_key=keys.key(obj, keys.OFFSET_MM),
        threshold_mm=math.inf,  # the offset is the pushes' business: only the yaw decides
        max_attempts=max_regrasps,
        obj=obj,
        yaw_key=keys.key(obj, keys.YAW_ERROR_DEG),
        yaw_threshold_deg=yaw_limit_deg,
    )


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
    loop = RepeatUntilWithin(
        name=f"correct {obj} to {threshold_mm:g} mm{label}",
        child=push_and_look,
        offset_key=keys.key(obj, keys.OFFSET_MM),
        threshold_mm=threshold_mm,
        max_attempts=max_pushes,
        corrections_key=keys.key(obj, keys.CORRECTIONS) if count else None,
        obj=obj,
        yaw_key=keys.key(obj, keys.YAW_ERROR_DEG),
        yaw_threshold_deg=yaw_threshold_deg,
        stall_after=STALL_AFTER_PUSHES if free else 0,
        margins=margins,
        release_again=bool(restage),
    )
    if not free:
        return loop
    kind = target.object_type
    again = RepeatUntilWithin(
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
        offset_key=keys.key(obj, keys.OFFSET_MM),
        threshold_mm=threshold_mm,
        max_attempts=max_pushes,
        corrections_key=keys.key(obj, keys.CORRECTIONS) if count else None,
        obj=obj,
        yaw_key=keys.key(obj, keys.YAW_ERROR_DEG),
        yaw_threshold_deg=yaw_threshold_deg,
        accumulate=True,
        margins=margins,
    )
    place_again = py_trees.composites.Sequence(
        name=f"place {obj} again when its pushes stall{label}",
        memory=True,
        children=[
            py_trees.behaviours.CheckBlackboardVariableValue(
                name=f"{obj}'s pushes stalled{label}",
                check=py_trees.common.ComparisonExpression(
                    keys.key(obj, keys.PUSHES_STALLED), keys.STALLED, operator.eq
                ),
            ),
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


def _restage(target: Target, towards: str, release: Release, label: str) -> py_trees.behaviour.Behaviour:
    """When Push needed ``towards`` from a blocked side: pick the part up, release it past the target on that side."""
    obj = target.obj
    dx, dy = release.offset_m
    return py_trees.composites.Sequence(
        name=f"release {obj} again {fixed(dx * 1000, 0, sign=True)}, {fixed(dy * 1000, 0, sign=True)} mm "
        f"to push it {towards}{label}",
        memory=True,
        children=[
            py_trees.behaviours.CheckBlackboardVariableValue(
                name=f"{obj} needs a push {towards}{label}",
                check=py_trees.common.ComparisonExpression(keys.key(obj, keys.BLOCKED_TOWARDS), towards, operator.eq),
            ),
            # The loop allows it while a correction is left to push the part back and doing so brought it closer.
            py_trees.behaviours.CheckBlackboardVariableValue(
                name=f"{obj} may be released again{label}",
                check=py_trees.common.ComparisonExpression(
                    keys.key(obj, keys.RELEASE_AGAIN), keys.ALLOWED, operator.eq
                ),
            ),
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
            py_trees.behaviours.CheckBlackboardVariableValue(
                name=f"{obj} needs a push {move.towards}{label}",
                check=py_trees.common.ComparisonExpression(
                    keys.key(obj, keys.BLOCKED_TOWARDS), move.towards, operator.eq
                ),
            ),
            py_trees.behaviours.CheckBlackboardVariableValue(
                name=f"{other} is in its way{label}",
                check=py_trees.common.ComparisonExpression(keys.key(obj, keys.BLOCKED_BY), other, operator.eq),
            ),
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
