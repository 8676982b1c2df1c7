"""A tree that grows while it runs (a puzzle's ``ArrangeSolved``), served to a Groot2 client.

The publisher numbers the tree again when it sees a node it does not know: the full tree then
holds the new nodes, statuses already shown are kept, and every reply names a new tree UUID.
The XML writer writes a leaf's built children only for that view (as a control node), never
into a file.
"""

from __future__ import annotations

import struct
import xml.etree.ElementTree as ET

import py_trees
import pytest
from py_trees.common import Status

from bt_arrange import xmltree
from bt_arrange.groot2 import Groot2Publisher, protocol
from bt_arrange.puzzle import PuzzleSpec
from bt_arrange.runner import TransitionLog
from bt_arrange.trees.puzzle import ArrangeSolved

pytest.importorskip("zmq")
pytest.importorskip("msgpack")
from test_groot2 import Client, free_port_pair  # noqa: E402  (the raw protocol client)


class Grows(py_trees.composites.Sequence):
    """A sequence that builds its two children on its first tick, as ``ArrangeSolved`` does from the solve."""

    def __init__(self, name: str) -> None:
        super().__init__(name=name, memory=True, children=[])

    def tick(self):
        if not self.children:
            self.add_children([py_trees.behaviours.Success("built 1"), py_trees.behaviours.Running("built 2")])
        yield from super().tick()


def tick(root, publisher, log: TransitionLog) -> None:
    for _ in root.tick():
        pass
    for transition in log.observe(root, 0.0):
        publisher.on_transition(transition)


def served_names(client: Client) -> list[tuple[str, int]]:
    tree = ET.fromstring(client.ask("T")[1].decode())
    return [(e.get("name"), int(e.get("_uid"))) for e in tree.find("BehaviorTree").iter() if e.get("_uid")]


def test_a_grown_tree_is_served_again_with_its_new_nodes_under_a_new_uuid() -> None:
    root = py_trees.composites.Sequence(
        "root", memory=True, children=[py_trees.behaviours.Success("first"), Grows("grows")]
    )
    with Groot2Publisher(root, free_port_pair(), tree_id="root") as publisher:
        client = Client(publisher.port)
        try:
            assert served_names(client) == [("root", 1), ("first", 2), ("grows", 3)]
            before = client.ask("S")[0][6:]
            log = TransitionLog()
            tick(root, publisher, log)
            reply = client.ask("S")
            assert reply[0][6:] != before, "the header names another tree once it grew"
            assert served_names(client) == [("root", 1), ("first", 2), ("grows", 3), ("built 1", 4), ("built 2", 5)]
            codes = dict(struct.unpack_from("<HB", reply[1], k) for k in range(0, len(reply[1]), 3))
            assert codes[2] == protocol.SUCCESS  # shown before the growth, kept
            assert codes[4] == protocol.SUCCESS and codes[5] == protocol.RUNNING
            assert codes[1] == codes[3] == protocol.RUNNING
        finally:
            client.close()


def test_refresh_numbers_a_grown_tree_again_too() -> None:
    root = Grows("grows")
    with Groot2Publisher(root, free_port_pair()) as publisher:
        uuid_before = publisher.tree_uuid
        for _ in root.tick():
            pass
        publisher.refresh()
        assert publisher.tree_uuid != uuid_before
        assert [n.name for n in publisher.nodes] == ["grows", "built 1", "built 2"]
        assert publisher.status_buffer()[3 * 2 + 2] == protocol.RUNNING
        assert root.status == Status.RUNNING


SPEC = PuzzleSpec("slab", (0.16, 0.12, 0.02), 4, 0.002, "red", 0.5, 0.0, 0.0)


def test_a_built_leaf_is_written_as_a_leaf_in_a_file_and_with_its_children_for_groot2() -> None:
    node = ArrangeSolved("arrange slab", SPEC, {})
    node.add_child(py_trees.behaviours.Success("then the next (slab 1)"))
    in_file = ET.fromstring(xmltree.to_xml(node))
    leaf = in_file.find("BehaviorTree/ArrangeSolved")
    assert leaf is not None and list(leaf) == []
    assert in_file.find("TreeNodesModel/Action[@ID='ArrangeSolved']") is not None
    viewed = ET.fromstring(xmltree.to_xml(node, generic=True))
    grown = viewed.find("BehaviorTree/ArrangeSolved")
    assert [child.get("name") for child in grown] == ["then the next (slab 1)"]
    assert viewed.find("TreeNodesModel/Control[@ID='ArrangeSolved']") is not None
