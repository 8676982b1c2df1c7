"""The live view: a running tree redrawn in a terminal with its statuses, throttled in wall time."""

from __future__ import annotations

import math
import shutil
import sys
import time
import uuid
from collections.abc import Callable
from typing import TextIO

import py_trees
from py_trees.common import Status

from bt_arrange.display.rendering import strip_ansi, with_types

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
        text = with_types(draw(root, show_status=True), root)
        compact = self.compact
        if compact is None:
            compact = self.tty and self._rows(text) > shutil.get_terminal_size().lines - 2
        if compact:
            expanded: dict[uuid.UUID, Status] = {
                node.id: node.status for node in root.iterate() if node.status in (Status.RUNNING, Status.FAILURE)
            }
            text = with_types(
                draw(root, show_only_visited=True, show_status=True, visited=expanded), root, visited=expanded
            )
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
