"""A correction among neighbours that releases its part again for a blocked push: never left worse than its best.

The child stands for Push (writing ``/red/blocked_towards``: ``"none"`` for a free push, ``"+y"`` for one a
neighbour blocks, then released again past the place) and Inspect (the next offset of a script).
"""

from __future__ import annotations

import math
from collections.abc import Iterable

import py_trees
from py_trees.common import Access, Status

from bt_arrange.behaviours import keys
from bt_arrange.decorators import RepeatUntilWithin

OFFSET = "/red/offset_mm"
BLOCKED = "/red/blocked_towards"
RELEASE_AGAIN = "/red/release_again"
OFFSET_XY = "/red/offset_xy_mm"
BLOCKED_BY = "/red/blocked_by"
FREE = keys.NOT_BLOCKED


class Correction(py_trees.behaviour.Behaviour):
    """One correction a tick: a push (blocked: released again past the place, if allowed), then the offset after it.

    The script gives, per correction, the push's verdict (``"none"``: free, ``"+y"``: blocked) and the offset
    (target frame, mm) measured after it.
    """

    def __init__(self, script: Iterable[tuple[str, tuple[float, float]]]) -> None:
        super().__init__(name="push and inspect red")
        self.script = list(script)
        self.allowed_seen: list[str] = []
        self.blackboard = self.attach_blackboard_client(name="correction")
        for key in (OFFSET, OFFSET_XY, BLOCKED, BLOCKED_BY):
            self.blackboard.register_key(key, access=Access.WRITE)
        self.blackboard.register_key(RELEASE_AGAIN, access=Access.READ)

    def update(self) -> Status:
        allowed = self.blackboard.get(RELEASE_AGAIN)
        self.blackboard.set(BLOCKED_BY, "blue" if self.script[0][0] != FREE else FREE, overwrite=True)
        self.allowed_seen.append(allowed)
        blocked, offset_xy = self.script.pop(0)
        self.blackboard.set(BLOCKED, blocked, overwrite=True)
        if blocked != keys.NOT_BLOCKED and allowed != keys.ALLOWED:
            return Status.FAILURE
        write_offset(offset_xy)
        return Status.SUCCESS


def write_offset(offset_xy: tuple[float, float]) -> None:
    client = py_trees.blackboard.Client(name="test")
    for key in (OFFSET, OFFSET_XY):
        client.register_key(key, access=Access.WRITE)
    client.set(OFFSET_XY, offset_xy, overwrite=True)
    client.set(OFFSET, math.hypot(*offset_xy), overwrite=True)


def loop(
    child: py_trees.behaviour.Behaviour, placed_xy_mm: tuple[float, float], max_attempts: int = 10
) -> RepeatUntilWithin:
    write_offset(placed_xy_mm)
    return RepeatUntilWithin(
        name="correct red",
        child=child,
        offset_key=OFFSET,
        threshold_mm=0.5,
        max_attempts=max_attempts,
        obj="red",
        release_again=True,
    )


def run(node: RepeatUntilWithin, ticks: int = 30) -> Status:
    node.setup()
    for _ in range(ticks):
        node.tick_once()
        if node.status != Status.RUNNING:
            break
    return node.status


def test_a_release_again_that_brings_the_part_closer_goes_on() -> None:
    # Blocked towards +y: released 4 mm past its place (and 2.5 mm off in x), pushed back, then a free push in x.
    child = Correction([("+y", (2.5, -4.0)), (FREE, (2.5, 0.6)), (FREE, (0.1, 0.6)), (FREE, (0.1, -0.2))])
    node = loop(child, placed_xy_mm=(0.0, 2.0))
    assert run(node) == Status.SUCCESS
    assert node.attempts == 4


def test_released_again_for_a_push_that_came_back_as_short_the_part_is_not_released_a_third_time() -> None:
    # The cycle: blocked towards +y at 2.0 mm, released and pushed back 0.7 mm short, released again and
    # pushed back 0.68 mm short: the third time would only cycle, so the loop ends naming the push.
    script = [
        ("+y", (2.5, -4.0)),
        (FREE, (2.5, 0.7)),
        (FREE, (0.1, 0.7)),
        ("+y", (-2.0, -4.1)),
        (FREE, (-2.0, 0.68)),
        (FREE, (0.05, 0.68)),
        ("+y", (0.0, 0.0)),
    ]
    child = Correction(script)
    node = loop(child, placed_xy_mm=(0.0, 2.0))
    assert run(node) == Status.FAILURE
    assert child.allowed_seen[3] == keys.ALLOWED, "0.70 mm is shorter than the 2.00 mm it was first released for"
    assert child.allowed_seen[6].startswith("released past its place for a push of 0.70 mm towards +y")
    assert node.attempts == 6
    assert "its push towards +y is blocked at 0.68 mm" in node.feedback_message
    assert "it was not released again: released past its place" in node.feedback_message
    assert node.blackboard.get(OFFSET) < 2.0, "never left further off than it was placed"


def test_no_release_again_without_a_correction_left_to_push_the_part_back() -> None:
    # Nine free pushes that get nowhere, then a blocked one: releasing it now would end the loop 4 mm off.
    child = Correction([(FREE, (0.0, 0.9))] * 9 + [("+y", (0.0, -4.0))])
    node = loop(child, placed_xy_mm=(0.0, 1.0))
    assert run(node) == Status.FAILURE
    assert child.allowed_seen[:9] == [keys.ALLOWED] * 9
    assert child.allowed_seen[9] == "no correction would be left to push it back"
    assert node.blackboard.get(OFFSET) == 0.9
    assert "no correction would be left to push it back" in node.feedback_message


def test_corrections_that_run_out_name_the_push_a_neighbour_blocked() -> None:
    child = Correction([("+y", (0.0, -4.0)), (FREE, (0.0, 0.7)), (FREE, (0.0, 0.7))])
    node = loop(child, placed_xy_mm=(0.0, 2.0), max_attempts=3)
    assert run(node) == Status.FAILURE
    assert node.feedback_message == (
        "offset still 0.70 mm >= 0.50 mm after 3 correction(s); its push towards +y was blocked on its -y side by blue"
    )


def test_the_release_again_key_is_written_only_where_asked() -> None:
    node = RepeatUntilWithin(
        name="correct red",
        child=py_trees.behaviours.Success(name="s"),
        offset_key=OFFSET,
        threshold_mm=0.5,
        max_attempts=3,
        obj="red",
    )
    assert node.release_again_key is None
    assert RELEASE_AGAIN not in node.blackboard.write
