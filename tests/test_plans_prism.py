"""Plan files with irregular parts: ``outline_mm`` and ``height_mm`` (the contract), checked up front."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import pytest

from bt_arrange import plans
from bt_arrange.errors import PlanError
from bt_arrange.shapes import Prism
from bt_arrange.trees import Arrangement

ELL_PLAN = """
[objects.ell]
outline_mm = [[0, 0], [60, 0], [60, 20], [20, 20], [20, 50], [0, 50]]   # the top face, in mm, either winding
height_mm = 20

[[targets]]
object = "ell"
colour = "red"
x_mm = 480
y_mm = 50
yaw_deg = 30
"""


def write(tmp_path: Path, text: str, name: str = "plan.toml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def test_an_outline_type_is_a_prism_about_its_centroid_and_its_target_says_where_the_centroid_goes(tmp_path) -> None:
    plan = plans.load(write(tmp_path, ELL_PLAN))
    ell = plan.object_types["ell"]
    assert isinstance(ell.shape, Prism)
    assert ell.shape.height_m == pytest.approx(0.02)
    assert ell.shape.area_m2 == pytest.approx(0.0018)
    (target,) = plan.targets
    assert (target.x_m, target.y_m, math.degrees(target.yaw_rad)) == pytest.approx((0.48, 0.05, 30.0))
    root = plan.create_root()
    assert isinstance(root, Arrangement) and root.targets[0].object_type == ell
    clockwise = ELL_PLAN.replace(
        "[[0, 0], [60, 0], [60, 20], [20, 20], [20, 50], [0, 50]]",
        "[[0, 50], [20, 50], [20, 20], [60, 20], [60, 0], [0, 0]]",
    )
    assert plans.load(write(tmp_path, clockwise, "cw.toml")).object_types["ell"] == ell


@pytest.mark.parametrize(
    ("entry", "message"),
    [
        ("outline_mm = [[0, 0], [60, 60], [60, 0], [0, 40]]\nheight_mm = 20", "crosses itself"),
        ("outline_mm = [[0, 0], [60, 40], [60, 0], [0, 40]]\nheight_mm = 20", "crosses itself"),
        ("outline_mm = [[0, 0], [60, 0]]\nheight_mm = 20", "at least three points"),
        ("outline_mm = [[0, 0], [30, 0], [60, 0]]\nheight_mm = 20", "encloses no area"),
        ("outline_mm = [[0, 0], [60, 0], [60, 40], [55, 45], [0, 45]]\nheight_mm = 20", "under the 10 mm the camera"),
        (
            "outline_mm = [[0, 0], [100, 0], [100, 90], [50, 100], [0, 90]]\nheight_mm = 20",
            "no two edges the 2F-85 can close on",
        ),
        # A rectangle along its axes is the box of that size, refused as a box is.
        (
            "outline_mm = [[0, 0], [100, 0], [100, 90], [0, 90]]\nheight_mm = 20",
            "no horizontal side the gripper can span",
        ),
        ("outline_mm = [[0, 0], [60, 0], [0, 50]]\nheight_mm = 8", "thinner than the pads"),
        ("outline_mm = [[0, 0], [60, 0], [0, 50]]\nheight_mm = 120", "taller than 100 mm"),
        ("outline_mm = [[0, 0], [60, 0], [0, 50]]", "missing height_mm"),
        ("outline_mm = [[0, 0], [60, 0], [0, 50]]\nheight_mm = 20\nsize_mm = [50, 50, 50]", "not both"),
        ("outline_mm = [0, 60, 0]\nheight_mm = 20", r"is not a list of \[x, y\] points"),
    ],
)
def test_a_bad_outline_is_one_line_naming_the_file_and_the_type(tmp_path, entry, message) -> None:
    lines = ELL_PLAN.splitlines()
    text = "\n".join(lines[:2] + [entry] + lines[4:]) + "\n"
    path = write(tmp_path, text)
    with pytest.raises(PlanError, match=message) as caught:
        plans.load(path)
    assert "[objects.ell]" in str(caught.value) and str(path) in str(caught.value)
    assert "\n" not in str(caught.value)


def test_an_outline_plan_shown_as_xml_reads_back_as_the_same_plan(tmp_path) -> None:
    path = write(tmp_path, ELL_PLAN)
    out = tmp_path / "ell.xml"
    result = subprocess.run(
        [sys.executable, "-m", "bt_arrange.cli", "show", str(path), "--format", "xml", "--out", str(out)],
        capture_output=True,
        text=True,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    from bt_arrange import xmltree

    written = plans.load(path).create_root()
    back = xmltree.load_module(out).create_root()
    assert isinstance(back, Arrangement)
    assert back.targets == written.targets  # the ell's outline and height, exactly
    assert back.targets[0].object_type == plans.load(path).object_types["ell"]
    assert list(xmltree.iter_structure(back)) == list(xmltree.iter_structure(written))
    text = out.read_text()
    assert 'object_type="ell=outline_mm ' in text and " height_mm 20" in text


TWO_RED = """
[objects.ell]
outline_mm = [[0, 0], [60, 0], [60, 20], [20, 20], [20, 50], [0, 50]]
height_mm = 20

[objects.other]
outline_mm = OTHER
height_mm = 20

[[targets]]
object = "ell"
colour = "red"
name = "red ell"
x_mm = 450
y_mm = 80
yaw_deg = 30

[[targets]]
object = "other"
colour = "red"
name = "red other"
x_mm = 560
y_mm = -60
yaw_deg = -45
"""


def test_irregular_parts_of_different_outlines_may_share_a_colour_congruent_ones_may_not(tmp_path) -> None:
    from bt_arrange.shapes import told_apart

    trapezoid = "[[0, 0], [70, 0], [50, 35], [15, 35]]"
    plan = plans.load(write(tmp_path, TWO_RED.replace("OTHER", trapezoid)))
    assert [t.colour for t in plan.targets] == ["red", "red"]
    # The same L written mirrored and turned: congruent, so the camera could not tell the two apart.
    mirrored = "[[0, 0], [0, 60], [20, 60], [20, 20], [50, 20], [50, 0]]"
    with pytest.raises(PlanError, match="one colour is one type"):
        plans.load(write(tmp_path, TWO_RED.replace("OTHER", mirrored), "mirrored.toml"))
    ell = plan.object_types["ell"].shape
    assert told_apart(ell, plan.object_types["other"].shape)
    assert not told_apart(ell, ell)
