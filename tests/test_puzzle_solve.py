"""The puzzle solver alone: outlines of the simulator's break, turned, shuffled and noised, put back.

The outlines come from ``bt_arrange_sim.puzzles.measured_break`` (the scene's own break, each
vertex moved 0.05 mm in a random direction): the solve sees only them, the truths judge it.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_arrange.puzzle import (
    MeasuredPiece,
    PuzzleAmbiguous,
    PuzzleError,
    PuzzleSpec,
    PuzzleUnsolved,
    solve,
)
from bt_arrange.shapes.polygon import centroid_m, signed_area_m2
from bt_arrange_sim.puzzles import MeasuredBreak, measured_break

#: The benchmark's slabs (``benchmarks/puzzle.py``): a size per piece count.
SIZES_M = {4: (0.14, 0.10, 0.02), 6: (0.16, 0.12, 0.02), 12: (0.18, 0.14, 0.02)}
#: Vertex noise of the outlines: about the camera's (docs/puzzle.md, 95th percentile 0.086 mm in the cell).
NOISE_M = 0.00005


def spec_of(pieces: int, gap_m: float = 0.002) -> PuzzleSpec:
    return PuzzleSpec("slab", SIZES_M[pieces], pieces, gap_m, "red", 0.5, 0.0, 0.0)


def pieces_of(broken: MeasuredBreak) -> list[MeasuredPiece]:
    return [MeasuredPiece(label, outline) for label, outline in zip(broken.labels, broken.outlines, strict=True)]


@pytest.mark.parametrize(("pieces", "seed"), [(4, 0), (6, 0), (6, 1)])
def test_the_solver_puts_every_piece_of_a_break_back_where_it_was_cut(pieces: int, seed: int) -> None:
    spec = spec_of(pieces)
    broken = measured_break(spec, seed, NOISE_M)
    assembly = solve(pieces_of(broken), spec.size_m, spec.gap_m)
    assert [p.label for p in assembly.placements] == list(broken.labels)
    place_m, turn_rad = broken.errors(assembly.placements, spec.symmetry_turns_rad)
    assert place_m < 0.0002, place_m
    assert turn_rad < math.radians(0.3), math.degrees(turn_rad)
    assert 0 < assembly.residual_m < 0.0001
    assert assembly.solve_s > 0


def test_the_solved_placements_move_each_measured_outline_onto_its_place_in_the_slab() -> None:
    spec = spec_of(4)
    broken = measured_break(spec, 2, NOISE_M)
    assembly = solve(pieces_of(broken), spec.size_m, spec.gap_m)
    # The canonical copy: the smallest label's piece at the smallest x (of the slab's two half turns).
    first = min(range(4), key=lambda k: int(broken.labels[k].split()[-1]))
    centre_x = assembly.placements[first].centroid_m[0]
    for symmetry in spec.symmetry_turns_rad:
        c = math.cos(symmetry)
        assert centre_x <= c * centroid_m(broken.truths[first])[0] + 0.0002
    for placement, outline in zip(assembly.placements, broken.outlines, strict=True):
        moved = placement.to_slab(outline)
        assert np.allclose(centroid_m(moved), placement.centroid_m, atol=1e-9)
        assert np.all(np.abs(moved) <= np.array(spec.size_m[:2]) / 2 + 0.0002)


@pytest.mark.parametrize(
    ("pieces", "seed"),
    [
        (6, 3),  # a corner 0.79 mm short of the long side, between two neighbours on it
        (12, 27),  # a corner 0.41 mm short of a short side, at a corner of the slab
    ],
)
def test_a_piece_touching_the_border_only_at_a_corner_is_placed_too(pieces: int, seed: int) -> None:
    # Regression: the piece's border edge, shorter than the gap, vanished when the gap shrank it.
    # The search stopped at 4 and 10 pieces.
    spec = spec_of(pieces)
    broken = measured_break(spec, seed, NOISE_M)
    half = np.array(spec.size_m[:2]) / 2
    # how far short of each side each piece comes (0: a border edge on it): one comes close, not onto it
    short = np.concatenate(
        [half - truth.max(axis=0) for truth in broken.truths] + [half + truth.min(axis=0) for truth in broken.truths]
    )
    assert np.any((short > 0.0002) & (short < 0.002)), short  # the case is still there
    assembly = solve(pieces_of(broken), spec.size_m, spec.gap_m)
    place_m, turn_rad = broken.errors(assembly.placements, spec.symmetry_turns_rad)
    assert place_m < 0.0002, place_m
    assert turn_rad < math.radians(0.3), math.degrees(turn_rad)


def test_pieces_nearly_meeting_at_a_point_are_placed_though_a_short_fracture_between_them_vanished() -> None:
    # Regression: seed 23's 12-piece break at 2 mm has five pieces meeting within 3 mm of a point; the
    # cell edges facing across it differ by 1.05 mm, and the search stopped at 10 pieces.
    spec = spec_of(12)
    broken = measured_break(spec, 23, NOISE_M)
    assembly = solve(pieces_of(broken), spec.size_m, spec.gap_m)
    place_m, turn_rad = broken.errors(assembly.placements, spec.symmetry_turns_rad)
    assert place_m < 0.0002, place_m
    assert turn_rad < math.radians(0.3), math.degrees(turn_rad)


def strips(count: int, length_m: float, width_m: float, gap_m: float) -> list[MeasuredPiece]:
    """The slab cut across its length into ``count`` identical rectangles, each turned and moved apart."""
    rng = np.random.default_rng(5)
    each = (length_m - (count - 1) * gap_m) / count
    out = []
    for k in range(count):
        x0 = -length_m / 2 + k * (each + gap_m)
        rectangle = np.array(
            [[x0, -width_m / 2], [x0 + each, -width_m / 2], [x0 + each, width_m / 2], [x0, width_m / 2]]
        )
        turn = float(rng.uniform(-math.pi, math.pi))
        c, s = math.cos(turn), math.sin(turn)
        out.append(MeasuredPiece(f"strip {k + 1}", rectangle @ np.array([[c, s], [-s, c]]) + [0.2 * k, 0.1]))
    return out


def test_identical_pieces_are_ambiguous_and_the_failure_names_the_pieces_that_could_swap() -> None:
    with pytest.raises(PuzzleAmbiguous) as caught:
        solve(strips(3, 0.16, 0.12, 0.002), (0.16, 0.12), 0.002)
    message = str(caught.value)
    assert "\n" not in message
    assert "fit equally well" in message
    named = {name for role, name in caught.value.parts if role == "piece"}
    assert len(named) >= 2 and named <= {"strip 1", "strip 2", "strip 3"}
    for name in named:
        assert name in message


def test_two_identical_halves_are_one_assembly_under_the_slab_s_half_turn() -> None:
    # Swapped, then the whole turned half a turn, each rectangle lies where the other did, turned half
    # a turn itself: the same place, since a rectangle looks the same so turned. Not an ambiguity.
    assembly = solve(strips(2, 0.16, 0.12, 0.002), (0.16, 0.12), 0.002)
    first, second = assembly.placements
    assert first.centroid_m[0] < 0 < second.centroid_m[0]  # the smallest label at the smallest x
    assert math.isclose(first.centroid_m[0], -0.0405, abs_tol=1e-4)


def test_a_missing_piece_is_unsolved_in_one_line() -> None:
    spec = spec_of(6)
    pieces = pieces_of(measured_break(spec, 0, NOISE_M))
    with pytest.raises(PuzzleUnsolved) as caught:
        solve(pieces[:5], spec.size_m, spec.gap_m)
    message = str(caught.value)
    assert "\n" not in message and "missing" in message


def test_a_foreign_piece_added_or_in_place_of_one_is_unsolved_in_one_line() -> None:
    spec = spec_of(6)
    own = pieces_of(measured_break(spec, 0, NOISE_M))
    foreign_break = measured_break(spec, 1, NOISE_M)
    foreign = MeasuredPiece("stranger", foreign_break.outlines[0])
    with pytest.raises(PuzzleUnsolved) as added:
        solve([*own, foreign], spec.size_m, spec.gap_m)
    assert "\n" not in str(added.value) and "too many" in str(added.value)
    # In place of the own piece nearest its area, so that the area check cannot tell.
    areas = [abs(signed_area_m2(p.outline_m)) for p in own]
    foreign_area = abs(signed_area_m2(foreign.outline_m))
    swapped = int(np.argmin([abs(a - foreign_area) for a in areas]))
    with pytest.raises(PuzzleUnsolved) as replaced:
        solve([*own[:swapped], foreign, *own[swapped + 1 :]], spec.size_m, spec.gap_m)
    assert "\n" not in str(replaced.value)


def test_fewer_than_two_pieces_or_a_self_crossing_outline_is_a_puzzle_error_in_one_line() -> None:
    square = np.array([[0.0, 0.0], [0.05, 0.0], [0.05, 0.05], [0.0, 0.05]])
    for pieces in ([], [MeasuredPiece("a", square)]):
        with pytest.raises(PuzzleError, match="2 pieces or more") as caught:
            solve(pieces, (0.1, 0.05), 0.002)
        assert not isinstance(caught.value, (PuzzleUnsolved, PuzzleAmbiguous))
    bow_tie = np.array([[0.0, 0.0], [0.05, 0.05], [0.05, 0.0], [0.0, 0.05]])
    with pytest.raises(PuzzleError, match="piece b: the outline crosses itself") as crossed:
        solve([MeasuredPiece("a", square), MeasuredPiece("b", bow_tie)], (0.1, 0.05), 0.002)
    assert "\n" not in str(crossed.value)
    assert crossed.value.parts == (("piece", "b"),)
    with pytest.raises(PuzzleError, match="share a label"):
        solve([MeasuredPiece("a", square), MeasuredPiece("a", square + 0.06)], (0.1, 0.05), 0.002)


def test_solved_places_closer_than_the_layout_s_gap_are_spread_evenly_until_they_clear_it() -> None:
    from bt_arrange.objects import ObjectType
    from bt_arrange.plan.footprints import gap_m
    from bt_arrange.plan.puzzle_targets import spread_to_gap
    from bt_arrange.plan.targets import Target, parts_of
    from bt_arrange.puzzle import PuzzleSpec
    from bt_arrange.settings import ManipulationSettings

    spec = PuzzleSpec("slab", (0.102, 0.05, 0.02), 2, 0.002, "ochre", 0.5, 0.0, 0.0)
    half = ObjectType("slab half", (0.05, 0.05, 0.02))
    settings = ManipulationSettings()  # twice a 1 mm threshold: 2 mm between two targets
    measured = [Target("ochre", 0.5 - 0.025995, 0.0, name="slab 1", object_type=half),
                Target("ochre", 0.5 + 0.025995, 0.0, name="slab 2", object_type=half)]  # fmt: skip
    first, second = parts_of(measured, settings)
    assert gap_m(first.footprint, second.footprint) < settings.min_target_gap_m  # 1.99 mm: the layout refuses it
    spread = spread_to_gap(measured, spec, settings)
    first, second = parts_of(spread, settings)
    assert settings.min_target_gap_m <= gap_m(first.footprint, second.footprint) < settings.min_target_gap_m + 1e-4
    assert spread[0].x_m + spread[1].x_m == pytest.approx(2 * spec.x_m)  # the whole keeps its place
    apart = [Target(t.colour, t.x_m * 1.01, t.y_m, name=t.name, object_type=half) for t in measured]
    assert spread_to_gap(apart, spec, settings) is apart  # places that clear the gap are returned as they are
