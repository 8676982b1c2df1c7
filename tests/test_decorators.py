"""RetryUntilThreshold alone: scripted children (StatusQueue) and a hand-filled offset, checked every tick."""

from __future__ import annotations

import math
from collections.abc import Iterable

import py_trees
import pytest
from py_trees.behaviours import StatusQueue
from py_trees.common import Access, Status

from bt_arrange.decorators import RetryUntilThreshold
from bt_arrange.errors import PlanError

OFFSET = "/red/offset_mm"
CORRECTIONS = "/red/corrections"


class WriteOffset(py_trees.behaviour.Behaviour):
    """Stands for Inspect: writes the next offset of a script, one per run."""

    def __init__(self, offsets_mm: Iterable[float | None]) -> None:
        super().__init__(name="inspect")
        self.offsets_mm = list(offsets_mm)
        self.blackboard = self.attach_blackboard_client(name="inspect")
        self.blackboard.register_key(OFFSET, access=Access.WRITE)

    def update(self) -> Status:
        offset = self.offsets_mm.pop(0)
        self.blackboard.set(OFFSET, offset, overwrite=True)
        self.feedback_message = f"offset {offset} mm"
        return Status.SUCCESS


class Explained(StatusQueue):
    """A StatusQueue that says why it fails."""

    def __init__(self, name: str, queue: list[Status], reason: str) -> None:
        super().__init__(name=name, queue=queue, eventually=None)
        self.reason = reason

    def update(self) -> Status:
        status = super().update()
        self.feedback_message = self.reason if status == Status.FAILURE else "pushing"
        return status


def write_offset(offset_mm: float | None) -> None:
    client = py_trees.blackboard.Client(name="test")
    client.register_key(OFFSET, access=Access.WRITE)
    client.set(OFFSET, offset_mm, overwrite=True)


def corrections() -> int:
    return py_trees.blackboard.Blackboard.get(CORRECTIONS)


def push_then_inspect(offsets_mm: Iterable[float | None]) -> tuple[py_trees.composites.Sequence, StatusQueue]:
    """A correction that takes two ticks (push RUNNING, then SUCCESS) and then writes the next offset."""
    push = StatusQueue(name="push", queue=[Status.RUNNING, Status.SUCCESS], eventually=None)
    child = py_trees.composites.Sequence(name="push and inspect", memory=True, children=[push, WriteOffset(offsets_mm)])
    return child, push


def retry(
    child: py_trees.behaviour.Behaviour, max_attempts: int = 10, threshold_mm: float = 1.0
) -> RetryUntilThreshold:
    return RetryUntilThreshold(
        name="correct red",
        child=child,
        offset_key=OFFSET,
        threshold_mm=threshold_mm,
        max_attempts=max_attempts,
        corrections_key=CORRECTIONS,
    )


def tick(behaviour: py_trees.behaviour.Behaviour) -> tuple[Status, str, int]:
    behaviour.tick_once()
    return behaviour.status, behaviour.feedback_message, corrections()


def test_an_offset_already_under_the_threshold_succeeds_at_once_without_ticking_the_child() -> None:
    write_offset(0.4)
    push = StatusQueue(name="push", queue=[Status.SUCCESS], eventually=None)
    decorator = retry(push)
    assert tick(decorator) == (Status.SUCCESS, "offset 0.40 mm < 1.00 mm after 0 correction(s)", 0)
    assert push.status == Status.INVALID
    assert push.current_queue == [Status.SUCCESS], "the child was never ticked"


def test_a_converging_correction_succeeds_after_n_corrections_counted_on_the_blackboard() -> None:
    write_offset(5.0)
    child, push = push_then_inspect([3.0, 1.5, 0.6])
    decorator = retry(child, max_attempts=10)
    expected = [
        (Status.RUNNING, "correcting (0 done), offset 5.00 mm", 0),
        (Status.RUNNING, "1 correction(s), offset 3.00 mm", 1),
        (Status.RUNNING, "correcting (1 done), offset 3.00 mm", 1),
        (Status.RUNNING, "2 correction(s), offset 1.50 mm", 2),
        (Status.RUNNING, "correcting (2 done), offset 1.50 mm", 2),
        (Status.RUNNING, "3 correction(s), offset 0.60 mm", 3),
        (Status.SUCCESS, "offset 0.60 mm < 1.00 mm after 3 correction(s)", 3),
    ]
    for number, want in enumerate(expected, start=1):
        assert tick(decorator) == want, f"tick {number}"
    assert decorator.attempts == 3
    assert push.status == Status.SUCCESS, "the last push finished; nothing is left running"


def test_an_offset_equal_to_the_threshold_still_needs_a_correction() -> None:
    write_offset(1.0)
    child, _ = push_then_inspect([0.99])
    decorator = retry(child)
    assert tick(decorator)[0] == Status.RUNNING
    assert tick(decorator)[0] == Status.RUNNING
    assert tick(decorator) == (Status.SUCCESS, "offset 0.99 mm < 1.00 mm after 1 correction(s)", 1)


def test_running_out_of_attempts_fails_with_the_residual_offset() -> None:
    write_offset(4.0)
    child, _ = push_then_inspect([3.0, 2.25, 1.7])
    decorator = retry(child, max_attempts=2)
    statuses = [tick(decorator) for _ in range(4)]
    assert [s[0] for s in statuses] == [Status.RUNNING] * 4
    assert [s[2] for s in statuses] == [0, 1, 1, 2]
    assert tick(decorator) == (Status.FAILURE, "offset still 2.25 mm >= 1.00 mm after 2 correction(s)", 2)
    assert child.children[1].offsets_mm == [1.7], "no third correction was started"


def test_zero_attempts_fails_at_once_when_the_offset_is_too_large() -> None:
    write_offset(1.5)
    push = StatusQueue(name="push", queue=[Status.SUCCESS], eventually=None)
    decorator = retry(push, max_attempts=0)
    assert tick(decorator) == (Status.FAILURE, "offset still 1.50 mm >= 1.00 mm after 0 correction(s)", 0)
    assert push.status == Status.INVALID


def test_a_failing_correction_fails_with_the_childs_reason() -> None:
    write_offset(3.0)
    push = Explained("push", [Status.RUNNING, Status.FAILURE], "lower the fingers: target out of reach")
    decorator = retry(push)
    assert tick(decorator) == (Status.RUNNING, "correcting (0 done), offset 3.00 mm", 0)
    assert tick(decorator) == (Status.FAILURE, "correction failed: lower the fingers: target out of reach", 0)
    assert push.status == Status.FAILURE


@pytest.mark.parametrize("offset", ["missing", None], ids=["no key", "None"])
def test_a_missing_offset_fails_with_a_clear_message(offset) -> None:
    if offset is None:
        write_offset(None)
    push = StatusQueue(name="push", queue=[Status.SUCCESS], eventually=None)
    decorator = retry(push)
    status, feedback, _ = tick(decorator)
    assert status == Status.FAILURE
    assert feedback == "no offset at /red/offset_mm: inspect the object before correcting it"
    assert push.status == Status.INVALID


def test_a_second_run_counts_its_corrections_from_zero() -> None:
    write_offset(4.0)
    child, _ = push_then_inspect([3.0, 2.0, 0.5])
    decorator = retry(child, max_attempts=1)
    assert [tick(decorator)[0] for _ in range(3)] == [Status.RUNNING, Status.RUNNING, Status.FAILURE]
    assert corrections() == 1
    assert tick(decorator) == (Status.RUNNING, "correcting (0 done), offset 3.00 mm", 0)
    assert tick(decorator) == (Status.RUNNING, "1 correction(s), offset 2.00 mm", 1)
    assert tick(decorator) == (Status.FAILURE, "offset still 2.00 mm >= 1.00 mm after 1 correction(s)", 1)


def test_interrupting_the_decorator_interrupts_the_running_correction() -> None:
    write_offset(3.0)
    child, push = push_then_inspect([0.5])
    decorator = retry(child)
    assert tick(decorator)[0] == Status.RUNNING
    assert push.status == Status.RUNNING
    decorator.stop(Status.INVALID)
    assert decorator.status == Status.INVALID
    assert child.status == Status.INVALID and push.status == Status.INVALID


def test_without_a_corrections_key_nothing_is_written() -> None:
    write_offset(0.2)
    decorator = RetryUntilThreshold("correct red", StatusQueue("push", [Status.SUCCESS], None), OFFSET, 1.0, 3)
    decorator.tick_once()
    assert decorator.status == Status.SUCCESS
    assert not py_trees.blackboard.Blackboard.exists(CORRECTIONS)


@pytest.mark.parametrize(
    ("threshold_mm", "max_attempts", "message"),
    [
        (0.0, 3, r"threshold 0.0 mm must be a positive number of millimetres"),
        (-1.0, 3, r"threshold -1.0 mm must be a positive"),
        (math.nan, 3, r"threshold nan mm must be a positive"),
        (1.0, -1, r"max_attempts -1 must be a whole number, 0 or more"),
        (1.0, 2.5, r"max_attempts 2.5 must be a whole number"),
        (1.0, "3", r"max_attempts '3' must be a whole number"),
    ],
    ids=["zero threshold", "negative threshold", "nan threshold", "negative attempts", "fractional", "text"],
)
def test_an_invalid_threshold_or_attempt_count_is_a_plan_error(threshold_mm, max_attempts, message) -> None:
    with pytest.raises(PlanError, match=message):
        RetryUntilThreshold("correct", StatusQueue("push", [Status.SUCCESS], None), OFFSET, threshold_mm, max_attempts)


def test_a_threshold_given_as_text_is_a_plan_error() -> None:
    with pytest.raises(PlanError, match="threshold '1' mm"):
        RetryUntilThreshold("correct", StatusQueue("push", [Status.SUCCESS], None), OFFSET, "1", 3)


@pytest.mark.parametrize(("measured_on", "within"), [("whole face", True), ("free edges", False), (None, True)])
def test_only_a_whole_face_confirms_a_part_within(measured_on: str | None, within: bool) -> None:
    """A look on the free edges of a face merged with a neighbour's steers pushes but never confirms "within"."""
    write_offset(0.2)
    if measured_on is not None:
        client = py_trees.blackboard.Client(name="inspect")
        client.register_key("/red/measured_on", access=Access.WRITE)
        client.set("/red/measured_on", measured_on, overwrite=True)
    push = StatusQueue("push", [Status.SUCCESS], None)
    decorator = RetryUntilThreshold("correct red", push, OFFSET, 1.0, 3)
    decorator.tick_once()
    assert decorator.status == (Status.SUCCESS if within else Status.FAILURE)
    assert push.status == Status.INVALID, "pushing further cannot make the measurement better"
    if not within:
        assert decorator.feedback_message.startswith("unconfirmed: offset 0.20 mm measured on its free edges only")
