"""Puzzles (issue 32): a broken slab reassembled from its pieces alone, seen, solved and put back together."""

from bt_arrange.puzzle.spec import MAX_PUZZLE_PIECES, MIN_PUZZLE_PIECES, PuzzleSpec

__all__ = ["MAX_PUZZLE_PIECES", "MIN_PUZZLE_PIECES", "PuzzleSpec"]
