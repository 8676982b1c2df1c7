"""Accumulating wall-clock timers for benchmarks: where a run's time goes.

Nothing in the framework calls these: a benchmark wraps the methods it wants to measure
(``timers.wrap_method(cell, "step", "physics")``), so an uninstrumented run pays nothing. A
section nested in another (a render inside a tree tick) counts for the inner section only: each
section's figure is exclusive, and the figures add up to the time spent inside any section::

    timers = SectionTimers()
    timers.wrap_method(cell, "step", "physics")
    timers.wrap_method(cell.camera, "capture", "render")
    ...run...
    timers.seconds  # {"physics": 12.3, "render": 0.4, ...}
"""

from __future__ import annotations

import functools
import time
from collections.abc import Callable
from typing import Any, TypeVar

F = TypeVar("F", bound=Callable[..., Any])


class SectionTimers:
    """Exclusive wall time and call count per named section, with nesting.

    ``clock`` is what is counted: ``time.perf_counter`` (wall time, None: the default) or, say,
    ``time.process_time`` (the process's CPU time, which other jobs on a shared machine do not take).
    """

    def __init__(self, clock: Callable[[], float] | None = None) -> None:
        self._clock = clock
        self.seconds: dict[str, float] = {}
        self.calls: dict[str, int] = {}
        # The open sections, innermost last: [name, time it (re)started counting].
        self._stack: list[list[Any]] = []

    def wrap(self, section: str, function: F) -> F:
        """``function`` with its time (minus nested sections) added to ``section``.

        The wrapper's own work is kept short (the clock, the stack and the tallies bound once, no
        method calls): what it costs outside its two clock readings lands in no section, and a
        benchmark's wall time includes it.
        """
        clock = self._clock if self._clock is not None else time.perf_counter
        stack, seconds, calls = self._stack, self.seconds, self.calls

        @functools.wraps(function)
        def timed(*args: Any, **kwargs: Any) -> Any:
            now = clock()
            if stack:
                outer = stack[-1]
                seconds[outer[0]] = seconds.get(outer[0], 0.0) + (now - outer[1])
            stack.append([section, now])
            calls[section] = calls.get(section, 0) + 1
            try:
                return function(*args, **kwargs)
            finally:
                end = clock()
                name, since = stack.pop()
                seconds[name] = seconds.get(name, 0.0) + (end - since)
                if stack:
                    stack[-1][1] = end

        return timed  # type: ignore[return-value]

    def wrap_method(self, owner: object, attribute: str, section: str) -> None:
        """Replace ``owner.attribute`` (a method) on that object only by its timed version."""
        setattr(owner, attribute, self.wrap(section, getattr(owner, attribute)))

    def total_s(self) -> float:
        """Seconds spent inside any section."""
        return sum(self.seconds.values())
