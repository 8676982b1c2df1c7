"""The public builder: compile a plan, then render its tree (puzzles included).

``arrangement(targets, threshold_mm=...)`` parses and checks what a user wrote (the edge where names
become ``PushStrategy`` and ``CorrectMode``), compiles the plan (``bt_arrange.plan.compiled``), and
renders the tree of its parts (``bt_arrange.trees.arrangement``), each puzzle's subtree after them
(``bt_arrange.trees.puzzle``), and the park of the arm at the end.
"""

from __future__ import annotations

import dataclasses
import inspect
from collections.abc import Iterable
from typing import Any

import py_trees

from bt_arrange.checks import positive_number
from bt_arrange.deprecation import warn_once
from bt_arrange.errors import PlanError
from bt_arrange.plan.check import check_puzzles
from bt_arrange.plan.choices import CorrectMode, PushStrategy
from bt_arrange.plan.compiled import ArrangementPlan, compile_plan
from bt_arrange.plan.targets import DEFAULT_YAW_THRESHOLD_DEG, Target, check_threshold
from bt_arrange.plan.tolerance import Tolerance
from bt_arrange.suggest import did_you_mean
from bt_arrange.trees.arrangement import Arrangement, render
from bt_arrange.trees.puzzle import OPTIONS as PUZZLE_OPTIONS
from bt_arrange.trees.puzzle import arrange_puzzle
from bt_arrange.trees.steps import Locate

#: The keywords of ``arrangement`` beyond the targets, the threshold and ``locate``: the plan's options,
#: ``compile_plan``'s own and the two the builder takes itself.
PLAN_OPTIONS = ("yaw_threshold_deg", "puzzles", *list(inspect.signature(compile_plan).parameters)[2:])
#: The former positional parameters after ``threshold_mm``, deprecated.
_POSITIONAL = ("max_pushes", "correct")


def arrangement(
    targets: Iterable[Target],
    threshold_mm: float = 1.0,
    *legacy: Any,
    locate: Locate | None = None,
    **options: Any,
) -> Arrangement:
    """An arrangement of several parts, checked before anything moves: ``compile_plan``, then ``render``.

    ``threshold_mm`` is the accuracy each part must end within; ``locate`` says how each part is
    found before it is picked (default ``by_camera()``). The plan's ``options`` (``PLAN_OPTIONS``):

    - ``yaw_threshold_deg`` (default 1; None: position only);
    - ``correct``: ``"each"`` corrects every part right after placing it (Algorithm 1, the default),
      ``"after_all"`` places all of them first (the paper's Fig. 5) (``CorrectMode``);
    - ``strategy``: ``"paper"`` (alternating x and y, Table 1's), ``"learned"`` or ``"diagonal"``
      (``PushStrategy``); ``max_pushes`` (10) and ``max_regrasps`` (3);
    - ``keep_going`` (True): a part that cannot be finished does not stop the others;
    - ``order``: the placing order (object names; default the layout's);
    - ``colours``: the plan's colour table; ``settings``: the handling settings (the gripper among them);
    - ``puzzles`` (``bt_arrange.puzzle.PuzzleSpec``s): slabs reassembled from the camera alone after
      the targets; with puzzles, ``targets`` may be empty.

    ``arrangement(targets, threshold_mm, max_pushes, correct)`` with those two positional still
    works, with a ``DeprecationWarning`` once.
    """
    if legacy:
        if len(legacy) > len(_POSITIONAL):
            raise TypeError(f"arrangement() takes 2 positional arguments but {2 + len(legacy)} were given")
        warn_once(
            "arrangement(targets, threshold_mm, max_pushes, correct)", "arrangement(targets, threshold_mm, **options)"
        )
        for name, value in zip(_POSITIONAL, legacy, strict=False):
            if name in options:
                raise TypeError(f"arrangement() got multiple values for argument {name!r}")
            options[name] = value
    unknown = sorted(set(options) - set(PLAN_OPTIONS))
    if unknown:
        raise TypeError(
            f"arrangement() got an unexpected keyword argument {unknown[0]!r}{did_you_mean(unknown[0], PLAN_OPTIONS)}"
        )
    yaw_threshold_deg = options.pop("yaw_threshold_deg", DEFAULT_YAW_THRESHOLD_DEG)
    puzzles = tuple(options.pop("puzzles", ()))
    options["strategy"] = PushStrategy.parse(options.get("strategy", PushStrategy.PAPER), "strategy")
    options["correct"] = correct = CorrectMode.parse(options.get("correct", CorrectMode.EACH), "correct")
    targets = list(targets) if isinstance(targets, Iterable) and not isinstance(targets, (str, bytes)) else targets
    if puzzles and correct is not CorrectMode.EACH:
        raise PlanError(f"correct={correct.value!r}: a plan with a [puzzle] is corrected part by part (each)")
    settings = options.get("settings")
    check_threshold(threshold_mm, settings)
    if yaw_threshold_deg is not None:
        positive_number("yaw_threshold_deg", yaw_threshold_deg, "deg")
    tolerance = Tolerance(float(threshold_mm), yaw_threshold_deg)
    if not puzzles:
        return render(compile_plan(targets, tolerance, **options), locate)
    check_puzzles(puzzles, targets, float(threshold_mm), settings)
    # Without targets, a stand-in's plan checks the options and gives the run's settings; its steps are dropped.
    plan = compile_plan(targets or [Target("red", 0.5, 0.0)], tolerance, **options)
    if not targets:
        plan = dataclasses.replace(plan, targets=(), steps=())
    return _with_puzzles(render(dataclasses.replace(plan, puzzles=puzzles), locate))


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


__all__ = ["PLAN_OPTIONS", "arrangement"]
