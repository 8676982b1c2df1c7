"""``bt-arrange run puzzle`` in the pybullet cell: seen, solved and reassembled from the camera alone."""

from __future__ import annotations

import json
import re

import py_trees
import pytest

from bt_arrange import treefile
from bt_arrange.plan.layout import Outline, gap_m
from bt_arrange_sim.puzzles import PieceStart
from bt_arrange_sim.pybullet.runs import SimulatedRun


@pytest.fixture(scope="module")
def reassembled():
    module = treefile.load("puzzle")
    root = treefile.build_root(module)
    scene = treefile.scene(module, 0)
    with SimulatedRun(root, scene) as run:
        report = run.run()
        board = {key: value for key, value in py_trees.blackboard.Blackboard.storage.items()}
        # The pieces as the simulator made them (their true outlines, in their own frames), where they ended.
        outlines = {}
        for start in scene:
            x, y, yaw = run.cell.part_planar_truth(start.name)
            convex = tuple(tuple(map(tuple, piece)) for piece in start.object_type.shape.convex_pieces())
            outlines[start.name] = Outline(x, y, yaw, convex)
    return report, root, scene, board, outlines


def test_every_piece_ends_within_1_mm_and_1_deg_of_its_true_home(reassembled) -> None:
    report, root, _, _, _ = reassembled
    objects = report.to_dict()["objects"]
    assert [o["name"] for o in objects] == [f"slab {k}" for k in range(1, 7)]
    for outcome in objects:
        assert outcome["status"] == "within", outcome
        assert len(outcome["truth_home_mm"]) == 3  # contract: where the break says it belongs (evaluation only)
        assert outcome["final_offset_truth_mm"] < 1.0, outcome
        assert abs(outcome["final_yaw_error_truth_deg"]) < 1.0, outcome
    json.dumps(report.to_dict(), allow_nan=False)  # the --json report stays JSON


def test_no_two_pieces_touch(reassembled) -> None:
    _, _, _, _, outlines = reassembled
    names = list(outlines)
    smallest = min(gap_m(outlines[a], outlines[b]) for i, a in enumerate(names) for b in names[i + 1 :])
    assert smallest > 0.001  # the plan's gap is 2 mm; each piece within 0.8 mm by the camera


def test_the_tree_s_blackboard_holds_what_the_camera_measured_never_the_break(reassembled) -> None:
    """Honesty (item 5): no value on the blackboard is the simulator's: no start, no fragment's name, no home."""
    _, _, scene, board, _ = reassembled
    assert all(isinstance(start, PieceStart) for start in scene)
    homes = {start.home for start in scene}
    for key, value in board.items():
        assert "fragment" not in key
        for item in value if isinstance(value, tuple) else (value,):
            assert not isinstance(item, PieceStart), key
            assert getattr(item, "home", None) not in homes, key


def test_a_puzzle_at_the_default_gap_and_threshold_is_solved_and_placed(tmp_path) -> None:
    """2 mm gaps at a 1 mm threshold: the solved places (1.99 mm apart as measured) are spread to the layout's 2 mm."""
    from bt_arrange import examples

    text = examples.path_of("puzzle").read_text(encoding="utf-8")
    assert "threshold_mm = 0.8\n" in text and "gap_mm = 2 " in text
    plan = tmp_path / "defaults.toml"
    plan.write_text(text.replace("threshold_mm = 0.8\n", "").replace("yaw_threshold_deg = 0.8\n", ""))
    module = treefile.load(plan)
    record = tmp_path / "record"
    with SimulatedRun(treefile.build_root(module), treefile.scene(module, 0), record_dir=record) as run:
        report = run.run()
    assert report.threshold_mm == 1.0 and report.sim_seconds > 30.0, "the pieces moved"
    for outcome in report.to_dict()["objects"]:
        assert outcome["status"] == "within", outcome
        assert outcome["final_offset_truth_mm"] < 1.0, outcome
    # The record shows every piece: the solved targets join the scene on /parts and the offsets on /offsets.
    pytest.importorskip("mcap_protobuf")
    from test_foxglove_mcap import read

    _, decoded = read(record)
    pieces = {f"slab {k}" for k in range(1, 7)}
    scenes = [value for _, channel, _, value in decoded if channel.topic == "/parts"]
    assert {e.id for e in scenes[-1].entities} >= {f"part/{name}" for name in pieces}
    offsets = [value for _, channel, _, value in decoded if channel.topic == "/offsets"]
    assert {part["name"] for part in offsets[-1]["parts"]} == pieces
    # The tree grows as it runs: /tree names each piece's steps once they are built ...
    trees = [value for _, channel, _, value in decoded if channel.topic == "/tree"]
    last_names = {row["name"] for row in trees[-1]["nodes"]}
    assert len(trees[-1]["nodes"]) > len(trees[0]["nodes"])
    assert {f"transfer {name}" for name in pieces} <= last_names
    # ... and so does the replay page, where the pieces are a table on the blackboard.
    page = (record / "replay.html").read_text()
    data = json.loads(re.search(r'<script id="replay-data" type="application/json">(.*?)</script>', page, re.S)[1])
    names = [node["name"] for node in data["nodes"]]
    assert {"survey slab", "solve slab", "transfer slab 1", "arrange slab 6"} <= set(names)
    assert {names[event["node"]] for event in data["events"]} >= {"transfer slab 1", "transfer slab 6"}
    (solved,) = {json.dumps(b["table"]) for b in data["blackboard"] if b["key"] == "/slab/solved" and "table" in b}
    assert [row[4] for row in json.loads(solved)["rows"]] == [f"slab {k}" for k in range(1, 7)]
