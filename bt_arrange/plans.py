"""Plan files: an arrangement as data (TOML), beside Python and XML tree files.

``load(path)`` reads a plan and returns a :class:`Plan` with ``create_root(...)`` and
``create_scene(seed)``, the two functions of a tree file, so the runner treats both alike
(``bt_arrange.treefile.load`` hands ``.toml`` files here). The format (docs/plans.md) is a contract::

    threshold_mm = 1.0          # optional, default 1.0
    yaw_threshold_deg = 1.0     # optional, default 1.0
    correct = "each"            # optional: "each" (Algorithm 1) or "after_all"
    max_pushes = 10             # optional, default 10
    strategy = "paper"          # optional: how pushes are chosen, "paper", "learned" or "diagonal"

    [objects.bar]               # a user's type; "cube" (50 x 50 x 50 mm) is built in
    size_mm = [80, 40, 40]      # mass_kg, friction: optional simulator settings

    [colours.orange]            # a user's colour: rgb in 0..1 (paint, and the HSV range around it),
    rgb = [1.0, 0.5, 0.0]       # or hue_deg = [low, high], saturation = [low, high], value = [low, high]

    [[targets]]
    object = "bar"              # optional, default "cube"
    colour = "orange"
    x_mm = 560
    y_mm = -60
    yaw_deg = 30                # optional, default 0
    name = "orange bar"         # optional; default the colour, numbered for identical parts
    z_mm = 40                   # optional, default 0: its bottom face this high, on the parts below (a layer)

    [fresco.tile]               # a slab broken into pieces "tile 1" ... "tile N", each a target at its place
    size_mm = [160, 120, 20]    # the whole slab: length, width, height
    pieces = 6                  # 3 to 12
    gap_mm = 2                  # optional, default 2: the gap along every fracture once reassembled,
                                # at least twice threshold_mm (0.5 at a 0.25 mm threshold)
    seed = 3                    # optional, default 0: the fracture pattern
    colour = "ochre"            # a built-in or [colours.NAME]; every piece the same colour
    x_mm = 500                  # where the whole goes (its centre)
    y_mm = 0
    yaw_deg = 0                 # optional, default 0

    [scene]                     # simulator only, optional: where the objects start
    seed = 0                    # scattered clear of each other and of the targets; --seed overrides
    # or [[scene.starts]] with object, colour, x_mm, y_mm, yaw_deg (name optional)

Every mistake is one ``PlanError`` naming the file, the entry and the problem, raised while the
plan loads, before anything moves.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any

from bt_arrange.checks import toml_shown as _shown
from bt_arrange.errors import BtArrangeError, PlanError
from bt_arrange.filelimits import (
    MAX_OBJECT_TYPES,
    MAX_OUTLINE_POINTS,
    MAX_PLAN_OUTLINE_POINTS,
    MAX_TARGETS,
    read_limited,
)
from bt_arrange.objects import CUBE, ObjectStart, ObjectType
from bt_arrange.perception.colours import ColourTable
from bt_arrange.plan.choices import PushStrategy
from bt_arrange.plan.targets import Target
from bt_arrange.plan.validate import LOOKS_LIKE_MILLIMETRES_M
from bt_arrange.plan_colours import COLOUR_KEYS as COLOUR_KEYS  # the plan format's names, kept here
from bt_arrange.plan_colours import read_colour_table
from bt_arrange.puzzle.spec import painted_colours, read_puzzles
from bt_arrange.settings import DEFAULT_TARGET_GAP_M, ManipulationSettings
from bt_arrange.shapes import Prism
from bt_arrange.shapes.fracture import MAX_PIECES, MIN_GAP_M, MIN_PIECES, fracture
from bt_arrange.suggest import did_you_mean

if TYPE_CHECKING:
    from bt_arrange.backends import Backend
    from bt_arrange.plan.check import PlanSource

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

TOP_KEYS = (
    "threshold_mm",
    "yaw_threshold_deg",
    "correct",
    "max_pushes",
    "strategy",
    "objects",
    "colours",
    "targets",
    "fresco",
    "puzzle",
    "scene",
)
OBJECT_KEYS = ("size_mm", "outline_mm", "height_mm", "mass_kg", "friction")
TARGET_KEYS = ("object", "colour", "x_mm", "y_mm", "yaw_deg", "name", "z_mm")
SCENE_KEYS = ("seed", "starts")
FRESCO_KEYS = ("size_mm", "pieces", "gap_mm", "seed", "colour", "x_mm", "y_mm", "yaw_deg")
#: A part starts on the table: a start has no ``z_mm``.
START_KEYS = TARGET_KEYS[:-1]
#: A position or a size in an ``_mm`` field below this many millimetres looks like metres (0.45 for 450).
LOOKS_LIKE_METRES_MM = 2.0


@dataclass
class Plan:
    """A loaded plan file: its targets, colour table and options, and where the parts start.

    ``create_root(...)`` builds the arrangement tree (``bt_arrange.trees.arrangement``) and
    ``create_scene(seed, backend)`` says where the parts start in a simulator: the plan's own
    starts, or parts scattered from ``seed`` (default the plan's ``[scene] seed``, else 0) by the
    backend the run uses (``--backend``; without one, the default backend).
    """

    path: Path
    targets: list[Any]
    colours: ColourTable
    object_types: dict[str, ObjectType]
    threshold_mm: float = 1.0
    yaw_threshold_deg: float = 1.0
    correct: str = "each"
    max_pushes: int = 10
    #: How pushes are chosen (``bt_arrange.plan.choices.PushStrategy``): paper, learned or diagonal.
    strategy: str = "paper"
    seed: int = 0
    starts: list[ObjectStart] | None = None
    raw: dict[str, Any] = field(default_factory=dict, repr=False)
    #: The plan's ``[puzzle.NAME]`` tables (``bt_arrange.puzzle.PuzzleSpec``): slabs solved from the camera alone.
    puzzles: list[Any] = field(default_factory=list)

    def create_root(
        self,
        threshold_mm: float | None = None,
        max_pushes: int | None = None,
        correct: str | None = None,
        yaw_threshold_deg: float | None = None,
    ) -> Any:
        """The arrangement tree; options given here override the file's."""
        from bt_arrange.trees import arrangement

        try:
            root = arrangement(
                self.targets,
                threshold_mm=self.threshold_mm if threshold_mm is None else threshold_mm,
                max_pushes=self.max_pushes if max_pushes is None else max_pushes,
                correct=self.correct if correct is None else correct,
                yaw_threshold_deg=self.yaw_threshold_deg if yaw_threshold_deg is None else yaw_threshold_deg,
                strategy=self.strategy,
                colours=self.colours,
                puzzles=self.puzzles,
            )
        except PlanError as error:
            raise self.source.locate(error) from error
        except BtArrangeError as error:
            raise PlanError(f"{self.path}: {error}") from error
        # The run's plan check (the camera's view, the scene, the colours) names this file's entries too.
        root.source = self.source
        # An XML export of the tree starts its parts as the plan does.
        root.scene_seed, root.starts = self.seed, self.starts
        return root

    @property
    def source(self) -> PlanSource:
        """The file and, for each target, start and colour of the plan, its entry (``[[targets]] 3``)."""
        from bt_arrange.plan.check import PlanSource

        entries: dict[tuple[str, str], str] = {}
        for index, target in enumerate(self.targets, start=1):
            entries[("target", target.obj)] = f"[[targets]] {index}"
            entries.setdefault(("colour", target.colour), f"[[targets]] {index} (colour = {_shown(target.colour)})")
        for index, start in enumerate(self.starts or [], start=1):
            entries[("start", start.name or start.colour)] = f"[[scene.starts]] {index}"
        for name in self.raw.get("colours", {}) if isinstance(self.raw.get("colours"), dict) else ():
            entries[("colour", name)] = f"[colours.{name}]"
        frescoes = self.raw.get("fresco", {}) if isinstance(self.raw.get("fresco"), dict) else {}
        pieces = {}
        for fresco in frescoes:
            for target in self.targets:
                if target.obj.startswith(f"{fresco} ") and target.obj[len(fresco) + 1 :].isdigit():
                    pieces[target.obj] = f"[fresco.{fresco}] piece {target.obj[len(fresco) + 1 :]}"
        for target in self.targets:
            if target.obj in pieces:
                entries[("target", target.obj)] = pieces[target.obj]
        for name in self.object_types:
            if name in pieces:
                entries[("object", name)] = pieces[name]
            elif name != "cube":
                entries[("object", name)] = f"[objects.{name}]"
        return PlanSource(str(self.path), entries)

    def create_scene(self, seed: int | None = None, backend: Backend | None = None) -> list[ObjectStart]:
        """Where the parts start: the file's ``[[scene.starts]]``, or scattered from ``seed`` by ``backend``.

        ``backend`` is the one the run uses; without one, the default backend (loaded only then).
        """
        if self.starts is not None and not self.puzzles:
            return list(self.starts)
        from bt_arrange.backends import PuzzleBackend, ScatteringBackend, require

        chosen = self.seed if seed is None else seed
        if backend is None:
            from bt_arrange import backends

            backend = backends.load()
        try:
            if self.puzzles:
                # The slab is broken and its pieces scattered by the backend alone: the tree never learns how.
                puzzles = require(backend, PuzzleBackend, "break a [puzzle] slab")
                return list(puzzles.puzzle_scene(self.targets, self.puzzles, chosen, starts=self.starts))
            scattering = require(backend, ScatteringBackend, "scatter a plan's parts")
            return list(
                scattering.scatter(
                    [t.colour for t in self.targets],
                    chosen,
                    avoid=self.targets,
                    object_types=[t.object_type for t in self.targets],
                    names=[t.name for t in self.targets],
                )
            )
        except BtArrangeError as error:
            raise PlanError(f"{self.path}: [scene] seed {chosen}: {error}") from error


def load(path: str | Path) -> Plan:
    """Read and check the plan file at ``path``; a ``PlanError`` names the file, the entry and the problem."""
    path = Path(path)
    try:
        text = read_limited(path, "plan file", PlanError)
    except FileNotFoundError:
        raise PlanError(f"plan file {path} not found") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise PlanError(f"{path}: not TOML: {error}") from None
    except RecursionError:
        raise PlanError(f"{path}: not TOML a plan can hold: its arrays or tables nest too deep") from None
    plan = _Reader(path).read(data)
    plan.create_root()  # every check of the tree builder (reach, layout, thresholds) now, before anything moves
    return plan


def load_module(path: str | Path) -> ModuleType:
    """A plan file as a tree-file module: ``create_root()``, ``create_scene(seed)`` and ``plan``."""
    plan = load(path)
    module = ModuleType(f"bt_arrange_plan_{Path(path).stem}")
    module.__file__ = str(path)
    module.plan = plan  # type: ignore[attr-defined]
    module.create_root = plan.create_root  # type: ignore[attr-defined]
    module.create_scene = plan.create_scene  # type: ignore[attr-defined]
    #: The seed ``bt-arrange run`` uses when no --seed is given.
    module.default_seed = plan.seed  # type: ignore[attr-defined]
    return module


class _Reader:
    """Turns the parsed TOML into a Plan, naming the file and the entry in every error."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def fail(self, where: str, problem: str) -> PlanError:
        return PlanError(f"{self.path}: {where}: {problem}")

    def keys(self, table: Any, known: Sequence[str], where: str) -> dict[str, Any]:
        if not isinstance(table, dict):
            raise self.fail(where, f"must be a table, got {_shown(table)}")
        for key in table:
            if key not in known:
                raise self.fail(where, f"unknown key {key!r}{did_you_mean(key, known)} (known: {', '.join(known)})")
        return table

    def number(self, value: Any, where: str, name: str, *, positive: bool = False) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise self.fail(where, f"{name} = {_shown(value)} is not a number")
        if positive and value <= 0:
            raise self.fail(where, f"{name} = {_shown(value)} must be positive")
        return float(value)

    def pair(self, value: Any, where: str, name: str) -> tuple[float, float]:
        if not isinstance(value, list) or len(value) != 2:
            raise self.fail(where, f"{name} = {_shown(value)} is not a [low, high] pair")
        low, high = (self.number(v, where, name) for v in value)
        return low, high

    def read(self, data: dict[str, Any]) -> Plan:
        self.keys(data, TOP_KEYS, "the top level")
        options: dict[str, Any] = {}
        for key in ("threshold_mm", "yaw_threshold_deg"):
            if key in data:
                options[key] = self.number(data[key], "the top level", key, positive=True)
        if "correct" in data:
            if data["correct"] not in ("each", "after_all"):
                raise self.fail("the top level", f'correct = {_shown(data["correct"])}: choose "each" or "after_all"')
            options["correct"] = data["correct"]
        if "max_pushes" in data:
            value = data["max_pushes"]
            if isinstance(value, bool) or not isinstance(value, int) or value < 0:
                raise self.fail("the top level", f"max_pushes = {_shown(value)} is not a whole number, 0 or more")
            options["max_pushes"] = value
        if "strategy" in data:
            choices = [strategy.value for strategy in PushStrategy]
            if data["strategy"] not in choices:
                raise self.fail(
                    "the top level",
                    f"strategy = {_shown(data['strategy'])}: choose " + ", ".join(f'"{c}"' for c in choices),
                )
            options["strategy"] = data["strategy"]
        types = self.object_types(data.get("objects", {}))
        colours = self.colour_table(data.get("colours", {}))
        if "targets" not in data and "fresco" not in data and "puzzle" not in data:
            raise self.fail(
                "the top level", "no [[targets]], no [fresco.NAME] and no [puzzle.NAME]: a plan needs at least one"
            )
        targets = self.targets(data["targets"], types, colours) if "targets" in data else []
        threshold_mm = options.get("threshold_mm", Plan.threshold_mm)
        for kind, target in self.frescoes(data.get("fresco", {}), types, colours, targets, threshold_mm):
            types[kind.name] = kind
            targets.append(target)
        taken = {t.obj for t in targets} | set(types)
        puzzles = read_puzzles(self, data.get("puzzle", {}), colours, taken, LOOKS_LIKE_METRES_MM)
        colours = painted_colours(self, puzzles, targets, colours)
        seed, starts = self.scene(data.get("scene", {}), types, colours, targets)
        return Plan(self.path, targets, colours, types, seed=seed, starts=starts, raw=data, puzzles=puzzles, **options)

    def object_types(self, table: Any) -> dict[str, ObjectType]:
        types = {"cube": CUBE}
        if not isinstance(table, dict):
            raise self.fail("[objects]", f"must be a table of types, got {_shown(table)}")
        if len(table) > MAX_OBJECT_TYPES:
            raise self.fail(
                "[objects]",
                f"{len(table):,} types, over the limit of {MAX_OBJECT_TYPES} (bt_arrange.filelimits.MAX_OBJECT_TYPES)",
            )
        outlines = [entry.get("outline_mm") for entry in table.values() if isinstance(entry, dict)]
        counts = [len(outline) for outline in outlines if isinstance(outline, list)]
        if sum(counts) > MAX_PLAN_OUTLINE_POINTS and max(counts) <= MAX_OUTLINE_POINTS:
            raise self.fail(
                "[objects]",
                f"{sum(counts):,} outline points in all, over the limit of {MAX_PLAN_OUTLINE_POINTS} "
                "(bt_arrange.filelimits.MAX_PLAN_OUTLINE_POINTS)",
            )
        for name, entry in table.items():
            where = f"[objects.{name}]"
            self.keys(entry, OBJECT_KEYS, where)
            if name == "cube":
                raise self.fail(where, "'cube' is built in (50 x 50 x 50 mm): name your type otherwise")
            if "outline_mm" in entry or "height_mm" in entry:
                types[name] = self.prism_type(name, entry, where)
                continue
            if "size_mm" not in entry:
                raise self.fail(where, "missing size_mm = [x, y, z] (or outline_mm = [[x, y], ...] and height_mm)")
            size = entry["size_mm"]
            if not isinstance(size, list) or len(size) != 3:
                raise self.fail(where, f"size_mm = {_shown(size)} is not three numbers [x, y, z] in mm")
            edges = [self.number(v, where, "size_mm") for v in size]
            if min(edges) <= 0:
                raise self.fail(where, f"size_mm = {_shown(size)} has an edge that is not positive")
            if max(edges) < LOOKS_LIKE_METRES_MM:
                raise self.fail(
                    where,
                    f"size_mm = {_shown(size)} looks like metres: the plan is in millimetres "
                    f"(size_mm = [{', '.join(f'{v * 1000:g}' for v in edges)}])",
                )
            mass = self.number(entry["mass_kg"], where, "mass_kg", positive=True) if "mass_kg" in entry else None
            friction = self.number(entry["friction"], where, "friction", positive=True) if "friction" in entry else None
            try:
                types[name] = ObjectType(name, (edges[0] / 1000, edges[1] / 1000, edges[2] / 1000), mass, friction)
            except PlanError as error:
                raise self.fail(where, str(error)) from None
        return types

    def prism_type(self, name: str, entry: dict[str, Any], where: str) -> ObjectType:
        """A part type of any simple outline: ``outline_mm = [[x, y], ...]`` and ``height_mm``."""
        if "size_mm" in entry:
            raise self.fail(where, "give size_mm (a cuboid) or outline_mm and height_mm (a prism), not both")
        for key in ("outline_mm", "height_mm"):
            if key not in entry:
                raise self.fail(where, f"missing {key}: a prism needs outline_mm = [[x, y], ...] and height_mm")
        outline = entry["outline_mm"]
        if not isinstance(outline, list) or not all(isinstance(p, list) and len(p) == 2 for p in outline):
            raise self.fail(where, f"outline_mm = {_shown(outline)} is not a list of [x, y] points in mm")
        points = [[self.number(v, where, "outline_mm") / 1000 for v in point] for point in outline]
        height_m = self.number(entry["height_mm"], where, "height_mm", positive=True) / 1000
        mass = self.number(entry["mass_kg"], where, "mass_kg", positive=True) if "mass_kg" in entry else None
        friction = self.number(entry["friction"], where, "friction", positive=True) if "friction" in entry else None
        try:
            return ObjectType(name, None, mass, friction, shape=Prism.from_outline(points, height_m))
        except PlanError as error:
            raise self.fail(where, str(error)) from None

    def frescoes(
        self, table: Any, types: dict[str, ObjectType], colours: ColourTable, targets: list[Any], threshold_mm: float
    ) -> list[tuple[ObjectType, Any]]:
        """Each ``[fresco.NAME]``'s pieces: a type and a target per piece, ``NAME 1`` ... ``NAME N``.

        The gap along its fractures must keep two pieces each within ``threshold_mm`` apart (twice it).
        """
        if not isinstance(table, dict):
            raise self.fail("[fresco]", f"must be a table of frescoes, got {_shown(table)}")
        taken = {t.obj for t in targets}
        out: list[tuple[ObjectType, Any]] = []
        for name, entry in table.items():
            where = f"[fresco.{name}]"
            self.keys(entry, FRESCO_KEYS, where)
            if not name.strip() or "/" in name:
                raise self.fail(where, "a fresco's name must be a non-empty text without '/'")
            for key in ("size_mm", "pieces", "colour", "x_mm", "y_mm"):
                if key not in entry:
                    raise self.fail(where, f"missing {key}")
            size = entry["size_mm"]
            if not isinstance(size, list) or len(size) != 3:
                raise self.fail(where, f"size_mm = {_shown(size)} is not three numbers [length, width, height] in mm")
            edges = [self.number(v, where, "size_mm", positive=True) for v in size]
            if max(edges) < LOOKS_LIKE_METRES_MM:
                raise self.fail(
                    where,
                    f"size_mm = {_shown(size)} looks like metres: the plan is in millimetres "
                    f"(size_mm = [{', '.join(f'{v * 1000:g}' for v in edges)}])",
                )
            pieces = entry["pieces"]
            if isinstance(pieces, bool) or not isinstance(pieces, int) or not MIN_PIECES <= pieces <= MAX_PIECES:
                raise self.fail(where, f"pieces = {_shown(pieces)}: a fresco breaks into {MIN_PIECES} to {MAX_PIECES}")
            least_mm = ManipulationSettings().gap_for_threshold_m(threshold_mm) * 1000
            gap_mm = self.number(entry.get("gap_mm", DEFAULT_TARGET_GAP_M * 1000), where, "gap_mm")
            if gap_mm < least_mm - 1e-9:
                raise self.fail(
                    where,
                    f"gap_mm = {_shown(entry['gap_mm'])}: two pieces each within the threshold ({threshold_mm:g} mm) "
                    f"must not touch, so the gap along a fracture must be at least {least_mm:g} mm (twice the "
                    f"threshold, {MIN_GAP_M * 1000:g} mm at the finest)",
                )
            seed = entry.get("seed", 0)
            if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
                raise self.fail(where, f"seed = {_shown(seed)} is not a whole number, 0 or more")
            colour = entry["colour"]
            if not isinstance(colour, str) or colour not in colours:
                raise self.fail(
                    where,
                    f"unknown colour {_shown(colour)}{did_you_mean(str(colour), colours.names)}: not in the table "
                    f"({', '.join(colours.names)}) and no [colours.NAME] with rgb",
                )
            x_mm = self.number(entry["x_mm"], where, "x_mm")
            y_mm = self.number(entry["y_mm"], where, "y_mm")
            yaw_deg = self.number(entry.get("yaw_deg", 0.0), where, "yaw_deg")
            if 0.0 < max(abs(x_mm), abs(y_mm)) < LOOKS_LIKE_METRES_MM:
                raise self.fail(
                    where,
                    f"x_mm = {_shown(entry['x_mm'])}, y_mm = {_shown(entry['y_mm'])} look like metres: the plan is "
                    f"in millimetres (x_mm = {x_mm * 1000:g}, y_mm = {y_mm * 1000:g})",
                )
            try:
                broken = fracture(
                    (edges[0] / 1000, edges[1] / 1000, edges[2] / 1000),
                    pieces,
                    gap_mm / 1000,
                    seed,
                    (x_mm / 1000, y_mm / 1000, math.radians(yaw_deg)),
                )
            except PlanError as error:
                raise self.fail(where, str(error)) from None
            for piece in broken:
                piece_name = f"{name} {piece.index}"
                if piece_name in types or piece_name in taken:
                    raise self.fail(where, f"its piece {piece_name!r} has the name of another type or target")
                try:
                    kind = ObjectType(piece_name, shape=piece.prism)
                except PlanError as error:
                    raise self.fail(where, f"piece {piece.index}: {error}") from None
                target = Target(colour, piece.x_m, piece.y_m, piece.yaw_rad, name=piece_name, object_type=kind)
                out.append((kind, target))
                taken.add(piece_name)
        return out

    def colour_table(self, table: Any) -> ColourTable:
        return read_colour_table(self, table)

    def entry(
        self,
        entry: Any,
        where: str,
        types: dict[str, ObjectType],
        colours: ColourTable,
        known: Sequence[str] = TARGET_KEYS,
    ) -> tuple[ObjectType, str, float, float, float, str | None]:
        self.keys(entry, known, where)
        type_name = entry.get("object", "cube")
        if not isinstance(type_name, str) or type_name not in types:
            raise self.fail(
                where,
                f"unknown object type {_shown(type_name)}{did_you_mean(type_name, types)} "
                f"(known: {', '.join(types)}; add [objects.NAME])",
            )
        if "colour" not in entry:
            raise self.fail(where, "missing colour")
        colour = entry["colour"]
        if not isinstance(colour, str) or colour not in colours:
            raise self.fail(
                where,
                f"unknown colour {_shown(colour)}{did_you_mean(colour, colours.names)}: not in the table "
                f"({', '.join(colours.names)}) and no [colours.NAME] with rgb",
            )
        for key in ("x_mm", "y_mm"):
            if key not in entry:
                raise self.fail(where, f"missing {key}")
        x_mm = self.number(entry["x_mm"], where, "x_mm")
        y_mm = self.number(entry["y_mm"], where, "y_mm")
        yaw_deg = self.number(entry.get("yaw_deg", 0.0), where, "yaw_deg")
        if 0.0 < max(abs(x_mm), abs(y_mm)) < LOOKS_LIKE_METRES_MM:
            raise self.fail(
                where,
                f"x_mm = {_shown(entry['x_mm'])}, y_mm = {_shown(entry['y_mm'])} look like metres: the plan is in "
                f"millimetres (x_mm = {x_mm * 1000:g}, y_mm = {y_mm * 1000:g})",
            )
        if max(abs(x_mm), abs(y_mm)) > LOOKS_LIKE_MILLIMETRES_M * 1000:
            raise self.fail(
                where,
                f"x_mm = {_shown(entry['x_mm'])}, y_mm = {_shown(entry['y_mm'])} lie "
                f"{max(abs(x_mm), abs(y_mm)) / 1000:g} m from the table's origin: beyond any arm's reach",
            )
        name = entry.get("name")
        if name is not None and (not isinstance(name, str) or not name.strip() or "/" in name):
            raise self.fail(where, f"name = {_shown(name)} must be a non-empty text without '/'")
        return types[type_name], colour, x_mm / 1000, y_mm / 1000, math.radians(yaw_deg), name

    def z_m(self, entry: dict[str, Any], where: str) -> float:
        """A target's ``z_mm`` (its bottom face above the table; default 0) in metres."""
        if "z_mm" not in entry:
            return 0.0
        z_mm = self.number(entry["z_mm"], where, "z_mm")
        if z_mm < 0:
            raise self.fail(where, f"z_mm = {_shown(entry['z_mm'])}: a part's bottom face cannot lie below the table")
        if 0.0 < z_mm < LOOKS_LIKE_METRES_MM:
            raise self.fail(where, f"z_mm = {_shown(entry['z_mm'])} looks like metres: the plan is in millimetres")
        if z_mm > LOOKS_LIKE_MILLIMETRES_M * 1000:
            raise self.fail(where, f"z_mm = {_shown(entry['z_mm'])} is {z_mm / 1000:g} m up: beyond any arm's reach")
        return z_mm / 1000

    def targets(self, entries: Any, types: dict[str, ObjectType], colours: ColourTable) -> list[Any]:

        if not isinstance(entries, list) or not entries:
            raise self.fail("[[targets]]", "must be a list of targets with at least one entry")
        if len(entries) > MAX_TARGETS:
            raise self.fail(
                "[[targets]]",
                f"{len(entries)} targets, over the limit of {MAX_TARGETS} (bt_arrange.filelimits.MAX_TARGETS)",
            )
        read = [self.entry(entry, f"[[targets]] {i}", types, colours) for i, entry in enumerate(entries, start=1)]
        heights_m = [self.z_m(entry, f"[[targets]] {i}") for i, entry in enumerate(entries, start=1)]
        counts: dict[str, int] = {}
        for _, colour, *_ in read:
            counts[colour] = counts.get(colour, 0) + 1
        numbers: dict[str, int] = {}
        targets = []
        for (kind, colour, x_m, y_m, yaw_rad, name), z_m in zip(read, heights_m, strict=True):
            if name is None and counts[colour] > 1:
                numbers[colour] = numbers.get(colour, 0) + 1
                name = f"{colour} {numbers[colour]}"
            targets.append(Target(colour, x_m, y_m, yaw_rad, name=name, object_type=kind, z_m=z_m))
        return targets

    def scene(
        self, table: Any, types: dict[str, ObjectType], colours: ColourTable, targets: list[Any]
    ) -> tuple[int, list[ObjectStart] | None]:
        self.keys(table, SCENE_KEYS, "[scene]")
        seed = table.get("seed", 0)
        if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
            raise self.fail("[scene]", f"seed = {_shown(seed)} is not a whole number, 0 or more")
        if "starts" not in table:
            return seed, None
        entries = table["starts"]
        if not isinstance(entries, list):
            raise self.fail("[[scene.starts]]", "must be a list of starts")
        if len(entries) > MAX_TARGETS:
            raise self.fail(
                "[[scene.starts]]",
                f"{len(entries)} starts, over the limit of {MAX_TARGETS} (bt_arrange.filelimits.MAX_TARGETS)",
            )
        # A start without a name takes the name of the next target of its kind, in order.
        names_by_kind: dict[tuple[str, str], list[str]] = {}
        for target in targets:
            names_by_kind.setdefault((target.object_type.name, target.colour), []).append(target.obj)
        starts = []
        for index, entry in enumerate(entries, start=1):
            where = f"[[scene.starts]] {index}"
            kind, colour, x_m, y_m, yaw_rad, name = self.entry(entry, where, types, colours, START_KEYS)
            if name is None:
                waiting = names_by_kind.get((kind.name, colour), [])
                name = waiting.pop(0) if waiting else None
            starts.append(ObjectStart(colour, x_m, y_m, yaw_rad, name, kind))
        return seed, starts
