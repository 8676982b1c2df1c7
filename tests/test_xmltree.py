"""BehaviorTree.CPP XML trees: the files in trees/ are up to date and round-trip; bad or hostile files are refused."""

import sys
import textwrap
from pathlib import Path

import py_trees
import pytest

from bt_arrange import cli, treefile, xmltree
from bt_arrange.behaviours import Place, Push
from bt_arrange.display import blackboard_access
from bt_arrange.xmltree import XmlTreeError

TREES = Path(__file__).resolve().parents[1] / "trees"
PYTHON_TREES = sorted(TREES.glob("*.py"))


def build(path):
    return treefile.build_root(treefile.load(path))


def export(path) -> str:
    return xmltree.to_xml(
        build(path), tree_id=path.stem, comment=f"generated from {path.name} by bt-arrange show (format xml)"
    )


def keys_of(root):
    return [(a.key, a.writers, a.readers) for a in blackboard_access(root)]


@pytest.mark.parametrize("path", PYTHON_TREES, ids=[p.stem for p in PYTHON_TREES])
def test_every_tree_file_has_an_up_to_date_xml_twin(path):
    twin = path.with_suffix(".xml")
    assert twin.is_file(), f"run: bt-arrange show trees/{path.name} --format xml --out trees/{twin.name}"
    assert twin.read_text() == export(path), (
        f"stale: bt-arrange show trees/{path.name} --format xml --out trees/{twin.name}"
    )


@pytest.mark.parametrize("path", PYTHON_TREES, ids=[p.stem for p in PYTHON_TREES])
def test_python_to_xml_to_tree_keeps_structure_parameters_and_blackboard_keys(path):
    original = build(path)
    reloaded = xmltree.from_xml(export(path))
    assert list(xmltree.iter_structure(reloaded)) == list(xmltree.iter_structure(original))
    assert [type(n) for n in reloaded.iterate()] == [type(n) for n in original.iterate()]
    assert keys_of(reloaded) == keys_of(original)
    assert reloaded.targets == original.targets and reloaded.threshold_mm == original.threshold_mm


def test_an_xml_tree_file_gives_the_scene_of_its_python_file():
    python, xml = treefile.load(TREES / "four_cubes.py"), treefile.load(TREES / "four_cubes.xml")
    for seed in (0, 3):
        assert treefile.scene(xml, seed) == treefile.scene(python, seed)


def test_builtin_composites_and_decorators_round_trip():
    leaf = py_trees.behaviours.Success
    root = py_trees.composites.Selector(
        "choose",
        memory=False,
        children=[
            py_trees.composites.Parallel(
                "both",
                py_trees.common.ParallelPolicy.SuccessOnOne(),
                children=[leaf("a"), py_trees.behaviours.Failure("b")],
            ),
            py_trees.decorators.Repeat("twice", py_trees.decorators.Inverter("not", leaf("c")), num_success=2),
            py_trees.composites.Sequence("reactive", memory=False, children=[leaf("d")]),
            py_trees.decorators.SuccessIsFailure("force failure", leaf("e")),
        ],
    )
    text = xmltree.to_xml(root)
    assert "<ReactiveFallback" in text and 'success_count="1"' in text and 'num_cycles="2"' in text
    assert "<TreeNodesModel>\n  </TreeNodesModel>" in text, "builtin nodes stay out of the model"
    reloaded = xmltree.from_xml(text)
    assert list(xmltree.iter_structure(reloaded)) == list(xmltree.iter_structure(root))
    assert isinstance(reloaded.children[0].policy, py_trees.common.ParallelPolicy.SuccessOnOne)


def test_a_subtree_is_inlined_and_ports_default_when_absent():
    text = """<root BTCPP_format="4" main_tree_to_execute="Main">
      <BehaviorTree ID="Main"><Sequence name="all"><SubTree ID="Look"/><MoveHome name="home"/></Sequence></BehaviorTree>
      <BehaviorTree ID="Look"><Detect name="look" obj="red"/></BehaviorTree>
    </root>"""
    root = xmltree.from_xml(text)
    detect = root.children[0]
    assert (detect.name, detect.obj, detect.colour) == ("look", "red", "red")


def test_writing_an_unregistered_behaviour_names_it():
    class Mine(py_trees.behaviours.Success):
        pass

    with pytest.raises(XmlTreeError, match="Mine is not a registered node"):
        xmltree.to_xml(py_trees.composites.Sequence("s", True, children=[Mine("mine")]))


def xml_file(tmp_path, body: str) -> Path:
    path = tmp_path / "tree.xml"
    path.write_text(textwrap.dedent(body).lstrip())
    return path


def show_error(capsys, path) -> str:
    code = cli.main(["show", str(path), "--format", "xml"])
    out, err = capsys.readouterr()
    assert code == 2, out
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("bt-arrange: error: "), err
    return lines[0]


def tree(node: str) -> str:
    return f"""
    <root BTCPP_format="4">
      <BehaviorTree ID="T">
        <Sequence name="s">
          {node}
        </Sequence>
      </BehaviorTree>
    </root>
    """


@pytest.mark.parametrize(
    ("node", "fragments"),
    [
        ('<Shell name="x" cmd="rm -rf /"/>', ["line 4", "<Shell> is not a registered node"]),
        ('<os.system name="x"/>', ["line 4", "<os.system> is not a registered node"]),
        ('<Detect name="d" obj="red" _skipIf="import os"/>', ["line 4", "_skipIf", "scripts are code"]),
        ('<Detect name="d"/>', ["line 4", "needs port 'obj'"]),
        ('<Detect name="d" obj="red" module="os"/>', ["line 4", "no port 'module'"]),
        ('<Detect name="d" obj="{the_object}"/>', ["line 4", "not blackboard references"]),
        (
            '<RetryUntilThreshold name="r" offset_key="/a" threshold_mm="abc"><Push obj="red"/></RetryUntilThreshold>',
            ["line 4", "threshold_mm='abc' is not a double"],
        ),
        (
            '<RetryUntilThreshold name="r" offset_key="/a" threshold_mm="-1"><Push obj="a"/></RetryUntilThreshold>',
            ["line 4", "positive"],
        ),
        ('<Pick name="p" obj="red"><Place obj="red"/></Pick>', ["line 4", "leaf"]),
        ('<GraspGuard name="g"/>', ["line 4", "exactly one child"]),
        ('<SubTree ID="T"/>', ["line 4", "includes itself"]),
    ],
)
def test_a_bad_node_is_refused_with_its_tag_and_line(capsys, tmp_path, node, fragments):
    message = show_error(capsys, xml_file(tmp_path, tree(node)))
    for fragment in fragments:
        assert fragment in message


@pytest.mark.parametrize(
    ("text", "fragments"),
    [
        ('<root BTCPP_format="4">\n<Include path="other.xml"/>\n</root>', ["line 2", "<Include> is not supported"]),
        ('<!DOCTYPE root [<!ENTITY a "aaaa">]>\n<root BTCPP_format="4"/>', ["line 1", "DOCTYPE"]),
        (
            '<root BTCPP_format="3"><BehaviorTree ID="T"><MoveHome/></BehaviorTree></root>',
            ["line 1", 'BTCPP_format="4"'],
        ),
        ('<root BTCPP_format="4">\n<BehaviorTree ID="T">\n<MoveHome>\n</root>', ["line 4", "not well-formed"]),
        ("<tree/>", ["line 1", "not <root"]),
    ],
)
def test_a_bad_document_is_refused_with_its_line(capsys, tmp_path, text, fragments):
    message = show_error(capsys, xml_file(tmp_path, text))
    for fragment in fragments:
        assert fragment in message


def test_loading_runs_no_code_the_file_names(capsys, tmp_path, monkeypatch):
    """A module on sys.path that the file names is never imported (py_trees' parser would import a type by name)."""
    marker = tmp_path / "imported"
    (tmp_path / "booby_trap.py").write_text(f"open({str(marker)!r}, 'w').close()\nclass Trap: pass\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    for node in ('<booby_trap.Trap name="x"/>', '<Detect name="d" obj="red" colour="booby_trap.Trap"/>'):
        path = xml_file(tmp_path, tree(node))
        cli.main(["show", str(path), "--format", "xml"])
        capsys.readouterr()
    assert not marker.exists() and "booby_trap" not in sys.modules


def test_an_xml_tree_does_not_take_a_threshold_from_the_command_line(capsys):
    code = cli.main(["run", str(TREES / "single_cube.xml"), "--threshold-mm", "0.5"])
    _, err = capsys.readouterr()
    assert code == 2 and "edit them instead of passing --threshold-mm" in err and len(err.strip().splitlines()) == 1


def test_show_writes_xml_to_a_file_and_reads_it_back(capsys, tmp_path):
    out = tmp_path / "four.xml"
    assert cli.main(["show", str(TREES / "four_cubes.py"), "--format", "xml", "--out", str(out)]) == 0
    assert f"wrote {out}" in capsys.readouterr().out
    assert out.read_text() == (TREES / "four_cubes.xml").read_text()
    assert cli.main(["show", str(out)]) == 0
    assert "correct yellow to 1 mm" in capsys.readouterr().out


def test_a_dense_tree_keeps_where_the_pads_go_through_xml():
    dense = build(TREES / "dense_block.py")
    reloaded = xmltree.from_xml(xmltree.to_xml(dense, tree_id="dense"))
    for original, copy in zip(dense.iterate(), reloaded.iterate(), strict=True):
        for attribute in ("grasp", "release", "where", "towards", "opening_m", "after"):
            assert getattr(copy, attribute, None) == getattr(original, attribute, None), (original.name, attribute)
    releases = [n.release for n in reloaded.iterate() if isinstance(n, Place) and n.release is not None]
    assert any(r.staged for r in releases) and any(not r.staged for r in releases)


@pytest.mark.parametrize(
    ("tag", "port", "value"),
    [
        ("Pick", "grasp", "z;0.06"),
        ("Pick", "grasp", "x;0.06;0.01"),
        ("Place", "release", "x;-0.06"),
        ("Place", "release", "y;nan"),
        ("Push", "towards", "+x,up"),
        ("Push", "opening_m", "__import__('os')"),
    ],
)
def test_a_bad_dense_port_value_is_a_one_line_error_naming_tag_port_and_line(tag, port, value):
    text = textwrap.dedent(
        f"""\
        <root BTCPP_format="4">
          <BehaviorTree ID="t">
            <{tag} name="n" obj="red" {port}="{value}"/>
          </BehaviorTree>
        </root>
        """
    )
    with pytest.raises(XmlTreeError) as caught:
        xmltree.from_xml(text, source="bad.xml")
    message = str(caught.value)
    assert message.startswith("bad.xml line 3: ") and f"<{tag} name='n'> {port}=" in message and "\n" not in message


def test_a_place_with_an_unknown_where_is_refused_with_its_line():
    text = (
        '<root BTCPP_format="4"><BehaviorTree ID="t">\n<Place name="n" obj="red" where="moon"/></BehaviorTree></root>'
    )
    with pytest.raises(XmlTreeError, match=r"line 2: <Place name='n'>: .*where='moon'"):
        xmltree.from_xml(text)


def test_a_push_strategy_survives_xml_and_an_unknown_one_is_refused_with_its_line():
    from bt_arrange.trees import Target, arrangement

    root = arrangement([Target("red", x_m=0.45, y_m=0.05)], strategy="diagonal")
    text = xmltree.to_xml(root, tree_id="t")
    reloaded = xmltree.from_xml(text)
    # The correction's push, and the push after placing the part again when its pushes stall.
    assert [n.strategy for n in reloaded.iterate() if isinstance(n, Push)] == ["diagonal", "diagonal"]
    with pytest.raises(XmlTreeError, match=r"line \d+: <Push name='push red'>: push strategy 'sideways'"):
        xmltree.from_xml(text.replace('strategy="diagonal"', 'strategy="sideways"'))


# ----------------------------------------------------------------------------------------------
# Parts as SubTrees with remapped ports; blackboard entries as ports
# ----------------------------------------------------------------------------------------------

BEFORE_SUBTREES = Path(__file__).resolve().parent / "data" / "four_cubes_before_subtrees.xml"


def elements(text: str) -> list:
    import xml.etree.ElementTree as ET

    return list(ET.fromstring(text).iter())


def test_four_cubes_is_one_part_definition_and_four_subtrees_within_90_elements(capsys):
    assert cli.main(["show", str(TREES / "four_cubes.py"), "--format", "xml"]) == 0
    text = capsys.readouterr().out
    document = elements(text)
    # every element: the trees and the TreeNodesModel (186 before the SubTrees; 80 before the look that
    # separates touching parts)
    assert len(document) <= 90
    trees = [e.get("ID") for e in document if e.tag == "BehaviorTree"]
    assert trees == ["four_cubes", "arrange_cube"]
    instances = [e for e in document if e.tag == "SubTree" and e.get("obj")]
    assert [e.get("obj") for e in instances] == ["red", "green", "blue", "yellow"]
    assert all(e.get("offset_mm") == "{/" + e.get("obj") + "/offset_mm}" for e in instances)  # remapped
    # the threshold's value once for the parts: the SubTree's port default, read as {threshold_mm} inside
    assert text.count('"{threshold_mm}"') == 2 and text.count('name="threshold_mm" default="1.0"') == 1
    assert 'threshold_mm="1.0"' in text.split("<SubTree")[0]  # and the plan's, on the Arrangement
    assert "object_type=" not in text and 'obj="{obj}"' in text and 'name="detect {obj}"' in text
    root = xmltree.from_xml(text)
    assert list(xmltree.iter_structure(root)) == list(xmltree.iter_structure(build(TREES / "four_cubes.py")))


def test_a_file_written_before_the_subtrees_reads_and_runs_as_the_python_tree():
    """The former form (every part inline, every port written, keys as plain text) reads as it did."""
    text = BEFORE_SUBTREES.read_text()
    assert "<SubTree" not in text and 'offset_key="/red/offset_mm"' in text
    original, before = build(TREES / "four_cubes.py"), xmltree.load_xml(BEFORE_SUBTREES)
    assert list(xmltree.iter_structure(before)) == list(xmltree.iter_structure(original))
    assert keys_of(before) == keys_of(original)
    # Written again it stays inline (its parts carry no SubTree's ports), the ports at their defaults left out.
    inline = xmltree.to_xml(original, tree_id="four_cubes", subtrees=False)
    assert xmltree.to_xml(before, tree_id="four_cubes") == inline
    module = xmltree.load_module(BEFORE_SUBTREES)
    assert treefile.scene(module, 3) == treefile.scene(treefile.load(TREES / "four_cubes.py"), 3)


@pytest.mark.parametrize(
    "path", [*PYTHON_TREES, TREES / "fresco.toml", TREES / "irregular_parts.toml"], ids=lambda p: p.name
)
def test_parts_that_differ_get_their_own_definitions_and_every_tree_reads_back(path):
    root = build(path)
    text = xmltree.to_xml(root, tree_id=path.stem)
    reloaded = xmltree.from_xml(text)
    assert list(xmltree.iter_structure(reloaded)) == list(xmltree.iter_structure(root))
    assert keys_of(reloaded) == keys_of(root)
    assert xmltree.to_xml(reloaded, tree_id=path.stem) == text  # read and written again: the same file
    inline = xmltree.to_xml(root, tree_id=path.stem, subtrees=False)
    assert "<SubTree" not in inline
    assert list(xmltree.iter_structure(xmltree.from_xml(inline))) == list(xmltree.iter_structure(root))


def test_an_xml_author_remaps_an_entry_of_a_node_and_of_a_subtree():
    text = """<root BTCPP_format="4" main_tree_to_execute="Main">
      <BehaviorTree ID="Main">
        <Sequence name="all">
          <SetBlackboardVariable name="target" variable_name="/red/target" variable_value="0.5;0.0;0.0"/>
          <Detect name="look" obj="red" pose="{/camera/red}"/>
          <SubTree ID="Take" obj="red" seen="{/camera/red}"/>
        </Sequence>
      </BehaviorTree>
      <BehaviorTree ID="Take"><Pick name="pick {obj}" obj="{obj}" pose="{seen}"/></BehaviorTree>
    </root>"""
    root = xmltree.from_xml(text)
    _, detect, pick = root.children
    assert pick.name == "pick red"
    for node in (detect, pick):  # the node asks for /red/pose; its client keeps it at /camera/red
        assert dict(node.blackboard.remappings)["/red/pose"] == "/camera/red"
    from bt_arrange.keycheck import check_keys, required_reads, written_keys

    assert "/camera/red" in written_keys(detect) and "/camera/red" in required_reads(pick)
    check_keys(root)  # Pick's pose is written before it, at the key both remap it to
    detect.blackboard.set("/red/pose", "seen")
    assert py_trees.blackboard.Blackboard.get("/camera/red") == "seen"
    assert not py_trees.blackboard.Blackboard.exists("/red/pose")
    written = xmltree.to_xml(root)
    assert written.count('pose="{/camera/red}"') == 2


def test_a_reference_to_no_port_of_its_subtree_is_refused_with_its_line():
    text = """<root BTCPP_format="4" main_tree_to_execute="Main">
      <BehaviorTree ID="Main"><SubTree ID="Look" obj="red"/></BehaviorTree>
      <BehaviorTree ID="Look"><Detect name="look" obj="{obj}" colour="{color}"/></BehaviorTree>
    </root>"""
    with pytest.raises(XmlTreeError, match=r"line 3: <Detect> colour='\{color\}': ports take values.*obj"):
        xmltree.from_xml(text)


def test_the_full_model_lists_every_port_with_its_description(capsys):
    assert cli.main(["show", str(TREES / "four_cubes.py"), "--format", "xml", "--full-model"]) == 0
    text = capsys.readouterr().out
    assert '<output_port name="pose" type="BlackboardEntry" default="{pose}">the measured pose</output_port>' in text
    assert '<input_port name="object_type" type="ObjectType" default="">' in text and "<MetadataFields>" in text
    assert list(xmltree.iter_structure(xmltree.from_xml(text))) == list(
        xmltree.iter_structure(build(TREES / "four_cubes.py"))
    )
