"""Puzzle solving: a broken slab reassembled from its pieces' measured outlines (``bt_arrange.puzzle.solve``)."""

from bt_arrange.puzzle.solve import (
    Assembly,
    MeasuredPiece,
    Placement,
    PuzzleAmbiguous,
    PuzzleError,
    PuzzleUnsolved,
    solve,
)

__all__ = ["Assembly", "MeasuredPiece", "Placement", "PuzzleAmbiguous", "PuzzleError", "PuzzleUnsolved", "solve"]
