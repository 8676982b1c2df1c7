"""A part held along its pads off where the pick meant: the TCP follows it only as far as the pads stay clear."""

from __future__ import annotations

import dataclasses
import math

import pytest

from bt_arrange.plan.layout import Pads, Part, Rect, Release, plan_layout, release_pads
from bt_arrange.plan.release_room import Settled, release_room
from bt_arrange.shapes import ROBOTIQ_2F85, Prism

PADS = Pads()
ELL = Prism.from_outline([[0, 0], [0.06, 0], [0.06, 0.02], [0.02, 0.02], [0.02, 0.05], [0, 0.05]], 0.02)
PART = Part("ell", 0.5, 0.0, 0.0, ELL, ROBOTIQ_2F85)
ACROSS_X = Release("x", 0.06)


def beside_a_pad(room_mm: float, on_the_other_side: float | None = None) -> list[tuple[str, Rect]]:
    """A neighbour ``room_mm`` beyond the pads' clearance along +y from a pad; another one along -y from the part."""
    pad = release_pads(PART, PART.footprint, "x", PADS)[0]
    edge_m = pad.y_m + pad.half_y_m + PADS.pad_clearance_m + room_mm / 1000
    placed = [("beside", Rect(pad.x_m, edge_m + 0.01, 0.0, 0.01, 0.01))]
    if on_the_other_side is not None:
        low_m = min(y for piece in PART.footprint.world_pieces() for _, y in piece)
        gap_m = PADS.place_clearance_m + on_the_other_side / 1000
        placed.append(("below", Rect(0.5 + 0.03, low_m - gap_m - 0.01, 0.0, 0.04, 0.01)))
    return placed


def test_a_slide_that_brings_a_pad_onto_a_neighbour_is_cut_short_and_the_part_lands_off_by_the_rest() -> None:
    room = release_room(PART, ACROSS_X, beside_a_pad(3.0), PADS)
    assert room is not None and room.along_pads() == (0.0, 1.0)
    assert room.pads_meet(0.0) == [] and room.pads_meet(0.005) == ["beside"]
    settled = room.settle(0.005)
    assert settled.kept_off == ("beside",)
    # As far as the pads stay clear (3 mm of room), to the slide step; the part lands off by the rest.
    assert 0.0025 <= settled.tcp_slide_m <= 0.003
    assert settled.part_off_m == pytest.approx(settled.tcp_slide_m - 0.005)
    assert room.pads_meet(settled.tcp_slide_m) == [] and room.part_meets(settled.part_off_m) == []


def test_a_slide_the_pads_have_room_for_or_away_from_the_neighbour_is_followed_whole() -> None:
    room = release_room(PART, ACROSS_X, beside_a_pad(3.0), PADS)
    assert room is not None
    assert room.settle(0.002) == Settled(0.002, 0.0)
    assert room.settle(-0.007) == Settled(-0.007, 0.0)


def test_without_room_for_the_part_either_the_slide_is_followed_whole_as_before() -> None:
    # The part cannot land 2 mm or more towards -y: another part stands 1 mm beyond its clearance there.
    room = release_room(PART, ACROSS_X, beside_a_pad(0.5, on_the_other_side=1.0), PADS)
    assert room is not None and room.part_meets(-0.002) == ["below"]
    assert room.settle(0.005) == Settled(0.005, 0.0)


def test_the_along_pads_direction_turns_with_the_target() -> None:
    room = release_room(PART, Release("y", 0.06), beside_a_pad(3.0), PADS)
    assert room is not None and room.along_pads() == (1.0, 0.0)
    ux, uy = room.along_pads_world(math.pi / 2)
    assert (ux, uy) == pytest.approx((0.0, 1.0))


def test_the_layout_gives_each_release_among_neighbours_its_room_and_none_to_the_first() -> None:
    square = Prism.from_outline([[0, 0], [0.04, 0], [0.04, 0.04], [0.0, 0.03]], 0.02)
    parts = [Part(f"p{i}", 0.5 + 0.055 * i, 0.0, 0.0, square, ROBOTIQ_2F85) for i in range(3)]
    steps = plan_layout(parts, PADS)
    assert steps[0].release.room is None
    for step in steps[1:]:
        room = step.release.room
        assert room is not None and room.part is step.part and room.release == step.release
        assert {name for name, _ in room.placed} == {s.part.name for s in steps[: steps.index(step)]}
    assert release_room(PART, ACROSS_X, [], PADS) is None


def test_place_cuts_the_held_correction_s_slide_towards_a_neighbour_and_says_so(bt_blackboard) -> None:
    from bt_arrange.behaviours import Place
    from bt_arrange.geometry import PlanarPose
    from bt_arrange.objects import ObjectType
    from bt_arrange.testing.scene import make_context

    context = make_context(gripper_width_m=0.03, object_width_m=0.03)
    bt_blackboard.set("/ell/target", PlanarPose(0.5, 0.0, 0.0))
    release = dataclasses.replace(ACROSS_X, room=release_room(PART, ACROSS_X, beside_a_pad(3.0), PADS))
    place = Place("place ell", "ell", ObjectType("ell", shape=ELL), release=release, held=True)
    place.setup(context=context)
    cut = []
    for slide_m in (0.005, -0.005):  # in the TCP's frame: one of the two slides the pads towards +y
        bt_blackboard.set("/ell/held_correction", PlanarPose(0.0, slide_m, 0.0))
        place.stages(context)
        cut.append(place.settled)
    kept = [settled for settled in cut if settled is not None]
    assert len(kept) == 1 and kept[0].kept_off == ("beside",)
    place.settled = kept[0]
    assert "to keep off beside" in place.success_message()
