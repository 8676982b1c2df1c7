"""A puzzle's scene: the slab broken from the run's seed, its pieces scattered turned at random.

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
from bt_arrange.objects import ObjectStart, ObjectType
from bt_arrange.puzzle.spec import MAX_PUZZLE_PIECES, MIN_PUZZLE_PIECES
from bt_arrange.shapes.fracture import fracture

#: Breaks drawn for a puzzle before its scene is refused (each from the next sub-seed).
MAX_REDRAWS = 20
#: A puzzle's slab breaks into as many pieces as its plan may ask for.
LIMITS = (MIN_PUZZLE_PIECES, MAX_PUZZLE_PIECES)

#: The break's seed is the run's seed mixed with this, so that a puzzle's break and its scatter differ.
BREAK_SALT = 7919


@dataclass(frozen=True)
class PieceStart(ObjectStart):
    """A piece of a puzzle where it starts, and (evaluation only) its home: ``(x_m, y_m, yaw_rad)`` in the whole."""

    home: tuple[float, float, float] = (0.0, 0.0, 0.0)
    puzzle: str = ""
    #: A painted slab's picture file, and each outline vertex's place in it (u, v in 0..1), or None: plain.
    picture: str | None = None
    picture_uv: tuple[tuple[float, float], ...] = ()


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

    colours, kinds, names, homes, paints = [], [], [], [], []
    for spec in puzzles:
        pieces = buildable_break(spec, seed)
        for piece in pieces:
            paints.append(_paint_of(spec, piece))
            colours.append(spec.colour)
            kinds.append(ObjectType(fragment_name(spec.name, piece.index), shape=piece.prism))
            names.append(fragment_name(spec.name, piece.index))
            homes.append((spec.name, (piece.x_m, piece.y_m, piece.yaw_rad)))
    if starts is not None:
        own = list(starts)
        avoid = [*targets, *own]
    else:
        own = (
            scatter(
                [t.colour for t in targets],
                seed,
                avoid=targets,
                object_types=[t.object_type for t in targets],
                names=[t.name for t in targets],
            )
            if targets
            else []
        )
        avoid = [*targets, *own]
    spots = _free_spots(kinds, avoid, puzzles, seed)
    pieces_out = [
        PieceStart(colour, x, y, yaw, name, kind, home=home, puzzle=puzzle, picture=paint[0], picture_uv=paint[1])
        for colour, kind, name, (puzzle, home), (x, y, yaw), paint in zip(
            colours, kinds, names, homes, spots, paints, strict=True
        )
    ]
    return [*own, *pieces_out]


def _free_spots(
    kinds: Sequence[ObjectType], avoid: Sequence[Any], puzzles: Sequence[Any], seed: int
) -> list[tuple[float, float, float]]:
    """A start per piece, drawn from ``seed``, each turned at random.

    The starts are sites of a hexagonal grid over the scatter's table at the spacing the pads need
    between the largest two pieces, clear of ``avoid`` (as ``scenes.scatter`` keeps them), of every
    whole slab's place (as the plan check keeps a start from a target's footprint) and in the
    camera's view. Random sequential placement fills about half the room a grid does.
    """
    import numpy as np

    from bt_arrange.objects import object_type_of
    from bt_arrange.plan.layout import Pads, start_clearance_m
    from bt_arrange.settings import ManipulationSettings
    from bt_arrange_sim.config import CameraConfig
    from bt_arrange_sim.scenes import MAX_RADIUS_M, X_RANGE_M, Y_RANGE_M, clearance_m

    if not kinds:
        return []
    view = CameraConfig().view()
    largest = max(kinds, key=lambda k: k.shape.sweep_radius_m)
    spacing = clearance_m(largest, largest)
    rng = np.random.default_rng([seed, BREAK_SALT])
    # The grid's offset is drawn too, so that seeds differ in more than the order of the sites.
    x0, y0 = rng.uniform(0.0, spacing, size=2)
    sites = []
    row = 0
    y = Y_RANGE_M[0] + y0 * math.sqrt(3) / 2
    while y <= Y_RANGE_M[1]:
        x = X_RANGE_M[0] + (x0 + (spacing / 2 if row % 2 else 0.0)) % spacing
        while x <= X_RANGE_M[1]:
            sites.append((x, y))
            x += spacing
        y += spacing * math.sqrt(3) / 2
        row += 1
    order = rng.permutation(len(sites))
    taken = [(float(a.x_m), float(a.y_m), object_type_of(a)) for a in avoid]
    pads = Pads.from_settings(ManipulationSettings())

    def off_the_wholes(x: float, y: float, kind: ObjectType) -> bool:
        need = start_clearance_m(kind.shape.sweep_radius_m, pads)
        for spec in puzzles:
            c, s_ = math.cos(spec.yaw_rad), math.sin(spec.yaw_rad)
            u, v = c * (x - spec.x_m) + s_ * (y - spec.y_m), -s_ * (x - spec.x_m) + c * (y - spec.y_m)
            outside = math.hypot(max(abs(u) - spec.size_m[0] / 2, 0.0), max(abs(v) - spec.size_m[1] / 2, 0.0))
            if outside < need:
                return False
        return True

    out: list[tuple[float, float, float]] = []
    for kind in kinds:
        x_m, y_m = kind.shape.extent_m
        radius_m = 0.5 * math.hypot(x_m + 2 * view.margin_m, y_m + 2 * view.margin_m) + 0.001
        for index in order:
            x, y = sites[index]
            if (
                math.hypot(x, y) <= MAX_RADIUS_M
                and all(math.hypot(x - u, y - v) >= clearance_m(kind, other) for u, v, other in taken)
                and off_the_wholes(x, y, kind)
                and view.sees_disc(x, y, radius_m, kind.shape.height_m)
            ):
                break
        else:
            raise PlanError(f"no room left on the table for {len(kinds)} pieces: ask for fewer or a smaller slab")
        taken.append((x, y, kind))
        out.append((x, y, float(rng.uniform(-math.pi, math.pi))))
    return out


def _paint_of(spec: Any, piece: Any) -> tuple[str | None, tuple[tuple[float, float], ...]]:
    """A painted slab's piece: the picture's file and where each vertex of its outline lies in it."""
    if spec.picture is None:
        return None, ()
    import numpy as np

    from bt_arrange.puzzle.picture import picture_file, slab_uv

    own = piece.prism.outline_m
    c, s = math.cos(piece.yaw_rad), math.sin(piece.yaw_rad)
    on_table = own @ np.array([[c, s], [-s, c]]) + [piece.x_m, piece.y_m]
    c0, s0 = math.cos(spec.yaw_rad), math.sin(spec.yaw_rad)
    in_slab = (on_table - [spec.x_m, spec.y_m]) @ np.array([[c0, -s0], [s0, c0]])
    uv = slab_uv(in_slab, spec.size_m)
    return str(picture_file(spec.picture)), tuple((float(u), float(v)) for u, v in uv)


def buildable_break(spec: Any, seed: int) -> list[Any]:
    """The slab of ``spec`` broken from ``seed``: the first of ``MAX_REDRAWS`` breaks whose pieces can be built.

    A break whose pieces no order and approach can put back at their homes (the pads find no room
    between two of them) is redrawn, as a fresco's break with a piece the gripper cannot handle is.
    The check is the arrangement's own, at the finest threshold the gap allows (half of it, at most
    1 mm). Only the simulator sees the homes it checks.
    """
    from bt_arrange.trees import Target, arrangement

    threshold_mm = min(1.0, spec.gap_m * 1000 / 2)
    last = ""
    for redraw in range(MAX_REDRAWS):
        try:
            pieces = fracture(
                spec.size_m,
                spec.pieces,
                spec.gap_m,
                (seed * BREAK_SALT + spec.pieces) * MAX_REDRAWS + redraw,
                (spec.x_m, spec.y_m, spec.yaw_rad),
                piece_limits=LIMITS,
            )
        except PlanError as error:
            raise PlanError(f"[puzzle.{spec.name}]: {error}") from None
        homes = [
            Target(
                "red",  # a built-in colour stands in for the plan's: the layout does not look at colours
                p.x_m,
                p.y_m,
                p.yaw_rad,
                name=f"piece {p.index}",
                object_type=ObjectType(f"piece {p.index}", shape=p.prism),
            )
            for p in pieces
        ]
        try:
            arrangement(homes, threshold_mm=threshold_mm)
        except PlanError as error:
            last = str(error)
            continue
        return pieces
    raise PlanError(f"[puzzle.{spec.name}]: no break from seed {seed} in {MAX_REDRAWS} draws can be built: {last}")


@dataclass(frozen=True)
class MeasuredBreak:
    """A slab broken as the scene breaks it, its pieces' outlines as a camera might give them (evaluation only).

    ``outlines[k]`` is piece k's top face turned by ``turns_rad[k]`` about the origin, shifted, and
    each vertex moved ``noise_m`` in a random direction; ``labels[k]`` its name (shuffled: label
    order is no clue). ``truths[k]`` is the piece's outline as cut, in the slab's frame.
    """

    labels: tuple[str, ...]
    outlines: tuple[Any, ...]
    truths: tuple[Any, ...]
    turns_rad: tuple[float, ...]

    def errors(self, placements: Sequence[Any], symmetry_turns_rad: Sequence[float]) -> tuple[float, float]:
        """A solve's worst centroid error (m) and turn error (rad), under the slab's symmetric turn that fits best.

        ``placements`` are a solve's, in the order of ``labels``.
        """
        import numpy as np

        from bt_arrange.shapes.polygon import centroid_m

        best = (math.inf, math.inf)
        for symmetry in symmetry_turns_rad:
            c, s = math.cos(symmetry), math.sin(symmetry)
            turned = np.array([[c, -s], [s, c]])
            places, turns = [], []
            for placement, truth, turn in zip(placements, self.truths, self.turns_rad, strict=True):
                places.append(math.hypot(*(np.asarray(placement.centroid_m) - turned @ centroid_m(truth))))
                # the outline was turned by ``turn`` from the slab: the solve turns it back, then by the symmetry
                off = placement.turn_rad - (symmetry - turn)
                turns.append(abs(math.atan2(math.sin(off), math.cos(off))))
            if max(places) < best[0]:
                best = (max(places), max(turns))
        return best


def measured_break(spec: Any, seed: int, noise_m: float = 0.00005, *, scatter_seed: int = 0) -> MeasuredBreak:
    """``buildable_break`` of ``spec`` from ``seed``, its pieces turned, moved, shuffled, noised (``scatter_seed``).

    For the solver's tests and benchmark: the outlines stand in for a survey's, the truths judge
    the solve. Only the evaluation side may call this.
    """
    import numpy as np

    pieces = buildable_break(spec, seed)
    rng = np.random.default_rng([seed, scatter_seed, BREAK_SALT])
    order = rng.permutation(len(pieces))
    labels, outlines, truths, turns = [], [], [], []
    for rank, index in enumerate(order):
        truth = np.asarray(pieces[index].slab_outline_m, dtype=float)
        turn = float(rng.uniform(-math.pi, math.pi))
        c, s = math.cos(turn), math.sin(turn)
        shift = rng.uniform(-0.3, 0.3, size=2)
        angles = rng.uniform(-math.pi, math.pi, size=len(truth))
        noise = noise_m * np.stack([np.cos(angles), np.sin(angles)], axis=1)
        outlines.append(truth @ np.array([[c, s], [-s, c]]) + shift + noise)
        truths.append(truth)
        turns.append(turn)
        labels.append(f"{spec.name} {rank + 1}")
    return MeasuredBreak(tuple(labels), tuple(outlines), tuple(truths), tuple(turns))


def homes_of(starts: Sequence[Any]) -> dict[str, tuple[str, tuple[float, float, float]]]:
    """Each piece's puzzle and home by its world name, from a scene's starts (empty without puzzles)."""
    return {s.name: (s.puzzle, s.home) for s in starts if isinstance(s, PieceStart)}


__all__ = ["MeasuredBreak", "PieceStart", "fragment_name", "homes_of", "measured_break", "puzzle_scene"]
