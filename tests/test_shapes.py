"""The shape seam: the cuboid's grasps, faces and footprint, and the gripper's openings, against today's figures."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_arrange.errors import PlanError
from bt_arrange.objects import BAR, CUBE, ObjectType
from bt_arrange.settings import ManipulationSettings
from bt_arrange.shapes import (
    ROBOTIQ_2F85,
    Cuboid,
    Gripper,
    Shape,
    folded_yaw,
    footprint_m,
    grown,
    min_centre_distance_m,
    preferred_grasp,
    yaw_error_rad,
)


def test_the_cube_and_the_bar_are_cuboids_behind_the_protocol() -> None:
    for kind in (CUBE, BAR):
        shape: Shape = kind.shape
        assert isinstance(shape, Cuboid)
        assert kind.size_m == shape.size_m
    assert CUBE.size_text == "50 x 50 x 50 mm"
    assert BAR.size_text == "80 x 40 x 40 mm"


def test_the_cube_is_held_across_either_side_at_half_its_height() -> None:
    grasps = CUBE.shape.grasps(ROBOTIQ_2F85)
    assert [(g.axis, g.yaw_offset_rad, g.width_m, g.height_m) for g in grasps] == [
        ("x", 0.0, 0.05, 0.025),
        ("y", math.pi / 2, 0.05, 0.025),
    ]


def test_a_bar_is_held_across_its_40_mm_side_only_and_low_enough_for_the_pads() -> None:
    (grasp,) = BAR.shape.grasps(ROBOTIQ_2F85)
    assert (grasp.axis, grasp.yaw_offset_rad, grasp.width_m) == ("y", math.pi / 2, 0.04)
    # Half of 40 mm would put the pads' bottoms 1.25 mm above the table: they stay 4 mm above it.
    assert grasp.height_m == pytest.approx(0.02275)
    assert grasp.height_m == pytest.approx(ROBOTIQ_2F85.pad_half_height_m + ROBOTIQ_2F85.table_clearance_m)


def test_a_part_wider_than_the_stroke_allows_has_no_grasp_and_is_refused_naming_the_limit() -> None:
    assert Cuboid((0.081, 0.09, 0.05)).grasps(ROBOTIQ_2F85) == ()
    with pytest.raises(PlanError, match=r"object type 'slab': .*closes across at most 80 mm: its 85 mm stroke"):
        ObjectType("slab", (0.081, 0.09, 0.05))
    # A wider gripper takes it.
    wide = Gripper(stroke_m=0.14)
    assert preferred_grasp(Cuboid((0.081, 0.09, 0.05)), wide).width_m == 0.081


@pytest.mark.parametrize(
    ("size_m", "message"),
    [
        ((0.05, 0.0, 0.05), "has an edge that is not positive"),
        ((0.05, 0.01, 0.05), "has an edge under 15 mm"),
        ((0.05, 0.05, 0.12), "120 mm tall, taller than 100 mm"),
    ],
)
def test_a_cuboid_the_pads_or_the_camera_cannot_handle_is_one_plan_error(size_m, message) -> None:
    with pytest.raises(PlanError, match=message):
        ObjectType("odd", size_m)


def test_the_pushed_face_is_the_one_square_to_the_push_and_its_leading_width_shrinks_with_the_turn() -> None:
    bar = BAR.shape
    along_x = bar.pushed_face(0.0, 0.0)
    assert (along_x.width_m, along_x.depth_m, along_x.leading_width_m) == (0.04, 0.08, 0.04)
    along_y = bar.pushed_face(math.pi / 2, 0.0)
    assert (along_y.width_m, along_y.depth_m) == (0.08, 0.04)
    turned = CUBE.shape.pushed_face(0.0, math.radians(10.0))
    assert turned.leading_width_m == pytest.approx(0.05 * (math.cos(math.radians(10)) - math.sin(math.radians(10))))
    # Turned past 45 degrees the other face leads: the same leading width as turned the other way.
    assert CUBE.shape.pushed_face(0.0, math.radians(80.0)).leading_width_m == pytest.approx(turned.leading_width_m)


def test_the_footprint_is_the_outline_placed_on_the_table() -> None:
    corners = footprint_m(BAR.shape, 0.45, 0.1, math.pi / 2)
    np.testing.assert_allclose(corners, [[0.47, 0.06], [0.47, 0.14], [0.43, 0.14], [0.43, 0.06]], atol=1e-12)
    grown_corners = footprint_m(grown(CUBE.shape, 0.01), 0.0, 0.0, 0.0)
    np.testing.assert_allclose(grown_corners, [[-0.035, -0.035], [0.035, -0.035], [0.035, 0.035], [-0.035, 0.035]])


def test_symmetry_folds_yaw_errors_and_sweep_radii_space_parts() -> None:
    assert CUBE.shape.symmetry_rad == pytest.approx(math.pi / 2)
    assert BAR.shape.symmetry_rad == pytest.approx(math.pi)
    assert math.degrees(yaw_error_rad(CUBE.shape, math.radians(91.0), 0.0)) == pytest.approx(1.0)
    assert math.degrees(yaw_error_rad(BAR.shape, math.radians(91.0), 0.0)) == pytest.approx(91.0 - 180.0)
    assert folded_yaw(CUBE.shape, math.radians(50.0)) == pytest.approx(math.radians(-40.0))
    assert min_centre_distance_m(CUBE.shape, CUBE.shape) == pytest.approx(0.05 * math.sqrt(2))


def test_the_gripper_opens_42_mm_for_a_free_push_and_24_mm_among_neighbours_on_a_cube() -> None:
    assert ROBOTIQ_2F85.free_push_opening_m(0.05) == pytest.approx(0.042)
    assert ROBOTIQ_2F85.neighbour_push_opening_m(0.05) == pytest.approx(0.024)
    assert ROBOTIQ_2F85.neighbour_push_opening_m(0.02) == 0.0
    assert ROBOTIQ_2F85.max_grasp_width_m == pytest.approx(0.080)


def test_one_settings_value_holds_the_gripper_and_the_heights_follow_the_shape() -> None:
    settings = ManipulationSettings()
    assert settings.gripper is ROBOTIQ_2F85
    assert settings.open_width_m == ROBOTIQ_2F85.stroke_m
    assert settings.tcp_heights_m(CUBE.shape) == (0.025, 0.10, 0.025)
    grasp_m, approach_m, push_m = settings.tcp_heights_m(Cuboid((0.05, 0.05, 0.08)))
    assert (grasp_m, push_m) == (0.04, 0.04)
    assert approach_m == pytest.approx(0.13), "a part 3 cm taller raises the moves above the table by 3 cm"


def test_a_cube_grown_by_a_machining_error_stays_the_same_type_in_name() -> None:
    grown_cube = CUBE.resized(0.0002)
    assert grown_cube.name == "cube"
    assert grown_cube.size_m == pytest.approx((0.0502, 0.0502, 0.0502))


def test_an_object_type_takes_a_shape_or_a_size_not_both() -> None:
    assert ObjectType("box", shape=Cuboid((0.04, 0.06, 0.03))) == ObjectType("box", (0.04, 0.06, 0.03))
    with pytest.raises(PlanError, match="a size or a shape, not both"):
        ObjectType("box", (0.04, 0.06, 0.03), shape=Cuboid((0.04, 0.06, 0.03)))
