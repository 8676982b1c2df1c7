"""The subtrees of one part in the paper's Algorithm 1: set its target, find it, transfer it, look, correct.

``locate`` says how a part is found before it is picked: ``by_camera()`` (the default, the top
camera's colour detection, ``Detect``) or ``by_depth(seed)`` (the depth-only grasp estimator of
Table 1's row 4, ``EstimateGraspFromDepth``); any ``Callable[[Target], Behaviour]`` that writes
``/<obj>/pose`` will do.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import py_trees

from bt_arrange.behaviours import (
    Detect,
    EstimateGraspFromDepth,
    GraspGuard,
    LookAtHeld,
    Pick,
    Place,
    Separate,
    keys,
)
from bt_arrange.checks import whole_number
from bt_arrange.deprecation import warn_once
from bt_arrange.errors import PlanError
from bt_arrange.geometry import PlanarPose
from bt_arrange.perception.depth_grasp import DepthGraspConfig, DepthGraspEstimator
from bt_arrange.plan.compiled import ArrangementPlan, PartStep
from bt_arrange.plan.layout import Release
from bt_arrange.plan.targets import Target
from bt_arrange.trees.corrections import (
    STALL_AFTER_PUSHES,
    _correction,
    check_strategy,
    correction,
    inspect,
    reads_text,
)
from bt_arrange.trees.turned import (
    CAMERA_YAW_MARGIN_DEG,
    COARSE_YAW_THRESHOLD_DEG,
    MAX_TURNED_REGRASPS,
    REGRASP_ANY_YAW_DEG,
    REGRASP_YAW_DEG,
    regrasp_while_turned,
    turned_limit_deg,
)

#: The correction subtrees live in ``bt_arrange.trees.corrections``, a turned part's in ``trees.turned``;
#: their names are this module's too.
__all__ = [
    "CAMERA_YAW_MARGIN_DEG",
    "COARSE_YAW_THRESHOLD_DEG",
    "Locate",
    "MAX_TURNED_REGRASPS",
    "REGRASP_ANY_YAW_DEG",
    "REGRASP_YAW_DEG",
    "STALL_AFTER_PUSHES",
    "_correction",
    "by_camera",
    "by_depth",
    "check_strategy",
    "correction",
    "held_look",
    "inspect",
    "regrasp_while_turned",
    "set_target",
    "transfer",
    "turned_limit_deg",
]


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
                        reads_text(
                            f"{obj} touches parts of its colour", keys.key(obj, keys.TOUCHING), keys.TOUCHING_PARTS
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
