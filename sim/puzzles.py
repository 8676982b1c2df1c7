"""A puzzle's scene (issue 32): the slab broken from the run's seed, its pieces scattered turned at random.

Only the simulator knows how the slab broke: the pieces' outlines and homes (where each belongs in
the whole the plan places) travel in ``PieceStart``s to the world, which keeps the homes for the
report's evaluation (``CellWorld.home_pose``). The tree sees the pieces through the camera alone.
The world's part of a piece is named ``NAME fragment K`` (K the break's own numbering), never the
tree's ``NAME k``: which piece the tree calls what is its own business, matched by the session by
where the tree saw each one.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from bt_arrange.errors import PlanError
from bt_arrange.objects import ObjectStart, ObjectType, PartOnTable
from bt_arrange.shapes.fracture import fracture

#: The break's seed is the run's seed mixed with this, so that a puzzle's break and its scatter differ.
BREAK_SALT = 7919


@dataclass(frozen=True)
class PieceStart(ObjectStart):
    """A piece of a puzzle where it starts, and (evaluation only) its home: ``(x_m, y_m, yaw_rad)`` in the whole."""

    home: tuple[float, float, float] = (0.0, 0.0, 0.0)
    puzzle: str = ""


def fragment_name(puzzle: str, index: int) -> str:
    """The world's name of a puzzle's piece: ``NAME fragment K``."""
    return f"{puzzle} fragment {index}"


def puzzle_scene(
    targets: Sequence[Any], puzzles: Sequence[Any], seed: int, *, starts: Sequence[Any] | None = None
) -> list[ObjectStart]:
    """Every part's start: the targets' parts (``starts``, or scattered) and each puzzle's pieces, broken from ``seed``.

    The pieces are scattered clear of the targets, of every whole slab's place and of each other.
    """
    from bt_arrange_sim.scenes import scatter

    colours, kinds, names, homes = [], [], [], []
    for spec in puzzles:
        try:
            pieces = fracture(
                spec.size_m,
                spec.pieces,
                spec.gap_m,
                seed * BREAK_SALT + spec.pieces,
                (spec.x_m, spec.y_m, spec.yaw_rad),
            )
        except PlanError as error:
            raise PlanError(f"[puzzle.{spec.name}]: {error}") from None
        for piece in pieces:
            colours.append(spec.colour)
            kinds.append(ObjectType(fragment_name(spec.name, piece.index), shape=piece.prism))
            names.append(fragment_name(spec.name, piece.index))
            homes.append((spec.name, (piece.x_m, piece.y_m, piece.yaw_rad)))
    wholes = [spot for spec in puzzles for spot in _whole_spots(spec)]
    if starts is not None:
        own = list(starts)
        avoid = [*targets, *wholes, *own]
    else:
        own = (
            scatter(
                [t.colour for t in targets],
                seed,
                avoid=[*targets, *wholes],
                object_types=[t.object_type for t in targets],
                names=[t.name for t in targets],
            )
            if targets
            else []
        )
        avoid = [*targets, *wholes, *own]
    scattered = scatter(colours, seed + 1, avoid=avoid, object_types=kinds, names=names)
    pieces_out = [
        PieceStart(s.colour, s.x_m, s.y_m, s.yaw_rad, s.name, s.object_type, home=home, puzzle=puzzle)
        for s, (puzzle, home) in zip(scattered, homes, strict=True)
    ]
    return [*own, *pieces_out]


def _whole_spots(spec: Any, spacing_m: float = 0.04) -> list[PartOnTable]:
    """Points over a whole slab's place, each kept clear as a cube would be: no piece starts on the slab's place."""
    length, width, _ = spec.size_m
    along = max(2, math.ceil(length / spacing_m) + 1)
    across = max(2, math.ceil(width / spacing_m) + 1)
    spots = []
    for i in range(along):
        for j in range(across):
            x, y = spec.to_table(-length / 2 + length * i / (along - 1), -width / 2 + width * j / (across - 1))
            spots.append(PartOnTable(spec.colour, x, y))
    return spots


def homes_of(starts: Sequence[Any]) -> dict[str, tuple[str, tuple[float, float, float]]]:
    """Each piece's puzzle and home by its world name, from a scene's starts (empty without puzzles)."""
    return {s.name: (s.puzzle, s.home) for s in starts if isinstance(s, PieceStart)}


__all__ = ["PieceStart", "fragment_name", "homes_of", "puzzle_scene"]
