"""The plan check by geometry (bt_arrange.plan.layout): hand-made plans, the order and approach, the push sides."""

from __future__ import annotations

import math

import pytest

from bt_arrange.errors import PlanError
from bt_arrange.plan.layout import (
    Pads,
    Part,
    Rect,
    choose_release,
    free_push_directions,
    gap_m,
    overlap,
    plan_layout,
    release_pads,
    start_clearance_m,
)
from bt_arrange.shapes import Prism

EDGE = 0.05
PADS = Pads()


def cube(name: str, x_mm: float, y_mm: float, yaw_deg: float = 0.0) -> Part:
    return Part(name, 0.45 + x_mm / 1000, y_mm / 1000, math.radians(yaw_deg), Prism.box(EDGE, EDGE, EDGE))


def grid(columns: int, rows: int, gap_mm: float) -> list[Part]:
    pitch = 50 + gap_mm
    return [cube(f"p{i}{j}", i * pitch, j * pitch) for j in range(rows) for i in range(columns)]


def placed(*parts: Part) -> list[tuple[str, Rect]]:
    return [(p.name, p.footprint) for p in parts]


# -- rectangles ------------------------------------------------------------------------------


def test_gaps_and_overlaps_of_turned_rectangles() -> None:
    a = Rect(0.0, 0.0, 0.0, 0.025, 0.025)
    assert gap_m(a, Rect(0.052, 0.0, 0.0, 0.025, 0.025)) == pytest.approx(0.002)
    assert not overlap(a, Rect(0.052, 0.0, 0.0, 0.025, 0.025))
    assert overlap(a, Rect(0.052, 0.0, 0.0, 0.025, 0.025), clearance_m=0.0021)
    # A square turned 45 degrees reaches 35.4 mm from its centre along x.
    turned = Rect(0.062, 0.0, math.pi / 4, 0.025, 0.025)
    assert gap_m(a, turned) == pytest.approx(0.062 - 0.025 - 0.025 * math.sqrt(2), abs=1e-9)
    assert overlap(a, Rect(0.05, 0.0, math.pi / 4, 0.025, 0.025))


# -- the plan check ------------------------------------------------------------------------


@pytest.mark.parametrize(
    "parts",
    [grid(2, 2, 2.0), grid(5, 1, 2.0), grid(3, 3, 3.0), grid(2, 2, 3.0)],
    ids=["2x2 block, 2 mm", "row of five, 2 mm", "3x3 grid, 3 mm", "2x2 block, 3 mm"],
)
def test_dense_plans_that_can_be_built_are_accepted_with_a_step_per_part(parts: list[Part]) -> None:
    steps = plan_layout(parts, PADS)
    assert sorted(s.part.name for s in steps) == sorted(p.name for p in parts)
    on_table: list[Part] = []
    for step in steps:
        # Whatever the step chose, its pads keep clear of what is on the table then.
        part = step.part
        at = part.footprint.moved(*step.release.offset_m)
        for pad in release_pads(part, at, step.release.axis, PADS):
            assert all(not overlap(pad, p.footprint, PADS.pad_clearance_m) for p in on_table)
        on_table.append(part)


def test_targets_closer_than_2_mm_are_refused_naming_both() -> None:
    with pytest.raises(PlanError, match=r"^targets a and b are 1.5 mm apart, under the 2 mm"):
        plan_layout([cube("a", 0, 0), cube("b", 51.5, 0)], PADS)
    with pytest.raises(PlanError, match=r"^targets a and b overlap"):
        plan_layout([cube("a", 0, 0), cube("b", 30, 10)], PADS)


def test_an_order_that_boxes_a_part_in_is_refused_naming_the_parts_in_the_way() -> None:
    parts = grid(3, 3, 3.0)  # p11 is the centre
    last = ["p00", "p10", "p20", "p01", "p21", "p02", "p12", "p22", "p11"]
    with pytest.raises(
        PlanError, match=r"\(in this order\): p11 has no room for the pads, p01, p10, p12 and p21 stand in the way"
    ):
        plan_layout(parts, PADS, order=last)
    # Without an order the search finds one (here the plan's own, row by row).
    assert [s.part.name for s in plan_layout(parts, PADS)] == [p.name for p in parts]


def test_a_plan_no_order_can_build_names_the_part_and_who_blocks_it() -> None:
    # Pads that need 2.5 mm to lower a part beside another and may not stage: two parts 2 mm apart
    # can be placed in neither order.
    strict = Pads(place_clearance_m=0.0025, staging_steps_m=())
    with pytest.raises(PlanError, match=r"\(in any order\): b has no room for the pads, a stands in the way"):
        plan_layout([cube("a", 0, 0), cube("b", 52, 0)], strict)


def test_a_start_keeps_clear_of_the_pads_working_at_another_target() -> None:
    # Picking (85 mm open plus a finger, 11 mm half a pad wide) or pushing (32 mm behind a face).
    assert start_clearance_m(EDGE * math.sqrt(2) / 2, PADS) == pytest.approx(0.0354 + 0.032 + 0.002, abs=2e-4)


# -- the order and the approach --------------------------------------------------------------


def test_a_part_beside_one_neighbour_is_released_at_its_target_with_the_pads_on_its_free_faces() -> None:
    first, second = cube("a", 0, 0), cube("b", 52, 0)  # b's -x face is 2 mm from a
    release, in_way = choose_release(second, placed(first), PADS)
    assert release is not None and in_way == []
    assert release.axis == "y" and not release.staged  # the pads close along y, beside its free y faces
    assert release.opening_m == pytest.approx(EDGE + 2 * PADS.release_gap_m)


def test_a_part_boxed_in_on_two_sides_is_staged_away_from_them_and_pushed_home_from_a_free_side() -> None:
    a, b, c, d = grid(2, 2, 2.0)  # d at +x +y: neighbours c (-x) and b (-y)
    release, _ = choose_release(d, placed(a, b, c), PADS)
    assert release is not None and release.staged
    dx, dy = release.offset_m
    assert dx >= 0 and dy >= 0  # away from the neighbours
    # Its pads fit in the room the offset opens: a pad beside a 2 mm gap never.
    moved = d.footprint.moved(dx, dy)
    for pad in release_pads(d, moved, release.axis, PADS):
        assert all(not overlap(pad, p.footprint, PADS.pad_clearance_m) for p in (a, b, c))


def test_the_free_push_directions_leave_out_the_sides_neighbours_block() -> None:
    middle = cube("m", 52, 0)
    neighbours = placed(cube("l", 0, 0), cube("r", 104, 0))
    # Pads on m's -x side would stand in the 2 mm gap to l (a push towards +x), on its +x side in the gap to r.
    assert free_push_directions(middle, neighbours, PADS) == ("+y", "-y")
    assert free_push_directions(middle, [], PADS) == ("+x", "-x", "+y", "-y")
