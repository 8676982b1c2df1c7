"""The paper's Sec. 3 errors by the names of ``experiment --rows``, injected into every part of any run.

``bt-arrange run TREE --inject translation,tilt`` reaches this through the sim backends'
``open_run(..., inject=..., inject_seed=...)``. A name is a row of the experiment that injects
errors (``ERRORS``); it injects that row's injectors (``rows.ROW_INJECTORS``) at their default
magnitudes, Table 1's, the figures the experiment uses: nothing is restated here.

Every part the tree picks (in tick order, then the plan's other targets) gets its own injectors,
each with its own generator drawn from the seed and the part's name, so two parts are not moved
alike and one part's draws do not depend on the others. ``perception`` is the exception: it moves
the camera until its part is first detected (``PerceptionOffset``), so it goes into the first part
picked only. Each injector still fires once, at the first occurrence of its moment for its part.
"""

from __future__ import annotations

import zlib
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import py_trees

from bt_arrange.behaviours import Pick
from bt_arrange.errors import PlanError
from bt_arrange.suggest import did_you_mean
from bt_arrange.trees import plan_of
from bt_arrange_sim.experiment.rows import RAISED_ROWS, ROW_INJECTORS, ROWS
from bt_arrange_sim.injection.framework import InjectableRun, Injector
from bt_arrange_sim.injection.registry import attach_all, make_injector

#: The errors ``--inject`` knows: every row of the experiment that injects something into the run's
#: own parts (the raised rows build a scene of their own), in the rows' order; ``all`` is every one.
ERRORS: tuple[str, ...] = tuple(row for row in ROWS if ROW_INJECTORS[row] and row not in RAISED_ROWS)
#: The error an injector stands for: the row that injects it alone.
_ERROR_OF: dict[str, str] = {ROW_INJECTORS[row][0]: row for row in ERRORS if len(ROW_INJECTORS[row]) == 1}
#: Injectors that act on the whole cell (the camera) rather than on their part: the first part only.
_FIRST_PART_ONLY = ("perception_offset",)


def parse_errors(names: str | Iterable[str]) -> list[str]:
    """The error names of ``--inject`` (``translation,tilt``), checked; duplicates dropped.

    A one-line ``PlanError`` for an empty list or an unknown name, naming the known ones.
    """
    items = [item.strip() for item in names.split(",")] if isinstance(names, str) else [str(n).strip() for n in names]
    items = [item for item in items if item]
    if not items:
        raise PlanError(f"--inject is empty; the errors are {', '.join(ERRORS)}")
    for item in items:
        if item not in ERRORS:
            raise PlanError(
                f"--inject {item}: unknown error{did_you_mean(item, ERRORS)}; the errors are {', '.join(ERRORS)}"
            )
    return list(dict.fromkeys(items))


def part_seed(seed: int, part: str) -> int:
    """The seed of one part's injectors: from the run's seed and the part's name."""
    return int(np.random.default_rng([int(seed), zlib.crc32(part.encode())]).integers(2**31))


@dataclass(frozen=True)
class Injected:
    """One injector in one part of a run, and the error name it was asked for under."""

    error: str
    part: str
    injector: Injector

    def record(self) -> dict[str, Any]:
        """JSON-able: ``error``, ``part``, then the injector's record (its name, magnitude, ``fired``, what it did)."""
        record = {k: v for k, v in self.injector.record().items() if k != "obj"}
        return {"error": self.error, "part": self.part, **record}


class Injection:
    """The errors of ``--inject`` attached to one run; ``records()`` says what each did, for the report."""

    def __init__(self, run: InjectableRun, errors: Sequence[str], seed: int) -> None:
        specs = _specs(parse_errors(errors))
        parts = parts_of(run)
        if not parts:
            check_named(run.root)
            raise PlanError(f"--inject: no part the tree names is in the cell (its parts: {', '.join(run.cell.parts)})")
        self.seed = int(seed)
        self.injected: list[Injected] = []
        for rank, part in enumerate(parts):
            chosen = [(error, spec) for error, spec in specs if rank == 0 or spec not in _FIRST_PART_ONLY]
            injectors = [make_injector(spec) for _, spec in chosen]
            # In the row's order: a later picking error is drawn to fit with an earlier one.
            attach_all(run, part, injectors, part_seed(self.seed, part))
            self.injected += [Injected(error, part, i) for (error, _), i in zip(chosen, injectors, strict=True)]

    def records(self) -> list[dict[str, Any]]:
        """What was injected into which part, in the order attached (JSON-able)."""
        return [injected.record() for injected in self.injected]


def _specs(errors: Sequence[str]) -> list[tuple[str, str]]:
    """(error, injector spec) pairs in the order of ``all``'s row; ``all`` names each by its own row."""
    wanted: dict[str, str] = {}
    for error in errors:
        for spec in ROW_INJECTORS[error]:
            wanted.setdefault(spec, error if error != "all" else _ERROR_OF.get(spec, error))
    order = {spec: i for i, spec in enumerate(ROW_INJECTORS["all"])}
    return sorted(((e, s) for s, e in wanted.items()), key=lambda pair: order.get(pair[1], len(order)))


def named_parts(root: py_trees.behaviour.Behaviour, plan: Any = None) -> list[str]:
    """The parts a tree names: those it picks, in tick order, then its plan's other targets.

    A tree that builds its picks while it runs (a puzzle's: its pieces are named by the solve, not
    by the cell) names none: an injector waits for its own part's behaviours, so it is refused.
    """
    names = [node.obj for node in root.iterate() if isinstance(node, Pick) and isinstance(node.obj, str)]
    names += [target.obj for target in getattr(plan if plan is not None else plan_of(root), "targets", ())]
    return list(dict.fromkeys(names))


def check_named(root: py_trees.behaviour.Behaviour) -> None:
    """A one-line ``PlanError``, before the world is built, when ``root`` names no part to inject into."""
    if not named_parts(root):
        raise PlanError(
            "--inject: this tree names no part it picks (a puzzle's pieces are named by its solve), "
            "so an error has nothing to wait for; inject into a tree or plan of named parts"
        )


def parts_of(run: InjectableRun) -> list[str]:
    """The parts of ``run``'s cell to inject into: ``named_parts`` of its tree and plan, in that order."""
    cell_parts = run.cell.parts
    return [name for name in named_parts(run.root, getattr(run, "plan", None)) if name in cell_parts]
