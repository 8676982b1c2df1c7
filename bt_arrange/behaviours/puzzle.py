"""Behaviours of a puzzle: see the unknown pieces, solve where each goes.

``SurveyPieces`` photographs the table (the arm parked) and measures the top-face outline of every
piece of the puzzle's colour from the image alone (``bt_arrange.perception.outline_unknown``),
naming them ``NAME 1`` ... ``NAME N`` by where they lie (along x, then y): it writes
``/NAME/pieces``. ``SolvePuzzle`` reads them and solves the puzzle from the outlines alone
(``bt_arrange.puzzle.solve``); it writes ``/NAME/solved``, each piece's target with its measured
outline as its type, and ``/NAME/solve_s``, the solve's process time. Neither reads the world:
the camera is their only input.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass

from bt_arrange.behaviours import keys
from bt_arrange.behaviours.base import InstantStage, Stage, StagedBehaviour
from bt_arrange.behaviours.context import Context
from bt_arrange.behaviours.looking import Detect, is_parked, park_stage
from bt_arrange.errors import BtArrangeError
from bt_arrange.geometry import FloatArray
from bt_arrange.objects import ObjectType
from bt_arrange.ports import Port, PortType
from bt_arrange.puzzle.spec import PuzzleSpec, format_spec, parse_spec
from bt_arrange.shapes.polygon import centroid_m

#: The port every node of a puzzle takes: the puzzle's whole (its spec), as text.
PUZZLE_PORT = Port(
    "puzzle",
    PortType("Puzzle", parse_spec, format_spec),
    description="name;length_m,width_m,height_m;pieces;gap_m;colour;x_m,y_m,yaw_rad",
)
#: ``/<puzzle>/pieces``: the pieces the camera measured (``MeasuredPiece``s, in the order of their names).
PIECES = "pieces"
#: ``/<puzzle>/solved``: each piece's ``Target`` where the solve puts it (its measured outline as its type).
SOLVED = "solved"
#: ``/<puzzle>/solve_s``: the solve's process time, seconds.
SOLVE_S = "solve_s"


@dataclass(frozen=True)
class SurveyedPiece:
    """A piece as the camera saw it before anything moved: its name, top-face outline (table, metres), centre."""

    name: str
    outline_m: FloatArray
    centre_m: tuple[float, float]
    edge_colours: tuple[FloatArray, ...] = ()


class DetectSurveyed(Detect):
    """Detect a puzzle's piece where the survey saw it, until it is first placed; at its target after.

    A puzzle's pieces share a colour and their measured outlines may fit each other's faces within
    the registration's tolerance: looked for in a window around where it lies, a piece is the only
    face there.
    """

    def __init__(
        self, name: str, obj: str, colour: str, object_type: ObjectType, surveyed_xy_m: tuple[float, float]
    ) -> None:
        super().__init__(name, obj, colour, object_type)
        self.surveyed_xy_m = surveyed_xy_m
        self.reads(keys.key(obj, keys.TARGET), keys.key(obj, keys.PLACED_OFFSET_MM))

    def expected_xy_m(self) -> tuple[float, float] | None:
        """Where the survey saw it, before it was placed; its target after (a regrasp)."""
        if not self.blackboard.exists(keys.key(self.obj, keys.PLACED_OFFSET_MM)):
            return self.surveyed_xy_m
        target = (
            self.blackboard.get(keys.key(self.obj, keys.TARGET))
            if self.blackboard.exists(keys.key(self.obj, keys.TARGET))
            else None
        )
        return None if target is None else (target.x_m, target.y_m)


class PuzzleNode(StagedBehaviour):
    """A behaviour of one puzzle: built from its ``puzzle`` port (XML) or its ``PuzzleSpec``."""

    @classmethod
    def provided_ports(cls) -> tuple[Port, ...]:
        """The puzzle's whole (BehaviorTree.CPP's ``providedPorts``)."""
        return (PUZZLE_PORT,)

    @classmethod
    def from_ports(cls, name: str, values: dict[str, object], children: Sequence[object]) -> PuzzleNode:
        """The node of an XML tree."""
        spec = values["puzzle"]
        assert isinstance(spec, PuzzleSpec)
        return cls(name, spec)

    def __init__(self, name: str, spec: PuzzleSpec) -> None:
        super().__init__(name)
        self.spec = spec
        self.obj = spec.name

    def port_values(self) -> dict[str, object]:
        """The port's value read back (the XML writer)."""
        return {"puzzle": self.spec}


class SurveyPieces(PuzzleNode):
    """Measure every piece of a puzzle on the table from one photograph; FAILURE says what the camera could not tell.

    The count must be the puzzle's: fewer or more pieces (one hidden, two touching, another part of
    the colour) is a FAILURE naming what was seen.
    """

    #: The node's description in the XML ``TreeNodesModel``.
    node_description = "camera -> /<puzzle>/pieces: unknown outlines measured"

    def __init__(self, name: str, spec: PuzzleSpec) -> None:
        super().__init__(name, spec)
        self.pieces: tuple[SurveyedPiece, ...] = ()
        self.writes(keys.key(spec.name, PIECES))

    def stages(self, context: Context) -> list[Stage]:
        """Park if needed, then photograph and measure."""
        context.detector.colours[self.spec.colour]  # raises PerceptionError for an unknown colour
        looking = InstantStage(f"look for the pieces of {self.spec.name}", self._survey)
        return [looking] if is_parked(context) else [park_stage(), looking]

    def _survey(self, context: Context) -> str | None:
        from bt_arrange.perception.outline_unknown import measure_unknown_outlines

        camera = context.robot.camera
        plane_z_m = context.detector.config.table_z_m + self.spec.height_m
        outlines, problems = measure_unknown_outlines(
            context.detector, camera.capture(), self.spec.colour, plane_z_m, painted=self.spec.picture is not None
        )
        if problems:
            return f"{self.spec.name}: {problems[0]}"
        if len(outlines) != self.spec.pieces:
            return (
                f"{self.spec.name}: the camera sees {len(outlines)} pieces of {self.spec.colour}, "
                f"the puzzle has {self.spec.pieces}"
            )
        found = [(m, (float(c[0]), float(c[1]))) for m in outlines for c in [centroid_m(m.outline_m)]]
        # Numbered by where they lie, so that a run's names are the same from the same scene.
        found.sort(key=lambda item: (round(item[1][0], 3), round(item[1][1], 3)))
        self.pieces = tuple(
            SurveyedPiece(name, m.outline_m, centre, tuple(getattr(m, "edge_colours", ())))
            for name, (m, centre) in zip(self.spec.piece_names, found, strict=True)
        )
        self.write(keys.key(self.spec.name, PIECES), self.pieces)
        return None

    def success_message(self) -> str:
        """Feedback: how many pieces and their vertices."""
        counts = ", ".join(str(len(p.outline_m)) for p in self.pieces)
        return f"{len(self.pieces)} pieces of {self.spec.name} measured ({counts} vertices)"


class SolvePuzzle(PuzzleNode):
    """Solve the puzzle from the surveyed outlines alone; FAILURE names the pieces when it cannot, or cannot choose."""

    #: The node's description in the XML ``TreeNodesModel``.
    node_description = "/<puzzle>/pieces -> /<puzzle>/solved: where each piece goes"

    def __init__(self, name: str, spec: PuzzleSpec) -> None:
        super().__init__(name, spec)
        self.solved: tuple[object, ...] = ()
        self.solve_s = math.nan
        self.reads(keys.key(spec.name, PIECES), written_by=f"SurveyPieces of {spec.name}")
        self.writes(keys.key(spec.name, SOLVED), keys.key(spec.name, SOLVE_S))

    def stages(self, context: Context) -> list[Stage]:
        """One step: the solve (computation only; the arm does not move)."""
        return [InstantStage(f"solve {self.spec.name}", self._solve)]

    def _solve(self, context: Context) -> str | None:
        from bt_arrange.plan.puzzle_targets import solved_targets

        pieces: Sequence[SurveyedPiece] = self.read(keys.key(self.spec.name, PIECES), "SurveyPieces")
        started = time.process_time()
        try:
            self.solved = tuple(solved_targets(self.spec, pieces, context.settings))
        except BtArrangeError as error:
            return f"{self.spec.name}: {error}"
        finally:
            self.solve_s = time.process_time() - started
        self.write(keys.key(self.spec.name, SOLVED), self.solved)
        self.write(keys.key(self.spec.name, SOLVE_S), self.solve_s)
        return None

    def success_message(self) -> str:
        """Feedback: solved, and how long it took."""
        return f"{self.spec.name} solved: {len(self.solved)} pieces placed in the whole in {self.solve_s:.2f} s"


__all__ = [
    "DetectSurveyed",
    "PIECES",
    "PUZZLE_PORT",
    "SOLVED",
    "SOLVE_S",
    "PuzzleNode",
    "SolvePuzzle",
    "SurveyPieces",
    "SurveyedPiece",
]
