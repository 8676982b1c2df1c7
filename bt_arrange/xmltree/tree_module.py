"""An XML tree as a tree-file module (``create_root()``, ``create_scene(seed)``), and its structure.

``iter_structure`` lists what a round trip through XML must keep: every node's depth, tag, name
and port values.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any

import py_trees

from bt_arrange.errors import XmlTreeError
from bt_arrange.filelimits import read_limited
from bt_arrange.trees import Arrangement
from bt_arrange.xmltree.reader import from_xml, load_xml
from bt_arrange.xmltree.registry import model_of

if TYPE_CHECKING:
    from bt_arrange.backends import Backend


def load_module(path: str | Path) -> ModuleType:
    """An XML tree as a tree-file module: ``create_root()`` builds it, ``create_scene(seed)`` places the cubes.

    The file is read and checked once, here; every ``create_root()`` builds a fresh tree. The scene
    is the one every file of ``trees/`` uses: the plan's cubes scattered by ``seed``, clear of the
    targets, so the XML root must be an ``<Arrangement>`` (its ``targets`` say what to scatter).
    ``create_scene(seed, backend)`` asks the run's backend to scatter them (default: the default backend).
    """
    path = Path(path)
    text_root = load_xml(path)  # fails here, before anything runs, on any error of the file
    source = read_limited(path, "XML tree", XmlTreeError)
    module = ModuleType(f"bt_arrange_xml_tree_{path.stem}", f"BehaviorTree.CPP XML tree {path}")
    module.__file__ = str(path)

    def create_root(threshold_mm: float | None = None) -> py_trees.behaviour.Behaviour:
        if threshold_mm is not None:
            raise XmlTreeError(
                f"{path}: an XML tree states its threshold in its ports (threshold_mm of Arrangement and "
                "RepeatUntilWithin): edit them instead of passing --threshold-mm"
            )
        return from_xml(source, source=str(path))

    def create_scene(seed: int = 0, backend: Backend | None = None) -> list[Any]:
        if not isinstance(text_root, Arrangement):
            raise XmlTreeError(
                f"{path}: the simulator places cubes from the plan of an <Arrangement> root; "
                f"this tree's root is <{model_of(text_root).tag}>"
            )
        from bt_arrange.backends import PuzzleBackend, ScatteringBackend, require

        if backend is None:
            from bt_arrange import backends  # the default backend, loaded only to run

            backend = backends.load()
        targets = text_root.targets
        if text_root.puzzles:  # each slab broken from the seed by the backend (its pieces' outlines stay there)
            # A declared capability of a backend: only a simulator can break a slab.
            puzzles = require(backend, PuzzleBackend, "break a [puzzle] slab")
            return list(puzzles.puzzle_scene(targets, text_root.puzzles, seed, starts=text_root.starts))
        if text_root.starts is not None:
            return list(text_root.starts)
        return require(backend, ScatteringBackend, "scatter a tree's parts").scatter(
            [t.colour for t in targets],
            seed,
            avoid=targets,
            object_types=[t.object_type for t in targets],
            names=[t.name for t in targets],
        )

    module.create_root = create_root  # type: ignore[attr-defined]
    module.create_scene = create_scene  # type: ignore[attr-defined]
    #: The seed ``bt-arrange run`` uses when no --seed is given: the exported plan's (``scene_seed``).
    module.default_seed = getattr(text_root, "scene_seed", 0)  # type: ignore[attr-defined]
    return module


def iter_structure(root: py_trees.behaviour.Behaviour) -> Iterator[tuple[int, str, str, dict[str, Any]]]:
    """``(depth, tag, name, port values)`` for every node top-down: what a round trip must keep."""

    def walk(node: py_trees.behaviour.Behaviour, depth: int) -> Iterator[tuple[int, str, str, dict[str, Any]]]:
        model = model_of(node)
        yield depth, model.tag, node.name, model.ports_of(node)
        for child in node.children:
            yield from walk(child, depth + 1)

    yield from walk(root, 0)
