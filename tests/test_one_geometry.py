"""A part has one geometry: every shape is a prism, a box is the prism Cuboid, and no step asks a shape's class."""

from __future__ import annotations

import ast
import math
import pickle
import re
from pathlib import Path

import pytest

from bt_arrange.errors import PlanError
from bt_arrange.objects import BAR, CUBE, ObjectType
from bt_arrange.plan.layout import Part
from bt_arrange.shapes import ROBOTIQ_2F85, Cuboid, Prism, Shape

ROOT = Path(__file__).resolve().parents[1]
#: Where a shape's class may be named: the shapes themselves and the modules that make types of them.
SHAPE_HOMES = ("bt_arrange/shapes/", "bt_arrange/objects.py", "bt_arrange/geometry.py", "bt_arrange/settings.py")
ELL = Prism.from_outline([[0, 0], [0.06, 0], [0.06, 0.02], [0.02, 0.02], [0.02, 0.05], [0, 0.05]], 0.02)


def _sources() -> list[Path]:
    return sorted(p for folder in ("bt_arrange", "sim") for p in (ROOT / folder).rglob("*.py"))


def _outside_shape_homes(path: Path) -> bool:
    relative = path.relative_to(ROOT).as_posix()
    return not relative.startswith(SHAPE_HOMES)


def test_no_step_asks_which_class_a_shape_is() -> None:
    found = []
    for path in filter(_outside_shape_homes, _sources()):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "isinstance":
                classes = ast.unparse(node.args[1]) if len(node.args) == 2 else ""
                if re.search(r"\b(Cuboid|Prism)\b", classes):
                    found.append(f"{path.relative_to(ROOT)}:{node.lineno}: {ast.unparse(node)}")
    assert found == []


@pytest.mark.parametrize(
    "pattern",
    [r"\bprism is (not )?None\b", r"\bPrismFit\b", r"\bcube_edge_m\b"],
    ids=["prism-is-None", "PrismFit", "cube-edge"],
)
def test_no_second_copy_of_a_part_and_no_cube_edge_read(pattern: str) -> None:
    found = [
        f"{path.relative_to(ROOT)}:{number}"
        for path in filter(_outside_shape_homes, _sources())
        for number, line in enumerate(path.read_text().splitlines(), start=1)
        if re.search(pattern, line)
    ]
    assert found == []


def test_every_module_stays_under_600_lines() -> None:
    long = {str(p.relative_to(ROOT)): n for p in _sources() if (n := len(p.read_text().splitlines())) >= 600}
    assert long == {}


def test_a_box_is_a_prism_with_the_rectangular_trait() -> None:
    box = Prism.box(0.08, 0.04, 0.04)
    assert isinstance(box, Prism) and box == Cuboid((0.08, 0.04, 0.04)) == BAR.shape
    assert box.rectangular and not box.square_top and not box.is_cube
    assert CUBE.shape.rectangular and CUBE.shape.square_top and CUBE.shape.is_cube
    assert not ELL.rectangular and not ELL.square_top and not ELL.is_cube
    assert box.size_m == (0.08, 0.04, 0.04) and box.area_m2 == pytest.approx(0.0032)
    assert [tuple(p) for p in box.outline_m] == [(-0.04, -0.02), (0.04, -0.02), (0.04, 0.02), (-0.04, 0.02)]
    assert len(box.convex_pieces()) == 1 and len(ELL.convex_pieces()) == 2
    assert pickle.loads(pickle.dumps(box)) == box and hash(pickle.loads(pickle.dumps(box))) == hash(box)


def test_a_rectangle_outline_along_its_axes_is_that_box_whatever_its_frame_and_winding() -> None:
    written = Prism.from_outline([[0.1, 0.2], [0.1, 0.24], [0.18, 0.24], [0.18, 0.2]], 0.04)
    assert written == Prism.box(0.08, 0.04, 0.04)
    # Turned, it is an outline like any other: its frame is the one it was written in.
    c, s = math.cos(0.3), math.sin(0.3)
    turned = Prism.from_outline(
        [[c * x - s * y, s * x + c * y] for x, y in [[0, 0], [0.08, 0], [0.08, 0.04], [0, 0.04]]], 0.04
    )
    assert not turned.rectangular
    assert turned.area_m2 == pytest.approx(0.0032)
    with pytest.raises(PlanError, match="crosses itself"):
        Prism.from_outline([[0, 0], [0.06, 0.04], [0.06, 0], [0, 0.04]], 0.02)


@pytest.mark.parametrize("shape", [CUBE.shape, BAR.shape, ELL], ids=["cube", "bar", "ell"])
def test_every_shape_answers_the_whole_protocol(shape: Shape) -> None:
    members = [name for name in vars(Shape) if not name.startswith("_")]
    assert {"rectangular", "named_pushes", "convex_pieces", "grasps", "pushed_face", "support_m"} <= set(members)
    for name in members:
        assert hasattr(shape, name), name
    grasp = shape.grasps(ROBOTIQ_2F85)[0]
    assert 0 < grasp.width_m <= ROBOTIQ_2F85.max_grasp_width_m
    assert shape.support_m([0.0, 0.0, 1.0]) == pytest.approx(shape.height_m / 2)
    assert shape.problems(ROBOTIQ_2F85) == [] and shape.size_problems() == []
    # Every shape has square pushes by name (a box's are its faces'), though a box is pushed along its frame.
    assert len(shape.named_pushes(ROBOTIQ_2F85)) >= 2


def test_the_layout_reads_the_shape_a_box_by_its_rectangle_an_outline_by_its_pieces() -> None:
    box = Part("bar", 0.5, 0.0, 0.0, BAR.shape)
    ell = Part("ell", 0.5, 0.0, 0.0, ELL)
    assert not box.by_outline and box.grasp_axes == ("y",) and box.push_directions == ("+x", "-x", "+y", "-y")
    assert box.grasp_half("y") == pytest.approx(0.02) and box.back("+x") == pytest.approx(0.04)
    assert ell.by_outline and ell.grasp_axes == (ELL.grasps(ROBOTIQ_2F85)[0].axis,)
    assert set(ell.push_directions) == set(ELL.named_pushes(ROBOTIQ_2F85))
    assert type(ell.footprint).__name__ == "Outline" and type(box.footprint).__name__ == "Rect"


def test_a_type_grown_by_machining_error_stays_a_box_and_an_outline_stays_as_written() -> None:
    grown = BAR.resized(0.001)
    assert grown.shape == Prism.box(0.081, 0.041, 0.041) and grown.name == "bar"
    ell = ObjectType("ell", shape=ELL)
    assert ell.resized(0.001) is ell
