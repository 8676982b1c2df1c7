"""The benchmark timers: exclusive time per section, nested sections counted once."""

from __future__ import annotations

import pytest

from bt_arrange import timing
from bt_arrange.timing import SectionTimers


class FakePerfCounter:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def test_a_nested_section_counts_for_itself_only(monkeypatch: pytest.MonkeyPatch) -> None:
    clock = FakePerfCounter()
    monkeypatch.setattr(timing.time, "perf_counter", clock)
    timers = SectionTimers()

    def render() -> str:
        clock.now += 2.0
        return "frame"

    timed_render = timers.wrap("render", render)

    def tick() -> str:
        clock.now += 1.0
        frame = timed_render()
        clock.now += 0.5
        return frame

    assert timers.wrap("tree", tick)() == "frame"
    assert timers.seconds == pytest.approx({"tree": 1.5, "render": 2.0})
    assert timers.calls == {"tree": 1, "render": 1}
    assert timers.total_s() == pytest.approx(3.5)


def test_wrap_method_times_one_object_and_keeps_its_result() -> None:
    class Camera:
        def capture(self, value: int) -> int:
            return value * 2

    camera, other = Camera(), Camera()
    timers = SectionTimers()
    timers.wrap_method(camera, "capture", "render")
    assert camera.capture(3) == 6 and other.capture(4) == 8
    assert timers.calls == {"render": 1}


def test_timers_count_the_clock_they_are_given() -> None:
    ticks = iter([0.0, 5.0, 5.5, 9.0])
    timers = SectionTimers(clock=lambda: next(ticks))

    def inner() -> None:
        return None

    timed_inner = timers.wrap("inner", inner)

    def outer() -> None:
        timed_inner()

    timers.wrap("outer", outer)()
    # outer from 0 to 5 and from 5.5 to 9 (8.5 s), inner from 5 to 5.5 (0.5 s), exclusive.
    assert timers.seconds == {"outer": 8.5, "inner": 0.5}
