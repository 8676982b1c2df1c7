"""The fracture generator: a slab broken into irregular, graspable pieces with the asked gap between them."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_arrange.errors import PlanError
from bt_arrange.shapes import ROBOTIQ_2F85
from bt_arrange.shapes.fracture import fracture, polygon_gap_m

SLAB_M = (0.16, 0.12, 0.02)


def _neighbour_gaps_m(pieces) -> list[float]:
    """The gap between each pair of pieces that face each other across a fracture (within 5 mm)."""
    gaps = []
    for i, first in enumerate(pieces):
        for second in pieces[i + 1 :]:
            gap = polygon_gap_m(first.slab_outline_m, second.slab_outline_m)
            if gap < 0.005:
                gaps.append(gap)
    return gaps


def test_the_same_seed_gives_the_same_pieces_and_another_seed_other_ones() -> None:
    first = fracture(SLAB_M, 6, 0.002, 3)
    again = fracture(SLAB_M, 6, 0.002, 3)
    other = fracture(SLAB_M, 6, 0.002, 4)
    assert [p.prism for p in first] == [p.prism for p in again]
    assert [(p.x_m, p.y_m, p.yaw_rad) for p in first] == [(p.x_m, p.y_m, p.yaw_rad) for p in again]
    assert [p.prism for p in first] != [p.prism for p in other]


@pytest.mark.parametrize("count", [3, 6, 12])
def test_it_breaks_into_the_pieces_asked_each_a_part_the_gripper_can_take(count: int) -> None:
    slab = (0.24, 0.16, 0.02) if count == 12 else SLAB_M
    pieces = fracture(slab, count, 0.002, 1)
    assert [p.index for p in pieces] == list(range(1, count + 1))
    for piece in pieces:
        assert piece.prism.problems(ROBOTIQ_2F85) == []
        grasp = piece.prism.grasps(ROBOTIQ_2F85)[0]
        # The piece's frame has its preferred grasp closing along x: the layout releases across it.
        assert grasp.axis == "x" and grasp.yaw_offset_rad == pytest.approx(0.0, abs=1e-9)


@pytest.mark.parametrize(("seed", "gap_m"), [(0, 0.002), (5, 0.002), (2, 0.004)])
def test_neighbouring_pieces_are_the_gap_apart_and_the_pieces_fill_the_slab_less_the_gaps(
    seed: int, gap_m: float
) -> None:
    pieces = fracture(SLAB_M, 6, gap_m, seed)
    gaps = _neighbour_gaps_m(pieces)
    # No two pieces nearer than the gap; along a shared fracture exactly the gap, and the pieces
    # hang together (at least a tree of fractures).
    assert min(gaps) == pytest.approx(gap_m, abs=1e-9)
    assert len([g for g in gaps if abs(g - gap_m) < 1e-9]) >= len(pieces) - 1
    area = sum(p.prism.area_m2 for p in pieces)
    slab_area = SLAB_M[0] * SLAB_M[1]
    # Each fracture of length l takes l x gap; fractures are at most a few slab widths long in all.
    assert slab_area - 6 * SLAB_M[1] * gap_m < area < slab_area - SLAB_M[1] * gap_m


def test_the_cuts_are_irregular_and_the_outer_edge_is_the_slabs() -> None:
    pieces = fracture(SLAB_M, 6, 0.002, 0)
    points = np.vstack([p.slab_outline_m for p in pieces])
    # Pieces reach the slab's outer edge (not shrunk there) and nowhere beyond it.
    assert points[:, 0].min() == pytest.approx(-0.08) and points[:, 0].max() == pytest.approx(0.08)
    assert points[:, 1].min() == pytest.approx(-0.06) and points[:, 1].max() == pytest.approx(0.06)
    # Not a grid: fracture edges run at many directions, not only along x and y.
    directions = set()
    for piece in pieces:
        edges = np.roll(piece.slab_outline_m, -1, axis=0) - piece.slab_outline_m
        directions |= {round(math.degrees(math.atan2(e[1], e[0])) % 180) for e in edges}
    assert len(directions - {0, 90, 180}) >= 4


def test_the_whole_is_placed_where_the_fresco_says() -> None:
    here = fracture(SLAB_M, 4, 0.002, 7)
    there = fracture(SLAB_M, 4, 0.002, 7, pose=(0.5, -0.1, math.radians(30)))
    c, s = math.cos(math.radians(30)), math.sin(math.radians(30))
    for a, b in zip(here, there, strict=True):
        assert b.prism == a.prism
        assert (b.x_m, b.y_m) == pytest.approx((0.5 + c * a.x_m - s * a.y_m, -0.1 + s * a.x_m + c * a.y_m))
        assert math.remainder(b.yaw_rad - a.yaw_rad - math.radians(30), 2 * math.pi) == pytest.approx(0.0, abs=1e-9)


def test_a_slab_no_draw_can_break_into_graspable_pieces_is_one_line() -> None:
    with pytest.raises(PlanError, match="no fracture of a 40 x 30 mm slab into 12 pieces") as caught:
        fracture((0.04, 0.03, 0.02), 12, 0.002, 0)
    assert "\n" not in str(caught.value)


def test_every_piece_shows_its_yaw_and_a_near_rectangle_would_not() -> None:
    from bt_arrange.shapes import Prism
    from bt_arrange.shapes.fracture import MIN_YAW_CUE_M, yaw_cue_m

    for piece in fracture(SLAB_M, 6, 0.002, 3):
        assert yaw_cue_m(piece.prism) >= MIN_YAW_CUE_M
    # A 60 x 40 mm rectangle with one corner 1 mm off looks the same turned by half a turn.
    near_rectangle = Prism.from_outline([[0, 0], [0.06, 0], [0.06, 0.04], [0.001, 0.041]], 0.02)
    assert yaw_cue_m(near_rectangle) < 0.5 * MIN_YAW_CUE_M
    fragment = Prism.from_outline(
        [[0, 0], [0.045, 0.004], [0.06, 0.03], [0.035, 0.028], [0.03, 0.05], [0.005, 0.04]], 0.02
    )
    assert yaw_cue_m(fragment) > MIN_YAW_CUE_M


def test_a_measured_piece_whose_two_sides_are_a_hair_from_parallel_is_framed_by_its_grasp() -> None:
    """Closing axes 0.013 deg apart: turned to the first, the second comes first; the frame settles on it."""
    from bt_arrange.shapes import fracture as fracture_module

    # The fake camera's measurement of seed 1's piece 6 (tests/behaviours/test_puzzle.py), centred, in metres.
    outline = np.array(
        [[-0.0263445, -0.0203163], [0.0214288, -0.0203062], [0.0214227, 0.0220072], [-0.0160931, 0.022008]]
    )
    assert fracture_module._judged([outline], 0.02, ROBOTIQ_2F85) is None, "the fracture's own judgement, unsettled"
    framed = fracture_module.in_grasp_frame(outline, 0.02)
    assert framed is not None
    prism, turn = framed
    assert prism.grasps(ROBOTIQ_2F85)[0].axis == "x"
    assert abs(math.sin(turn)) > 0.99  # the closing axis across the sides 42 mm apart, turned a quarter
