"""The prism shape on hand-made outlines: the outline check, the centroid frame, symmetry, grasps, pushed faces."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_arrange.errors import PlanError
from bt_arrange.objects import ObjectType
from bt_arrange.shapes import ROBOTIQ_2F85, Prism, footprint_m, outline_problem, yaw_error_rad
from bt_arrange.shapes.polygon import signed_area_m2

#: The issue's L, in metres: 60 x 50 mm, legs 20 mm wide.
ELL = [[0, 0], [0.06, 0], [0.06, 0.02], [0.02, 0.02], [0.02, 0.05], [0, 0.05]]


def regular(sides: int, radius_m: float) -> list[list[float]]:
    return [
        [radius_m * math.cos(2 * math.pi * k / sides), radius_m * math.sin(2 * math.pi * k / sides)]
        for k in range(sides)
    ]


@pytest.mark.parametrize(
    ("points", "message"),
    [
        ([[0, 0], [0.05, 0]], "at least three points"),
        ([[0, 0], [0.05, 0], [0.05, 0], [0, 0.05]], "repeats point 2"),
        ([[0, 0], [0.02, 0], [0.05, 0]], "encloses no area"),
        ([[0, 0], [0.05, 0.05], [0.05, 0], [0, 0.03]], "crosses itself"),
        ([[0, 0], [0.06, 0.04], [0.06, 0], [0, 0.04]], "crosses itself"),  # a bow tie: no signed area either
        ([[0, 0], [0.05, float("nan")], [0, 0.05]], "finite"),
    ],
)
def test_an_outline_that_is_no_simple_polygon_is_refused_in_one_line(points, message) -> None:
    problem = outline_problem(points)
    assert problem is not None and message in problem
    with pytest.raises(PlanError, match=message):
        Prism.from_outline(points, 0.02)


def test_the_frame_is_the_area_centroid_and_the_winding_does_not_matter() -> None:
    ell = Prism.from_outline(ELL, 0.02)
    # The L is a 60 x 20 bar and a 20 x 30 upright: centroid (23.33, 18.33) mm of the outline as written.
    np.testing.assert_allclose(ell.outline_m[0], [-0.0233333, -0.0183333], atol=1e-6)
    assert ell.area_m2 == pytest.approx(0.0018)
    assert np.mean(ell.outline_m, axis=0) != pytest.approx(0.0)  # not the vertex mean: the area centroid
    clockwise = Prism.from_outline(ELL[::-1], 0.02)
    assert clockwise.area_m2 == pytest.approx(ell.area_m2)
    assert clockwise.area_m2 > 0
    assert set(clockwise.outline) == set(ell.outline)
    shifted = Prism.from_outline([[x + 0.3, y - 0.2] for x, y in ELL], 0.02)
    np.testing.assert_allclose(sorted(shifted.outline), sorted(ell.outline), atol=1e-12)


@pytest.mark.parametrize(
    ("points", "degrees"),
    [
        (regular(3, 0.03), 120.0),
        (regular(4, 0.03), 90.0),
        (regular(5, 0.03), 72.0),
        ([[0, 0], [0.06, 0], [0.06, 0.03], [0, 0.03]], 180.0),
        (ELL, 360.0),
        ([[0, 0], [0.07, 0], [0.05, 0.035], [0.015, 0.035]], 360.0),
    ],
)
def test_symmetry_is_found_from_the_outline(points, degrees) -> None:
    prism = Prism.from_outline(points, 0.02)
    assert math.degrees(prism.symmetry_rad) == pytest.approx(degrees)
    turned = math.radians(degrees) + math.radians(3.0)
    assert math.degrees(yaw_error_rad(prism, turned, 0.0)) == pytest.approx(3.0)


def test_a_square_is_grasped_at_its_centre_across_either_side() -> None:
    square = Prism.from_outline([[0, 0], [0.04, 0], [0.04, 0.04], [0, 0.04]], 0.03)
    grasps = square.grasps(ROBOTIQ_2F85)
    assert sorted(g.axis for g in grasps) == ["x", "y"]
    for grasp in grasps:
        assert grasp.width_m == pytest.approx(0.04)
        assert grasp.centre_m == pytest.approx((0.0, 0.0), abs=1e-9)
        assert grasp.height_m == pytest.approx(0.02275), "a 30 mm part: the pads stay 4 mm above the table"


def test_a_triangle_is_held_between_an_edge_and_the_opposite_corner() -> None:
    triangle = Prism.from_outline([[0, 0], [0.05, 0], [0.025, 0.05 * math.sqrt(3) / 2]], 0.02)
    grasps = triangle.grasps(ROBOTIQ_2F85)
    assert len(grasps) == 3, "one per edge: no two edges of a triangle face each other"
    for grasp in grasps:
        assert grasp.width_m == pytest.approx(0.05 * math.sqrt(3) / 2, abs=1e-6)
        # The pads' centre lies on the altitude through the corner: the two contact forces are in line.
        centre = np.array(grasp.centre_m)
        closing = np.array([math.cos(grasp.yaw_offset_rad), math.sin(grasp.yaw_offset_rad)])
        assert abs(float(centre @ np.array([-closing[1], closing[0]]))) < 1e-3


def test_the_grasp_nearest_the_centroid_comes_first_and_nothing_of_the_outline_is_under_the_pads() -> None:
    ell = Prism.from_outline(ELL, 0.02)
    grasps = ell.grasps(ROBOTIQ_2F85)
    distances = [math.hypot(*g.centre_m) for g in grasps]
    assert distances == sorted(distances)
    first = grasps[0]
    closing = np.array([math.cos(first.yaw_offset_rad), math.sin(first.yaw_offset_rad)])
    along = np.array([-closing[1], closing[0]])
    centre = np.array(first.centre_m)
    # Every point of the outline in the pads' band lies between the pads.
    band = [p for p in ell.outline_m if abs(float((p - centre) @ along)) <= ROBOTIQ_2F85.pad_width_m / 2]
    across = [float((p - centre) @ closing) for p in band]
    assert max(across) <= first.width_m / 2 + 1e-6 and min(across) >= -first.width_m / 2 - 1e-6


def test_a_part_wider_than_the_stroke_everywhere_has_no_grasp_and_its_type_is_refused() -> None:
    wide = Prism.from_outline(regular(6, 0.05), 0.02)  # 86.6 mm across flats
    assert wide.grasps(ROBOTIQ_2F85) == ()
    with pytest.raises(PlanError, match="object type 'hex': no two edges the 2F-85 can close on"):
        ObjectType("hex", shape=wide)


def test_a_short_edge_at_a_corner_thin_and_tall_parts_are_refused_naming_the_limit() -> None:
    notched = Prism.from_outline([[0, 0], [0.05, 0], [0.05, 0.04], [0.045, 0.045], [0, 0.045]], 0.02)
    assert any("under the 10 mm the camera needs" in p for p in notched.problems(ROBOTIQ_2F85))
    # A short edge where the outline barely turns is no corner: it does not matter.
    bent = Prism.from_outline([[0, 0], [0.05, 0], [0.055, 0.0002], [0.055, 0.04], [0, 0.04]], 0.02)
    assert not any("the camera needs to measure a corner" in p for p in bent.problems(ROBOTIQ_2F85))
    # (It is refused for another reason: a near-rectangle whose half turn the camera cannot tell apart.)
    assert any("turned by 180 deg comes within" in p for p in bent.problems(ROBOTIQ_2F85))
    assert Prism.from_outline(ELL, 0.01).problems(ROBOTIQ_2F85)[0].startswith("10 mm tall, thinner than")
    assert "taller than 100 mm" in Prism.from_outline(ELL, 0.12).problems(ROBOTIQ_2F85)[0]


def test_a_push_meets_the_back_most_edge_and_reaches_from_the_centroid_to_it() -> None:
    ell = Prism.from_outline(ELL, 0.02)
    face = ell.pushed_face(0.0, 0.0)  # along +x: the pads meet the L's left edge, 50 mm long
    assert face.width_m == pytest.approx(0.05)
    assert face.depth_m == pytest.approx(2 * 0.0233333, abs=1e-6)
    low, high = ell.push_contact_m(0.0, 0.0)
    assert (low, high) == pytest.approx((-0.0183333, 0.0316667), abs=1e-6)
    # Turned a quarter, the same push meets the upright's top (20 mm); along the part's y, the bottom (60 mm).
    assert ell.pushed_face(0.0, math.pi / 2).width_m == pytest.approx(0.02)
    assert ell.pushed_face(math.pi / 2, 0.0).width_m == pytest.approx(0.06)
    # A corner leads when the push comes along a diagonal: nothing flat to meet.
    assert Prism.from_outline(regular(4, 0.03), 0.02).pushed_face(0.0, 0.0).width_m == 0.0


def test_a_prism_is_a_part_type_whose_footprint_is_its_outline_on_the_table() -> None:
    ell = ObjectType("ell", shape=Prism.from_outline(ELL, 0.02))
    assert ell.size_m == pytest.approx((2 * 0.0366667, 2 * 0.0316667, 0.02), abs=1e-6)
    corners = footprint_m(ell.shape, 0.5, 0.1, math.pi)
    np.testing.assert_allclose(corners[0], [0.5 + 0.0233333, 0.1 + 0.0183333], atol=1e-6)


def test_pads_on_the_push_line_meet_the_outline_where_it_lies_within_their_span_not_a_corner_beside_them() -> None:
    triangle = Prism.from_outline([[0, 0], [0.06, 0], [0.015, 0.045]], 0.02)
    # Pushed along +x, the back-most point is the corner 25 mm behind the centroid and 15 mm to its
    # side; pads 16 mm wide on the push's line meet the slanted edge instead, 22.67 mm behind it.
    assert triangle.pushed_face(0.0, 0.0).depth_m == pytest.approx(0.05)
    assert triangle.back_within_m(0.0, 0.0, 0.008) == pytest.approx(0.025 - 0.007 / 3, abs=1e-9)
    # Wide enough to reach the corner, the pads meet it first.
    assert triangle.back_within_m(0.0, 0.0, 0.02) == pytest.approx(0.025)


# The benchmark's non-convex fragment (benchmarks/plans/irregular_parts.toml), in metres.
FRAGMENT = [[0, 0], [0.045, 0.004], [0.060, 0.030], [0.035, 0.028], [0.030, 0.050], [0.005, 0.040]]


def contacts_mm(prism: Prism, grasp_index: int) -> tuple[np.ndarray, np.ndarray, float]:
    """Where the pads of one grasp touch the outline: the spans along the pads (mm, from the centroid) of the
    two contacts, and the grasp centre's place along them.

    The outline is sampled every 0.05 mm or finer; a contact is what lies within 0.1 mm of the part's
    widest and narrowest under the pads (their 22 mm width about the grasp centre).
    """
    grasp = prism.grasps(ROBOTIQ_2F85)[grasp_index]
    closing = np.array([math.cos(grasp.yaw_offset_rad), math.sin(grasp.yaw_offset_rad)])
    along = np.array([-closing[1], closing[0]])
    centre_t_m = float(np.array(grasp.centre_m) @ along)
    points = prism.outline_m
    ends = np.roll(points, -1, axis=0)
    steps = np.linspace(0.0, 1.0, 1000, endpoint=False)[:, None, None]
    samples = (points + steps * (ends - points)).reshape(-1, 2)
    across_m, along_m = samples @ closing, samples @ along
    under = np.abs(along_m - centre_t_m) <= ROBOTIQ_2F85.pad_width_m / 2
    top, bottom = float(np.max(across_m[under])), float(np.min(across_m[under]))
    upper = along_m[under & (across_m >= top - 1e-4)] * 1000
    lower = along_m[under & (across_m <= bottom + 1e-4)] * 1000
    return np.array([upper.min(), upper.max()]), np.array([lower.min(), lower.max()]), centre_t_m * 1000


def is_corner(span_mm: np.ndarray) -> bool:
    return float(span_mm[1] - span_mm[0]) < 1.0


def test_the_fragment_is_held_across_an_edge_and_the_corner_facing_it_on_a_line_near_its_centroid() -> None:
    fragment = Prism.from_outline(FRAGMENT, 0.02)
    upper, lower, centre_mm = contacts_mm(fragment, 0)
    edge, corner = (lower, upper) if is_corner(upper) else (upper, lower)
    # An antipodal pair: one pad flat on an edge, the other on one corner lying well inside that edge's
    # contact along the pads, so the squeeze itself has no lever to turn the part.
    assert is_corner(corner) and not is_corner(edge)
    assert edge[0] + 2 <= corner[0] <= edge[1] - 2
    # The closing axis is that edge's normal: the edge written (45, 4) -> (60, 30), at -30 deg.
    assert math.degrees(fragment.grasps(ROBOTIQ_2F85)[0].yaw_offset_rad) == pytest.approx(-30.0, abs=0.1)
    # The contact line (through the corner, along the closing axis) passes 6.2 mm from the centroid,
    # the nearest of any grasp the fragment has.
    assert abs(float(np.mean(corner))) == pytest.approx(6.2, abs=0.3) and abs(centre_mm) == pytest.approx(6.2, abs=0.3)
    levers_mm = [abs(contacts_mm(fragment, k)[2]) for k in range(len(fragment.grasps(ROBOTIQ_2F85)))]
    assert len(levers_mm) >= 3 and min(levers_mm) == pytest.approx(levers_mm[0])


def test_the_fragment_has_no_two_edges_flat_on_both_pads_so_no_grasp_choice_avoids_a_corner() -> None:
    fragment = Prism.from_outline(FRAGMENT, 0.02)
    for k in range(len(fragment.grasps(ROBOTIQ_2F85))):
        upper, lower, _ = contacts_mm(fragment, k)
        assert sorted((is_corner(upper), is_corner(lower))) == [False, True], k


def test_the_fragment_is_two_convex_pieces_and_no_corner_a_pad_presses_is_split_between_them() -> None:
    """The first ear clipping made three, with slivers of 44 and 53 deg at the corners the pads press."""
    fragment = Prism.from_outline(FRAGMENT, 0.02)
    pieces = fragment.convex_pieces()
    assert len(pieces) == 2
    assert sum(abs(signed_area_m2(piece)) for piece in pieces) == pytest.approx(abs(signed_area_m2(fragment.outline_m)))
    outline = fragment.outline_m
    for corner in (outline[1], outline[5]):  # (45, 4) under one pad, (5, 40) under the other
        holding = [piece for piece in pieces if np.min(np.linalg.norm(piece - corner, axis=1)) < 1e-9]
        assert len(holding) == 1


def test_a_trapezoid_is_held_across_its_two_parallel_edges_on_a_line_through_its_centroid() -> None:
    trapezoid = Prism.from_outline([[0, 0], [0.07, 0], [0.05, 0.035], [0.015, 0.035]], 0.02)
    upper, lower, centre_mm = contacts_mm(trapezoid, 0)
    assert trapezoid.grasps(ROBOTIQ_2F85)[0].width_m == pytest.approx(0.035)
    assert not is_corner(upper) and not is_corner(lower), "both pads flat on an edge"
    assert abs(centre_mm) < 0.5, "the pads' centre lies on the line through the centroid"
