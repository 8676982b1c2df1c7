"""Near-symmetric outlines: the feature that tells a part's yaws apart, and the plan's limit.

A part whose outline, turned to another yaw that is no symmetry, comes within 0.3 mm of itself is
refused before anything moves, in millimetres; anything more the camera's sub-pixel edges tell
apart (tests/test_perception_outline.py); a truly symmetric outline is accepted at any of its yaws.
"""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from bt_arrange import plans
from bt_arrange.errors import PlanError
from bt_arrange.objects import ObjectType
from bt_arrange.shapes import Prism
from bt_arrange.shapes.prism import MIN_YAW_FEATURE_M
from bt_arrange.shapes.yaw_feature import yaw_feature_m


def prism(points_mm: list[list[float]]) -> Prism:
    return Prism.from_outline((np.asarray(points_mm, dtype=float) / 1000).tolist(), 0.02)


def feature_mm(points_mm: list[list[float]]) -> tuple[float, float]:
    shape = prism(points_mm)
    feature_m, turn_rad = yaw_feature_m(shape.outline_m, shape.symmetry_rad)
    return feature_m * 1000, math.degrees(turn_rad)


@pytest.mark.parametrize("bump_mm", [0.2, 0.6, 1.0, 2.0])
def test_a_bump_on_a_rectangle_tells_its_half_turn_apart_by_half_its_height(bump_mm: float) -> None:
    # Turned half a turn about the centroid, the bump's apex lies over the straight side opposite, and the
    # straight side under the apex: each misses the other by half the bump (the centroid moves by little).
    feature, turn = feature_mm([[0, 0], [30, -bump_mm], [60, 0], [60, 30], [0, 30]])
    assert turn == pytest.approx(180.0, abs=0.5)
    assert feature == pytest.approx(bump_mm / 2, rel=0.05)


def test_the_issues_isosceles_triangle_is_told_apart_by_a_millimetre_under_its_third_turns() -> None:
    feature, turn = feature_mm([[0, 0], [60, 0], [30, 50]])
    assert feature == pytest.approx(1.08, abs=0.02)
    assert min(abs(turn - 120.0), abs(turn - 240.0)) < 1.0


@pytest.mark.parametrize(
    "points_mm",
    [
        [[30, 0], [15, 25.98], [-15, 25.98], [-30, 0], [-15, -25.98], [15, -25.98]],  # regular hexagon
        [[0, 0], [60, 0], [30, 51.96]],  # equilateral triangle
    ],
    ids=["hexagon", "equilateral"],
)
def test_a_truly_symmetric_outline_has_no_other_yaw_to_tell_apart(points_mm) -> None:
    assert feature_mm(points_mm)[0] == math.inf


def test_a_rectangles_half_turn_is_a_symmetry_and_its_quarter_turn_is_told_apart_by_half_its_sides_difference():
    shape = Prism.from_outline([[0, 0], [0.06, 0], [0.06, 0.03], [0, 0.03]], 0.02)
    assert math.degrees(shape.symmetry_rad) == pytest.approx(180.0)
    feature, turn = feature_mm([[0, 0], [60, 0], [60, 30], [0, 30]])
    assert feature == pytest.approx(15.0, abs=0.01)
    assert turn == pytest.approx(90.0, abs=0.1) or turn == pytest.approx(270.0, abs=0.1)


def test_an_irregular_outline_shows_its_yaw_by_millimetres() -> None:
    assert feature_mm([[0, 0], [45, 4], [60, 30], [35, 28], [30, 50], [5, 40]])[0] > 5.0
    assert feature_mm([[0, 0], [25, -22], [70, 0], [25, 22]])[0] > 5.0  # the kite


def test_an_outline_under_the_limit_is_refused_in_millimetres_naming_the_turn() -> None:
    with pytest.raises(PlanError) as refused:
        ObjectType("bumped", shape=prism([[0, 0], [30, -0.4], [60, 0], [60, 30], [0, 30]]))
    message = str(refused.value)
    assert "\n" not in message
    assert message.startswith("object type 'bumped': the outline turned by 180 deg comes within 0.20 mm of itself")
    assert f"a feature of at least {MIN_YAW_FEATURE_M * 1000:.1f} mm" in message


@pytest.mark.parametrize(
    "points_mm",
    [
        [[0, 0], [30, -0.6], [60, 0], [60, 30], [0, 30]],  # 0.3 mm: at the limit
        [[0, 0], [60, 0], [30, 50]],
        [[0, 0], [60, 0], [60, 30], [1, 30]],
        [[30, 0], [15, 25.98], [-15, 25.98], [-30, 0], [-15, -25.98], [15, -25.98]],
    ],
    ids=["bump-at-limit", "isosceles", "almost-rectangle", "hexagon"],
)
def test_outlines_the_camera_tells_apart_are_accepted(points_mm) -> None:
    ObjectType("part", shape=prism(points_mm))


@pytest.mark.parametrize(("side_mm", "refused"), [(50.3, False), (50.5, True), (50.6, False), (53.0, False)])
def test_a_nearly_square_box_is_refused_only_between_square_and_told_apart(side_mm: float, refused: bool) -> None:
    # Under 0.5 mm of difference a box is square (any quarter turn is as good); from 0.6 mm its corners
    # tell the quarter turn apart; in between, neither.
    size = (0.05, side_mm / 1000, 0.02)
    if refused:
        with pytest.raises(PlanError, match="its top turned by 90 deg comes within 0.25 mm of itself"):
            ObjectType("box", size)
    else:
        ObjectType("box", size)


PLAN = """
[objects.isosceles]
outline_mm = [[0, 0], [60, 0], [30, 50]]
height_mm = 20

[objects.bumped]
outline_mm = [[0, 0], [30, -0.2], [60, 0], [60, 30], [0, 30]]
height_mm = 20

[[targets]]
object = "isosceles"
colour = "red"
x_mm = 450
y_mm = 0
yaw_deg = 0

[[targets]]
object = "bumped"
colour = "green"
x_mm = 550
y_mm = 0
yaw_deg = 0
"""


def test_the_plan_check_refuses_before_anything_moves(tmp_path: Path) -> None:
    path = tmp_path / "plan.toml"
    path.write_text(PLAN)
    with pytest.raises(PlanError, match="bumped.*comes within 0.10 mm of itself"):
        plans.load(path)
    result = subprocess.run(
        [sys.executable, "-m", "bt_arrange.cli", "run", str(path)], capture_output=True, text=True, timeout=120
    )
    assert result.returncode == 2
    (line,) = result.stderr.strip().splitlines()
    assert "bumped" in line and "0.10 mm" in line and "Traceback" not in result.stderr
