"""Run the world at a chosen multiple of real time (``bt-arrange run --pace F``), so a person can watch it.

The runner steps the world as fast as it goes; a ``Pacer`` is a tick hook that sleeps after a tick
until the wall time since the first tick is the world time since then divided by the factor. A
world slower than the pace is not held back further (the pacer never sleeps a negative time, and
does not catch up later by running faster than the world goes).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any


class Pacer:
    """A tick hook: ``pacer.tick(root)`` after every tick keeps world time at ``factor`` times wall time.

    ``world_s`` reads the world's clock (e.g. ``session.elapsed_s``); ``wall`` and ``sleep`` are
    ``time.monotonic`` and ``time.sleep`` unless a test hands in others.
    """

    def __init__(
        self,
        factor: float,
        world_s: Callable[[], float],
        *,
        wall: Callable[[], float] = time.monotonic,
        sleep: Callable[[float], None] = time.sleep,
    ) -> None:
        if (
            isinstance(factor, bool)
            or not isinstance(factor, (int, float))
            or not (math.isfinite(factor) and factor > 0)
        ):
            raise ValueError(f"pace {factor!r} must be a positive number (1 is real time)")
        self.factor = float(factor)
        self.world_s = world_s
        self.wall = wall
        self.sleep = sleep
        self._start: tuple[float, float] | None = None
        #: Wall time slept so far [s].
        self.slept_s = 0.0

    def tick(self, root: Any = None) -> None:
        """Sleep until the wall clock has caught up with the world at the pace."""
        world, wall = self.world_s(), self.wall()
        if self._start is None:
            self._start = (world, wall)
            return
        ahead_s = self._start[1] + (world - self._start[0]) / self.factor - wall
        if ahead_s > 0:
            self.sleep(ahead_s)
            self.slept_s += ahead_s
