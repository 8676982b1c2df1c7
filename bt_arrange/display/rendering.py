"""A tree as text, as Graphviz source, or as a PNG or SVG picture (``dot``), built without a robot."""

from __future__ import annotations

import re
import shutil
import subprocess
import textwrap
import uuid
from pathlib import Path

import py_trees
import pydot
from py_trees.common import Status

from bt_arrange.display.blackboard import _preorder, blackboard_access, blackboard_table
from bt_arrange.errors import DisplayError

FORMATS = ("text", "dot", "png", "svg")
PICTURE_FORMATS = ("png", "svg")

NO_GRAPHVIZ = (
    "PNG and SVG need Graphviz's 'dot' program, which is not installed: install it with 'apt-get install graphviz' "
    "(Debian/Ubuntu) or 'brew install graphviz' (macOS); --format text or dot work without it"
)

#: Wall time [s] a ``dot`` run may take before it counts as failed (a 60-node tree takes ~0.1 s).
DOT_TIMEOUT_S = 60.0

_ANSI_ESCAPE = re.compile(r"\x1b\[[0-9;?]*[ -/]*[@-~]")


def strip_ansi(text: str) -> str:
    """``text`` without terminal escape sequences (py_trees adds colours when stdout is a terminal)."""
    return _ANSI_ESCAPE.sub("", text)


# ----------------------------------------------------------------------------------------------
# Text and Graphviz
# ----------------------------------------------------------------------------------------------


def _has_run(root: py_trees.behaviour.Behaviour) -> bool:
    """True once any behaviour of the tree has a status (a freshly built tree has none)."""
    return any(node.status != Status.INVALID for node in root.iterate())


def with_types(
    text: str,
    root: py_trees.behaviour.Behaviour,
    *,
    visited: dict[uuid.UUID, Status] | None = None,
    classes: bool = False,
) -> str:
    """py_trees' text tree with each node's BehaviorTree.CPP type before its name, as the XML writes it.

    ``-^- <ForceSuccess> then the next (red) [✓]``; ``classes`` adds the py_trees class where it
    differs (``<ForceSuccess (py_trees FailureIsSuccess)>``). ``visited`` is what the text was drawn
    with (``show_only_visited``): a collapsed subtree is one ``...`` line. Text that does not line
    up with the tree (not drawn by py_trees) is returned as it is.
    """
    from bt_arrange.xmltree import tag_of, type_label

    order: list[py_trees.behaviour.Behaviour | None] = [root]

    def walk(node: py_trees.behaviour.Behaviour) -> None:
        for child in node.children:
            order.append(child)
            if child.children:
                if visited is None or child.id in visited:
                    walk(child)
                else:
                    order.append(None)  # py_trees' "..." line

    walk(root)
    lines = text.rstrip("\n").split("\n")
    if len(lines) != len(order):
        return text
    typed = []
    for line, node in zip(lines, order, strict=True):
        if node is not None:
            name = node.name.replace("\n", " ")
            at = line.find(name)
            if at >= 0:
                label = type_label(node) if classes else tag_of(node)
                line = f"{line[:at]}<{label}> {line[at:]}"
        typed.append(line)
    return "\n".join(typed) + ("\n" if text.endswith("\n") else "")


def text_tree(root: py_trees.behaviour.Behaviour, *, blackboard: bool = False) -> str:
    """py_trees' unicode tree with the nodes' BehaviorTree.CPP types, statuses once it has run, optionally its keys."""
    text = with_types(strip_ansi(py_trees.display.unicode_tree(root, show_status=_has_run(root))), root, classes=True)
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


#: Characters per line of a node's label in a picture.
LABEL_WIDTH = 20


def _wrap_labels(graph: pydot.Dot) -> None:
    """Break each node's label into lines of at most ``LABEL_WIDTH`` characters (at spaces)."""
    for node in graph.get_nodes():
        label = node.get("label")
        if not label:
            continue
        text = str(label).strip('"')
        if len(text) > LABEL_WIDTH:
            node.set("label", '"' + "\\n".join(textwrap.wrap(text, LABEL_WIDTH)) + '"')


def dot_graph(root: py_trees.behaviour.Behaviour, *, blackboard: bool = False) -> pydot.Dot:
    """``py_trees.display.dot_tree(root)``, plus this tree's blackboard keys when asked.

    The keys are drawn as py_trees draws them (boxes in a "Blackboard" subgraph ranked below the tree, a
    blue edge from each writer, a green edge to each reader) but only for the given tree: py_trees'
    own ``with_blackboard_variables`` draws every client still registered on the global blackboard,
    so a second tree built in the same process would appear twice.
    """
    graph = py_trees.display.dot_tree(root)
    # Left to right, labels wrapped: a plan's parts stack downwards, so a six-part tree stays about
    # 2,000 px wide (top-down with one line per label it was 13,000).
    graph.set("rankdir", "LR")
    _wrap_labels(graph)
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
