"""The subtrees of one part in the paper's Algorithm 1: set its target, find it, transfer it, look, correct.

``locate`` says how a part is found before it is picked: ``by_camera()`` (the default, the top
camera's colour detection, ``Detect``) or ``by_depth(seed)`` (the depth-only grasp estimator of
Table 1's row 4, ``EstimateGraspFromDepth``); any ``Callable[[Target], Behaviour]`` that writes
``/<obj>/pose`` will do.
"""

from __future__ import annotations

import operator
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import py_trees

from bt_arrange.behaviours import (
    Detect,
    EstimateGraspFromDepth,
    GraspGuard,
    Inspect,
    LookAtHeld,
    Pick,
    Place,
    Push,
    Separate,
    keys,
)
from bt_arrange.checks import positive_number, whole_number
from bt_arrange.decorators import RepeatUntilWithin
from bt_arrange.deprecation import warn_once
from bt_arrange.errors import PlanError
from bt_arrange.geometry import PlanarPose
from bt_arrange.numbers import fixed
from bt_arrange.perception.depth_grasp import DepthGraspConfig, DepthGraspEstimator
from bt_arrange.plan.choices import PushStrategy
from bt_arrange.plan.compiled import ArrangementPlan, NeighbourCheck, PartStep
from bt_arrange.plan.layout import Release
from bt_arrange.plan.targets import DEFAULT_YAW_THRESHOLD_DEG, Target, check_threshold
from bt_arrange.plan.tolerance import Tolerance
from bt_arrange.settings import ManipulationSettings
from bt_arrange.trees.turned import (  # noqa: F401  (re-exported: the names' former home)
    CAMERA_YAW_MARGIN_DEG,
    COARSE_YAW_THRESHOLD_DEG,
    MAX_TURNED_REGRASPS,
    REGRASP_ANY_YAW_DEG,
    REGRASP_YAW_DEG,
    regrasp_while_turned,
    turned_limit_deg,
)


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
    known = (estimator.config if estimator is not None else DepthGraspConfig()).part

    def locate(target: Target) -> py_trees.behaviour.Behaviour:
        if target.object_type != known:
            raise PlanError(
                f"target {target.obj}: the depth-only grasp estimator looks for a {known.name} ({known.size_text}), "
                f"not a {target.object_type.name} ({target.object_type.size_text}): it finds one box type per run, "
                "given as by_depth(estimator=DepthGraspEstimator(DepthGraspConfig(part=...)))"
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
    step: PartStep | Target,
    plan: ArrangementPlan | None = None,
    *legacy: Any,
    locate: Locate | None = None,
    **legacy_keywords: Any,
) -> py_trees.behaviour.Behaviour:
    """Locate, pick and place one part: ``step`` is a compiled plan's ``PartStep``, or a ``Target`` placed free.

    ``plan`` gives the regrasps (``max_regrasps``, default 3); ``locate`` builds the behaviour that
    finds the part (default ``by_camera()``: Detect). The step says where the pads go among
    neighbours and whether the wrist takes its nearest grasp. The older form
    ``transfer(target, max_regrasps, kind_targets=, release=, nearest=)`` still works, with a
    ``DeprecationWarning`` once.
    """
    if legacy or legacy_keywords or (plan is not None and not isinstance(plan, ArrangementPlan)):
        warn_once("transfer(target, max_regrasps, kind_targets=, release=, nearest=)", "transfer(step, plan)")
        target = step.target if isinstance(step, PartStep) else step
        return _transfer(target, *(() if plan is None else (plan,)), *legacy, locate=locate, **legacy_keywords)
    part = step if isinstance(step, PartStep) else PartStep.free(step)
    return _transfer(
        part.target,
        plan.max_regrasps if plan is not None else 3,
        locate=locate,
        kind_targets=part.kind_targets,
        release=part.release,
        nearest=part.nearest_grasp,
    )


def _transfer(
    target: Target,
    max_regrasps: int = 3,
    *,
    locate: Locate | None = None,
    kind_targets: Sequence[PlanarPose] = (),
    release: Release | None = None,
    nearest: bool = False,
) -> py_trees.behaviour.Behaviour:
    """Locate, pick and place one object; a part lost on the way is located and picked again.

    ``locate`` builds the behaviour that finds the object (default ``by_camera()``: Detect).
    ``kind_targets`` (identical parts: the targets of the kind) let a Detect choose a part that
    is not at one of them. ``release`` says where the pads go among neighbours
    (``bt_arrange.plan.layout``; default: anywhere). ``nearest``: the wrist's nearest grasp and turn
    (``Pick(nearest_grasp=...)``, ``Place(nearest_turn=...)``), for a part neighbours are placed
    beside (measured, the half turn and the short way round moved more of them out).

    A part that touches others of its colour where it starts is separated before it is picked: the
    first look (``Detect(alone=True)``) fails on touching parts of its colour, and the part's
    ``Separate`` pushes one of them aside before it looks again::

        Selector "find <obj>, else separate it from touching parts"
        ├── Detect "detect <obj>"                        before_pick(): fails on touching parts
        └── Sequence "separate <obj> from touching parts, then look again"
            ├── CheckBlackboardVariableValue "<obj> touches parts of its colour"   /<obj>/touching
            ├── Separate "push a part touching <obj> aside"
            └── Detect "detect <obj> after separating"

    Where nothing touches, the first Detect succeeds as before and the rest never runs.
    """
    obj = target.obj
    kind = target.object_type

    def find(name: str | None = None) -> py_trees.behaviour.Behaviour:
        finder = (locate or by_camera())(target)
        if kind_targets and isinstance(finder, Detect):
            finder.among(kind_targets)
        if name is not None:
            finder.name = name
        return finder

    def find_alone() -> py_trees.behaviour.Behaviour:
        first = find()
        if not isinstance(first, Detect) or type(first) is not Detect:
            return first  # another locator (depth) has no blob to separate
        first.before_pick()
        again = find(f"detect {obj} after separating")
        assert isinstance(again, Detect)
        again.before_pick()
        separate = Separate(f"push a part touching {obj} aside", obj, target.colour, kind)
        return py_trees.composites.Selector(
            name=f"find {obj}, else separate it from touching parts",
            memory=True,
            children=[
                first,
                py_trees.composites.Sequence(
                    name=f"separate {obj} from touching parts, then look again",
                    memory=True,
                    children=[
                        # Only a look that failed on touching parts goes on: a part not found costs no look more.
                        py_trees.behaviours.CheckBlackboardVariableValue(
                            name=f"{obj} touches parts of its colour",
                            check=py_trees.common.ComparisonExpression(
                                keys.key(obj, keys.TOUCHING), keys.TOUCHING_PARTS, operator.eq
                            ),
                        ),
                        separate,
                        again,
                    ],
                ),
            ],
        )

    look_again: list[py_trees.behaviour.Behaviour] = []
    held = release is not None and target.z_m == 0.0 and not kind.shape.rectangular
    # Layers: a part going onto others is set down and picked centred first, as among
    # neighbours: an offset in the pads would put its centre of mass off its support.
    if release is not None or target.z_m > 0.0:
        # Among neighbours the part's offset in the pads (a pick 2 cm off places it 2 cm off) would
        # carry into a neighbour: set it down where it was picked, look at it again, and pick it centred.
        set_down: list[py_trees.behaviour.Behaviour] = [
            GraspGuard(
                f"while setting {obj} down",
                Place(f"set {obj} down to look again", obj, kind, where="pick"),
            ),
            find(),
            # Among neighbours the wrist's nearest grasp, as the layout planned it; the half
            # turn was not measured to help there (the tight-gap fresco benchmark, docs/motion.md).
            Pick(f"pick {obj} centred", obj, kind, nearest_grasp=True),
        ]
        look_again = set_down
        if held:
            # An irregular part sticks out beside the pads, where the top camera sees it (a box the
            # pads hold centred is hidden under the gripper, and keeps the set-down).
            look_again = [held_look(target, set_down)]
    carry = py_trees.composites.Sequence(
        name=f"transfer {obj}",
        memory=True,
        children=[
            find_alone(),
            Pick(f"pick {obj}", obj, kind, nearest_grasp=nearest or bool(look_again)),
            *look_again,
            GraspGuard(
                f"while holding {obj}",
                Place(
                    f"place {obj}",
                    obj,
                    kind,
                    release=release,
                    z_m=target.z_m,
                    nearest_turn=nearest,
                    held=held,
                ),
            ),
        ],
    )
    whole_number("max_regrasps", max_regrasps)
    # py_trees' Retry counts every attempt: the first one plus max_regrasps more.
    return py_trees.decorators.Retry(name=f"pick and place {obj}", child=carry, num_failures=max_regrasps + 1)


def held_look(target: Target, set_down: Sequence[py_trees.behaviour.Behaviour]) -> py_trees.behaviour.Behaviour:
    """Measure the held part in the fingers; set it down and pick it centred only when that cannot be trusted.

    Among neighbours, after the pick::

        Selector "look at <obj> in the fingers, else set it down"
        ├── GraspGuard "while looking at <obj> in the fingers"
        │   └── LookAtHeld "look at <obj> in the fingers"      /<obj>/held_correction, held_look = "held look"
        ├── GraspGuard "while looking at <obj> in the fingers again"
        │   └── LookAtHeld "look at <obj> in the fingers, turned"   the pads a quarter turn round
        └── Sequence "set <obj> down, look at it and pick it centred"     (held_look stays "set down")
            └── the set-down: Place where="pick", the look, Pick "pick <obj> centred"

    The placing after it (``Place(held=True)``) corrects its TCP pose by what was measured.
    """
    obj = target.obj
    return py_trees.composites.Selector(
        name=f"look at {obj} in the fingers, else set it down",
        memory=True,
        children=[
            GraspGuard(
                f"while looking at {obj} in the fingers",
                LookAtHeld(f"look at {obj} in the fingers", obj, target.colour, target.object_type),
            ),
            # Where the first look saw too little, the pads a quarter turn round show other edges.
            GraspGuard(
                f"while looking at {obj} in the fingers again",
                LookAtHeld(
                    f"look at {obj} in the fingers, turned", obj, target.colour, target.object_type, quarter_turn=True
                ),
            ),
            py_trees.composites.Sequence(
                name=f"set {obj} down, look at it and pick it centred", memory=True, children=list(set_down)
            ),
        ],
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
    # A free part whose pushes stop converging is picked up and placed again, and corrected once more,
    # rather than spending the rest of its pushes. Among neighbours the release and the
    # sides to push from are the layout's: there the loop keeps its pushes.
    free = towards is None and not restage
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
