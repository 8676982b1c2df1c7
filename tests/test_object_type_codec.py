"""The XML port codec of any part (docs/xml.md, "Object types"): an outline and a height in mm, read back exactly.

Every plan the CLI runs exports to XML and reads back as the same plan: the same types (``==``:
the same outline floats, the box class for a box), targets, releases, square pushes and scene.
The former ``name=x_m*y_m*z_m`` of a box still reads; it is no longer written.
"""

from __future__ import annotations

import math
import random
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from bt_arrange import plans, ports, treefile, xmltree
from bt_arrange.errors import PortValueError, XmlTreeError
from bt_arrange.objects import BAR, CUBE, ObjectStart, ObjectType
from bt_arrange.plan.layout import Release
from bt_arrange.ports import DIRECTIONS_TYPE, LIMIT, OBJECT_TYPE, RELEASE
from bt_arrange.shapes import Cuboid, Prism
from bt_arrange.trees import Arrangement

ROOT = Path(__file__).resolve().parents[1]
PLANS = sorted([*(ROOT / "trees").glob("*.toml"), *(ROOT / "bt_arrange/examples").glob("*.toml")])


def round_trip(kind: ObjectType) -> ObjectType:
    return OBJECT_TYPE.parse(OBJECT_TYPE.format(kind))


@pytest.mark.parametrize("path", PLANS, ids=[f"{p.parent.name}/{p.name}" for p in PLANS])
def test_every_type_of_every_plan_reads_back_identical(path):
    for kind in plans.load(path).object_types.values():
        text = OBJECT_TYPE.format(kind)
        assert "," not in text and ";" not in text  # they separate the Targets port's fields and targets
        back = OBJECT_TYPE.parse(text)
        assert back == kind and type(back.shape) is type(kind.shape)


@pytest.mark.parametrize("path", PLANS, ids=[f"{p.parent.name}/{p.name}" for p in PLANS])
def test_every_plan_exported_reads_back_as_the_same_tree_and_plan(path):
    module = treefile.load(path)
    root = treefile.build_root(module)
    text = xmltree.to_xml(root, tree_id=path.stem)
    back = xmltree.from_xml(text)
    assert xmltree.to_xml(back, tree_id=path.stem) == text  # read and written again: the same file
    assert isinstance(back, Arrangement)
    assert back.targets == root.targets
    assert (back.scene_seed, back.starts) == (module.default_seed, None)
    assert list(xmltree.iter_structure(back)) == list(xmltree.iter_structure(root))
    assert [type(node) for node in back.iterate()] == [type(node) for node in root.iterate()]


def test_a_box_is_written_as_its_outline_and_reads_back_as_the_same_box():
    assert OBJECT_TYPE.format(BAR) == "bar=outline_mm -40:-20 40:-20 40:20 -40:20 height_mm 40"
    assert OBJECT_TYPE.format(CUBE) == ""  # the default type
    for kind in (
        BAR,
        ObjectType("cube", CUBE.size_m, mass_kg=0.2),
        ObjectType("odd", (0.0512345678901, 1 / 30, 0.0412)),
    ):
        back = round_trip(kind)
        assert back == kind and isinstance(back.shape, Cuboid) and back.shape.size_m == kind.size_m


def test_the_former_box_text_in_metres_still_reads():
    assert OBJECT_TYPE.parse("bar=0.08*0.04*0.04") == BAR
    assert OBJECT_TYPE.parse(" small = 0.03*0.03*0.03 ") == ObjectType("small", (0.03, 0.03, 0.03))


def test_the_documented_example_is_the_plans_triangle():
    """docs/xml.md's example, written by hand in the plan's own frame: re-centred as the plan does."""
    plan = plans.load(ROOT / "trees/irregular_parts.toml")
    written = OBJECT_TYPE.parse("triangle=outline_mm 0:0 60:0 15:45 height_mm 20")
    assert written == plan.object_types["triangle"]
    assert OBJECT_TYPE.format(written).startswith("triangle=outline_mm -24.999999999999998:-15 35:-15 ")


def test_mass_and_friction_are_carried():
    kind = ObjectType(
        "ell",
        None,
        0.15,
        0.8,
        shape=Prism.from_outline([[0, 0], [0.06, 0], [0.06, 0.02], [0.02, 0.02], [0.02, 0.05], [0, 0.05]], 0.02),
    )
    text = OBJECT_TYPE.format(kind)
    assert text.endswith(" height_mm 20 mass_kg 0.15 friction 0.8")
    assert round_trip(kind) == kind


@given(st.floats(min_value=-1.0, max_value=1.0, allow_nan=False))
def test_millimetres_read_back_as_the_same_metres(value_m):
    text = ports._format_mm(value_m)
    assert ports._parse_mm(text) == value_m and math.copysign(1, ports._parse_mm(text)) == math.copysign(1, value_m)


def test_a_random_prism_reads_back_identical():
    rng = random.Random(7)
    for _ in range(50):
        count = rng.randint(3, 9)
        points = [
            (rng.uniform(0.02, 0.04) * math.cos(a), rng.uniform(0.02, 0.04) * math.sin(a))
            for a in sorted(rng.uniform(0, 2 * math.pi) for _ in range(count))
        ]
        try:
            kind = ObjectType("p", shape=Prism.from_outline(points, rng.uniform(0.015, 0.05)))
        except Exception:
            continue  # not a part the gripper takes
        assert round_trip(kind) == kind


@pytest.mark.parametrize(
    ("text", "says"),
    [
        ("tri=outline_mm 0:0 60:0 height_mm 20", "at least three points"),
        ("tri=outline_mm 0:0 60:0 15:x height_mm 20", "'x' is not a number of millimetres"),
        ("tri=outline_mm 0:0 60:0 15:45", "has no height_mm"),
        ("tri=outline_mm 0:0 60:0 15:45 height_mm 20 colour red", "'colour' is not one of height_mm"),
        ("tri=outline_mm 0:0 60:0 15:45 height_mm 20 height_mm 30", "each once"),
        ("tri=outline_mm 0:0 60:0 15:45 height_mm", "has no value"),
        ("tri=0:0 60:0 15:45 height_mm 20", "does not start its shape with outline_mm"),
        ("tri=outline_mm 0:0 60:0 15:45 height_mm inf", "not a finite number"),
        ("tri=outline_mm 0:0:1 60:0 15:45 height_mm 20", "is not X:Y"),
        ("tri=outline_mm 0:0 60:0 15:45 height_mm 20 mass_kg -1", "mass_kg must be a positive number"),
        ("tri=outline_mm 0:0 60:0 0:60 60:60 height_mm 20", "the outline crosses itself"),  # a bow tie
        ("=outline_mm 0:0 60:0 15:45 height_mm 20", "is not NAME=outline_mm"),
        ("tri", "is not NAME=outline_mm"),
    ],
)
def test_a_bad_object_type_is_one_port_value_error(text, says):
    with pytest.raises(PortValueError, match="is not a ObjectType: ") as caught:
        OBJECT_TYPE.parse(text)
    assert says in str(caught.value) and "\n" not in str(caught.value)


@pytest.mark.parametrize("name", ["a,b", "a;b", "a=b", " a"])
def test_a_name_the_targets_port_cannot_hold_is_refused_when_written(name):
    with pytest.raises(PortValueError, match="a name in XML has no"):
        OBJECT_TYPE.format(ObjectType(name, (0.05, 0.05, 0.05)))


def test_the_ports_a_prism_tree_needs():
    assert LIMIT.parse(LIMIT.format(math.inf)) == math.inf and LIMIT.parse("2.5") == 2.5
    with pytest.raises(PortValueError):
        LIMIT.parse("nan")
    assert DIRECTIONS_TYPE.parse("@61.5,@-90.0,+x") == ("@61.5", "@-90.0", "+x")
    with pytest.raises(PortValueError, match="nor a square push"):
        DIRECTIONS_TYPE.parse("@north")
    off_centre = Release("x", 0.064, (-0.0135, 0.0071), (0.0025, 0.0071))
    assert RELEASE.format(off_centre) == "x;0.064;-0.0135;0.0071;0.0025;0.0071"
    assert RELEASE.parse(RELEASE.format(off_centre)) == off_centre
    centred_in_place = Release("y", 0.05, (0.003, 0.0), (0.003, 0.0))
    assert RELEASE.parse(RELEASE.format(centred_in_place)) == centred_in_place
    assert RELEASE.format(Release("y", 0.058)) == "y;0.058"  # as files written before


STARTS_PLAN = """
[objects.triangle]
outline_mm = [[0, 0], [60, 0], [15, 45]]
height_mm = 20

[[targets]]
object = "triangle"
colour = "red"
x_mm = 480
y_mm = 50

[[targets]]
colour = "blue"
x_mm = 480
y_mm = -80

[scene]
seed = 4

[[scene.starts]]
object = "triangle"
colour = "red"
x_mm = 400
y_mm = -200
yaw_deg = 10

[[scene.starts]]
colour = "blue"
x_mm = 600
y_mm = -200
"""


def test_a_plans_starts_and_seed_are_carried_by_its_xml(tmp_path):
    path = tmp_path / "starts.toml"
    path.write_text(STARTS_PLAN)
    module = treefile.load(path)
    exported = tmp_path / "starts.xml"
    exported.write_text(xmltree.to_xml(treefile.build_root(module), tree_id="starts"))
    xml_module = xmltree.load_module(exported)
    assert xml_module.default_seed == 4
    starts = xml_module.create_scene(4)
    assert [(s.obj, s.x_m, s.y_m, s.yaw_rad, s.object_type) for s in starts] == [
        (s.obj, s.x_m, s.y_m, s.yaw_rad, s.object_type) for s in module.create_scene(4)
    ]
    assert all(isinstance(s, ObjectStart) for s in starts)


def test_a_negative_scene_seed_is_one_line_naming_the_node():
    xml = (
        '<root BTCPP_format="4"><BehaviorTree ID="t"><Arrangement name="a" targets="red,0.5,0.0,0.0" '
        'threshold_mm="1" scene_seed="-4"><MoveHome name="m"/></Arrangement></BehaviorTree></root>'
    )
    with pytest.raises(XmlTreeError, match=r"<Arrangement name='a'>: scene_seed=-4 must be a whole number") as caught:
        xmltree.from_xml(xml, source="bad.xml")
    assert "\n" not in str(caught.value)
