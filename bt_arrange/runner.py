"""Tick a tree on the world's clock, stepping the world between ticks, and log every transition.

The runner ticks the tree, lets the context's brake finish any interrupted motion, then steps
the world by one control period, until the root finishes or a limit of world time passes. Each
change of a behaviour's status is a ``Transition``; a ``TransitionLog`` (a py_trees visitor of the
tree) writes them as JSON lines as they happen, so an interrupted run keeps what it logged.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Iterable, Mapping
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import py_trees
import py_trees.visitors
from py_trees.common import Status

from bt_arrange.behaviours import Context
from bt_arrange.behaviours.base import FAILURE, INVALID, RUNNING, SUCCESS
from bt_arrange.files import LineLog
from bt_arrange.motion.safety import SafetyStop
from bt_arrange.robot import Clock


@dataclass(frozen=True)
class Transition:
    """One behaviour changing status, at a moment of world time.

    ``behaviour`` is the node's name and ``kind`` its BehaviorTree.CPP type as the XML names it
    (``ForceSuccess`` for a ``FailureIsSuccess``, ``Pick`` for a ``Pick``), for people reading the log;
    programs select by ``node_id`` (the py_trees ``Behaviour.id``, as text), which
    ``TransitionLog.node(transition)`` and ``Runner.node(transition)`` turn back into the node,
    and by ``obj``, the object the node handles (``None`` for a node of no single object).

    ``facts`` are what the node states as data at that moment, for reports and error injectors
    (copied from the node's ``facts`` mapping, when it has one; empty otherwise): read them here,
    never out of ``feedback``, which is text for people. Keys are the node's own, values JSON-able.
    """

    time_s: float
    behaviour: str
    kind: str
    old: str
    new: str
    feedback: str
    node_id: str = ""
    obj: str | None = None
    facts: dict[str, Any] = field(default_factory=dict, hash=False)

    def to_json(self) -> str:
        """One line of the transition log (``facts`` only when there are some)."""
        data = asdict(self)
        if not self.facts:
            del data["facts"]
        return json.dumps(data, default=str)


def facts_of(node: py_trees.behaviour.Behaviour) -> dict[str, Any]:
    """A copy of the facts a behaviour states (its ``facts`` mapping, if it has one), else an empty dict."""
    facts = getattr(node, "facts", None)
    return dict(facts) if isinstance(facts, Mapping) and facts else {}


def object_of(node: py_trees.behaviour.Behaviour) -> str | None:
    """The object a behaviour handles (its ``obj``: Detect, Pick, GraspGuard, RepeatUntilWithin, ...), or None."""
    obj = getattr(node, "obj", None)
    return obj if isinstance(obj, str) else None


class TransitionLog(py_trees.visitors.VisitorBase):
    """A py_trees visitor that records every status change of a tree (JSON lines when given a path).

    Add it with ``tree.add_visitor(log)`` (the ``Runner`` does): py_trees hands it each behaviour
    as it is ticked. A behaviour can also change without being ticked, when a parent stops it
    (an interruption, a reset: always to INVALID); so after the tick the log looks below the
    ticked nodes, and below the nodes just stopped, for children that held a status. It does not
    walk the whole tree every tick. ``clock`` (anything with ``now()``, seconds) stamps the changes.
    """

    def __init__(self, path: Path | str | None = None, clock: Clock | None = None) -> None:
        super().__init__(full=False)
        self.path = Path(path) if path is not None else None
        self.clock = clock
        self.transitions: list[Transition] = []
        #: The changes of the last tick (``finalise`` fills it, ``take`` empties it).
        self.pending: list[Transition] = []
        #: Every node that changed status, by its id (as text): ``node(transition)`` looks them up.
        self.nodes: dict[str, py_trees.behaviour.Behaviour] = {}
        # Keyed by the node itself (identity hash, in C), not by its UUID (hashed in Python):
        # the log looks at a few nodes every tick.
        self._last: dict[py_trees.behaviour.Behaviour, Status] = {}
        self._visited: list[py_trees.behaviour.Behaviour] = []
        self._file: LineLog | None = None
        self._kinds: dict[py_trees.behaviour.Behaviour, str] = {}

    # -- the visitor ---------------------------------------------------------------------------

    def initialise(self) -> None:
        """Before a tick: nothing visited yet."""
        self._visited = []

    def run(self, behaviour: py_trees.behaviour.Behaviour) -> None:
        """A behaviour was ticked; its status is read after the tick (a parent may still stop it)."""
        self._visited.append(behaviour)

    def visit_all(self, behaviours: Iterable[py_trees.behaviour.Behaviour]) -> None:
        """``run`` each behaviour of a tick as it is yielded (``Runner.tick_tree``'s loop, without a call per node)."""
        self._visited.extend(behaviours)

    def finalise(self) -> None:
        """After a tick: log what changed among the ticked nodes and the nodes stopped below them."""
        self.look(self._visited, self.clock.now() if self.clock is not None else 0.0)
        self._visited = []

    # -- looking and logging -------------------------------------------------------------------

    def look(self, nodes: Iterable[py_trees.behaviour.Behaviour], time_s: float) -> list[Transition]:
        """Compare ``nodes``, and the children of any of them that changed unseen, with the last look."""
        changes: list[Transition] = []
        last = self._last
        seen: set[py_trees.behaviour.Behaviour] = set()
        # Breadth first (a list read from the front, growing as it is read): the changes come in the order of the tick.
        queue = list(nodes)
        invalid = INVALID
        get, add = last.get, seen.add
        for node in queue:
            if node in seen:
                continue
            add(node)
            before = get(node, invalid)
            if node.status is not before:
                changes.append(self._transition(node, before, time_s))
                last[node] = node.status
            # A child changes without a tick only when a parent stops it (to INVALID): so only below a node
            # ticked or stopped now, and only a child whose status differs from the last look.
            for child in node.children:
                if get(child, invalid) is not child.status:
                    queue.append(child)
        if changes:
            self.pending.extend(changes)
            self.transitions.extend(changes)
            self._write(changes)
        return changes

    def observe(self, root: py_trees.behaviour.Behaviour, time_s: float) -> list[Transition]:
        """Compare every node of the tree with the last look (for a tree ticked without this visitor)."""
        changes = self.look(root.iterate(), time_s)
        self.take()
        return changes

    def take(self) -> list[Transition]:
        """The changes logged since the last ``take``, oldest first."""
        changes, self.pending = self.pending, []
        return changes

    def node(self, transition: Transition) -> py_trees.behaviour.Behaviour | None:
        """The behaviour a transition is about (None for a node this log never saw)."""
        return self.nodes.get(transition.node_id)

    def _transition(self, node: py_trees.behaviour.Behaviour, before: Status, time_s: float) -> Transition:
        node_id = str(node.id)
        self.nodes[node_id] = node
        return Transition(
            time_s=round(time_s, 4),
            behaviour=node.name,
            kind=self._kind(node),
            old=before.value,
            new=node.status.value,
            feedback=node.feedback_message,
            node_id=node_id,
            obj=object_of(node),
            facts=facts_of(node),
        )

    def _kind(self, node: py_trees.behaviour.Behaviour) -> str:
        kind = self._kinds.get(node)
        if kind is None:
            from bt_arrange.xmltree import tag_of  # the XML's vocabulary (imported late: xmltree imports the trees)

            kind = self._kinds[node] = tag_of(node)
        return kind

    def _write(self, changes: list[Transition]) -> None:
        if self.path is None:
            return
        if self._file is None:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._file = LineLog(self.path)
        # Whole lines only; a full disk stops the file at its last whole line (``fault``), the run goes on.
        self._file.write(change.to_json() for change in changes)

    @property
    def fault(self) -> OSError | None:
        """The error that stopped the file (a full disk, a folder gone), or None."""
        return self._file.fault if self._file is not None else None

    def close(self) -> None:
        """Close the file, if one was written."""
        if self._file is not None:
            self._file.close()


def _passed_on_to(node: py_trees.behaviour.Behaviour) -> py_trees.behaviour.Behaviour | None:
    """The child a running node's tick does nothing but tick (and, a decorator, ``update()`` after); else None.

    Read off py_trees' own ``tick`` of each kind, for a node that runs and keeps running:

    - a ``Sequence`` with memory resumes its current child, and runs while it runs;
    - a ``Selector`` with memory does the same once the children before the current one are
      INVALID (before that, its tick stops them);
    - ``FailureIsSuccess`` and ``Retry`` tick their child, and their ``update()`` says RUNNING
      while the child runs (setting only their feedback).

    Any other node (a subclass with its own ``tick``, a guard checking a condition, a decorator
    whose ``update()`` may end it) is ticked as py_trees ticks it. Which of these a node is
    depends only on its class and its memory, fixed when it is built: it is worked out at its
    first look (``_pass_kind``) and kept on the node, not worked out again every tick.
    """
    if node.status is not RUNNING:
        return None
    kind = getattr(node, _PASS_KIND, None)
    if kind is None:
        kind = _pass_kind(node)
        setattr(node, _PASS_KIND, kind)
    if kind is _SEQUENCE:
        return node.current_child  # type: ignore[attr-defined]
    if kind is _DECORATOR:
        return node.decorated  # type: ignore[attr-defined]
    if kind is _SELECTOR:
        current = node.current_child  # type: ignore[attr-defined]
        for child in node.children:
            if child is current:
                return current
            if child.status is not INVALID:
                return None
    return None


#: Decorators whose ``update()`` with a running child returns RUNNING, whatever else it sets (its feedback).
_PASSING_DECORATORS = (py_trees.decorators.FailureIsSuccess, py_trees.decorators.Retry)
#: The attribute a node's kind is kept in (``_passed_on_to``), and the kinds.
_PASS_KIND = "_bt_arrange_pass_kind"
_SEQUENCE, _SELECTOR, _DECORATOR, _OTHER = "sequence", "selector", "decorator", "other"


def _pass_kind(node: py_trees.behaviour.Behaviour) -> str:
    """How a node's tick treats a running child: passes it on as a sequence, a selector, a decorator, or otherwise."""
    kind = type(node)
    if kind in _PASSING_DECORATORS:
        return _DECORATOR
    if not isinstance(node, py_trees.composites.Composite) or not getattr(node, "memory", False):
        return _OTHER
    if kind.tick is py_trees.composites.Sequence.tick:
        return _SEQUENCE
    if kind.tick is py_trees.composites.Selector.tick:
        return _SELECTOR
    return _OTHER


def resumed_tick(root: py_trees.behaviour.Behaviour) -> list[py_trees.behaviour.Behaviour]:
    """Tick ``root`` once and return the ticked nodes in the order py_trees yields them, ticking only what can change.

    While a behaviour runs (a motion, 125 times a second), the nodes above it that only pass the
    tick on (``_passed_on_to``) would each re-run py_trees' tick to find the same running child.
    The tick resumes instead at the highest node that does more (a guard's condition, a
    behaviour): it is ticked as its parent would tick it. If it still runs, each node above it
    does what its tick does after a running child, bottom up: a decorator's ``update()``, a
    composite's RUNNING. If it ended, the nodes above must act on that within this tick (a
    sequence moves on to the next child): the root is ticked as py_trees ticks it, the resumed
    node's tick handed back as it happened, not run twice. Either way every node ends the tick
    as ``root.tick()`` would leave it, and the same nodes are yielded in the same order.
    """
    running = RUNNING
    above: list[py_trees.behaviour.Behaviour] = []
    node = root
    while True:
        child = _passed_on_to(node)
        if child is None or child.status is not running:
            break
        above.append(node)
        node = child
    if not above:
        return list(root.tick())
    ticked = list(node.tick())
    if node.status is running:
        for parent in reversed(above):
            # Every node above was looked at on the way down (``_passed_on_to``), which kept its kind.
            if getattr(parent, _PASS_KIND) is _DECORATOR:
                # Decorator.tick after its child: update(), and stop on a status other than RUNNING.
                status = parent.update()
                if status is not running:
                    parent.stop(status)
                parent.status = status
            else:
                parent.status = running
            ticked.append(parent)
        return ticked
    # The resumed node ended: the root's tick reaches it as before (the nodes above it did nothing on
    # the way down) and is handed its tick as it happened.
    node.tick = lambda: iter(ticked)  # type: ignore[method-assign]
    try:
        return list(root.tick())
    finally:
        del node.tick


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
    #: The one-line reason of a safety stop that ended the run (``bt_arrange.motion.safety.SafetyStop``), else "".
    safety_stop: str = ""


class Runner:
    """Runs one tree against one world.

    ``step_world()`` advances the world by one control period (for the pybullet cell,
    ``cell.step``). A ``SafetyStop`` raised by it (the robot stopped) or by a behaviour's planning (a
    motion outside the workspace box) ends the run at once: every behaviour is stopped, the result is a
    FAILURE with the stop's reason (``safety_stop``), and the world is stepped no more; only a refused
    motion (``arm_stopped`` False) lets the brake bring the arm to rest first. ``on_transition`` is
    called with each status change, e.g. to save an image
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
        if self.log.clock is None:
            self.log.clock = context.robot.clock
        self.tree.add_visitor(self.log)
        self._is_set_up = False
        self._ticks = 0
        self._timed_out = False

    def node(self, transition: Transition) -> py_trees.behaviour.Behaviour | None:
        """The behaviour a transition is about, by its id."""
        return self.log.node(transition)

    def setup(self) -> None:
        """Hand the context to every behaviour (``setup(context=...)``)."""
        self.tree.setup(context=self.context)
        self._is_set_up = True

    def tick_tree(self) -> None:
        """Tick the tree once, handing the ticked behaviours to its visitors (the log among them).

        Through ``BehaviourTree.tick`` when a full visitor or a tick handler was added to
        ``self.tree``; otherwise the same steps without the walk over every node that
        ``BehaviourTree.tick`` makes for full visitors even when there are none.
        """
        tree = self.tree
        visitors = tree.visitors
        handlers = tree.pre_tick_handlers or tree.post_tick_handlers
        if not handlers and len(visitors) == 1 and visitors[0] is self.log:
            # The usual case, the log alone: it reads the statuses after the tick (``finalise``), so the
            # tick may resume below the nodes that only pass it on (``resumed_tick``).
            log = self.log
            log.initialise()
            log.visit_all(resumed_tick(self.root))
            log.finalise()
            tree.count += 1
            return
        if handlers or any(v.full for v in visitors):
            tree.tick()
            return
        for visitor in visitors:
            visitor.initialise()
        # ``node.visit(visitor)`` is ``visitor.run(node)``: the bound methods, looked up once per tick.
        runs = [visitor.run for visitor in visitors]
        for node in self.root.tick():
            for run in runs:
                run(node)
        for visitor in visitors:
            visitor.finalise()
        tree.count += 1

    def run(self) -> RunResult:
        """Tick until the root succeeds or fails, the world-time limit passes, or a safety stop ends it."""
        if not self._is_set_up:
            self.setup()
        clock = self.context.robot.clock
        start_s = clock.now()
        wall_start = time.perf_counter()
        self._ticks = 0
        self._timed_out = False
        stop: SafetyStop | None = None
        try:
            try:
                while self._tick_and_step(clock, start_s):
                    pass
            except SafetyStop as raised:
                stop = raised
                self._end_on_stop(stop, clock, start_s)
        finally:
            self.log.close()
        feedback = self.root.feedback_message
        if self._timed_out:
            feedback = f"stopped after {self.time_limit_s:g} s of world time"
        if stop is not None:
            feedback = stop.reason
        return RunResult(
            status=FAILURE if stop is not None else self.root.status,
            timed_out=self._timed_out,
            ticks=self._ticks,
            sim_seconds=clock.now() - start_s,
            wall_seconds=time.perf_counter() - wall_start,
            feedback=feedback,
            transitions=list(self.log.transitions),
            safety_stop=stop.reason if stop is not None else "",
        )

    def _tick_and_step(self, clock: Clock, start_s: float) -> bool:
        """One tick, the brake's setpoint, and one step of the world; False once the run is over."""
        self.tick_tree()
        self._ticks += 1
        for transition in self.log.take():
            if self.on_transition is not None:
                self.on_transition(transition)
        if self.on_tick is not None:
            self.on_tick(self.root)
        self.context.brake.step()
        if self.root.status in (SUCCESS, FAILURE):
            # A motion handed on at speed by the last behaviour runs to its end (the arm
            # arrives where it was going) before the run ends: the world time includes it.
            while self.context.brake.busy and clock.now() - start_s < self.time_limit_s:
                self.step_world()
                self.context.brake.step()
            return False
        if clock.now() - start_s >= self.time_limit_s:
            self._timed_out = True
            self.root.stop(INVALID)
            self.log.look([self.root], clock.now())
            self.log.take()
            return False
        self.step_world()
        return True

    def _end_on_stop(self, stop: SafetyStop, clock: Clock, start_s: float) -> None:
        """A safety stop: stop every behaviour; a refused motion's arm is braked to rest, a stopped robot left alone."""
        self.root.stop(INVALID)
        self.log.look([self.root], clock.now())
        for transition in self.log.take():
            if self.on_transition is not None:
                self.on_transition(transition)
        if stop.arm_stopped:
            return
        # The framework refused a motion: the arm may still carry a motion handed on at speed, which
        # the brake stops (jerk-limited) as it would for any interruption, before the run ends.
        brake = self.context.brake
        brake.brake_carried()
        try:
            while brake.busy and clock.now() - start_s < self.time_limit_s:
                self.step_world()
                brake.step()
        except SafetyStop:
            return  # the robot stopped while braking: nothing more is sent
