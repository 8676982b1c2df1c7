"""A puzzle: a slab broken into pieces whose outlines and places nobody gives.

A plan's ``[puzzle.NAME]`` table says only what the whole is and where it goes::

    [puzzle.slab]
    size_mm = [240, 160, 20]    # the whole slab: length, width, height
    pieces = 6                  # 2 to 16
    gap_mm = 2                  # optional, default 2: the gap to leave along every fracture
    colour = "ochre"            # every piece's colour
    x_mm = 500                  # where the whole goes (its centre)
    y_mm = 0
    yaw_deg = 0                 # optional, default 0
    # or, instead of colour, picture = "PATH.png" (or "fresco", the built-in one) painted on its top

There is no seed and no outline. In a simulator the scene breaks the slab from the run's seed
and scatters the pieces; the tree sees them with the camera, measures their outlines, solves the
puzzle (``bt_arrange.puzzle.solve``) and arranges the pieces ``NAME 1`` ... ``NAME N`` where the
solve puts them. Everything here is in metres and radians.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from bt_arrange.errors import PlanError

#: A puzzle has this many pieces at least and at most.
MIN_PUZZLE_PIECES = 2
MAX_PUZZLE_PIECES = 16
#: The keys of a ``[puzzle.NAME]`` table.
PUZZLE_KEYS = ("size_mm", "pieces", "gap_mm", "colour", "picture", "x_mm", "y_mm", "yaw_deg")
#: The colour of a painted puzzle's pieces: any saturated hue (``painted_range``), the table and the sides are grey.
PAINTED = "painted"


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
    #: The picture painted on the slab's top face: a file, or a built-in's name (``picture.picture_file``); None: plain.
    picture: str | None = None

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
        if self.picture is not None:
            return (0.0,)  # the picture tells the whole's turns apart
        if math.isclose(length, width, rel_tol=0.0, abs_tol=1e-6):
            return (0.0, math.pi / 2, math.pi, -math.pi / 2)
        return (0.0, math.pi)


def format_spec(spec: PuzzleSpec) -> str:
    """A puzzle as its XML port writes it: ``name;length_m,width_m,height_m;pieces;gap_m;colour;x_m,y_m,yaw_rad``."""
    numbers = ",".join(f"{v:.9g}" for v in spec.size_m)
    pose = ",".join(f"{v:.9g}" for v in (spec.x_m, spec.y_m, spec.yaw_rad))
    text = f"{spec.name};{numbers};{spec.pieces};{spec.gap_m:.9g};{spec.colour};{pose}"
    return text if spec.picture is None else f"{text};{spec.picture}"


def parse_spec(text: str) -> PuzzleSpec:
    """A puzzle read back from its XML port's text (``format_spec``'s); a ``ValueError`` says what is wrong."""
    fields = text.split(";")
    if len(fields) not in (6, 7):
        raise ValueError("a puzzle is name;length_m,width_m,height_m;pieces;gap_m;colour;x_m,y_m,yaw_rad[;picture]")
    name, size, pieces, gap, colour, pose = (f.strip() for f in fields[:6])
    picture = fields[6].strip() or None if len(fields) == 7 else None
    edges = [float(v) for v in size.split(",")]
    where = [float(v) for v in pose.split(",")]
    count = int(pieces)
    if not name or "/" in name or len(edges) != 3 or len(where) != 3 or not colour:
        raise ValueError("a puzzle is name;length_m,width_m,height_m;pieces;gap_m;colour;x_m,y_m,yaw_rad")
    if not all(math.isfinite(v) and v > 0 for v in [*edges, float(gap)]) or not all(math.isfinite(v) for v in where):
        raise ValueError("its size and gap must be positive and its pose finite")
    if not MIN_PUZZLE_PIECES <= count <= MAX_PUZZLE_PIECES:
        raise ValueError(f"a puzzle has {MIN_PUZZLE_PIECES} to {MAX_PUZZLE_PIECES} pieces")
    return PuzzleSpec(
        name, (edges[0], edges[1], edges[2]), count, float(gap), colour, where[0], where[1], where[2], picture=picture
    )


def _picture_of(reader: Any, entry: dict[str, Any], where: str) -> str | None:
    """A puzzle's picture file (a path beside the plan, or a built-in's drawn file), checked; None without one."""
    from bt_arrange.puzzle.picture import BUILT_IN, check_picture, picture_file

    if "picture" not in entry:
        if "colour" not in entry:
            raise reader.fail(where, "missing colour (or picture)")
        return None
    if "colour" in entry:
        raise reader.fail(where, "give colour or picture, not both: a painted slab's colours are its picture's")
    value = entry["picture"]
    if not isinstance(value, str) or not value.strip():
        raise reader.fail(where, f"picture = {value!r} is not a file name or a built-in ({', '.join(BUILT_IN)})")
    chosen = value if value in BUILT_IN else str((reader.path.parent / value).resolve())
    try:
        check_picture(picture_file(chosen))
    except PlanError as error:
        raise reader.fail(where, str(error)) from None
    return chosen


def painted_range() -> Any:
    """The camera's colour of a painted puzzle's pieces: every hue, saturated (``picture.MIN_SATURATION``)."""
    from bt_arrange.perception.colours import ColourRange

    return ColourRange(PAINTED, ((0.0, 360.0),), (0.3, 1.0), (0.2, 1.0))  # no paint: the picture is printed


def painted_colours(reader: Any, puzzles: list[PuzzleSpec], targets: list[Any], colours: Any) -> Any:
    """The plan's colour table, with the painted colour when a puzzle is painted (then it is the plan's only part)."""
    painted = [spec for spec in puzzles if spec.picture is not None]
    if not painted:
        return colours
    if targets or len(puzzles) > 1:
        raise reader.fail(
            f"[puzzle.{painted[0].name}]",
            "a painted slab is found by its saturated colours: a plan with one holds no other target or puzzle",
        )
    return colours.with_colour(painted_range())


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
        for key in ("size_mm", "pieces", "x_mm", "y_mm"):
            if key not in entry:
                raise reader.fail(where, f"missing {key}")
        picture = _picture_of(reader, entry, where)
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
        colour = PAINTED if picture is not None else entry["colour"]
        if picture is None and (not isinstance(colour, str) or colour not in colours):
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
            picture,
        )
        for piece in spec.piece_names:
            if piece in taken:
                raise reader.fail(where, f"its piece {piece!r} has the name of another type or target")
            taken.add(piece)
        out.append(spec)
    return out


__all__ = ["MAX_PUZZLE_PIECES", "MIN_PUZZLE_PIECES", "PUZZLE_KEYS", "PuzzleSpec", "read_puzzles"]
