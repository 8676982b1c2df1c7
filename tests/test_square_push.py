"""Square pushes of irregular parts: the edge a push meets squarely through the centroid, and which push to make."""

from __future__ import annotations

import math

import pytest

from bt_arrange.behaviours.push import SQUARING_PRESS_MM, Blocked, Push
from bt_arrange.shapes import ROBOTIQ_2F85, Prism
from bt_arrange.shapes.prism import push_heading_rad, push_name

SQUARE = Prism.from_outline([[0, 0], [0.05, 0], [0.05, 0.05], [0, 0.05]], 0.02)
#: A right triangle: legs along x and y, the hypotenuse facing up and to the right.
TRIANGLE = Prism.from_outline([[0, 0], [0.06, 0], [0, 0.06]], 0.02)
ELL = Prism.from_outline([[0, 0], [0.06, 0], [0.06, 0.02], [0.02, 0.02], [0.02, 0.05], [0, 0.05]], 0.02)


def headings_deg(prism: Prism) -> set[float]:
    return {round(math.degrees(p.heading_rad), 1) for p in prism.named_pushes(ROBOTIQ_2F85).values()}


def test_a_square_is_pushed_squarely_on_each_of_its_four_sides() -> None:
    pushes = SQUARE.named_pushes(ROBOTIQ_2F85)
    assert headings_deg(SQUARE) == {0.0, 90.0, -90.0, 180.0}
    for push in pushes.values():
        assert push.back_m == pytest.approx(0.025)
        assert push.edge_m == pytest.approx(0.05)


def test_a_triangle_is_pushed_on_its_legs_and_hypotenuse_each_along_its_normal() -> None:
    # Its centroid (20, 20) mm projects onto every side well inside it: three square pushes.
    assert headings_deg(TRIANGLE) == {90.0, 0.0, -135.0}
    hypotenuse = next(
        p for p in TRIANGLE.named_pushes(ROBOTIQ_2F85).values() if round(math.degrees(p.heading_rad)) == -135
    )
    assert hypotenuse.back_m == pytest.approx(0.02 / math.sqrt(2), abs=1e-9)  # centroid (20, 20) to x + y = 60
    assert hypotenuse.edge_m == pytest.approx(0.06 * math.sqrt(2))


def test_an_edge_the_centroids_line_misses_or_that_lies_behind_another_is_no_square_push() -> None:
    headings = headings_deg(ELL)
    # The L's centroid is at (22, 17) mm: its long sides (bottom, left) and the arm's end (x = 60)
    # are met squarely; the inner edges are not (the line through the centroid misses them), and
    # the top of the upright arm (y = 50) lies 2 mm beside the centroid's line: no room for the pads.
    assert 90.0 in headings and 0.0 in headings
    for push in ELL.named_pushes(ROBOTIQ_2F85).values():
        contact = ELL.back_within_m(push.heading_rad, 0.0, 0.01)
        assert contact == pytest.approx(push.back_m, abs=0.001)
    assert len(headings) < len(ELL.outline)


def test_names_carry_the_heading() -> None:
    assert push_name(math.radians(-54.0)) == "@-54.0"
    assert push_heading_rad("@-54.0") == pytest.approx(math.radians(-54.0))
    assert push_heading_rad("+x") is None


def test_the_push_that_closes_most_of_the_offset_is_made_by_its_projection() -> None:
    pushes = TRIANGLE.named_pushes(ROBOTIQ_2F85)
    names = {round(math.degrees(p.heading_rad)): n for n, p in pushes.items()}
    # Offset (target minus pose) of 3 mm along +x: the push along +x (onto the leg at x = 0).
    name, distance = Push.choose_square_push((3.0, 0.5), pushes, tuple(pushes), 0.2, False)
    assert name == names[0] and distance == pytest.approx(3.0)
    # Towards -x and -y together: the hypotenuse's push (-135 deg) closes most of it.
    name, distance = Push.choose_square_push((-2.0, -2.0), pushes, tuple(pushes), 0.2, False)
    assert name == names[-135] and distance == pytest.approx(2 * math.sqrt(2))
    # Blocked there, the best free one that still helps: none helps towards -x, -y but...
    free = (names[0], names[90])
    assert Push.choose_square_push((-2.0, -2.0), pushes, free, 0.2, False) == Blocked(
        names[-135], pytest.approx(2 * math.sqrt(2))
    )
    # ... towards -x a little and +y more, the +y push helps though the best is blocked.
    name, distance = Push.choose_square_push((-0.5, 2.0), pushes, free, 0.2, False)
    assert name == names[90] and distance == pytest.approx(2.0)


def test_within_reach_but_turned_it_is_squared_where_the_pads_stand_widest() -> None:
    pushes = TRIANGLE.named_pushes(ROBOTIQ_2F85)
    names = {round(math.degrees(p.heading_rad)): n for n, p in pushes.items()}
    assert Push.choose_square_push((0.05, 0.05), pushes, tuple(pushes), 0.2, False) is None
    name, distance = Push.choose_square_push((0.05, 0.05), pushes, tuple(pushes), 0.2, True)
    assert name == names[-135] and distance == SQUARING_PRESS_MM
    name, _ = Push.choose_square_push((0.05, 0.05), pushes, (names[0], names[90]), 0.2, True)
    assert name in (names[0], names[90])


def test_among_neighbours_two_free_pushes_close_an_offset_between_them_by_their_own_shares() -> None:
    # With +x and the hypotenuse's push (-135 deg) free and +y blocked, an offset of
    # (-0.25, -1) mm is 0.75 mm along +x plus 1.41 mm along -135 deg. Pushed by its whole projection
    # (0.88 mm along -135 deg), the part would be left (0.375, -0.375) mm off: a -y push, blocked, then.
    pushes = TRIANGLE.named_pushes(ROBOTIQ_2F85)
    names = {round(math.degrees(p.heading_rad)): n for n, p in pushes.items()}
    free = (names[0], names[-135])
    name, distance = Push.choose_square_push((-0.25, -1.0), pushes, free, 0.2, False)
    assert name == names[-135] and distance == pytest.approx(math.sqrt(2))
    name, distance = Push.choose_square_push((0.75, 0.0), pushes, free, 0.2, False)  # what is left
    assert name == names[0] and distance == pytest.approx(0.75)
    # Every push free (a part with no neighbour): the projection rule, as before.
    name, distance = Push.choose_square_push((-0.25, -1.0), pushes, tuple(pushes), 0.2, False)
    assert name == names[-135] and distance == pytest.approx(1.25 / math.sqrt(2))
    # An offset outside the free pushes' cone: the projection rule too.
    name, distance = Push.choose_square_push((-0.5, 2.0), pushes, (names[0], names[90]), 0.2, False)
    assert name == names[90] and distance == pytest.approx(2.0)


def test_far_from_its_target_a_part_among_neighbours_is_pushed_by_the_projection() -> None:
    # A staged part 20 mm from home goes the way its staging chose: the layout checked that push's pads.
    from bt_arrange.behaviours.push import CONE_MAX_OFFSET_MM

    pushes = TRIANGLE.named_pushes(ROBOTIQ_2F85)
    names = {round(math.degrees(p.heading_rad)): n for n, p in pushes.items()}
    free = (names[0], names[-135])
    scale = 2 * CONE_MAX_OFFSET_MM / math.hypot(0.5, 2.0)
    name, distance = Push.choose_square_push((-0.5 * scale, -2.0 * scale), pushes, free, 0.2, False)
    assert name == names[-135] and distance == pytest.approx(2.5 * scale / math.sqrt(2))


def test_among_neighbours_a_long_push_stops_short_of_the_target() -> None:
    # A staged part pushed all the way home landed 0.2 to 0.35 mm beside its place, on
    # a side only a blocked push reaches. It stops APPROACH_RESERVE_MM short, for a push that also moves it across.
    from bt_arrange.behaviours.push import APPROACH_RESERVE_MM, LONG_PUSH_MM, SquareMove

    pushes = TRIANGLE.named_pushes(ROBOTIQ_2F85)
    names = {round(math.degrees(p.heading_rad)): n for n, p in pushes.items()}
    free = (names[0], names[90])
    # Its pads bring it onto the target's line as they go (0.3 mm across, to the left of +x).
    assert Push.plan_square_push((20.0, 0.3), pushes, free, 0.2, False, 0.25) == SquareMove(
        names[0], pytest.approx(20.0 - APPROACH_RESERVE_MM), pytest.approx(0.3)
    )
    assert Push.plan_square_push((LONG_PUSH_MM - 0.1, 0.0), pushes, free, 0.2, False, 0.25) == SquareMove(
        names[0], pytest.approx(LONG_PUSH_MM - 0.1)
    )
    # A part with no neighbour: the whole way, as before.
    assert Push.plan_square_push((20.0, 0.3), pushes, tuple(pushes), 0.2, False, 0.25) == SquareMove(
        names[0], pytest.approx(20.0)
    )
    # A coarse threshold (the reserve under STOP_SHORT_FACTOR of it), or none known: the whole way, onto
    # the line. Left 1 mm short at 0.8 mm, the part would count as within there, short of its place.
    for threshold_mm in (0.8, None):
        assert Push.plan_square_push((20.0, 0.3), pushes, free, 0.2, False, threshold_mm) == SquareMove(
            names[0], pytest.approx(20.0), pytest.approx(0.3)
        )
    # At most LONG_PUSH_ACROSS_RATIO of the push across on the way for a square part (11 mm: 2.75 mm) ...
    from bt_arrange.behaviours.push import LONG_PUSH_MAX_ACROSS_MM
    from bt_arrange.behaviours.square_pushes import LONG_PUSH_ACROSS_RATIO

    distance_mm = 12.0 - APPROACH_RESERVE_MM
    assert Push.plan_square_push((12.0, -4.0), pushes, free, 0.2, False, 0.25) == SquareMove(
        names[0], pytest.approx(distance_mm), pytest.approx(-LONG_PUSH_ACROSS_RATIO * distance_mm)
    )
    assert Push.plan_square_push((12.0, -2.0), pushes, free, 0.2, False, 0.25) == SquareMove(
        names[0], pytest.approx(distance_mm), pytest.approx(-2.0)
    )
    # ... as much for a turned one (it squares on the way), less the swing its squaring predicts ...
    turned_rad = math.radians(2.0)
    move = Push.plan_square_push((12.0, -4.0), pushes, free, 0.2, False, 0.25, turned_rad)
    assert isinstance(move, SquareMove)
    assert move.across_mm == pytest.approx(-LONG_PUSH_ACROSS_RATIO * distance_mm)
    # ... and at least LONG_PUSH_MAX_ACROSS_MM on a short one.
    move = Push.plan_square_push((3.5, -2.0), pushes, free, 0.2, False, None, turned_rad)
    assert isinstance(move, SquareMove) and move.across_mm == pytest.approx(-LONG_PUSH_MAX_ACROSS_MM)


def test_among_neighbours_an_offset_no_two_free_pushes_close_is_closed_by_a_push_that_also_moves_across() -> None:
    # Free: +x and +y. (1, -0.1) mm needs -y, which only the blocked hypotenuse push gives; pushed 1 mm
    # along +x the part is left 0.1 mm off towards +y: "no free push closes it". The pads move 0.1 mm
    # towards -y (right of the heading) while they press 1 mm along +x.
    from bt_arrange.behaviours.push import DIAGONAL_ACROSS_RATIO, SLANT_STEP_RESERVE_MM, SquareMove

    pushes = TRIANGLE.named_pushes(ROBOTIQ_2F85)
    names = {round(math.degrees(p.heading_rad)): n for n, p in pushes.items()}
    free = (names[0], names[90])
    assert Push.choose_square_push((1.0, -0.1), pushes, free, 0.05, False) == (names[0], pytest.approx(1.0))
    assert Push.plan_square_push((1.0, -0.1), pushes, free, 0.05, False, 0.25) == SquareMove(
        names[0], pytest.approx(1.0), pytest.approx(-0.1)
    )
    # Far across (0.3 mm): onto the target's line first, SLANT_STEP_RESERVE_MM short, the rest by the next
    # push; at a threshold that reserve leaves well outside (0.25 mm), not at a coarser one.
    assert Push.plan_square_push((1.0, -0.3), pushes, free, 0.05, False, 0.25) == SquareMove(
        names[0], pytest.approx(1.0 - SLANT_STEP_RESERVE_MM), pytest.approx(-0.3)
    )
    assert Push.plan_square_push((1.0, -0.3), pushes, free, 0.05, False, 0.5) == SquareMove(
        names[0], pytest.approx(1.0), pytest.approx(-0.3)
    )
    # At a coarse threshold: choose_square_push's, nothing across (0.3 mm beside the place is within 0.8 mm).
    assert Push.plan_square_push((1.0, -0.3), pushes, free, 0.05, False, 0.8) == SquareMove(
        names[0], pytest.approx(1.0)
    )
    # Across by at most DIAGONAL_ACROSS_RATIO of the push (friction): the rest is left to the next push.
    assert Push.plan_square_push((0.5, -0.5), pushes, free, 0.05, False, 0.25) == SquareMove(
        names[0], pytest.approx(0.5), pytest.approx(-0.5 * DIAGONAL_ACROSS_RATIO)
    )
    # Between two free pushes too: one push straight there, the squarest, rather than two.
    assert Push.plan_square_push((1.0, 0.1), pushes, free, 0.05, False, 0.25) == SquareMove(
        names[0], pytest.approx(1.0), pytest.approx(0.1)
    )
    # No one push closes it, two free ones take it between them: their shares, as before.
    assert Push.plan_square_push((0.5, 0.5), pushes, free, 0.05, False, 0.25) == SquareMove(
        *Push.choose_square_push((0.5, 0.5), pushes, free, 0.05, False)
    )
    # Every push free: choose_square_push's, nothing across.
    assert Push.plan_square_push((1.0, -0.1), pushes, tuple(pushes), 0.05, False) == SquareMove(
        names[0], pytest.approx(1.0)
    )
    # Nothing along a free push to carry it: blocked, as before.
    assert isinstance(Push.plan_square_push((-1.0, -1.0), pushes, free, 0.05, False, 0.25), Blocked)


def test_among_neighbours_a_part_near_its_place_is_never_pushed_past_it_by_two_nearly_opposite_pushes() -> None:
    # Tight gaps (seed 1's fracture, 0.5 mm gaps): free pushes at -178.7, 56.1 and -1.3 deg. 1 mm
    # from home, their shares sent the piece 1.6 mm along -178.7 deg, past its place into a neighbour.
    from bt_arrange.behaviours.push import SquareMove
    from bt_arrange.shapes.base import SquarePush

    pushes = {f"@{d}": SquarePush(math.radians(d), 0.02, 0.05, i) for i, d in enumerate((-178.7, 56.1, -1.3, -81.1))}
    free = ("@-178.7", "@56.1", "@-1.3")
    name, distance = Push.choose_square_push((-1.0, -0.05), pushes, free, 0.1, False)
    assert (name, distance) == ("@-178.7", pytest.approx(1.60, abs=0.01))
    assert Push.plan_square_push((-1.0, -0.05), pushes, free, 0.1, False, 0.25) == SquareMove(
        "@-178.7", pytest.approx(1.0, abs=0.01)
    )


def test_among_neighbours_a_part_left_between_2_and_3_mm_from_its_place_goes_there_in_one_slanted_push() -> None:
    # Tight gaps (seed 8's fracture, 1 mm gaps): a piece turned 2 deg at its set-down ended its long
    # push 2.2 mm short and 0.75 mm beside its line; pushed by its projection it met a neighbour.
    from bt_arrange.behaviours.push import CONE_MAX_OFFSET_MM, LONG_PUSH_MM, SLANT_STEP_RESERVE_MM, SquareMove

    pushes = TRIANGLE.named_pushes(ROBOTIQ_2F85)
    names = {round(math.degrees(p.heading_rad)): n for n, p in pushes.items()}
    offset = (2.1, -0.75)
    assert CONE_MAX_OFFSET_MM < math.hypot(*offset) < LONG_PUSH_MM
    assert Push.plan_square_push(offset, pushes, (names[0],), 0.05, False, 0.25) == SquareMove(
        names[0], pytest.approx(2.1 - SLANT_STEP_RESERVE_MM), pytest.approx(-0.75)
    )


def test_the_tree_gives_an_irregular_part_among_neighbours_its_threshold_and_nobody_else() -> None:
    # Push stops short only when it knows the correction's threshold: an irregular
    # part among neighbours gets it; a box (Table 1's pushes) and a free part do not.
    from bt_arrange.objects import CUBE, ObjectType
    from bt_arrange.plan.targets import Target
    from bt_arrange.trees.steps import correction

    triangle = ObjectType("triangle", shape=TRIANGLE)
    names = tuple(TRIANGLE.named_pushes(ROBOTIQ_2F85))

    def thresholds(target: Target, towards: tuple[str, ...] | None) -> set[float | None]:
        import dataclasses

        from bt_arrange.plan import ArrangementPlan, PartStep, Tolerance

        step = dataclasses.replace(PartStep.free(target), push_towards=towards)
        tree = correction(step, ArrangementPlan.of([target], Tolerance(0.25, 1.0)))
        return {node.threshold_mm for node in tree.iterate() if isinstance(node, Push)}

    assert thresholds(Target("red", 0.5, 0.0, object_type=triangle), names[:2]) == {0.25}
    assert thresholds(Target("red", 0.5, 0.0, object_type=triangle), None) == {None}
    assert thresholds(Target("red", 0.5, 0.0, object_type=CUBE), ("+x", "-y")) == {None}


def test_at_a_coarse_threshold_a_push_that_would_leave_the_part_blocked_beside_its_place_moves_across() -> None:
    # Free: +x and +y. (1, -1) mm at 0.8 mm: pushed 1 mm along +x it is left 1 mm off towards -y, which
    # only the blocked hypotenuse push closes. Moving across while it presses (0.6 of 1 mm) leaves 0.4.
    from bt_arrange.behaviours.push import DIAGONAL_ACROSS_RATIO, SquareMove

    pushes = TRIANGLE.named_pushes(ROBOTIQ_2F85)
    names = {round(math.degrees(p.heading_rad)): n for n, p in pushes.items()}
    free = (names[0], names[90])
    assert Push.choose_square_push((1.0, -1.0), pushes, free, 0.05, False) == (names[0], pytest.approx(1.0))
    assert Push.plan_square_push((1.0, -1.0), pushes, free, 0.05, False, 0.8) == SquareMove(
        names[0], pytest.approx(1.0), pytest.approx(-DIAGONAL_ACROSS_RATIO)
    )
    # Left half the threshold beside its place or less, or with every push free: the push by the projection.
    assert Push.plan_square_push((1.0, -0.35), pushes, free, 0.05, False, 0.8) == SquareMove(
        names[0], pytest.approx(1.0)
    )
    every = tuple(pushes)
    assert Push.plan_square_push((1.0, -1.0), pushes, every, 0.05, False, 0.8) == SquareMove(
        names[0], pytest.approx(1.0)
    )
    # Far from the target (a staged part on its way home) the long push goes the whole way, onto the line.
    assert Push.plan_square_push((10.0, -1.0), pushes, free, 0.05, False, 0.8) == SquareMove(
        names[0], pytest.approx(10.0), pytest.approx(-1.0)
    )


def test_a_long_push_among_neighbours_takes_away_what_squaring_the_part_carries_it_across() -> None:
    # A push meets a turned part's leading corner first; the part turns square about it, and its
    # centroid, back_m ahead of the edge, swings across: pieces of the example fresco turned -1.33 deg
    # ended their long pushes 0.62 mm to the left (their edge 26.6 mm behind the centroid), so a second
    # push was needed. The pads now move across by what lies beside the line less that swing.
    from bt_arrange.behaviours.push import LONG_PUSH_MAX_ACROSS_MM, SquareMove
    from bt_arrange.behaviours.square_pushes import squaring_shift_mm

    pushes = TRIANGLE.named_pushes(ROBOTIQ_2F85)
    names = {round(math.degrees(p.heading_rad)): n for n, p in pushes.items()}
    free = (names[0], names[90])
    push = pushes[names[0]]
    turn_rad = math.radians(-1.33)
    swing_mm = squaring_shift_mm(push, turn_rad)
    assert swing_mm == pytest.approx(-turn_rad * push.back_m * 1000) and swing_mm > 0  # a clockwise turn: left
    # Nothing beside the line: the pads move right by the swing, so that the part ends on its line.
    assert Push.plan_square_push((15.0, 0.0), pushes, free, 0.05, False, 0.8, turn_rad) == SquareMove(
        names[0], pytest.approx(15.0), pytest.approx(-swing_mm)
    )
    # The swing the other way cancels what lies beside; the same way, it adds to it (a turned part too
    # is moved across by up to a quarter of the push, not held to LONG_PUSH_MAX_ACROSS_MM).
    assert Push.plan_square_push((15.0, -swing_mm), pushes, free, 0.05, False, 0.8, -turn_rad) == SquareMove(
        names[0], pytest.approx(15.0)
    )
    assert Push.plan_square_push((15.0, -1.0), pushes, free, 0.05, False, 0.8, turn_rad) == SquareMove(
        names[0], pytest.approx(15.0), pytest.approx(-1.0 - swing_mm)
    )
    assert 1.0 + swing_mm > LONG_PUSH_MAX_ACROSS_MM
    # A staged part whose pushes are all free is among neighbours too (Push passes it: its opening was
    # given); a part placed free is pushed as before, the whole way by the projection.
    every = tuple(pushes)
    assert Push.plan_square_push((15.0, 0.4), pushes, every, 0.05, False, 0.8, 0.0, True) == SquareMove(
        names[0], pytest.approx(15.0), pytest.approx(0.4)
    )
    assert Push.plan_square_push((15.0, 0.4), pushes, every, 0.05, False, 0.8, turn_rad) == SquareMove(
        names[0], pytest.approx(15.0)
    )


def test_two_nearly_opposite_pushes_never_take_an_offset_between_them() -> None:
    # A slab whose right edge leans 1.1 deg: its left and right pushes are 178.9 deg apart, and a
    # 1.19 mm offset across them lies "between" them only for 59.5 mm of travel each way (seed 25 of
    # the tight gaps pushed a piece so, into two neighbours).
    slab = Prism.from_outline([[0, 0], [0.05, 0], [0.05 + 0.05 * math.tan(math.radians(1.1)), 0.05], [0, 0.05]], 0.02)
    pushes = slab.named_pushes(ROBOTIQ_2F85)
    by_heading = {round(math.degrees(p.heading_rad), 1): n for n, p in pushes.items()}
    sides = tuple(n for h, n in by_heading.items() if abs(h) < 5 or abs(abs(h) - 180) < 5)
    assert len(sides) == 2 and len(pushes) > 2, by_heading
    choice = Push.choose_square_push((0.0, 1.19), pushes, sides, 0.2, False)
    assert isinstance(choice, Blocked), choice
    assert choice.towards not in sides, "the push it needs is the blocked one along +y"
