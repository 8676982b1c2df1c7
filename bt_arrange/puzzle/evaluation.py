"""A puzzle's ground truth, for the report only: which part of the world each piece is, where it belongs.

The tree names the pieces ``NAME 1`` ... ``NAME N`` as its camera found them; the world knows its
parts by its own names and knows where each belongs (its home, by the simulator's break). When the
survey succeeds, each named piece is matched to the world's part nearest where the camera saw it;
at the report, the whole's symmetry (a rectangle is the same slab turned by half a turn; a square
by a quarter) is chosen once per puzzle, the one that brings the solved targets nearest the true
homes: the pieces alone cannot tell those apart, so neither is an error. Nothing here reaches the tree.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from typing import Any

from bt_arrange.puzzle.spec import PuzzleSpec


def _turned(
    home: tuple[float, float, float], centre: tuple[float, float], turn_rad: float
) -> tuple[float, float, float]:
    c, s = math.cos(turn_rad), math.sin(turn_rad)
    dx, dy = home[0] - centre[0], home[1] - centre[1]
    yaw = home[2] + turn_rad
    return centre[0] + c * dx - s * dy, centre[1] + s * dx + c * dy, math.atan2(math.sin(yaw), math.cos(yaw))


class PuzzleTruth:
    """The ground truth of a run's puzzles: empty (and inert) without puzzles or without a world that knows homes."""

    def __init__(self, puzzles: Sequence[PuzzleSpec], world_truth: Any) -> None:
        self.puzzles = {spec.name: spec for spec in puzzles}
        self._truth = world_truth
        #: The world's part of each named piece, matched at the survey.
        self.parts: dict[str, str] = {}
        self._turns: dict[str, float] = {}

    def _home(self, part: str) -> tuple[str, tuple[float, float, float]] | None:
        finder = getattr(self._truth, "home_pose", None)
        return finder(part) if finder is not None else None

    def surveyed(self, spec: PuzzleSpec, pieces: Sequence[Any]) -> None:
        """Match each surveyed piece (name, centre) to the world's part of the puzzle nearest it."""
        if self._truth is None:
            return
        candidates = [n for n in self._truth.part_names() if (self._home(n) or ("",))[0] == spec.name]
        for piece in pieces:
            if not candidates:
                return

            def distance(name: str, at: tuple[float, float] = piece.centre_m) -> float:
                x, y, _ = self._truth.planar_pose(name)
                return math.hypot(x - at[0], y - at[1])

            nearest = min(candidates, key=distance)
            self.parts[piece.name] = nearest
            candidates.remove(nearest)

    def puzzle_of(self, name: str) -> PuzzleSpec | None:
        """The puzzle a named piece belongs to, or None."""
        head, _, number = name.rpartition(" ")
        return self.puzzles.get(head) if number.isdigit() else None

    def home(self, target: Any, targets: Sequence[Any]) -> tuple[float, float, float] | None:
        """Where ``target``'s piece truly belongs, under its whole's chosen symmetry; None when not a matched piece."""
        spec = self.puzzle_of(target.obj)
        part = self.parts.get(target.obj)
        found = self._home(part) if part is not None else None
        if spec is None or found is None:
            return None
        if spec.name not in self._turns:
            self._turns[spec.name] = self._choose_turn(spec, targets)
        return _turned(found[1], (spec.x_m, spec.y_m), self._turns[spec.name])

    def home_target(self, target: Any, targets: Sequence[Any]) -> Any:
        """``target`` moved to its piece's true home (for the truth offsets), or ``target`` as it is."""
        home = self.home(target, targets)
        if home is None:
            return target
        return replace(target, x_m=home[0], y_m=home[1], yaw_rad=home[2])

    def _choose_turn(self, spec: PuzzleSpec, targets: Sequence[Any]) -> float:
        solved = [t for t in targets if self.puzzle_of(t.obj) is spec and t.obj in self.parts]

        def spread(turn: float) -> float:
            total = 0.0
            for t in solved:
                found = self._home(self.parts[t.obj])
                if found is not None:
                    x, y, _ = _turned(found[1], (spec.x_m, spec.y_m), turn)
                    total += math.hypot(x - t.x_m, y - t.y_m)
            return total

        return min(spec.symmetry_turns_rad, key=spread)


__all__ = ["PuzzleTruth"]
