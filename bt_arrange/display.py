"""Show a tree: as text, as Graphviz source, as a PNG or SVG picture, and live in a terminal while it runs.

``render_tree(root, fmt)`` draws a tree built without a robot (``arrangement(...)``, a tree file's
``create_root()``); with ``blackboard=True`` it also shows who writes and who reads each blackboard
key, from the keys every behaviour declared with ``register_key``. Only the clients of the given
tree are drawn, never those left on the global blackboard by other trees built in the same process.

``LiveView`` redraws a running tree with its statuses, the world time and the tip's feedback
message, throttled to a few frames per second of wall time.

PNG and SVG need Graphviz's ``dot`` program; text and dot output do not.
"""

from __future__ import annotations

import math
import re
import shutil
import subprocess
import sys
import time
import uuid
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import TextIO

import py_trees
import pydot
from py_trees.common import Status

from bt_arrange.errors import BtArrangeError

FORMATS = ("text", "dot", "png", "svg")
PICTURE_FORMATS = ("png", "svg")

NO_GRAPHVIZ = (
    "PNG and SVG need Graphviz's 'dot' program, which is not installed: install it with 'apt-get install graphviz' "
    "(Debian/Ubuntu) or 'brew install graphviz' (macOS); --format text or dot work without it"
)

#: Wall time [s] a ``dot`` run may take before it counts as failed (a 60-node tree takes ~0.1 s).
DOT_TIMEOUT_S = 60.0

_ANSI_ESCAPE = re.compile(r"\x1b\[[0-9;?]*[ -/]*[@-~]")


class DisplayError(BtArrangeError):
    """A tree cannot be shown as asked: an unknown format, no Graphviz, an unwritable file."""


def strip_ansi(text: str) -> str:
    """``text`` without terminal escape sequences (py_trees adds colours when stdout is a terminal)."""
    return _ANSI_ESCAPE.sub("", text)


# ----------------------------------------------------------------------------------------------
# Blackboard access, from the tree's own clients
# ----------------------------------------------------------------------------------------------


@dataclass
class KeyAccess:
    """Who touches one blackboard key, in tree order (behaviour names, each listed once)."""

    key: str
    writers: list[str] = field(default_factory=list)
    readers: list[str] = field(default_factory=list)


def _preorder(root: py_trees.behaviour.Behaviour) -> Iterator[py_trees.behaviour.Behaviour]:
    """Behaviours top-down in the order they are drawn (``Behaviour.iterate`` yields children first)."""
    yield root
    for child in root.children:
        yield from _preorder(child)


def blackboard_access(root: py_trees.behaviour.Behaviour) -> list[KeyAccess]:
    """Every blackboard key declared by the behaviours of ``root``'s tree, with its writers and readers.

    Keys come in the order the tree first mentions them. A remapped key is listed where it is
    stored, the behaviour with ``(as <its own name for it>)``. Exclusive writers count as writers.
    """
    table: dict[str, KeyAccess] = {}

    def note(key: str, who: str, remapped: dict[str, str], writes: bool) -> None:
        stored = remapped.get(key, key)
        label = who if stored == key else f"{who} (as {key})"
        entry = table.setdefault(stored, KeyAccess(stored))
        names = entry.writers if writes else entry.readers
        if label not in names:
            names.append(label)

    for behaviour in _preorder(root):
        for client in behaviour.blackboards:
            remappings = dict(client.remappings)
            for key in sorted(client.write | client.exclusive):
                note(key, behaviour.name, remappings, writes=True)
            for key in sorted(client.read):
                note(key, behaviour.name, remappings, writes=False)
    return list(table.values())


def blackboard_table(root: py_trees.behaviour.Behaviour) -> str:
    """The blackboard keys of a tree as text: per key, the behaviours that write it and those that read it."""
    access = blackboard_access(root)
    if not access:
        return "Blackboard: no behaviour of this tree declares a key\n"
    lines = ["Blackboard keys (declared with register_key)"]
    for entry in access:
        lines.append(f"  {entry.key}")
        lines.append(f"      written by  {', '.join(entry.writers) or '- (nobody in this tree)'}")
        lines.append(f"      read by     {', '.join(entry.readers) or '- (nobody in this tree)'}")
    return "\n".join(lines) + "\n"


# ----------------------------------------------------------------------------------------------
# Text and Graphviz
# ----------------------------------------------------------------------------------------------


def _has_run(root: py_trees.behaviour.Behaviour) -> bool:
    """True once any behaviour of the tree has a status (a freshly built tree has none)."""
    return any(node.status != Status.INVALID for node in root.iterate())


def text_tree(root: py_trees.behaviour.Behaviour, *, blackboard: bool = False) -> str:
    """py_trees' unicode tree, with statuses once the tree has run, and optionally its blackboard keys."""
    text = strip_ansi(py_trees.display.unicode_tree(root, show_status=_has_run(root)))
    if blackboard:
        text += "\n" + blackboard_table(root)
    return text


def _dot_node_names(root: py_trees.behaviour.Behaviour) -> dict[uuid.UUID, str]:
    """The Graphviz node of every behaviour, named as ``py_trees.display.dot_tree`` names them.

    ``dot_tree`` walks the tree top-down and appends ``*`` to a name already taken. A behaviour
    hidden inside a black box (not drawn at the default visibility) maps to the drawn box.
    """
    names = {root.id: root.name}

    def walk(parent: py_trees.behaviour.Behaviour, drawn: bool) -> None:
        show_children = drawn and py_trees.common.VisibilityLevel.DETAIL < parent.blackbox_level
        for child in parent.children:
            if show_children:
                name = child.name
                while name in names.values():
                    name += "*"
                names[child.id] = name
            else:
                names[child.id] = names[parent.id]
            walk(child, show_children)

    walk(root, True)
    return names


def dot_graph(root: py_trees.behaviour.Behaviour, *, blackboard: bool = False) -> pydot.Dot:
    """``py_trees.display.dot_tree(root)``, plus this tree's blackboard keys when asked.

    The keys are drawn as py_trees draws them (boxes in a "Blackboard" subgraph ranked below the tree, a
    blue edge from each writer, a green edge to each reader) but only for the given tree: py_trees'
    own ``with_blackboard_variables`` draws every client still registered on the global blackboard,
    so a second tree built in the same process would appear twice.
    """
    graph = py_trees.display.dot_tree(root)
    if not blackboard:
        return graph
    nodes = _dot_node_names(root)
    storage = py_trees.blackboard.Blackboard.storage
    colour, fontsize = "blue", 8
    cluster = pydot.Subgraph(graph_name="Blackboard", id="Blackboard", label="Blackboard", rank="sink")
    edges: set[tuple[str, str, str]] = set()
    for behaviour in _preorder(root):
        for client in behaviour.blackboards:
            for key in client.read | client.write | client.exclusive:
                stored = client.remappings.get(key, key)
                if key in client.write | client.exclusive:
                    edges.add((nodes[behaviour.id], stored, colour if key in client.write else "deepskyblue"))
                if key in client.read:
                    edges.add((stored, nodes[behaviour.id], "green"))
    for entry in blackboard_access(root):
        label = entry.key
        if entry.key in storage:
            label += ": " + py_trees.utilities.truncate(str(storage[entry.key]), 20)
        cluster.add_node(
            pydot.Node(
                entry.key,
                label=label,
                shape="box",
                style="filled",
                color=colour,
                fillcolor="white",
                fontsize=fontsize,
                fontcolor=colour,
                width=0,
                height=0,
                fixedsize=False,
            )
        )
    graph.add_subgraph(cluster)
    for source, target, edge_colour in sorted(edges):
        graph.add_edge(pydot.Edge(source, target, color=edge_colour, constraint=False, weight=0))
    return graph


def _write_text(path: Path, text: str) -> None:
    try:
        path.write_text(text, encoding="utf-8")
    except OSError as error:
        raise DisplayError(f"cannot write {path}: {error.strerror or error}") from error


def render_picture(graph: pydot.Dot, fmt: str, out: Path) -> Path:
    """Run Graphviz's ``dot`` on ``graph`` and write a ``fmt`` (png or svg) picture to ``out``."""
    dot = shutil.which("dot")
    if dot is None:
        raise DisplayError(NO_GRAPHVIZ)
    source = graph.to_string()
    if fmt == "png":
        # A PNG bakes in the glyphs of this machine's fonts, which often lack py_trees' marks:
        # use py_trees' own ASCII fallbacks ("M" for a composite with memory) rather than empty boxes.
        for mark in ("memory", "synchronised"):
            source = source.replace(py_trees.display.unicode_symbols[mark], py_trees.display.ascii_symbols[mark])
    try:
        result = subprocess.run(
            [dot, f"-T{fmt}", "-o", str(out)],
            input=source.encode("utf-8"),
            capture_output=True,
            timeout=DOT_TIMEOUT_S,
            check=False,
        )
    except subprocess.TimeoutExpired as error:
        raise DisplayError(f"Graphviz's dot took more than {DOT_TIMEOUT_S:g} s to draw {out}") from error
    except OSError as error:
        raise DisplayError(f"cannot run Graphviz's dot ({dot}): {error.strerror or error}") from error
    if result.returncode != 0:
        reason = result.stderr.decode("utf-8", "replace").strip().splitlines()
        raise DisplayError(
            f"Graphviz's dot could not write {out} (exit status {result.returncode})"
            + (f": {reason[0]}" if reason else "")
        )
    if not out.is_file() or out.stat().st_size == 0:
        raise DisplayError(f"Graphviz's dot reported success but wrote nothing to {out}")
    return out


def render_tree(
    root: py_trees.behaviour.Behaviour,
    fmt: str = "text",
    *,
    blackboard: bool = False,
    out: Path | None = None,
    name: str | None = None,
) -> str:
    """Draw a tree as ``fmt`` (one of ``FORMATS``); return the text, or the path of the picture written.

    - ``"text"``: py_trees' unicode tree (statuses once it has run); ``blackboard=True`` adds a table
      of the keys each behaviour writes and reads. Written to ``out`` too when given.
    - ``"dot"``: the Graphviz source; ``blackboard=True`` adds the keys and their writers and readers.
      Written to ``out`` too when given.
    - ``"png"``/``"svg"``: the picture, written to ``out`` or to ``<name or root.name>.<fmt>`` in the
      current directory (spaces and odd characters replaced); needs Graphviz's ``dot``.

    Every failure (unknown format, no Graphviz, a file that cannot be written) is a ``DisplayError``.
    """
    if fmt not in FORMATS:
        raise DisplayError(f"unknown format {fmt!r}: choose one of {', '.join(FORMATS)}")
    if not isinstance(root, py_trees.behaviour.Behaviour):
        raise DisplayError(f"expected the root behaviour of a py_trees tree, got {type(root).__name__}")
    path = Path(out) if out is not None else None
    if fmt == "text":
        text = text_tree(root, blackboard=blackboard)
        if path is not None:
            _write_text(path, text)
        return text
    if fmt in PICTURE_FORMATS and shutil.which("dot") is None:
        raise DisplayError(NO_GRAPHVIZ)
    graph = dot_graph(root, blackboard=blackboard)
    if fmt == "dot":
        source = graph.to_string()
        if path is not None:
            _write_text(path, source)
        return source
    if path is None:
        path = Path(f"{py_trees.utilities.get_valid_filename(name or root.name)}.{fmt}")
    elif path.suffix.lower() in {f".{other}" for other in PICTURE_FORMATS if other != fmt}:
        raise DisplayError(f"{path} ends in {path.suffix} but the format is {fmt}: name the file .{fmt}")
    if not path.parent.is_dir():
        raise DisplayError(f"cannot write {path}: the directory {path.parent} does not exist")
    return str(render_picture(graph, fmt, path))


# ----------------------------------------------------------------------------------------------
# Live view
# ----------------------------------------------------------------------------------------------


def _is_tty(stream: TextIO) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):  # no isatty, or a closed stream
        return False


def _can_encode(stream: TextIO, text: str) -> bool:
    encoding = getattr(stream, "encoding", None) or "utf-8"
    try:
        text.encode(encoding)
    except (LookupError, UnicodeError):
        return False
    return True


class LiveView:
    """A view of a running tree in the terminal, redrawn in place as the tree ticks.

    Call ``update(root, time_s)`` after every tick (cheap when it does not draw) and ``close()``
    at the end. A frame shows the world time, the tip (the behaviour ticked last) with its feedback
    message, and the tree with every status and feedback message.

    Drawing is throttled on wall time: a frame whose tree differs from the last drawn one (a status
    or a feedback message changed) is drawn once ``min_interval_s`` passed since the last frame, an
    unchanged one only every ``refresh_interval_s`` (to move the clock on); ``final=True`` always draws.

    On a terminal each frame replaces the previous one (ANSI cursor movement), and a tree taller
    than the terminal is drawn compactly: only running (and failed) subtrees are expanded. On
    anything else (a pipe, a file, a test's ``StringIO``) frames are appended, separated by a line,
    without any escape sequence.
    """

    def __init__(
        self,
        stream: TextIO = sys.stdout,
        min_interval_s: float = 0.2,
        clock: Callable[[], float] = time.monotonic,
        *,
        refresh_interval_s: float = 1.0,
        compact: bool | None = None,
    ) -> None:
        self.stream = stream
        self.min_interval_s = float(min_interval_s)
        self.refresh_interval_s = max(float(refresh_interval_s), self.min_interval_s)
        self.clock = clock
        self.compact = compact
        self.tty = _is_tty(stream)
        self.frames = 0
        self._unicode = _can_encode(stream, "\u2713\u2715")
        self._last_draw_s: float | None = None
        self._last_tree: str | None = None
        self._last_frame: str | None = None
        self._rows_drawn = 0
        self._root: py_trees.behaviour.Behaviour | None = None
        self._time_s = 0.0
        self._closed = False
        self._closing = False

    def update(self, root: py_trees.behaviour.Behaviour, time_s: float, *, final: bool = False) -> bool:
        """Draw the tree at world time ``time_s`` [s] unless throttled; return whether a frame was drawn."""
        self._root, self._time_s = root, time_s
        now = self.clock()
        since_s = math.inf if self._last_draw_s is None else now - self._last_draw_s
        if not final and since_s < self.min_interval_s:
            return False
        tree = self._tree(root)
        if not final and tree == self._last_tree and since_s < self.refresh_interval_s:
            return False
        frame = self._header(root, time_s) + "\n" + tree
        if self._closing and frame == self._last_frame:
            return False  # close(): the last state is already on screen
        self._draw(frame)
        self._last_draw_s, self._last_tree, self._last_frame = now, tree, frame
        return True

    def close(self) -> None:
        """Draw the last state seen by ``update`` (unless it is already on screen); later calls do nothing."""
        if self._closed:
            return
        self._closed = self._closing = True
        if self._root is not None:
            self.update(self._root, self._time_s, final=True)
        self.stream.flush()

    def __enter__(self) -> LiveView:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    def _header(self, root: py_trees.behaviour.Behaviour, time_s: float) -> str:
        tip = root.tip()
        if tip is None:
            return f"world time {time_s:.2f} s | not started"
        what = tip.feedback_message or tip.status.value
        return f"world time {time_s:.2f} s | {root.name} {root.status.value} | {tip.name}: {what}"

    def _tree(self, root: py_trees.behaviour.Behaviour) -> str:
        draw = py_trees.display.unicode_tree if self._unicode else py_trees.display.ascii_tree
        text = draw(root, show_status=True)
        compact = self.compact
        if compact is None:
            compact = self.tty and self._rows(text) > shutil.get_terminal_size().lines - 2
        if compact:
            expanded: dict[uuid.UUID, Status] = {
                node.id: node.status for node in root.iterate() if node.status in (Status.RUNNING, Status.FAILURE)
            }
            text = draw(root, show_only_visited=True, show_status=True, visited=expanded)
        return text if self.tty else strip_ansi(text)

    def _rows(self, text: str) -> int:
        """Terminal rows ``text`` takes, counting lines that wrap."""
        columns = max(shutil.get_terminal_size().columns, 1)
        lines = text.rstrip("\n").split("\n")
        return sum(max(1, math.ceil(len(strip_ansi(line)) / columns)) for line in lines)

    def _draw(self, frame: str) -> None:
        frame = frame.rstrip("\n") + "\n"
        if self.tty:
            if self._rows_drawn:
                self.stream.write(f"\x1b[{self._rows_drawn}A\r\x1b[J")  # up to the last frame's top, clear below
            self._rows_drawn = self._rows(frame)
        elif self.frames:
            self.stream.write("-" * 72 + "\n")
        self.stream.write(frame)
        self.stream.flush()
        self.frames += 1
