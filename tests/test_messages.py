"""Messages a user can act on: each message added shows here, with what it says.

The pre-run check of the blackboard and the first real cause of a failure; plan errors naming the
file and the entry, in the file's units, with the fix; nearest-name suggestions; the mass limits;
the limits on shared files (XML trees, plans, cell files); the smaller fixes (the replay page's
markers, Fig. 4, the real cell's paper column). No simulator starts: the sessions run on
``tests/fakeworld.py``'s world, or are refused before one is built.
"""

from __future__ import annotations

import json
import re
import time
from pathlib import Path

import py_trees
import pytest
from fakeworld import FakeWorld, camera_view

from bt_arrange import plans, treefile, xmltree
from bt_arrange.behaviours import Detect, Pick, Place
from bt_arrange.errors import PlanError, TreeFileError, XmlTreeError
from bt_arrange.filelimits import MAX_FILE_BYTES, MAX_TARGETS, MAX_TREE_DEPTH, MAX_TREE_NODES
from bt_arrange.keycheck import check_keys
from bt_arrange.objects import ObjectStart, ObjectType
from bt_arrange.replay import ReplayRecorder
from bt_arrange.runner import Transition
from bt_arrange.session import Session
from bt_arrange.settings import ManipulationSettings
from bt_arrange.suggest import did_you_mean, nearest
from bt_arrange.trees import Target, arrangement, by_depth, validate_targets

ROOT = Path(__file__).resolve().parents[1]


class Opener:
    """``open_world`` that remembers whether it was called."""

    def __init__(self) -> None:
        self.opened = 0

    def __call__(self) -> FakeWorld:
        self.opened += 1
        return FakeWorld()


# ----------------------------------------------------------------------------------------------
# 1. Every key a node needs is written before it; the first real cause of a failure
# ----------------------------------------------------------------------------------------------


def test_a_hand_built_tree_without_the_target_setter_is_refused_before_anything_moves() -> None:
    root = py_trees.composites.Sequence(
        "blue",
        memory=True,
        children=[Detect("detect blue", "blue"), Pick("pick blue", "blue"), Place("place blue", "blue")],
    )
    opener = Opener()
    with pytest.raises(PlanError) as caught:
        Session(root, [ObjectStart("blue", 0.45, -0.2, 0.0)], opener, view=camera_view())
    assert str(caught.value) == (
        "'place blue' needs /blue/target on the blackboard, written by the tree's target setter (a "
        "SetBlackboardVariable, bt_arrange.trees.steps.set_target), but no node before it in the tree writes it: "
        "put that step before 'place blue' (checked before anything moves)"
    )
    assert opener.opened == 0


def test_a_key_written_only_after_its_reader_names_the_late_writer() -> None:
    target = Target("red", 0.45, 0.05)
    from bt_arrange.trees import set_target

    root = py_trees.composites.Sequence(
        "red",
        memory=True,
        children=[Detect("detect red", "red"), Pick("pick red", "red"), Place("place red", "red"), set_target(target)],
    )
    with pytest.raises(PlanError, match=r"; only 'red target', which runs after it, writes it: put that step before"):
        check_keys(root)
    with pytest.raises(PlanError, match=r"^'pick red' needs /red/pose on the blackboard, written by Detect of red"):
        check_keys(py_trees.composites.Sequence("s", memory=True, children=[Pick("pick red", "red")]))


@pytest.mark.parametrize(
    "options",
    [{}, {"correct": "after_all"}, {"strategy": "learned"}, {"strategy": "diagonal"}, {"yaw_threshold_deg": None}],
)
def test_every_tree_the_builders_make_passes_the_key_check(options: dict) -> None:
    check_keys(arrangement([Target("red", 0.45, 0.05), Target("blue", 0.55, 0.05)], **options))
    check_keys(arrangement([Target("red", 0.45, 0.05)], locate=by_depth()))


def test_every_shipped_tree_passes_the_key_check() -> None:
    paths = [*sorted((ROOT / "trees").glob("*.py")), *sorted((ROOT / "trees").glob("*.xml")), "six_in_a_row"]
    for path in paths:
        check_keys(treefile.build_root(treefile.load(path)))


def test_the_reason_of_a_failed_object_is_the_first_real_cause_not_the_last_symptom() -> None:
    root = arrangement([Target("red", 0.50, 0.05)])
    session = Session(root, [ObjectStart("red", 0.42, -0.22, 0.1)], FakeWorld, view=camera_view())
    try:
        by_type = {type(node).__name__: node for node in root.iterate()}

        def moment(node: py_trees.behaviour.Behaviour, new: str, feedback: str) -> Transition:
            return Transition(0.0, node.name, type(node).__name__, "RUNNING", new, feedback, str(node.id), "red")

        transitions = [
            moment(by_type["Detect"], "SUCCESS", "found red"),
            moment(by_type["Pick"], "SUCCESS", "grasped"),
            moment(by_type["Place"], "FAILURE", "place red needs /red/target on the blackboard"),
            moment(by_type["Detect"], "FAILURE", "not_found: no red blob"),
        ]
        assert session._last_failure(transitions, "red") == "place red needs /red/target on the blackboard"
        # A failure recovered from (Detect failed once, then everything succeeded up to a Push) is not the cause.
        recovered = [
            moment(by_type["Detect"], "FAILURE", "not_found: no red blob"),
            moment(by_type["Detect"], "SUCCESS", "found red"),
            moment(by_type["Push"], "FAILURE", "push blocked"),
        ]
        assert session._last_failure(recovered, "red") == "push blocked"
    finally:
        session.close()


# ----------------------------------------------------------------------------------------------
# 2. Plan errors: the file, the entry, the file's units, the fix
# ----------------------------------------------------------------------------------------------


def plan(tmp_path: Path, text: str, name: str = "plan.toml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def target(colour: str, x_mm: float, y_mm: float, extra: str = "") -> str:
    return f'[[targets]]\ncolour = "{colour}"\nx_mm = {x_mm}\ny_mm = {y_mm}\n{extra}\n'


def run_plan(path: Path) -> None:
    """Load a plan and open a session on it in the fake world: the run's checks, then nothing."""
    loaded = plans.load(path)
    root = loaded.create_root()
    starts = [
        ObjectStart(t.colour, 0.35 + 0.1 * i, -0.3, 0.0, t.obj, t.object_type) for i, t in enumerate(loaded.targets)
    ]
    opener = Opener()
    try:
        Session(root, starts, opener, view=camera_view()).close()
    finally:
        assert opener.opened <= 1


def test_a_target_outside_the_view_names_the_file_and_entry_in_mm(tmp_path: Path) -> None:
    path = plan(tmp_path, target("red", 450, 50) + target("blue", 450, 460))
    with pytest.raises(PlanError) as caught:
        run_plan(path)
    message = str(caught.value)
    assert message.startswith(f"{path}: [[targets]] 2: target blue at x 450 mm, y 460 mm is outside the camera's view")
    assert re.search(r"it sees about x -?\d+ to \d+ mm, y -?\d+ to \d+ mm", message), message
    assert " m," not in message and "0.4" not in message


def test_two_colours_that_overlap_name_both_entries_and_how_far_apart(tmp_path: Path) -> None:
    text = "[colours.teal]\nrgb = [0.1, 0.75, 0.2]\n" + target("green", 450, 50) + target("teal", 550, 50)
    path = plan(tmp_path, text)
    with pytest.raises(PlanError) as caught:
        run_plan(path)
    assert str(caught.value).startswith(f'{path}: [[targets]] 1 (colour = "green") and [colours.teal]: colours')
    assert "teal's paint has hue 129 deg, inside green's hue range 91..171 deg; move teal's hue at least 39 deg" in str(
        caught.value
    )


def test_out_of_reach_names_the_entry_once_in_mm_with_the_reach(tmp_path: Path) -> None:
    path = plan(tmp_path, target("red", 450, 50) + target("blue", 1450, 50))
    with pytest.raises(PlanError) as caught:
        plans.load(path)
    assert str(caught.value) == (
        f"{path}: [[targets]] 2: target blue at x 1450 mm, y 50 mm is out of reach: it lies 1451 mm from the base "
        "axis; in that direction the arm reaches 110 to 905 mm from its base axis: move it at least 546 mm closer"
    )
    assert "Pose(" not in str(caught.value) and str(caught.value).count("out of reach") == 1


@pytest.mark.parametrize(
    ("entry", "message"),
    [
        (
            target("red", 0.45, 0.05),
            "x_mm = 0.45, y_mm = 0.05 look like metres: the plan is in millimetres (x_mm = 450, y_mm = 50)",
        ),
        (target("red", 450, 0.5), None),  # a y of half a millimetre next to a real x is millimetres
    ],
)
def test_a_position_that_looks_like_metres_says_so(tmp_path: Path, entry: str, message: str | None) -> None:
    path = plan(tmp_path, entry)
    if message is None:
        plans.load(path)
        return
    with pytest.raises(PlanError) as caught:
        plans.load(path)
    assert str(caught.value) == f"{path}: [[targets]] 1: {message}"


def test_a_size_that_looks_like_metres_says_so(tmp_path: Path) -> None:
    path = plan(tmp_path, "[objects.bar]\nsize_mm = [0.08, 0.04, 0.04]\n" + target("red", 450, 50, 'object = "bar"'))
    with pytest.raises(PlanError) as caught:
        plans.load(path)
    assert str(caught.value) == (
        f"{path}: [objects.bar]: size_mm = [0.08, 0.04, 0.04] looks like metres: the plan is in millimetres "
        "(size_mm = [80, 40, 40])"
    )


def test_overlapping_targets_say_how_far_apart_they_must_be(tmp_path: Path) -> None:
    path = plan(tmp_path, target("red", 450, 50) + target("blue", 470, 50))
    with pytest.raises(PlanError) as caught:
        plans.load(path)
    assert str(caught.value) == (
        f"{path}: [[targets]] 1 and [[targets]] 2: targets red and blue overlap: two parts cannot stand there; "
        "their centres are 20.0 mm apart and must be at least 52.0 mm apart along that line (their footprints "
        "and the 2 mm gap): move them 32.0 mm further apart"
    )


def test_starts_of_a_plan_name_their_entries(tmp_path: Path) -> None:
    starts = '[[scene.starts]]\ncolour = "red"\nx_mm = 350\ny_mm = -250\n'
    starts += '[[scene.starts]]\ncolour = "blue"\nx_mm = 370\ny_mm = -250\n'
    path = plan(tmp_path, target("red", 450, 50) + target("blue", 550, 50) + starts)
    loaded = plans.load(path)
    with pytest.raises(PlanError) as caught:
        Session(loaded.create_root(), loaded.create_scene(), Opener(), view=camera_view())
    assert str(caught.value) == (
        f"{path}: [[scene.starts]] 1 and [[scene.starts]] 2: parts red and blue start 20 mm apart: closer than a "
        "cube's diagonal (71 mm), they would overlap: move them 51 mm further apart"
    )


# ----------------------------------------------------------------------------------------------
# 4. Nearest names
# ----------------------------------------------------------------------------------------------


def test_nearest_names() -> None:
    assert nearest("six_in_row", ["four_cubes", "mixed_parts", "six_in_a_row"]) == ["six_in_a_row"]
    assert nearest("gren", ["red", "green", "blue"]) == ["green"]
    assert nearest("Red", ["red"]) == ["red"]
    assert nearest("zzz", ["red", "green"]) == []
    assert did_you_mean("cubee", ["cube", "bar"]) == " (did you mean 'cube'?)"
    assert did_you_mean(3, ["cube"]) == ""


def test_a_mistyped_tree_file_suggests_the_nearest_example_or_file(tmp_path: Path) -> None:
    with pytest.raises(TreeFileError) as caught:
        treefile.load("six_in_row")
    assert str(caught.value) == (
        "tree file six_in_row not found (did you mean the example 'six_in_a_row'?): bt-arrange examples lists "
        "the examples, bt-arrange run NAME runs one"
    )
    (tmp_path / "four_cubes.py").write_text("")
    with pytest.raises(TreeFileError, match=r"not found \(did you mean '.*four_cubes\.py'\?\)"):
        treefile.load(tmp_path / "four_cube.py")


def test_a_mistyped_colour_type_or_key_of_a_plan_suggests_the_nearest(tmp_path: Path) -> None:
    cases = [
        (target("gren", 450, 50), "unknown colour \"gren\" (did you mean 'green'?)"),
        (target("red", 450, 50, 'object = "cub"'), "unknown object type \"cub\" (did you mean 'cube'?)"),
        (target("red", 450, 50, "colr = 1"), "unknown key 'colr' (did you mean 'colour'?)"),
    ]
    for text, fragment in cases:
        with pytest.raises(PlanError) as caught:
            plans.load(plan(tmp_path, text))
        assert fragment in str(caught.value), caught.value
    with pytest.raises(PlanError, match=r"unknown colour 'gren' \(did you mean 'green'\?\)"):
        validate_targets([Target("gren", 0.45, 0.05)])


def test_a_mistyped_row_cell_type_or_xml_node_suggests_the_nearest() -> None:
    from bt_arrange.objects import built_in_type
    from bt_arrange_sim.experiment.options import parse_rows
    from bt_arrange_sim.realcell import parse_cell

    with pytest.raises(PlanError, match=r"^unknown row 'translaton' \(did you mean 'translation'\?\); the rows are"):
        parse_rows("translaton")
    with pytest.raises(PlanError, match=r"^unknown cell 'rael' \(did you mean 'real'\?\)"):
        parse_cell("rael")
    with pytest.raises(PlanError, match=r"^unknown object type 'bra' \(did you mean 'bar'\?\)"):
        built_in_type("bra")
    text = '<root BTCPP_format="4"><BehaviorTree ID="T"><Sequense><AlwaysSuccess/></Sequense></BehaviorTree></root>'
    with pytest.raises(XmlTreeError, match=r"<Sequense> is not a registered node \(did you mean 'Sequence'\?\)"):
        xmltree.from_xml(text)


# ----------------------------------------------------------------------------------------------
# 5. Masses the arm and the pads can lift
# ----------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("mass_kg", "fragment"),
    [
        (
            3.0,
            "a brick of 3 kg is more than the pads can lift by friction: 2.45 kg (two pads, friction 1.2 x 0.5, "
            "grip 40 N",
        ),
        (
            6.0,
            "a brick of 6 kg is more than the arm can carry: 4.08 kg (the UR5's 5 kg payload less the gripper's "
            "0.925 kg)",
        ),
    ],
)
def test_a_part_too_heavy_is_refused_naming_the_limit(tmp_path: Path, mass_kg: float, fragment: str) -> None:
    text = f"[objects.brick]\nsize_mm = [60, 40, 40]\nmass_kg = {mass_kg}\n" + target(
        "red", 450, 50, 'object = "brick"'
    )
    path = plan(tmp_path, text)
    with pytest.raises(PlanError) as caught:
        plans.load(path)
    assert str(caught.value).startswith(f"{path}: [objects.brick] and [[targets]] 1: target red: {fragment}")


def test_a_heavier_part_lifts_with_more_grip_or_friction() -> None:
    brick = ObjectType("brick", (0.06, 0.04, 0.04), mass_kg=3.0, lateral_friction=1.0)
    assert brick.mass_problem(ManipulationSettings()) is None
    assert (
        ObjectType("brick", (0.06, 0.04, 0.04), mass_kg=3.0).mass_problem(ManipulationSettings(grip_force_n=60)) is None
    )


def test_the_framework_s_pad_friction_is_the_cell_s() -> None:
    from bt_arrange.objects import DEFAULT_PART_FRICTION, DEFAULT_PART_MASS_KG
    from bt_arrange.shapes import ROBOTIQ_2F85
    from bt_arrange_sim.config import PhysicsConfig
    from bt_arrange_sim.parts import CUBE_MASS_KG

    physics = PhysicsConfig()
    assert ROBOTIQ_2F85.pad_friction == physics.pad_contact.lateral_friction
    assert DEFAULT_PART_FRICTION == physics.cube_contact.lateral_friction
    assert DEFAULT_PART_MASS_KG == CUBE_MASS_KG


# ----------------------------------------------------------------------------------------------
# 6. Shared files cannot exhaust the machine
# ----------------------------------------------------------------------------------------------


def subtree_bomb(levels: int) -> str:
    """Each tree holds two SubTrees of the next: 2**levels leaves once expanded, in about 100 bytes a level."""
    lines = ['<root BTCPP_format="4" main_tree_to_execute="T0">']
    for i in range(levels):
        lines.append(
            f'<BehaviorTree ID="T{i}"><Sequence><SubTree ID="T{i + 1}"/><SubTree ID="T{i + 1}"/></Sequence>'
            "</BehaviorTree>"
        )
    lines.append(f'<BehaviorTree ID="T{levels}"><AlwaysSuccess/></BehaviorTree></root>')
    return "\n".join(lines)


def test_a_subtree_bomb_is_refused_in_milliseconds_naming_the_limit() -> None:
    text = subtree_bomb(40)  # 2**40 nodes expanded
    assert len(text) < 5000
    started = time.perf_counter()
    with pytest.raises(XmlTreeError) as caught:
        xmltree.from_xml(text, source="bomb.xml")
    elapsed_s = time.perf_counter() - started
    assert re.fullmatch(
        r"bomb\.xml line \d+: <SubTree ID='T\d+'>: the tree 'T\d+' expands to more than 10,000 nodes with its "
        r"SubTrees \([\d,]+ so far\), the limit \(bt_arrange\.filelimits\.MAX_TREE_NODES\)",
        str(caught.value),
    ), caught.value
    print(f"a {len(text)}-byte SubTree bomb of 2**40 nodes refused in {elapsed_s * 1000:.1f} ms")


def test_a_tree_within_the_limits_still_expands() -> None:
    root = xmltree.from_xml(subtree_bomb(12))  # 4,096 leaves and 4,095 sequences: under 10,000
    assert sum(1 for _ in root.iterate()) == 2**13 - 1


def test_nesting_beyond_the_depth_limit_is_refused_without_a_recursion_error() -> None:
    deep = '<root BTCPP_format="4"><BehaviorTree ID="T">' + "<Inverter>" * 3000 + "<AlwaysSuccess/>"
    deep += "</Inverter>" * 3000 + "</BehaviorTree></root>"
    with pytest.raises(
        XmlTreeError, match=rf"elements nest more than {MAX_TREE_DEPTH} levels deep below <BehaviorTree>"
    ):
        xmltree.from_xml(deep)
    # SubTrees that each nest 60 levels: fine alone, too deep together.
    inner = "<Inverter>" * 60 + "<SubTree ID='B'/>" + "</Inverter>" * 60
    two = (
        f'<root BTCPP_format="4" main_tree_to_execute="A"><BehaviorTree ID="A">{inner}</BehaviorTree>'
        f'<BehaviorTree ID="B">{"<Inverter>" * 60}<AlwaysSuccess/>{"</Inverter>" * 60}</BehaviorTree></root>'
    )
    with pytest.raises(XmlTreeError, match=rf"nests more than {MAX_TREE_DEPTH} levels deep with its SubTrees"):
        xmltree.from_xml(two)


def test_a_flat_tree_over_the_node_limit_and_a_file_over_the_size_limit_are_refused(tmp_path: Path) -> None:
    flat = '<root BTCPP_format="4"><BehaviorTree ID="T"><Sequence>' + "<AlwaysSuccess/>" * (MAX_TREE_NODES + 1)
    flat += "</Sequence></BehaviorTree></root>"
    with pytest.raises(XmlTreeError, match=r"<BehaviorTree ID='T'> has 10,002 nodes, over the limit of 10,000"):
        xmltree.from_xml(flat)
    big = tmp_path / "big.xml"
    big.write_text("<!--" + "x" * MAX_FILE_BYTES + "-->")
    with pytest.raises(XmlTreeError, match=r"big\.xml is 1,048,583 bytes, over the limit of 1,048,576 bytes"):
        xmltree.load_xml(big)
    big_plan = tmp_path / "big.toml"
    big_plan.write_text("#" * (MAX_FILE_BYTES + 1))
    with pytest.raises(PlanError, match=r"^plan file .*big\.toml is 1,048,577 bytes, over the limit"):
        plans.load(big_plan)


def test_a_python_tree_nested_too_deep_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "deep.py"
    path.write_text(
        "import py_trees\n"
        "def create_root():\n"
        "    node = py_trees.behaviours.Success('leaf')\n"
        "    for i in range(500):\n"
        "        node = py_trees.decorators.Inverter(f'not {i}', node)\n"
        "    return node\n"
    )
    with pytest.raises(TreeFileError, match=r"the tree nests more than 100 levels deep, the limit"):
        treefile.build_root(treefile.load(path))


def test_plans_and_cell_files_within_limits(tmp_path: Path) -> None:
    many = "".join(target("red", 450, 50, f'name = "r{i}"') for i in range(MAX_TARGETS + 1))
    with pytest.raises(PlanError, match=r"\[\[targets\]\]: 201 targets, over the limit of 200"):
        plans.load(plan(tmp_path, many))
    colours = "".join(f"[colours.c{i}]\nrgb = [1.0, 0.5, 0.0]\n" for i in range(65))
    with pytest.raises(PlanError, match=r"\[colours\]: 65 colours, over the limit of 64"):
        plans.load(plan(tmp_path, colours + target("red", 450, 50)))
    nested = "x = " + "[" * 5000 + "]" * 5000 + "\n"
    with pytest.raises(PlanError, match=r"its arrays or tables nest too deep"):
        plans.load(plan(tmp_path, nested))
    from bt_arrange_sim.realcell import load_toml

    with pytest.raises(PlanError, match=r"^cell file .* nests too deep"):
        load_toml(plan(tmp_path, nested, "cell.toml"))
    big = tmp_path / "big_cell.toml"
    big.write_text("#" * (MAX_FILE_BYTES + 1))
    with pytest.raises(PlanError, match=r"^cell file .*big_cell\.toml is 1,048,577 bytes, over the limit"):
        load_toml(big)


# ----------------------------------------------------------------------------------------------
# 7. The smaller items
# ----------------------------------------------------------------------------------------------


def test_the_replay_page_escapes_everything_it_inserts(tmp_path: Path) -> None:
    name = "__DATA__ </script><!-- & __TITLE__"
    root = py_trees.behaviours.Success(name)
    recorder = ReplayRecorder(root)
    recorder.observe(0.0)
    page = recorder.write(tmp_path / "replay.html", title=name, summary={"note": "</script>"}).read_text()
    data = re.search(r'<script id="replay-data" type="application/json">(.*?)</script>', page, re.S)
    assert data is not None
    payload = json.loads(data.group(1))
    assert payload["title"] == name and payload["summary"] == {"note": "</script>"}
    assert "<title>__DATA__ &lt;/script&gt;&lt;!-- &amp; __TITLE__ - bt-arrange replay</title>" in page
    assert page.count("</script>") == page.count("<script")


def test_the_real_cell_summary_is_beside_the_paper_s_real_column() -> None:
    from bt_arrange_sim.experiment.summaries import markdown_table, summarise

    def record(cell: str) -> dict:
        return {
            "row": "system",
            "cell": cell,
            "placed_mm": 3.0,
            "pushed_mm": 0.5,
            "pushed_truth_mm": 0.5,
            "pushes": 1,
            "status": "within",
            "threshold_mm": 1.0,
        }

    (real,) = summarise([record("real")], ["system"])
    assert (real["paper_placed_mean_mm"], real["paper_pushed_mean_mm"], real["paper_column"]) == (
        3.72,
        0.72,
        "real robot",
    )
    (ideal,) = summarise([record("ideal")], ["system"])
    assert (ideal["paper_placed_mean_mm"], ideal["paper_column"]) == (0.47, "simulation")
    assert "Paper: Table 1, real robot column." in markdown_table([real])


def test_fig4_draws_the_threshold_and_counts_each_box(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.axes import Axes

    from bt_arrange_sim.experiment.summaries import plot_fig4

    lines: list[float] = []
    labels: list[str] = []
    original_line, original_box = Axes.axhline, Axes.boxplot
    monkeypatch.setattr(Axes, "axhline", lambda self, y=0, *a, **k: lines.append(y) or original_line(self, y, *a, **k))
    monkeypatch.setattr(
        Axes,
        "boxplot",
        lambda self, data, *a, **k: labels.extend(k["tick_labels"]) or original_box(self, data, *a, **k),
    )
    records = [{"row": "system", "placed_mm": 0.4 + i / 10, "pushed_mm": 0.2, "threshold_mm": 1.0} for i in range(3)]
    plot_fig4(records, ["system"], tmp_path / "fig4.png")
    assert lines == [1.0]
    assert labels == ["after\nplacing\nn = 3", "after\npushing\nn = 3"]
    assert (tmp_path / "fig4.png").stat().st_size > 0


def test_the_experiment_names_the_trials_file(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    from bt_arrange import cli_experiment

    class Table:
        @staticmethod
        def markdown_table(summary: list[dict]) -> str:
            return ""

    cli_experiment._print_experiment(Table(), [{}], tmp_path)  # type: ignore[arg-type]
    assert capsys.readouterr().out.startswith("trials.jsonl, summary.json")
