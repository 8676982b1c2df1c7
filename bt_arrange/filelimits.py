"""Limits on the files a user may have been sent: XML trees, plan files, cell files.

A file from elsewhere must not exhaust the machine: each is refused with one line naming the
limit before it is built, and no input raises a traceback. The limits are generous (tens of
times what the shipped files need, docs/xml.md and docs/plans.md) and documented:

| limit | value | the shipped files need |
|---|---|---|
| ``MAX_FILE_BYTES``: a tree, plan or cell file's size | 1 MiB | 26 KB (``trees/dense_row_identical.xml``) |
| ``MAX_TREE_NODES``: nodes of a tree, SubTrees expanded | 10,000 | 316 (a 3 x 3 grid of identical cubes) |
| ``MAX_TREE_DEPTH``: nesting of a tree, SubTrees expanded (and of an XML file's elements) | 100 | 10 |
| ``MAX_TARGETS``: targets (and starts) of a plan file | 200 | 9 |
| ``MAX_COLOURS``: colours of a plan file | 64 | 2 |
| ``MAX_OUTLINE_POINTS``: points of one outline (``outline_mm``) | 256 | 6 (``irregular_parts.toml``'s fragment) |
| ``MAX_PLAN_OUTLINE_POINTS``: points of all a plan file's outlines | 768 | 24 (``irregular_parts.toml``) |
| ``MAX_OBJECT_TYPES``: types of a plan file (``[objects.NAME]``) | 12 | 5 (``irregular_parts.toml``) |

The last three are set by what judging a type costs as the plan loads (``benchmarks/outline_limits.py``):
its outline's checks, the search for where the pads can close (``bt_arrange.shapes.antipodal``) and
the yaw check (``bt_arrange.shapes.yaw_feature``) each take O(n log n) for n points (the grasp
search's n^2 / 2 pairs of edges aside, taken at once in numpy: 5 ms for 256 points), a part fixed a
type (every closing axis, every coarse turn) and a part a point: about 0.12 s of CPU for a round
64-point type, 0.24 s for a 256-point one, so that the hardest plan tried within them (12 round
64-point types) loads in 1.6 s.

``read_limited(path, what)`` reads a file's text within ``MAX_FILE_BYTES``; ``check_tree_size(root,
where)`` walks a built tree without recursion and refuses one beyond the node or depth limit.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from bt_arrange.errors import BtArrangeError, TreeFileError

MAX_FILE_BYTES = 1024 * 1024
MAX_TREE_NODES = 10_000
MAX_TREE_DEPTH = 100
MAX_TARGETS = 200
MAX_COLOURS = 64
#: Points of one outline (a prism's top face): every outline check after this one is O(n log n).
MAX_OUTLINE_POINTS = 256
#: Points of all the outlines of a plan file's types together: three of ``MAX_OUTLINE_POINTS``, or twelve of 64.
MAX_PLAN_OUTLINE_POINTS = 768
#: Types of a plan file (``[objects.NAME]``, the cube aside): each is judged (its grasps searched) as it loads.
MAX_OBJECT_TYPES = 12


def too_large(what: str, path: Path | str, size: int) -> str:
    """The message for a file over ``MAX_FILE_BYTES``."""
    return (
        f"{what} {path} is {size:,} bytes, over the limit of {MAX_FILE_BYTES:,} bytes "
        "(bt_arrange.filelimits.MAX_FILE_BYTES); the shipped files are under 30 KB"
    )


def read_limited(path: Path | str, what: str, error: type[BtArrangeError] = BtArrangeError) -> str:
    """The UTF-8 text of ``path``; ``error`` (one line) when it is over ``MAX_FILE_BYTES`` or unreadable.

    Only ``MAX_FILE_BYTES + 1`` bytes are read, whatever the file's size (a device, a pipe).
    A missing file raises ``FileNotFoundError`` for the caller to word.
    """
    path = Path(path)
    try:
        with path.open("rb") as handle:
            data = handle.read(MAX_FILE_BYTES + 1)
    except FileNotFoundError:
        raise
    except OSError as problem:
        raise error(f"cannot read {what} {path}: {problem.strerror or problem}") from None
    if len(data) > MAX_FILE_BYTES:
        size = path.stat().st_size if path.is_file() else len(data)
        raise error(too_large(what, path, size))
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        raise error(f"{what} {path} is not UTF-8 text") from None


def tree_counts(root: Any) -> tuple[int, int]:
    """The number of nodes and the depth of a py_trees tree, walked without recursion (stops past a limit)."""
    nodes, depth = 0, 0
    stack = [(root, 1)]
    while stack:
        node, level = stack.pop()
        nodes += 1
        depth = max(depth, level)
        if nodes > MAX_TREE_NODES or depth > MAX_TREE_DEPTH:
            break
        stack.extend((child, level + 1) for child in getattr(node, "children", ()))
    return nodes, depth


def check_tree_size(root: Any, where: str) -> None:
    """A ``TreeFileError`` (one line, the limit named) for a tree beyond ``MAX_TREE_NODES`` or ``MAX_TREE_DEPTH``."""
    nodes, depth = tree_counts(root)
    if nodes > MAX_TREE_NODES:
        raise TreeFileError(
            f"{where}: the tree has more than {MAX_TREE_NODES:,} nodes, the limit "
            "(bt_arrange.filelimits.MAX_TREE_NODES)"
        )
    if depth > MAX_TREE_DEPTH:
        raise TreeFileError(
            f"{where}: the tree nests more than {MAX_TREE_DEPTH} levels deep, the limit "
            "(bt_arrange.filelimits.MAX_TREE_DEPTH)"
        )
