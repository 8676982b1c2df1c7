"""The public builder: compile a plan, then render its tree (puzzles included).

``arrangement(targets, threshold_mm=...)`` parses and checks what a user wrote (the edge where names
become ``PushStrategy`` and ``CorrectMode``), compiles the plan (``bt_arrange.plan.compiled``), and
renders the tree of its parts (``bt_arrange.trees.arrangement``), each puzzle's subtree after them
(``bt_arrange.trees.puzzle``), and the park of the arm at the end.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import py_trees

from bt_arrange.checks import positive_number
from bt_arrange.errors import PlanError
from bt_arrange.perception import ColourTable
from bt_arrange.plan.choices import CorrectMode, PushStrategy
from bt_arrange.plan.compiled import ArrangementPlan, compile_plan
from bt_arrange.plan.targets import DEFAULT_YAW_THRESHOLD_DEG, Target, check_threshold
from bt_arrange.plan.tolerance import Tolerance
from bt_arrange.settings import ManipulationSettings
from bt_arrange.trees.arrangement import Arrangement, render
from bt_arrange.trees.puzzle import OPTIONS as PUZZLE_OPTIONS
from bt_arrange.trees.puzzle import arrange_puzzle
from bt_arrange.trees.steps import Locate


def arrangement(
    targets: Iterable[Target],
    threshold_mm: float = 1.0,
    max_pushes: int = 10,
    correct: CorrectMode | str = CorrectMode.EACH,
    *,
    max_regrasps: int = 3,
    keep_going: bool = True,
    locate: Locate | None = None,
    order: Sequence[str] | None = None,
    strategy: PushStrategy | str = PushStrategy.PAPER,
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
    (``bt_arrange.plan.layout.plan_layout``: the plan's own order where it can be built). Among
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
    strategy = PushStrategy.parse(strategy, "strategy")
    correct = CorrectMode.parse(correct, "correct")
    targets = list(targets) if isinstance(targets, Iterable) and not isinstance(targets, (str, bytes)) else targets
    if puzzles and correct is not CorrectMode.EACH:
        raise PlanError(f"correct={correct.value!r}: a plan with a [puzzle] is corrected part by part (each)")
    check_threshold(threshold_mm, settings)
    if yaw_threshold_deg is not None:
        positive_number("yaw_threshold_deg", yaw_threshold_deg, "deg")
    tolerance = Tolerance(float(threshold_mm), yaw_threshold_deg)  # type: ignore[arg-type]
    options: dict[str, Any] = dict(
        settings=settings,
        correct=correct,
        strategy=strategy,
        order=order,
        max_pushes=max_pushes,
        max_regrasps=max_regrasps,
        keep_going=keep_going,
        colours=colours,
    )
    if not puzzles:
        return render(compile_plan(targets, tolerance, **options), locate)  # type: ignore[arg-type]
    # Without targets, a stand-in's plan checks the options and gives the run's settings; its steps are dropped.
    plan = compile_plan(targets or [Target("red", 0.5, 0.0)], tolerance, **options)  # type: ignore[arg-type]
    if not targets:
        plan = dataclasses.replace(plan, targets=(), steps=())
    return _with_puzzles(render(dataclasses.replace(plan, puzzles=tuple(puzzles)), locate))


def _with_puzzles(root: Arrangement) -> Arrangement:
    """The targets' arrangement (if any), then each puzzle's subtree, then the park."""
    plan: ArrangementPlan = root.plan
    options = {
        "threshold_mm": plan.tolerance.threshold_mm,
        "yaw_threshold_deg": plan.tolerance.yaw_threshold_deg,
        "max_pushes": plan.max_pushes,
        "max_regrasps": plan.max_regrasps,
        "strategy": plan.strategy,
        "keep_going": plan.keep_going,
    }
    park = root.children[-1]
    root.remove_child(park)
    for spec in plan.puzzles:
        subtree = arrange_puzzle(spec, {k: v for k, v in options.items() if k in PUZZLE_OPTIONS})
        root.add_child(
            py_trees.decorators.FailureIsSuccess(name=f"then the next ({spec.name})", child=subtree)
            if plan.keep_going
            else subtree
        )
    root.add_child(park)
    return root


__all__ = ["arrangement"]
