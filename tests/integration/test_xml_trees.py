"""A tree exported to XML and read back runs as its Python file or plan does: same statuses, same offsets, same seed."""

import json
from pathlib import Path

import pytest

from bt_arrange import treefile, xmltree
from bt_arrange_sim.pybullet.runs import SimulatedRun

TREES = Path(__file__).resolve().parents[2] / "trees"


def run(path: Path) -> tuple[dict, list[dict]]:
    module = treefile.load(path)
    seed = getattr(module, "default_seed", 0)  # a plan's [scene] seed, which its XML export carries
    with SimulatedRun(treefile.build_root(module), treefile.scene(module, seed=seed)) as simulated:
        report = simulated.run()
    # Each transition as its line of transitions.jsonl (the recorded run's form: facts only when stated).
    return report.to_dict(), [json.loads(t.to_json()) for t in report.transitions]


def same_node(transition: dict) -> dict:
    """A transition without its node id: the id names a node of one tree, and these are two trees."""
    return {k: v for k, v in transition.items() if k != "node_id"}


def without_wall_time(report: dict) -> dict:
    return {k: v for k, v in report.items() if k != "wall_seconds"}


@pytest.mark.parametrize(
    "stem",
    [
        "single_cube",
        "four_cubes",
        "row_of_three",
        "four_cubes_after_all",
        "dense_block",
        "dense_row",
    ],
)
def test_the_xml_tree_runs_as_its_python_file(stem, request):
    python_report, python_transitions = run(TREES / f"{stem}.py")
    if stem == "four_cubes":  # the recorded CLI run of the XML file, shared with the replay-page tests
        record = request.getfixturevalue("four_cubes_xml_record")
        xml_report, xml_transitions = record["report"], record["transitions"]
    else:
        xml_report, xml_transitions = run(TREES / f"{stem}.xml")
    assert xml_report["tree_status"] == "SUCCESS"
    assert len(xml_transitions) == len(python_transitions) > 20
    for xml_t, python_t in zip(xml_transitions, python_transitions, strict=True):
        assert same_node(xml_t) == same_node(python_t)
    assert json.dumps(without_wall_time(xml_report)) == json.dumps(without_wall_time(python_report))


@pytest.mark.parametrize("stem", ["irregular_parts", "fresco"])
def test_a_plan_of_prisms_exported_to_xml_runs_as_the_plan(stem, tmp_path):
    """Outlines, square pushes, releases off a piece's centroid and the scene's seed all survive the export."""
    plan = TREES / f"{stem}.toml"
    if stem == "fresco":
        # Three pieces, not six: the same kinds of steps, a third of the world time (the example itself
        # runs whole in test_examples.py).
        text = plan.read_text(encoding="utf-8")
        assert "pieces = 6 " in text
        plan = tmp_path / "fresco.toml"
        plan.write_text(text.replace("pieces = 6 ", "pieces = 3 "), encoding="utf-8")
    else:
        # At 1 mm every part is set down within: at 0.3 mm some are pushed.
        text = plan.read_text(encoding="utf-8")
        assert "threshold_mm = 1.0\n" in text
        plan = tmp_path / f"{stem}.toml"
        plan.write_text(text.replace("threshold_mm = 1.0\n", "threshold_mm = 0.3\n"), encoding="utf-8")
    exported = tmp_path / f"{stem}.xml"
    exported.write_text(xmltree.to_xml(treefile.build_root(treefile.load(plan)), tree_id=stem))
    plan_report, plan_transitions = run(plan)
    xml_report, xml_transitions = run(exported)
    assert xml_report["tree_status"] == "SUCCESS"
    assert any(o["pushes"] for o in xml_report["objects"]), "the run pushes, so the pushes' ports are checked too"
    assert [same_node(t) for t in xml_transitions] == [same_node(t) for t in plan_transitions]
    assert json.dumps(without_wall_time(xml_report)) == json.dumps(without_wall_time(plan_report))
