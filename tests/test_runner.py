"""The runner's TransitionLog is a py_trees visitor: it logs what a walk over every node would, with node ids."""

from __future__ import annotations

import json

import py_trees
import pytest
from py_trees.common import Status

from bt_arrange.behaviours import Detect, Inspect, Pick
from bt_arrange.runner import Runner, Transition, TransitionLog
from bt_arrange.testing import FakeClock, make_context, part
from bt_arrange.trees import Target, arrangement

RED, GREEN = Target("red", 0.50, 0.0), Target("green", 0.50, -0.15)


def run_beside_a_full_walk(root, context) -> tuple[list[list[tuple]], list[list[tuple]], Runner]:
    """Run ``root``; after every tick compare the visitor's changes with a full walk's (an ``observe``)."""
    full = TransitionLog()
    by_visitor: list[list[tuple]] = []
    by_walk: list[list[tuple]] = []
    this_tick: list[Transition] = []
    clock = context.robot.clock

    def after_tick(tree_root) -> None:
        by_visitor.append(sorted((t.node_id, t.old, t.new) for t in this_tick))
        by_walk.append(sorted((t.node_id, t.old, t.new) for t in full.observe(tree_root, clock.now())))
        this_tick.clear()

    runner = Runner(
        root,
        context,
        lambda: clock.advance(context.robot.arm.control_period_s),
        time_limit_s=600.0,
        on_transition=this_tick.append,
        on_tick=after_tick,
    )
    result = runner.run()
    assert result.status in (Status.SUCCESS, Status.FAILURE)
    return by_visitor, by_walk, runner


@pytest.mark.parametrize("correct", ["each", "after_all"])
@pytest.mark.parametrize("held_width_m", [None, 0.05])
def test_the_visitor_logs_every_change_a_full_walk_sees(correct: str, held_width_m: float | None) -> None:
    # None: every pick closes on nothing (retries, resets, FailureIsSuccess). 0.05: red is held, placed,
    # inspected and pushed (the fake camera still sees it where it lay). Green is not there.
    context = make_context(clock=FakeClock(), parts=[part("red", 0.60, -0.12)], object_width_m=held_width_m)
    root = arrangement([RED, GREEN], correct=correct, max_regrasps=1, max_pushes=2)
    by_visitor, by_walk, runner = run_beside_a_full_walk(root, context)
    assert sum(len(tick) for tick in by_walk) > 30, "the run changed many statuses"
    assert any(new == Status.INVALID.value for tick in by_walk for _, _, new in tick), "nodes were reset"
    assert by_visitor == by_walk


def test_a_transition_names_its_node_by_id_and_its_object() -> None:
    context = make_context(clock=FakeClock(), parts=[part("red", 0.60, -0.12)], object_width_m=None)
    root = arrangement([RED], max_regrasps=0)
    _, _, runner = run_beside_a_full_walk(root, context)
    transitions = runner.log.transitions
    picks = [t for t in transitions if isinstance(runner.node(t), Pick)]
    assert picks and all(t.obj == "red" and runner.node(t).obj == "red" for t in picks)
    assert {t.kind for t in picks} == {"Pick"}
    detects = [t for t in transitions if isinstance(runner.node(t), Detect) and not isinstance(runner.node(t), Inspect)]
    assert detects and detects[0].new == Status.SUCCESS.value, "parked: the first look succeeds at once"
    root_changes = [t for t in transitions if runner.node(t) is root]
    assert root_changes and root_changes[0].obj is None


def test_the_json_lines_keep_the_old_fields_and_add_the_node(tmp_path) -> None:
    context = make_context(clock=FakeClock(), parts=[], object_width_m=None)
    log = TransitionLog(tmp_path / "log.jsonl")
    clock = context.robot.clock
    Runner(arrangement([RED], max_regrasps=0), context, lambda: clock.advance(0.008), log=log).run()
    lines = [json.loads(line) for line in (tmp_path / "log.jsonl").read_text().splitlines()]
    assert lines and len(lines) == len(log.transitions)
    for line in lines:
        assert {"time_s", "behaviour", "kind", "old", "new", "feedback"} <= set(line)
        assert log.nodes[line["node_id"]].name == line["behaviour"]
    detect = next(line for line in lines if line["behaviour"] == "detect red")
    assert (detect["kind"], detect["obj"]) == ("Detect", "red")


class _Counting(py_trees.behaviour.Behaviour):
    """Succeeds on its second tick and states, as data, how many ticks it took."""

    def __init__(self) -> None:
        super().__init__("count")
        self.facts: dict[str, object] = {}
        self.ticks = 0

    def update(self) -> Status:
        self.ticks += 1
        self.facts = {"ticks": self.ticks, "pushed_mm": 1.25}
        return Status.SUCCESS if self.ticks >= 2 else Status.RUNNING


def test_a_transition_carries_the_facts_its_node_states(tmp_path) -> None:
    counting, silent = _Counting(), py_trees.behaviours.Success("silent")
    root = py_trees.composites.Sequence("both", memory=True, children=[counting, silent])
    log = TransitionLog(tmp_path / "log.jsonl")
    for time_s in (0.0, 0.1):
        root.tick_once()
        log.observe(root, time_s)
    log.close()
    by_node = {(t.behaviour, t.new): t for t in log.transitions}
    assert by_node[("count", "RUNNING")].facts == {"ticks": 1, "pushed_mm": 1.25}
    assert by_node[("count", "SUCCESS")].facts == {"ticks": 2, "pushed_mm": 1.25}  # a copy at each change
    assert by_node[("silent", "SUCCESS")].facts == {} and by_node[("both", "SUCCESS")].facts == {}
    lines = {(line["behaviour"], line["new"]): line for line in map(json.loads, (tmp_path / "log.jsonl").open())}
    assert lines[("count", "SUCCESS")]["facts"] == {"ticks": 2, "pushed_mm": 1.25}
    # A node that states nothing logs the same line as before facts existed.
    assert "facts" not in lines[("silent", "SUCCESS")] and "facts" not in lines[("both", "SUCCESS")]
    assert isinstance(hash(by_node[("count", "SUCCESS")]), int)  # still a hashable, frozen value


class _Scripted(py_trees.behaviour.Behaviour):
    """A leaf that returns the statuses of its script, one a tick (the last one after that)."""

    def __init__(self, name: str, script: list[Status]) -> None:
        super().__init__(name)
        self.script = list(script)
        self.ticks = 0

    def update(self) -> Status:
        status = self.script[min(self.ticks, len(self.script) - 1)]
        self.ticks += 1
        self.feedback_message = f"{self.name} tick {self.ticks}"
        return status


def _passing_tree() -> py_trees.behaviour.Behaviour:
    """Memory sequences and selectors, FailureIsSuccess and Retry above leaves that run, fail, succeed."""
    R, S, F = Status.RUNNING, Status.SUCCESS, Status.FAILURE
    first = py_trees.composites.Sequence(
        "first", True, [_Scripted("a", [R, R, S]), _Scripted("b", [R, R, R, F]), _Scripted("c", [S])]
    )
    retried = py_trees.decorators.Retry("retry", first, 2)
    choice = py_trees.composites.Selector("choice", True, [_Scripted("d", [R, F]), _Scripted("e", [R, R, R, R, S])])
    guarded = py_trees.decorators.EternalGuard("guard", _Scripted("f", [R, R, S]), condition=lambda: True)
    body = py_trees.composites.Sequence("body", True, [retried, choice, guarded])
    return py_trees.composites.Sequence("root", True, [py_trees.decorators.FailureIsSuccess("lenient", body)])


def test_a_resumed_tick_leaves_every_node_as_py_trees_tick_does() -> None:
    """Tick by tick: the same nodes yielded in the same order, every node's status and feedback the same."""
    from bt_arrange.runner import resumed_tick

    plain, resumed = _passing_tree(), _passing_tree()
    for _ in range(40):
        expected = [node.name for node in plain.tick()]
        got = [node.name for node in resumed_tick(resumed)]
        assert got == expected
        assert [(n.name, n.status, n.feedback_message) for n in resumed.iterate()] == [
            (n.name, n.status, n.feedback_message) for n in plain.iterate()
        ]
        if plain.status != Status.RUNNING:
            break
    assert plain.status == resumed.status != Status.RUNNING
