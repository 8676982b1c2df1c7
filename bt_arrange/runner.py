"""Tick a tree on the world's clock, stepping the world between ticks, and log every transition.

The runner ticks the tree, lets the context's brake finish any interrupted motion, then steps
the world by one control period, until the root finishes or a limit of world time passes. Each
change of a behaviour's status is a ``Transition``; a ``TransitionLog`` writes them as JSON lines
as they happen, so an interrupted run keeps what it logged.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import IO

import py_trees
from py_trees.common import Status

from bt_arrange.behaviours import Context


@dataclass(frozen=True)
class Transition:
    """One behaviour changing status, at a moment of world time."""

    time_s: float
    behaviour: str
    kind: str
    old: str
    new: str
    feedback: str

    def to_json(self) -> str:
        """One line of the transition log."""
        return json.dumps(asdict(self))


class TransitionLog:
    """Watches every behaviour of a tree and records status changes (JSON lines when given a path)."""

    def __init__(self, path: Path | str | None = None) -> None:
        self.path = Path(path) if path is not None else None
        self.transitions: list[Transition] = []
        self._last: dict[int, Status] = {}
        self._file: IO[str] | None = None
        self._root: py_trees.behaviour.Behaviour | None = None
        self._nodes: list[py_trees.behaviour.Behaviour] = []

    def observe(self, root: py_trees.behaviour.Behaviour, time_s: float) -> list[Transition]:
        """Compare every node's status with the last look; log and return the changes.

        The nodes of ``root`` are listed once: a tree keeps its structure while it runs (walking
        py_trees' recursive generator every tick cost more than the tick itself).
        """
        if self._root is not root:
            self._root, self._nodes = root, list(root.iterate())
        changes = []
        for node in self._nodes:
            before = self._last.get(id(node), Status.INVALID)
            if node.status != before:
                changes.append(
                    Transition(
                        time_s=round(time_s, 4),
                        behaviour=node.name,
                        kind=type(node).__name__,
                        old=before.value,
                        new=node.status.value,
                        feedback=node.feedback_message,
                    )
                )
                self._last[id(node)] = node.status
        if changes:
            self.transitions.extend(changes)
            self._write(changes)
        return changes

    def _write(self, changes: list[Transition]) -> None:
        if self.path is None:
            return
        if self._file is None:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._file = self.path.open("w")
        for change in changes:
            self._file.write(change.to_json() + "\n")
        self._file.flush()

    def close(self) -> None:
        """Close the file, if one was written."""
        if self._file is not None:
            self._file.close()
            self._file = None


@dataclass
class RunResult:
    """How a run ended."""

    status: Status
    timed_out: bool
    ticks: int
    sim_seconds: float
    wall_seconds: float
    feedback: str = ""
    transitions: list[Transition] = field(default_factory=list)


class Runner:
    """Runs one tree against one world.

    ``step_world()`` advances the world by one control period (for the pybullet cell,
    ``cell.step``). ``on_transition`` is called with each status change, e.g. to save an image
    or to inject an error at a given moment.
    """

    def __init__(
        self,
        root: py_trees.behaviour.Behaviour,
        context: Context,
        step_world: Callable[[], None],
        *,
        time_limit_s: float = 1800.0,
        log: TransitionLog | None = None,
        on_transition: Callable[[Transition], None] | None = None,
        on_tick: Callable[[py_trees.behaviour.Behaviour], None] | None = None,
    ) -> None:
        self.root = root
        self.context = context
        self.step_world = step_world
        self.time_limit_s = time_limit_s
        self.log = log or TransitionLog()
        self.on_transition = on_transition
        self.on_tick = on_tick
        self.tree = py_trees.trees.BehaviourTree(root)
        self._is_set_up = False

    def setup(self) -> None:
        """Hand the context to every behaviour (``setup(context=...)``)."""
        self.tree.setup(context=self.context)
        self._is_set_up = True

    def tick_tree(self) -> None:
        """Tick the tree once.

        Through ``BehaviourTree.tick`` when visitors or tick handlers were added to ``self.tree``;
        otherwise the root's ``tick_once()`` alone, which skips the walk over every node that
        ``BehaviourTree.tick`` makes for visitors even when there are none.
        """
        tree = self.tree
        if tree.visitors or tree.pre_tick_handlers or tree.post_tick_handlers:
            tree.tick()
            return
        self.root.tick_once()
        tree.count += 1

    def run(self) -> RunResult:
        """Tick until the root succeeds or fails, or the world-time limit passes."""
        if not self._is_set_up:
            self.setup()
        clock = self.context.robot.clock
        start_s = clock.now()
        wall_start = time.perf_counter()
        ticks = 0
        timed_out = False
        try:
            while True:
                self.tick_tree()
                ticks += 1
                for transition in self.log.observe(self.root, clock.now()):
                    if self.on_transition is not None:
                        self.on_transition(transition)
                if self.on_tick is not None:
                    self.on_tick(self.root)
                self.context.brake.step()
                if self.root.status in (Status.SUCCESS, Status.FAILURE):
                    break
                if clock.now() - start_s >= self.time_limit_s:
                    timed_out = True
                    self.root.stop(Status.INVALID)
                    self.log.observe(self.root, clock.now())
                    break
                self.step_world()
        finally:
            self.log.close()
        feedback = self.root.feedback_message
        if timed_out:
            feedback = f"stopped after {self.time_limit_s:g} s of world time"
        return RunResult(
            status=self.root.status,
            timed_out=timed_out,
            ticks=ticks,
            sim_seconds=clock.now() - start_s,
            wall_seconds=time.perf_counter() - wall_start,
            feedback=feedback,
            transitions=list(self.log.transitions),
        )
