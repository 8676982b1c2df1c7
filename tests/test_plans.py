"""Plan files: the contract's names and units, defaults, identical parts numbered, starts given by hand."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from bt_arrange import examples, plans
from bt_arrange.errors import PlanError
from bt_arrange.objects import CUBE
from bt_arrange.trees import Arrangement


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "plan.toml"
    path.write_text(text)
    return path


def test_the_issue_s_example_loads_with_its_units(tmp_path: Path) -> None:
    plan = plans.load(
        write(
            tmp_path,
            """
threshold_mm = 1.5
yaw_threshold_deg = 2.0
correct = "after_all"
max_pushes = 7
[objects.bar]
size_mm = [80, 40, 40]
[colours.orange]
rgb = [1.0, 0.5, 0.0]
[colours.teal]
hue_deg = [160, 200]
saturation = [0.4, 1.0]
[[targets]]
colour = "red"
x_mm = 450
y_mm = 50
name = "red cube"
[[targets]]
object = "bar"
colour = "orange"
x_mm = 560
y_mm = -160
yaw_deg = 30
[scene]
seed = 3
""",
        )
    )
    red, bar = plan.targets
    assert (red.obj, red.object_type, red.x_m, red.y_m) == ("red cube", CUBE, 0.45, 0.05)
    assert bar.object_type.size_m == (0.08, 0.04, 0.04) and bar.yaw_rad == pytest.approx(math.radians(30))
    assert (plan.threshold_mm, plan.yaw_threshold_deg, plan.correct, plan.max_pushes, plan.seed) == (
        1.5,
        2.0,
        "after_all",
        7,
        3,
    )
    assert plan.colours["orange"].rgb == (1.0, 0.5, 0.0)
    assert plan.colours["teal"].hue_ranges_deg == ((160.0, 200.0),)
    root = plan.create_root()
    assert isinstance(root, Arrangement) and root.yaw_threshold_deg == 2.0 and "orange" in root.colours


def test_identical_parts_are_numbered_and_explicit_starts_take_their_names(tmp_path: Path) -> None:
    targets = "".join(f'[[targets]]\ncolour = "green"\nx_mm = 520\ny_mm = {y}\n' for y in (-100, 0, 100))
    starts = "".join(f'[[scene.starts]]\ncolour = "green"\nx_mm = 330\ny_mm = {y}\n' for y in (-200, 0, 200))
    plan = plans.load(write(tmp_path, targets + starts))
    assert [t.obj for t in plan.targets] == ["green 1", "green 2", "green 3"]
    assert [s.name for s in plan.create_scene()] == ["green 1", "green 2", "green 3"]


def test_errors_name_the_file_and_the_entry(tmp_path: Path) -> None:
    path = write(tmp_path, '[[targets]]\ncolour = "red"\nx_mm = 450\n')
    with pytest.raises(PlanError, match=r"plan\.toml: \[\[targets\]\] 1: missing y_mm$"):
        plans.load(path)


@pytest.mark.parametrize("name", examples.names())
def test_every_example_loads_and_builds(name: str) -> None:
    path = examples.path_of(name)
    assert path is not None
    plan = plans.load(path)
    assert isinstance(plan.create_root(), Arrangement)
    assert examples.describe(name)


def test_a_plan_file_target_beyond_any_reach_is_refused_in_its_own_millimetres(tmp_path):
    path = tmp_path / "far.toml"
    path.write_text('[[targets]]\ncolour = "red"\nx_mm = 5000\ny_mm = 0\n')
    with pytest.raises(PlanError, match=r"x_mm = 5000, y_mm = 0 lie 5 m from the table's origin: beyond any arm"):
        plans.load(path).create_root()
