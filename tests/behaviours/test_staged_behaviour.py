"""The staged behaviours' base class: set-up against a context, the blackboard keys, the stages."""

from __future__ import annotations

from collections.abc import Callable

import py_trees
import pytest

from bt_arrange.behaviours import Detect, Inspect, MoveHome, Pick, Place, Push, Stage, StagedBehaviour, keys
from bt_arrange.errors import BtArrangeError


def test_blackboard_keys_are_one_namespace_per_object() -> None:
    assert keys.key("red", keys.POSE) == "/red/pose"
    assert [keys.key("a", field) for field in (keys.TARGET, keys.OFFSET_MM, keys.OFFSET_XY_MM)] == [
        "/a/target",
        "/a/offset_mm",
        "/a/offset_xy_mm",
    ]
    assert [keys.key("a", field) for field in (keys.PLACED_OFFSET_MM, keys.CORRECTIONS, keys.PUSH_AXIS)] == [
        "/a/placed_offset_mm",
        "/a/corrections",
        "/a/push_axis",
    ]


# -- set-up --------------------------------------------------------------------------------------

BEHAVIOURS: dict[str, Callable[[], StagedBehaviour]] = {
    "Detect": lambda: Detect("detect red", "red"),
    "Inspect": lambda: Inspect("inspect red", "red"),
    "Pick": lambda: Pick("pick red", "red"),
    "Place": lambda: Place("place red", "red"),
    "Push": lambda: Push("push red", "red"),
    "MoveHome": lambda: MoveHome("park"),
}


@pytest.mark.parametrize("make", BEHAVIOURS.values(), ids=BEHAVIOURS.keys())
def test_setup_without_a_context_raises_a_clear_error(make: Callable[[], StagedBehaviour]) -> None:
    behaviour = make()
    with pytest.raises(BtArrangeError, match=r"needs setup\(context=Context\(\.\.\.\)\), got NoneType"):
        behaviour.setup()
    assert behaviour.context is None


def test_setup_with_something_else_than_a_context_names_what_it_got() -> None:
    with pytest.raises(BtArrangeError, match=r"'pick red' needs setup\(context=Context\(\.\.\.\)\), got dict"):
        Pick("pick red", "red").setup(context={"arm": None})


def test_ticking_a_behaviour_that_was_not_set_up_raises_a_clear_error() -> None:
    with pytest.raises(BtArrangeError, match=r"'park' was not set up: call tree.setup\(context=\.\.\.\) first"):
        MoveHome("park").tick_once()


def test_a_stage_without_poll_cannot_be_made() -> None:
    class Forgetful(Stage):
        pass

    with pytest.raises(TypeError, match="abstract"):
        Forgetful("forgot to poll")  # type: ignore[abstract]


def test_the_base_class_owns_the_client_and_the_declared_keys() -> None:
    push = Push("push red", "red")
    assert isinstance(push.blackboard, py_trees.blackboard.Client)
    assert set(push.blackboard.read) >= {"/red/pose", "/red/target", "/red/offset_xy_mm", "/red/push_axis"}
    assert set(push.blackboard.write) == {"/red/push_axis", "/red/blocked_towards", "/red/blocked_by"}
    inspect = Inspect("inspect red", "red", after_placing=True)
    assert set(inspect.blackboard.write) == {
        "/red/pose",
        "/red/offset_mm",
        "/red/offset_xy_mm",
        "/red/placed_offset_mm",
        "/red/yaw_error_deg",
        "/red/measured_on",
        "/red/placed_yaw_error_deg",
    }
