"""Reassemble a broken slab from its pieces' measured outlines alone: which piece goes where, turned how.

``solve(pieces, size_m, gap_m)`` takes each piece's top face as the camera measured it on the
table and returns an :class:`Assembly`: per piece a :class:`Placement`, the rigid motion (a turn
about the table origin, then an offset) taking the measured outline to its place in the slab frame
(slab centred on the origin, length along x).

How: each piece pushed back out by half the gap along its fractures is its Voronoi cell, and the
cells tile the rectangle edge to edge (``bt_arrange.puzzle.shapes``). A depth-first search fills
the rectangle cell by cell, always at the free corner fewest piece corners fit
(``bt_arrange.puzzle.search``); every tiling found is fitted as a whole on the measured outlines
(``bt_arrange.puzzle.refine``) and scored by its residual: the RMS misfit of the facing fracture
edges from the gap and of the border edges from the rectangle.

Equivalence and the representative returned: the rectangle looks the same turned half a turn
about its centre (a square one a quarter turn too), so every assembly comes with its turned
copies, all the same solution. The one returned is the copy in which the piece with the smallest
label (natural order: "slab 2" before "slab 10") has its centroid at the smallest x (then the
smallest y). Two assemblies that no such turn makes agree (every centroid within 2 mm, every turn
within 2 degrees) are different; when the best two different ones fit equally well (the second's
residual within ``AMBIGUOUS_RATIO`` times the best's plus ``AMBIGUOUS_FLOOR_M``) and colours do not
tell them apart, ``PuzzleAmbiguous`` names the pieces whose places differ. Pieces are never
flipped: mirror images are not considered.
"""

from __future__ import annotations

import math
import re
import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from bt_arrange.errors import PlanError
from bt_arrange.geometry import FloatArray
from bt_arrange.puzzle.refine import Fitted, fit
from bt_arrange.puzzle.search import Search, Tolerances
from bt_arrange.puzzle.shapes import Shape, make_shape, rotation, wrap
from bt_arrange.shapes.polygon import outline_problem, signed_area_m2

#: The default tolerance: how far a cell's edge may be from its neighbour's, in length and place.
TOLERANCE_M = 0.0006
#: Corner angles match within this.
ANGLE_TOLERANCE_RAD = math.radians(2.5)
#: The pieces' area may differ from the slab's less its gaps by this share before the search is tried.
AREA_SHARE = 0.02
#: Two assemblies fit equally when the second's residual is within this many times the best's ...
AMBIGUOUS_RATIO = 2.0
#: ... plus this.
AMBIGUOUS_FLOOR_M = 0.00002
#: Colours tell two assemblies apart when one's colour misfit is this many times the other's, or more ...
COLOUR_RATIO = 2.0
#: ... and above this (mean squared RGB difference, RGB in 0..1).
COLOUR_FLOOR = 1e-3
#: Assemblies are the same when every centroid agrees within this and every turn within ``SAME_TURN_RAD``.
SAME_PLACE_M = 0.002
SAME_TURN_RAD = math.radians(2.0)
#: The search stops after this many placements tried, or this many tilings found.
MAX_NODES = 20000
MAX_SOLUTIONS = 24


class PuzzleError(PlanError):
    """The pieces cannot be reassembled into the slab: the message says why, on one line."""


class PuzzleAmbiguous(PuzzleError):
    """Two different assemblies fit equally well: the message names the pieces whose places differ."""


class PuzzleUnsolved(PuzzleError):
    """No assembly of the pieces fills the slab: the message says why."""


@dataclass(frozen=True)
class MeasuredPiece:
    """One piece as measured: its top face on the table (counter-clockwise, metres) and optional edge colours.

    ``edge_colours[k]`` are colour samples (K x 3, RGB in 0..1) taken just inside edge k (corner k
    to corner k+1), in order along it, for a painted slab.
    """

    label: str
    outline_m: FloatArray
    edge_colours: Sequence[FloatArray] | None = None


@dataclass(frozen=True)
class Placement:
    """Where a piece goes: turn its measured outline by ``turn_rad`` about the table origin, then add ``offset_m``.

    The result is the piece in the slab frame. ``centroid_m`` is the measured outline's area
    centroid so moved (the piece's place in the slab frame, as a target wants it); the piece's turn
    from the table to the slab is ``turn_rad`` itself.
    """

    label: str
    turn_rad: float
    offset_m: tuple[float, float]
    centroid_m: tuple[float, float]

    def to_slab(self, points_m: FloatArray) -> FloatArray:
        """Points measured on the table (N x 2) in the slab frame."""
        points = np.asarray(points_m, dtype=float).reshape(-1, 2)
        return np.asarray(points @ rotation(self.turn_rad).T + np.asarray(self.offset_m), dtype=float)


@dataclass(frozen=True)
class Assembly:
    """One placement per piece (in the order given), the fit's residual, the solve's time and the runner-up's residual.

    ``colour_misfit`` is the mean squared RGB difference across the fractures (None without colours).
    """

    placements: tuple[Placement, ...]
    residual_m: float
    solve_s: float
    runner_up_residual_m: float | None
    colour_misfit: float | None = None


def _natural(label: str) -> list[object]:
    return [int(part) if part.isdigit() else part for part in re.split(r"(\d+)", label)]


def _symmetries(length: float, width: float) -> list[float]:
    if abs(length - width) < 1e-6:
        return [0.0, math.pi / 2, math.pi, -math.pi / 2]
    return [0.0, math.pi]


def _turned(fitted: Fitted, symmetry: float) -> tuple[FloatArray, FloatArray]:
    turns = np.array([wrap(t + symmetry) for t in fitted.turns])
    return turns, fitted.shifts @ rotation(symmetry).T


def _same_face(shape: Shape, first_turn: float, second_turn: float) -> bool:
    """Whether the piece turned by either turn covers the same place: its outline's own symmetry (a rectangle's)."""
    one = shape.points @ rotation(first_turn).T
    two = shape.points @ rotation(second_turn).T
    return bool(
        np.max(np.min(np.hypot(*(one[:, None, :] - two[None, :, :]).transpose(2, 0, 1)), axis=1)) <= SAME_PLACE_M
    )


def _differing(first: Fitted, second: Fitted, symmetries: list[float], shapes: Sequence[Shape]) -> list[int]:
    """The shapes whose places differ between two assemblies, under the symmetry that makes the fewest differ.

    A piece turned differently still has the same place when its outline looks the same so turned.
    """
    best: list[int] | None = None
    for symmetry in symmetries:
        turns, shifts = _turned(second, symmetry)
        moved = np.hypot(*(shifts - first.shifts).T)
        turned = np.abs([wrap(a - b) for a, b in zip(turns, first.turns, strict=True)])
        differ = [
            i
            for i in range(len(turns))
            if moved[i] > SAME_PLACE_M
            or (turned[i] > SAME_TURN_RAD and not _same_face(shapes[i], float(turns[i]), float(first.turns[i])))
        ]
        if best is None or len(differ) < len(best):
            best = differ
    return best or []


def _area_problem(
    shapes: Sequence[Shape], raw: Sequence[FloatArray], length: float, width: float, gap: float
) -> str | None:
    area = sum(abs(signed_area_m2(np.asarray(r, dtype=float).reshape(-1, 2))) for r in raw)
    perimeter = sum(float(np.sum(s.lengths)) for s in shapes)
    fractures = max(0.0, perimeter - 2 * (length + width))
    expected = length * width - gap / 2 * fractures
    share = (area - expected) / (length * width)
    if abs(share) <= AREA_SHARE:
        return None
    side = "over" if share > 0 else "under"
    return (
        f"the pieces' area is {abs(share) * 100:.1f} % {side} the slab's less its gaps "
        f"({area * 1e6:.0f} mm2 for {expected * 1e6:.0f} mm2): a piece {'too many' if share > 0 else 'missing'}?"
    )


def _size(size_m: Sequence[float]) -> str:
    return f"{size_m[0] * 1000:g} x {size_m[1] * 1000:g} mm"


def solve(
    pieces: Sequence[MeasuredPiece],
    size_m: tuple[float, float] | tuple[float, float, float],
    gap_m: float,
    *,
    tolerance_m: float = TOLERANCE_M,
) -> Assembly:
    """The assembly of ``pieces`` into the slab ``size_m`` (length, width; a height is ignored) with ``gap_m`` between.

    ``tolerance_m`` is how far a piece's edge may be from where its neighbour's says it should be
    (length and place) while searching. Raises ``PuzzleError`` for input no puzzle is made of (fewer
    than 2 pieces, two sharing a label, an outline that is no simple polygon), ``PuzzleUnsolved``
    when no assembly fills the slab and ``PuzzleAmbiguous`` when two different ones fit equally well.
    """
    started = time.process_time()
    length, width = float(size_m[0]), float(size_m[1])
    if len(pieces) < 2:
        raise PuzzleError(f"a puzzle needs 2 pieces or more to fill the {_size(size_m)} slab, got {len(pieces)}")
    labels = [p.label for p in pieces]
    if len(set(labels)) != len(labels):
        raise PuzzleError(f"two pieces share a label: {sorted(labels, key=_natural)}")
    for piece in pieces:
        problem = outline_problem(np.asarray(piece.outline_m, dtype=float).reshape(-1, 2).tolist())
        if problem is not None:
            raise PuzzleError(f"piece {piece.label}: {problem}", parts=(("piece", piece.label),))
    shapes = [make_shape(i, p.label, p.outline_m, gap_m / 2, p.edge_colours) for i, p in enumerate(pieces)]
    problem = _area_problem(shapes, [p.outline_m for p in pieces], length, width, gap_m)
    if problem is not None:
        raise PuzzleUnsolved(problem)
    right = sum(int(np.sum(np.abs(s.angles - math.pi / 2) <= ANGLE_TOLERANCE_RAD)) for s in shapes)
    if right == 0:
        raise PuzzleUnsolved(f"no piece has a corner of the {_size(size_m)} slab (no right-angled corner)")
    tolerances = Tolerances(
        length_m=tolerance_m,
        overlap_m=tolerance_m,
        cluster_m=2 * tolerance_m,
        angle_rad=ANGLE_TOLERANCE_RAD,
        side_m=2 * tolerance_m,
        residual_m=tolerance_m / 2,
    )
    search = Search(shapes, length / 2, width / 2, gap_m, tolerances, MAX_NODES, MAX_SOLUTIONS)
    search.run()
    if not search.solutions:
        capped = "" if search.exhausted else f", gave up after {search.nodes} tries"
        raise PuzzleUnsolved(
            f"no assembly of the {len(shapes)} pieces fills the {_size(size_m)} slab with {gap_m * 1000:g} mm gaps: "
            f"at most {search.deepest} fit together{capped}"
        )
    fitted = []
    for solution in search.solutions:
        order = sorted(solution, key=lambda p: p.shape)
        fitted.append(
            fit(
                shapes,
                np.array([p.turn for p in order]),
                np.array([p.shift for p in order]),
                length / 2,
                width / 2,
                gap_m,
            )
        )
    symmetries = _symmetries(length, width)
    distinct: list[Fitted] = []
    for candidate in sorted(fitted, key=lambda f: f.residual_m):
        if all(_differing(candidate, kept, symmetries, shapes) for kept in distinct):
            distinct.append(candidate)
    best = distinct[0]
    runner_up = distinct[1] if len(distinct) > 1 else None
    if runner_up is not None and runner_up.residual_m <= AMBIGUOUS_RATIO * best.residual_m + AMBIGUOUS_FLOOR_M:
        ties = [d for d in distinct if d.residual_m <= AMBIGUOUS_RATIO * best.residual_m + AMBIGUOUS_FLOOR_M]
        by_colour = sorted(ties, key=lambda d: math.inf if d.colour_misfit is None else d.colour_misfit)
        first, second = by_colour[0], by_colour[1]
        if (
            first.colour_misfit is not None
            and second.colour_misfit is not None
            and second.colour_misfit >= COLOUR_RATIO * first.colour_misfit
            and second.colour_misfit > COLOUR_FLOOR
        ):
            best, runner_up = first, second
        else:
            differ = _differing(first, second, symmetries, shapes)
            names = ", ".join(sorted((shapes[i].label for i in differ), key=_natural))
            raise PuzzleAmbiguous(
                f"{len(ties)}{'+' if not search.exhausted else ''} different assemblies fit equally well "
                f"(residuals {first.residual_m * 1000:.3f} and {second.residual_m * 1000:.3f} mm): "
                f"{names} can go in either place",
                parts=tuple(("piece", shapes[i].label) for i in differ),
            )
    placements = _canonical(best, shapes, symmetries)
    return Assembly(
        placements,
        best.residual_m,
        time.process_time() - started,
        None if runner_up is None else runner_up.residual_m,
        best.colour_misfit,
    )


def _canonical(fitted: Fitted, shapes: Sequence[Shape], symmetries: list[float]) -> tuple[Placement, ...]:
    """The turned copy in which the smallest label's centroid has the smallest x (then y), as placements."""
    first = min(range(len(shapes)), key=lambda i: _natural(shapes[i].label))
    options = [_turned(fitted, s) for s in symmetries]
    turns, shifts = min(options, key=lambda o: (round(float(o[1][first, 0]) / SAME_PLACE_M), float(o[1][first, 1])))
    placements = []
    for shape, turn, shift in zip(shapes, turns, shifts, strict=True):
        offset = shift - rotation(float(turn)) @ shape.centre
        placements.append(
            Placement(
                shape.label,
                float(turn),
                (float(offset[0]), float(offset[1])),
                (float(shift[0]), float(shift[1])),
            )
        )
    return tuple(placements)


__all__ = [
    "Assembly",
    "MeasuredPiece",
    "Placement",
    "PuzzleAmbiguous",
    "PuzzleError",
    "PuzzleUnsolved",
    "solve",
]
