"""The replay page of a tree that grows while it runs (a puzzle's pieces), and records shown as tables."""

from __future__ import annotations

import json
import re
from dataclasses import dataclass
from pathlib import Path

import py_trees

from bt_arrange.replay import ReplayRecorder, table_of


class Grows(py_trees.composites.Sequence):
    """A sequence that builds its children on its first tick, as ``ArrangeSolved`` does from the solve."""

    def __init__(self, name: str) -> None:
        super().__init__(name=name, memory=True, children=[])

    def tick(self):  # noqa: ANN201
        if not self.children:
            self.add_children([py_trees.behaviours.Success("built 1"), py_trees.behaviours.Running("built 2")])
        yield from super().tick()


def payload(page: Path) -> dict:
    match = re.search(r'<script id="replay-data" type="application/json">(.*?)</script>', page.read_text(), re.S)
    assert match is not None
    return json.loads(match.group(1))


def test_nodes_built_while_the_tree_runs_are_on_the_page_under_their_parent(tmp_path: Path) -> None:
    root = py_trees.composites.Sequence(
        "root", memory=True, children=[Grows("arrange slab"), py_trees.behaviours.Success("after")]
    )
    recorder = ReplayRecorder(root)
    recorder.observe(0.0)
    assert [node["name"] for node in recorder.nodes] == ["root", "arrange slab", "after"]
    root.tick_once()
    recorder.observe(1.5)
    data = payload(recorder.write(tmp_path / "replay.html", title="growing"))
    names = [node["name"] for node in data["nodes"]]
    assert names == ["root", "arrange slab", "built 1", "built 2", "after"]  # the tree's order, not birth order
    parents = {node["name"]: names[node["parent"]] for node in data["nodes"] if node["parent"] >= 0}
    assert parents == {"arrange slab": "root", "built 1": "arrange slab", "built 2": "arrange slab", "after": "root"}
    born = {node["name"]: node["born"] for node in data["nodes"]}
    assert born["built 1"] == 1.5 and born["after"] == 0.0
    # Each event names the node it is about after the renumbering.
    statuses = {(names[event["node"]], event["status"]) for event in data["events"]}
    assert ("built 1", "SUCCESS") in statuses and ("built 2", "RUNNING") in statuses
    assert ("after", "SUCCESS") not in statuses


@dataclass(frozen=True)
class Piece:
    name: str
    centre_m: tuple[float, float]
    outline_m: tuple[tuple[float, float], ...]


def test_a_sequence_of_records_is_a_table_with_long_fields_summarised() -> None:
    outline = tuple((0.01 * i, 0.02 * i) for i in range(8))
    table = table_of((Piece("slab 1", (0.36, -0.13), outline), Piece("slab 2", (0.4, 0.1), outline[:1])))
    assert table is not None
    assert table["columns"] == ["name", "centre_m", "outline_m"]
    assert table["rows"][0] == ["slab 1", "(0.3600, -0.1300)", "8 values"]
    assert table["rows"][1][2] == "((0.0000, 0.0000))"
    assert table_of([]) is None and table_of((1.0, 2.0)) is None and table_of("text") is None


def test_the_blackboard_entry_of_records_carries_its_table(tmp_path: Path) -> None:
    storage = py_trees.blackboard.Blackboard.storage
    storage["/slab/pieces"] = (Piece("slab 1", (0.36, -0.13), ()),)
    try:
        recorder = ReplayRecorder(py_trees.behaviours.Success("root"))
        recorder.observe(0.0)
        (entry,) = [e for e in recorder.blackboard if e["key"] == "/slab/pieces"]
        assert entry["table"]["rows"] == [["slab 1", "(0.3600, -0.1300)", "()"]]
    finally:
        del storage["/slab/pieces"]
