"""A puzzle: a slab broken into pieces whose outlines and places nobody gives (issue 32).

A plan's ``[puzzle.NAME]`` table says only what the whole is and where it goes::

    [puzzle.slab]
    size_mm = [240, 160, 20]    # the whole slab: length, width, height
    pieces = 6                  # 2 to 16
    gap_mm = 2                  # optional, default 2: the gap to leave along every fracture
    colour = "ochre"            # every piece's colour
    x_mm = 500                  # where the whole goes (its centre)
    y_mm = 0
    yaw_deg = 0                 # optional, default 0

There is no seed and no outline. In a simulator the scene breaks the slab from the run's seed
and scatters the pieces; the tree sees them with the camera, measures their outlines, solves the
puzzle (``bt_arrange.puzzle.solve``) and arranges the pieces ``NAME 1`` ... ``NAME N`` where the
solve puts them. Everything here is in metres and radians.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

#: A puzzle has this many pieces at least and at most.
MIN_PUZZLE_PIECES, MAX_PUZZLE_PIECES = 2, 16
#: The keys of a ``[puzzle.NAME]`` table.
PUZZLE_KEYS = ("size_mm", "pieces", "gap_mm", "colour", "x_mm", "y_mm", "yaw_deg")


@dataclass(frozen=True)
class PuzzleSpec:
    """A slab broken into ``pieces`` of one ``colour``, to be reassembled with ``gap_m`` at ``(x_m, y_m, yaw_rad)``."""

    name: str
    size_m: tuple[float, float, float]
    pieces: int
    gap_m: float
    colour: str
    x_m: float
    y_m: float
    yaw_rad: float = 0.0

    @property
    def piece_names(self) -> list[str]:
        """``NAME 1`` ... ``NAME N``: the framework's names of the pieces, numbered as the camera found them."""
        return [f"{self.name} {k}" for k in range(1, self.pieces + 1)]

    @property
    def height_m(self) -> float:
        """The slab's (and every piece's) height."""
        return self.size_m[2]

    def to_table(self, x_m: float, y_m: float) -> tuple[float, float]:
        """A point of the slab's frame (centred on the origin, length along x) on the table."""
        c, s = math.cos(self.yaw_rad), math.sin(self.yaw_rad)
        return self.x_m + c * x_m - s * y_m, self.y_m + s * x_m + c * y_m

    @property
    def symmetry_turns_rad(self) -> tuple[float, ...]:
        """The turns about its centre that leave the slab's rectangle as it is: the pieces cannot tell them apart."""
        length, width, _ = self.size_m
        if math.isclose(length, width, rel_tol=0.0, abs_tol=1e-6):
            return (0.0, math.pi / 2, math.pi, -math.pi / 2)
        return (0.0, math.pi)


def _format_spec(spec: PuzzleSpec) -> str:
    numbers = ",".join(f"{v:.9g}" for v in spec.size_m)
    pose = ",".join(f"{v:.9g}" for v in (spec.x_m, spec.y_m, spec.yaw_rad))
    return f"{spec.name};{numbers};{spec.pieces};{spec.gap_m:.9g};{spec.colour};{pose}"


def _parse_spec(text: str) -> PuzzleSpec:
    fields = text.split(";")
    if len(fields) != 6:
        raise ValueError("a puzzle is name;length_m,width_m,height_m;pieces;gap_m;colour;x_m,y_m,yaw_rad")
    name, size, pieces, gap, colour, pose = (f.strip() for f in fields)
    edges = [float(v) for v in size.split(",")]
    where = [float(v) for v in pose.split(",")]
    count = int(pieces)
    if not name or "/" in name or len(edges) != 3 or len(where) != 3 or not colour:
        raise ValueError("a puzzle is name;length_m,width_m,height_m;pieces;gap_m;colour;x_m,y_m,yaw_rad")
    if not all(math.isfinite(v) and v > 0 for v in [*edges, float(gap)]) or not all(math.isfinite(v) for v in where):
        raise ValueError("its size and gap must be positive and its pose finite")
    if not MIN_PUZZLE_PIECES <= count <= MAX_PUZZLE_PIECES:
        raise ValueError(f"a puzzle has {MIN_PUZZLE_PIECES} to {MAX_PUZZLE_PIECES} pieces")
    return PuzzleSpec(name, (edges[0], edges[1], edges[2]), count, float(gap), colour, *where)


def puzzle_port_type() -> Any:
    """The XML port type of a puzzle: ``name;length_m,width_m,height_m;pieces;gap_m;colour;x_m,y_m,yaw_rad``."""
    from bt_arrange.ports import PortType

    return PortType("std::string", _parse_spec, _format_spec)


def read_puzzles(reader: Any, table: Any, colours: Any, taken: set[str], metres_below_mm: float) -> list[PuzzleSpec]:
    """Each ``[puzzle.NAME]`` of a plan, checked by ``reader`` (``bt_arrange.plans._Reader``), one line per mistake.

    ``taken`` holds the names of the plan's other targets and types: a piece may not take one.
    """
    from bt_arrange.settings import DEFAULT_TARGET_GAP_M
    from bt_arrange.shapes.fracture import MIN_GAP_M
    from bt_arrange.suggest import did_you_mean

    if not isinstance(table, dict):
        raise reader.fail("[puzzle]", f"must be a table of puzzles, got {table!r}")
    out = []
    for name, entry in table.items():
        where = f"[puzzle.{name}]"
        reader.keys(entry, PUZZLE_KEYS, where)
        if not name.strip() or "/" in name:
            raise reader.fail(where, "a puzzle's name must be a non-empty text without '/'")
        for key in ("size_mm", "pieces", "colour", "x_mm", "y_mm"):
            if key not in entry:
                raise reader.fail(where, f"missing {key}")
        size = entry["size_mm"]
        if not isinstance(size, list) or len(size) != 3:
            raise reader.fail(where, f"size_mm = {size!r} is not three numbers [length, width, height] in mm")
        edges = [reader.number(v, where, "size_mm", positive=True) for v in size]
        if max(edges) < metres_below_mm:
            raise reader.fail(where, f"size_mm = {size!r} looks like metres: the plan is in millimetres")
        pieces = entry["pieces"]
        whole = isinstance(pieces, int) and not isinstance(pieces, bool)
        if not whole or not MIN_PUZZLE_PIECES <= pieces <= MAX_PUZZLE_PIECES:
            raise reader.fail(
                where, f"pieces = {pieces!r}: a puzzle has {MIN_PUZZLE_PIECES} to {MAX_PUZZLE_PIECES} pieces"
            )
        gap_mm = reader.number(entry.get("gap_mm", DEFAULT_TARGET_GAP_M * 1000), where, "gap_mm")
        if gap_mm < MIN_GAP_M * 1000 - 1e-9:
            raise reader.fail(where, f"gap_mm = {gap_mm:g}: two pieces need at least {MIN_GAP_M * 1000:g} mm")
        colour = entry["colour"]
        if not isinstance(colour, str) or colour not in colours:
            raise reader.fail(
                where,
                f"unknown colour {colour!r}{did_you_mean(str(colour), colours.names)}: not in the table "
                f"({', '.join(colours.names)}) and no [colours.NAME] with rgb",
            )
        x_mm = reader.number(entry["x_mm"], where, "x_mm")
        y_mm = reader.number(entry["y_mm"], where, "y_mm")
        yaw_deg = reader.number(entry.get("yaw_deg", 0.0), where, "yaw_deg")
        if 0.0 < max(abs(x_mm), abs(y_mm)) < metres_below_mm:
            raise reader.fail(where, f"x_mm = {x_mm:g}, y_mm = {y_mm:g} look like metres: the plan is in millimetres")
        spec = PuzzleSpec(
            name,
            (edges[0] / 1000, edges[1] / 1000, edges[2] / 1000),
            pieces,
            gap_mm / 1000,
            colour,
            x_mm / 1000,
            y_mm / 1000,
            math.radians(yaw_deg),
        )
        for piece in spec.piece_names:
            if piece in taken:
                raise reader.fail(where, f"its piece {piece!r} has the name of another type or target")
            taken.add(piece)
        out.append(spec)
    return out


__all__ = ["MAX_PUZZLE_PIECES", "MIN_PUZZLE_PIECES", "PUZZLE_KEYS", "PuzzleSpec", "read_puzzles"]
