"""The layout with irregular parts: outlines instead of bounding boxes, the pads at a prism's own grasp."""

from __future__ import annotations

import math

import pytest

from bt_arrange.objects import ObjectType
from bt_arrange.plan.layout import (
    Outline,
    Pads,
    Part,
    Rect,
    free_push_directions,
    gap_m,
    overlap,
    plan_layout,
    release_pads,
)
from bt_arrange.plan.targets import parts_of
from bt_arrange.shapes import ROBOTIQ_2F85, Prism
from bt_arrange.shapes.fracture import fracture, polygon_gap_m
from bt_arrange.trees import Target

PADS = Pads()
ELL = Prism.from_outline([[0, 0], [0.06, 0], [0.06, 0.02], [0.02, 0.02], [0.02, 0.05], [0, 0.05]], 0.02)


def ell_at(x_m: float, y_m: float, yaw_rad: float = 0.0) -> Outline:
    part = Part("ell", x_m, y_m, yaw_rad, ELL, ROBOTIQ_2F85)
    assert part.by_outline
    return part.footprint


def test_an_outline_is_tested_by_its_own_pieces_not_its_bounding_box() -> None:
    ell = ell_at(0.5, 0.0)
    points = ELL.outline_m
    # A 10 mm square in the L's notch, 5 mm from both inner edges: its box would overlap, the L does not.
    corner = points[3] + [0.5, 0.0]  # the inner corner (20, 20) mm of the outline as written
    square = Rect(float(corner[0]) + 0.010, float(corner[1]) + 0.010, 0.0, 0.005, 0.005)
    assert not overlap(ell, square)
    assert gap_m(ell, square) == pytest.approx(0.005, abs=1e-9)
    box = Rect(0.5, 0.0, 0.0, *(e / 2 for e in ELL.extent_m))
    assert overlap(box, square)
    # Moved into the L's arm it overlaps; with a clearance beyond the gap it overlaps too.
    assert overlap(ell, Rect(float(corner[0]) + 0.010, float(corner[1]) - 0.004, 0.0, 0.005, 0.005))
    assert overlap(ell, square, clearance_m=0.0051) and not overlap(ell, square, clearance_m=0.0049)


def test_fresco_pieces_have_the_fractures_gap_between_their_footprints() -> None:
    pieces = fracture((0.16, 0.12, 0.02), 6, 0.002, 0, (0.5, 0.0, 0.3))
    targets = [
        Target(
            "red", p.x_m, p.y_m, p.yaw_rad, name=f"tile {p.index}", object_type=ObjectType(f"t{p.index}", shape=p.prism)
        )
        for p in pieces
    ]
    parts = parts_of(targets)
    for i, a in enumerate(parts):
        for j, b in enumerate(parts[i + 1 :], start=i + 1):
            expected = polygon_gap_m(pieces[i].slab_outline_m, pieces[j].slab_outline_m)
            assert gap_m(a.footprint, b.footprint) == pytest.approx(expected, abs=1e-7)
    assert min(gap_m(a.footprint, b.footprint) for i, a in enumerate(parts) for b in parts[i + 1 :]) == pytest.approx(
        0.002, abs=1e-7
    )


def _fresco_parts(count: int, seed: int) -> list[Part]:
    pieces = fracture((0.16, 0.12, 0.02), count, 0.002, seed, (0.5, 0.0, 0.0))
    return parts_of(
        [
            Target(
                "red", p.x_m, p.y_m, p.yaw_rad, name=f"t{p.index}", object_type=ObjectType(f"t{p.index}", shape=p.prism)
            )
            for p in pieces
        ]
    )


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_fresco_is_built_piece_by_piece_each_released_where_its_pads_miss_the_pieces_placed(seed: int) -> None:
    parts = _fresco_parts(6, seed)
    steps = plan_layout(parts, PADS)
    placed: list[tuple[str, object]] = []
    for step in steps:
        part = step.part
        # The pads stand at the part's grasp (its centre off the centroid), released where they fit.
        at = part.footprint.moved(*step.release.staging_m)
        for pad in release_pads(part, at, step.release.axis, PADS):
            assert not any(overlap(pad, footprint, PADS.pad_clearance_m) for _, footprint in placed)
        assert step.release.offset_m == pytest.approx(
            tuple(s + c for s, c in zip(step.release.staging_m, part.grasp_centre(step.release.axis), strict=True))
        )
        if step.release.staged:
            # It is pushed home from sides that are free once it is down.
            assert step.push_towards
            assert set(step.push_towards) <= set(free_push_directions(part, placed, PADS))
        placed.append((part.name, part.footprint))
    # Pieces 2 mm from one placed before leave no room for a pad at the target: staged, pushed home.
    assert sum(step.release.staged for step in steps) >= 2


def test_a_prism_grasped_off_its_centroid_has_its_pads_about_the_grasp() -> None:
    (part,) = _fresco_parts(3, 0)[:1]
    assert part.by_outline and part.grasp_axes == ("x",)
    width, centre = 2 * part.grasp_half("x"), part.grasp_centre("x")
    left, right = release_pads(part, part.footprint, "x", PADS)
    middle = ((left.x_m + right.x_m) / 2, (left.y_m + right.y_m) / 2)
    c, s = math.cos(part.yaw_rad), math.sin(part.yaw_rad)
    assert middle == pytest.approx((part.x_m + c * centre[0] - s * centre[1], part.y_m + s * centre[0] + c * centre[1]))
    spread = math.hypot(left.x_m - right.x_m, left.y_m - right.y_m)
    assert spread == pytest.approx(width + PADS.release_gap_m + PADS.finger_depth_m, abs=1e-9)
