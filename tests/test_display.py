"""Showing trees: text, Graphviz source, PNG/SVG pictures, and the live terminal view.

The blackboard is cleared around every test by ``clean_blackboard`` in ``conftest.py``.
"""

from __future__ import annotations

import io
import re
import shutil
import stat
from pathlib import Path

import py_trees
import pydot
import pytest
from py_trees.common import Status

from bt_arrange import display
from bt_arrange.display import FORMATS, NO_GRAPHVIZ, DisplayError, LiveView, blackboard_access, render_tree
from bt_arrange.errors import BtArrangeError
from bt_arrange.trees import Arrangement, Target, arrangement

HAS_DOT = shutil.which("dot") is not None
needs_dot = pytest.mark.skipif(
    not HAS_DOT, reason="Graphviz's 'dot' is not installed (apt-get install graphviz): PNG/SVG cannot be drawn"
)

TWO_CUBES_IN_ORDER = [
    "arrangement",
    "arrange red",
    "red target",
    "detect red",
    "pick red",
    "while holding red",
    "place red",
    "inspect red after placing",
    "push red",
    "inspect red",
    "arrange green",
    "detect green",
    "pick green",
    "place green",
    "push green",
    "inspect green",
    "park the arm",
]


def two_cubes() -> Arrangement:
    return arrangement([Target("red", 0.45, 0.05), Target("green", 0.45, -0.05)])


def tree_lines(text: str) -> list[str]:
    """The names drawn by py_trees, one per line, without the marks ({-}, -->, -^-), indentation and <Type>."""
    names = []
    for line in text.splitlines():
        parts = line.strip().split(" ", 1)
        if len(parts) == 2 and parts[0] in {"{-}", "[-]", "{o}", "[o]", "/_/", "-^-", "-->"}:
            names.append(re.sub(r"^<[^>]*> ", "", parts[1]))
    return names


def access_section(text: str, key: str) -> tuple[str, str]:
    """The 'written by' and 'read by' lines of ``key`` in the blackboard table."""
    lines = text.splitlines()
    at = lines.index(f"  {key}")
    written, read = lines[at + 1].strip(), lines[at + 2].strip()
    assert written.startswith("written by") and read.startswith("read by"), (written, read)
    return written.removeprefix("written by").strip(), read.removeprefix("read by").strip()


def status_queue(name: str, *statuses: Status) -> py_trees.behaviours.StatusQueue:
    return py_trees.behaviours.StatusQueue(name=name, queue=list(statuses), eventually=Status.SUCCESS)


def small_tree() -> py_trees.composites.Sequence:
    """look: RUNNING once, then SUCCESS; move: RUNNING three times, then SUCCESS."""
    return py_trees.composites.Sequence(
        name="job",
        memory=True,
        children=[
            status_queue("look", Status.RUNNING, Status.SUCCESS),
            status_queue("move", Status.RUNNING, Status.RUNNING, Status.RUNNING, Status.SUCCESS),
        ],
    )


class FakeWallClock:
    def __init__(self) -> None:
        self.now_s = 100.0

    def __call__(self) -> float:
        return self.now_s


class FakeTerminal(io.StringIO):
    def isatty(self) -> bool:
        return True


# ----------------------------------------------------------------------------------------------
# text
# ----------------------------------------------------------------------------------------------


def test_text_names_each_node_by_its_bt_cpp_type_with_the_py_trees_class_where_it_differs() -> None:
    lines = render_tree(two_cubes()).splitlines()
    assert lines[0].startswith("{-} <Arrangement> ")
    assert any(line.strip().startswith("-^- <ForceSuccess (py_trees FailureIsSuccess)> ") for line in lines)
    assert any(line.strip().startswith("-^- <RepeatUntilWithin> ") for line in lines)
    assert any(line.strip().startswith("--> <Pick> pick red") for line in lines)


def test_text_names_the_behaviours_of_two_cubes_in_order() -> None:
    text = render_tree(two_cubes())
    names = tree_lines(text)
    positions = [names.index(name) for name in TWO_CUBES_IN_ORDER]
    assert positions == sorted(positions)
    # 30 per cube (14, the 11 that place it again when its pushes stall and the 5 that separate touching
    # parts before the pick), the root, the arm parked at the end
    assert len(names) == 62
    assert "[" not in text and "\x1b" not in text  # a fresh tree: no statuses, no escapes
    assert "Blackboard keys" not in text and "Blackboard:" not in text


def test_text_shows_statuses_once_the_tree_has_run() -> None:
    root = small_tree()
    root.tick_once()
    text = render_tree(root)
    assert "look [" in text and "move [" in text
    assert "\x1b" not in text


def test_text_with_blackboard_lists_who_writes_and_who_reads_each_key() -> None:
    text = render_tree(two_cubes(), blackboard=True)
    writers, readers = access_section(text, "/red/pose")
    assert writers.split(", ")[0] == "detect red"
    assert "inspect red" in writers.split(", ")
    assert readers.split(", ") == [
        "push a part touching red aside",
        "pick red",
        "push red",
        "pick red to place it again",
        "push red after placing it again",
    ]
    writers, readers = access_section(text, "/red/target")
    assert writers == "red target"
    assert "place red" in readers.split(", ")
    writers, readers = access_section(text, "/green/offset_mm")
    assert "inspect green" in writers.split(", ")
    assert readers == "correct green to 1 mm, correct green to 1 mm after placing it again"
    assert tree_lines(text) == tree_lines(render_tree(two_cubes()))  # the tree itself drawn as without


def test_blackboard_access_covers_only_the_given_tree() -> None:
    two_cubes()  # a tree built earlier leaves its clients on the global blackboard
    root = arrangement([Target("red", 0.45, 0.05)])
    access = {entry.key: entry for entry in blackboard_access(root)}
    assert "/green/pose" not in access
    assert access["/red/pose"].writers == [
        "detect red",
        "detect red after separating",
        "inspect red after placing",
        "inspect red",
        "inspect red after placing it again",
        "inspect red after pushing it again",
    ]


def test_text_is_written_to_out(tmp_path: Path) -> None:
    out = tmp_path / "tree.txt"
    text = render_tree(two_cubes(), "text", blackboard=True, out=out)
    assert out.read_text(encoding="utf-8") == text


def test_unwritable_out_is_a_display_error(tmp_path: Path) -> None:
    with pytest.raises(DisplayError, match="cannot write"):
        render_tree(two_cubes(), "text", out=tmp_path / "missing" / "tree.txt")


# ----------------------------------------------------------------------------------------------
# dot
# ----------------------------------------------------------------------------------------------


# pydot's parser (used only to check the source) calls pyparsing's deprecated camelCase API.
@pytest.mark.filterwarnings("ignore::DeprecationWarning:pydot.dot_parser")
def test_dot_is_graphviz_source_naming_the_behaviours(tmp_path: Path) -> None:
    out = tmp_path / "tree.dot"
    source = render_tree(two_cubes(), "dot", out=out)
    assert out.read_text(encoding="utf-8") == source
    graphs = pydot.graph_from_dot_data(source)
    assert graphs is not None and len(graphs) == 1
    nodes = {node.get_name().strip('"') for node in graphs[0].get_nodes()}
    assert set(TWO_CUBES_IN_ORDER) <= nodes
    edges = {(e.get_source().strip('"'), e.get_destination().strip('"')) for e in graphs[0].get_edges()}
    assert ("transfer red", "find red, else separate it from touching parts") in edges
    assert ("find red, else separate it from touching parts", "detect red") in edges
    assert not any(node.startswith("/") for node in nodes)


@pytest.mark.filterwarnings("ignore::DeprecationWarning:pydot.dot_parser")
def test_dot_with_blackboard_draws_writer_and_reader_edges_of_this_tree_only() -> None:
    source = render_tree(two_cubes(), "dot", blackboard=True)
    assert render_tree(two_cubes(), "dot", blackboard=True) == source  # the first tree's clients do not show
    graphs = pydot.graph_from_dot_data(source)
    assert graphs is not None
    graph = graphs[0]
    edges = [(e.get_source().strip('"'), e.get_destination().strip('"')) for e in graph.get_edges()]
    edges += [
        (e.get_source().strip('"'), e.get_destination().strip('"'))
        for sub in graph.get_subgraphs()
        for e in sub.get_edges()
    ]
    assert ("detect red", "/red/pose") in edges
    assert ("/red/pose", "pick red") in edges
    assert edges.count(("detect red", "/red/pose")) == 1
    assert ("detect green", "/red/pose") not in edges


@needs_dot
def test_dot_source_is_accepted_by_graphviz(tmp_path: Path) -> None:
    out = tmp_path / "tree.svg"
    render_tree(two_cubes(), "svg", blackboard=True, out=out)
    assert "/red/pose" in out.read_text(encoding="utf-8")


# ----------------------------------------------------------------------------------------------
# png and svg
# ----------------------------------------------------------------------------------------------


@needs_dot
def test_png_and_svg_are_written(tmp_path: Path) -> None:
    png = render_tree(two_cubes(), "png", out=tmp_path / "tree.png")
    svg = render_tree(two_cubes(), "svg", out=tmp_path / "tree.svg")
    assert png == str(tmp_path / "tree.png") and svg == str(tmp_path / "tree.svg")
    assert Path(png).read_bytes().startswith(b"\x89PNG\r\n\x1a\n")
    text = Path(svg).read_text(encoding="utf-8")
    assert "<svg" in text and "detect red" in text and "park the arm" in text


@needs_dot
def test_picture_defaults_to_the_name_in_the_current_directory(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    assert render_tree(two_cubes(), "svg") == "arrangement.svg"
    assert render_tree(two_cubes(), "png", name="two cubes") == "two_cubes.png"
    assert (tmp_path / "arrangement.svg").stat().st_size > 0
    assert (tmp_path / "two_cubes.png").stat().st_size > 0


@pytest.mark.parametrize("fmt", ["png", "svg"])
def test_without_graphviz_pictures_are_a_display_error_with_the_install_hint(
    fmt: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("PATH", str(tmp_path))  # an empty directory: no 'dot' anywhere
    assert shutil.which("dot") is None
    out = tmp_path / f"tree.{fmt}"
    with pytest.raises(DisplayError) as caught:
        render_tree(two_cubes(), fmt, out=out)
    assert str(caught.value) == NO_GRAPHVIZ
    assert "apt-get install graphviz" in str(caught.value) and "brew install graphviz" in str(caught.value)
    assert "\n" not in str(caught.value)
    assert isinstance(caught.value, BtArrangeError)
    assert not out.exists()
    assert "detect red" in render_tree(two_cubes(), "text") and "digraph" in render_tree(two_cubes(), "dot")


def test_graphviz_failing_is_a_display_error(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    fake_dot = tmp_path / "dot"
    fake_dot.write_text("#!/bin/sh\necho 'Error: <stdin>: syntax error in line 3' >&2\nexit 1\n")
    fake_dot.chmod(fake_dot.stat().st_mode | stat.S_IXUSR)
    monkeypatch.setattr(display.rendering.shutil, "which", lambda name: str(fake_dot) if name == "dot" else None)
    with pytest.raises(DisplayError, match=r"\(exit status 1\): Error: <stdin>: syntax error in line 3$"):
        render_tree(two_cubes(), "png", out=tmp_path / "tree.png")


def test_unknown_format_is_a_display_error_naming_it_and_the_known_ones() -> None:
    with pytest.raises(DisplayError) as caught:
        render_tree(two_cubes(), "jpeg")
    message = str(caught.value)
    assert "'jpeg'" in message
    assert all(fmt in message for fmt in FORMATS)


def test_picture_named_for_another_format_is_a_display_error(tmp_path: Path) -> None:
    if not HAS_DOT:
        pytest.skip("Graphviz's 'dot' is not installed: the format check comes after the Graphviz check")
    with pytest.raises(DisplayError, match=r"ends in \.svg but the format is png"):
        render_tree(two_cubes(), "png", out=tmp_path / "tree.svg")
    with pytest.raises(DisplayError, match="does not exist"):
        render_tree(two_cubes(), "svg", out=tmp_path / "missing" / "tree.svg")


def test_a_root_that_is_not_a_behaviour_is_a_display_error() -> None:
    with pytest.raises(DisplayError, match="got NoneType"):
        render_tree(None, "text")  # type: ignore[arg-type]


# ----------------------------------------------------------------------------------------------
# LiveView
# ----------------------------------------------------------------------------------------------


def test_live_view_draws_on_change_but_throttles(monkeypatch: pytest.MonkeyPatch) -> None:
    clock, stream = FakeWallClock(), io.StringIO()
    view = LiveView(stream, min_interval_s=0.2, clock=clock)
    root = small_tree()
    root.tick_once()  # look RUNNING
    assert view.update(root, 0.01)  # the first frame is drawn at once
    clock.now_s += 0.05
    assert not view.update(root, 0.02)  # nothing changed, and too soon
    root.tick_once()  # look SUCCESS, move RUNNING
    assert not view.update(root, 0.03)  # changed, but only 0.05 s of wall time since the last frame
    clock.now_s += 0.2
    assert view.update(root, 0.04)  # the change is drawn once the interval has passed
    clock.now_s += 0.3
    assert not view.update(root, 0.05)  # unchanged: only refreshed every refresh_interval_s (1 s)
    clock.now_s += 0.8
    assert view.update(root, 0.06)  # the refresh moves the clock on
    assert view.frames == 3
    frames = stream.getvalue().split("-" * 72 + "\n")
    assert len(frames) == 3
    assert frames[0].startswith("world time 0.01 s | job RUNNING | look:")
    assert frames[1].startswith("world time 0.04 s | job RUNNING | move:")
    assert "look [✓]" in frames[1] and "move [*]" in frames[1]
    assert "look [*]" in frames[0] and "move [-]" in frames[0]


def test_live_view_final_frame_and_close() -> None:
    clock, stream = FakeWallClock(), io.StringIO()
    view = LiveView(stream, clock=clock)
    root = small_tree()
    root.tick_once()
    assert view.update(root, 0.1)
    for _ in range(4):
        root.tick_once()
    assert root.status == Status.SUCCESS
    assert view.update(root, 0.5, final=True)  # drawn although no wall time passed
    view.close()  # the final state is already on screen: not drawn twice
    assert view.frames == 2
    last = stream.getvalue().split("-" * 72 + "\n")[-1]
    assert last.startswith("world time 0.50 s | job SUCCESS")
    assert "move [✓]" in last


def test_live_view_close_draws_the_last_state_it_skipped() -> None:
    clock, stream = FakeWallClock(), io.StringIO()
    view = LiveView(stream, clock=clock)
    root = small_tree()
    root.tick_once()
    view.update(root, 0.1)
    for _ in range(4):
        root.tick_once()
    assert not view.update(root, 0.2)  # throttled
    view.close()
    view.close()
    assert view.frames == 2
    assert "world time 0.20 s | job SUCCESS" in stream.getvalue()


def test_live_view_writes_no_escapes_to_a_stream_that_is_not_a_terminal(monkeypatch: pytest.MonkeyPatch) -> None:
    # As if the program had started on a terminal: py_trees then colours statuses and bolds the tip.
    symbols = py_trees.display.unicode_symbols
    monkeypatch.setitem(symbols, Status.SUCCESS, "\x1b[32m✓\x1b[0m")
    monkeypatch.setitem(symbols, Status.RUNNING, "\x1b[34m*\x1b[0m")
    monkeypatch.setitem(symbols, "bold", "\x1b[1m")
    monkeypatch.setitem(symbols, "bold_reset", "\x1b[0m")
    clock, stream = FakeWallClock(), io.StringIO()
    view = LiveView(stream, clock=clock)
    root = small_tree()
    for _ in range(3):
        root.tick_once()
        view.update(root, 0.1, final=True)
    view.close()
    assert view.frames == 3
    assert "\x1b" not in stream.getvalue()
    assert "look [✓]" in stream.getvalue()


def test_live_view_redraws_in_place_on_a_terminal() -> None:
    terminal = FakeTerminal()
    view = LiveView(terminal, clock=FakeWallClock(), compact=False)
    root = small_tree()
    root.tick_once()
    view.update(root, 0.1)
    first = terminal.getvalue()
    assert "\x1b[" not in first.split("\n", 1)[0]  # nothing to erase before the first frame
    root.tick_once()
    view.update(root, 0.2, final=True)
    second = terminal.getvalue()[len(first) :]
    rows = len(first.rstrip("\n").split("\n"))
    assert second.startswith(f"\x1b[{rows}A\r\x1b[J")  # back to the first frame's top, erased
    assert "-" * 72 not in terminal.getvalue()


def test_live_view_compact_expands_only_running_subtrees() -> None:
    stream = io.StringIO()
    view = LiveView(stream, clock=FakeWallClock(), compact=True)
    root = py_trees.composites.Sequence(
        name="job",
        memory=True,
        children=[
            py_trees.composites.Sequence(name="first", memory=True, children=[status_queue("a")]),
            py_trees.composites.Sequence(name="second", memory=True, children=[status_queue("b", Status.RUNNING)]),
        ],
    )
    root.tick_once()  # first done, second running
    view.update(root, 1.0)
    text = stream.getvalue()
    assert "first [✓]" in text and "second [*]" in text
    assert "--> <StatusQueue> b [*]" in text  # inside the running subtree, named by its type as the XML would
    assert "a [" not in text  # the finished subtree is folded
    assert "..." in text


@needs_dot
def test_a_six_part_plan_s_picture_stays_readable_in_width(tmp_path):
    import cv2

    from bt_arrange import examples, plans

    root = plans.load(examples.path_of("six_in_a_row")).create_root()
    path = Path(render_tree(root, "png", out=tmp_path / "six.png"))
    height, width = cv2.imread(str(path)).shape[:2]
    assert width <= 2500 < height, (width, height)
