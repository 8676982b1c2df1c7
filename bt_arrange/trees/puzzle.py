"""The subtree of a puzzle: survey the pieces, solve the puzzle, arrange what the solve found.

Its shape::

    ArrangePuzzle "reassemble slab"
    ├── SurveyPieces "survey slab"        camera -> /slab/pieces (outlines nobody gave)
    ├── SolvePuzzle "solve slab"          /slab/pieces -> /slab/solved (targets from the outlines alone)
    └── ArrangeSolved "arrange slab"      built once solved: Algorithm 1 per piece, as a fresco's

``ArrangeSolved`` builds its children when it first runs, from ``/slab/solved``, with the very
builder of a plan's arrangement (``bt_arrange.trees.arrangement``): the layout among neighbours,
the staged releases, the corrections and the looks again are a fresco's. The solved targets join
the root ``Arrangement``'s plan then, so the report, the live view and the records name every piece.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import py_trees
from py_trees.common import Status

from bt_arrange.behaviours import Detect, keys
from bt_arrange.behaviours.puzzle import PIECES, PUZZLE_PORT, SOLVED, DetectSurveyed, SolvePuzzle, SurveyPieces
from bt_arrange.checks import positive_number
from bt_arrange.errors import BtArrangeError, XmlTreeError
from bt_arrange.plan.compiled import ArrangementPlan, compile_plan
from bt_arrange.plan.targets import check_threshold
from bt_arrange.plan.tolerance import Tolerance
from bt_arrange.ports import DOUBLE, INT, OFF_DOUBLE, STRING, Port
from bt_arrange.puzzle.spec import PuzzleSpec
from bt_arrange.trees.arrangement import render_targets

#: The options of ``bt_arrange.trees.arrangement`` an ``ArrangeSolved`` builds its pieces' subtrees with.
OPTIONS = ("threshold_mm", "yaw_threshold_deg", "max_pushes", "max_regrasps", "strategy", "keep_going")


class ArrangeSolved(py_trees.composites.Sequence):
    """Arrange the pieces where the solve put them: its children are built from ``/<puzzle>/solved`` when it first runs.

    ``options`` are the keyword arguments of ``bt_arrange.trees.arrangement`` the puzzle's plan was
    built with (``OPTIONS``: thresholds, pushes, strategy); the colours and the handling settings are
    the root ``Arrangement``'s. A solved plan the arrangement refuses (two pieces' targets too close,
    one out of reach) is a FAILURE saying so. In XML its children are never written: they are built.
    """

    #: In XML a leaf: what runs inside it is decided by the solve, so no file can list it.
    node_category = "Action"
    #: The node's description in the XML ``TreeNodesModel``.
    node_description = "/<puzzle>/solved -> Algorithm 1 per piece (children built when it first runs)"

    @classmethod
    def provided_ports(cls) -> tuple[Port, ...]:
        """The puzzle and the options its pieces are arranged with (BehaviorTree.CPP's ``providedPorts``)."""
        return (
            PUZZLE_PORT,
            Port("threshold_mm", DOUBLE, 1.0, "each piece's accuracy threshold [mm]"),
            Port("yaw_threshold_deg", OFF_DOUBLE, 1.0, "each piece's yaw threshold [deg] (0: position only)"),
            Port("max_pushes", INT, 10, "pushes per piece at most"),
            Port("max_regrasps", INT, 3, "picks again per piece at most"),
            Port("strategy", STRING, "paper", "the pushes: paper, learned or diagonal"),
        )

    @classmethod
    def from_ports(cls, name: str, values: dict[str, Any], children: list[Any]) -> ArrangeSolved:
        """The node of an XML tree: without children, which the solve decides."""
        if children:
            raise XmlTreeError(f"<ArrangeSolved name={name!r}> takes no children: they are built from the solve")
        spec = values.pop("puzzle")
        return cls(name, spec, values)

    def port_values(self) -> dict[str, Any]:
        """The ports read back (the XML writer)."""
        return {"puzzle": self.spec, **{k: self.options[k] for k in OPTIONS if k != "keep_going"}}

    def __init__(self, name: str, spec: PuzzleSpec, options: dict[str, Any]) -> None:
        super().__init__(name=name, memory=True, children=[])
        self.spec = spec
        self.obj = spec.name
        unknown = set(options) - set(OPTIONS)
        if unknown:
            raise BtArrangeError(f"ArrangeSolved: unknown options {', '.join(sorted(unknown))}")
        self.options: dict[str, Any] = {
            "threshold_mm": 1.0,
            "yaw_threshold_deg": 1.0,
            "max_pushes": 10,
            "max_regrasps": 3,
        }
        self.options.update({"strategy": "paper", "keep_going": True, **options})
        self._setup_kwargs: dict[str, Any] = {}
        #: The solved pieces' targets, once the children are built from them.
        self.arranged: tuple[Any, ...] = ()
        self.blackboard = self.attach_blackboard_client(name=name)
        self.blackboard.register_key(keys.key(spec.name, SOLVED), access=py_trees.common.Access.READ)
        self.blackboard.register_key(keys.key(spec.name, PIECES), access=py_trees.common.Access.READ)

    def setup(self, **kwargs: Any) -> None:
        """Keep what the tree's setup hands out (the context): the children built later receive it too."""
        self._setup_kwargs = dict(kwargs)

    def tick(self) -> Iterator[py_trees.behaviour.Behaviour]:
        """Build the children on the first tick, then tick them as a sequence with memory."""
        if self.status != Status.RUNNING and not self.children:
            problem = self._build()
            if problem is not None:
                self.feedback_message = problem
                self.stop(Status.FAILURE)
                yield self
                return
        yield from super().tick()

    def _surveyed(self) -> dict[str, tuple[float, float]]:
        """Where the survey saw each piece (its centre on the table)."""
        pieces = (
            self.blackboard.get(keys.key(self.spec.name, PIECES))
            if self.blackboard.exists(keys.key(self.spec.name, PIECES))
            else ()
        )
        return {piece.name: piece.centre_m for piece in pieces}

    def _build(self) -> str | None:
        solved_key = keys.key(self.spec.name, SOLVED)
        if not self.blackboard.exists(solved_key):
            return f"{self.spec.name}: not solved (no {solved_key})"
        targets = list(self.blackboard.get(solved_key))
        root: py_trees.behaviour.Behaviour = self
        while root.parent is not None:
            root = root.parent
        # The whole tree's plan (its colours and settings) when the root carries one: a rendered arrangement.
        whole: ArrangementPlan | None = getattr(root, "plan", None)
        surveyed = self._surveyed()

        def locate(target: Any) -> py_trees.behaviour.Behaviour:
            if target.obj not in surveyed:  # solved by hand (a test, a user's tree): found as any part is
                return Detect(f"detect {target.obj}", target.obj, target.colour, target.object_type)
            return DetectSurveyed(
                f"detect {target.obj}", target.obj, target.colour, target.object_type, surveyed[target.obj]
            )

        options: dict[str, Any] = dict(self.options)
        try:
            threshold_mm = check_threshold(options.pop("threshold_mm"), whole.settings if whole else None)
            yaw_threshold_deg = options.pop("yaw_threshold_deg")
            if yaw_threshold_deg is not None:
                positive_number("yaw_threshold_deg", yaw_threshold_deg, "deg")
            shared: dict[str, Any] = {"colours": whole.colours, "settings": whole.settings} if whole else {}
            plan = compile_plan(targets, Tolerance(threshold_mm, yaw_threshold_deg), **options, **shared)
        except BtArrangeError as error:
            return f"{self.spec.name}: the solved places cannot be arranged: {error}"
        for child in render_targets(plan, locate):
            self.add_child(child)
            for node in child.iterate():
                node.setup(**self._setup_kwargs)
        #: The solved pieces' targets this node arranges (a run's report reads them).
        self.arranged = tuple(targets)
        if whole is not None:
            root.plan = whole.joined(targets)  # type: ignore[attr-defined]
        return None


def arrange_puzzle(spec: PuzzleSpec, options: dict[str, Any]) -> py_trees.behaviour.Behaviour:
    """The subtree that reassembles ``spec``'s slab: survey, solve, then arrange the solved pieces (``options``)."""
    return py_trees.composites.Sequence(
        name=f"reassemble {spec.name}",
        memory=True,
        children=[
            SurveyPieces(f"survey {spec.name}", spec),
            SolvePuzzle(f"solve {spec.name}", spec),
            ArrangeSolved(f"arrange {spec.name}", spec, options),
        ],
    )


__all__ = ["ArrangeSolved", "arrange_puzzle"]
