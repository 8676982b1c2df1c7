"""Plan files with frescoes: ``[fresco.NAME]`` (the contract), every bad key one line naming it."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from bt_arrange import plans
from bt_arrange.errors import PlanError
from bt_arrange.shapes import Prism
from bt_arrange.shapes.fracture import fracture

FRESCO = """
[colours.ochre]
rgb = [0.8, 0.55, 0.2]

[fresco.tile]
size_mm = [120, 80, 20]
pieces = 3
gap_mm = 2
seed = 0
colour = "ochre"
x_mm = 500
y_mm = 0
yaw_deg = 0
"""


def write(tmp_path: Path, text: str, name: str = "plan.toml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def with_key(key: str, value: str | None) -> str:
    """The fresco plan with ``key`` set to ``value`` (None: left out)."""
    lines = [line for line in FRESCO.splitlines() if not line.startswith(f"{key} =")]
    if value is not None:
        lines.insert(lines.index("[fresco.tile]") + 1, f"{key} = {value}")
    return "\n".join(lines) + "\n"


def test_a_fresco_is_its_pieces_each_a_prism_of_the_colour_at_its_place_in_the_whole(tmp_path) -> None:
    plan = plans.load(write(tmp_path, FRESCO))
    assert [t.obj for t in plan.targets] == ["tile 1", "tile 2", "tile 3"]
    assert {t.colour for t in plan.targets} == {"ochre"}
    expected = fracture((0.12, 0.08, 0.02), 3, 0.002, 0, (0.5, 0.0, 0.0))
    for target, piece in zip(plan.targets, expected, strict=True):
        assert isinstance(target.object_type.shape, Prism)
        assert target.object_type.name == target.obj
        assert target.object_type.shape == piece.prism
        assert (target.x_m, target.y_m, target.yaw_rad) == pytest.approx((piece.x_m, piece.y_m, piece.yaw_rad))
    # The scene scatters the pieces like other parts, clear of the targets.
    turned = plans.load(write(tmp_path, with_key("yaw_deg", "90"), "turned.toml"))
    for a, b in zip(plan.targets, turned.targets, strict=True):
        assert (b.x_m - 0.5, b.y_m) == pytest.approx((-a.y_m, a.x_m - 0.5), abs=1e-9)
        assert math.remainder(b.yaw_rad - a.yaw_rad - math.pi / 2, 2 * math.pi) == pytest.approx(0.0, abs=1e-9)


def test_a_fresco_beside_other_targets_and_optional_keys(tmp_path) -> None:
    text = with_key("gap_mm", None).replace("seed = 0\n", "")
    text += '\n[[targets]]\ncolour = "red"\nx_mm = 450\ny_mm = 250\n'
    plan = plans.load(write(tmp_path, text))
    assert [t.obj for t in plan.targets] == ["red", "tile 1", "tile 2", "tile 3"]
    same = plans.load(write(tmp_path, FRESCO, "full.toml"))
    assert [t.object_type for t in plan.targets[1:]] == [t.object_type for t in same.targets]


@pytest.mark.parametrize(
    ("key", "value", "message"),
    [
        ("pieces", "2", "pieces = 2: a fresco breaks into 3 to 12"),
        ("pieces", "13", "pieces = 13: a fresco breaks into 3 to 12"),
        ("pieces", "4.5", "pieces = 4.5: a fresco breaks into 3 to 12"),
        (
            "gap_mm",
            "1.5",
            r"gap_mm = 1.5: two pieces each within the threshold \(1 mm\) must not touch, so the gap along a "
            r"fracture must be at least 2 mm \(twice the threshold, 0.5 mm at the finest\)",
        ),
        ("gap_mm", '"2"', 'gap_mm = "2" is not a number'),
        ("seed", "-1", "seed = -1 is not a whole number"),
        ("colour", '"ocher"', 'unknown colour "ocher".*ochre'),
        ("size_mm", "[120, 80]", r"size_mm = \[120, 80\] is not three numbers"),
        ("size_mm", "[0.12, 0.08, 0.02]", "looks like metres"),
        ("size_mm", "[120, -80, 20]", "must be positive"),
        ("size_mm", "[24, 16, 20]", "no fracture of a 24 x 16 mm slab into 3 pieces"),
        ("x_mm", "0.5", "look like metres"),
        ("x_mm", None, "missing x_mm"),
        ("pieces", None, "missing pieces"),
        ("yaw_deg", "true", "yaw_deg = true is not a number"),
        ("piece", "3", "unknown key 'piece'.*pieces"),
        ("x_mm", "2000", "tile 1 at .* is out of reach"),
    ],
)
def test_a_bad_fresco_key_is_one_line_naming_the_file_the_fresco_and_the_key(tmp_path, key, value, message) -> None:
    path = write(tmp_path, with_key(key, value))
    with pytest.raises(PlanError, match=message) as caught:
        plans.load(path)
    text = str(caught.value)
    assert "[fresco.tile]" in text and str(path) in text
    assert "\n" not in text


def test_a_fresco_whose_piece_names_are_taken_is_refused(tmp_path) -> None:
    text = FRESCO + '\n[[targets]]\ncolour = "red"\nname = "tile 2"\nx_mm = 450\ny_mm = 250\n'
    with pytest.raises(PlanError, match=r"\[fresco.tile\]: its piece 'tile 2' has the name of another"):
        plans.load(write(tmp_path, text))


def test_a_plan_needs_targets_or_a_fresco(tmp_path) -> None:
    with pytest.raises(PlanError, match=r"no \[\[targets\]\], no \[fresco.NAME\] and no \[puzzle.NAME\]"):
        plans.load(write(tmp_path, "threshold_mm = 1.0\n"))


@pytest.mark.parametrize(
    ("threshold_mm", "gap_mm", "refused"),
    [
        (0.25, 0.5, False),
        (0.25, 0.45, True),
        (0.5, 0.9, True),
        (0.5, 1.0, False),
        (0.1, 0.5, False),
        (0.1, 0.4, True),
        (3.0, 2.0, False),
    ],
)
def test_the_least_gap_is_twice_the_plans_threshold_from_half_a_millimetre_to_two(
    tmp_path, threshold_mm: float, gap_mm: float, refused: bool
) -> None:
    # Two pieces each within the threshold of their targets, towards each other, must not touch; 2 mm
    # (what a 1 mm threshold needs) is kept for coarser thresholds, 0.5 mm is the least at all.
    text = f"threshold_mm = {threshold_mm}\n" + with_key("gap_mm", str(gap_mm))
    path = write(tmp_path, text)
    if refused:
        least = max(0.5, min(2.0, 2 * threshold_mm))
        with pytest.raises(PlanError, match=f"must be at least {least:g} mm"):
            plans.load(path)
    else:
        plan = plans.load(path)
        assert len(plan.targets) == 3


def test_a_tree_run_coarser_than_its_plan_refuses_the_tight_gaps_naming_the_pieces(tmp_path) -> None:
    from bt_arrange.trees import arrangement

    plan = plans.load(write(tmp_path, "threshold_mm = 0.25\n" + with_key("gap_mm", "0.5")))
    arrangement(plan.targets, threshold_mm=0.25, colours=plan.colours)  # built as written
    with pytest.raises(PlanError, match=r"^targets tile \d and tile \d are 0.5 mm apart, under the 2 mm two parts"):
        arrangement(plan.targets, threshold_mm=1.0, colours=plan.colours)
