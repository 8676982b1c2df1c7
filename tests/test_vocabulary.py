"""One vocabulary: nodes named by their BehaviorTree.CPP type everywhere, and no ``-0.00`` in what people read."""

from __future__ import annotations

import re
from pathlib import Path

import py_trees
import pytest
from py_trees.common import Status

from bt_arrange import xmltree
from bt_arrange.decorators import RepeatUntilWithin
from bt_arrange.numbers import fixed
from bt_arrange.replay import ReplayRecorder, format_value
from bt_arrange.runner import TransitionLog

PACKAGE = Path(__file__).resolve().parents[1] / "bt_arrange"


@pytest.mark.parametrize(
    ("value", "digits", "sign", "text"),
    [
        (-0.0001, 2, False, "0.00"),
        (-0.0001, 2, True, "+0.00"),
        (-0.0, 4, False, "0.0000"),
        (-0.4, 0, True, "+0"),
        (-0.6, 0, True, "-1"),
        (-1.234, 1, False, "-1.2"),
        (1.234, 2, True, "+1.23"),
        (-10.001, 2, False, "-10.00"),
    ],
)
def test_fixed_never_writes_a_negative_zero(value, digits, sign, text):
    assert fixed(value, digits, sign=sign) == text


def test_the_replay_page_writes_no_negative_zero():
    assert format_value(-0.00001) == "0.0000"
    assert format_value((-0.00001, -0.5)) == "(0.0000, -0.5000)"


def test_no_signed_float_format_is_left_in_what_the_tree_says():
    """Signed figures in feedback go through ``fixed`` (a ``{x:+.2f}`` writes ``-0.00``)."""
    for path in [*(PACKAGE / "behaviours").glob("*.py"), PACKAGE / "decorators.py", *(PACKAGE / "trees").glob("*.py")]:
        assert not re.search(r"\{[^}]*:\+\.\d+f\}", path.read_text()), path


def test_transitions_and_the_replay_page_name_nodes_by_their_bt_cpp_type():
    child = py_trees.behaviours.Failure("fails")
    root = py_trees.decorators.FailureIsSuccess("then the next", child=child)
    log = TransitionLog()
    root.tick_once()
    changes = log.observe(root, 0.0)
    assert {(t.behaviour, t.kind) for t in changes} == {("then the next", "ForceSuccess"), ("fails", "AlwaysFailure")}
    assert root.status is Status.SUCCESS
    page = ReplayRecorder(root)
    assert [node["kind"] for node in page.nodes] == [
        "ForceSuccess (py_trees FailureIsSuccess)",
        "AlwaysFailure (py_trees Failure)",
    ]


def test_tag_of_and_type_label():
    leaf = py_trees.behaviours.Success("s")
    assert xmltree.tag_of(py_trees.composites.Sequence("r", memory=False, children=[])) == "ReactiveSequence"
    assert xmltree.tag_of(py_trees.decorators.Retry("r", child=leaf, num_failures=2)) == "RetryUntilSuccessful"
    assert xmltree.type_label(py_trees.decorators.Retry("r", child=leaf, num_failures=2)) == (
        "RetryUntilSuccessful (py_trees Retry)"
    )
    assert (
        xmltree.type_label(RepeatUntilWithin("c", leaf, offset_key="/red/offset_mm", threshold_mm=1.0, max_attempts=3))
        == "RepeatUntilWithin"
    )

    class Mine(py_trees.behaviour.Behaviour):
        def update(self) -> Status:
            return Status.SUCCESS

    assert xmltree.tag_of(Mine("m")) == xmltree.type_label(Mine("m")) == "Mine"  # not registered: its class
