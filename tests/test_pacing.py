"""``run --pace F``: the pacer sleeps so that world time runs at F times wall time, never catching up by racing."""

import pytest

from bt_arrange.pacing import Pacer


class Clocks:
    def __init__(self) -> None:
        self.world = 0.0
        self.wall = 0.0
        self.slept: list[float] = []

    def sleep(self, seconds: float) -> None:
        self.slept.append(seconds)
        self.wall += seconds


def test_the_pacer_holds_the_world_at_the_pace():
    clocks = Clocks()
    pacer = Pacer(2.0, lambda: clocks.world, wall=lambda: clocks.wall, sleep=clocks.sleep)
    pacer.tick()  # the first tick sets the start
    for _ in range(10):
        clocks.world += 0.1  # a control period of 0.1 s, computed in no wall time
        pacer.tick()
    assert clocks.wall == pytest.approx(0.5)  # 1 s of world time at twice real time
    assert pacer.slept_s == pytest.approx(0.5)


def test_a_world_slower_than_the_pace_is_not_slept_for():
    clocks = Clocks()
    pacer = Pacer(1.0, lambda: clocks.world, wall=lambda: clocks.wall, sleep=clocks.sleep)
    pacer.tick()
    clocks.world, clocks.wall = 0.1, 0.3  # slower than real time
    pacer.tick()
    assert clocks.slept == []


@pytest.mark.parametrize("factor", [0, -1, float("inf"), float("nan"), True, "2"])
def test_a_pace_must_be_a_positive_number(factor):
    with pytest.raises(ValueError, match="positive number"):
        Pacer(factor, lambda: 0.0)
