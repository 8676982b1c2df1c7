"""Place: lower the cube onto its target and release it."""

from __future__ import annotations

import math

import numpy as np
import pytest
from behaviour_helpers import CUBE_EDGE_M, CUBE_GRASP_HEIGHT_M, SETTINGS, assert_never_blocks, command_at, set_up, write
from py_trees.common import Status

from bt_arrange.behaviours import Place, stages
from bt_arrange.geometry import PlanarPose, fold_yaw
from bt_arrange.testing import fake_arm, fake_gripper, make_context, tick_until_done

# -- Place ---------------------------------------------------------------------------------------


def test_place_lowers_the_cube_onto_its_target_and_releases_it(clock) -> None:
    context = make_context(clock=clock, gripper_width_m=CUBE_EDGE_M, object_width_m=CUBE_EDGE_M)
    target = PlanarPose(0.45, -0.1, math.radians(30.0))
    write({"/red/target": target})
    run = tick_until_done(set_up(Place("place red", "red"), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    assert run.feedback == "red released at its target"
    assert_never_blocks(run)
    assert list(dict.fromkeys(t.feedback for t in run.running)) == [
        stages.CARRY_ABOVE_TARGET,
        stages.LOWER_PART,
        stages.RELEASE_PART,
        stages.RETREAT,
    ]
    arm, gripper = fake_arm(context), fake_gripper(context)
    # The pads open only the release clearance beyond the cube on each side (8 mm: 66 mm for a 5 cm cube).
    opening_m = CUBE_EDGE_M + 2 * SETTINGS.release_clearance_per_side_m
    assert [(c.kind, c.value) for c in gripper.commands] == [("open", pytest.approx(opening_m))]
    release = arm.tcp_pose_at(command_at(arm.commands, gripper.commands[0].time_s).positions_rad)
    expected_z_m = CUBE_GRASP_HEIGHT_M + SETTINGS.release_clearance_m
    assert gripper.commands[0].speed_m_s == SETTINGS.finger_speed_m_s, "on the table: the usual release"
    np.testing.assert_allclose(release.position_m, [0.45, -0.1, expected_z_m], atol=1e-6)
    assert fold_yaw(release.yaw_rad - target.yaw_rad) == pytest.approx(0.0, abs=1e-4)
    np.testing.assert_allclose(arm.tcp_pose().position_m, [0.45, -0.1, SETTINGS.approach_height_m], atol=1e-6)


def _release_yaw_rad(clock, object_type, target_yaw_rad: float) -> tuple[float, np.ndarray]:
    from bt_arrange.plan.layout import Release

    context = make_context(clock=clock, gripper_width_m=0.04, object_width_m=0.04)
    write({"/p/target": PlanarPose(0.45, -0.1, target_yaw_rad)})
    place = Place("place p", "p", object_type, release=Release("x", 0.05, (0.003, -0.002), (0.003, -0.002)))
    run = tick_until_done(set_up(place, context), context)
    assert run.status == Status.SUCCESS, run.feedback
    arm, gripper = fake_arm(context), fake_gripper(context)
    release = arm.tcp_pose_at(command_at(arm.commands, gripper.commands[0].time_s).positions_rad)
    return release.yaw_rad, release.position_m[:2]


@pytest.mark.parametrize("turn_deg", [0.0, 180.0])
def test_among_neighbours_an_irregular_part_is_released_at_its_targets_own_yaw_not_half_a_turn_off(
    clock, turn_deg: float
) -> None:
    from bt_arrange.objects import ObjectType
    from bt_arrange.shapes import Prism

    outline = [[0, 0], [0.045, 0.004], [0.06, 0.03], [0.035, 0.028], [0.005, 0.04]]
    fragment = ObjectType("fragment", shape=Prism.from_outline(outline, 0.02))
    target_yaw = math.radians(20.0 + turn_deg)
    yaw, position = _release_yaw_rad(clock, fragment, target_yaw)
    # The part has no half-turn symmetry: the gripper's half turn would land it turned by one.
    assert fold_yaw(yaw - target_yaw, 2 * math.pi) == pytest.approx(0.0, abs=1e-4)
    # The TCP stands at the grasp's centre, which the release's offset holds, turned with the target.
    c, s = math.cos(target_yaw), math.sin(target_yaw)
    np.testing.assert_allclose(position, [0.45 + c * 0.003 + s * 0.002, -0.1 + s * 0.003 - c * 0.002], atol=1e-6)


def test_among_neighbours_a_cube_takes_the_gripper_half_turn_nearest_the_wrist(clock) -> None:
    from bt_arrange.objects import CUBE

    first, _ = _release_yaw_rad(clock, CUBE, math.radians(20.0))
    turned, _ = _release_yaw_rad(clock, CUBE, math.radians(200.0))
    assert fold_yaw(first - turned, 2 * math.pi) == pytest.approx(0.0, abs=1e-4)


# -- a part wedged between the pads --------------------------------------------------------------


def test_a_release_held_short_by_a_wedged_part_opens_all_the_way_and_then_succeeds(clock) -> None:
    context = make_context(clock=clock, gripper_width_m=CUBE_EDGE_M, object_width_m=CUBE_EDGE_M)
    write({"/red/target": PlanarPose(0.45, -0.1, 0.0)})
    gripper = fake_gripper(context)
    gripper.wedge(CUBE_EDGE_M + 0.001, opens=1)
    run = tick_until_done(set_up(Place("place red", "red"), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    opening_m = CUBE_EDGE_M + 2 * SETTINGS.release_clearance_per_side_m
    # The release stopped 15 mm short: the pads were sent all the way open, and got there.
    assert [(c.kind, c.value) for c in gripper.commands] == [
        ("open", pytest.approx(opening_m)),
        ("open", pytest.approx(SETTINGS.open_width_m)),
    ]
    assert gripper.width() == pytest.approx(SETTINGS.open_width_m)


def test_a_part_that_stays_wedged_fails_the_place_naming_the_widths(clock) -> None:
    context = make_context(clock=clock, gripper_width_m=CUBE_EDGE_M, object_width_m=CUBE_EDGE_M)
    write({"/red/target": PlanarPose(0.45, -0.1, 0.0)})
    fake_gripper(context).wedge(0.0402, opens=2)
    run = tick_until_done(set_up(Place("place red", "red"), context), context)
    assert run.status == Status.FAILURE
    assert "the fingers stopped at 40.2 mm, short of 85.0 mm: the part is wedged between the pads" in run.feedback
    assert stages.RETREAT not in {t.feedback for t in run.running}


def test_among_neighbours_the_release_opens_no_further_than_the_layout_allows(clock) -> None:
    from bt_arrange.plan.layout import Release

    context = make_context(clock=clock, gripper_width_m=0.04, object_width_m=0.04)
    write({"/p/target": PlanarPose(0.45, -0.1, 0.0)})
    gripper = fake_gripper(context)
    gripper.wedge(0.041, opens=1)  # a pad stopped by a neighbour's side, or the part: the layout's limit holds
    place = Place("place p", "p", release=Release("x", 0.05, (0.0, 0.0), (0.0, 0.0)))
    run = tick_until_done(set_up(place, context), context)
    assert run.status == Status.SUCCESS, run.feedback
    assert [c.value for c in gripper.commands] == [pytest.approx(0.05)]


def test_a_part_staged_among_neighbours_is_carried_the_way_round_that_with_the_park_after_turns_least() -> None:
    # A look (Inspect after placing) parks the arm home after every placing, among neighbours too: the
    # carry's last wrist joint takes the whole turn either side that makes the carry and that park the
    # shortest (toward_home_q). The example fresco at seed 0: 45.9 s of world time, 46.8 s with the
    # nearest turn for its staged pieces. A part placed free keeps its nearest turn when asked to (a
    # part neighbours are placed beside), and a cuboid's half turn is free: neither changes.
    from bt_arrange.objects import CUBE, ObjectType
    from bt_arrange.plan.layout import Release
    from bt_arrange.shapes import Prism

    triangle = ObjectType("triangle", shape=Prism.from_outline([[0, 0], [0.06, 0], [0, 0.06]], 0.02))
    staged = Release("x", 0.07, (0.015, 0.0))
    assert Place("p", "p", triangle, release=staged, nearest_turn=True)._free_transfer(triangle)
    assert Place("p", "p", triangle, release=staged)._free_transfer(triangle)
    assert Place("p", "p", triangle)._free_transfer(triangle)
    assert not Place("p", "p", triangle, nearest_turn=True)._free_transfer(triangle)
    assert not Place("p", "p", CUBE, release=staged)._free_transfer(CUBE)
    assert not Place("p", "p", triangle, release=staged, where="pick")._free_transfer(triangle)
