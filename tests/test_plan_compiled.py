"""The plan's floor: a compiled plan, the one "within" rule, the choices, and the builders that take a step."""

from __future__ import annotations

import dataclasses
import math
import warnings

import py_trees
import pytest

from bt_arrange import deprecation
from bt_arrange.errors import PlanError
from bt_arrange.plan import (
    ArrangementPlan,
    CorrectMode,
    PartStep,
    PushStrategy,
    Target,
    Tolerance,
    compile_plan,
)
from bt_arrange.trees import Arrangement, arrange_one, arrangement, correction, plan_of, render, render_part, transfer

ROW = [Target("green", 0.50, 0.10), Target("red", 0.50, 0.0), Target("blue", 0.50, -0.10)]
#: Three cubes 52 mm apart along x: each placed beside the one before, among neighbours.
TIGHT = [Target("red", 0.45, 0.0), Target("green", 0.502, 0.0), Target("blue", 0.554, 0.0)]


@pytest.fixture(autouse=True)
def fresh_process(monkeypatch):
    """Each test sees the deprecated forms as a new process does: none has warned yet."""
    monkeypatch.setattr(deprecation, "_warned", set())


def shape(node: py_trees.behaviour.Behaviour, depth: int = 0) -> list[str]:
    lines = [f"{'  ' * depth}{type(node).__name__} {node.name}"]
    for child in node.children:
        lines += shape(child, depth + 1)
    return lines


def test_the_tolerance_owns_the_within_rule():
    tolerance = Tolerance(1.0, yaw_threshold_deg=1.0)
    assert tolerance.within(0.9)
    assert not tolerance.within(0.9, margin_mm=0.1)  # the camera's margin counts against the offset
    assert not tolerance.within(0.5, yaw_error_deg=-1.0)
    assert tolerance.within(0.5, yaw_error_deg=None)  # a yaw not measured does not count against it
    assert Tolerance(1.0).within(0.5, yaw_error_deg=30.0)  # position only
    assert Tolerance(math.inf, 5.0).yaw_only and not Tolerance(math.inf, 5.0).within(9e9, 5.0)


def test_a_tolerance_of_no_threshold_is_refused_in_one_line():
    with pytest.raises(PlanError, match="^threshold 0 mm must be a positive number"):
        Tolerance(0)


def test_the_choices_parse_their_names_and_read_as_them():
    assert PushStrategy.parse("learned", "strategy") is PushStrategy.LEARNED
    assert PushStrategy.LEARNED == "learned" and f"{PushStrategy.LEARNED}" == "learned"
    assert str(CorrectMode.AFTER_ALL) == "after_all"
    with pytest.raises(PlanError, match=r"^strategy='papr' \(did you mean 'paper'\?\): choose one of paper"):
        PushStrategy.parse("papr", "strategy")


def test_a_compiled_plan_has_a_step_per_part_in_placing_order():
    plan = compile_plan(ROW, Tolerance(1.0, 1.0), order=["red", "green", "blue"], strategy="learned")
    assert [step.target.obj for step in plan.steps] == ["red", "green", "blue"]
    assert [t.obj for t in plan.targets] == ["green", "red", "blue"]  # the plan's own order
    assert plan.strategy is PushStrategy.LEARNED and plan.correct is CorrectMode.EACH
    free = plan.steps[0]
    assert not free.among_neighbours and free.release is None and free.push_towards is None and free.margins == 1
    with pytest.raises(dataclasses.FrozenInstanceError):
        plan.max_pushes = 3  # type: ignore[misc]


def test_parts_among_neighbours_get_their_release_sides_and_looks_again():
    plan = compile_plan(TIGHT, Tolerance(1.0, 1.0))
    by_obj = {step.target.obj: step for step in plan.steps}
    looked_again = {n.target.obj for step in plan.steps for n in step.neighbours}
    assert looked_again, "a part placed beside another looks at it again"
    assert all(by_obj[name].rechecked and by_obj[name].margins == 2 for name in looked_again)
    assert any(step.among_neighbours and step.push_towards is not None for step in plan.steps)
    assert all(step.nearest_grasp == (step.among_neighbours or step.rechecked) for step in plan.steps)


def test_the_public_builder_is_compile_then_render():
    built = arrangement(TIGHT, threshold_mm=1.0)
    rendered = render(compile_plan(TIGHT, Tolerance(1.0, 1.0)))
    assert shape(built) == shape(rendered)
    assert plan_of(built) is built.plan and built.plan.targets == rendered.plan.targets
    assert plan_of(py_trees.composites.Sequence("mine", memory=True)) is None


def test_the_builders_take_a_step_and_its_plan():
    plan = compile_plan(ROW, Tolerance(1.0, 1.0), max_pushes=4, strategy="diagonal")
    step = plan.steps[0]
    loop = next(n for n in correction(step, plan).iterate() if n.name.startswith("correct green to 1 mm"))
    assert loop.max_attempts == 4 and loop.tolerance == plan.tolerance
    push = next(n for n in correction(step, plan).iterate() if type(n).__name__ == "Push")
    assert push.strategy is PushStrategy.DIAGONAL
    assert shape(render_part(step, plan))[0] == "Sequence arrange green"
    retry = transfer(step, dataclasses.replace(plan, max_regrasps=1))
    assert retry.num_failures == 2
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the new forms do not warn
        transfer(Target("red", 0.5, 0.0))
        correction(Target("red", 0.5, 0.0))


def test_the_old_forms_still_build_the_same_subtrees_and_warn_once():
    plan = compile_plan([ROW[1]], Tolerance(0.5, 1.0), max_pushes=7)
    step = plan.steps[0]
    with pytest.warns(DeprecationWarning, match=r"correction\(target, threshold_mm.*use correction\(step, plan\)"):
        old = correction(ROW[1], 0.5, 7)
    assert shape(old) == shape(correction(step, plan))
    with pytest.warns(DeprecationWarning, match=r"transfer\(target, max_regrasps"):
        assert shape(transfer(ROW[1], 3)) == shape(transfer(step, plan))
    with pytest.warns(DeprecationWarning, match=r"arrange_one\(target.*use render_part\(step, plan\)"):
        assert shape(arrange_one(ROW[1], 0.5, 7)) == shape(render_part(step, plan))
    with pytest.warns(DeprecationWarning, match=r"arrangement\(targets, threshold_mm, max_pushes, correct\)"):
        assert shape(arrangement(ROW, 1.0, 10, "each")) == shape(arrangement(ROW, 1.0, correct="each"))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # once per process
        correction(ROW[1], 0.5, 7)


def test_an_unknown_option_of_the_builder_is_named():
    with pytest.raises(TypeError, match=r"unexpected keyword argument 'max_push'.*did you mean 'max_pushes'"):
        arrangement(ROW, 1.0, max_push=3)


@pytest.mark.parametrize(
    ("old", "new"),
    [
        ("bt_arrange.stacking", "bt_arrange.plan.stacking"),
        ("bt_arrange.plancheck", "bt_arrange.plan.check"),
        ("bt_arrange.layout", "bt_arrange.plan.layout"),
        ("bt_arrange.footprints", "bt_arrange.plan.footprints"),
        ("bt_arrange.trees.targets", "bt_arrange.plan.targets"),
        ("bt_arrange.puzzle.targets", "bt_arrange.plan.puzzle_targets"),
    ],
)
def test_a_moved_module_imports_by_its_old_path_with_one_warning(old, new, monkeypatch):
    import importlib
    import sys

    monkeypatch.delitem(sys.modules, old, raising=False)
    with pytest.warns(
        DeprecationWarning, match=rf"^{old} is deprecated and will be removed in the next release; use {new}$"
    ):
        moved = importlib.import_module(old)
    assert moved is importlib.import_module(new)


def test_a_hand_built_root_carries_a_plan_of_its_targets():
    root = Arrangement("mine", [], [ROW[0]], 0.8, yaw_threshold_deg=2.0)
    assert isinstance(root.plan, ArrangementPlan) and root.plan.steps == ()
    assert root.targets == [ROW[0]] and root.threshold_mm == 0.8 and root.plan.tolerance == Tolerance(0.8, 2.0)


def test_a_puzzle_piece_joins_the_plan_once():
    plan = ArrangementPlan.of([ROW[0]], Tolerance(1.0))
    joined = plan.joined([ROW[0], ROW[1]])
    assert [t.obj for t in joined.targets] == ["green", "red"] and plan.joined([ROW[0]]) is plan


def test_a_free_step_is_a_part_placed_anywhere_at_its_target():
    step = PartStep.free(ROW[0])
    assert step.layout is None and step.release is None and step.push_towards is None and not step.nearest_grasp
