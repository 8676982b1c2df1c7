"""Puzzles: a broken slab reassembled from its pieces alone, seen, solved and put back together.

``spec`` is a plan's ``[puzzle.NAME]``; ``solve`` reassembles the slab from the pieces' measured
outlines alone; ``targets`` turns a solve into the targets the arrangement steps reach;
``evaluation`` is the report's ground truth (never the tree's).
"""

from bt_arrange.puzzle.solve import (
    Assembly,
    MeasuredPiece,
    Placement,
    PuzzleAmbiguous,
    PuzzleError,
    PuzzleUnsolved,
    solve,
)
from bt_arrange.puzzle.spec import MAX_PUZZLE_PIECES, MIN_PUZZLE_PIECES, PuzzleSpec

__all__ = [
    "MAX_PUZZLE_PIECES",
    "MIN_PUZZLE_PIECES",
    "Assembly",
    "MeasuredPiece",
    "Placement",
    "PuzzleAmbiguous",
    "PuzzleError",
    "PuzzleSpec",
    "PuzzleUnsolved",
    "solve",
]
