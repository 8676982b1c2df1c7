"""The world a session runs against: a backend's robot, clock and parts, and its ground truth where it has one.

A backend supplies a ``World`` (simulated, or a real cell); ``bt_arrange.session.Session`` runs a
tree against it the same way for every backend. ``GroundTruth`` is for evaluation only, never for
the tree.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Protocol, runtime_checkable

from bt_arrange.perception import ColourTable
from bt_arrange.robot import CameraFrame, Clock, Robot


@runtime_checkable
class GroundTruth(Protocol):
    """What a world knows of its parts beyond its sensors: for evaluation only, never for the tree."""

    def part_names(self) -> Sequence[str]:
        """The names of the parts present in the world."""
        ...

    def planar_pose(self, name: str) -> tuple[float, float, float]:
        """The true planar pose of part ``name``: ``(x_m, y_m, yaw_rad)`` in the world frame."""
        ...


@runtime_checkable
class World(Protocol):
    """One work cell a tree runs in: simulated, or real.

    The session calls ``place`` and ``settle`` once, before the tree starts, then ``step`` between
    ticks; ``capture_image`` only when recording; ``close`` at the end.
    """

    @property
    def robot(self) -> Robot:
        """The arm, gripper, camera and clock the behaviours use (``Context.create``)."""
        ...

    @property
    def clock(self) -> Clock:
        """World time, in seconds (the robot's clock)."""
        ...

    @property
    def truth(self) -> GroundTruth | None:
        """Ground truth for the report (evaluation only), or None: the report is then camera only."""
        ...

    def place(self, starts: Sequence[Any], colours: ColourTable) -> None:
        """Put the parts where they start, painted with ``colours`` (a real cell: check that they are there).

        A start is ``ObjectStart``-like: colour, x_m, y_m, yaw_rad, name and optionally object_type.
        """
        ...

    def settle(self, seconds: float) -> None:
        """Let world time pass with the robot still until the parts rest, at most ``seconds`` (or just that long)."""
        ...

    def step(self) -> None:
        """Advance the world by one control period of the arm."""
        ...

    def capture_image(self) -> CameraFrame:
        """A frame of the top camera for the recorded images (its ``rgb`` is saved)."""
        ...

    def close(self) -> None:
        """Release the world (disconnect the simulator, stop the robot)."""
        ...


__all__ = ["GroundTruth", "World"]
