"""Plans in layers: z_mm, the build order bottom-up, and one refusal per problem, in one line."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from bt_arrange import plans
from bt_arrange.errors import PlanError
from bt_arrange.plan import stacking
from bt_arrange.plan.check import check_plan
from bt_arrange.settings import ManipulationSettings
from bt_arrange.trees import TARGETS, Target, plan_steps
from bt_arrange_sim.config import CameraConfig

PILLAR = """
[objects.pillar]
size_mm = [50, 50, 100]
"""


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "stack.toml"
    path.write_text(text)
    return path


def cube(colour: str, x_mm: float, y_mm: float, z_mm: float = 0.0, yaw_deg: float = 0.0, obj: str = "") -> str:
    kind = f'object = "{obj}"\n' if obj else ""
    return f'[[targets]]\n{kind}colour = "{colour}"\nx_mm = {x_mm}\ny_mm = {y_mm}\nyaw_deg = {yaw_deg}\nz_mm = {z_mm}\n'


def refusal(tmp_path: Path, text: str) -> str:
    with pytest.raises(PlanError) as caught:
        plans.load(write(tmp_path, text))
    message = str(caught.value)
    assert "\n" not in message
    assert message.startswith(str(tmp_path / "stack.toml") + ": [[targets]]"), message
    return message


def test_a_tower_loads_with_its_heights_and_builds_bottom_up_whatever_the_file_s_order(tmp_path: Path) -> None:
    text = cube("yellow", 500, 0, 150, 45) + cube("blue", 500, 0, 100, 30) + cube("green", 500, 0, 50, 15)
    plan = plans.load(write(tmp_path, text + cube("red", 500, 0, 0)))
    assert [t.z_m for t in plan.targets] == [0.15, 0.1, 0.05, 0.0]
    assert [st.part.name for st in plan_steps(plan.targets)] == ["red", "green", "blue", "yellow"]
    root = plan.create_root()
    assert [t.obj for t in root.targets] == ["yellow", "blue", "green", "red"]
    # The tree places them in the check's order: the first subtree is the bottom cube's.
    assert root.children[0].name == "then the next (red)"


def test_z_mm_is_a_target_s_and_a_start_has_none(tmp_path: Path) -> None:
    text = cube("red", 500, 0) + '[[scene.starts]]\ncolour = "red"\nx_mm = 400\ny_mm = 150\nz_mm = 50\n'
    with pytest.raises(PlanError, match=r"\[\[scene.starts\]\] 1: unknown key 'z_mm'"):
        plans.load(write(tmp_path, text))
    with pytest.raises(PlanError, match=r"\[\[targets\]\] 1: z_mm = -5: .* below the table"):
        plans.load(write(tmp_path, cube("red", 500, 0, -5)))


def test_the_xml_codec_carries_a_raised_target_s_height_and_leaves_a_table_target_as_it_was() -> None:
    raised = Target("green", 0.5, 0.0, 0.25, z_m=0.05)
    on_table = Target("red", 0.5, 0.0, 0.0)
    text = TARGETS.format([on_table, raised])
    assert text == "red,0.5,0.0,0.0;green,0.5,0.0,0.25,,,0.05"
    assert TARGETS.parse(text) == [on_table, raised]


def test_a_part_standing_on_nothing_is_refused(tmp_path: Path) -> None:
    message = refusal(tmp_path, cube("red", 500, 0) + cube("green", 500, 0, 60))
    assert message.endswith(
        "[[targets]] 2: target green at z 60 mm stands on nothing: no part's top face is at 60 mm under its "
        "footprint (the tops under it lie at 50 mm)"
    )


def test_a_centre_of_mass_too_near_its_support_s_edge_is_refused(tmp_path: Path) -> None:
    # 20 mm off a 5 cm cube: its centre 5 mm inside the 30 mm of contact.
    message = refusal(tmp_path, cube("red", 500, 0) + cube("green", 520, 0, 50))
    assert "[[targets]] 2 and [[targets]] 1: target green at z 50 mm: its centre of mass lies 5.0 mm inside" in message
    assert "at least 10 mm inside" in message
    # A leaning tower: each cube 9 mm further out stands alone, but the second carries the two above it.
    text = cube("red", 500, 0) + cube("green", 509, 0, 50) + cube("blue", 518, 0, 100) + cube("yellow", 527, 0, 150)
    message = refusal(tmp_path, text)
    assert "target green at z 50 mm: its centre of mass (with the 2 parts standing on it) lies 7.0 mm inside" in message


def test_two_parts_sharing_heights_that_overlap_are_refused(tmp_path: Path) -> None:
    message = refusal(tmp_path, cube("red", 500, 0) + cube("green", 500, 0, 50) + cube("blue", 510, 0, 50))
    assert "target green and blue overlap, both at z 50 mm" in message.replace("targets green", "target green")
    message = refusal(tmp_path, cube("red", 500, 0) + cube("green", 500, 40, 30))
    assert "targets red and green overlap, at z 0 mm to 50 mm and 30 mm to 80 mm" in message


def test_a_layer_the_pads_cannot_reach_without_touching_a_lower_part_is_refused(tmp_path: Path) -> None:
    # A 10 cm pillar 10 mm beside the bottom cube: the pads releasing the cube on top come down beside it.
    text = PILLAR + cube("red", 500, 0) + cube("blue", 560, 0, obj="pillar") + cube("green", 500, 0, 50)
    message = refusal(tmp_path, text)
    assert "target green at z 50 mm: the pads releasing it come down to 56.3 mm, onto blue below, whose top" in message
    assert "the gripper cannot reach this layer without touching a lower part" in message


def test_a_tower_taller_than_the_arm_allows_is_refused(tmp_path: Path) -> None:
    pillars = "".join(cube("red", 700, 0, z, obj="pillar") for z in (0, 100, 200, 300))
    message = refusal(tmp_path, PILLAR + pillars + cube("green", 700, 0, 400))
    assert "[[targets]] 5: target green at z 400 mm: the tower is taller than the arm allows" in message
    assert "the TCP reaches up to 465 mm there" in message


def test_a_tower_taller_than_the_camera_allows_is_refused(tmp_path: Path) -> None:
    pillars = "".join(cube("red", 500, 0, z, obj="pillar") for z in (0, 100, 200, 300, 400))
    plan = plans.load(write(tmp_path, PILLAR + pillars))  # the arm reaches it: only the cell's camera refuses it
    with pytest.raises(PlanError) as caught:
        check_plan(plan.targets, view=CameraConfig().view())
    message = str(plan.source.locate(caught.value))
    assert message.endswith(
        "[[targets]] 5: target red 5: its top face at 500 mm is 200 mm from the camera, nearer than its depth's "
        "250 mm: the tower is taller than the camera allows (top faces up to 450 mm there)"
    )


def test_the_support_polygon_of_a_turned_cube_holds_the_disc_of_its_inscribed_circle() -> None:
    settings = ManipulationSettings()
    below = Target("red", 0.5, 0.0, 0.0)
    above = Target("green", 0.5, 0.0, math.radians(15), z_m=0.05)
    support = stacking.support_of(above, [below, above], settings)
    assert [t.obj for t in support.below] == ["red"]
    assert stacking.depth_inside_m(support.polygon, 0.5, 0.0) == pytest.approx(0.025, abs=1e-9)
    # Two cubes side by side 2 mm apart carry one between them: the hull spans both contacts.
    left, right = Target("red", 0.5, -0.026, 0.0), Target("blue", 0.5, 0.026, 0.0)
    top = Target("green", 0.5, 0.0, 0.0, z_m=0.05)
    polygon = stacking.support_of(top, [left, right, top], settings).polygon
    assert np.ptp(polygon[:, 1]) == pytest.approx(0.05, abs=1e-9)


def nodes(root, kind):
    import py_trees

    return [n for n in root.iterate() if isinstance(n, kind)] if isinstance(root, py_trees.behaviour.Behaviour) else []


def test_a_raised_part_s_subtree_works_at_its_height_and_checks_that_it_stands() -> None:
    from bt_arrange.behaviours import CheckStanding, Inspect, Pick, Place, Push

    root = plans.load(examples_path("tower")).create_root()
    green = next(c for c in root.children if c.name == "then the next (green)")
    assert {n.z_m for n in nodes(green, Place) if n.where == "target"} == {0.05}
    # Set down where it was picked (on the table) and picked centred before it goes on the tower.
    assert [n.z_m for n in nodes(green, Place) if n.where == "pick"] == [0.0]
    assert {n.z_m for n in nodes(green, Inspect)} == {0.05}
    assert {n.z_m for n in nodes(green, Push)} == {0.05}
    assert sorted({n.z_m for n in nodes(green, Pick)}) == [0.0, 0.05]
    assert [n.z_m for n in nodes(green, CheckStanding)] == [0.05, 0.05]  # after placing, and after placing again
    # Every move above the table clears the finished tower's top (200 mm) by the approach clearance.
    assert root.settings.approach_height_m == pytest.approx(0.25)


def test_after_each_raised_placement_the_parts_below_still_in_view_are_looked_at_again() -> None:
    from bt_arrange.behaviours import Recheck

    root = plans.load(examples_path("pyramid")).create_root()
    watched = {
        c.name.removeprefix("then the next ("): [(n.obj, n.after) for n in nodes(c, Recheck)]
        for c in root.children
        if c.name.startswith("then the next")
    }
    # The first green cube leaves the third red one in view; the second covers it; the top one covers all.
    assert watched["green 1)"] == [("red 3", "green 1")]
    assert watched["green 2)"] == [("green 1", "green 2")]  # its neighbour in its own layer
    assert watched["blue)"] == []


def test_a_plan_in_layers_is_corrected_part_by_part(tmp_path: Path) -> None:
    text = 'correct = "after_all"\n' + cube("red", 500, 0) + cube("green", 500, 0, 50)
    with pytest.raises(PlanError, match=r'\[\[targets\]\] 2: correct = "after_all" places every part before'):
        plans.load(write(tmp_path, text))


def test_a_raised_part_released_off_its_target_must_stand_there_too(tmp_path: Path) -> None:
    # Two bars across two, 2 mm apart: no room for the pads between them, so the second is released
    # 14 mm off its target, where 5 mm of its centre's margin would be left.
    bars = "[objects.bar]\nsize_mm = [80, 40, 40]\n"
    text = bars + cube("red", 500, -21, obj="bar") + cube("green", 500, 21, obj="bar")
    text += cube("blue", 479, 0, 40, 90, obj="bar") + cube("yellow", 521, 0, 40, 90, obj="bar")
    message = refusal(tmp_path, text)
    assert (
        "target yellow at z 40 mm: its neighbours leave the pads no room at its target, and released 14 mm" in message
    )


def examples_path(name: str) -> Path:
    from bt_arrange import examples

    path = examples.path_of(name)
    assert path is not None
    return path


def test_a_raised_part_among_neighbours_is_picked_off_its_support_as_the_layout_releases_it() -> None:
    from bt_arrange.behaviours import Inspect, Pick, Place

    root = plans.load(examples_path("pyramid")).create_root()
    green = next(c for c in root.children if c.name == "then the next (green 2)")
    placed = next(n for n in nodes(green, Place) if n.name == "place green 2")
    assert placed.release is not None  # its neighbour 2 mm away: the pads stand across the free axis
    picked_off = next(n for n in nodes(green, Pick) if n.name == "pick green 2 off its support")
    placed_again = next(n for n in nodes(green, Place) if n.name == "place green 2 on its support again")
    # Not the default grasp, whose pad could come down into the gap beside green 1 and knock the layer off.
    assert picked_off.grasp == placed.release
    assert placed_again.release == placed.release
    # Two identical green cubes: the inspection after placing it again tells it from its twin.
    again = next(n for n in nodes(green, Inspect) if n.name == "inspect green 2 after placing it on its support again")
    assert len(again.kind_targets) == 2


# -- Flat parts come down to the approach clearance over the tallest --------------------


@pytest.mark.parametrize(
    ("example", "approach_m"),
    [("irregular_parts", 0.06), ("near_symmetric", 0.06), ("four_cubes", 0.10), ("fresco", 0.10)],
)
def test_a_plan_of_flat_parts_placed_free_moves_above_the_table_at_the_clearance_over_its_tallest(
    example: str, approach_m: float
) -> None:
    """Flat parts placed free come down to 5 cm over the tallest; cubes, and pieces among neighbours, do not."""
    root = plans.load(examples_path(example)).create_root()
    assert root.settings.approach_height_m == pytest.approx(approach_m)


def test_the_approach_over_the_plan_can_be_turned_off_and_never_rises_above_the_setting() -> None:
    settings = ManipulationSettings()
    from bt_arrange.shapes import Prism

    flat = settings.for_tallest_part(0.02)
    flat_square = Prism.from_outline([[0, 0], [0.03, 0], [0.03, 0.03], [0, 0.03]], 0.02)
    assert flat.approach_height_m == pytest.approx(0.06)
    assert flat.tcp_heights_m(flat_square)[1] == pytest.approx(0.06), "every shape of the plan as low"
    assert settings.for_tallest_part(0.05) is settings, "a cube's plan keeps 0.10 m"
    assert settings.for_tallest_part(0.08) is settings, "a taller part raises it through the shape's own height"
    kept = ManipulationSettings(approach_over_plan=False)
    assert kept.for_tallest_part(0.02) is kept


@pytest.mark.parametrize(("example", "approach_m"), [("irregular_parts", 0.06), ("tower", 0.25)])
def test_a_plan_exported_to_xml_moves_above_the_table_at_the_plans_own_height(
    example: str, approach_m: float, tmp_path: Path
) -> None:
    from bt_arrange import treefile, xmltree

    exported = tmp_path / f"{example}.xml"
    exported.write_text(xmltree.to_xml(treefile.build_root(treefile.load(examples_path(example))), tree_id=example))
    root = treefile.build_root(treefile.load(exported))
    assert root.settings.approach_height_m == pytest.approx(approach_m)


@pytest.mark.parametrize(("example", "nearest"), [("irregular_parts", False), ("fresco", True)])
def test_parts_neighbours_are_placed_beside_keep_the_wrists_nearest_grasp_and_turn(example: str, nearest: bool) -> None:
    """The half turn and the short way round are for parts placed free; among neighbours as planned."""
    from bt_arrange.behaviours import Pick, Place

    root = plans.load(examples_path(example)).create_root()
    # The transfers (a part picked up again after a miss takes the free choice either way).
    picks = [n for n in root.iterate() if isinstance(n, Pick) and n.grasp is None and "again" not in n.name]
    places = [
        n
        for n in root.iterate()
        if isinstance(n, Place) and n.release is None and n.where == "target" and "again" not in n.name
    ]
    assert picks and {p.nearest_grasp for p in picks} == {nearest}
    if places:
        assert {p.nearest_turn for p in places} == {nearest}
