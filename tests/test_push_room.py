"""Sides no pad can push from: warned about before anything moves, with the gap they would need."""

from __future__ import annotations

import pytest

from bt_arrange.cli_run import _warn_tight_sides
from bt_arrange.plan.compiled import compile_plan
from bt_arrange.plan.layout import Pads
from bt_arrange.plan.push_room import EXPECTED_PLACE_ERROR_MM, needed_gap_mm, tight_sides, warnings
from bt_arrange.plan.targets import Target
from bt_arrange.plan.tolerance import Tolerance
from bt_arrange.trees import render


def row(gap_mm: float, threshold_mm: float = 0.5):  # type: ignore[no-untyped-def]
    pitch_m = (50.0 + gap_mm) / 1000
    targets = [Target(colour, 0.5, (i - 1) * pitch_m) for i, colour in enumerate(("red", "blue", "green"))]
    return compile_plan(targets, Tolerance(threshold_mm, 1.0))


def test_the_gap_a_pad_needs_is_its_reach_its_clearance_the_placing_error_and_the_threshold() -> None:
    pads = Pads()
    assert needed_gap_mm(pads, 0.5) == pytest.approx(10 + 22 + 2 + EXPECTED_PLACE_ERROR_MM + 0.5)


def test_a_row_30_mm_apart_names_each_side_its_neighbour_and_the_gap_it_would_need() -> None:
    sides = {(s.obj, s.towards): s for s in tight_sides(row(30.0))}
    assert set(sides) == {("red", "-y"), ("blue", "+y"), ("blue", "-y"), ("green", "+y")}
    blue = sides[("blue", "+y")]
    assert (blue.neighbour, blue.side, blue.blocked) == ("red", "-y", True)
    assert blue.gap_mm == pytest.approx(30.0, abs=0.01)
    assert blue.needed_mm == pytest.approx(38.2)
    text = blue.text()
    assert text.startswith("blue's -y side is 30.0 mm from red")
    assert "needs 38.2 mm" in text
    # The ends of the row can be picked up and released past their place; the middle one cannot.
    assert sides[("green", "+y")].restaged and not blue.restaged


def test_a_side_free_at_nominal_but_not_at_the_expected_error_is_warned_about_too() -> None:
    sides = tight_sides(row(36.0))
    assert sides and not any(side.blocked for side in sides)


def test_a_row_with_room_for_the_pads_is_not_warned_about() -> None:
    assert tight_sides(row(120.0)) == []
    assert warnings(row(40.0)) == []


def test_many_tight_sides_are_summed_up_after_a_few() -> None:
    lines = warnings(row(1.0), limit=2)
    assert len(lines) == 3
    assert lines[-1] == "and 8 more side(s) where a neighbour leaves the pads no room"


def test_the_command_line_prints_them_on_stderr_before_the_run(capsys: pytest.CaptureFixture[str]) -> None:
    _warn_tight_sides(render(row(30.0)))
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 4
    assert all(line.startswith("bt-arrange: warning: ") for line in err)
